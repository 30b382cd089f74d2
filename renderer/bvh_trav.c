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
#include "renderer/bvh_node.h"
#include "renderer/trav.h"

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
      bt_sort_nearest(kids, m);
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
