/* One BVH node visit's child box tests, binary and 8-wide, shared by the
 * single-ray traversal (bvh_trav.c) and the packet traversal (bvh_packet.c)
 * so that both meet every box with the same arithmetic: a child entered by a
 * ray alone is entered by it inside a packet. The arithmetic is the k-d
 * traversal's (trav.h): box planes thickened by the ray's slack exactly as
 * the root box is. Quantized boxes contain the exact ones (bvh8.c checks
 * each plane at build). Private to renderer/. */
#ifndef RTSIM_RENDERER_BVH_NODE_H
#define RTSIM_RENDERER_BVH_NODE_H

#include <stdbool.h>
#include <stdint.h>

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

/* kids[0..m) nearest first by entry distance, ties in their order (an
 * insertion sort: m is at most 8). */
BT_INLINE void bt_sort_nearest(struct bt_entry *kids, uint32_t m) {
  for (uint32_t i = 1; i < m; i++)
    for (uint32_t j = i; j > 0 && kids[j].t < kids[j - 1].t; j--) {
      const struct bt_entry x = kids[j];
      kids[j] = kids[j - 1];
      kids[j - 1] = x;
    }
}

/* Bytes of a node of b as the memory image holds it (64 or 80). */
static inline uint32_t bt_node_bytes(const struct bvh *b) {
  return b->kind == ACCEL_BVH8 ? (uint32_t)sizeof(struct bvh8_node) : 64u;
}

#endif
