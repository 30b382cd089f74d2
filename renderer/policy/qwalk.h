/* The resumable walk: a k-d traversal that pauses at queue points and resumes
 * there later, possibly on another worker, with exactly the arithmetic of
 * trace.c's (renderer/trav.h), so that a ray cut into pieces tests the same
 * triangles and finds the same hit as the ray traced in one go.
 *
 * Queue points are the nodes whose bit is set in the bitmap the walk is given
 * (qpoint_marked): the dynamic policy's (qpoint.h), or
 * any other set of subtree roots that holds every leaf with geometry below it
 * (a treelet policy marks its treelet roots). Nothing here queues a ray: the
 * walk only says where it stopped.
 *
 * - A closest-hit walk's pending stack is a function of the path from the
 *   root to the current node (the far children of the ancestors where it went
 *   near), so a walk resumed at queue point q rebuilds it by descending from
 *   the root to q with the same arithmetic (qwalk_to); its best hit so far
 *   travels in the ray record (hit_prim) and is recomputed bit for bit.
 * - A shadow ray's walk follows its segment reversed (from its end at the
 *   light back to the point, widened by 2^-16 at both ends), but every
 *   triangle is tested with the canonical ray: occlusion is whether any
 *   triangle crossing the segment is hit, and the reversed walk visits every
 *   leaf the segment crosses, so the answer is trace_any's. Private to
 *   renderer/. */
#ifndef RTSIM_RENDERER_POLICY_QWALK_H
#define RTSIM_RENDERER_POLICY_QWALK_H

#include <stdbool.h>
#include <stdint.h>

#include "renderer/bvh.h"
#include "renderer/kdtree.h"
#include "renderer/trace.h"
#include "renderer/trav.h"

struct ray;
struct scene;

/* What a walk reads: the tree, the scene (to recompute a carried hit) and the
 * nodes, and the queue points' bitmap (qpoint.h). Borrowed. On a BVH (bvh
 * set; qwalk_bvh.c walks it) nodes are NULL, the walk is at a place
 * (qpoint.h: a node or a leaf), and parent and leaf_count are the selection's
 * (qpoint_set). */
struct qwalk_tree {
  const struct kd_tree *kd;
  const struct scene *s;
  const struct kd_node *nodes;
  const uint64_t *mark;
  const struct bvh *bvh;
  const uint32_t *parent;
  const uint8_t *leaf_count;
};

/* A pending BVH child: its place and the ray's entry into its box. */
struct qwalk_bentry {
  uint32_t place;
  float t;
};
/* Pending BVH children: (width - 1) a level, as bvh_trav.c's stack. */
#define QWALK_BSTACK (BVH_DEPTH_LIMIT * 7 + 8)

/* One ray's walk: the scheduling traversal (for a shadow ray the reversed
 * segment), the canonical ray's test, the best hit so far, the current node
 * and its pending stack. */
struct qwalk {
  struct trav_ray tv;
  struct trace_isect_ray ir;
  float tmin;
  int32_t ignore;
  bool any;
  struct trav_best best;
  uint32_t ni; /* the node (on a BVH the place) the walk is at */
  float t0, t1;
  int sp;
  union { /* the pending nodes: the k-d tree's, or a BVH's */
    struct trav_entry stack[KD_DEPTH_LIMIT];
    struct qwalk_bentry bstack[QWALK_BSTACK];
  };
};

/* Where a walk stopped: it left the tree (or its subtree's pending nodes are
 * done), it reached a queue point (ni), or a shadow ray is occluded / a leaf
 * pass found the ray's end. */
enum qwalk_end { QWALK_DONE, QWALK_QUEUED, QWALK_HIT };

/* Prepare r's walk at the root, its carried hit (hit_prim) restored. False
 * when r ends without a traversal, exactly when trace.c's would (invalid ray,
 * empty tree, root box missed). */
bool qwalk_init(const struct qwalk_tree *t, struct qwalk *w, const struct ray *r);

/* Test entries [j0, j1) of leaf (place) n as trace.c does (announced through
 * tr). True: a shadow ray is occluded. */
bool qwalk_leaf(const struct qwalk_tree *t, struct trace_ctx *tr, struct qwalk *w, uint32_t n,
                uint32_t j0, uint32_t j1);

/* Walk on from the current node. In a queue point's subtree (to_queue false)
 * run until its pending nodes (those above stack depth floor) are done; above
 * the queue points (to_queue true) stop at the first queue point reached. */
enum qwalk_end qwalk_run(const struct qwalk_tree *t, struct trace_ctx *tr, struct qwalk *w,
                         int floor, bool to_queue);

/* Rebuild the walk at queue point q: descend from the root along the path to
 * q, pushing (and popping) what the uncut traversal did there. */
void qwalk_to(const struct qwalk_tree *t, struct trace_ctx *tr, struct qwalk *w, uint32_t q);

/* After a queue point's subtree: on to the next queue point, or the end. */
enum qwalk_end qwalk_leave(const struct qwalk_tree *t, struct trace_ctx *tr, struct qwalk *w);

/* Treelets (treelet.h; of[n]: node n's treelet): walk on inside the current
 * node's treelet, all pending nodes included, and stop without loading it at
 * the first node of another treelet (QWALK_QUEUED, w->ni), at the end, or at
 * a hit that ends the ray. */
enum qwalk_end qwalk_run_treelet(const struct qwalk_tree *t, struct trace_ctx *tr, struct qwalk *w,
                                 const uint32_t *of);

/* After a leaf treelet (its leaf tested): the next pending node, where the
 * ray queues (QWALK_QUEUED, w->ni), or the end. */
enum qwalk_end qwalk_leave_treelet(const struct qwalk_tree *t, struct qwalk *w);

/* The best hit so far as a record carries it (hit_prim): -1 when none. */
static inline int32_t qwalk_best_prim(const struct qwalk *w) {
  return w->best.found ? (int32_t)w->best.p : -1;
}

#endif
