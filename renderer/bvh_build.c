/* The binary BVH's build: a top-down binned SAH (BVH_BINS bins of triangle
 * centroids per axis, Wald 2007), with an explicit work list so that no
 * scene can exhaust the host stack. A range becomes a leaf when it holds one
 * triangle, or at most BVH_LEAF_MAX and the SAH prices the leaf no higher
 * than the best split; a range no bin plane separates (centroids that
 * coincide) and every range below BVH_SAH_DEPTH splits at its median along
 * the widest centroid axis, which bounds the depth. The leaf lists are the
 * triangle ids partitioned in place, so each triangle is in one leaf. */
#include "renderer/bvh.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "renderer/scene.h"
#include "sim/err.h"

/* SAH costs relative to one triangle test: a node visit (its child boxes). */
#define BVH_COST_NODE 1.0

const char *const accel_names[ACCEL_COUNT] = {"kd", "bvh2", "bvh8"};

struct box {
  float lo[3], hi[3];
};

static void box_empty(struct box *b) {
  for (int a = 0; a < 3; a++) {
    b->lo[a] = FLT_MAX;
    b->hi[a] = -FLT_MAX;
  }
}

/* Written as selects (min and max instructions, no branches to mispredict). */
static void box_grow(struct box *b, const struct box *o) {
  for (int a = 0; a < 3; a++) {
    b->lo[a] = o->lo[a] < b->lo[a] ? o->lo[a] : b->lo[a];
    b->hi[a] = o->hi[a] > b->hi[a] ? o->hi[a] : b->hi[a];
  }
}

static double box_area(const struct box *b) { return bvh_box_area(b->lo, b->hi); }

struct task {
  uint32_t begin, end, depth, parent, slot; /* parent BVH_EMPTY: the root */
};

struct builder {
  struct bvh *b;
  struct box *tb;  /* triangle bounds */
  float (*cen)[3]; /* centroids */
  struct task *todo;
  uint32_t ntodo, cap_todo, cap_nodes;
  int sort_axis; /* the median split's axis, for cmp_centroid */
  double sah;    /* the tree's SAH cost so far (bvh_stats.sah_cost, not yet divided) */
};

static uint32_t new_node(struct builder *bd) {
  struct bvh *b = bd->b;
  if (b->node_count == bd->cap_nodes) {
    bd->cap_nodes = bd->cap_nodes ? 2 * bd->cap_nodes : 64;
    b->n2 = xrealloc(b->n2, (unsigned long long)bd->cap_nodes * sizeof *b->n2);
  }
  struct bvh2_node *n = &b->n2[b->node_count];
  memset(n, 0, sizeof *n);
  n->count[0] = n->count[1] = BVH_EMPTY;
  return b->node_count++;
}

static void push(struct builder *bd, struct task t) {
  if (bd->ntodo == bd->cap_todo) {
    bd->cap_todo = bd->cap_todo ? 2 * bd->cap_todo : 64;
    bd->todo = xrealloc(bd->todo, (unsigned long long)bd->cap_todo * sizeof *bd->todo);
  }
  bd->todo[bd->ntodo++] = t;
}

/* The binned SAH's bins: triangle counts and bounds, per axis. */
struct bins {
  struct box box[3][BVH_BINS];
  uint32_t n[3][BVH_BINS];
};

static int bin_of(float c, float lo, float k) {
  const int i = (int)((c - lo) * k);
  return i < 0 ? 0 : (i >= BVH_BINS ? BVH_BINS - 1 : i);
}

/* The best split of axis a's bins: true if one separates them, its price
 * and first upper bin if it beats *cost (or none was found yet). */
static bool sweep(const struct bins *bn, int a, double area, bool found, double *cost, int *bin) {
  double la[BVH_BINS];
  uint32_t lc[BVH_BINS];
  struct box acc;
  box_empty(&acc);
  uint32_t c = 0;
  for (int i = 0; i < BVH_BINS; i++) {
    box_grow(&acc, &bn->box[a][i]);
    c += bn->n[a][i];
    la[i] = box_area(&acc);
    lc[i] = c;
  }
  box_empty(&acc);
  c = 0;
  bool better = false;
  for (int i = BVH_BINS - 1; i > 0; i--) {
    box_grow(&acc, &bn->box[a][i]);
    c += bn->n[a][i];
    if (c == 0 || lc[i - 1] == 0) continue;
    const double s =
        BVH_COST_NODE + (la[i - 1] * lc[i - 1] + box_area(&acc) * c) / (area > 0 ? area : 1.0);
    if (!found || s < *cost) {
      found = better = true;
      *cost = s;
      *bin = i;
    }
  }
  return better;
}

/* The best binned SAH split of prims[begin, end) with centroid bounds cb:
 * its axis and the first bin of the upper side; the price in *cost
 * (relative to a triangle test). False when no bin plane separates them.
 * One pass over the triangles bins all three axes. */
static bool sah_split(const struct builder *bd, const uint32_t *prims, uint32_t begin, uint32_t end,
                      const struct box *node, const struct box *cb, int *axis, int *bin,
                      double *cost) {
  struct bins bn;
  float k[3];
  bool live[3];
  for (int a = 0; a < 3; a++) {
    const float ext = cb->hi[a] - cb->lo[a];
    live[a] = ext > 0.0f;
    k[a] = live[a] ? (float)BVH_BINS * (1.0f - 1e-6f) / ext : 0.0f;
    for (int i = 0; i < BVH_BINS; i++) {
      box_empty(&bn.box[a][i]);
      bn.n[a][i] = 0;
    }
  }
  for (uint32_t j = begin; j < end; j++) {
    const uint32_t p = prims[j];
    for (int a = 0; a < 3; a++) {
      const int i = bin_of(bd->cen[p][a], cb->lo[a], k[a]);
      bn.n[a][i]++;
      box_grow(&bn.box[a][i], &bd->tb[p]);
    }
  }
  bool found = false;
  for (int a = 0; a < 3; a++)
    if (live[a] && sweep(&bn, a, box_area(node), found, cost, bin)) {
      found = true;
      *axis = a;
    }
  return found;
}

static int cmp_centroid(const uint32_t *x, const uint32_t *y, const struct builder *bd) {
  const uint32_t p = *x, q = *y;
  const float a = bd->cen[p][bd->sort_axis], b = bd->cen[q][bd->sort_axis];
  if (a != b) return a < b ? -1 : 1;
  return p < q ? -1 : (p > q);
}

/* Sort prims[begin, end) by (centroid on axis a, id): a bottom-up merge
 * sort, as C11's qsort takes no context for the axis. */
static void sort_range(struct builder *bd, uint32_t *prims, uint32_t begin, uint32_t end, int a) {
  bd->sort_axis = a;
  const uint32_t n = end - begin;
  uint32_t *tmp = xmalloc((unsigned long long)n * sizeof *tmp);
  uint32_t *src = prims + begin, *dst = tmp;
  for (uint32_t w = 1; w < n; w *= 2) {
    for (uint32_t i = 0; i < n; i += 2 * w) {
      uint32_t m = i + w < n ? i + w : n, e = i + 2 * w < n ? i + 2 * w : n;
      uint32_t l = i, r = m, o = i;
      while (l < m && r < e)
        dst[o++] = cmp_centroid(&src[l], &src[r], bd) <= 0 ? src[l++] : src[r++];
      while (l < m) dst[o++] = src[l++];
      while (r < e) dst[o++] = src[r++];
    }
    uint32_t *t = src;
    src = dst;
    dst = t;
  }
  if (src != prims + begin) memcpy(prims + begin, src, (size_t)n * sizeof *src);
  free(tmp);
}

/* Split prims[t.begin, t.end) in two (returns the middle) or return t.end
 * for a leaf. */
static uint32_t split_range(struct builder *bd, const struct task *t, const struct box *node,
                            const struct box *cb) {
  uint32_t *prims = bd->b->prims;
  const uint32_t n = t->end - t->begin;
  if (n <= 1) return t->end;
  int axis = 0, bin = 0;
  double cost = 0;
  const bool sah = t->depth < BVH_SAH_DEPTH &&
                   sah_split(bd, prims, t->begin, t->end, node, cb, &axis, &bin, &cost);
  if (sah && n <= BVH_LEAF_MAX && (double)n <= cost) return t->end;
  if (sah) {
    const float k = (float)BVH_BINS * (1.0f - 1e-6f) / (cb->hi[axis] - cb->lo[axis]);
    uint32_t i = t->begin, j = t->end;
    while (i < j) {
      if (bin_of(bd->cen[prims[i]][axis], cb->lo[axis], k) < bin) {
        i++;
      } else {
        const uint32_t tmp = prims[i];
        prims[i] = prims[--j];
        prims[j] = tmp;
      }
    }
    return i;
  }
  if (n <= BVH_LEAF_MAX && t->depth < BVH_SAH_DEPTH) return t->end;
  /* The median along the widest centroid axis (coincident centroids: any
   * halving does, the ids order them). */
  int a = 0;
  for (int k = 1; k < 3; k++)
    if (cb->hi[k] - cb->lo[k] > cb->hi[a] - cb->lo[a]) a = k;
  sort_range(bd, prims, t->begin, t->end, a);
  return t->begin + n / 2;
}

/* One range: its box into its parent's slot, then a leaf or a node whose two
 * children are pushed. */
static void process(struct builder *bd, struct task t) {
  struct bvh *b = bd->b;
  struct box node, cb;
  box_empty(&node);
  box_empty(&cb);
  for (uint32_t j = t.begin; j < t.end; j++) {
    const uint32_t p = b->prims[j];
    box_grow(&node, &bd->tb[p]);
    const struct box c = {{bd->cen[p][0], bd->cen[p][1], bd->cen[p][2]},
                          {bd->cen[p][0], bd->cen[p][1], bd->cen[p][2]}};
    box_grow(&cb, &c);
  }
  const uint32_t mid = split_range(bd, &t, &node, &cb);
  const double area = box_area(&node);
  bd->sah += mid == t.end ? area * BVH_SAH_PRIM * (t.end - t.begin) : area * BVH_SAH_NODE;
  uint32_t parent = t.parent, slot = t.slot;
  if (parent == BVH_EMPTY) {
    b->lo = v3(node.lo[0], node.lo[1], node.lo[2]);
    b->hi = v3(node.hi[0], node.hi[1], node.hi[2]);
    if (mid != t.end) {
      new_node(bd); /* the root */
      push(bd, (struct task){mid, t.end, 1, 0, 1});
      push(bd, (struct task){t.begin, mid, 1, 0, 0});
      return;
    }
    parent = new_node(bd); /* a root leaf: a node of one leaf child */
    bd->sah += area * BVH_SAH_NODE;
    slot = 0;
  }
  struct bvh2_node *pn = &b->n2[parent];
  memcpy(pn->lo[slot], node.lo, sizeof node.lo);
  memcpy(pn->hi[slot], node.hi, sizeof node.hi);
  const uint32_t depth = t.depth > 0 ? t.depth : 1;
  if (mid == t.end) {
    pn->ref[slot] = t.begin;
    pn->count[slot] = t.end - t.begin;
    b->stats.leaves++;
    if (depth > b->stats.max_depth) b->stats.max_depth = depth;
    if (t.end - t.begin > b->stats.max_leaf_prims) b->stats.max_leaf_prims = t.end - t.begin;
    return;
  }
  const uint32_t ni = new_node(bd);
  pn = &b->n2[parent];
  pn->ref[slot] = ni;
  pn->count[slot] = 0;
  push(bd, (struct task){mid, t.end, depth + 1, ni, 1});
  push(bd, (struct task){t.begin, mid, depth + 1, ni, 0});
}

static void build2(struct bvh *b, const struct scene *s) {
  memset(b, 0, sizeof *b);
  b->kind = ACCEL_BVH2;
  const uint32_t n = s->tri_count;
  if (n == 0) return;
  struct builder bd;
  memset(&bd, 0, sizeof bd);
  bd.b = b;
  bd.tb = xmalloc((unsigned long long)n * sizeof *bd.tb);
  bd.cen = xmalloc((unsigned long long)n * sizeof *bd.cen);
  b->prims = xmalloc((unsigned long long)n * sizeof *b->prims);
  b->prim_count = n;
  for (uint32_t p = 0; p < n; p++) {
    const struct scene_tri *t = &s->tris[p];
    for (int a = 0; a < 3; a++) {
      const float x = v3_get(t->v[0], a), y = v3_get(t->v[1], a), z = v3_get(t->v[2], a);
      bd.tb[p].lo[a] = fminf(x, fminf(y, z));
      bd.tb[p].hi[a] = fmaxf(x, fmaxf(y, z));
      bd.cen[p][a] = 0.5f * bd.tb[p].lo[a] + 0.5f * bd.tb[p].hi[a];
    }
    b->prims[p] = p;
  }
  push(&bd, (struct task){0, n, 0, BVH_EMPTY, 0});
  while (bd.ntodo > 0) process(&bd, bd.todo[--bd.ntodo]);
  CHECK_LE(b->stats.max_depth, BVH_DEPTH_LIMIT);
  b->stats.nodes = b->node_count;
  b->stats.node_bytes = 64ull * b->node_count;
  const float lo[3] = {b->lo.x, b->lo.y, b->lo.z}, hi[3] = {b->hi.x, b->hi.y, b->hi.z};
  const double root = bvh_box_area(lo, hi);
  b->stats.sah_cost = root > 0 ? bd.sah / root : bd.sah;
  free(bd.tb);
  free(bd.cen);
  free(bd.todo);
}

void bvh_build(struct bvh *b, const struct scene *s, enum accel_kind kind) {
  CHECK(kind == ACCEL_BVH2 || kind == ACCEL_BVH8);
  if (kind == ACCEL_BVH2) {
    build2(b, s);
    return;
  }
  struct bvh b2;
  build2(&b2, s);
  bvh8_collapse(b, &b2);
  bvh_fini(&b2);
}

void bvh_fini(struct bvh *b) {
  if (!b) return;
  free(b->n2);
  free(b->n8);
  free(b->prims);
  memset(b, 0, sizeof *b);
}
