/* Treelet formation (treelet.h), on the k-d tree (nodes in depth-first
 * preorder: below child = this + 1, above child by index; a child's box is its
 * parent's cut at the split) or on a BVH (places, qpoint.h: a child's box is
 * the one its parent holds for it). */
#include "renderer/policy/treelet.h"

#include <stdlib.h>
#include <string.h>

#include "renderer/bvh.h"
#include "renderer/kdtree.h"
#include "renderer/policy/qpoint.h"
#include "sim/err.h"

struct box {
  float lo[3], hi[3];
};

/* A node with its box and half its box's surface area: the relative chance
 * that a ray crossing the root's box crosses the node's (the SAH's measure).
 * Boxes and areas are carried with the nodes waiting in the heap and in the
 * list of treelet roots, not kept for every node (36 bytes a node were 220
 * MB on sphereflake). */
struct cand {
  uint32_t node;
  struct box b;
  double area;
};

static struct cand cand_of(uint32_t node, const struct box *b) {
  struct cand c = {node, *b, 0.0};
  double d[3];
  for (int a = 0; a < 3; a++) d[a] = (double)b->hi[a] - (double)b->lo[a];
  c.area = d[0] * d[1] + d[1] * d[2] + d[2] * d[0];
  return c;
}

/* The children of interior k-d node c, boxes split at its plane. */
static void kd_children(const struct kd_tree *kd, const struct cand *c, struct cand out[2]) {
  struct kd_node nd = kd->nodes[c->node];
  uint32_t below = c->node + 1, above = kd_above(nd);
  CHECK_LT(below, kd->node_count);
  CHECK_GT(above, below);
  CHECK_LT(above, kd->node_count);
  int ax = kd_axis(nd);
  float s = kd_split(nd);
  struct box bb = c->b, ab = c->b;
  bb.hi[ax] = s;
  ab.lo[ax] = s;
  out[0] = cand_of(below, &bb);
  out[1] = cand_of(above, &ab);
}

/* The children of BVH node c (a place below the nodes) with the boxes it
 * holds for them (the 8-wide node's dequantized); returns how many. */
static uint32_t bvh_children(const struct bvh *b, const struct cand *c, struct cand out[8]) {
  uint32_t m = 0;
  for (int k = 0; k < (b->kind == ACCEL_BVH8 ? 8 : 2); k++) {
    uint32_t ref, count;
    struct box bx;
    if (b->kind == ACCEL_BVH8) {
      const struct bvh8_node *nd = &b->n8[c->node];
      bool interior;
      if (!bvh8_child(nd, k, &interior, &ref, &count)) continue;
      for (int a = 0; a < 3; a++) {
        const float sc = bvh8_scale(nd->e[a]);
        bx.lo[a] = bvh8_plane(nd->p[a], nd->qlo[a][k], sc);
        bx.hi[a] = bvh8_plane(nd->p[a], nd->qhi[a][k], sc);
      }
    } else {
      const struct bvh2_node *nd = &b->n2[c->node];
      if (nd->count[k] == BVH_EMPTY) continue;
      ref = nd->ref[k];
      count = nd->count[k];
      memcpy(bx.lo, nd->lo[k], sizeof bx.lo);
      memcpy(bx.hi, nd->hi[k], sizeof bx.hi);
    }
    out[m++] = cand_of(qpoint_bvh_place(b->node_count, ref, count), &bx);
  }
  return m;
}

struct former {
  const struct kd_tree *kd;
  const struct bvh *bvh;     /* the BVH's, else NULL */
  const uint8_t *leaf_count; /* on a BVH: triangles of the leaf at each entry */
  const uint32_t *tris;      /* distinct triangles in each subtree */
  uint32_t *stamp;           /* stamp[p] == t + 1: triangle p is in treelet t */
  uint32_t *fresh;           /* the triangles a trial just stamped */
  struct cand *heap;
  uint32_t heap_n, heap_cap;
  uint32_t *stack;
  uint32_t tri_bytes;
};

static int above_in_heap(const struct cand *a, const struct cand *b) {
  if (a->area != b->area) return a->area > b->area;
  return a->node < b->node;
}

static void heap_push(struct former *f, struct cand v) {
  if (f->heap_n == f->heap_cap) {
    f->heap_cap = f->heap_cap ? 2 * f->heap_cap : 64;
    f->heap = xrealloc(f->heap, (uint64_t)f->heap_cap * sizeof *f->heap);
  }
  uint32_t i = f->heap_n++;
  while (i > 0) {
    uint32_t p = (i - 1) / 2;
    if (!above_in_heap(&v, &f->heap[p])) break;
    f->heap[i] = f->heap[p];
    i = p;
  }
  f->heap[i] = v;
}

static struct cand heap_pop(struct former *f) {
  struct cand top = f->heap[0], v = f->heap[--f->heap_n];
  uint32_t i = 0;
  for (;;) {
    uint32_t c = 2 * i + 1;
    if (c >= f->heap_n) break;
    if (c + 1 < f->heap_n && above_in_heap(&f->heap[c + 1], &f->heap[c])) c++;
    if (!above_in_heap(&f->heap[c], &v)) break;
    f->heap[i] = f->heap[c];
    i = c;
  }
  if (f->heap_n) f->heap[i] = v;
  return top;
}

/* Stamps node v's triangles into treelet t and returns its bytes; the
 * triangles new to t are left in fresh[0..*fresh_n) so a refusal can undo. */
static uint64_t trial(struct former *f, uint32_t v, uint32_t t, uint32_t *fresh_n) {
  *fresh_n = 0;
  if (f->bvh) {
    /* A node its bytes; a leaf its index entries and triangles (each
     * triangle is in one leaf: all new). */
    if (v < f->bvh->node_count) return f->bvh->stats.node_bytes / f->bvh->node_count;
    const uint64_t cnt = f->leaf_count[v - f->bvh->node_count];
    return cnt * (4 + f->tri_bytes);
  }
  struct kd_node nd = f->kd->nodes[v];
  if (!kd_is_leaf(nd)) return 8;
  for (uint32_t j = 0; j < kd_leaf_count(nd); j++) {
    uint32_t p = f->kd->prims[kd_leaf_offset(nd) + j];
    if (f->stamp[p] == t + 1) continue;
    f->stamp[p] = t + 1;
    f->fresh[(*fresh_n)++] = p;
  }
  return 8 + (uint64_t)*fresh_n * f->tri_bytes;
}

/* A subtree without triangles joins treelet t whole: 8 bytes a node. */
static uint64_t absorb(struct former *f, struct treelet_set *ts, uint32_t c, uint32_t t) {
  CHECK(!f->bvh); /* every place of a BVH holds triangles */
  uint64_t bytes = 0;
  uint32_t sp = 0;
  f->stack[sp++] = c;
  while (sp) {
    uint32_t v = f->stack[--sp];
    ts->of[v] = t;
    bytes += 8;
    struct kd_node nd = f->kd->nodes[v];
    if (kd_is_leaf(nd)) continue;
    f->stack[sp++] = kd_above(nd);
    f->stack[sp++] = v + 1;
  }
  return bytes;
}

/* Is place v a leaf. */
static bool is_leaf(const struct former *f, uint32_t v) {
  return f->bvh ? v >= f->bvh->node_count : kd_is_leaf(f->kd->nodes[v]);
}

/* The partition from the root box rb, f made ready. */
static void form(struct treelet_set *ts, struct former *f, const struct box *rb) {
  /* Roots waiting to start their treelet, first in first out. */
  struct cand *todo = xmalloc(64 * sizeof *todo);
  uint32_t todo_head = 0, todo_tail = 0, todo_cap = 64;
  todo[todo_tail++] = cand_of(0, rb);
  while (todo_head < todo_tail) {
    struct cand r = todo[todo_head++];
    uint32_t t = ts->count++;
    uint64_t bytes = 0;
    ts->root[t] = r.node;
    heap_push(f, r);
    while (f->heap_n) {
      struct cand c = heap_pop(f);
      uint32_t v = c.node, fresh_n;
      uint64_t cost = trial(f, v, t, &fresh_n);
      if (v != r.node && bytes + cost > ts->budget) {
        for (uint32_t k = 0; k < fresh_n; k++) f->stamp[f->fresh[k]] = 0;
        if (todo_tail == todo_cap) {
          /* Reclaim the consumed head before growing. */
          memmove(todo, todo + todo_head, (uint64_t)(todo_tail - todo_head) * sizeof *todo);
          todo_tail -= todo_head;
          todo_head = 0;
          if (todo_tail == todo_cap) {
            todo_cap *= 2;
            todo = xrealloc(todo, (uint64_t)todo_cap * sizeof *todo);
          }
        }
        todo[todo_tail++] = c;
        continue;
      }
      ts->of[v] = t;
      bytes += cost;
      if (is_leaf(f, v)) continue;
      struct cand kids[8];
      uint32_t m = 2;
      if (f->bvh) m = bvh_children(f->bvh, &c, kids);
      else kd_children(f->kd, &c, kids);
      for (uint32_t k = 0; k < m; k++) {
        if (f->tris[kids[k].node] == 0) bytes += absorb(f, ts, kids[k].node, t);
        else heap_push(f, kids[k]);
      }
    }
    ts->bytes[t] = bytes;
  }
  free(todo);
}

static void alloc_set(struct treelet_set *ts, uint32_t n, uint64_t budget) {
  memset(ts, 0, sizeof *ts);
  ts->node_count = n;
  ts->budget = budget;
  ts->of = xmalloc((uint64_t)n * sizeof *ts->of + 1);
  for (uint32_t i = 0; i < n; i++) ts->of[i] = TREELET_NONE;
  ts->root = xmalloc((uint64_t)n * sizeof *ts->root + 1);
  ts->bytes = xmalloc((uint64_t)n * sizeof *ts->bytes + 1);
}

static void former_free(struct former *f) {
  free(f->stack);
  free(f->heap);
  free(f->fresh);
  free(f->stamp);
}

/* Forms the treelets of the whole structure (its box lo..hi), then frees
 * the former's own arrays. */
static void form_whole(struct treelet_set *ts, struct former *f, vec3 lo, vec3 hi) {
  struct box root_box;
  for (int a = 0; a < 3; a++) {
    root_box.lo[a] = v3_get(lo, a);
    root_box.hi[a] = v3_get(hi, a);
  }
  form(ts, f, &root_box);
  former_free(f);
}

void treelet_build(struct treelet_set *ts, const struct kd_tree *kd, uint32_t tri_bytes,
                   uint64_t budget) {
  const uint32_t n = kd->node_count;
  alloc_set(ts, n, budget);
  if (n == 0) return;

  uint32_t tri_count = 0, leaf_max = 0;
  for (uint32_t j = 0; j < kd->prim_ref_count; j++)
    if (kd->prims[j] + 1 > tri_count) tri_count = kd->prims[j] + 1;
  for (uint32_t i = 0; i < n; i++)
    if (kd_is_leaf(kd->nodes[i]) && kd_leaf_count(kd->nodes[i]) > leaf_max)
      leaf_max = kd_leaf_count(kd->nodes[i]);
  uint32_t *tris = xmalloc((uint64_t)n * sizeof *tris);
  qpoint_subtree_tris(kd, tris);
  struct former f = {
      .kd = kd,
      .tris = tris,
      .stamp = xcalloc((uint64_t)tri_count + 1, sizeof *f.stamp),
      .fresh = xmalloc(((uint64_t)leaf_max + 1) * sizeof *f.fresh),
      .stack = xmalloc((uint64_t)n * sizeof *f.stack),
      .tri_bytes = tri_bytes,
  };
  form_whole(ts, &f, kd->lo, kd->hi);
  free(tris);
}

void treelet_bvh_build(struct treelet_set *ts, const struct bvh *b, const uint8_t *leaf_count,
                       uint32_t tri_bytes, uint64_t budget) {
  const uint32_t n = qpoint_bvh_places(b);
  alloc_set(ts, n, budget);
  if (b->node_count == 0) return;
  uint32_t *tris = xmalloc((uint64_t)n * sizeof *tris);
  qpoint_bvh_subtree_tris(b, tris);
  struct former f = {
      .bvh = b,
      .leaf_count = leaf_count,
      .tris = tris,
      .stamp = xcalloc(1, sizeof *f.stamp),
      .fresh = xmalloc(sizeof *f.fresh),
      .stack = xmalloc((uint64_t)n * sizeof *f.stack),
      .tri_bytes = tri_bytes,
  };
  form_whole(ts, &f, b->lo, b->hi);
  free(tris);
}

void treelet_fini(struct treelet_set *ts) {
  if (!ts) return;
  free(ts->of);
  free(ts->root);
  free(ts->bytes);
  memset(ts, 0, sizeof *ts);
}
