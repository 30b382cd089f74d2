/* k-d traversal steps shared by the single-ray and packet queries (trace.c)
 * and the dynamic policy, which pauses the same traversal at queue points:
 * one copy, so every policy visits nodes with exactly the same arithmetic and
 * therefore finds exactly the same hits. Private to renderer/. */
#ifndef RTSIM_RENDERER_TRAV_H
#define RTSIM_RENDERER_TRAV_H

#include <float.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>

#include "renderer/kdtree.h"
#include "renderer/ray.h"
#include "renderer/trace.h"
#include "sim/err.h"
#include "sim/mem.h"

/* Relative slack of traversal planes, in units of R = the ray origin's largest
 * per-axis distance to the root box. The triangle test decides hits from
 * coordinates relative to the origin with a few roundings of magnitude R, so
 * its hit points lie within ~8 eps R of the triangle; 64 FLT_EPSILON (7.6e-6 R)
 * leaves a wide margin. Cost: rays within this distance of a split plane visit
 * both children, which is negligible. */
#define TRACE_SLACK (64.0f * FLT_EPSILON)

/* Rays whose direction is shorter than this (largest component) miss
 * everything: below it 1/d overflows and the test's shear is meaningless. */
#define TRACE_MIN_DIR 1e-30f

/* Per-ray traversal constants. flat[a]: d[a] is too small for 1/d[a]; the ray
 * is then treated as not moving along a (it moves < 1e-8 R inside the box). */
struct trav_ray {
  float o[3], inv[3], tol[3];
  bool flat[3];
  float delta; /* slack in scene units */
  float t0, t1; /* clipped to the slack-thickened root box */
};

static inline bool ray_valid(const struct ray *r) {
  if (!isfinite(r->o.x) || !isfinite(r->o.y) || !isfinite(r->o.z)) return false;
  if (!isfinite(r->d.x) || !isfinite(r->d.y) || !isfinite(r->d.z)) return false;
  if (isnan(r->tmin) || isnan(r->tmax) || !(r->tmin < r->tmax)) return false;
  float m = fmaxf(fabsf(r->d.x), fmaxf(fabsf(r->d.y), fabsf(r->d.z)));
  return m >= TRACE_MIN_DIR;
}

/* Set up tr and clip the ray to the thickened root box; false if it misses.
 * NOTE: inline keeps it inlined in traverse() now that packets call it too. */
static inline bool trav_setup(struct trav_ray *tr, const struct kd_tree *kd, const struct ray *r) {
  float lo[3] = {kd->lo.x, kd->lo.y, kd->lo.z}, hi[3] = {kd->hi.x, kd->hi.y, kd->hi.z};
  float d[3] = {r->d.x, r->d.y, r->d.z};
  tr->o[0] = r->o.x;
  tr->o[1] = r->o.y;
  tr->o[2] = r->o.z;
  float reach = 0.0f;
  for (int a = 0; a < 3; a++)
    reach = fmaxf(reach, fmaxf(fabsf(lo[a] - tr->o[a]), fabsf(hi[a] - tr->o[a])));
  tr->delta = reach * TRACE_SLACK + FLT_MIN;
  float t0 = r->tmin, t1 = r->tmax;
  for (int a = 0; a < 3; a++) {
    float inv = 1.0f / d[a];
    tr->flat[a] = !isfinite(inv);
    if (tr->flat[a]) {
      tr->inv[a] = 0.0f;
      tr->tol[a] = 0.0f;
      if (tr->o[a] - lo[a] < -tr->delta || tr->o[a] - hi[a] > tr->delta) return false;
      continue;
    }
    tr->inv[a] = inv;
    tr->tol[a] = tr->delta * fabsf(inv);
    float tn = ((lo[a] - tr->o[a]) - tr->delta) * inv;
    float tf = ((hi[a] - tr->o[a]) + tr->delta) * inv;
    if (inv < 0.0f) {
      float tmp = tn;
      tn = tf;
      tf = tmp;
    }
    /* NaN-safe: a NaN bound leaves the interval as it is. */
    if (tn > t0) t0 = tn;
    if (tf < t1) t1 = tf;
  }
  tr->t0 = t0;
  tr->t1 = t1;
  return t0 <= t1;
}

struct trav_entry {
  uint32_t node;
  float t0, t1;
};

/* One traversal step at interior node nd (index ni) over [t0, t1]: picks the
 * child to visit next (*next, its interval in *t0, *t1) and pushes the other one if
 * both need a visit. Returns false when neither child needs one. */
static inline bool trav_interior(const struct trav_ray *tr, struct kd_node nd, uint32_t ni, float *t0,
                          float *t1, uint32_t *next, struct trav_entry *stack, int *sp) {
  int a = kd_axis(nd);
  float s = kd_split(nd);
  uint32_t below = ni + 1, above = kd_above(nd);
  uint32_t near_c, far_c;
  float n0 = *t0, n1 = *t1, f0 = *t0, f1 = *t1;
  bool vnear, vfar;
  if (tr->flat[a]) {
    /* Parallel to the plane: the side(s) within the slack; a ray lying in the
     * plane sees both children. */
    bool vb = tr->o[a] - s <= tr->delta, va = s - tr->o[a] <= tr->delta;
    bool below_first = tr->o[a] <= s;
    near_c = below_first ? below : above;
    far_c = below_first ? above : below;
    vnear = below_first ? vb : va;
    vfar = below_first ? va : vb;
  } else {
    float ts = (s - tr->o[a]) * tr->inv[a];
    float lo_t = ts - tr->tol[a], hi_t = ts + tr->tol[a];
    near_c = tr->inv[a] > 0.0f ? below : above;
    far_c = tr->inv[a] > 0.0f ? above : below;
    if (isnan(lo_t) || isnan(hi_t)) {
      vnear = vfar = true;
    } else {
      if (hi_t < n1) n1 = hi_t;
      if (lo_t > f0) f0 = lo_t;
      vnear = *t0 <= hi_t;
      vfar = lo_t <= *t1;
    }
  }
  if (vnear && vfar) {
    CHECK(*sp < KD_DEPTH_LIMIT);
    stack[*sp].node = far_c;
    stack[*sp].t0 = f0;
    stack[*sp].t1 = f1;
    (*sp)++;
  }
  if (vnear) {
    *next = near_c;
    *t0 = n0;
    *t1 = n1;
    return true;
  }
  if (vfar) {
    *next = far_c;
    *t0 = f0;
    *t1 = f1;
    return true;
  }
  return false;
}

static inline void announce_node(struct tracer *tr, uint32_t ni) {
  mem_load(&tr->mem, tr->layout.node_base + 8ull * ni, 8, MEM_CLASS_NODE);
  mem_compute(&tr->mem, tr->layout.node_cycles);
  tr->stats.node_visits++;
}

static inline void announce_tri(struct tracer *tr, uint32_t p) {
  mem_load(&tr->mem, tr->layout.tri_base + (uint64_t)tr->layout.tri_bytes * p,
           tr->layout.tri_bytes, MEM_CLASS_GEOMETRY);
  mem_compute(&tr->mem, tr->layout.tri_cycles);
  tr->stats.tri_tests++;
  if (tr->tested) tr->tested[p >> 6] |= 1ull << (p & 63);
}

#endif
