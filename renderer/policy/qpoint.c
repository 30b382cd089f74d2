/* Queue-point selection. Nodes are in depth-first preorder (below child =
 * this + 1, above child after the below subtree), so parents precede
 * children: every pass here is a plain forward or backward scan or a walk
 * with a stack as deep as the tree, with no recursion. */
#include "renderer/policy/qpoint.h"

#include <stdlib.h>
#include <string.h>

#include "renderer/bvh.h"
#include "renderer/kdtree.h"
#include "sim/err.h"

#define QPOINT_NONE UINT32_MAX

void qpoint_subtree_tris(const struct kd_tree *kd, uint32_t *out) {
  const uint32_t n = kd->node_count;
  if (n == 0) return;
  /* Parents, for the meeting points below. */
  uint32_t *parent = xmalloc((uint64_t)n * sizeof *parent);
  parent[0] = QPOINT_NONE;
  for (uint32_t i = 0; i < n; i++) {
    struct kd_node nd = kd->nodes[i];
    if (kd_is_leaf(nd)) continue;
    CHECK_LT(i + 1, n);
    CHECK_GT(kd_above(nd), i + 1);
    CHECK_LT(kd_above(nd), n);
    parent[i + 1] = parent[kd_above(nd)] = i;
  }

  uint32_t tri_count = 0;
  for (uint32_t j = 0; j < kd->prim_ref_count; j++)
    if (kd->prims[j] + 1 > tri_count) tri_count = kd->prims[j] + 1;
  /* The last leaf (in node order) each triangle was seen in. */
  uint32_t *last = xmalloc((uint64_t)tri_count * sizeof *last + 1);
  for (uint32_t p = 0; p < tri_count; p++) last[p] = QPOINT_NONE;

  /* +1 at each leaf, -1 at the meeting point of a triangle's consecutive
   * leaves (leaves are visited in increasing node order, so last[p] and i
   * are consecutive): after the subtree sums, a subtree counts each of its
   * triangles once. The lowest common ancestor of leaves a < i is the first
   * node at or above i whose index is at most a: a subtree is the run of
   * node indices from its root, so an ancestor of i numbered at most a holds
   * a (a lies between it and i), and one numbered above a does not. So only
   * i climbs, and no depths are needed; a triangle's consecutive leaves are
   * near each other, so the climb is short. A repeated reference (a == i)
   * cancels itself. Sums are kept in out modulo 2^32: a partial sum may go
   * below zero, every final one is a count. */
  memset(out, 0, (uint64_t)n * sizeof *out);
  for (uint32_t i = 0; i < n; i++) {
    struct kd_node nd = kd->nodes[i];
    if (!kd_is_leaf(nd)) continue;
    for (uint32_t j = 0; j < kd_leaf_count(nd); j++) {
      uint32_t p = kd->prims[kd_leaf_offset(nd) + j];
      out[i]++;
      uint32_t a = last[p];
      last[p] = i;
      if (a == QPOINT_NONE) continue;
      uint32_t x = i;
      while (x > a) x = parent[x];
      out[x]--;
    }
  }
  free(last);
  for (uint32_t i = n; i-- > 1;) out[parent[i]] += out[i];
  free(parent);
  for (uint32_t i = 0; i < n; i++) CHECK_LE(out[i], tri_count);
}

uint64_t *qpoint_mark_new(uint32_t n) { return xcalloc(n / 64 + 1, sizeof(uint64_t)); }

void qpoint_select(struct qpoint_set *qs, const struct kd_tree *kd, const uint32_t *tris,
                   uint32_t tri_bytes, uint64_t gmax_bytes) {
  const uint32_t n = kd->node_count;
  memset(qs, 0, sizeof *qs);
  qs->node_count = n;
  qs->gmax_bytes = gmax_bytes;
  qs->nodes = kd->nodes;
  qs->mark = qpoint_mark_new(n);
  uint32_t cap = 64;
  qs->qnode = xmalloc(cap * sizeof *qs->qnode);
  if (n == 0) return;
  /* A preorder walk that does not enter the subtree of a queue point it
   * marks: the first qualifying node on every branch, in increasing node
   * order. The stack holds the above children still to come (as many as the
   * tree is deep). */
  uint32_t stack[KD_DEPTH_LIMIT + 2], sp = 0;
  stack[sp++] = 0;
  while (sp) {
    uint32_t i = stack[--sp];
    if (tris[i] == 0) continue; /* no geometry: nothing to queue for */
    struct kd_node nd = kd->nodes[i];
    if (kd_is_leaf(nd) || (uint64_t)tris[i] * tri_bytes <= gmax_bytes) {
      qpoint_mark(qs->mark, i);
      if (qs->count == cap) {
        cap *= 2;
        qs->qnode = xrealloc(qs->qnode, (uint64_t)cap * sizeof *qs->qnode);
      }
      qs->qnode[qs->count++] = i;
      continue;
    }
    /* Interior above the queue points: its below child next, then above. */
    CHECK_LT(sp + 2, KD_DEPTH_LIMIT + 3);
    stack[sp++] = kd_above(nd);
    stack[sp++] = i + 1;
  }
}

static uint64_t share(uint64_t cache, uint32_t div) {
  CHECK_GT(div, 0);
  return cache / div;
}

static uint64_t min_u64(uint64_t a, uint64_t b) { return a < b ? a : b; }

static uint64_t gmax_of(const struct qpoint_reserve *r, struct qpoint_budget *b) {
  CHECK_GT(r->holders, 0);
  uint64_t used = b->node_bytes + b->table_bytes + b->ray_bytes;
  b->gmax_bytes = r->cache_bytes > used ? (r->cache_bytes - used) / r->holders : 0;
  return b->gmax_bytes;
}

/* The plan's shape, the structure's selection given: select(ctx, qs, gmax)
 * makes a selection for a bound, node_bytes is the structure's. */
typedef void (*select_fn)(const void *ctx, struct qpoint_set *qs, uint64_t gmax_bytes);

static void plan(struct qpoint_set *qs, struct qpoint_budget *b, uint64_t node_bytes,
                 const struct qpoint_reserve *r, select_fn select, const void *ctx) {
  b->node_bytes = min_u64(node_bytes, share(r->cache_bytes, r->node_share));
  b->ray_bytes = min_u64(r->ray_buffer_bytes, share(r->cache_bytes, r->ray_share));
  b->table_bytes = share(r->cache_bytes, r->table_share);
  select(ctx, qs, gmax_of(r, b));
  if (8ull * qs->count < b->table_bytes) {
    b->table_bytes = 8ull * qs->count;
    uint64_t old = qs->gmax_bytes;
    if (gmax_of(r, b) != old) {
      uint32_t before = qs->count;
      qpoint_fini(qs);
      select(ctx, qs, b->gmax_bytes);
      CHECK_LE(qs->count, before);
    }
  }
}

struct select_args {
  const struct kd_tree *kd;
  const struct bvh *bvh;
  const uint32_t *tris;
  uint32_t tri_bytes;
};

static void select_kd(const void *ctx, struct qpoint_set *qs, uint64_t gmax_bytes) {
  const struct select_args *a = ctx;
  qpoint_select(qs, a->kd, a->tris, a->tri_bytes, gmax_bytes);
}

static void select_bvh(const void *ctx, struct qpoint_set *qs, uint64_t gmax_bytes) {
  const struct select_args *a = ctx;
  qpoint_bvh_select(qs, a->bvh, a->tris, a->tri_bytes, gmax_bytes);
}

void qpoint_plan(struct qpoint_set *qs, struct qpoint_budget *b, const struct kd_tree *kd,
                 const uint32_t *tris, uint32_t tri_bytes, const struct qpoint_reserve *r) {
  const struct select_args a = {kd, NULL, tris, tri_bytes};
  plan(qs, b, 8ull * kd->node_count, r, select_kd, &a);
}

void qpoint_bvh_plan(struct qpoint_set *qs, struct qpoint_budget *b, const struct bvh *bvh,
                     const uint32_t *tris, uint32_t tri_bytes, const struct qpoint_reserve *r) {
  const struct select_args a = {NULL, bvh, tris, tri_bytes};
  plan(qs, b, bvh->stats.node_bytes, r, select_bvh, &a);
}

int64_t qpoint_index(const struct qpoint_set *qs, uint32_t n) {
  uint32_t lo = 0, hi = qs->count;
  while (lo < hi) {
    uint32_t mid = lo + (hi - lo) / 2;
    if (qs->qnode[mid] < n) lo = mid + 1;
    else hi = mid;
  }
  return lo < qs->count && qs->qnode[lo] == n ? (int64_t)lo : -1;
}

bool qpoint_leaf(const struct qpoint_set *qs, uint32_t n, uint32_t *first, uint32_t *count) {
  CHECK_LT(n, qs->node_count);
  if (qs->bvh) {
    const uint32_t nodes = qs->node_count - qs->bvh->prim_count;
    if (n < nodes) return false;
    *first = n - nodes;
    *count = qs->leaf_count[*first];
    return true;
  }
  const struct kd_node nd = qs->nodes[n];
  if (!kd_is_leaf(nd)) return false;
  *first = kd_leaf_offset(nd);
  *count = kd_leaf_count(nd);
  return true;
}

void qpoint_fini(struct qpoint_set *qs) {
  if (!qs) return;
  free(qs->mark);
  free(qs->qnode);
  free(qs->parent);
  free(qs->leaf_count);
  memset(qs, 0, sizeof *qs);
}
