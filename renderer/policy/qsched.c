/* The queue scheduler (qsched.h), after the paper's section 2: rays wait in
 * queues at queue points and a queue is processed as a whole, so that the
 * geometry below it is loaded once for all its rays. This file holds phases
 * and generations and the rays' lives; the policy says which queue a ray goes
 * to and how its walk goes on (qsched_route: queue points whose subtree fits
 * the cache in policy_dynamic.c, treelets in policy_treelet.c), and the parts
 * it is built from are each their own module:
 * - the plan (qplan.h): the budget the cache gives, the block and group sizes;
 * - the resumable walk (qwalk.h): a traversal cut at queue points;
 * - the queue store (qstore.h): queues in simulated memory, the chunk arena,
 *   the order in which queues are taken (the fullest first);
 * - the multi-core drain (qdrain.h): how the cores' workers share the queues;
 * - the parked workers (qpark.h): who waits for what, who is woken first.
 *
 * Rays are traced in generations (section 2.1.2): the closest hits of a
 * generation, then its shadow rays (traced from the light toward the points),
 * then the next generation's reflection rays, until none are left. Primary
 * rays are admitted all at once, or dyn_batch_rays at a time with each batch
 * traced through all its generations (policy.h); a batch is a work item. A
 * batch goes through phases: its primary rays are admitted (each worker takes
 * the next), then each phase (closest hits, shadow rays) drains its own queue
 * set (the store's active set); a phase ends when no ray of it is queued or
 * being traced, and the worker that finds it over starts the next. With one
 * worker all this is one loop: admit, then drain each phase's queues in turn.
 *
 * A worker with nothing to take parks (mem_park: no events, no issue slots,
 * no stack while parked) and is woken by the worker whose action makes work
 * for it, as many as the new work can feed:
 * - an enqueue that gives the active set a new free queue wakes one idle
 *   worker (to take it), once its table store has published the ray;
 * - a take or a new pass (qdrain STARTED) wakes up to one worker a claim it
 *   offers, besides the starter: first the core's own workers waiting for its
 *   pass, then idle ones (they join);
 * - the end of a pass that another follows wakes the core's workers waiting
 *   for it (one of them starts the next);
 * - a new phase wakes one idle worker a free queue; the end of a batch wakes
 *   every parked worker (they go on to the next batch, or finish).
 * - a ray's store wakes the worker whose claim waits for it: a claim is
 *   traced once all its rays are stored (qstore.h's hazards).
 * A woken worker that finds the work gone (someone running took it) parks
 * again.
 *
 * Same image as the recursive policy, bit for bit: every ray tests the same
 * triangles as under trace.c (qwalk.h says why), the hit rule (trav.h) does
 * not depend on their order, and which worker traces a ray, and when, changes
 * nothing: a ray's record is the host's, written whole when it is queued, and
 * the framebuffer sums contributions in fixed point.
 *
 * A ray that ends is shaded at once (section 2.1.1: "shade the intersection
 * point immediately"), and the rays it spawns are taken down to their first
 * queue point and queued for their phase: each queue point has a queue for
 * this generation's closest-hit rays (store set QS_SET_NOW), one for its
 * shadow rays (QS_SET_SHADOW: drained once all closest-hit rays are done, so
 * they queue up in full before any is traced) and one for the next generation
 * (QS_SET_NEXT). So a ray waits in memory only in a queue, and the picture is
 * still the recursive policy's: shading is linear and the framebuffer sums in
 * fixed point, so order does not matter.
 *
 * Simulated memory besides nodes, leaf lists and triangles (as trace.c) and
 * the queues (qstore.h): primary rays are read from the camera's array
 * (policy_primary). */
#include "renderer/policy/qsched.h"

#include <stdlib.h>

#include "renderer/camera.h"
#include "renderer/framebuffer.h"
#include "renderer/kdtree.h"
#include "renderer/policy/policy.h"
#include "renderer/policy/policy_impl.h"
#include "renderer/policy/qdrain.h"
#include "renderer/policy/qpark.h"
#include "renderer/policy/qpoint.h"
#include "renderer/policy/qstore.h"
#include "renderer/policy/qwalk.h"
#include "renderer/scene.h"
#include "renderer/shade.h"
#include "renderer/trace.h"
#include "sim/err.h"

/* Host-only mark of a ray that ended during a blocked pass (never simulated). */
#define QS_FLAG_DEAD 0x80u

/* The store's queue sets: the phase being drained (the active set), this
 * generation's shadow rays, the next generation. */
enum { QS_SET_NOW = 0, QS_SET_SHADOW = 1, QS_SET_NEXT = 2, QS_SETS = 3 };

/* ---- scheduler state ---------------------------------------------------------- */

struct ray_buf {
  struct ray *r;
  uint64_t n, cap;
};

enum qsched_phase { QS_ADMIT, QS_CLOSEST, QS_SHADOW };

/* The job's shared state: queue points and the policy's routes, the queue
 * store and the drains, the primary rays' order, the batch and its phase. */
struct qsched {
  const struct qpoint_set *qs;
  const struct qsched_route *route;
  const void *ctx;      /* the routes' */
  struct qwalk_tree wt; /* the tree with qs's queue points */
  struct qstore st;
  struct qdrain_set ds;
  uint32_t *order; /* primary rays (work items) in Hilbert order */
  uint64_t batch;  /* primary rays a work item admits */
  /* The batch being traced: primary rays [lo, hi), the next to admit, the
   * admissions under way; its phase; the rays of the phase's queue set that
   * are queued or being traced (a phase ends when none are). */
  bool active;
  uint64_t lo, hi, admit_next, batch_seq;
  uint32_t admitting;
  enum qsched_phase phase;
  uint64_t pending;
  /* Rays spawned and terminated by all workers, for progress. */
  uint64_t spawned, terminated, progress_at;
  struct qpark pk; /* the parked workers */
};

/* A worker's own (its scratch): where its accesses and counts go, the rays
 * its shading spawned, started once the ray that spawned them is done (so
 * each ray's cost is its own), and its claim. */
struct qsched_worker {
  struct qsched *q;
  struct policy_job *job;
  struct policy_worker *wk;
  struct trace_ctx *tr;
  struct render_stats *st;
  struct ray_buf pend;
  struct qdrain_claim cl;
  struct qpark_list *wait; /* where work() found nothing: the list to park in
                              (NULL: it waits for a ray's store) */
  bool holding;            /* cl is claimed and not yet traced */
};

/* ---- parking ------------------------------------------------------------------ */

/* Park x in list l (NULL: x waits for a slot, qpark_wait_slot): its worker
 * function returns now (qsched_step), and runs again when woken. */
static void park(struct qsched_worker *x, struct qpark_list *l) {
  qpark_add(&x->q->pk, l, x->wk->id);
  /* A parked worker holds no host memory it does not need: its spawned rays
   * are all started (a machine of thousands of mostly parked contexts). */
  CHECK_EQ(x->pend.n, 0);
  free(x->pend.r);
  x->pend = (struct ray_buf){0};
  /* One worker always has something to do while its batch goes on. */
  CHECK(mem_park(&x->tr->mem));
  x->wk->parked = true;
}

/* Wake up to n workers of list l at x's time. Returns how many. */
static uint64_t wake(struct qsched_worker *x, struct qpark_list *l, uint64_t n) {
  return qpark_wake(&x->q->pk, l, n, &x->tr->mem);
}

static void buf_push(struct ray_buf *b, const struct ray *r) {
  if (b->n == b->cap) {
    b->cap = b->cap ? 2 * b->cap : 2 * SHADE_MAX_SPAWN; /* a ray's children, mostly */
    b->r = xrealloc(b->r, b->cap * sizeof *b->r);
  }
  b->r[b->n++] = *r;
}

/* Append r to queue qi of store set `set`: the slot is claimed (counts, host
 * copy, heap) before the accesses, as any of them may suspend this worker
 * (qstore.h's hazards); a ray of the phase being drained counts as pending. */
static void enqueue(struct qsched_worker *x, uint32_t qi, const struct ray *r, uint32_t set,
                    uint32_t entry) {
  struct qsched *q = x->q;
  CHECK(!(r->flags & QS_FLAG_DEAD));
  const uint32_t free0 = qstore_free_queues(&q->st);
  const uint64_t slot = qstore_push(&q->st, set, qi, r);
  qstore_set_entry(&q->st, slot, entry);
  const bool fresh = qstore_free_queues(&q->st) > free0; /* a queue to take */
  if (set == QS_SET_NOW) q->pending++;
  qstore_write(&q->st, &x->tr->mem, qi, slot);
  if (q->pk.slot_waits) qpark_wake_slot(&q->pk, slot, &x->tr->mem);
  if (fresh) wake(x, &q->pk.idle, 1);
}

/* ---- ray ends ---------------------------------------------------------------- */

/* Progress: rays terminated of rays spawned so far, by all workers. */
static void progress(struct qsched_worker *x) {
  struct qsched *q = x->q;
  const struct policy_setup *s = &x->job->setup;
  if (s->progress && q->terminated >= q->progress_at && q->terminated < q->spawned) {
    s->progress(s->progress_ctx, q->terminated, q->spawned);
    q->progress_at = q->terminated + (1u << 16);
  }
}

/* A ray ends: a shadow ray adds its light, any other is shaded now (its hit
 * is the walk's best; a miss has t = tmax, as trace_closest gives it) and its
 * children wait in pend until this ray's work is counted. */
static void terminate(struct qsched_worker *x, struct ray *r, const struct qwalk *w,
                      enum qwalk_end e) {
  const struct policy_setup *s = &x->job->setup;
  x->st->rays[r->type]++;
  x->st->terminated++;
  x->q->terminated++;
  if (r->type == RAY_SHADOW) {
    shade_shadow(r, e == QWALK_HIT, s->fb, &x->tr->mem);
  } else {
    struct trace_hit h;
    trav_best_hit(&w->best, &h);
    r->hit_prim = -1;
    struct ray spawn[SHADE_MAX_SPAWN];
    uint32_t n = shade_hit(s->sc, r, &h, s->fb, &x->tr->mem, spawn);
    x->st->spawned += n;
    x->q->spawned += n;
    for (uint32_t k = 0; k < n; k++) buf_push(&x->pend, &spawn[k]);
  }
  progress(x);
}

/* Where a ray goes after a walk: a queue of store set `set`, or its end. */
static void route(struct qsched_worker *x, struct ray *r, const struct qwalk *w, enum qwalk_end e,
                  uint32_t set) {
  if (e == QWALK_QUEUED) {
    const struct qsched *q = x->q;
    const uint32_t qi = q->route->queue(q->ctx, w->ni);
    r->hit_prim = qwalk_best_prim(w);
    enqueue(x, qi, r, set, w->ni);
  } else {
    terminate(x, r, w, e);
  }
}

/* Per-pixel cost: the work this worker's tracer counted for a ray since the
 * marks (its own counters: others' work never lands in them). */
static void cost_add(const struct qsched_worker *x, uint32_t pixel, uint64_t nodes0,
                     uint64_t tris0) {
  struct framebuffer *fb = x->job->setup.fb;
  fb->cost_nodes[pixel] += (uint32_t)(x->tr->stats.node_visits - nodes0);
  fb->cost_tris[pixel] += (uint32_t)(x->tr->stats.tri_tests - tris0);
}

/* A new ray: take it to its first queue point (the route's start) and queue
 * it there, or end it. Primary rays join the queues being filled for
 * generation 0, shadow rays this generation's shadow queues, reflection rays
 * the next generation's. */
static void start(struct qsched_worker *x, struct ray *r) {
  struct qsched *q = x->q;
  struct trace_ctx *tr = x->tr;
  uint64_t n0 = tr->stats.node_visits, t0 = tr->stats.tri_tests;
  struct qwalk w;
  const uint32_t set = r->type == RAY_PRIMARY  ? QS_SET_NOW
                       : r->type == RAY_SHADOW ? QS_SET_SHADOW
                                               : QS_SET_NEXT;
  if (!qwalk_init(&q->wt, &w, r)) terminate(x, r, &w, QWALK_DONE);
  else route(x, r, &w, q->route->start(q->ctx, &q->wt, tr, &w), set);
  cost_add(x, r->pixel, n0, t0);
}

/* Start the rays that this worker's shading spawned, and any that they spawn
 * in turn when they end at once (pend grows meanwhile: n is re-read). */
static void flush(struct qsched_worker *x) {
  for (uint64_t i = 0; i < x->pend.n; i++) {
    struct ray r = x->pend.r[i];
    start(x, &r);
  }
  x->pend.n = 0;
}

/* ---- tracing a claim ------------------------------------------------------------ */

/* A ray queued at node, an interior queue point's: rebuild its walk there and
 * go on as the route says, to its next queue or its end. */
static void process_subtree(struct qsched_worker *x, struct ray *r, uint32_t node) {
  struct qsched *q = x->q;
  struct trace_ctx *tr = x->tr;
  uint64_t n0 = tr->stats.node_visits, t0 = tr->stats.tri_tests;
  struct qwalk w;
  CHECK(qwalk_init(&q->wt, &w, r));
  qwalk_to(&q->wt, tr, &w, node);
  route(x, r, &w, q->route->run(q->ctx, &q->wt, tr, &w), QS_SET_NOW);
  cost_add(x, r->pixel, n0, t0);
  flush(x);
}

/* The claimed ray of an interior queue point: on from the node where it
 * queued (the queue point itself, or for a treelet the node of it the ray
 * entered by). */
static void trace_subtree_claim(struct qsched_worker *x) {
  struct qsched *q = x->q;
  const uint64_t slot = x->cl.slot[0];
  struct ray r = *qstore_ray(&q->st, slot);
  trace_attribute(x->tr, &r.pixel, 1);
  mem_load(&x->tr->mem, qstore_slot_addr(&q->st, slot), sizeof r, TRACE_CLASS_RAY);
  process_subtree(x, &r, qstore_entry(&q->st, slot));
  q->pending--;
  qdrain_slot_done(&q->ds, &x->cl, 0);
}

/* The claimed rays of a leaf queue point against the pass's block of its
 * geometry (the whole leaf unless it exceeds g_max: the paper's "separate
 * scheduling problem"): each is loaded and tested; before the last pass it is
 * stored back with its best hit (or marked ended), after the last it goes on.
 * Every ray still tests all of the leaf's triangles, so its hit is the one a
 * single traversal finds (the hit rule does not depend on their order).
 * NOTE: a pass's writes into a ray's slot after its accesses (its best hit,
 * or its end) land in the ray's own record: its chunk is not freed while the
 * ray is handed out (qstore.h). */
static void trace_leaf_claim(struct qsched_worker *x) {
  struct qsched *q = x->q;
  struct trace_ctx *tr = x->tr;
  const struct mem_port *mem = &tr->mem;
  const struct qdrain_claim *cl = &x->cl;
  for (uint32_t t = 0; t < cl->n; t++) {
    const uint64_t slot = cl->slot[t];
    if (qstore_ray(&q->st, slot)->flags & QS_FLAG_DEAD) {
      qdrain_slot_done(&q->ds, cl, t);
      continue;
    }
    struct ray r = *qstore_ray(&q->st, slot);
    uint64_t n0 = tr->stats.node_visits, t0 = tr->stats.tri_tests;
    trace_attribute(tr, &r.pixel, 1);
    mem_load(mem, qstore_slot_addr(&q->st, slot), sizeof r, TRACE_CLASS_RAY);
    struct qwalk w;
    CHECK(qwalk_init(&q->wt, &w, &r));
    bool over = true;
    if (qwalk_leaf(&q->wt, tr, &w, cl->node, cl->j0, cl->j1)) {
      terminate(x, &r, &w, QWALK_HIT);
      if (!cl->last) qstore_ray(&q->st, slot)->flags |= QS_FLAG_DEAD; /* later passes skip it */
    } else if (!cl->last) {
      qstore_ray(&q->st, slot)->hit_prim = qwalk_best_prim(&w);
      over = false;
    } else {
      qwalk_to(&q->wt, tr, &w, cl->node);
      route(x, &r, &w, q->route->leave(q->ctx, &q->wt, tr, &w), QS_SET_NOW);
    }
    cost_add(x, r.pixel, n0, t0);
    flush(x);
    if (over) q->pending--;
    qdrain_slot_done(&q->ds, cl, t);
  }
  /* Store the group back with its best hits (the last pass moved them on). */
  for (uint32_t t = 0; !cl->last && t < cl->n; t++)
    if (!(qstore_ray(&q->st, cl->slot[t])->flags & QS_FLAG_DEAD)) {
      trace_attribute(tr, &qstore_ray(&q->st, cl->slot[t])->pixel, 1);
      mem_store(mem, qstore_slot_addr(&q->st, cl->slot[t]), sizeof(struct ray), TRACE_CLASS_RAY);
    }
}

/* Admit the batch's next primary ray: read it, take it to its first queue. */
static bool admit(struct qsched_worker *x) {
  struct qsched *q = x->q;
  if (q->admit_next == q->hi) return false;
  const uint64_t k = q->admit_next++;
  q->admitting++;
  const uint32_t w = x->job->setup.fb->width;
  struct ray r;
  trace_attribute(x->tr, &q->order[k], 1);
  policy_primary(x->job, x->wk, q->order[k] % w, q->order[k] / w, &r);
  x->st->spawned++;
  q->spawned++;
  start(x, &r);
  flush(x);
  q->admitting--;
  return true;
}

/* Trace x's claim once all its rays are stored (a ray that ended in an
 * earlier pass is never read again); until then x waits (qpark_wait_slot)
 * for the first that is not (qstore.h's hazards: its enqueuer wakes x). One
 * worker never waits: its enqueues are over before it drains. False when x
 * must wait. */
static bool trace_claim(struct qsched_worker *x) {
  struct qsched *q = x->q;
  for (uint32_t t = 0; t < x->cl.n; t++) {
    const uint64_t slot = x->cl.slot[t];
    if ((qstore_ray(&q->st, slot)->flags & QS_FLAG_DEAD) || qstore_stored(&q->st, slot)) continue;
    qpark_wait_slot(&q->pk, slot, x->wk->id);
    x->wait = NULL;
    return false;
  }
  x->holding = false;
  if (x->cl.leaf) trace_leaf_claim(x);
  else trace_subtree_claim(x);
  if (qdrain_claim_done(&q->ds, &x->cl)) wake(x, &q->pk.pass[x->cl.drain], UINT64_MAX);
  return true;
}

/* Do one thing for the batch: admit a primary ray, or what the drain gives
 * x's core to do (take a queue point, start a pass, trace claimed rays), and
 * wake the parked workers the work it made can feed. False when there is
 * nothing to do now (x->wait: where to park). */
static bool work(struct qsched_worker *x) {
  struct qsched *q = x->q;
  const uint32_t core = x->wk->core;
  x->wait = &q->pk.idle;
  if (x->holding) return trace_claim(x); /* woken by the store it waited for */
  if (q->phase == QS_ADMIT) return admit(x);
  switch (qdrain_work(&q->ds, core, x->tr, &x->cl)) {
  case QDRAIN_NOTHING: return false;
  case QDRAIN_PASS_WAIT: x->wait = &q->pk.pass[core]; return false;
  case QDRAIN_STARTED: {
    /* x takes one of the new pass's claims itself. */
    uint64_t n = qdrain_claims_left(&q->ds, core);
    n = n > 0 ? n - 1 : 0;
    n -= wake(x, &q->pk.pass[core], n);
    wake(x, &q->pk.idle, n);
    return true;
  }
  case QDRAIN_CLAIMED: break;
  }
  x->holding = true;
  return trace_claim(x);
}

/* ---- phases and generations ------------------------------------------------- */

/* The phase is over: its primary rays are all admitted, or no ray of its queue
 * set is queued or being traced and no core has a pass left over its queue
 * point (a pass goes on over its rays even when they have all ended). */
static bool phase_over(const struct qsched *q) {
  if (q->phase == QS_ADMIT) return q->admit_next == q->hi && q->admitting == 0;
  if (q->pending > 0 || qstore_any_free(&q->st)) return false;
  return qdrain_idle(&q->ds);
}

/* Make store set `set` the one being drained (the drained set, empty now,
 * takes its place): the cores let their queue points go, and the set's
 * non-empty queues are ordered in the store's heap. */
static void activate(struct qsched *q, uint32_t set) {
  CHECK(!qstore_any_free(&q->st));
  CHECK_EQ(q->pending, 0);
  qdrain_release_all(&q->ds);
  q->pending += qstore_activate(&q->st, set);
}

/* Start the phase after the one that is over: closest hits, their shadow rays,
 * the next generation's closest hits; skip those without rays. True when
 * there is none: the batch is done. */
static bool advance(struct qsched *q) {
  for (;;) {
    switch (q->phase) {
    case QS_ADMIT: q->phase = QS_CLOSEST; break;
    case QS_CLOSEST:
      activate(q, QS_SET_SHADOW);
      q->phase = QS_SHADOW;
      break;
    case QS_SHADOW:
      activate(q, QS_SET_NEXT);
      q->phase = QS_CLOSEST;
      if (!qstore_any_free(&q->st)) return true; /* no next generation */
      break;
    }
    if (!phase_over(q)) return false;
  }
}

/* ---- the scheduler --------------------------------------------------------------- */

struct qsched *qsched_create(struct policy_job *job, const struct qpoint_set *qs,
                             uint32_t block_tris, uint32_t group, const struct qsched_route *route,
                             const void *ctx) {
  const struct policy_params *p = &job->params;
  const struct trace_layout *l = &job->setup.layout;
  struct qsched *q = xcalloc(1, sizeof *q);
  q->qs = qs;
  q->route = route;
  q->ctx = ctx;
  q->wt = (struct qwalk_tree){job->setup.kd, job->setup.scene, qs->nodes,     qs->mark,
                              qs->bvh,       qs->parent,       qs->leaf_count};
  CHECK(qs->bvh == job->setup.bvh);
  qpark_init(&q->pk, job->cores, job->workers);
  qstore_init(&q->st, qs->count, QS_SETS, l->qtable_base, l->queue_base);
  qdrain_init(&q->ds, &q->st, qs, job->cores, block_tris, group);
  if (p->dyn_sharing == POLICY_DYN_CHIP) qdrain_share_chip(&q->ds, (uint64_t)job->workers * group);

  /* The work items: primary rays in Hilbert order, admitted a batch at a time. */
  const uint32_t w = job->setup.fb->width, h = job->setup.fb->height;
  job->total = (uint64_t)w * h;
  job->progress_every = 0; /* progress counts rays (progress()) */
  q->order = xmalloc(job->total * sizeof *q->order + 1);
  camera_hilbert_order(w, h, q->order);
  q->batch = p->dyn_batch_rays ? p->dyn_batch_rays : job->total;
  q->phase = QS_CLOSEST;
  return q;
}

void qsched_destroy(struct qsched *q) {
  if (!q) return;
  free(q->order);
  qpark_fini(&q->pk);
  qdrain_fini(&q->ds);
  qstore_fini(&q->st);
  free(q);
}

void qsched_scratch_free(void *scratch) {
  struct qsched_worker *x = scratch;
  if (!x) return;
  free(x->pend.r);
  qdrain_claim_fini(&x->cl);
  free(x);
}

/* The batch is done: count its primary rays as work items done. */
static void batch_end(struct policy_job *job, struct qsched *q) {
  q->active = false;
  q->batch_seq++;
  policy_job_done(job, q->hi - q->lo);
  const struct policy_setup *s = &job->setup;
  if (job->done == job->total && s->progress)
    s->progress(s->progress_ctx, q->terminated, q->terminated);
}

/* Take part in a batch of primary rays until it is done: the first worker to
 * find none under way claims the next (before any access), every worker then
 * does what work() finds, starts the next phase when it finds the phase over,
 * and otherwise parks (and comes back here when woken). One worker does the
 * whole batch in one loop: each primary ray to its first queue, then every
 * generation: closest-hit rays, their shadow rays, the next generation. */
bool qsched_step(struct qsched *q, struct policy_job *job, struct policy_worker *wk) {
  if (!q->active) {
    uint64_t k0, n = policy_job_claim(job, q->batch, &k0);
    if (n == 0) return false;
    CHECK_EQ(q->pending, 0);
    CHECK(!qstore_any_free(&q->st));
    q->active = true;
    q->lo = q->admit_next = k0;
    q->hi = k0 + n;
    q->admitting = 0;
    q->phase = QS_ADMIT;
  }
  if (!wk->scratch) {
    struct qsched_worker *nx = xcalloc(1, sizeof *nx);
    qdrain_claim_init(&q->ds, &nx->cl);
    wk->scratch = nx;
  }
  struct qsched_worker *x = wk->scratch;
  x->q = q;
  x->job = job;
  x->wk = wk;
  x->tr = &wk->tr;
  x->st = &wk->st;
  const uint64_t seq = q->batch_seq;
  while (q->batch_seq == seq) {
    if (work(x)) continue;
    if (!x->holding && phase_over(q)) {
      /* No worker waits for a pass between phases (a pass left is no phase
       * over): the idle ones get a free queue each, or all go on at the end. */
      CHECK_EQ(q->pk.busy, 0);
      if (advance(q)) {
        batch_end(job, q);
        wake(x, &q->pk.idle, UINT64_MAX);
      } else {
        wake(x, &q->pk.idle, qstore_free_queues(&q->st));
      }
      continue;
    }
    /* Others are still tracing rays of this phase (or testing the last rays
     * of this core's pass): their rays may make work for this one. */
    park(x, x->wait);
    return true;
  }
  return true;
}

/* Every queue empty, every chunk free; the queue arena at its largest: the
 * rays in flight. */
void qsched_finish(const struct qsched *q, struct render_stats *st) {
  CHECK(!q->active);
  CHECK_EQ(q->pending, 0);
  CHECK_EQ(q->pk.parked, 0);
  qstore_check_empty(&q->st);
  qdrain_check_done(&q->ds);
  st->ray_slots_max += (uint64_t)qstore_chunks(&q->st) * QSTORE_CHUNK_RAYS;
}
