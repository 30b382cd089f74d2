/* The dynamic policy (the paper's section 2): rays wait in queues at queue
 * points, nodes whose subtree geometry fits the cache (qpoint.h), and a queue
 * is processed as a whole so that its subtree's geometry is loaded once for
 * all its rays. This file holds phases and generations and the rays' lives;
 * the parts it is built from are each their own module:
 * - the resumable walk (qwalk.h): a traversal cut at queue points;
 * - the queue store (qstore.h): queues in simulated memory, the chunk arena,
 *   the order in which queues are taken (the fullest first);
 * - the multi-core drain (qdrain.h): how the cores' workers share the queues.
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
 * worker all this is the single loop it always was: the same accesses in the
 * same order.
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
 * this generation's closest-hit rays (store set DYN_SET_NOW), one for its
 * shadow rays (DYN_SET_SHADOW: drained once all closest-hit rays are done, so
 * they queue up in full before any is traced) and one for the next generation
 * (DYN_SET_NEXT). So a ray waits in memory only in a queue, and the picture is
 * still the recursive policy's: shading is linear and the framebuffer sums in
 * fixed point, so order does not matter.
 *
 * Simulated memory besides nodes, leaf lists and triangles (as trace.c) and
 * the queues (qstore.h): primary rays are read from the camera's array
 * (policy_primary). */
#include "renderer/policy/policy_impl.h"

#include <stdlib.h>
#include <string.h>

#include "renderer/camera.h"
#include "renderer/framebuffer.h"
#include "renderer/kdtree.h"
#include "renderer/policy/policy.h"
#include "renderer/policy/qdrain.h"
#include "renderer/policy/qpoint.h"
#include "renderer/policy/qstore.h"
#include "renderer/policy/qwalk.h"
#include "renderer/policy/treelet.h"
#include "renderer/scene.h"
#include "renderer/shade.h"
#include "renderer/trace.h"
#include "sim/err.h"

#define DYN_NONE UINT32_MAX
/* Host-only mark of a ray that ended during a blocked pass (never simulated). */
#define DYN_FLAG_DEAD 0x80u

/* The store's queue sets: the phase being drained (the active set), this
 * generation's shadow rays, the next generation. */
enum { DYN_SET_NOW = 0, DYN_SET_SHADOW = 1, DYN_SET_NEXT = 2, DYN_SETS = 3 };

/* ---- policy state ---------------------------------------------------------- */

struct ray_buf {
  struct ray *r;
  uint64_t n, cap;
};

enum dyn_phase { DYN_ADMIT, DYN_CLOSEST, DYN_SHADOW };

/* A list of parked workers (by worker id), first parked first woken. */
struct dyn_parked {
  uint32_t head, tail;
};

/* Worker id waits for the ray in slot to be stored. */
struct dyn_slot_wait {
  uint64_t slot;
  uint32_t id;
};

/* The job's shared state: queue points, the queue store and the drains, the
 * primary rays' order, the batch and its phase. */
struct dyn {
  struct qpoint_set qs;
  /* The treelet policy (policy_treelet_module): qs marks the treelet roots,
   * queue i is the treelet rooted at qs.qnode[i], and tl_of[n] is the queue
   * of node n's treelet; NULL for the dynamic policy. */
  uint32_t *tl_of;
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
  enum dyn_phase phase;
  uint64_t pending;
  /* Rays spawned and terminated by all workers, for progress. */
  uint64_t spawned, terminated, progress_at;
  /* Parked workers: those with nothing to do (idle), per core those waiting
   * for the end of its pass (pass[core]), linked by park_next; and those
   * whose claim waits for a ray's store (slot_wait, slot_waits of them). */
  struct dyn_parked idle, *pass;
  uint32_t *park_next;
  struct dyn_slot_wait *slot_wait;
  uint32_t slot_waits, slot_wait_cap;
  uint32_t parked, parked_busy; /* all, and those that are not idle */
};

/* A worker's own (its scratch): where its accesses and counts go, the rays
 * its shading spawned, started once the ray that spawned them is done (so
 * each ray's cost is its own), and its claim. */
struct dyn_worker {
  struct dyn *d;
  struct policy_job *job;
  struct policy_worker *wk;
  struct trace_ctx *tr;
  struct render_stats *st;
  struct ray_buf pend;
  struct qdrain_claim cl;
  struct dyn_parked *wait; /* where work() found nothing: the list to park in
                              (NULL: it waits for a ray's store) */
  bool holding;            /* cl is claimed and not yet traced */
};

/* ---- parking ------------------------------------------------------------------ */

/* Park x in list l (NULL: x is in slot_wait): its worker function returns now
 * (dyn_step), and runs again when woken. */
static void park(struct dyn_worker *x, struct dyn_parked *l) {
  struct dyn *d = x->d;
  const uint32_t id = x->wk->id;
  if (l) {
    d->park_next[id] = DYN_NONE;
    if (l->tail == DYN_NONE) l->head = id;
    else d->park_next[l->tail] = id;
    l->tail = id;
  }
  d->parked++;
  d->parked_busy += l != &d->idle;
  /* A parked worker holds no host memory it does not need: its spawned rays
   * are all started (a machine of thousands of mostly parked contexts). */
  CHECK_EQ(x->pend.n, 0);
  free(x->pend.r);
  x->pend = (struct ray_buf){0};
  /* One worker always has something to do while its batch goes on. */
  CHECK(mem_park(&x->tr->mem));
  x->wk->parked = true;
}

/* Wake up to n workers of list l, first parked first, at x's time. Returns
 * how many. */
static uint64_t wake(struct dyn_worker *x, struct dyn_parked *l, uint64_t n) {
  struct dyn *d = x->d;
  uint64_t k = 0;
  for (; k < n && l->head != DYN_NONE; k++) {
    const uint32_t id = l->head;
    l->head = d->park_next[id];
    if (l->head == DYN_NONE) l->tail = DYN_NONE;
    d->parked--;
    d->parked_busy -= l != &d->idle;
    mem_wake(&x->tr->mem, id);
  }
  return k;
}

/* The ray in slot is stored: wake the worker whose claim waits for it. */
static void wake_slot(struct dyn_worker *x, uint64_t slot) {
  struct dyn *d = x->d;
  for (uint32_t i = 0; i < d->slot_waits; i++) {
    if (d->slot_wait[i].slot != slot) continue;
    const uint32_t id = d->slot_wait[i].id;
    d->slot_wait[i] = d->slot_wait[--d->slot_waits];
    d->parked--;
    d->parked_busy--;
    mem_wake(&x->tr->mem, id);
    return;
  }
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
static void enqueue(struct dyn_worker *x, uint32_t qi, const struct ray *r, uint32_t set,
                    uint32_t entry) {
  struct dyn *d = x->d;
  CHECK(!(r->flags & DYN_FLAG_DEAD));
  const uint32_t free0 = qstore_free_queues(&d->st);
  const uint64_t slot = qstore_push(&d->st, set, qi, r);
  qstore_set_entry(&d->st, slot, entry);
  const bool fresh = qstore_free_queues(&d->st) > free0; /* a queue to take */
  if (set == DYN_SET_NOW) d->pending++;
  qstore_write(&d->st, &x->tr->mem, qi, slot);
  if (d->slot_waits) wake_slot(x, slot);
  if (fresh) wake(x, &d->idle, 1);
}

/* ---- ray ends ---------------------------------------------------------------- */

/* Progress: rays terminated of rays spawned so far, by all workers. */
static void progress(struct dyn_worker *x) {
  struct dyn *d = x->d;
  const struct policy_setup *s = &x->job->setup;
  if (s->progress && d->terminated >= d->progress_at && d->terminated < d->spawned) {
    s->progress(s->progress_ctx, d->terminated, d->spawned);
    d->progress_at = d->terminated + (1u << 16);
  }
}

/* A ray ends: a shadow ray adds its light, any other is shaded now (its hit
 * is the walk's best; a miss has t = tmax, as trace_closest gives it) and its
 * children wait in pend until this ray's work is counted. */
static void terminate(struct dyn_worker *x, struct ray *r, const struct qwalk *w,
                      enum qwalk_end e) {
  const struct policy_setup *s = &x->job->setup;
  x->st->rays[r->type]++;
  x->st->terminated++;
  x->d->terminated++;
  if (r->type == RAY_SHADOW) {
    shade_shadow(r, e == QWALK_HIT, s->fb, &x->tr->mem);
  } else {
    struct trace_hit h;
    trav_best_hit(&w->best, &h);
    r->hit_prim = -1;
    struct ray spawn[SHADE_MAX_SPAWN];
    uint32_t n = shade_hit(s->sc, r, &h, s->fb, &x->tr->mem, spawn);
    x->st->spawned += n;
    x->d->spawned += n;
    for (uint32_t k = 0; k < n; k++) buf_push(&x->pend, &spawn[k]);
  }
  progress(x);
}

/* Where a ray goes after a walk: a queue of store set `set`, or its end. */
static void route(struct dyn_worker *x, struct ray *r, const struct qwalk *w, enum qwalk_end e,
                  uint32_t set) {
  if (e == QWALK_QUEUED) {
    const struct dyn *d = x->d;
    int64_t qi = d->tl_of ? (int64_t)d->tl_of[w->ni] : qpoint_index(&d->qs, w->ni);
    CHECK_GE(qi, 0);
    r->hit_prim = qwalk_best_prim(w);
    enqueue(x, (uint32_t)qi, r, set, w->ni);
  } else {
    terminate(x, r, w, e);
  }
}

/* Per-pixel cost: the work this worker's tracer counted for a ray since the
 * marks (its own counters: others' work never lands in them). */
static void cost_add(const struct dyn_worker *x, uint32_t pixel, uint64_t nodes0, uint64_t tris0) {
  struct framebuffer *fb = x->job->setup.fb;
  fb->cost_nodes[pixel] += (uint32_t)(x->tr->stats.node_visits - nodes0);
  fb->cost_tris[pixel] += (uint32_t)(x->tr->stats.tri_tests - tris0);
}

/* A new ray: found its first queue point (the one holding its origin, for a
 * ray that starts inside the scene) and queue it there, or end it. Primary
 * rays join the queues being filled for generation 0, shadow rays this
 * generation's shadow queues, reflection rays the next generation's.
 * The walk that finds the queue point is not charged to memory: it follows
 * the path from the root to that queue point, which the ray loads when it is
 * dequeued there (qwalk_to), so charging it here would count the path twice.
 * It runs on a native copy of the worker's tracer (its counts are kept), so
 * the worker's port is never changed. (The paper starts a new ray at the
 * queue point holding its origin.) */
static void start(struct dyn_worker *x, struct ray *r) {
  struct dyn *d = x->d;
  struct trace_ctx *tr = x->tr;
  uint64_t n0 = tr->stats.node_visits, t0 = tr->stats.tri_tests;
  struct qwalk w;
  const uint32_t set = r->type == RAY_PRIMARY  ? DYN_SET_NOW
                       : r->type == RAY_SHADOW ? DYN_SET_SHADOW
                                               : DYN_SET_NEXT;
  if (!qwalk_init(&d->wt, &w, r)) {
    terminate(x, r, &w, QWALK_DONE);
  } else if (d->tl_of) {
    route(x, r, &w, QWALK_QUEUED, set); /* at the root, in the root's treelet */
  } else {
    struct trace_ctx quiet = *tr;
    quiet.mem = mem_port_native();
    enum qwalk_end e = qwalk_run(&d->wt, &quiet, &w, 0, true);
    tr->stats = quiet.stats;
    route(x, r, &w, e, set);
  }
  cost_add(x, r->pixel, n0, t0);
}

/* Start the rays that this worker's shading spawned, and any that they spawn
 * in turn when they end at once (pend grows meanwhile: n is re-read). */
static void flush(struct dyn_worker *x) {
  for (uint64_t i = 0; i < x->pend.n; i++) {
    struct ray r = x->pend.r[i];
    start(x, &r);
  }
  x->pend.n = 0;
}

/* ---- tracing a claim ------------------------------------------------------------ */

/* A ray of interior queue point node: its subtree, then onward. A treelet's
 * ray resumes at its entry node and walks on until it leaves the treelet. */
static void process_subtree(struct dyn_worker *x, struct ray *r, uint32_t node) {
  struct dyn *d = x->d;
  struct trace_ctx *tr = x->tr;
  uint64_t n0 = tr->stats.node_visits, t0 = tr->stats.tri_tests;
  struct qwalk w;
  CHECK(qwalk_init(&d->wt, &w, r));
  qwalk_to(&d->wt, tr, &w, node);
  enum qwalk_end e;
  if (d->tl_of) {
    e = qwalk_run_treelet(&d->wt, tr, &w, d->tl_of);
  } else {
    e = qwalk_run(&d->wt, tr, &w, w.sp, false);
    if (e == QWALK_DONE) e = qwalk_leave(&d->wt, tr, &w);
  }
  route(x, r, &w, e, DYN_SET_NOW);
  cost_add(x, r->pixel, n0, t0);
  flush(x);
}

/* The claimed ray of an interior queue point: its subtree, then onward. */
static void trace_subtree_claim(struct dyn_worker *x) {
  struct dyn *d = x->d;
  const uint64_t slot = x->cl.slot[0];
  struct ray r = *qstore_ray(&d->st, slot);
  trace_attribute(x->tr, &r.pixel, 1);
  mem_load(&x->tr->mem, qstore_slot_addr(&d->st, slot), sizeof r, TRACE_CLASS_RAY);
  process_subtree(x, &r, d->tl_of ? qstore_entry(&d->st, slot) : x->cl.node);
  d->pending--;
  qdrain_slot_done(&d->ds, &x->cl, 0);
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
static void trace_leaf_claim(struct dyn_worker *x) {
  struct dyn *d = x->d;
  struct trace_ctx *tr = x->tr;
  const struct mem_port *mem = &tr->mem;
  const struct qdrain_claim *cl = &x->cl;
  const struct kd_node nd = d->qs.nodes[cl->node];
  for (uint32_t t = 0; t < cl->n; t++) {
    const uint64_t slot = cl->slot[t];
    if (qstore_ray(&d->st, slot)->flags & DYN_FLAG_DEAD) {
      qdrain_slot_done(&d->ds, cl, t);
      continue;
    }
    struct ray r = *qstore_ray(&d->st, slot);
    uint64_t n0 = tr->stats.node_visits, t0 = tr->stats.tri_tests;
    trace_attribute(tr, &r.pixel, 1);
    mem_load(mem, qstore_slot_addr(&d->st, slot), sizeof r, TRACE_CLASS_RAY);
    struct qwalk w;
    CHECK(qwalk_init(&d->wt, &w, &r));
    bool over = true;
    if (qwalk_leaf(tr, &w, nd, cl->j0, cl->j1)) {
      terminate(x, &r, &w, QWALK_HIT);
      if (!cl->last) qstore_ray(&d->st, slot)->flags |= DYN_FLAG_DEAD; /* later passes skip it */
    } else if (!cl->last) {
      qstore_ray(&d->st, slot)->hit_prim = qwalk_best_prim(&w);
      over = false;
    } else {
      qwalk_to(&d->wt, tr, &w, cl->node);
      route(x, &r, &w, d->tl_of ? qwalk_leave_treelet(&w) : qwalk_leave(&d->wt, tr, &w),
            DYN_SET_NOW);
    }
    cost_add(x, r.pixel, n0, t0);
    flush(x);
    if (over) d->pending--;
    qdrain_slot_done(&d->ds, cl, t);
  }
  /* Store the group back with its best hits (the last pass moved them on). */
  for (uint32_t t = 0; !cl->last && t < cl->n; t++)
    if (!(qstore_ray(&d->st, cl->slot[t])->flags & DYN_FLAG_DEAD)) {
      trace_attribute(tr, &qstore_ray(&d->st, cl->slot[t])->pixel, 1);
      mem_store(mem, qstore_slot_addr(&d->st, cl->slot[t]), sizeof(struct ray), TRACE_CLASS_RAY);
    }
}

/* Admit the batch's next primary ray: read it, take it to its first queue. */
static bool admit(struct dyn_worker *x) {
  struct dyn *d = x->d;
  if (d->admit_next == d->hi) return false;
  const uint64_t k = d->admit_next++;
  d->admitting++;
  const uint32_t w = x->job->setup.fb->width;
  struct ray r;
  trace_attribute(x->tr, &d->order[k], 1);
  policy_primary(x->job, x->wk, d->order[k] % w, d->order[k] / w, &r);
  x->st->spawned++;
  d->spawned++;
  start(x, &r);
  flush(x);
  d->admitting--;
  return true;
}

/* Trace x's claim once all its rays are stored (a ray that ended in an
 * earlier pass is never read again); until then x waits in slot_wait for the
 * first that is not (qstore.h's hazards: its enqueuer wakes x). One worker
 * never waits: its enqueues are over before it drains. False when x must
 * wait. */
static bool trace_claim(struct dyn_worker *x) {
  struct dyn *d = x->d;
  for (uint32_t t = 0; t < x->cl.n; t++) {
    const uint64_t slot = x->cl.slot[t];
    if ((qstore_ray(&d->st, slot)->flags & DYN_FLAG_DEAD) || qstore_stored(&d->st, slot)) continue;
    if (d->slot_waits == d->slot_wait_cap) {
      d->slot_wait_cap = d->slot_wait_cap ? 2 * d->slot_wait_cap : 16;
      d->slot_wait = xrealloc(d->slot_wait, (uint64_t)d->slot_wait_cap * sizeof *d->slot_wait);
    }
    d->slot_wait[d->slot_waits++] = (struct dyn_slot_wait){slot, x->wk->id};
    x->wait = NULL;
    return false;
  }
  x->holding = false;
  if (x->cl.leaf) trace_leaf_claim(x);
  else trace_subtree_claim(x);
  if (qdrain_claim_done(&d->ds, &x->cl)) wake(x, &d->pass[x->cl.drain], UINT64_MAX);
  return true;
}

/* Do one thing for the batch: admit a primary ray, or what the drain gives
 * x's core to do (take a queue point, start a pass, trace claimed rays), and
 * wake the parked workers the work it made can feed. False when there is
 * nothing to do now (x->wait: where to park). */
static bool work(struct dyn_worker *x) {
  struct dyn *d = x->d;
  const uint32_t core = x->wk->core;
  x->wait = &d->idle;
  if (x->holding) return trace_claim(x); /* woken by the store it waited for */
  if (d->phase == DYN_ADMIT) return admit(x);
  switch (qdrain_work(&d->ds, core, x->tr, &x->cl)) {
  case QDRAIN_NOTHING: return false;
  case QDRAIN_PASS_WAIT: x->wait = &d->pass[core]; return false;
  case QDRAIN_STARTED: {
    /* x takes one of the new pass's claims itself. */
    uint64_t n = qdrain_claims_left(&d->ds, core);
    n = n > 0 ? n - 1 : 0;
    n -= wake(x, &d->pass[core], n);
    wake(x, &d->idle, n);
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
 * point (passes go on over rays that all ended, as one worker's loop did). */
static bool phase_over(const struct dyn *d) {
  if (d->phase == DYN_ADMIT) return d->admit_next == d->hi && d->admitting == 0;
  if (d->pending > 0 || qstore_any_free(&d->st)) return false;
  return qdrain_idle(&d->ds);
}

/* Make store set `set` the one being drained (the drained set, empty now,
 * takes its place): the cores let their queue points go, and the set's
 * non-empty queues are ordered in the store's heap. */
static void activate(struct dyn *d, uint32_t set) {
  CHECK(!qstore_any_free(&d->st));
  CHECK_EQ(d->pending, 0);
  qdrain_release_all(&d->ds);
  d->pending += qstore_activate(&d->st, set);
}

/* Start the phase after the one that is over: closest hits, their shadow rays,
 * the next generation's closest hits; skip those without rays. True when
 * there is none: the batch is done. */
static bool advance(struct dyn *d) {
  for (;;) {
    switch (d->phase) {
    case DYN_ADMIT: d->phase = DYN_CLOSEST; break;
    case DYN_CLOSEST:
      activate(d, DYN_SET_SHADOW);
      d->phase = DYN_SHADOW;
      break;
    case DYN_SHADOW:
      activate(d, DYN_SET_NEXT);
      d->phase = DYN_CLOSEST;
      if (!qstore_any_free(&d->st)) return true; /* no next generation */
      break;
    }
    if (!phase_over(d)) return false;
  }
}

/* ---- the module --------------------------------------------------------------- */

static uint32_t clamp_u32(uint64_t v) {
  return v == 0 ? 1 : (v > UINT32_MAX ? UINT32_MAX : (uint32_t)v);
}

/* policy_dynamic_plan with the subtree triangle counts given (tris,
 * qpoint_subtree_tris of kd). */
static void plan_counted(const struct policy_params *p, uint32_t workers, uint32_t cores,
                         const struct kd_tree *kd, const uint32_t *tris, uint32_t tri_bytes,
                         struct qpoint_set *qs, struct qpoint_budget *b, uint32_t *block_tris,
                         uint32_t *group) {
  CHECK_GE(workers, 1);
  CHECK_GE(cores, 1);
  CHECK_LE(cores, workers);
  CHECK_GT(tri_bytes, 0);
  const uint64_t rays =
      p->dyn_ray_buffer_bytes ? p->dyn_ray_buffer_bytes : (uint64_t)workers * sizeof(struct ray);
  /* Geometry resident at once: one queue point a core, or one for the chip. */
  const uint32_t holders = p->dyn_sharing == POLICY_DYN_CHIP ? 1 : cores;
  struct qpoint_reserve res = {
      p->cache_bytes, p->dyn_node_share, p->dyn_table_share, p->dyn_ray_share, rays, holders};
  qpoint_plan(qs, b, kd, tris, tri_bytes, &res);
  *block_tris = clamp_u32(b->gmax_bytes / tri_bytes);
  *group = clamp_u32(b->ray_bytes / sizeof(struct ray) / workers);
}

void policy_dynamic_plan(const struct policy_params *p, uint32_t workers, uint32_t cores,
                         const struct kd_tree *kd, uint32_t tri_bytes, struct qpoint_set *qs,
                         struct qpoint_budget *b, uint32_t *block_tris, uint32_t *group) {
  uint32_t *tris = xmalloc((uint64_t)kd->node_count * sizeof *tris + 1);
  qpoint_subtree_tris(kd, tris);
  plan_counted(p, workers, cores, kd, tris, tri_bytes, qs, b, block_tris, group);
  free(tris);
}

/* policy_dynamic_plan for a job: with the setup's subtree counts if it has them. */
static void job_plan(const struct policy_job *job, struct qpoint_set *qs, struct qpoint_budget *b,
                     uint32_t *block_tris, uint32_t *group) {
  const struct policy_setup *s = &job->setup;
  if (s->subtree_tris)
    plan_counted(&job->params, job->workers, job->cores, s->kd, s->subtree_tris,
                 s->layout.tri_bytes, qs, b, block_tris, group);
  else
    policy_dynamic_plan(&job->params, job->workers, job->cores, s->kd, s->layout.tri_bytes, qs, b,
                        block_tris, group);
}

/* The job's shared state around a selection of queue points (d->qs, whose
 * node array marks them): the walk, the store, the drains, the parking lists
 * and the work items. Everything after the selection is the same for any set
 * of subtree roots that holds every leaf with geometry (a treelet policy's
 * selection would come in here with its own block_tris and group). */
static void dyn_setup(struct policy_job *job, struct dyn *d, uint32_t block_tris, uint32_t group) {
  const struct policy_params *p = &job->params;
  const struct trace_layout *l = &job->setup.layout;
  d->wt = (struct qwalk_tree){job->setup.kd, job->setup.scene, d->qs.nodes, d->qs.mark};
  d->idle.head = d->idle.tail = DYN_NONE;
  d->pass = xmalloc((uint64_t)job->cores * sizeof *d->pass);
  for (uint32_t c = 0; c < job->cores; c++) d->pass[c] = d->idle;
  d->park_next = xmalloc((uint64_t)job->workers * sizeof *d->park_next);
  qstore_init(&d->st, d->qs.count, DYN_SETS, l->qtable_base, l->queue_base);
  qdrain_init(&d->ds, &d->st, &d->qs, job->cores, block_tris, group);
  if (p->dyn_sharing == POLICY_DYN_CHIP) qdrain_share_chip(&d->ds, (uint64_t)job->workers * group);

  /* The work items: primary rays in Hilbert order, admitted a batch at a time. */
  const uint32_t w = job->setup.fb->width, h = job->setup.fb->height;
  job->total = (uint64_t)w * h;
  job->progress_every = 0; /* progress counts rays (progress()) */
  d->order = xmalloc(job->total * sizeof *d->order + 1);
  camera_hilbert_order(w, h, d->order);
  d->batch = p->dyn_batch_rays ? p->dyn_batch_rays : job->total;
  d->phase = DYN_CLOSEST;
  job->shared = d;
}

static void dyn_create(struct policy_job *job) {
  struct dyn *d = xcalloc(1, sizeof *d);
  /* Queue points for the cache and the machine (policy.h). */
  struct qpoint_budget bud;
  uint32_t block_tris, group;
  job_plan(job, &d->qs, &bud, &block_tris, &group);
  dyn_setup(job, d, block_tris, group);
}

/* The treelet policy: treelets of the tree for the same budget the dynamic
 * policy gives a queue point's geometry (g_max: the cache left once the tree's
 * share, the queue table and the ray buffer are reserved, over the cores that
 * hold one at once), nodes and triangles counted (treelet.h), and each
 * treelet's root a queue point. Queue i is the treelet of the i-th root in
 * node order, so the drains see an ordinary selection. */
static void tl_create(struct policy_job *job) {
  struct dyn *d = xcalloc(1, sizeof *d);
  const struct kd_tree *kd = job->setup.kd;
  struct qpoint_budget bud;
  uint32_t block_tris, group;
  job_plan(job, &d->qs, &bud, &block_tris, &group);
  qpoint_fini(&d->qs);
  struct treelet_set ts;
  treelet_build(&ts, kd, job->setup.layout.tri_bytes, bud.gmax_bytes);
  const uint32_t n = kd->node_count;
  d->qs.node_count = n;
  d->qs.gmax_bytes = bud.gmax_bytes;
  d->qs.nodes = kd->nodes;
  d->qs.mark = qpoint_mark_new(n);
  d->qs.qnode = xmalloc((uint64_t)ts.count * sizeof *d->qs.qnode + 1);
  uint32_t *qi_of_treelet = xmalloc((uint64_t)ts.count * sizeof *qi_of_treelet + 1);
  for (uint32_t i = 0; i < n; i++) {
    if (ts.root[ts.of[i]] == i) {
      qpoint_mark(d->qs.mark, i);
      qi_of_treelet[ts.of[i]] = d->qs.count;
      d->qs.qnode[d->qs.count++] = i;
    }
  }
  CHECK_EQ(d->qs.count, ts.count);
  /* The treelet of every node becomes its queue, in place: a second array
   * of a word a node would be the run's peak on a large tree. */
  for (uint32_t i = 0; i < n; i++) ts.of[i] = qi_of_treelet[ts.of[i]];
  d->tl_of = ts.of;
  ts.of = NULL;
  free(qi_of_treelet);
  treelet_fini(&ts);
  dyn_setup(job, d, block_tris, group);
}

static void dyn_destroy(struct policy_job *job) {
  struct dyn *d = job->shared;
  if (!d) return;
  free(d->order);
  free(d->pass);
  free(d->park_next);
  free(d->slot_wait);
  qdrain_fini(&d->ds);
  qstore_fini(&d->st);
  qpoint_fini(&d->qs);
  free(d->tl_of);
  free(d);
}

static void dyn_scratch_free(void *scratch) {
  struct dyn_worker *x = scratch;
  if (!x) return;
  free(x->pend.r);
  qdrain_claim_fini(&x->cl);
  free(x);
}

/* The batch is done: count its primary rays as work items done. */
static void batch_end(struct policy_job *job, struct dyn *d) {
  d->active = false;
  d->batch_seq++;
  policy_job_done(job, d->hi - d->lo);
  const struct policy_setup *s = &job->setup;
  if (job->done == job->total && s->progress)
    s->progress(s->progress_ctx, d->terminated, d->terminated);
}

/* Take part in a batch of primary rays until it is done: the first worker to
 * find none under way claims the next (before any access), every worker then
 * does what work() finds, starts the next phase when it finds the phase over,
 * and otherwise parks (and comes back here when woken). One worker does the
 * whole batch in the order the single loop did: each primary ray to its first
 * queue, then every generation: closest-hit rays, their shadow rays, the next
 * generation. */
static bool dyn_step(struct policy_job *job, struct policy_worker *wk) {
  struct dyn *d = job->shared;
  if (!d->active) {
    uint64_t k0, n = policy_job_claim(job, d->batch, &k0);
    if (n == 0) return false;
    CHECK_EQ(d->pending, 0);
    CHECK(!qstore_any_free(&d->st));
    d->active = true;
    d->lo = d->admit_next = k0;
    d->hi = k0 + n;
    d->admitting = 0;
    d->phase = DYN_ADMIT;
  }
  if (!wk->scratch) {
    struct dyn_worker *nx = xcalloc(1, sizeof *nx);
    qdrain_claim_init(&d->ds, &nx->cl);
    wk->scratch = nx;
  }
  struct dyn_worker *x = wk->scratch;
  x->d = d;
  x->job = job;
  x->wk = wk;
  x->tr = &wk->tr;
  x->st = &wk->st;
  const uint64_t seq = d->batch_seq;
  while (d->batch_seq == seq) {
    if (work(x)) continue;
    if (!x->holding && phase_over(d)) {
      /* No worker waits for a pass between phases (a pass left is no phase
       * over): the idle ones get a free queue each, or all go on at the end. */
      CHECK_EQ(d->parked_busy, 0);
      if (advance(d)) {
        batch_end(job, d);
        wake(x, &d->idle, UINT64_MAX);
      } else {
        wake(x, &d->idle, qstore_free_queues(&d->st));
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
static void dyn_finish(struct policy_job *job, struct render_stats *st) {
  const struct dyn *d = job->shared;
  CHECK(!d->active);
  CHECK_EQ(d->pending, 0);
  CHECK_EQ(d->parked, 0);
  qstore_check_empty(&d->st);
  qdrain_check_done(&d->ds);
  st->ray_slots_max += (uint64_t)qstore_chunks(&d->st) * QSTORE_CHUNK_RAYS;
}

const struct policy_module policy_treelet_module = {
    .region_bytes = 0, /* its rays wait in the queues, at queue_base */
    .max_workers = 0,
    .create = tl_create,
    .destroy = dyn_destroy,
    .step = dyn_step,
    .scratch_free = dyn_scratch_free,
    .finish = dyn_finish,
};

const struct policy_module policy_dynamic_module = {
    .region_bytes = 0, /* its rays wait in the queues, at queue_base */
    .max_workers = 0,  /* any: a core's workers share its queue point */
    .create = dyn_create,
    .destroy = dyn_destroy,
    .step = dyn_step,
    .scratch_free = dyn_scratch_free,
    .finish = dyn_finish,
};
