/* Rendering: Hilbert order, order-independent framebuffer sums, determinism,
 * ray conservation, agreement with brute force, and the EXR the CLI writes. */
#include <stdlib.h>
#include <string.h>

#include "renderer/camera.h"
#include "renderer/framebuffer.h"
#include "renderer/image.h"
#include "renderer/kdtree.h"
#include "renderer/policy/policy.h"
#include "renderer/scene.h"
#include "renderer/scene/scene_file.h"
#include "renderer/shade.h"
#include "renderer/trace.h"
#include "sim/err.h"
#include "testing.h"

static void check_hilbert(uint32_t w, uint32_t h) {
  uint64_t n = (uint64_t)w * h;
  uint32_t *order = malloc(n * sizeof *order);
  unsigned char *seen = calloc(n, 1);
  camera_hilbert_order(w, h, order);
  int perm = 1;
  for (uint64_t i = 0; i < n; i++) {
    if (order[i] >= n || seen[order[i]]) perm = 0;
    else seen[order[i]] = 1;
  }
  EXPECTF(perm, "%ux%u: not a permutation", w, h);
  if ((w & (w - 1)) == 0 && w == h) { /* full curve: each step moves to a neighbour */
    int adjacent = 1;
    for (uint64_t i = 1; i < n; i++) {
      int dx = abs((int)(order[i] % w) - (int)(order[i - 1] % w));
      int dy = abs((int)(order[i] / w) - (int)(order[i - 1] / w));
      if (dx + dy != 1) adjacent = 0;
    }
    EXPECTF(adjacent, "%ux%u: Hilbert steps must be unit moves", w, h);
  }
  free(order);
  free(seen);
}

struct world {
  struct scene s;
  struct kd_tree kd;
};

static int load(struct world *w, const char *path) {
  return testing_load_world(&w->s, &w->kd, path);
}

static void render(struct world *w, uint32_t mask, uint32_t size, struct framebuffer *fb,
                   struct render_stats *st) {
  struct shade_ctx sc = {&w->s, mask, 7, 0};
  struct policy_setup ps;
  testing_policy_setup(&ps, &w->s, &w->kd, &sc, fb);
  fb_init(fb, size, size, ps.layout.fb_base);
  struct policy_params pp;
  policy_params_default(&pp);
  policy_run(POLICY_RECURSIVE, &ps, &pp, mem_port_native(), st, NULL);
}

int main(void) {
  check_hilbert(1, 1);
  check_hilbert(7, 5);
  check_hilbert(16, 16);
  check_hilbert(33, 17);
  check_hilbert(64, 64);

  /* Fixed-point sums do not depend on order (floats would). */
  {
    struct framebuffer a, b;
    fb_init(&a, 1, 1, 0);
    fb_init(&b, 1, 1, 0);
    struct mem_port m = mem_port_native();
    float vals[] = {1e-3f, 0.7f, 1e-7f, 0.33333f, 3.5f, 1e-5f, 0.1f};
    int n = (int)(sizeof vals / sizeof vals[0]);
    for (int i = 0; i < n; i++) fb_add(&a, 0, v3(vals[i], vals[i], vals[i]), &m);
    for (int i = n; i-- > 0;) fb_add(&b, 0, v3(vals[i], vals[i], vals[i]), &m);
    EXPECT(memcmp(a.acc, b.acc, 3 * sizeof *a.acc) == 0);
    fb_fini(&a);
    fb_fini(&b);
  }

  struct world w;
  if (!load(&w, RTSIM_SOURCE_DIR "/scenes/small/sphereflake.yaml")) return 1;
  const uint32_t all =
      RAY_MASK(RAY_PRIMARY) | RAY_MASK(RAY_SHADOW) | RAY_MASK(RAY_SPECULAR) | RAY_MASK(RAY_DIFFUSE);
  const uint32_t size = 48;

  /* Determinism and conservation with every ray type. */
  struct framebuffer f1, f2;
  struct render_stats s1, s2;
  render(&w, all, size, &f1, &s1);
  render(&w, all, size, &f2, &s2);
  EXPECT(memcmp(f1.acc, f2.acc, 3 * sizeof *f1.acc * size * size) == 0);
  EXPECT(memcmp(&s1, &s2, sizeof s1) == 0);
  EXPECT(s1.spawned == s1.terminated);
  EXPECT(s1.rays[RAY_PRIMARY] == (uint64_t)size * size);
  EXPECT(s1.rays[RAY_SHADOW] > 0 && s1.rays[RAY_SPECULAR] > 0 && s1.rays[RAY_DIFFUSE] > 0);
  /* Shadow rays: at most one per light per non-shadow ray. */
  EXPECT(s1.rays[RAY_SHADOW] <=
         3 * (s1.rays[RAY_PRIMARY] + s1.rays[RAY_SPECULAR] + s1.rays[RAY_DIFFUSE]));
  /* Diffuse rays come in rounds of at most 9. */
  EXPECT(s1.rays[RAY_DIFFUSE] <=
         9 * (s1.rays[RAY_PRIMARY] + s1.rays[RAY_SPECULAR] + s1.rays[RAY_DIFFUSE] / 9 + 1));
  fb_fini(&f2);

  /* Primary rays only: a pixel whose ray misses (brute force) is exactly the
   * background; a pixel whose ray hits has tested triangles. */
  struct world g;
  if (!load(&g, RTSIM_SOURCE_DIR "/scenes/small/grove.yaml")) return 1;
  struct framebuffer f3;
  struct render_stats s3;
  render(&g, RAY_MASK(RAY_PRIMARY), size, &f3, &s3);
  EXPECT(s3.rays[RAY_PRIMARY] == s3.terminated && s3.rays[RAY_SHADOW] == 0);
  struct camera_frame cf;
  camera_frame_init(&cf, &g.s.camera, size, size);
  struct framebuffer bg;
  fb_init(&bg, 1, 1, 0);
  struct mem_port m = mem_port_native();
  fb_add(&bg, 0, g.s.background, &m);
  int misses = 0, wrong = 0;
  for (uint32_t y = 0; y < size; y++)
    for (uint32_t x = 0; x < size; x++) {
      struct ray r;
      camera_primary(&cf, x, y, 7, &r);
      struct trace_hit h;
      uint32_t p = y * size + x;
      bool is_bg = memcmp(&f3.acc[3 * p], bg.acc, 3 * sizeof *bg.acc) == 0;
      if (!trace_brute(&g.s, &r, &h)) {
        misses++;
        wrong += !is_bg;
      } else {
        wrong += f3.cost_tris[p] == 0;
      }
    }
  EXPECTF(misses > 0 && misses < (int)(size * size) && wrong == 0, "misses %d wrong %d", misses,
          wrong);
  fb_fini(&bg);
  kd_fini(&g.kd);
  scene_fini(&g.s);

  /* The CLI's EXR equals the in-process render, and two runs are bit-identical. */
  char cmd[2048], out[8192];
  const char *a = RTSIM_TMP "/render_a.exr", *b = RTSIM_TMP "/render_b.exr";
  for (int k = 0; k < 2; k++) {
    snprintf(cmd, sizeof cmd,
             "%s render %s/scenes/small/sphereflake.yaml -o %s --width %u --height %u --seed 7",
             RTSIM_BINARY, RTSIM_SOURCE_DIR, k ? b : a, size, size);
    EXPECTF(testing_run(cmd, out, sizeof out) == 0, "%s", out);
  }
  snprintf(cmd, sizeof cmd, "cmp %s %s", a, b);
  EXPECTF(testing_run(cmd, out, sizeof out) == 0, "renders differ: %s", out);
  struct image im, ref;
  struct err e;
  memset(&e, 0, sizeof e);
  EXPECT(image_read_exr(&im, a, &e));
  fb_to_image(&f1, &ref);
  EXPECT(im.width == size && im.height == size);
  static const char *const ch[] = {"R", "G", "B", "cost.nodes", "cost.tris"};
  for (int c = 0; c < 5; c++) {
    int i = image_channel(&im, ch[c]);
    EXPECTF(i >= 0, "channel %s missing", ch[c]);
    if (i >= 0)
      EXPECTF(memcmp(im.planes[i], ref.planes[c], sizeof(float) * size * size) == 0,
              "channel %s differs from the in-process render", ch[c]);
  }
  image_fini(&im);
  image_fini(&ref);
  fb_fini(&f1);
  fb_fini(&f3);
  kd_fini(&w.kd);
  scene_fini(&w.s);
  return testing_done("test_render");
}
