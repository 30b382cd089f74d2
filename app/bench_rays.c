/* The benchmarks' ray sets (see bench_rays.h). */
#include "app/bench_rays.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "renderer/camera.h"
#include "renderer/framebuffer.h"
#include "renderer/ray.h"
#include "renderer/rng.h"
#include "renderer/scene.h"
#include "renderer/shade.h"
#include "renderer/trace.h"
#include "sim/err.h"

struct ray *bench_rays_primary(const struct scene *s, uint32_t W, uint32_t H) {
  const uint32_t n = W * H;
  uint32_t *order = xmalloc((unsigned long long)n * sizeof *order);
  struct ray *rays = xmalloc((unsigned long long)n * sizeof *rays);
  struct camera_frame cf;
  camera_frame_init(&cf, &s->camera, W, H);
  camera_hilbert_order(W, H, order);
  for (uint32_t i = 0; i < n; i++)
    camera_primary(&cf, order[i] % W, order[i] / W, s->seed, &rays[i]);
  free(order);
  return rays;
}

struct ray *bench_rays_spawned(struct trace_ctx *tr, const struct ray *primary, uint32_t n,
                               uint32_t W, uint32_t H, int type, uint32_t *out_n) {
  const struct shade_ctx sc = {tr->scene, RAY_MASK(type), tr->scene->seed, 0};
  struct framebuffer fb;
  fb_init(&fb, W, H, 0);
  const struct mem_port native = mem_port_native();
  uint32_t cap = n, m = 0;
  struct ray *out = xmalloc((unsigned long long)cap * sizeof *out), spawn[SHADE_MAX_SPAWN];
  for (uint32_t i = 0; i < n; i++) {
    struct trace_hit h;
    trace_closest(tr, &primary[i], &h);
    const uint32_t k = shade_hit(&sc, &primary[i], &h, &fb, &native, spawn);
    for (uint32_t j = 0; j < k; j++) {
      if (spawn[j].type != type) continue;
      if (m == cap) {
        cap *= 2;
        out = xrealloc(out, (unsigned long long)cap * sizeof *out);
      }
      out[m++] = spawn[j];
    }
  }
  fb_fini(&fb);
  *out_n = m;
  return out;
}

struct ray *bench_rays_random(const struct scene *s, uint32_t n, uint64_t seed) {
  vec3 lo = s->tri_count ? s->tris[0].v[0] : v3(0, 0, 0), hi = lo;
  for (uint32_t p = 0; p < s->tri_count; p++)
    for (int k = 0; k < 3; k++) {
      lo = v3_min(lo, s->tris[p].v[k]);
      hi = v3_max(hi, s->tris[p].v[k]);
    }
  const vec3 ext = v3_sub(hi, lo);
  const float pad = 0.1f * sqrtf(v3_dot(ext, ext));
  lo = v3_sub(lo, v3(pad, pad, pad));
  hi = v3_add(hi, v3(pad, pad, pad));
  struct rng g = rng_make(seed, 41);
  struct ray *rays = xcalloc(n ? n : 1, sizeof *rays);
  for (uint32_t i = 0; i < n; i++) {
    struct ray *r = &rays[i];
    r->o = v3(lo.x + (hi.x - lo.x) * rng_f32(&g), lo.y + (hi.y - lo.y) * rng_f32(&g),
              lo.z + (hi.z - lo.z) * rng_f32(&g));
    /* Uniform in the unit ball, by rejection (no libm: the same rays on
     * every host); its direction is uniform on the sphere. */
    do r->d = v3(2 * rng_f32(&g) - 1, 2 * rng_f32(&g) - 1, 2 * rng_f32(&g) - 1);
    while (v3_dot(r->d, r->d) > 1.0f || v3_dot(r->d, r->d) < 1e-6f);
    r->tmin = 0;
    r->tmax = INFINITY;
    r->pixel = i;
    r->ignore_prim = -1;
    r->hit_prim = -1;
  }
  return rays;
}
