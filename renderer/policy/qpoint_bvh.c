/* Queue points on a BVH (qpoint.h): the k-d tree's rule on the BVH's places
 * (its nodes, and its leaves, which are slots of their parents). A queue point
 * is the first place on a root-to-leaf branch whose triangles fit g_max; a
 * leaf reached without finding one is a queue point whatever its size. Node
 * indices need not follow the tree's order, so passes here walk with a stack
 * and the queue points are sorted into place order at the end. */
#include <stdlib.h>
#include <string.h>

#include "renderer/bvh.h"
#include "renderer/policy/qpoint.h"
#include "sim/err.h"

#define QB_NONE UINT32_MAX

uint32_t qpoint_bvh_places(const struct bvh *b) {
  CHECK_LE((uint64_t)b->node_count + b->prim_count, UINT32_MAX - 1);
  return b->node_count + b->prim_count;
}

/* The children of node ni as places; returns how many. */
static uint32_t kids_of(const struct bvh *b, uint32_t ni, uint32_t out[8], uint32_t cnt[8]) {
  uint32_t m = 0;
  if (b->kind == ACCEL_BVH8) {
    for (int k = 0; k < 8; k++) {
      bool interior;
      uint32_t ref, count;
      if (!bvh8_child(&b->n8[ni], k, &interior, &ref, &count)) continue;
      cnt[m] = count;
      out[m++] = qpoint_bvh_place(b->node_count, ref, count);
    }
    return m;
  }
  for (int k = 0; k < 2; k++) {
    const uint32_t count = b->n2[ni].count[k];
    if (count == BVH_EMPTY) continue;
    cnt[m] = count;
    out[m++] = qpoint_bvh_place(b->node_count, b->n2[ni].ref[k], count);
  }
  return m;
}

/* The places in preorder from the root (*n of them), each place's parent and
 * each leaf's triangle count (either may be NULL). */
static uint32_t *preorder(const struct bvh *b, uint32_t *n, uint32_t *parent, uint8_t *leaf_count) {
  const uint32_t places = qpoint_bvh_places(b);
  uint32_t *order = xmalloc((uint64_t)places * sizeof *order + 4);
  uint32_t *stack = xmalloc((uint64_t)places * sizeof *stack + 4);
  uint32_t sp = 0, k = 0;
  if (parent)
    for (uint32_t i = 0; i < places; i++) parent[i] = QB_NONE;
  if (leaf_count) memset(leaf_count, 0, b->prim_count + 1u);
  if (b->node_count > 0) stack[sp++] = 0;
  while (sp) {
    const uint32_t v = stack[--sp];
    order[k++] = v;
    if (v >= b->node_count) continue;
    uint32_t kids[8], cnt[8];
    const uint32_t m = kids_of(b, v, kids, cnt);
    for (uint32_t j = m; j-- > 0;) {
      CHECK_LT(sp, places);
      stack[sp++] = kids[j];
      if (parent) parent[kids[j]] = v;
      if (leaf_count && cnt[j] > 0) leaf_count[kids[j] - b->node_count] = (uint8_t)cnt[j];
    }
  }
  free(stack);
  *n = k;
  return order;
}

void qpoint_bvh_subtree_tris(const struct bvh *b, uint32_t *out) {
  const uint32_t places = qpoint_bvh_places(b);
  uint32_t *parent = xmalloc((uint64_t)places * sizeof *parent + 4);
  uint8_t *leaf_count = xmalloc((uint64_t)b->prim_count + 1);
  uint32_t n;
  uint32_t *order = preorder(b, &n, parent, leaf_count);
  memset(out, 0, (uint64_t)places * sizeof *out);
  /* Children after their parents in preorder: sum backwards. */
  for (uint32_t i = n; i-- > 0;) {
    const uint32_t v = order[i];
    if (v >= b->node_count) out[v] = leaf_count[v - b->node_count];
    if (parent[v] != QB_NONE) out[parent[v]] += out[v];
  }
  free(order);
  free(leaf_count);
  free(parent);
}

static int cmp_u32(const void *a, const void *b) {
  const uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
  return (x > y) - (x < y);
}

void qpoint_bvh_tree(struct qpoint_set *qs, const struct bvh *b) {
  const uint32_t places = qpoint_bvh_places(b);
  qs->bvh = b;
  qs->parent = xmalloc((uint64_t)places * sizeof *qs->parent + 4);
  qs->leaf_count = xmalloc((uint64_t)b->prim_count + 1);
  uint32_t n;
  free(preorder(b, &n, qs->parent, qs->leaf_count));
}

void qpoint_bvh_select(struct qpoint_set *qs, const struct bvh *b, const uint32_t *tris,
                       uint32_t tri_bytes, uint64_t gmax_bytes) {
  const uint32_t places = qpoint_bvh_places(b);
  memset(qs, 0, sizeof *qs);
  qs->node_count = places;
  qs->gmax_bytes = gmax_bytes;
  qs->mark = qpoint_mark_new(places);
  qpoint_bvh_tree(qs, b);
  qs->qnode = xmalloc(((uint64_t)places + 1) * sizeof *qs->qnode);
  if (b->node_count == 0) return;
  /* Preorder, not entering a queue point's subtree. */
  uint32_t *stack = xmalloc((uint64_t)places * sizeof *stack + 4), sp = 0;
  stack[sp++] = 0;
  while (sp) {
    const uint32_t v = stack[--sp];
    if (tris[v] == 0) continue; /* no geometry: nothing to queue for */
    if (v >= b->node_count || (uint64_t)tris[v] * tri_bytes <= gmax_bytes) {
      qpoint_mark(qs->mark, v);
      qs->qnode[qs->count++] = v;
      continue;
    }
    uint32_t kids[8], cnt[8];
    for (uint32_t j = kids_of(b, v, kids, cnt); j-- > 0;) stack[sp++] = kids[j];
  }
  free(stack);
  /* Queue indices in place order (qpoint_index searches them). */
  qsort(qs->qnode, qs->count, sizeof *qs->qnode, cmp_u32);
}
