/* The treelet policy: the tree cut into treelets (treelet.h) for the budget
 * the dynamic policy gives a queue point's geometry, each treelet a queue of
 * the queue scheduler (qsched.h), which does the rest. A ray is always in one
 * treelet: a new ray queues at the root's, and a ray taken from a treelet's
 * queue walks on inside it from the node it entered by, and queues again at
 * the first node of another treelet it reaches. */
#include "renderer/policy/policy_impl.h"

#include <stdlib.h>

#include "renderer/bvh.h"
#include "renderer/kdtree.h"
#include "renderer/policy/policy.h"
#include "renderer/policy/qplan.h"
#include "renderer/policy/qpoint.h"
#include "renderer/policy/qsched.h"
#include "renderer/policy/qwalk.h"
#include "renderer/policy/treelet.h"
#include "sim/err.h"

/* The job's shared state: qs marks the treelet roots, queue i is the treelet
 * rooted at qs.qnode[i], and of[n] is the queue of node n's treelet. */
struct tl {
  struct qpoint_set qs;
  uint32_t *of;
  struct qsched *q;
};

static uint32_t tl_queue(const void *ctx, uint32_t node) {
  const struct tl *p = ctx;
  return p->of[node];
}

/* At the root, in the root's treelet: it queues there. */
static enum qwalk_end tl_start(const void *ctx, const struct qwalk_tree *t, struct trace_ctx *tr,
                               struct qwalk *w) {
  (void)ctx;
  (void)t;
  (void)tr;
  (void)w;
  return QWALK_QUEUED;
}

static enum qwalk_end tl_run(const void *ctx, const struct qwalk_tree *t, struct trace_ctx *tr,
                             struct qwalk *w) {
  const struct tl *p = ctx;
  return qwalk_run_treelet(t, tr, w, p->of);
}

static enum qwalk_end tl_leave(const void *ctx, const struct qwalk_tree *t, struct trace_ctx *tr,
                               struct qwalk *w) {
  (void)ctx;
  (void)tr;
  return qwalk_leave_treelet(t, w);
}

static const struct qsched_route tl_route = {tl_queue, tl_start, tl_run, tl_leave};

/* The treelets for g_max (the cache left once the tree's share, the queue
 * table and the ray buffer are reserved, over the cores that hold one at
 * once), nodes and triangles counted (treelet.h), and each treelet's root a
 * queue point. Queue i is the treelet of the i-th root in node order, so the
 * drains see an ordinary selection. */
static void tl_select(struct tl *p, const struct kd_tree *kd, const struct bvh *bvh,
                      uint32_t tri_bytes, uint64_t gmax_bytes) {
  struct treelet_set ts;
  if (bvh) {
    qpoint_bvh_tree(&p->qs, bvh);
    treelet_bvh_build(&ts, bvh, p->qs.leaf_count, tri_bytes, gmax_bytes);
  } else {
    treelet_build(&ts, kd, tri_bytes, gmax_bytes);
    p->qs.nodes = kd->nodes;
  }
  const uint32_t n = ts.node_count;
  p->qs.node_count = n;
  p->qs.gmax_bytes = gmax_bytes;
  p->qs.mark = qpoint_mark_new(n);
  p->qs.qnode = xmalloc((uint64_t)ts.count * sizeof *p->qs.qnode + 1);
  uint32_t *qi_of_treelet = xmalloc((uint64_t)ts.count * sizeof *qi_of_treelet + 1);
  for (uint32_t i = 0; i < n; i++) {
    if (ts.of[i] != TREELET_NONE && ts.root[ts.of[i]] == i) {
      qpoint_mark(p->qs.mark, i);
      qi_of_treelet[ts.of[i]] = p->qs.count;
      p->qs.qnode[p->qs.count++] = i;
    }
  }
  CHECK_EQ(p->qs.count, ts.count);
  /* The treelet of every node becomes its queue, in place: a second array
   * of a word a node would be the run's peak on a large tree. */
  for (uint32_t i = 0; i < n; i++)
    if (ts.of[i] != TREELET_NONE) ts.of[i] = qi_of_treelet[ts.of[i]];
  p->of = ts.of;
  ts.of = NULL;
  free(qi_of_treelet);
  treelet_fini(&ts);
}

static void tl_create(struct policy_job *job) {
  struct tl *p = xcalloc(1, sizeof *p);
  /* The dynamic policy's budget; its queue points are not used. */
  struct qpoint_budget bud;
  uint32_t block_tris, group;
  qplan_job(job, &p->qs, &bud, &block_tris, &group);
  qpoint_fini(&p->qs);
  tl_select(p, job->setup.kd, job->setup.bvh, job->setup.layout.tri_bytes, bud.gmax_bytes);
  p->q = qsched_create(job, &p->qs, block_tris, group, &tl_route, p);
  job->shared = p;
}

static void tl_destroy(struct policy_job *job) {
  struct tl *p = job->shared;
  if (!p) return;
  qsched_destroy(p->q);
  qpoint_fini(&p->qs);
  free(p->of);
  free(p);
}

static bool tl_step(struct policy_job *job, struct policy_worker *wk) {
  const struct tl *p = job->shared;
  return qsched_step(p->q, job, wk);
}

static void tl_finish(struct policy_job *job, struct render_stats *st) {
  const struct tl *p = job->shared;
  qsched_finish(p->q, st);
}

const struct policy_module policy_treelet_module = {
    .region_bytes = 0, /* its rays wait in the queues, at queue_base */
    .max_workers = 0,  /* any: a core's workers share its treelet */
    .create = tl_create,
    .destroy = tl_destroy,
    .step = tl_step,
    .scratch_free = qsched_scratch_free,
    .finish = tl_finish,
};
