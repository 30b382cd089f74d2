/* Queue-point selection. Nodes are in depth-first preorder (below child =
 * this + 1, above child after the below subtree), so node n's subtree is the
 * index range [n, end[n]) and parents precede children: every pass here is a
 * plain forward or backward scan, with no recursion. */
#include "renderer/qpoint.h"

#include <stdlib.h>
#include <string.h>

#include "renderer/kdtree.h"
#include "sim/err.h"

#define QPOINT_NONE UINT32_MAX

/* end[n]: one past the last node of n's subtree. */
static void subtree_ends(const struct kd_tree *kd, uint32_t *end) {
  for (uint32_t i = kd->node_count; i-- > 0;) {
    struct kd_node nd = kd->nodes[i];
    end[i] = kd_is_leaf(nd) ? i + 1 : end[kd_above(nd)];
  }
}

void qpoint_subtree_tris(const struct kd_tree *kd, uint32_t *out) {
  const uint32_t n = kd->node_count;
  if (n == 0) return;
  uint32_t *parent = xmalloc((uint64_t)n * sizeof *parent);
  uint32_t *end = xmalloc((uint64_t)n * sizeof *end);
  int64_t *acc = xcalloc(n, sizeof *acc);
  parent[0] = QPOINT_NONE;
  for (uint32_t i = 0; i < n; i++) {
    struct kd_node nd = kd->nodes[i];
    if (kd_is_leaf(nd)) continue;
    CHECK_LT(i + 1, n);
    CHECK_GT(kd_above(nd), i + 1);
    CHECK_LT(kd_above(nd), n);
    parent[i + 1] = i;
    parent[kd_above(nd)] = i;
  }
  subtree_ends(kd, end);

  /* Each triangle's leaves in increasing node order (a counting sort). */
  uint32_t tri_count = 0;
  for (uint32_t j = 0; j < kd->prim_ref_count; j++)
    if (kd->prims[j] + 1 > tri_count) tri_count = kd->prims[j] + 1;
  uint32_t *start = xcalloc((uint64_t)tri_count + 1, sizeof *start);
  uint32_t *list = xmalloc((uint64_t)kd->prim_ref_count * sizeof *list + 1);
  for (uint32_t i = 0; i < n; i++) {
    struct kd_node nd = kd->nodes[i];
    if (!kd_is_leaf(nd)) continue;
    for (uint32_t j = 0; j < kd_leaf_count(nd); j++) start[kd->prims[kd_leaf_offset(nd) + j] + 1]++;
  }
  for (uint32_t p = 0; p < tri_count; p++) start[p + 1] += start[p];
  uint32_t *fill = xmalloc((uint64_t)tri_count * sizeof *fill + 1);
  memcpy(fill, start, (uint64_t)tri_count * sizeof *fill);
  for (uint32_t i = 0; i < n; i++) {
    struct kd_node nd = kd->nodes[i];
    if (!kd_is_leaf(nd)) continue;
    for (uint32_t j = 0; j < kd_leaf_count(nd); j++) list[fill[kd->prims[kd_leaf_offset(nd) + j]]++] = i;
  }
  free(fill);

  /* +1 at each leaf, -1 at the meeting point of consecutive leaves: after the
   * subtree sums, a subtree counts each of its triangles once. The lowest
   * common ancestor of leaves a <= b is the first ancestor of a whose range
   * holds b; consecutive leaves of a triangle are near each other, so the walk
   * is short. A repeated reference (a == b) cancels itself. */
  for (uint32_t p = 0; p < tri_count; p++) {
    for (uint32_t k = start[p]; k < start[p + 1]; k++) {
      acc[list[k]]++;
      if (k == start[p]) continue;
      uint32_t a = list[k - 1], b = list[k], x = a;
      while (end[x] <= b) x = parent[x];
      acc[x]--;
    }
  }
  for (uint32_t i = n; i-- > 1;) acc[parent[i]] += acc[i];
  for (uint32_t i = 0; i < n; i++) {
    CHECK_GE(acc[i], 0);
    CHECK_LE(acc[i], (int64_t)tri_count);
    out[i] = (uint32_t)acc[i];
  }
  free(start);
  free(list);
  free(acc);
  free(end);
  free(parent);
}

void qpoint_select(struct qpoint_set *qs, const struct kd_tree *kd, const uint32_t *tris,
                   uint32_t tri_bytes, uint64_t gmax_bytes) {
  const uint32_t n = kd->node_count;
  memset(qs, 0, sizeof *qs);
  qs->node_count = n;
  qs->gmax_bytes = gmax_bytes;
  qs->nodes = xmalloc((uint64_t)n * sizeof *qs->nodes + 1);
  if (n) memcpy(qs->nodes, kd->nodes, (uint64_t)n * sizeof *qs->nodes);
  uint32_t *end = xmalloc((uint64_t)n * sizeof *end + 1);
  subtree_ends(kd, end);
  uint32_t cap = 64;
  qs->qnode = xmalloc(cap * sizeof *qs->qnode);
  /* A preorder walk that skips the subtree of each queue point it marks: the
   * first qualifying node on every branch, in increasing node order. */
  for (uint32_t i = 0; i < n;) {
    struct kd_node *nd = &qs->nodes[i];
    kd_set_queue_point(nd, false);
    if (tris[i] == 0) { /* no geometry: nothing to queue for */
      for (uint32_t j = i; j < end[i]; j++) kd_set_queue_point(&qs->nodes[j], false);
      i = end[i];
      continue;
    }
    if (kd_is_leaf(*nd) || (uint64_t)tris[i] * tri_bytes <= gmax_bytes) {
      kd_set_queue_point(nd, true);
      if (qs->count == cap) {
        cap *= 2;
        qs->qnode = xrealloc(qs->qnode, (uint64_t)cap * sizeof *qs->qnode);
      }
      qs->qnode[qs->count++] = i;
      for (uint32_t j = i + 1; j < end[i]; j++) kd_set_queue_point(&qs->nodes[j], false);
      i = end[i];
      continue;
    }
    i++; /* interior above the queue points: its below child is next */
  }
  free(end);
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

void qpoint_plan(struct qpoint_set *qs, struct qpoint_budget *b, const struct kd_tree *kd,
                 const uint32_t *tris, uint32_t tri_bytes, const struct qpoint_reserve *r) {
  b->node_bytes = min_u64(8ull * kd->node_count, share(r->cache_bytes, r->node_share));
  b->ray_bytes = min_u64(r->ray_buffer_bytes, share(r->cache_bytes, r->ray_share));
  b->table_bytes = share(r->cache_bytes, r->table_share);
  qpoint_select(qs, kd, tris, tri_bytes, gmax_of(r, b));
  if (8ull * qs->count < b->table_bytes) {
    b->table_bytes = 8ull * qs->count;
    uint64_t old = qs->gmax_bytes;
    if (gmax_of(r, b) != old) {
      uint32_t before = qs->count;
      qpoint_fini(qs);
      qpoint_select(qs, kd, tris, tri_bytes, b->gmax_bytes);
      CHECK_LE(qs->count, before);
    }
  }
}

int64_t qpoint_index(const struct qpoint_set *qs, uint32_t n) {
  uint32_t lo = 0, hi = qs->count;
  while (lo < hi) {
    uint32_t mid = lo + (hi - lo) / 2;
    if (qs->qnode[mid] < n)
      lo = mid + 1;
    else
      hi = mid;
  }
  return lo < qs->count && qs->qnode[lo] == n ? (int64_t)lo : -1;
}

void qpoint_fini(struct qpoint_set *qs) {
  if (!qs) return;
  free(qs->nodes);
  free(qs->qnode);
  memset(qs, 0, sizeof *qs);
}
