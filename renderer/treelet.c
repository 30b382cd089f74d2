/* Treelet formation (treelet.h). Nodes are in depth-first preorder (below
 * child = this + 1, above child by index), so a node's box follows from its
 * parent's in one forward scan. */
#include "renderer/treelet.h"

#include <stdlib.h>
#include <string.h>

#include "renderer/kdtree.h"
#include "renderer/qpoint.h"
#include "sim/err.h"

struct box {
  float lo[3], hi[3];
};

/* Half the surface area of every node's box: the relative chance that a ray
 * crossing the root's box crosses the node's (the SAH's measure). */
static double *node_areas(const struct kd_tree *kd) {
  const uint32_t n = kd->node_count;
  struct box *b = xmalloc((uint64_t)n * sizeof *b);
  double *area = xmalloc((uint64_t)n * sizeof *area);
  for (int a = 0; a < 3; a++) {
    b[0].lo[a] = v3_get(kd->lo, a);
    b[0].hi[a] = v3_get(kd->hi, a);
  }
  for (uint32_t i = 0; i < n; i++) {
    double d[3];
    for (int a = 0; a < 3; a++) d[a] = (double)b[i].hi[a] - (double)b[i].lo[a];
    area[i] = d[0] * d[1] + d[1] * d[2] + d[2] * d[0];
    struct kd_node nd = kd->nodes[i];
    if (kd_is_leaf(nd)) continue;
    uint32_t below = i + 1, above = kd_above(nd);
    CHECK_LT(below, n);
    CHECK_GT(above, below);
    CHECK_LT(above, n);
    int ax = kd_axis(nd);
    float s = kd_split(nd);
    b[below] = b[i];
    b[below].hi[ax] = s;
    b[above] = b[i];
    b[above].lo[ax] = s;
  }
  free(b);
  return area;
}

struct former {
  const struct kd_tree *kd;
  const double *area;
  const uint32_t *tris;  /* distinct triangles in each subtree */
  uint32_t *stamp;       /* stamp[p] == t + 1: triangle p is in treelet t */
  uint32_t *fresh;       /* the triangles a trial just stamped */
  uint32_t *heap, heap_n;
  uint32_t *stack;
  uint32_t tri_bytes;
};

static int above_in_heap(const struct former *f, uint32_t a, uint32_t b) {
  if (f->area[a] != f->area[b]) return f->area[a] > f->area[b];
  return a < b;
}

static void heap_push(struct former *f, uint32_t v) {
  uint32_t i = f->heap_n++;
  while (i > 0) {
    uint32_t p = (i - 1) / 2;
    if (!above_in_heap(f, v, f->heap[p])) break;
    f->heap[i] = f->heap[p];
    i = p;
  }
  f->heap[i] = v;
}

static uint32_t heap_pop(struct former *f) {
  uint32_t top = f->heap[0], v = f->heap[--f->heap_n], i = 0;
  for (;;) {
    uint32_t c = 2 * i + 1;
    if (c >= f->heap_n) break;
    if (c + 1 < f->heap_n && above_in_heap(f, f->heap[c + 1], f->heap[c])) c++;
    if (!above_in_heap(f, f->heap[c], v)) break;
    f->heap[i] = f->heap[c];
    i = c;
  }
  if (f->heap_n) f->heap[i] = v;
  return top;
}

/* Stamps node v's triangles into treelet t and returns its bytes; the
 * triangles new to t are left in fresh[0..*fresh_n) so a refusal can undo. */
static uint64_t trial(struct former *f, uint32_t v, uint32_t t, uint32_t *fresh_n) {
  struct kd_node nd = f->kd->nodes[v];
  *fresh_n = 0;
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

void treelet_build(struct treelet_set *ts, const struct kd_tree *kd, uint32_t tri_bytes,
                   uint64_t budget) {
  const uint32_t n = kd->node_count;
  memset(ts, 0, sizeof *ts);
  ts->node_count = n;
  ts->budget = budget;
  ts->of = xmalloc((uint64_t)n * sizeof *ts->of + 1);
  ts->root = xmalloc((uint64_t)n * sizeof *ts->root + 1);
  ts->bytes = xmalloc((uint64_t)n * sizeof *ts->bytes + 1);
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
      .area = node_areas(kd),
      .tris = tris,
      .stamp = xcalloc((uint64_t)tri_count + 1, sizeof *f.stamp),
      .fresh = xmalloc(((uint64_t)leaf_max + 1) * sizeof *f.fresh),
      .heap = xmalloc((uint64_t)n * sizeof *f.heap),
      .stack = xmalloc((uint64_t)n * sizeof *f.stack),
      .tri_bytes = tri_bytes,
  };
  /* Roots waiting to start their treelet, first in first out. Every node
   * enters the heap once (from its parent) and leaves it into a treelet or
   * into this list, so n entries suffice. */
  uint32_t *todo = xmalloc((uint64_t)n * sizeof *todo);
  uint32_t todo_head = 0, todo_tail = 0;
  todo[todo_tail++] = 0;
  while (todo_head < todo_tail) {
    uint32_t r = todo[todo_head++], t = ts->count++;
    uint64_t bytes = 0;
    ts->root[t] = r;
    heap_push(&f, r);
    while (f.heap_n) {
      uint32_t v = heap_pop(&f), fresh_n;
      uint64_t cost = trial(&f, v, t, &fresh_n);
      if (v != r && bytes + cost > budget) {
        for (uint32_t k = 0; k < fresh_n; k++) f.stamp[f.fresh[k]] = 0;
        todo[todo_tail++] = v;
        continue;
      }
      ts->of[v] = t;
      bytes += cost;
      struct kd_node nd = kd->nodes[v];
      if (kd_is_leaf(nd)) continue;
      uint32_t kids[2] = {v + 1, kd_above(nd)};
      for (int k = 0; k < 2; k++) {
        if (tris[kids[k]] == 0)
          bytes += absorb(&f, ts, kids[k], t);
        else
          heap_push(&f, kids[k]);
      }
    }
    ts->bytes[t] = bytes;
  }
  free(todo);
  free(f.stack);
  free(f.heap);
  free(f.fresh);
  free(f.stamp);
  free((void *)f.area);
  free(tris);
}

void treelet_fini(struct treelet_set *ts) {
  if (!ts) return;
  free(ts->of);
  free(ts->root);
  free(ts->bytes);
  memset(ts, 0, sizeof *ts);
}
