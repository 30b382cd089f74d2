/* Single-ray BVH traversal, binary and 8-wide: a node's child boxes are
 * tested at once, the children hit are visited nearest entry first (the
 * others wait on an explicit stack, (width - 1) entries a level), and a
 * pending child is dropped when the best hit lies before its entry. The
 * arithmetic is the k-d traversal's (trav.h): the same ray set-up and root
 * clip, box planes thickened by the ray's slack exactly as the root box is,
 * the same triangle test, best-hit rule and announcements, so a BVH returns
 * what brute force does. Quantized boxes contain the exact ones (bvh8.c
 * checks each plane at build). */
#include "renderer/bvh_trav.h"

#include "renderer/bvh.h"
#include "renderer/trav.h"

#define BT_INLINE static inline __attribute__((always_inline))

/* A child to visit: an interior node (count 0) or a leaf's entries
 * [ref, ref + count), entered at t. */
struct bt_entry {
  uint32_t ref, count;
  float t;
};

/* The ray's interval in box [lo, hi] (thickened by the slack) intersected
 * with [t0, t1]: true if not empty, its start in *enter. */
BT_INLINE bool bt_box(const struct trav_ray *tv, const float lo[3], const float hi[3], float t0,
                      float t1, float *enter) {
  for (int a = 0; a < 3; a++) {
    if (tv->flat[a]) {
      if (tv->o[a] - lo[a] < -tv->delta || tv->o[a] - hi[a] > tv->delta) return false;
      continue;
    }
    float tn = ((lo[a] - tv->o[a]) - tv->delta) * tv->inv[a];
    float tf = ((hi[a] - tv->o[a]) + tv->delta) * tv->inv[a];
    if (tv->inv[a] < 0.0f) {
      const float tmp = tn;
      tn = tf;
      tf = tmp;
    }
    if (tn > t0) t0 = tn;
    if (tf < t1) t1 = tf;
  }
  *enter = t0;
  return t0 <= t1;
}

/* The children of node ni that the ray enters within [t0, t1], into out
 * (their count returned). */
BT_INLINE uint32_t bt_children2(const struct bvh *b, uint32_t ni, const struct trav_ray *tv,
                                float t0, float t1, struct bt_entry *out, uint32_t *tested) {
  const struct bvh2_node *nd = &b->n2[ni];
  uint32_t m = 0;
  for (int k = 0; k < 2; k++) {
    if (nd->count[k] == BVH_EMPTY) continue;
    (*tested)++;
    float t;
    if (!bt_box(tv, nd->lo[k], nd->hi[k], t0, t1, &t)) continue;
    out[m++] = (struct bt_entry){nd->ref[k], nd->count[k], t};
  }
  return m;
}

/* The same for an 8-wide node, a plane of every slot at a time (loops the
 * compiler can keep in vector registers): the near plane of each axis is lo
 * for a ray going up it and hi going down, thickened by the slack as bt_box
 * does, and computed in t as the node's origin plane plus q steps of the
 * scale (as k-d splits are tested in t): one multiply-add a plane. Its
 * rounding, a few eps of the ray's reach R, lies well inside the slack
 * (64 eps R, of which the triangle test needs 8), and the dequantized plane
 * itself contains the exact box (bvh8.c checks it). */
/* Four lanes, a slot each, the node's eight slots in two halves (GCC's and
 * Clang's vector extensions, SSE2 registers). Lane-wise IEEE arithmetic:
 * the same values as a loop over the slots. */
typedef float bt_f4 __attribute__((vector_size(16)));
typedef int32_t bt_i4 __attribute__((vector_size(16)));

BT_INLINE bt_f4 bt_q4(const uint8_t q[4]) {
  const bt_i4 i = {q[0], q[1], q[2], q[3]};
  return __builtin_convertvector(i, bt_f4);
}

/* Lane-wise m ? a : b (m all ones or zero a lane, as comparisons give). */
BT_INLINE bt_f4 bt_sel(bt_i4 m, bt_f4 a, bt_f4 b) {
  return (bt_f4)(((bt_i4)a & m) | ((bt_i4)b & ~m));
}

BT_INLINE uint32_t bt_children8(const struct bvh *b, uint32_t ni, const struct trav_ray *tv,
                                float t0, float t1, struct bt_entry *out, uint32_t *tested) {
  const struct bvh8_node *nd = &b->n8[ni];
  const bt_f4 zero = {0};
  bt_f4 tn[2] = {zero + t0, zero + t0}, tf[2] = {zero + t1, zero + t1};
  for (int a = 0; a < 3; a++) {
    const float s = bvh8_scale(nd->e[a]), p = nd->p[a], o = tv->o[a], d = tv->delta;
    if (tv->flat[a]) {
      for (int h = 0; h < 2; h++) {
        const bt_f4 lo = p + bt_q4(nd->qlo[a] + 4 * h) * s, hi = p + bt_q4(nd->qhi[a] + 4 * h) * s;
        const bt_i4 outside = ((o - lo) < -d) | ((o - hi) > d);
        tn[h] = bt_sel(outside, zero + INFINITY, tn[h]);
        tf[h] = bt_sel(outside, zero - INFINITY, tf[h]);
      }
      continue;
    }
    const bool up = tv->inv[a] >= 0.0f;
    const uint8_t *qn = up ? nd->qlo[a] : nd->qhi[a], *qf = up ? nd->qhi[a] : nd->qlo[a];
    const float dn = up ? -d : d, df = -dn, inv = tv->inv[a];
    const float bn = ((p - o) + dn) * inv, bf = ((p - o) + df) * inv, st = s * inv;
    for (int h = 0; h < 2; h++) {
      const bt_f4 n = bn + bt_q4(qn + 4 * h) * st, f = bf + bt_q4(qf + 4 * h) * st;
      tn[h] = bt_sel(n > tn[h], n, tn[h]);
      tf[h] = bt_sel(f < tf[h], f, tf[h]);
    }
  }
  const bt_i4 hit[2] = {tn[0] <= tf[0], tn[1] <= tf[1]};
  uint32_t m = 0;
  for (int k = 0; k < 8; k++) {
    bool interior;
    uint32_t ref, count;
    if (!bvh8_child(nd, k, &interior, &ref, &count)) continue;
    (*tested)++;
    if (hit[k >> 2][k & 3]) out[m++] = (struct bt_entry){ref, count, tn[k >> 2][k & 3]};
  }
  return m;
}

/* Leaf entries [first, first + count): each a leaf-list load, then (unless
 * it is the ray's ignore primitive) a triangle load and test. With any, true
 * at the first hit. */
BT_INLINE bool bt_leaf(struct trace_ctx *tr, const struct trace_isect_ray *ir, const struct ray *r,
                       bool any, uint32_t first, uint32_t count, struct trav_best *best,
                       bool native) {
  for (uint32_t j = first; j < first + count; j++) {
    if (!native) mem_load(&tr->mem, tr->layout.prim_idx_base + 4ull * j, 4, TRACE_CLASS_NODE);
    const uint32_t p = tr->bvh->prims[j];
    if ((int64_t)p == (int64_t)r->ignore_prim) continue;
    trav_visit_tri(tr, p, 1, native);
    const struct scene_tri *tri = &tr->scene->tris[p];
    float t, b1, b2;
    if (!trace_isect_tri(ir, tri->v[0], tri->v[1], tri->v[2], r->tmin, best->upper, &t, &b1, &b2))
      continue;
    trav_best_offer(best, t, p, b1, b2);
    if (any) return true;
  }
  return false;
}

#define BT_STACK (BVH_DEPTH_LIMIT * 7 + 8)

BT_INLINE bool bt_traverse(struct trace_ctx *tr, const struct ray *r, bool any, struct trace_hit *h,
                           bool native, bool wide) {
  h->t = r->tmax;
  h->prim = -1;
  h->b1 = h->b2 = 0.0f;
  const struct bvh *b = tr->bvh;
  if (!trav_ray_valid(r) || b->node_count == 0) return false;
  struct trav_ray tv;
  if (!trav_setup_box(&tv, b->lo, b->hi, r)) return false;
  struct trace_isect_ray ir;
  trace_isect_prepare(&ir, r->o, r->d);
  struct trav_best best;
  trav_best_init(&best, r->tmax);
  const uint32_t node_bytes = wide ? (uint32_t)sizeof(struct bvh8_node) : 64u;
  struct bt_entry stack[BT_STACK], cur = {0, 0, tv.t0};
  int sp = 0;
  for (;;) {
    if (cur.count == 0) {
      struct bt_entry kids[8];
      uint32_t tested = 0;
      const float t1 = best.found ? best.t : tv.t1;
      const uint32_t m = wide ? bt_children8(b, cur.ref, &tv, tv.t0, t1, kids, &tested)
                              : bt_children2(b, cur.ref, &tv, tv.t0, t1, kids, &tested);
      if (!native) {
        mem_load(&tr->mem, tr->layout.node_base + (uint64_t)node_bytes * cur.ref, node_bytes,
                 TRACE_CLASS_NODE);
        mem_compute(&tr->mem, 3ull * tr->layout.node_cycles * tested);
      }
      tr->stats.node_visits++;
      /* Nearest first: sort by entry (stable), push the rest farthest first. */
      for (uint32_t i = 1; i < m; i++)
        for (uint32_t j = i; j > 0 && kids[j].t < kids[j - 1].t; j--) {
          const struct bt_entry x = kids[j];
          kids[j] = kids[j - 1];
          kids[j - 1] = x;
        }
      if (m > 0) {
        CHECK_LE(sp + (int)m - 1, BT_STACK);
        for (uint32_t i = m; i-- > 1;) stack[sp++] = kids[i];
        cur = kids[0];
        continue;
      }
    } else if (bt_leaf(tr, &ir, r, any, cur.ref, cur.count, &best, native)) {
      break; /* any: the first hit */
    }
    bool next = false;
    while (sp > 0) {
      cur = stack[--sp];
      if (best.found && best.t < cur.t) continue;
      next = true;
      break;
    }
    if (!next) break;
  }
  trav_best_hit(&best, h);
  return best.found;
}

/* One copy of the loop per (port, width): the native one has no backend calls. */
bool bvh_traverse(struct trace_ctx *tr, const struct ray *r, bool any, struct trace_hit *h) {
  const bool wide = tr->bvh->kind == ACCEL_BVH8;
  if (!tr->mem.ops)
    return wide ? bt_traverse(tr, r, any, h, true, true) : bt_traverse(tr, r, any, h, true, false);
  return wide ? bt_traverse(tr, r, any, h, false, true) : bt_traverse(tr, r, any, h, false, false);
}
