/* The 64-byte ray record. The simulator moves rays through memory as 64-byte
 * lines, so the host record has exactly that size and layout. */
#ifndef RTSIM_RENDERER_RAY_H
#define RTSIM_RENDERER_RAY_H

#include <stdint.h>

#include "renderer/vec.h"

enum ray_type {
  RAY_PRIMARY = 0,
  RAY_SHADOW = 1,
  RAY_SPECULAR = 2,
  RAY_DIFFUSE = 3,
  RAY_TYPE_COUNT = 4
};

/* Bit set of enabled ray types (1u << RAY_x). */
#define RAY_MASK(t) (1u << (t))

struct ray {
  vec3 o;              /* origin */
  vec3 d;              /* direction (not necessarily unit length) */
  float tmin, tmax;    /* extent along d */
  uint32_t pixel;      /* pixel id: y * width + x */
  vec3 w;              /* throughput: colour this ray's radiance is scaled by */
  int32_t ignore_prim; /* primitive the ray leaves from (never hit), or -1 */
  uint32_t path;       /* random-stream key of this ray's path */
  uint8_t depth;       /* bounces so far (0 for primary and its shadow rays) */
  uint8_t type;        /* enum ray_type */
  uint8_t light;       /* shadow rays: light index */
  uint8_t flags;
  int32_t hit_prim; /* scheduling state: best hit so far when a ray is deferred, or -1 */
};

_Static_assert(sizeof(struct ray) == 64, "a ray is one 64-byte line");

#endif
