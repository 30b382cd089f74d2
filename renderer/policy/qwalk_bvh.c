/* The resumable walk on a BVH (qwalk_bvh.h). The uncut traversal
 * (bvh_trav.c) at a node tests the children's boxes, visits those entered
 * nearest first and leaves the others pending, so its pending stack on
 * arriving at a place is a function of the path there: at each node on it,
 * the children entered farther than the one the path takes (those nearer were
 * visited and are done). qwalk_bvh_to rebuilds that stack from the root with
 * the same arithmetic and the ray's carried best hit. That best is at least
 * as good as the one the uncut traversal had at those nodes, so a child it
 * then left pending may now not be entered, exactly when the uncut
 * traversal would drop it on popping it (its entry lies beyond the best): the
 * same children are visited, the same triangles tested. A child on the path
 * is always entered: a best hit found below it lies at or after its entry,
 * one found before it did not drop it.
 *
 * Accesses, as bvh_trav.c's: a node visit loads the node (64 or 80 bytes)
 * and computes 3 node_cycles a child box; a leaf entry loads its 4-byte
 * index, then its triangle. A walk stopping at a queue point does not visit
 * it: the ray loads it when it is taken from the queue. */
#include "renderer/policy/qwalk_bvh.h"

#include "renderer/bvh.h"
#include "renderer/bvh_node.h"
#include "renderer/policy/qpoint.h"
#include "renderer/scene.h"
#include "renderer/trav.h"
#include "sim/err.h"

/* Visit node ni: its children entered by w's ray, nearest first (stable, as
 * bvh_trav.c sorts them), as places into out, their entries into t; the
 * node's load and compute announced. Returns how many. */
static uint32_t visit(const struct qwalk_tree *t, struct trace_ctx *tr, struct qwalk *w,
                      uint32_t ni, uint32_t out[8], float te[8]) {
  const struct bvh *b = t->bvh;
  struct bt_entry kids[8];
  uint32_t tested = 0;
  const float t1 = w->best.found ? w->best.t : w->tv.t1;
  const uint32_t m = b->kind == ACCEL_BVH8
                         ? bt_children8(b, ni, &w->tv, w->tv.t0, t1, kids, &tested)
                         : bt_children2(b, ni, &w->tv, w->tv.t0, t1, kids, &tested);
  const uint32_t node_bytes = bt_node_bytes(b);
  mem_load(&tr->mem, tr->layout.node_base + (uint64_t)node_bytes * ni, node_bytes,
           TRACE_CLASS_NODE);
  mem_compute(&tr->mem, 3ull * tr->layout.node_cycles * tested);
  tr->stats.node_visits++;
  bt_sort_nearest(kids, m);
  for (uint32_t i = 0; i < m; i++) {
    out[i] = qpoint_bvh_place(b->node_count, kids[i].ref, kids[i].count);
    te[i] = kids[i].t;
  }
  return m;
}

/* Leave children [from, m) pending, farthest first. */
static void push(struct qwalk *w, const uint32_t *place, const float *te, uint32_t from,
                 uint32_t m) {
  CHECK_LE(w->sp + (int)(m - from), QWALK_BSTACK);
  for (uint32_t i = m; i-- > from;) w->bstack[w->sp++] = (struct qwalk_bentry){place[i], te[i]};
}

bool qwalk_bvh_leaf(const struct qwalk_tree *t, struct trace_ctx *tr, struct qwalk *w, uint32_t n,
                    uint32_t j0, uint32_t j1) {
  const struct bvh *b = t->bvh;
  CHECK_GE(n, b->node_count);
  const uint32_t first = n - b->node_count;
  for (uint32_t j = first + j0; j < first + j1; j++) {
    mem_load(&tr->mem, tr->layout.prim_idx_base + 4ull * j, 4, TRACE_CLASS_NODE);
    const uint32_t p = b->prims[j];
    if ((int64_t)p == (int64_t)w->ignore) continue;
    trav_announce_tri(tr, p, 1);
    const struct scene_tri *tri = &t->s->tris[p];
    float th, b1, b2;
    if (!trace_isect_tri(&w->ir, tri->v[0], tri->v[1], tri->v[2], w->tmin, w->best.upper, &th, &b1,
                         &b2))
      continue;
    trav_best_offer(&w->best, th, p, b1, b2);
    if (w->any) return true;
  }
  return false;
}

bool qwalk_bvh_pop(struct qwalk *w, int floor) {
  while (w->sp > floor) {
    const struct qwalk_bentry e = w->bstack[--w->sp];
    if (w->best.found && w->best.t < e.t) continue;
    w->ni = e.place;
    return true;
  }
  return false;
}

/* One step at w->ni: a node's children entered (the nearest next, the rest
 * pending), or a leaf tested. False when the walk goes on by popping; *hit
 * when a leaf ended a shadow ray. */
static bool step(const struct qwalk_tree *t, struct trace_ctx *tr, struct qwalk *w, bool *hit) {
  const struct bvh *b = t->bvh;
  *hit = false;
  if (w->ni < b->node_count) {
    uint32_t place[8];
    float te[8];
    const uint32_t m = visit(t, tr, w, w->ni, place, te);
    if (m == 0) return false;
    push(w, place, te, 1, m);
    w->ni = place[0];
    return true;
  }
  *hit = qwalk_bvh_leaf(t, tr, w, w->ni, 0, t->leaf_count[w->ni - b->node_count]);
  return false;
}

enum qwalk_end qwalk_bvh_run(const struct qwalk_tree *t, struct trace_ctx *tr, struct qwalk *w,
                             int floor, bool to_queue) {
  for (;;) {
    if (to_queue && qpoint_marked(t->mark, w->ni)) return QWALK_QUEUED;
    /* Every leaf is a queue point or below one. */
    CHECK(!to_queue || w->ni < t->bvh->node_count);
    bool hit;
    if (step(t, tr, w, &hit)) continue;
    if (hit) return QWALK_HIT;
    if (!qwalk_bvh_pop(w, floor)) return QWALK_DONE;
  }
}

enum qwalk_end qwalk_bvh_run_treelet(const struct qwalk_tree *t, struct trace_ctx *tr,
                                     struct qwalk *w, const uint32_t *of) {
  const uint32_t cur = of[w->ni];
  for (;;) {
    if (of[w->ni] != cur) return QWALK_QUEUED;
    bool hit;
    if (step(t, tr, w, &hit)) continue;
    if (hit) return QWALK_HIT;
    if (!qwalk_bvh_pop(w, 0)) return QWALK_DONE;
  }
}

void qwalk_bvh_to(const struct qwalk_tree *t, struct trace_ctx *tr, struct qwalk *w, uint32_t q) {
  /* The path, from q up to the root (as deep as the BVH). */
  uint32_t path[BVH_DEPTH_LIMIT + 2], d = 0;
  for (uint32_t v = q; v != 0; v = t->parent[v]) {
    CHECK_LT(d, BVH_DEPTH_LIMIT + 1);
    CHECK_NE(t->parent[v], UINT32_MAX);
    path[d++] = v;
  }
  CHECK_EQ(w->ni, 0);
  while (d > 0) {
    const uint32_t c = path[--d];
    uint32_t place[8];
    float te[8];
    const uint32_t m = visit(t, tr, w, w->ni, place, te);
    uint32_t j = 0;
    while (j < m && place[j] != c) j++;
    CHECK_LT(j, m); /* the path's child is entered (above) */
    push(w, place, te, j + 1, m);
    w->ni = c;
  }
}
