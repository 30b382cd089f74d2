/* The dynamic policy (the paper's section 2): queue points are the nodes
 * whose subtree geometry fits the cache (qpoint.h), cut once across the tree:
 * above them a ray walks freely, below one it walks the subtree whole. Its
 * routes for the queue scheduler (qsched.h), which does the rest: a new ray
 * walks from the root to its first queue point; a ray taken from a queue
 * point walks its subtree, then on to the next queue point (qwalk_leave). */
#include "renderer/policy/policy_impl.h"

#include <stdlib.h>

#include "renderer/policy/policy.h"
#include "renderer/policy/qplan.h"
#include "renderer/policy/qpoint.h"
#include "renderer/policy/qsched.h"
#include "renderer/policy/qwalk.h"
#include "renderer/trace.h"
#include "sim/err.h"

/* The job's shared state: the queue points and the scheduler over them. */
struct dyn {
  struct qpoint_set qs;
  struct qsched *q;
};

static uint32_t dyn_queue(const void *ctx, uint32_t node) {
  const struct dyn *d = ctx;
  const int64_t qi = qpoint_index(&d->qs, node);
  CHECK_GE(qi, 0);
  return (uint32_t)qi;
}

/* The walk that finds the first queue point is not charged to memory: it
 * follows the path from the root to that queue point, which the ray loads when
 * it is dequeued there (qwalk_to), so charging it here would count the path
 * twice. It runs on a native copy of the worker's tracer (its counts are
 * kept), so the worker's port is never changed. (The paper starts a new ray at
 * the queue point holding its origin.) */
static enum qwalk_end dyn_start(const void *ctx, const struct qwalk_tree *t, struct trace_ctx *tr,
                                struct qwalk *w) {
  (void)ctx;
  struct trace_ctx quiet = *tr;
  quiet.mem = mem_port_native();
  const enum qwalk_end e = qwalk_run(t, &quiet, w, 0, true);
  tr->stats = quiet.stats;
  return e;
}

/* The queue point's subtree, then on to the next queue point. */
static enum qwalk_end dyn_run(const void *ctx, const struct qwalk_tree *t, struct trace_ctx *tr,
                              struct qwalk *w) {
  (void)ctx;
  const enum qwalk_end e = qwalk_run(t, tr, w, w->sp, false);
  return e == QWALK_DONE ? qwalk_leave(t, tr, w) : e;
}

static enum qwalk_end dyn_leave(const void *ctx, const struct qwalk_tree *t, struct trace_ctx *tr,
                                struct qwalk *w) {
  (void)ctx;
  return qwalk_leave(t, tr, w);
}

static const struct qsched_route dyn_route = {dyn_queue, dyn_start, dyn_run, dyn_leave};

void policy_dynamic_plan(const struct policy_params *p, uint32_t workers, uint32_t cores,
                         const struct kd_tree *kd, const struct bvh *bvh, uint32_t tri_bytes,
                         struct qpoint_set *qs, struct qpoint_budget *b, uint32_t *block_tris,
                         uint32_t *group) {
  qplan_make(p, workers, cores, kd, bvh, NULL, tri_bytes, qs, b, block_tris, group);
}

static void dyn_create(struct policy_job *job) {
  struct dyn *d = xcalloc(1, sizeof *d);
  /* Queue points for the cache and the machine (policy.h). */
  struct qpoint_budget bud;
  uint32_t block_tris, group;
  qplan_job(job, &d->qs, &bud, &block_tris, &group);
  d->q = qsched_create(job, &d->qs, block_tris, group, &dyn_route, d);
  job->shared = d;
}

static void dyn_destroy(struct policy_job *job) {
  struct dyn *d = job->shared;
  if (!d) return;
  qsched_destroy(d->q);
  qpoint_fini(&d->qs);
  free(d);
}

static bool dyn_step(struct policy_job *job, struct policy_worker *wk) {
  const struct dyn *d = job->shared;
  return qsched_step(d->q, job, wk);
}

static void dyn_finish(struct policy_job *job, struct render_stats *st) {
  const struct dyn *d = job->shared;
  qsched_finish(d->q, st);
}

const struct policy_module policy_dynamic_module = {
    .region_bytes = 0, /* its rays wait in the queues, at queue_base */
    .max_workers = 0,  /* any: a core's workers share its queue point */
    .create = dyn_create,
    .destroy = dyn_destroy,
    .step = dyn_step,
    .scratch_free = qsched_scratch_free,
    .finish = dyn_finish,
};
