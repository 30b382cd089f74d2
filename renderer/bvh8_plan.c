/* Ylitie, Karras and Laine's SAH collapse of a binary BVH into an 8-wide one
 * (HPG 2017, section 3.1): bottom up over the binary nodes, cost(n, i) for
 * i = 1..8 is the cheapest way to represent n's subtree with at most i roots,
 *   cost(n, 1) = min(leaf(n), node(n)),
 *   cost(n, i) = min(cost(n, i - 1), split(n, i)),   i > 1,
 *   leaf(n)    = A(n) BVH_SAH_PRIM triangles(n)  if triangles(n) <= BVH_LEAF_MAX,
 *   node(n)    = A(n) BVH_SAH_NODE + split(n, 8),
 *   split(n, j) = min over 0 < k < j of cost(left, k) + cost(right, j - k),
 * areas relative to nothing (the root's divides at the end); a binary leaf
 * costs leaf(n) for every i. rtsim's leaves hold at most BVH_LEAF_MAX = 3
 * triangles, as Ylitie et al.'s; a subtree of at most 3 becomes one leaf when
 * that is cheaper, its entries being consecutive in the binary BVH's prims
 * (the build partitions them in place). Ties keep the smaller choice: a leaf
 * before a node, fewer roots before more, the smallest k. Top down, a node's
 * children are split(n, 8)'s roots in the order of the binary tree (left
 * subtree's first), which is also the order of its slots.
 *
 * The binary build numbers its nodes in preorder (a node, its left subtree,
 * its right subtree), so going down the indices finishes the right subtree,
 * then the left, then the node: the cost rows still wanted (those of
 * finished nodes whose parent is not) form a stack no deeper than the tree,
 * the left child's row on top, the right child's under it. Only that stack
 * holds cost rows, not one row a node (64 bytes a binary node: 26 MB of
 * sphereflake's 409K); each pop checks it is the child it should be. */
#include "renderer/bvh8_plan.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sim/err.h"

/* A decision for (n, i): a leaf, a node, or k > 0 roots to the left child. */
#define PLAN_LEAF (-1)
#define PLAN_NODE 0

/* cost(n, i) for i = 1..8 of a finished binary node n. */
struct plan_row {
  uint32_t node;
  double cost[8]; /* cost[i - 1] */
};

struct bvh8_plan {
  struct plan_row *rows; /* the stack of rows still wanted */
  uint32_t nrows, cap;
  int8_t (*dec)[8];       /* the decision cost(n, i) took */
  uint8_t *split8;        /* k of split(n, 8): a node's children */
  uint32_t *first, *tris; /* n's subtree: its entries [first, first + tris) */
  double root;            /* node(root) / A(root) */
};

/* Slot k of binary node ni as a child. */
static struct bvh8_child slot(const struct bvh *b2, uint32_t ni, int k) {
  const struct bvh2_node *nd = &b2->n2[ni];
  struct bvh8_child c;
  memcpy(c.lo, nd->lo[k], sizeof c.lo);
  memcpy(c.hi, nd->hi[k], sizeof c.hi);
  c.ref = nd->ref[k];
  c.count = nd->count[k];
  return c;
}

/* A child's costs: its node's row, or a binary leaf's own price for every i. */
static void child_costs(struct bvh8_plan *p, const struct bvh8_child *c, double out[8]) {
  if (c->count == 0) {
    CHECK(p->nrows > 0);
    const struct plan_row *r = &p->rows[--p->nrows];
    CHECK_EQ(r->node, c->ref);
    memcpy(out, r->cost, sizeof r->cost);
    return;
  }
  const double leaf = bvh_box_area(c->lo, c->hi) * BVH_SAH_PRIM * c->count;
  for (int i = 0; i < 8; i++) out[i] = leaf;
}

/* split(n, j) of n's children's costs l and r: its cost and k. */
static double split(const double l[8], const double r[8], int j, int *k_best) {
  double best = INFINITY;
  for (int k = 1; k < j; k++) {
    const double c = l[k - 1] + r[j - k - 1];
    if (c < best) {
      best = c;
      *k_best = k;
    }
  }
  return best;
}

/* Binary node ni's row, its children's rows on the stack; a is its box's
 * area. Returns node(ni). */
static double plan_node(struct bvh8_plan *p, const struct bvh *b2, uint32_t ni, double a) {
  const struct bvh8_child l = slot(b2, ni, 0), r = slot(b2, ni, 1);
  CHECK(l.count != BVH_EMPTY && r.count != BVH_EMPTY);
  p->first[ni] = l.count ? l.ref : p->first[l.ref];
  p->tris[ni] = (l.count ? l.count : p->tris[l.ref]) + (r.count ? r.count : p->tris[r.ref]);
  double lc[8], rc[8];
  child_costs(p, &l, lc); /* the left child's row is on top */
  child_costs(p, &r, rc);
  int k8 = 1;
  const double node = a * BVH_SAH_NODE + split(lc, rc, 8, &k8);
  p->split8[ni] = (uint8_t)k8;
  const double leaf = p->tris[ni] <= BVH_LEAF_MAX ? a * BVH_SAH_PRIM * p->tris[ni] : INFINITY;
  if (p->nrows == p->cap) {
    p->cap = p->cap ? 2 * p->cap : 64;
    p->rows = xrealloc(p->rows, (unsigned long long)p->cap * sizeof *p->rows);
  }
  struct plan_row *row = &p->rows[p->nrows++];
  row->node = ni;
  row->cost[0] = leaf <= node ? leaf : node;
  p->dec[ni][0] = leaf <= node ? PLAN_LEAF : PLAN_NODE;
  for (int i = 2; i <= 8; i++) {
    int k = 1;
    const double s = split(lc, rc, i, &k);
    const bool take = s < row->cost[i - 2];
    row->cost[i - 1] = take ? s : row->cost[i - 2];
    p->dec[ni][i - 1] = take ? (int8_t)k : p->dec[ni][i - 2];
  }
  return node;
}

struct bvh8_plan *bvh8_plan_create(const struct bvh *b2) {
  CHECK(b2->kind == ACCEL_BVH2);
  struct bvh8_plan *p = xcalloc(1, sizeof *p);
  const uint32_t n = b2->node_count;
  if (n == 0) return p;
  p->dec = xmalloc((unsigned long long)n * sizeof *p->dec);
  p->split8 = xmalloc(n);
  p->first = xmalloc((unsigned long long)n * sizeof *p->first);
  p->tris = xmalloc((unsigned long long)n * sizeof *p->tris);
  /* A node's area is in its parent's slot; parents precede their children. */
  double *area = xmalloc((unsigned long long)n * sizeof *area);
  const float root_lo[3] = {b2->lo.x, b2->lo.y, b2->lo.z},
              root_hi[3] = {b2->hi.x, b2->hi.y, b2->hi.z};
  area[0] = bvh_box_area(root_lo, root_hi);
  for (uint32_t i = 0; i < n; i++)
    for (int k = 0; k < 2; k++)
      if (b2->n2[i].count[k] == 0) {
        CHECK_GT(b2->n2[i].ref[k], i);
        area[b2->n2[i].ref[k]] = bvh_box_area(b2->n2[i].lo[k], b2->n2[i].hi[k]);
      }
  /* A root of one leaf child (a scene of one leaf) needs no table. */
  const bool lone = b2->n2[0].count[1] == BVH_EMPTY;
  /* The root is an 8-wide node whatever its table chose: node(root). */
  double c = 0;
  for (uint32_t i = n; i-- > 0;) {
    if (i == 0 && lone) {
      const struct bvh8_child l = slot(b2, 0, 0);
      double lc[8];
      child_costs(p, &l, lc);
      c = area[0] * BVH_SAH_NODE + lc[0];
    } else {
      c = plan_node(p, b2, i, area[i]);
    }
  }
  CHECK(p->nrows <= 1); /* the root's own row, unless a lone leaf */
  free(p->rows);
  p->rows = NULL;
  p->nrows = p->cap = 0;
  p->root = area[0] > 0 ? c / area[0] : c;
  free(area);
  return p;
}

void bvh8_plan_destroy(struct bvh8_plan *p) {
  if (!p) return;
  free(p->rows);
  free(p->dec);
  free(p->split8);
  free(p->first);
  free(p->tris);
  free(p);
}

double bvh8_plan_cost(const struct bvh8_plan *p) { return p->root; }

/* Append to out the roots that represent child c with at most i of them. */
static void expand(const struct bvh8_plan *p, const struct bvh *b2, struct bvh8_child c, int i,
                   struct bvh8_child *out, uint32_t *n) {
  if (c.count != 0) {
    out[(*n)++] = c;
    return;
  }
  const int d = p->dec[c.ref][i - 1];
  if (d == PLAN_NODE) {
    out[(*n)++] = c;
  } else if (d == PLAN_LEAF) {
    c.count = p->tris[c.ref];
    c.ref = p->first[c.ref];
    out[(*n)++] = c;
  } else {
    expand(p, b2, slot(b2, c.ref, 0), d, out, n);
    expand(p, b2, slot(b2, c.ref, 1), i - d, out, n);
  }
}

uint32_t bvh8_plan_children(const void *plan, const struct bvh *b2, uint32_t ni,
                            struct bvh8_child out[8]) {
  const struct bvh8_plan *p = plan;
  uint32_t n = 0;
  if (b2->n2[ni].count[1] == BVH_EMPTY) {
    out[n++] = slot(b2, ni, 0);
    return n;
  }
  const int k = p->split8[ni];
  expand(p, b2, slot(b2, ni, 0), k, out, &n);
  expand(p, b2, slot(b2, ni, 1), 8 - k, out, &n);
  CHECK(n >= 2 && n <= 8);
  return n;
}

/* The greedy chooser: the two children, then the interior child of largest
 * area opened until there are eight or only leaves (Wald et al.'s and
 * Embree's wide BVHs). */
uint32_t bvh8_greedy_children(const void *ctx, const struct bvh *b2, uint32_t ni,
                              struct bvh8_child out[8]) {
  (void)ctx;
  uint32_t n = 0;
  for (int k = 0; k < 2; k++)
    if (b2->n2[ni].count[k] != BVH_EMPTY) out[n++] = slot(b2, ni, k);
  for (;;) {
    int best = -1;
    for (uint32_t k = 0; k < n; k++)
      if (out[k].count == 0 && (best < 0 || bvh_box_area(out[k].lo, out[k].hi) >
                                                bvh_box_area(out[best].lo, out[best].hi)))
        best = (int)k;
    if (best < 0 || n + 1 > 8) return n;
    const uint32_t open = out[best].ref;
    out[best] = out[n - 1];
    out[n - 1] = slot(b2, open, 0);
    out[n++] = slot(b2, open, 1);
  }
}
