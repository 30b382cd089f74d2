/* The ray sets the benchmarks trace: the image's primary rays in the order
 * the recursive policy casts them, the shadow and diffuse rays their nearest
 * hits spawn (first bounce, as shade_hit makes them), and random rays through
 * the scene's box. Each set is an array the caller frees. */
#ifndef RTSIM_APP_BENCH_RAYS_H
#define RTSIM_APP_BENCH_RAYS_H

#include <stdint.h>

struct scene;
struct ray;
struct trace_ctx;

/* The W x H image's primary rays (W H of them), in Hilbert order. */
struct ray *bench_rays_primary(const struct scene *s, uint32_t W, uint32_t H);

/* The rays of type `type` (RAY_SHADOW or RAY_DIFFUSE) that shading spawns at
 * the nearest hits of primary[0..n) traced through tr; their count in *out_n. */
struct ray *bench_rays_spawned(struct trace_ctx *tr, const struct ray *primary, uint32_t n,
                               uint32_t W, uint32_t H, int type, uint32_t *out_n);

/* n random rays, seeded: origins uniform in the scene's box widened by a
 * tenth of its diagonal a side, directions uniform on the sphere, extent
 * (0, inf), no ignored primitive. */
struct ray *bench_rays_random(const struct scene *s, uint32_t n, uint64_t seed);

#endif
