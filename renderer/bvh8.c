/* The compressed 8-wide BVH, collapsed from the binary one: which subtrees
 * become its nodes and leaves is a chooser's (bvh8_plan.h: Ylitie et al.'s
 * SAH collapse by default); this lays them out and quantizes them. Leaves
 * hold at most BVH_LEAF_MAX triangles. Nodes are laid out breadth first, so
 * each node's interior children are consecutive and its leaves' lists too,
 * as the 80-byte node's two base indices need (bvh.h). Child boxes are
 * quantized to 8 bits per plane relative to the node's box: lo rounded down
 * and hi rounded up, then checked in bvh8_plane's arithmetic so the quantized
 * box contains the exact one as traversal computes it. */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "renderer/bvh.h"
#include "renderer/bvh8_plan.h"
#include "sim/err.h"

/* Axis a of node nd quantized for node box [lo, hi]: origin, exponent, and
 * each child's planes. */
static void quantize_axis(struct bvh8_node *nd, int a, float lo, float hi,
                          const struct bvh8_child *c, uint32_t n) {
  nd->p[a] = lo;
  int e = 1;
  const double ext = (double)hi - lo;
  if (ext > 0.0) {
    int k;
    frexp(ext / 255.0, &k); /* ext / 255 < 2^k */
    e = k + 127;
    e = e < 1 ? 1 : (e > 254 ? 254 : e);
  }
  while (e < 254 && bvh8_plane(lo, 255, bvh8_scale((uint8_t)e)) < hi) e++;
  nd->e[a] = (uint8_t)e;
  const float s = bvh8_scale((uint8_t)e);
  for (uint32_t k = 0; k < n; k++) {
    double ql = floor(((double)c[k].lo[a] - lo) / s), qh = ceil(((double)c[k].hi[a] - lo) / s);
    int l = ql < 0 ? 0 : (ql > 255 ? 255 : (int)ql), h = qh < 0 ? 0 : (qh > 255 ? 255 : (int)qh);
    while (l > 0 && bvh8_plane(lo, (uint8_t)l, s) > c[k].lo[a]) l--;
    while (h < 255 && bvh8_plane(lo, (uint8_t)h, s) < c[k].hi[a]) h++;
    CHECK(bvh8_plane(lo, (uint8_t)l, s) <= c[k].lo[a]);
    CHECK(bvh8_plane(lo, (uint8_t)h, s) >= c[k].hi[a]);
    nd->qlo[a][k] = (uint8_t)l;
    nd->qhi[a][k] = (uint8_t)h;
  }
}

struct collapse {
  struct bvh *b;
  const struct bvh *b2;
  bvh8_chooser choose;
  const void *ctx;
  double sah;            /* the tree's SAH cost so far, areas not yet divided */
  uint32_t *src, *depth; /* per BVH8 node: its binary node, its level */
  uint32_t cap;
};

static uint32_t new_node(struct collapse *c, uint32_t src, uint32_t depth) {
  struct bvh *b = c->b;
  if (b->node_count == c->cap) {
    c->cap = c->cap ? 2 * c->cap : 64;
    b->n8 = xrealloc(b->n8, (unsigned long long)c->cap * sizeof *b->n8);
    c->src = xrealloc(c->src, (unsigned long long)c->cap * sizeof *c->src);
    c->depth = xrealloc(c->depth, (unsigned long long)c->cap * sizeof *c->depth);
  }
  memset(&b->n8[b->node_count], 0, sizeof *b->n8);
  c->src[b->node_count] = src;
  c->depth[b->node_count] = depth;
  return b->node_count++;
}

/* Fill BVH8 node i: its children placed (interior ones allocated, leaf
 * lists appended), its meta bytes and its quantized boxes. */
static void fill(struct collapse *c, uint32_t i) {
  struct bvh8_child ch[8];
  const uint32_t n = c->choose(c->ctx, c->b2, c->src[i], ch);
  struct bvh *b = c->b;
  const uint32_t depth = c->depth[i];
  float lo[3] = {FLT_MAX, FLT_MAX, FLT_MAX}, hi[3] = {-FLT_MAX, -FLT_MAX, -FLT_MAX};
  for (uint32_t k = 0; k < n; k++)
    for (int a = 0; a < 3; a++) {
      lo[a] = fminf(lo[a], ch[k].lo[a]);
      hi[a] = fmaxf(hi[a], ch[k].hi[a]);
    }
  uint32_t child_base = b->node_count, prim_base = b->prim_count, interior = 0, entries = 0;
  uint8_t meta[8] = {0}, imask = 0;
  for (uint32_t k = 0; k < n; k++) {
    const double area = bvh_box_area(ch[k].lo, ch[k].hi);
    c->sah += ch[k].count == 0 ? area * BVH_SAH_NODE : area * BVH_SAH_PRIM * ch[k].count;
    if (ch[k].count == 0) {
      new_node(c, ch[k].ref, depth + 1);
      meta[k] = (uint8_t)(0x20u | (24u + interior++));
      imask |= (uint8_t)(1u << k);
      continue;
    }
    CHECK_LE(ch[k].count, BVH_LEAF_MAX);
    static const uint8_t unary[4] = {0, 0x20, 0x60, 0xe0};
    meta[k] = (uint8_t)(unary[ch[k].count] | entries);
    for (uint32_t j = 0; j < ch[k].count; j++)
      b->prims[b->prim_count++] = c->b2->prims[ch[k].ref + j];
    entries += ch[k].count;
    b->stats.leaves++;
    if (depth + 1 > b->stats.max_depth) b->stats.max_depth = depth + 1;
    if (ch[k].count > b->stats.max_leaf_prims) b->stats.max_leaf_prims = ch[k].count;
  }
  CHECK_LT(entries, 25u);
  struct bvh8_node *nd = &b->n8[i];
  nd->child_base = child_base;
  nd->prim_base = prim_base;
  nd->imask = imask;
  memcpy(nd->meta, meta, sizeof meta);
  for (int a = 0; a < 3; a++) quantize_axis(nd, a, lo[a], hi[a], ch, n);
}

void bvh8_collapse_with(struct bvh *b, const struct bvh *b2, bvh8_chooser choose, const void *ctx) {
  CHECK(b2->kind == ACCEL_BVH2);
  memset(b, 0, sizeof *b);
  b->kind = ACCEL_BVH8;
  b->lo = b2->lo;
  b->hi = b2->hi;
  if (b2->node_count == 0) return;
  struct collapse c = {b, b2, choose, ctx, 0.0, NULL, NULL, 0};
  b->prims = xmalloc((unsigned long long)b2->prim_count * sizeof *b->prims);
  const float lo[3] = {b->lo.x, b->lo.y, b->lo.z}, hi[3] = {b->hi.x, b->hi.y, b->hi.z};
  const double root = bvh_box_area(lo, hi);
  c.sah = root * BVH_SAH_NODE;
  new_node(&c, 0, 0);
  for (uint32_t i = 0; i < b->node_count; i++) fill(&c, i);
  CHECK_EQ(b->prim_count, b2->prim_count);
  b->stats.nodes = b->node_count;
  b->stats.node_bytes = 80ull * b->node_count;
  b->stats.sah_cost = root > 0 ? c.sah / root : c.sah;
  free(c.src);
  free(c.depth);
}

void bvh8_collapse(struct bvh *b, const struct bvh *b2) {
  struct bvh8_plan *p = bvh8_plan_create(b2);
  bvh8_collapse_with(b, b2, bvh8_plan_children, p);
  bvh8_plan_destroy(p);
}
