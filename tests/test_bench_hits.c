/* rtsim bench --hits's parts. Oracles: hand-made rays and triangles for the
 * double-precision verdict (nearer, farther, a shared edge, a grazed edge, a
 * miss against a hit); brute force over all triangles for the tie count; and
 * on the small scenes' ray sets (primary, the shadow and diffuse rays their
 * hits spawn, random rays) the k-d tree, the BVH2 and the BVH8 give every ray
 * the same triangle and the same t, bit for bit. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "app/bench_hits.h"
#include "app/bench_rays.h"
#include "renderer/bvh.h"
#include "renderer/kdtree.h"
#include "renderer/ray.h"
#include "renderer/scene.h"
#include "renderer/trace.h"
#include "testing.h"

/* A square z = 1 of two triangles sharing the diagonal (0,0)-(1,1), and a
 * triangle z = 2 under it (as seen from z = 0 looking up). */
static void check_verdicts(void) {
  struct scene s;
  scene_init(&s);
  scene_add_tri(&s, v3(0, 0, 1), v3(1, 0, 1), v3(1, 1, 1), NULL, 0); /* 0 */
  scene_add_tri(&s, v3(0, 0, 1), v3(1, 1, 1), v3(0, 1, 1), NULL, 0); /* 1 */
  scene_add_tri(&s, v3(0, 0, 2), v3(1, 0, 2), v3(0, 1, 2), NULL, 0); /* 2 */
  struct ray r = testing_make_ray(0.6f, 0.2f, 0, 0, 0, 1, 0, INFINITY);
  EXPECT(bench_hits_decide(&s, &r, 0, 2) == BENCH_HITS_A);
  EXPECT(bench_hits_decide(&s, &r, 2, 0) == BENCH_HITS_B);
  EXPECT(bench_hits_decide(&s, &r, -1, 0) == BENCH_HITS_B); /* a missed a hit */
  EXPECT(bench_hits_decide(&s, &r, 0, -1) == BENCH_HITS_A);
  EXPECT(bench_hits_decide(&s, &r, 1, -1) == BENCH_HITS_B); /* 1 is no hit: the miss is right */
  struct ray diag = testing_make_ray(0.25f, 0.25f, 0, 0, 0, 1, 0, INFINITY);
  EXPECT(bench_hits_decide(&s, &diag, 0, 1) == BENCH_HITS_TIE);
  struct ray graze = testing_make_ray(0.999999f, 0.5f, 0, 0, 0, 1, 0, INFINITY);
  EXPECT(bench_hits_decide(&s, &graze, 0, -1) == BENCH_HITS_EDGE);
  /* The diagonal ray's tie, and none off it. */
  struct kd_tree kd;
  struct kd_build_params kp;
  kd_build_params_default(&kp);
  EXPECT(kd_build(&kd, &s, &kp, NULL));
  struct trace_ctx tr;
  trace_init(&tr, &s, &kd, mem_port_native(), NULL);
  struct trace_hit h;
  EXPECT(trace_closest(&tr, &diag, &h) && h.prim == 0 && bench_hits_tie(&tr, &diag, &h));
  EXPECT(trace_closest(&tr, &r, &h) && h.prim == 0 && !bench_hits_tie(&tr, &r, &h));
  kd_fini(&kd);
  scene_fini(&s);
}

/* Brute force: is another triangle than h's (and r's ignored one) hit at h->t? */
static bool brute_tie(const struct scene *s, const struct ray *r, const struct trace_hit *h) {
  if (h->prim < 0) return false;
  struct trace_isect_ray ir;
  trace_isect_prepare(&ir, r->o, r->d);
  for (uint32_t p = 0; p < s->tri_count; p++) {
    if ((int32_t)p == h->prim || (int32_t)p == r->ignore_prim) continue;
    float t, b1, b2;
    const struct scene_tri *tri = &s->tris[p];
    if (trace_isect_tri(&ir, tri->v[0], tri->v[1], tri->v[2], r->tmin, r->tmax, &t, &b1, &b2) &&
        t == h->t)
      return true;
  }
  return false;
}

static uint32_t fbits(float f) {
  uint32_t u;
  memcpy(&u, &f, sizeof u);
  return u;
}

static void check_scene(const char *name, uint32_t W, uint32_t H) {
  struct scene s;
  struct kd_tree kd;
  if (!testing_load_small(&s, &kd, name)) return;
  struct bvh b[ACCEL_COUNT];
  struct trace_ctx tr[ACCEL_COUNT];
  for (int k = 0; k < ACCEL_COUNT; k++) {
    memset(&b[k], 0, sizeof b[k]);
    if (k != ACCEL_KD) bvh_build(&b[k], &s, (enum accel_kind)k);
    trace_init(&tr[k], &s, &kd, mem_port_native(), NULL);
    tr[k].bvh = k != ACCEL_KD ? &b[k] : NULL;
  }
  uint32_t n[4] = {W * H, 0, 0, 2000};
  struct ray *set[4];
  set[0] = bench_rays_primary(&s, W, H);
  set[1] = bench_rays_spawned(&tr[0], set[0], n[0], W, H, RAY_SHADOW, &n[1]);
  set[2] = bench_rays_spawned(&tr[0], set[0], n[0], W, H, RAY_DIFFUSE, &n[2]);
  set[3] = bench_rays_random(&s, n[3], 5);
  uint64_t differ = 0, ties = 0, brute = 0, rays = 0, hits = 0;
  for (int i = 0; i < 4; i++) {
    EXPECT(n[i] > 0);
    for (uint32_t j = 0; j < n[i]; j++) {
      struct trace_hit h[ACCEL_COUNT];
      for (int k = 0; k < ACCEL_COUNT; k++) trace_closest(&tr[k], &set[i][j], &h[k]);
      for (int k = 1; k < ACCEL_COUNT; k++)
        differ += h[k].prim != h[0].prim || fbits(h[k].t) != fbits(h[0].t);
      const bool tie = bench_hits_tie(&tr[0], &set[i][j], &h[0]);
      ties += tie;
      brute += tie != brute_tie(&s, &set[i][j], &h[0]);
      hits += h[0].prim >= 0;
      rays++;
    }
    free(set[i]);
  }
  EXPECTF(differ == 0, "%s: %llu answers differ from the k-d tree's", name,
          (unsigned long long)differ);
  EXPECTF(brute == 0, "%s: %llu tie answers differ from brute force", name,
          (unsigned long long)brute);
  EXPECT(hits > 0);
  printf("%s: %llu rays, %llu hits, %llu ties, the same on all three structures\n", name,
         (unsigned long long)rays, (unsigned long long)hits, (unsigned long long)ties);
  for (int k = 0; k < ACCEL_COUNT; k++) bvh_fini(&b[k]);
  kd_fini(&kd);
  scene_fini(&s);
}

int main(void) {
  check_verdicts();
  check_scene("room", 24, 24);
  check_scene("grove", 24, 24);
  return testing_done("bench_hits");
}
