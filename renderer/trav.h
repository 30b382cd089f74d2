/* k-d traversal steps shared by the single-ray and packet queries (trace.c),
 * the brute-force reference and the dynamic policy, which pauses the same
 * traversal at queue points: one copy of the node step, the leaf test and the
 * hit rule, so every policy visits nodes and tests triangles with exactly the
 * same arithmetic and therefore finds exactly the same hits. Private to
 * renderer/. */
#ifndef RTSIM_RENDERER_TRAV_H
#define RTSIM_RENDERER_TRAV_H

#include <float.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#include "renderer/kdtree.h"
#include "renderer/ray.h"
#include "renderer/scene.h"
#include "renderer/trace.h"
#include "sim/err.h"
#include "sim/mem.h"

/* Relative slack of traversal planes, in units of R = the ray origin's largest
 * per-axis distance to the root box. The triangle test decides hits from
 * coordinates relative to the origin with a few roundings of magnitude R, so
 * its hit points lie within ~8 eps R of the triangle; 64 FLT_EPSILON (7.6e-6 R)
 * leaves a wide margin. Cost: rays within this distance of a split plane visit
 * both children, which is negligible. */
#define TRAV_SLACK (64.0f * FLT_EPSILON)

/* Rays whose direction is shorter than this (largest component) miss
 * everything: below it 1/d overflows and the test's shear is meaningless. */
#define TRAV_MIN_DIR 1e-30f

/* Per-ray traversal constants. flat[a]: d[a] is too small for 1/d[a]; the ray
 * is then treated as not moving along a (it moves < 1e-8 R inside the box). */
struct trav_ray {
  float o[3], inv[3], tol[3];
  bool flat[3];
  float delta;  /* slack in scene units */
  float t0, t1; /* clipped to the slack-thickened root box */
};

static inline bool trav_ray_valid(const struct ray *r) {
  if (!isfinite(r->o.x) || !isfinite(r->o.y) || !isfinite(r->o.z)) return false;
  if (!isfinite(r->d.x) || !isfinite(r->d.y) || !isfinite(r->d.z)) return false;
  if (isnan(r->tmin) || isnan(r->tmax) || !(r->tmin < r->tmax)) return false;
  float m = fmaxf(fabsf(r->d.x), fmaxf(fabsf(r->d.y), fabsf(r->d.z)));
  return m >= TRAV_MIN_DIR;
}

/* A packet's ray i before its traversal: no occlusion found yet (any_hit),
 * else no hit up to its tmax. */
static inline void trav_clear_result(const struct ray *r, bool any_hit, struct trace_hit *hit,
                                     bool *occ) {
  if (any_hit) {
    *occ = false;
  } else {
    hit->t = r->tmax;
    hit->prim = -1;
    hit->b1 = hit->b2 = 0.0f;
  }
}

/* Set up tr and clip the ray to the thickened root box [blo, bhi] (the k-d
 * tree's or a BVH's); false if it misses.
 * NOTE: inline keeps it inlined in traverse() now that packets call it too. */
static inline bool trav_setup_box(struct trav_ray *tr, vec3 blo, vec3 bhi, const struct ray *r) {
  float lo[3] = {blo.x, blo.y, blo.z}, hi[3] = {bhi.x, bhi.y, bhi.z};
  float d[3] = {r->d.x, r->d.y, r->d.z};
  tr->o[0] = r->o.x;
  tr->o[1] = r->o.y;
  tr->o[2] = r->o.z;
  float reach = 0.0f;
  for (int a = 0; a < 3; a++)
    reach = max_nonnan(reach, max_nonnan(fabsf(lo[a] - tr->o[a]), fabsf(hi[a] - tr->o[a])));
  tr->delta = reach * TRAV_SLACK + FLT_MIN;
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
static inline bool trav_setup(struct trav_ray *tr, const struct kd_tree *kd, const struct ray *r) {
  return trav_setup_box(tr, kd->lo, kd->hi, r);
}

struct trav_entry {
  uint32_t node;
  float t0, t1;
};

/* One traversal step at interior node nd (index ni) over [t0, t1]: picks the
 * child to visit next (*next, its interval in *t0, *t1) and pushes the other one if
 * both need a visit. Returns false when neither child needs one. */
static inline bool trav_interior(const struct trav_ray *tr, struct kd_node nd, uint32_t ni,
                                 float *t0, float *t1, uint32_t *next, struct trav_entry *stack,
                                 int *sp) {
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
    CHECK_LT(*sp, KD_DEPTH_LIMIT);
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

/* The announcements below take `native`, true when tr->mem is the native
 * port (which does nothing with them): a caller that passes a constant gets a
 * copy of its loop with no backend calls in it, which the compiler can keep
 * tight. Counters move either way. Host only: nothing simulated changes. */

/* Announce a visit of node ni by `rays` rays at once (1, or a packet's active
 * rays): one node load, node_cycles of compute per ray. */
static inline void trav_visit_node(struct trace_ctx *tr, uint32_t ni, uint32_t rays, bool native) {
  if (!native) {
    mem_load(&tr->mem, tr->layout.node_base + 8ull * ni, 8, TRACE_CLASS_NODE);
    mem_compute(&tr->mem, (uint64_t)tr->layout.node_cycles * rays);
  }
  tr->stats.node_visits++;
}
static inline void trav_announce_node(struct trace_ctx *tr, uint32_t ni, uint32_t rays) {
  trav_visit_node(tr, ni, rays, false);
}

/* Announce triangle p tested against `rays` rays at once: one record load,
 * tri_cycles of compute and one test per ray. */
static inline void trav_visit_tri(struct trace_ctx *tr, uint32_t p, uint32_t rays, bool native) {
  if (!native) {
    mem_load(&tr->mem, tr->layout.tri_base + (uint64_t)tr->layout.tri_bytes * p,
             tr->layout.tri_bytes, TRACE_CLASS_GEOMETRY);
    mem_compute(&tr->mem, (uint64_t)tr->layout.tri_cycles * rays);
  }
  tr->stats.tri_tests += rays;
  if (tr->tested) tr->tested[p >> 6] |= 1ull << (p & 63);
}
static inline void trav_announce_tri(struct trace_ctx *tr, uint32_t p, uint32_t rays) {
  trav_visit_tri(tr, p, rays, false);
}

/* Entry j of the leaf index lists: its 4-byte load, then the primitive. */
static inline uint32_t trav_leaf_prim_n(struct trace_ctx *tr, uint32_t j, bool native) {
  if (!native) mem_load(&tr->mem, tr->layout.prim_idx_base + 4ull * j, 4, TRACE_CLASS_NODE);
  return tr->kd->prims[j];
}
static inline uint32_t trav_leaf_prim(struct trace_ctx *tr, uint32_t j) {
  return trav_leaf_prim_n(tr, j, false);
}

/* The hit rule: a hit (t, p) beats the best so far (best_t, best_p) when
 * there is none yet, when it is nearer, or when it is as near and its
 * primitive id is smaller. */
static inline bool trav_hit_wins(bool found, float t, uint32_t p, float best_t, uint32_t best_p) {
  return !found || t < best_t || (t == best_t && p < best_p);
}

/* One ray's best hit so far. upper is the bound handed to the triangle test:
 * tmax until a hit is found, then nextafter(t), so that a hit at equal t still
 * competes on its primitive id. */
/* A mailbox (host only): the last triangles the ray was tested against, direct
 * mapped by primitive id. A big triangle lies in many leaves; testing it again
 * gives nothing new (best only improves, and the test is monotone in its upper
 * bound: a miss stays a miss, a hit cannot win twice), so the host skips the
 * arithmetic. The loads and cycles are still announced: the simulated tracer
 * has no mailbox, and every simulated figure is the same with or without. */
#define TRAV_MBOX 8
struct trav_best {
  bool found;
  float t, b1, b2, upper;
  uint32_t p;
  uint32_t mbox[TRAV_MBOX];
};

static inline void trav_best_init(struct trav_best *b, float tmax) {
  b->found = false;
  b->t = b->upper = tmax;
  b->b1 = b->b2 = 0.0f;
  b->p = 0;
  memset(b->mbox, 0xff, sizeof b->mbox);
}

/* True if b's ray has been tested against p already (and records it if not). */
static inline bool trav_mbox_seen(struct trav_best *b, uint32_t p) {
  uint32_t *slot = &b->mbox[p & (TRAV_MBOX - 1)];
  if (*slot == p) return true;
  *slot = p;
  return false;
}

/* Keep hit (t, p, b1, b2) if it wins under the hit rule. */
static inline void trav_best_offer(struct trav_best *b, float t, uint32_t p, float b1, float b2) {
  if (!trav_hit_wins(b->found, t, p, b->t, b->p)) return;
  b->found = true;
  b->t = t;
  b->b1 = b1;
  b->b2 = b2;
  b->upper = float_next_up(t);
  b->p = p;
}

/* The query result of b: its hit, or a miss (prim -1) at t = tmax. */
static inline void trav_best_hit(const struct trav_best *b, struct trace_hit *h) {
  h->t = b->t;
  h->prim = b->found ? (int32_t)b->p : -1;
  h->b1 = b->b1;
  h->b2 = b->b2;
}

/* The leaf test of one ray: entries [j0, j1) of leaf nd in leaf order, each a
 * leaf-list load, then (unless it is the ray's ignore primitive) a triangle
 * load and test in (tmin, b->upper); hits go to b. With any, stop at the first
 * hit and return true; otherwise return false. */
static inline bool trav_leaf_n(struct trace_ctx *tr, const struct trace_isect_ray *ir, float tmin,
                               int32_t ignore, bool any, struct kd_node nd, uint32_t j0,
                               uint32_t j1, struct trav_best *b, bool native) {
  uint32_t off = kd_leaf_offset(nd);
  for (uint32_t j = j0; j < j1; j++) {
    uint32_t p = trav_leaf_prim_n(tr, off + j, native);
    if ((int64_t)p == (int64_t)ignore) continue;
    trav_visit_tri(tr, p, 1, native);
    if (trav_mbox_seen(b, p)) continue;
    const struct scene_tri *tri = &tr->scene->tris[p];
    float t, b1, b2;
    if (!trace_isect_tri(ir, tri->v[0], tri->v[1], tri->v[2], tmin, b->upper, &t, &b1, &b2))
      continue;
    trav_best_offer(b, t, p, b1, b2);
    if (any) return true;
  }
  return false;
}
static inline bool trav_leaf(struct trace_ctx *tr, const struct trace_isect_ray *ir, float tmin,
                             int32_t ignore, bool any, struct kd_node nd, uint32_t j0, uint32_t j1,
                             struct trav_best *b) {
  return trav_leaf_n(tr, ir, tmin, ignore, any, nd, j0, j1, b, false);
}

/* Pop the next pending node above stack depth floor into (*ni, *t0, *t1),
 * skipping those that begin beyond the best hit. False when none is left. */
static inline bool trav_pop(const struct trav_entry *stack, int *sp, int floor,
                            const struct trav_best *b, uint32_t *ni, float *t0, float *t1) {
  while (*sp > floor) {
    (*sp)--;
    if (b->found && b->t < stack[*sp].t0) continue;
    *ni = stack[*sp].node;
    *t0 = stack[*sp].t0;
    *t1 = stack[*sp].t1;
    return true;
  }
  return false;
}

#endif
