/* Packet BVH traversal, binary and 8-wide: up to TRACE_PACKET_MAX rays go
 * down the BVH together, a node fetched once for the rays that need it (as
 * the k-d packet kernel in trace.c fetches a k-d node). Each active ray tests
 * the node's child boxes with its own interval, exactly as its single-ray
 * traversal (bvh_trav.c) does (the same inlined tests, bvh_node.h), so a ray
 * enters within a packet exactly the children it enters alone. The packet
 * visits a child when any ray entered it, the child nearest to any ray first;
 * a pending child is dropped for a ray whose best hit lies before its entry
 * (bvh_trav.c's rule). Only the order differs from the single ray's, and the
 * hit rule is a total order over true hits, so every ray gets bit for bit the
 * hit it gets alone (trace.c says why at more length for the k-d packet).
 *
 * Memory, as the single-ray BVH kernel: a node visit loads the node (64 or 80
 * bytes, class node) and computes 3 node_cycles per child tested per active
 * ray; a leaf entry loads its 4-byte index (class node) once for the packet,
 * then its triangle record once with tri_cycles per ray tested. */
#include <stdlib.h>
#include <string.h>

#include "renderer/bvh.h"
#include "renderer/bvh_node.h"
#include "renderer/bvh_trav.h"
#include "renderer/packet_mask.h"
#include "renderer/trace.h"
#include "renderer/trav.h"
#include "sim/err.h"

#define BP_MAX TRACE_PACKET_MAX
/* Pending children: up to (width - 1) a level (as the single ray's stack). */
#define BP_STACK (BVH_DEPTH_LIMIT * 7 + 8)

struct bp_entry {
  uint32_t ref, count; /* as bt_entry: count 0 an interior node */
  uint32_t base;       /* its rays' entry t, in the pool from here */
  uint64_t mask;       /* the rays that entered it */
};

struct bvh_packet {
  struct trav_ray tv[BP_MAX];
  struct trace_isect_ray ir[BP_MAX];
  float best_t[BP_MAX], upper[BP_MAX], tmin[BP_MAX];
  uint32_t best_p[BP_MAX], nodes[BP_MAX], tris[BP_MAX];
  int32_t ignore[BP_MAX];
  /* One node's children: the rays that entered each slot and their entries. */
  float kt[8][BP_MAX];
  uint64_t kmask[8];
  struct bp_entry stack[BP_STACK];
  float pool[BP_STACK * BP_MAX];
};

struct bvh_packet *bvh_packet_create(void) {
  return xcalloc(1, sizeof(struct bvh_packet));
}

void bvh_packet_destroy(struct bvh_packet *bp) { free(bp); }

/* Results cleared and the valid rays set up (trav_setup_box on the root box,
 * as bvh_traverse); returns the mask of live rays. */
static uint64_t bp_setup(const struct bvh *b, struct bvh_packet *bp, const struct ray *rays,
                         uint32_t n, bool any_hit, struct trace_hit *hits, bool *occ) {
  uint64_t live = 0;
  for (uint32_t i = 0; i < n; i++) {
    const struct ray *r = &rays[i];
    trav_clear_result(r, any_hit, &hits[i], &occ[i]);
    bp->nodes[i] = bp->tris[i] = 0;
    if (!trav_ray_valid(r) || b->node_count == 0 || !trav_setup_box(&bp->tv[i], b->lo, b->hi, r))
      continue;
    live |= 1ull << i;
    trace_isect_prepare(&bp->ir[i], r->o, r->d);
    bp->tmin[i] = r->tmin;
    bp->best_t[i] = bp->upper[i] = r->tmax;
    bp->best_p[i] = 0;
    bp->ignore[i] = r->ignore_prim;
  }
  return live;
}

/* Node ni's child slots: their references (interior: count 0), and how many
 * exist (the boxes a ray tests there). */
static uint32_t bp_slots(const struct bvh *b, uint32_t ni, uint32_t ref[8], uint32_t count[8]) {
  uint32_t m = 0;
  if (b->kind == ACCEL_BVH8) {
    for (int k = 0; k < 8; k++) {
      bool interior;
      if (bvh8_child(&b->n8[ni], k, &interior, &ref[k], &count[k])) m++;
      else ref[k] = 0, count[k] = BVH_EMPTY;
    }
    return m;
  }
  for (int k = 0; k < 2; k++) {
    ref[k] = b->n2[ni].ref[k];
    count[k] = b->n2[ni].count[k];
    m += count[k] != BVH_EMPTY;
  }
  return m;
}

/* Interior node ni for the rays in act: each tests the child boxes with its
 * own interval; kmask[k] gets the rays that entered slot k, kt[k] their
 * entries. Returns the node's existing children (tested a ray). */
static uint32_t bp_node(const struct bvh *b, struct bvh_packet *bp, uint32_t ni, uint64_t act,
                        uint64_t found, const uint32_t ref[8], const uint32_t count[8]) {
  const uint32_t width = b->kind == ACCEL_BVH8 ? 8 : 2;
  for (uint32_t k = 0; k < width; k++) bp->kmask[k] = 0;
  uint32_t tested = 0;
  for (uint64_t m = act; m; m &= m - 1) {
    const int i = packet_mask_first(m);
    const struct trav_ray *tv = &bp->tv[i];
    struct bt_entry kids[8];
    const float t1 = (found >> i) & 1u ? bp->best_t[i] : tv->t1;
    tested = 0;
    const uint32_t nk = b->kind == ACCEL_BVH8 ? bt_children8(b, ni, tv, tv->t0, t1, kids, &tested)
                                              : bt_children2(b, ni, tv, tv->t0, t1, kids, &tested);
    bp->nodes[i]++;
    /* A child is one slot: its (ref, count) is the slot's alone. */
    for (uint32_t j = 0, k = 0; j < nk; j++) {
      while (ref[k] != kids[j].ref || count[k] != kids[j].count) k++;
      bp->kmask[k] |= 1ull << i;
      bp->kt[k][i] = kids[j].t;
    }
  }
  return tested;
}

/* The rays in act tested against leaf entries [first, first + cnt): a hit
 * ends an any-hit ray (cleared from *live and act) and improves a closest-hit
 * ray's best (*found). */
static void bp_leaf(struct trace_ctx *tr, struct bvh_packet *bp, uint32_t first, uint32_t cnt,
                    uint64_t act, bool any_hit, struct trace_hit *hits, bool *occ, uint64_t *live,
                    uint64_t *found) {
  for (uint32_t j = first; j < first + cnt && act; j++) {
    mem_load(&tr->mem, tr->layout.prim_idx_base + 4ull * j, 4, TRACE_CLASS_NODE);
    const uint32_t p = tr->bvh->prims[j];
    uint64_t tm = 0;
    for (uint64_t m = act; m; m &= m - 1) {
      const int i = packet_mask_first(m);
      if ((int64_t)p != (int64_t)bp->ignore[i]) tm |= 1ull << i;
    }
    if (!tm) continue;
    trav_announce_tri(tr, p, packet_mask_count(tm));
    const struct scene_tri *tri = &tr->scene->tris[p];
    for (uint64_t m = tm; m; m &= m - 1) {
      const int i = packet_mask_first(m);
      const uint64_t bit = 1ull << i;
      bp->tris[i]++;
      float t, b1, b2;
      if (!trace_isect_tri(&bp->ir[i], tri->v[0], tri->v[1], tri->v[2], bp->tmin[i], bp->upper[i],
                           &t, &b1, &b2))
        continue;
      if (any_hit) {
        occ[i] = true;
        *live &= ~bit;
        act &= ~bit;
        continue;
      }
      if (!trav_hit_wins((*found & bit) != 0, t, p, bp->best_t[i], bp->best_p[i])) continue;
      *found |= bit;
      bp->best_t[i] = t;
      bp->upper[i] = float_next_up(t); /* equal t still competes on prim id */
      bp->best_p[i] = p;
      hits[i] = (struct trace_hit){t, (int32_t)p, b1, b2};
    }
  }
}

/* The smallest entry of slot k's rays: the packet's order of children. */
static float bp_near(const struct bvh_packet *bp, uint32_t k) {
  float t = INFINITY;
  for (uint64_t m = bp->kmask[k]; m; m &= m - 1) {
    const float x = bp->kt[k][packet_mask_first(m)];
    if (x < t) t = x;
  }
  return t;
}

/* Push the children entered (kmask) but the nearest, farthest first, their
 * rays' entries into the pool; the nearest becomes *cur with its rays.
 * False when no ray entered any. */
static bool bp_push(struct bvh_packet *bp, uint32_t width, const uint32_t ref[8],
                    const uint32_t count[8], int *sp, uint32_t *ptop, struct bp_entry *cur) {
  uint32_t order[8];
  float near[8];
  uint32_t m = 0;
  for (uint32_t k = 0; k < width; k++) {
    if (!bp->kmask[k]) continue;
    const float t = bp_near(bp, k);
    uint32_t j = m++;
    for (; j > 0 && t < near[j - 1]; j--) { /* stable: ties keep slot order */
      near[j] = near[j - 1];
      order[j] = order[j - 1];
    }
    near[j] = t;
    order[j] = k;
  }
  if (m == 0) return false;
  CHECK_LE(*sp + (int)m - 1, BP_STACK);
  for (uint32_t j = m; j-- > 1;) {
    const uint32_t k = order[j];
    struct bp_entry *e = &bp->stack[(*sp)++];
    *e = (struct bp_entry){ref[k], count[k], *ptop, bp->kmask[k]};
    for (uint64_t x = e->mask; x; x &= x - 1) bp->pool[(*ptop)++] = bp->kt[k][packet_mask_first(x)];
  }
  const uint32_t k = order[0];
  *cur = (struct bp_entry){ref[k], count[k], 0, bp->kmask[k]};
  return true;
}

/* The next pending child with the rays still live whose best hit does not
 * lie before their entry; false when none is left. */
static bool bp_pop(struct bvh_packet *bp, int *sp, uint32_t *ptop, uint64_t live, uint64_t found,
                   struct bp_entry *cur) {
  while (*sp > 0) {
    const struct bp_entry *e = &bp->stack[--(*sp)];
    *ptop = e->base;
    uint64_t act = 0;
    uint32_t k = e->base;
    for (uint64_t x = e->mask; x; x &= x - 1, k++) {
      const int i = packet_mask_first(x);
      if (!((live >> i) & 1u)) continue;
      if ((found >> i) & 1u && bp->best_t[i] < bp->pool[k]) continue;
      act |= 1ull << i;
    }
    if (!act) continue;
    *cur = (struct bp_entry){e->ref, e->count, 0, act};
    return true;
  }
  return false;
}

void bvh_packet_traverse(struct trace_ctx *tr, struct bvh_packet *bp, const struct ray *rays,
                         uint32_t n, bool any_hit, struct trace_hit *hits, bool *occ,
                         struct trace_packet_cost *cost) {
  CHECK_LE(n, BP_MAX);
  const struct bvh *b = tr->bvh;
  const uint32_t width = b->kind == ACCEL_BVH8 ? 8 : 2, node_bytes = bt_node_bytes(b);
  uint64_t found = 0, live = bp_setup(b, bp, rays, n, any_hit, hits, occ);
  int sp = 0;
  uint32_t ptop = 0;
  struct bp_entry cur = {0, 0, 0, live};
  bool more = live != 0;
  while (more) {
    if (cur.count == 0) {
      uint32_t ref[8], count[8];
      const uint32_t slots = bp_slots(b, cur.ref, ref, count);
      const uint32_t tested = bp_node(b, bp, cur.ref, cur.mask, found, ref, count);
      CHECK_EQ(tested, slots);
      mem_load(&tr->mem, tr->layout.node_base + (uint64_t)node_bytes * cur.ref, node_bytes,
               TRACE_CLASS_NODE);
      mem_compute(&tr->mem, 3ull * tr->layout.node_cycles * tested * packet_mask_count(cur.mask));
      tr->stats.node_visits++;
      if (bp_push(bp, width, ref, count, &sp, &ptop, &cur)) continue;
    } else {
      bp_leaf(tr, bp, cur.ref, cur.count, cur.mask, any_hit, hits, occ, &live, &found);
    }
    more = bp_pop(bp, &sp, &ptop, live, found, &cur);
  }
  if (cost)
    for (uint32_t i = 0; i < n; i++) {
      cost->nodes[i] = bp->nodes[i];
      cost->tris[i] = bp->tris[i];
    }
}
