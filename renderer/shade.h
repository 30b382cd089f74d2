/* Shading as the paper's ray types: at a hit, the ambient term, one shadow ray
 * toward every point light, a specular reflection ray from mirror materials
 * (at most 2 bounces) and diffuse reflection rays on a 3x3 hemisphere grid
 * (9 a round; a primary hit always samples, a diffuse bounce continues with a
 * 10% chance; at most 2 bounces).
 *
 * Radiance is linear in each ray's throughput w, so each ray's contribution is
 * added to its pixel on its own (Pharr et al.'s linear formulation): rays can
 * be traced in any order, which is what lets a scheduler reorder them. Random
 * choices come from a stream keyed by (seed, path, child), never by order. */
#ifndef RTSIM_RENDERER_SHADE_H
#define RTSIM_RENDERER_SHADE_H

#include <stdbool.h>
#include <stdint.h>

#include "renderer/ray.h"
#include "sim/mem.h"

struct scene;
struct trace_hit;
struct framebuffer;

#define SHADE_MAX_DEPTH 2    /* reflection bounces, the paper's limit */
#define SHADE_DIFFUSE_GRID 3 /* 3 x 3 = 9 diffuse rays a round */
#define SHADE_DIFFUSE_CONTINUE 0.1f
/* Most rays one hit can spawn: a shadow ray per light, a mirror ray, a round
 * of diffuse rays. */
#define SHADE_MAX_SPAWN (16 + 1 + SHADE_DIFFUSE_GRID * SHADE_DIFFUSE_GRID)

struct shade_ctx {
  const struct scene *scene;
  uint32_t ray_mask; /* RAY_MASK(RAY_SHADOW) | ...; primary rays are always traced */
  uint64_t seed;
  uint32_t shade_cycles; /* compute announced per shaded hit (0: none) */
};

/* Shade the result of a non-shadow ray r (h->prim < 0: a miss). A hit
 * announces c->shade_cycles of compute. Adds direct contributions to fb and writes the rays it
 * spawns to out[] (at most SHADE_MAX_SPAWN), shadow rays first. Returns how many it spawned. */
uint32_t shade_hit(const struct shade_ctx *c, const struct ray *r, const struct trace_hit *h,
                   struct framebuffer *fb, const struct mem_port *mem, struct ray *out);

/* Account for a shadow ray: adds its contribution unless occluded. */
void shade_shadow(const struct ray *r, bool occluded, struct framebuffer *fb,
                  const struct mem_port *mem);

/* Parse "primary,shadow,specular,diffuse" (any subset, comma-separated; primary
 * is implied) into a mask. Returns false on an unknown word or an empty item
 * ("", "primary,"). */
bool shade_parse_rays(const char *list, uint32_t *mask);

/* "primary,shadow,..." for a mask (buf of 64 bytes is enough). */
void shade_rays_name(uint32_t mask, char *buf, unsigned cap);

#endif
