/* The timed machine: cores, threads, ray contexts and their L1s, wired to the
 * event engine, the L2 (sim/l2.h) and the DRAM below it (sim/dram.h); and the
 * timed backend of the memory door (the ops a running ray context calls).
 *
 * Time flows through three kinds of event here: a core's issue slot (it
 * resumes one ray for one block), an access arriving at the L2, and a line
 * coming back for a waiting ray; the L2 and the DRAM keep their own. Only the
 * issue event resumes a coroutine, so everything else may run in any handler
 * without re-entering the renderer. */
#include "sim/machine.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sim/cache.h"
#include "sim/coro.h"
#include "sim/dram.h"
#include "sim/engine.h"
#include "sim/err.h"
#include "sim/l2.h"
#include "sim/machine_cfg.h"
#include "sim/machine_state.h"
#include "sim/ring.h"
#include "sim/stats.h"
#include "sim/timeline.h"

static const struct mem_ops timed_ops;

/* NOTE: `traced` below is the trace layer (machine_trace_enable), a constant
 * at each call like `costed`: the functions that change a thread's state come
 * in two instances, and without the layer they carry nothing of it. */

/* ---- parameters ---- */

static struct l2_params l2_params_of(const struct machine_params *p) {
  struct l2_params l = {p->l2_size_bytes, p->l2_ways,  p->l2_latency_cycles,
                        p->l2_banks,      p->l2_mshrs, p->l2_write_buffer};
  return l;
}

struct dram_params machine_dram_params(const struct machine_params *p) {
  struct dram_params d = {machine_fidelity_dram(p->fidelity),
                          p->dram_latency_cycles,
                          p->dram_bytes_per_cycle,
                          p->dram_queue_depth,
                          p->dram_clock_mhz,
                          p->dram_banked};
  return d;
}

uint64_t machine_core_khz(const struct machine_params *p) {
  return (uint64_t)llround(p->clock_ghz * 1e6);
}

double machine_dram_peak_bytes_per_cycle(const struct machine_params *p) {
  switch (machine_fidelity_dram(p->fidelity)) {
  case DRAM_MODEL_CHANNEL: return p->dram_bytes_per_cycle;
  case DRAM_MODEL_BANKED:
    return (double)p->dram_banked.channels * p->dram_banked.bus_bytes * 2.0 * p->dram_clock_mhz /
           (p->clock_ghz * 1e3);
  default: return 0;
  }
}

const char *machine_params_problem(const struct machine_params *p, char *buf, size_t cap) {
  const char *why = machine_cfg_range_problem(p, buf, cap);
  if (why) return why;
  if ((uint64_t)p->cores * p->threads_per_core * p->rays_per_thread > MACHINE_MAX_CONTEXTS)
    return "cores x threads_per_core x rays_per_thread: at most 2^20 ray contexts";
  if (p->l1_size_bytes) {
    struct cache_params c = {p->l1_size_bytes, p->l1_ways, SIM_LINE_LG2, false};
    if (cache_params_problem(&c)) return "l1: size and ways do not make a cache of 64-byte lines";
  }
  struct l2_params l2 = l2_params_of(p);
  if ((why = l2_params_problem(&l2))) return why;
  struct dram_params d = machine_dram_params(p);
  return dram_params_problem(&d);
}

/* ---- threads ---- */

/* Count thread time from th->since to t in its current state. */
static void th_account(struct machine *m, struct mthread *th, uint64_t t) {
  uint64_t d = t - th->since;
  switch (th->state) {
  case TH_BUSY:
    m->st.thread_busy_cycles += d;
    timeline_span(&m->tl, MACHINE_TL_BUSY_THREAD_CYCLES, th->since, t, 1.0);
    break;
  case TH_WAIT: m->st.thread_wait_cycles += d; break;
  case TH_PARKED: m->st.thread_parked_cycles += d; break;
  default: m->st.thread_done_cycles += d; break;
  }
  th->since = t;
}

static void th_set(struct machine *m, struct mthread *th, enum th_state s, uint64_t t) {
  if (th->state == s) return;
  th_account(m, th, t);
  th->state = (uint8_t)s;
}

static inline void kick(struct machine *m, uint32_t core, const bool traced);

/* Thread th takes ray c (ready) at cycle t: free if it ran c last. */
static inline void th_take(struct machine *m, struct mthread *th, uint32_t c, uint64_t t,
                           const bool traced) {
  th->cur = c;
  uint64_t *ready = &m->ready_at[th - m->th];
  *ready = t;
  const bool switched = th->last != NONE && th->last != c;
  if (switched) {
    *ready += m->p.cost_ray_switch_cycles;
    m->st.ray_switches++;
    m->st.switch_cycles += m->p.cost_ray_switch_cycles;
  }
  th_set(m, th, TH_BUSY, t);
  if (traced) trace_take(m, (uint32_t)(th - m->th), t, switched);
}

/* The thread's ray stopped (waits or is done) at cycle t: take the next ready one. */
static inline void th_next(struct machine *m, struct mthread *th, uint64_t t, const bool traced) {
  if (th->q_head != NONE) {
    uint32_t c = th->q_head;
    th->q_head = m->ctx[c].next;
    if (th->q_head == NONE) th->q_tail = NONE;
    th_take(m, th, c, t, traced);
    return;
  }
  th->cur = NONE;
  m->ready_at[th - m->th] = UINT64_MAX;
  th_set(m, th, !th->live ? TH_DONE : th->parked == th->live ? TH_PARKED : TH_WAIT, t);
  if (traced) trace_idle(m, (uint32_t)(th - m->th), t);
}

/* Ray c's data is back at cycle t. */
static inline void ray_ready(struct machine *m, struct mctx *c, uint64_t t, const bool traced) {
  c->state = CTX_READY;
  /* It runs soon: fetch the top of its stack, its coroutine's record and its
   * worker's state (machine_worker_state) into the host cache now. With
   * thousands of rays waiting, these are far from the host's near caches,
   * and the switch back would wait for them. */
  uint32_t id = (uint32_t)(c - m->ctx);
  if (c->hot) {
    __builtin_prefetch(c->co);
    for (unsigned i = 0; i < 6; i++) __builtin_prefetch(c->hot + 64 * i);
    if (m->ws_base)
      for (unsigned i = 0; i < 3; i++) __builtin_prefetch(m->ws_base + id * m->ws_stride + 64 * i);
  }
  struct mthread *th = &m->th[c->thread];
  if (th->cur == NONE) {
    /* NOTE: a block runs ahead of the engine (its ray's clock passes the
     * current event's cycle), so the thread may still be busy until its last
     * block's end, th->since: it cannot take the ray before that. */
    th_take(m, th, id, t > th->since ? t : th->since, traced);
  } else {
    c->next = NONE;
    if (th->q_tail == NONE) th->q_head = id;
    else m->ctx[th->q_tail].next = id;
    th->q_tail = id;
  }
  kick(m, th->core, traced);
}

/* ---- lines back ---- */

/* A line of ray c's load is back at cycle t (fills c's L1). costed: the
 * cost layer is on; traced: the trace layer (constants at each call: four
 * instances). */
static inline void line_done(struct machine *m, struct mctx *c, uint64_t line, uint64_t t,
                             const bool costed, const bool traced) {
  struct cache *l1 = m->core[c->info.core].l1;
  if (l1) cache_fill(l1, line, false); /* a victim: an L1 has no pending line */
  m->loads_back++;
  CHECK_GT(c->pending, 0);
  if (--c->pending == 0) {
    hist_add(&m->st.load_latency, t - c->wait_from);
    if (costed) cost_charge(c, COST_WAIT, t - c->wait_from);
    ray_ready(m, c, t, traced);
  }
  if (traced) trace_tick(m, t);
}

/* The L2 answers a load (sim/l2.h's client): ctx is the waiting ray. One
 * instance for each combination of the cost and trace layers. */
#define EV_LINE_DONE(name, costed, traced)                                                         \
  static void name(void *ctx, uint64_t line) {                                                     \
    struct mctx *c = ctx;                                                                          \
    line_done(c->m, c, line, engine_now(c->m->eng), costed, traced);                               \
  }
EV_LINE_DONE(ev_line_done, false, false)
EV_LINE_DONE(ev_line_done_costed, true, false)
EV_LINE_DONE(ev_line_done_traced, false, true)
EV_LINE_DONE(ev_line_done_costed_traced, true, true)
#undef EV_LINE_DONE

/* Accesses on their way to the L2, packed into the event's one argument:
 * the first line, the lines in a row from it (1 to ACCESS_RUN_MAX), op and
 * class. A load's lines that miss the L1 in a row travel in one event: the
 * events they were, one a line, came one right after another (same cycle,
 * scheduled in a row), so nothing ran between them. */
#define ACCESS_RUN_MAX 64u
static inline uint64_t access_pack(uint64_t line, uint32_t n, enum l2_op op, unsigned cls) {
  CHECK_LT(line, 1ull << 52);
  CHECK(n >= 1 && n <= ACCESS_RUN_MAX);
  CHECK_LT(cls, 16u);
  return line << 12 | (uint64_t)(n - 1) << 6 | (uint64_t)op << 4 | cls;
}
static inline uint64_t access_line(uint64_t a) { return a >> 12; }
static inline uint32_t access_lines(uint64_t a) { return (uint32_t)((a >> 6) & 63) + 1; }
static inline enum l2_op access_op(uint64_t a) { return (enum l2_op)((a >> 4) & 3); }
static inline unsigned access_cls(uint64_t a) { return (unsigned)(a & 15); }

/* Accesses reach the L2: ctx is the ray that made them, arg access_pack'ed. */
static void ev_l2_access(void *ctx, uint64_t arg) {
  struct mctx *c = ctx;
  const enum l2_op op = access_op(arg);
  const uint64_t line = access_line(arg);
  for (uint32_t i = 0, n = access_lines(arg); i < n; i++)
    l2_access(c->m->l2, line + i, op, access_cls(arg), op == L2_LOAD ? c : NULL, 0);
}
/* The same with the cost layer on: an access carries the item it is for. A
 * load's context waits for it, still working for the same items; a store's
 * tag waits in the context's FIFO (cost_store_push). */
static void ev_l2_access_costed(void *ctx, uint64_t arg) {
  struct mctx *c = ctx;
  const enum l2_op op = access_op(arg);
  const uint64_t line = access_line(arg);
  for (uint32_t i = 0, n = access_lines(arg); i < n; i++) {
    uint32_t tag = op == L2_LOAD ? cost_tag(c) : cost_store_pop(c);
    l2_access(c->m->l2, line + i, op, access_cls(arg), op == L2_LOAD ? c : NULL, tag);
  }
}

/* ---- cores ---- */

static void ev_issue(void *ctx, uint64_t core);
static void ev_issue_traced(void *ctx, uint64_t core);

/* Make sure core has an issue event at the first cycle one of its threads can
 * issue (stale events are recognised by their cycle and ignored). */
static inline void kick(struct machine *m, uint32_t core, const bool traced) {
  struct mcore *k = &m->core[core];
  /* The event the core has comes no later than the port is free or than
   * now, so no later than any cycle the scan below could find (it takes
   * the later of both): the scan would change nothing. On a busy core,
   * nearly every kick. */
  if (k->ev && (k->ev_at <= k->port_free || k->ev_at <= engine_now(m->eng))) return;
  const uint32_t T = m->p.threads_per_core;
  uint64_t best = UINT64_MAX;
  for (uint32_t i = 0; i < T; i++)
    if (m->ready_at[core * T + i] < best) best = m->ready_at[core * T + i];
  if (best == UINT64_MAX) return;
  if (best < k->port_free) best = k->port_free;
  if (best < engine_now(m->eng)) best = engine_now(m->eng);
  if (k->ev && k->ev_at <= best) return;
  k->ev = true;
  k->ev_at = best;
  engine_at(m->eng, best, traced ? ev_issue_traced : ev_issue, m, core);
}

static void ctx_main(void *arg) {
  struct mctx *c = arg;
  struct mem_port port = {c->m->ops, c};
  c->m->fn(c->m->fn_arg, &c->info, port);
}

/* Core `core`'s issue slot: resume one ray for one block. */
static inline void issue(struct machine *m, uint64_t core, const bool traced) {
  struct mcore *k = &m->core[core];
  const uint64_t t = engine_now(m->eng);
  if (!k->ev || k->ev_at != t) return; /* stale */
  k->ev = false;
  const uint32_t T = m->p.threads_per_core;
  uint32_t pick = NONE;
  for (uint32_t i = 1; i <= T && pick == NONE; i++) {
    const uint32_t j = k->rr + i < T ? k->rr + i : k->rr + i - T; /* (k->rr + i) % T */
    if (m->ready_at[core * T + j] <= t) pick = j;
  }
  if (pick == NONE || t < k->port_free) {
    kick(m, (uint32_t)core, traced);
    return;
  }
  k->rr = pick;
  struct mthread *th = &m->th[core * T + pick];
  if (traced) trace_issue(m, (uint32_t)(core * T + pick), t);
  uint32_t id = th->cur;
  struct mctx *c = &m->ctx[id];
  th->last = id;
  c->t = t;
  c->slots = 0;
  if (!c->co) {
    c->co = coro_create(m->pool, ctx_main, c);
    if (++m->stacks_live > m->st.stacks_max) m->st.stacks_max = m->stacks_live;
  }
  m->running = c;
  coro_resume(c->co);
  c->hot = coro_resume_point(c->co);
  m->running = NULL;
  m->st.blocks++;
  k->port_free = t + c->slots;
  m->st.issue_slots += c->slots;
  timeline_span(&m->tl, MACHINE_TL_ISSUED_OPS, t, t + c->slots, 1.0);
  if (coro_finished(c->co)) {
    if (m->painted_max < coro_stack_used(c->co)) m->painted_max = coro_stack_used(c->co);
    coro_destroy(c->co);
    c->co = NULL;
    m->stacks_live--;
    if (c->acc) { /* it starts again (a wake) without knowing whom it worked for */
      CHECK_LE(c->nitems, 1);
      machine_cost_flush(c);
      c->nitems = 0;
    }
    if (c->parking) { /* its stack is back in the pool until a wake */
      c->parking = false;
      c->state = CTX_PARKED;
      th->parked++;
    } else {
      c->state = CTX_DONE;
      th->live--;
    }
    th_next(m, th, c->t, traced);
  } else {
    CHECK_EQ(c->state, CTX_WAIT);
    th_next(m, th, c->t, traced);
  }
  kick(m, (uint32_t)core, traced);
  if (m->progress && (m->st.blocks & 0xFFFF) == 0) m->progress(m->progress_ctx, t);
}

static void ev_issue(void *ctx, uint64_t core) { issue(ctx, core, false); }
static void ev_issue_traced(void *ctx, uint64_t core) { issue(ctx, core, true); }

/* ---- the door ---- */

/* The door comes in two instances, without and with the cost layer
 * (timed_ops, costed_ops: machine_door_costed picks the second): each
 * function below takes `costed` as a constant, so with costs off the door
 * carries nothing of them. */

static inline void door_compute(struct mctx *c, uint64_t cycles, const bool costed) {
  c->t += cycles;
  c->slots += cycles;
  c->m->st.computes++;
  if (costed) cost_charge(c, COST_SLOTS, cycles);
}

/* What a load and a store pay first: one issue slot at the context's time. */
static inline struct machine *door_issue(struct mctx *c, uint32_t size, unsigned cls,
                                         const bool costed) {
  CHECK(!c->parking); /* a parking worker returns without another access */
  CHECK_GT(size, 0);
  CHECK_LT(cls, MEM_CLASS_MAX);
  c->t++;
  c->slots++;
  if (costed) cost_charge(c, COST_SLOTS, 1);
  return c->m;
}

static inline void door_load(struct mctx *c, uint64_t addr, uint32_t size, unsigned cls,
                             const bool costed) {
  struct machine *m = door_issue(c, size, cls, costed);
  m->st.loads++;
  struct cache *l1 = m->core[c->info.core].l1;
  uint64_t line = addr >> SIM_LINE_LG2, end = (addr + size - 1) >> SIM_LINE_LG2;
  uint32_t pending = 0, run = 0; /* the last `run` lines missed, not yet sent */
  for (; line <= end; line++) {
    bool hit = false;
    if (l1) {
      m->st.l1_accesses++;
      hit = cache_use(l1, line) != CACHE_NONE;
      m->st.l1_hits += hit;
    }
    if (!hit) {
      pending++;
      run++;
      l2_prefetch(m->l2, line);
    }
    /* Send the run when a hit, the end or the run's limit closes it. */
    if (run && (hit || line == end || run == ACCESS_RUN_MAX)) {
      engine_at(m->eng, c->t, costed ? ev_l2_access_costed : ev_l2_access, c,
                access_pack(line + !hit - run, run, L2_LOAD, cls));
      run = 0;
    }
  }
  if (!pending) {
    hist_add(&m->st.load_latency, m->p.l1_latency_cycles);
    if (costed) cost_charge(c, COST_WAIT, m->p.l1_latency_cycles);
    c->t += m->p.l1_latency_cycles;
    return;
  }
  m->loads_out += pending;
  m->st.blocking_loads++;
  c->pending = pending;
  c->wait_from = c->t;
  c->state = CTX_WAIT;
  coro_suspend(c->co);
}

static inline void door_store(struct mctx *c, uint64_t addr, uint32_t size, unsigned cls,
                              const bool costed) {
  struct machine *m = door_issue(c, size, cls, costed);
  m->st.stores++;
  struct cache *l1 = m->core[c->info.core].l1;
  const uint64_t last = addr + size - 1, lmask = SIM_LINE_BYTES - 1;
  uint64_t line = addr >> SIM_LINE_LG2, end = last >> SIM_LINE_LG2;
  const uint64_t first_whole = (addr & lmask) ? line + 1 : line;
  const bool last_whole = (last & lmask) == lmask;
  for (; line <= end; line++) {
    if (l1) {
      /* Write-through, no allocation: a line the L1 holds is updated. */
      cache_use(l1, line);
    }
    bool whole = line >= first_whole && (line < end || last_whole);
    l2_prefetch(m->l2, line);
    if (costed) cost_store_push(c, cost_tag(c));
    engine_at(m->eng, c->t, costed ? ev_l2_access_costed : ev_l2_access, c,
              access_pack(line, 1, whole ? L2_STORE_LINE : L2_STORE, cls));
  }
}

static void t_compute(void *ctx, uint64_t cycles) { door_compute(ctx, cycles, false); }
static void t_load(void *ctx, uint64_t addr, uint32_t size, unsigned cls) {
  door_load(ctx, addr, size, cls, false);
}
static void t_store(void *ctx, uint64_t addr, uint32_t size, unsigned cls) {
  door_store(ctx, addr, size, cls, false);
}
static void tc_compute(void *ctx, uint64_t cycles) { door_compute(ctx, cycles, true); }
static void tc_load(void *ctx, uint64_t addr, uint32_t size, unsigned cls) {
  door_load(ctx, addr, size, cls, true);
}
static void tc_store(void *ctx, uint64_t addr, uint32_t size, unsigned cls) {
  door_store(ctx, addr, size, cls, true);
}

static void ev_wake(void *ctx, uint64_t arg) {
  struct mctx *c = ctx;
  (void)arg;
  ray_ready(c->m, c, engine_now(c->m->eng), false);
}
static void ev_wake_traced(void *ctx, uint64_t arg) {
  struct mctx *c = ctx;
  (void)arg;
  ray_ready(c->m, c, engine_now(c->m->eng), true);
}

/* The ray has nothing to do for `cycles`: it waits like a load that touches
 * no memory (its thread may switch to another ray), and takes no issue slot. */
static inline void door_wait(struct mctx *c, uint64_t cycles, const bool traced) {
  struct machine *m = c->m;
  CHECK(!c->parking);
  m->st.waits++;
  m->st.wait_cycles += cycles;
  c->state = CTX_WAIT;
  engine_at(m->eng, c->t + cycles, traced ? ev_wake_traced : ev_wake, c, 0);
  coro_suspend(c->co);
}
static void t_wait(void *ctx, uint64_t cycles) { door_wait(ctx, cycles, false); }
static void tt_wait(void *ctx, uint64_t cycles) { door_wait(ctx, cycles, true); }

/* Park (sim/mem.h): the worker function returns next; ev_issue then gives its
 * stack back and leaves the context off the machine until t_wake. */
static void t_park(void *ctx) {
  struct mctx *c = ctx;
  CHECK(!c->parking);
  c->parking = true;
  c->m->st.parks++;
}

/* Wake parked context id at the waker's time: it is ready like a ray whose
 * line came back (its thread takes it, or queues it behind the running one).
 * A wake takes no issue slot: a hardware thread scheduler would flip the
 * context's ready bit, as a line fill does. */
static inline void door_wake(struct mctx *c, uint32_t id, const bool traced) {
  struct machine *m = c->m;
  CHECK(!c->parking);
  CHECK_LT(id, m->nctx);
  struct mctx *o = &m->ctx[id];
  CHECK_EQ(o->state, CTX_PARKED);
  m->st.wakes++;
  struct mthread *th = &m->th[o->thread];
  CHECK_GT(th->parked, 0);
  th->parked--;
  ray_ready(m, o, c->t, traced);
}
static void t_wake(void *ctx, uint32_t id) { door_wake(ctx, id, false); }
static void tt_wake(void *ctx, uint32_t id) { door_wake(ctx, id, true); }

static const struct mem_ops timed_ops = {t_load, t_store, t_compute, t_wait, t_park, t_wake};
static const struct mem_ops costed_ops = {tc_load, tc_store, tc_compute, t_wait, t_park, t_wake};
static const struct mem_ops traced_ops = {t_load, t_store, t_compute, tt_wait, t_park, tt_wake};
static const struct mem_ops costed_traced_ops = {tc_load, tc_store, tc_compute,
                                                 tt_wait, t_park,   tt_wake};

/* The door's instance and the L2's client for the layers installed: the
 * cost layer (m->cost_acc, machine_door_costed's hook) and the trace layer
 * (m->trace). Before the run. */
static void door_install(struct machine *m, void *cost_ctx, l2_cost_fn cost) {
  CHECK(!m->ran);
  static const engine_fn ready[2][2] = {{ev_line_done, ev_line_done_traced},
                                        {ev_line_done_costed, ev_line_done_costed_traced}};
  static const struct mem_ops *const ops[2][2] = {{&timed_ops, &traced_ops},
                                                  {&costed_ops, &costed_traced_ops}};
  const bool costed = cost != NULL, traced = m->trace != NULL;
  m->ops = ops[costed][traced];
  struct l2_client lc = {ready[costed][traced], cost_ctx, cost, NULL, NULL};
  if (traced) {
    lc.stall_ctx = m;
    lc.stall = trace_l2_stall;
  }
  l2_set_client(m->l2, &lc);
}

void machine_door_costed(struct machine *m, void *cost_ctx, l2_cost_fn cost) {
  m->cost_ctx = cost_ctx;
  m->cost_fn = cost;
  door_install(m, cost_ctx, cost);
}

void machine_door_traced(struct machine *m) { door_install(m, m->cost_ctx, m->cost_fn); }

/* ---- machine ---- */

static struct machine *create(const struct machine_params *p, uint64_t stack_bytes, bool paint) {
  char why[MACHINE_PROBLEM_MAX];
  CHECK(machine_params_problem(p, why, sizeof why) == NULL);
  CHECK(p->fidelity != MACHINE_FIDELITY_ANALYTIC);
  struct machine *m = xcalloc(1, sizeof *m);
  m->p = *p;
  m->eng = engine_create();
  m->pool = coro_pool_create(stack_bytes ? stack_bytes : coro_default_stack_bytes(), paint);
  timeline_init(&m->tl, MACHINE_TL_COLS, p->timeline_window_cycles);
  struct l2_params lp = l2_params_of(p);
  static const struct l2_timeline_cols cols = {MACHINE_TL_L2_ACCESSES, MACHINE_TL_L2_MISSES,
                                               MACHINE_TL_DRAM_READ_BYTES, MACHINE_TL_READ_CLASS0,
                                               MACHINE_TL_DRAM_WRITE_BYTES};
  m->ops = &timed_ops;
  struct l2_client lc = {ev_line_done, NULL, NULL, NULL, NULL};
  m->l2 = l2_create(&lp, m->eng, &m->tl, &cols, &lc);
  struct dram_params dp = machine_dram_params(p);
  struct dram_client dc = l2_dram_client(m->l2);
  m->dram = dram_create(&dp, machine_core_khz(p), m->eng, &dc);
  l2_attach(m->l2, m->dram);
  m->nth = p->cores * p->threads_per_core;
  m->nctx = m->nth * p->rays_per_thread;
  m->core = xcalloc(p->cores, sizeof *m->core);
  m->th = xcalloc(m->nth, sizeof *m->th);
  m->ready_at = xcalloc_aligned(64, (uint64_t)m->nth * sizeof *m->ready_at); /* all ready at 0 */
  m->ctx = xcalloc_aligned(64, (uint64_t)m->nctx * sizeof *m->ctx);
  m->warm = xcalloc(p->cores, sizeof *m->warm);
  for (uint32_t i = 0; i < p->cores; i++) {
    m->warm[i].m = m;
    m->warm[i].core = i;
    m->core[i].rr = p->threads_per_core - 1;
    if (p->l1_size_bytes) {
      struct cache_params l1 = {p->l1_size_bytes, p->l1_ways, SIM_LINE_LG2, false};
      m->core[i].l1 = cache_create(&l1);
    }
  }
  const uint32_t R = p->rays_per_thread;
  for (uint32_t t = 0; t < m->nth; t++) {
    struct mthread *th = &m->th[t];
    th->core = t / p->threads_per_core;
    th->last = NONE;
    th->live = R;
    th->state = TH_BUSY;
    /* The first ray runs at cycle 0; the others wait in the ready FIFO. */
    th->cur = t * R;
    th->q_head = R > 1 ? t * R + 1 : NONE;
    th->q_tail = R > 1 ? t * R + R - 1 : NONE;
    for (uint32_t r = 0; r < R; r++) {
      struct mctx *c = &m->ctx[t * R + r];
      c->m = m;
      c->thread = t;
      c->state = CTX_READY;
      c->next = r + 1 < R ? t * R + r + 1 : NONE;
      c->info.id = t * R + r;
      c->info.core = th->core;
      c->info.thread = t % p->threads_per_core;
      c->info.ray = r;
    }
  }
  m->st.contexts = m->nctx;
  m->st.threads = m->nth;
  machine_energy_start(m);
  return m;
}

struct machine *machine_create(const struct machine_params *p, uint64_t stack_bytes) {
  return create(p, stack_bytes, false);
}

struct machine *machine_create_painted(const struct machine_params *p, uint64_t stack_bytes) {
  return create(p, stack_bytes, true);
}

uint64_t machine_stack_used_max(const struct machine *m) { return m->painted_max; }

void machine_destroy(struct machine *m) {
  if (!m) return;
  for (uint32_t i = 0; i < m->nctx; i++) CHECK(m->ctx[i].co == NULL || !m->ran);
  for (uint32_t i = 0; i < m->nctx; i++) coro_destroy(m->ctx[i].co);
  for (uint32_t i = 0; i < m->nctx; i++) ring_free(&m->ctx[i].runs);
  free(m->cost_acc);
  free(m->costs.issue_slots);
  free(m->costs.load_wait_cycles);
  for (unsigned c = 0; c < MEM_CLASS_MAX; c++) free(m->costs.read_lines[c]);
  free(m->costs.write_lines);
  trace_destroy(m->trace);
  for (uint32_t i = 0; i < m->p.cores; i++) cache_destroy(m->core[i].l1);
  free(m->core);
  free(m->warm);
  free(m->th);
  free(m->ready_at);
  free(m->ctx);
  timeline_fini(&m->tl);
  l2_destroy(m->l2);
  dram_destroy(m->dram);
  coro_pool_destroy(m->pool);
  engine_destroy(m->eng);
  free(m);
}

void machine_run(struct machine *m, machine_worker_fn fn, void *arg, machine_progress_fn progress,
                 void *progress_ctx) {
  CHECK(!m->ran);
  m->ran = true;
  m->fn = fn;
  m->fn_arg = arg;
  m->progress = progress;
  m->progress_ctx = progress_ctx;
  for (uint32_t i = 0; i < m->p.cores; i++) {
    if (m->trace) kick(m, i, true);
    else kick(m, i, false);
  }
  engine_run(m->eng);
  /* Everything must be over: every ray returned (none parked with nobody left
   * to wake it), no miss outstanding. */
  for (uint32_t i = 0; i < m->nctx; i++) CHECK_NE(m->ctx[i].state, CTX_PARKED);
  for (uint32_t i = 0; i < m->nctx; i++) CHECK_EQ(m->ctx[i].state, CTX_DONE);
  CHECK(l2_quiet(m->l2));
  CHECK_EQ(m->loads_out, m->loads_back);
  /* The end: the last event (the last data served), the last block's last
   * cycle (blocks run ahead of the engine). */
  uint64_t end = engine_now(m->eng);
  for (uint32_t t = 0; t < m->nth; t++)
    if (m->th[t].since > end) end = m->th[t].since;
  dram_finish(m->dram, end);
  for (uint32_t t = 0; t < m->nth; t++) {
    CHECK_EQ(m->th[t].state, TH_DONE);
    th_account(m, &m->th[t], end);
  }
  if (m->trace) trace_finish(m, end);
  l2_finish(m->l2, end);
  machine_energy_finish(m, end);
  struct machine_stats *st = &m->st;
  st->cycles = end;
  st->l2 = *l2_get_stats(m->l2);
  st->dram = *dram_get_stats(m->dram);
  st->events = engine_events(m->eng);
  /* Conservation: bytes asked of DRAM are the bytes it moved. */
  CHECK_EQ(st->dram.read_bytes, st->l2.fetch_bytes);
  CHECK_EQ(st->dram.write_bytes, st->l2.writeback_bytes);
  CHECK_EQ(st->thread_busy_cycles + st->thread_wait_cycles + st->thread_parked_cycles +
               st->thread_done_cycles,
           (uint64_t)m->nth * end);
  /* The timeline covers the whole run. */
  timeline_cover(&m->tl, end);
  if (m->cost_acc) machine_cost_finish(m);
}

void machine_worker_state(struct machine *m, const void *base, uint64_t stride) {
  m->ws_base = base;
  m->ws_stride = stride;
}

const struct machine_stats *machine_get_stats(const struct machine *m) { return &m->st; }
const struct timeline *machine_timeline(const struct machine *m) { return &m->tl; }
struct dram *machine_dram(const struct machine *m) {
  return m->dram;
}
