/* The queue scheduler: what the dynamic policy (policy_dynamic.c) and the
 * treelet policy (policy_treelet.c) share. Rays wait in queues of a queue
 * store (qstore.h), one a queue point; the cores' workers drain them
 * (qdrain.h) a batch of primary rays at a time, phase by phase, shading a ray
 * as soon as it ends and parking when they have nothing to do. Which queue a
 * ray goes to and how its walk goes on from one is the policy's: a table of
 * routes (qsched_route) chosen when the policy creates the scheduler, and
 * called the same way for every ray. Private to renderer/. */
#ifndef RTSIM_RENDERER_POLICY_QSCHED_H
#define RTSIM_RENDERER_POLICY_QSCHED_H

#include <stdbool.h>
#include <stdint.h>

#include "renderer/policy/qwalk.h"

struct policy_job;
struct policy_worker;
struct qpoint_set;
struct render_stats;
struct trace_ctx;

/* How a policy routes rays between its queues. Every function gets the
 * policy's context (qsched_create's ctx) and the walk's tree; the walks go
 * through tr (its accesses and counts) and stop where qwalk.h says. */
struct qsched_route {
  /* The queue of queue point `node` (a walk stopped there: QWALK_QUEUED). */
  uint32_t (*queue)(const void *ctx, uint32_t node);
  /* A new ray's walk from the root to its first queue point, or its end. */
  enum qwalk_end (*start)(const void *ctx, const struct qwalk_tree *t, struct trace_ctx *tr,
                          struct qwalk *w);
  /* A ray taken from an interior queue point (the walk rebuilt at the node
   * where it queued): walk on to the next queue point, or the end. */
  enum qwalk_end (*run)(const void *ctx, const struct qwalk_tree *t, struct trace_ctx *tr,
                        struct qwalk *w);
  /* A ray past the last pass of a leaf queue point (the walk rebuilt at the
   * leaf): on to the next queue point, or the end. */
  enum qwalk_end (*leave)(const void *ctx, const struct qwalk_tree *t, struct trace_ctx *tr,
                          struct qwalk *w);
};

struct qsched;

/* The job's scheduler over the queue points qs marks (borrowed: qs->nodes and
 * qs->mark are the walk's, queue i is at qs->qnode[i]), routed by route with
 * context ctx (both borrowed); block_tris and group as qplan_make gives
 * them. Sets the job's total (its primary rays, the work items) and its
 * progress reporting. The caller destroys it (qsched_destroy). */
struct qsched *qsched_create(struct policy_job *job, const struct qpoint_set *qs,
                             uint32_t block_tris, uint32_t group, const struct qsched_route *route,
                             const void *ctx);
void qsched_destroy(struct qsched *q); /* NULL ok */

/* policy_module.step: take part in a batch of primary rays until it is done,
 * or park (true) until woken; false when no batch is left. */
bool qsched_step(struct qsched *q, struct policy_job *job, struct policy_worker *wk);

/* policy_module.scratch_free for the scheduler's workers. */
void qsched_scratch_free(void *scratch);

/* policy_module.finish: CHECKs every queue empty and every worker done, and
 * adds the queue arena at its largest (the rays in flight) to st. */
void qsched_finish(const struct qsched *q, struct render_stats *st);

#endif
