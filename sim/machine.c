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
#include "sim/ring.h"
#include "sim/stats.h"
#include "sim/timeline.h"

#define NONE UINT32_MAX

enum ctx_state { CTX_READY, CTX_WAIT, CTX_PARKED, CTX_DONE };
enum th_state { TH_BUSY, TH_WAIT, TH_PARKED, TH_DONE };

/* A ray context. Two host lines, line-aligned, what a load, a line back and
 * an issue read in the first (the engine fetches both ahead of an event):
 * on a large machine thousands of them are far from the host's near caches. */
struct mctx {
  _Alignas(64) struct machine *m;
  struct coro *co;
  /* Its suspended stack's top (coro_resume_point, taken when it suspends:
   * a wake then need not read the coroutine's record first); NULL: none. */
  const char *hot;
  uint64_t *acc;      /* per-item cost counters (below); NULL: costs not counted */
  uint64_t t;         /* the ray's own clock inside a block */
  uint64_t slots;     /* issue slots of the current block */
  uint64_t wait_from; /* cycle its waiting load left the core */
  uint32_t pending;   /* lines of the current load not yet back */
  uint32_t thread;    /* global thread index */
  struct machine_worker_info info;
  uint32_t next; /* ready FIFO of its thread */
  uint8_t state;
  bool parking; /* asked to park: its worker function is returning */
  /* Per-item costs (machine_costs_enable): the items it works for, what it
   * has cost them since (acc: COST_* counters, split when it is told anew),
   * and the tags of its stores on their way to the L2, in issue order. */
  const uint32_t *items;
  uint32_t nitems, item1;
  struct ring runs; /* struct tagrun */
};

/* Stores in a row with one tag. */
struct tagrun {
  uint32_t tag, n;
};

/* A context's cost counters: issue slots, load wait, lines written back,
 * then lines read by class. */
enum { COST_SLOTS, COST_WAIT, COST_WRITE, COST_READ0 };

struct mthread {
  uint32_t core;
  uint32_t cur;            /* the ray the thread runs or switches to; NONE when idle */
  uint32_t last;           /* the ray it ran last */
  uint32_t q_head, q_tail; /* rays ready to run, besides cur */
  uint32_t live;           /* rays not done */
  uint32_t parked;         /* of those, parked (mem_park) */
  uint8_t state;
  uint64_t since;
};

struct mcore {
  uint64_t port_free;
  uint64_t ev_at;
  bool ev;
  uint32_t rr; /* thread (local index) that issued last */
  struct cache *l1;
};

struct machine {
  struct machine_params p;
  struct engine *eng;
  struct coro_pool *pool;
  struct dram *dram;
  struct l2 *l2;
  struct mctx *ctx;
  struct mthread *th;
  /* When thread i's cur may issue: ready_at[i]; UINT64_MAX while idle, so a
   * core's earliest thread is a plain minimum over its threads' adjacent
   * entries (one host line for 8 threads a core, or a power of two fewer;
   * the threads' own records, a host cache miss each on a large machine,
   * are not read).
   * NOTE: cur is ready whenever kick or ev_issue asks (a ray that waits,
   * parks or ends is replaced by th_next before either runs again), so the
   * ray's own state is not read either. */
  uint64_t *ready_at;
  struct mcore *core;
  uint32_t nctx, nth;
  uint64_t stacks_live, painted_max;
  machine_worker_fn fn;
  void *fn_arg;
  const char *ws_base; /* machine_worker_state; NULL: none given */
  uint64_t ws_stride;
  machine_progress_fn progress;
  void *progress_ctx;
  bool ran;
  uint64_t loads_out, loads_back; /* conservation: L2 load requests and answers */
  struct timeline tl;
  struct machine_stats st;
  struct mctx *running; /* the ray inside a block, if any (machine_probe) */
  struct mwarm *warm;   /* one warming port context a core (machine_warm_port) */
  uint64_t warm_slots, count_slots;
  struct machine_costs costs; /* per item (machine_costs_enable) */
  uint64_t *cost_acc;         /* every context's counters; NULL: costs not counted */
  unsigned cost_stride;       /* counters a context */
};

/* A core's warming port (machine_warm_port). */
struct mwarm {
  struct machine *m;
  uint32_t core;
};

static const struct mem_ops timed_ops;

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

static void kick(struct machine *m, uint32_t core);

/* Thread th takes ray c (ready) at cycle t: free if it ran c last. */
static void th_take(struct machine *m, struct mthread *th, uint32_t c, uint64_t t) {
  th->cur = c;
  uint64_t *ready = &m->ready_at[th - m->th];
  *ready = t;
  if (th->last != NONE && th->last != c) {
    *ready += m->p.cost_ray_switch_cycles;
    m->st.ray_switches++;
    m->st.switch_cycles += m->p.cost_ray_switch_cycles;
  }
  th_set(m, th, TH_BUSY, t);
}

/* The thread's ray stopped (waits or is done) at cycle t: take the next ready one. */
static void th_next(struct machine *m, struct mthread *th, uint64_t t) {
  if (th->q_head != NONE) {
    uint32_t c = th->q_head;
    th->q_head = m->ctx[c].next;
    if (th->q_head == NONE) th->q_tail = NONE;
    th_take(m, th, c, t);
    return;
  }
  th->cur = NONE;
  m->ready_at[th - m->th] = UINT64_MAX;
  th_set(m, th, !th->live ? TH_DONE : th->parked == th->live ? TH_PARKED : TH_WAIT, t);
}

/* Ray c's data is back at cycle t. */
static void ray_ready(struct machine *m, struct mctx *c, uint64_t t) {
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
    th_take(m, th, id, t > th->since ? t : th->since);
  } else {
    c->next = NONE;
    if (th->q_tail == NONE) th->q_head = id;
    else m->ctx[th->q_tail].next = id;
    th->q_tail = id;
  }
  kick(m, th->core);
}

/* ---- per-item costs ---- */

/* Add v of counter ch to item. NOTE: line counts are 32-bit (half the host
 * memory): 2^32 lines, 256 GiB of DRAM traffic for one item, is far past any
 * run that ends. */
static void cost_put(struct machine *m, uint32_t item, unsigned ch, uint64_t v) {
  struct machine_costs *k = &m->costs;
  CHECK_LT(item, k->items);
  if (ch == COST_SLOTS) {
    k->issue_slots[item] += v;
  } else if (ch == COST_WAIT) {
    k->load_wait_cycles[item] += v;
  } else {
    uint32_t *p = ch == COST_WRITE ? &k->write_lines[item] : &k->read_lines[ch - COST_READ0][item];
    CHECK_LE(v, UINT32_MAX - *p);
    *p += (uint32_t)v;
  }
}

/* Charge what c has cost since it was told whom it works for: each counter
 * split evenly among its items, the remainder one each to the first. */
static void cost_flush(struct mctx *c) {
  struct machine *m = c->m;
  for (unsigned ch = 0; ch < m->cost_stride; ch++) {
    const uint64_t v = c->acc[ch];
    if (!v) continue;
    c->acc[ch] = 0;
    CHECK_GT(c->nitems, 0);
    const uint64_t q = v / c->nitems, r = v % c->nitems;
    for (uint32_t j = 0; j < c->nitems; j++)
      if (q + (j < r)) cost_put(m, c->items[j], ch, q + (j < r));
  }
}

/* c's own work (slots, waits, its loads' DRAM reads), charged when told anew. */
static inline void cost_charge(struct mctx *c, unsigned ch, uint64_t v) {
  if (!c->acc) return;
  CHECK_GT(c->nitems, 0); /* every access is attributed */
  c->acc[ch] += v;
}

/* The tag an access of c carries to the L2: the first item it works for. */
static uint32_t cost_tag(const struct mctx *c) {
  if (!c->acc) return 0;
  CHECK_GT(c->nitems, 0);
  return c->items[0];
}

/* A store's tag joins c's FIFO (its L2 access comes later: ev_l2_access). */
static void cost_store_push(struct mctx *c, uint32_t tag) {
  if (ring_len(&c->runs) && RING_BACK(&c->runs, struct tagrun)->tag == tag) {
    RING_BACK(&c->runs, struct tagrun)->n++;
    return;
  }
  *RING_PUSH(&c->runs, struct tagrun) = (struct tagrun){tag, 1};
}

/* NOTE: a context's L2 accesses leave in issue order (its clock never goes
 * back, and events of one cycle keep their order), so a FIFO finds each
 * store's tag. */
static uint32_t cost_store_pop(struct mctx *c) {
  CHECK_GT(ring_len(&c->runs), 0);
  struct tagrun *h = RING_HEAD(&c->runs, struct tagrun);
  const uint32_t tag = h->tag;
  if (--h->n == 0) ring_pop(&c->runs);
  return tag;
}

/* The L2's cost hook (struct l2_client): a line read for a miss or written
 * back. A load's read waits with its context, which still works for the
 * items it loaded for. */
static void l2_cost(void *ctx, void *waiter, uint32_t tag, unsigned cls, bool write) {
  struct machine *m = ctx;
  if (write) {
    cost_put(m, tag, COST_WRITE, 1);
    return;
  }
  CHECK_LT(cls, m->costs.classes);
  if (waiter) cost_charge(waiter, COST_READ0 + cls, 1);
  else cost_put(m, tag, COST_READ0 + cls, 1);
}

void machine_costs_enable(struct machine *m, uint64_t items, unsigned classes) {
  CHECK(!m->ran);
  CHECK(!m->cost_acc);
  CHECK_LT(classes, MEM_CLASS_MAX + 1);
  CHECK_LE(items, (uint64_t)UINT32_MAX + 1);
  struct machine_costs *k = &m->costs;
  k->items = items;
  k->classes = classes;
  k->issue_slots = xcalloc(items + 1, sizeof *k->issue_slots);
  k->load_wait_cycles = xcalloc(items + 1, sizeof *k->load_wait_cycles);
  for (unsigned c = 0; c < classes; c++)
    k->read_lines[c] = xcalloc(items + 1, sizeof *k->read_lines[c]);
  k->write_lines = xcalloc(items + 1, sizeof *k->write_lines);
  m->cost_stride = COST_READ0 + classes;
  m->cost_acc = xcalloc((uint64_t)m->nctx * m->cost_stride, sizeof *m->cost_acc);
  for (uint32_t i = 0; i < m->nctx; i++) m->ctx[i].acc = m->cost_acc + (uint64_t)i * m->cost_stride;
  l2_set_cost(m->l2, m, l2_cost);
}

void machine_attribute(struct machine *m, uint32_t ctx, const uint32_t *items, uint32_t n) {
  if (!m->cost_acc) return;
  CHECK_LT(ctx, m->nctx);
  struct mctx *c = &m->ctx[ctx];
  CHECK(m->running == c);
  cost_flush(c);
  for (uint32_t j = 0; j < n; j++) CHECK_LT(items[j], m->costs.items);
  c->item1 = n ? items[0] : 0;
  c->items = n == 1 ? &c->item1 : items;
  c->nitems = n;
}

const struct machine_costs *machine_get_costs(const struct machine *m) {
  return m->cost_acc ? &m->costs : NULL;
}

/* The end of a run that counted costs: every context's charged, and the
 * items' sums are the run's totals (conservation). */
static void cost_finish(struct machine *m) {
  for (uint32_t i = 0; i < m->nctx; i++) {
    CHECK_EQ(m->ctx[i].nitems, 0);
    CHECK_EQ(ring_len(&m->ctx[i].runs), 0);
  }
  const struct machine_costs *k = &m->costs;
  uint64_t slots = 0, wait = 0, wr = 0, rd[MEM_CLASS_MAX] = {0};
  for (uint64_t i = 0; i < k->items; i++) {
    slots += k->issue_slots[i];
    wait += k->load_wait_cycles[i];
    wr += k->write_lines[i];
    for (unsigned c = 0; c < k->classes; c++) rd[c] += k->read_lines[c][i];
  }
  CHECK_EQ(slots, m->st.issue_slots);
  CHECK_EQ(wait, m->st.load_latency.sum);
  CHECK_EQ(wr * SIM_LINE_BYTES, m->st.l2.writeback_bytes);
  for (unsigned c = 0; c < MEM_CLASS_MAX; c++)
    CHECK_EQ(c < k->classes ? rd[c] * SIM_LINE_BYTES : 0, m->st.l2.fetch_bytes_by_class[c]);
}

/* ---- lines back ---- */

/* A line of ray c's load is back at cycle t (fills c's L1). */
static void line_done(struct machine *m, struct mctx *c, uint64_t line, uint64_t t) {
  struct cache *l1 = m->core[c->info.core].l1;
  if (l1) cache_fill(l1, line, false); /* a victim: an L1 has no pending line */
  m->loads_back++;
  CHECK_GT(c->pending, 0);
  if (--c->pending == 0) {
    hist_add(&m->st.load_latency, t - c->wait_from);
    cost_charge(c, COST_WAIT, t - c->wait_from);
    ray_ready(m, c, t);
  }
}

/* The L2 answers a load (sim/l2.h's client): ctx is the waiting ray. */
static void ev_line_done(void *ctx, uint64_t line) {
  struct mctx *c = ctx;
  line_done(c->m, c, line, engine_now(c->m->eng));
}

/* An access reaches the L2: ctx is the ray that made it, arg l2_pack'ed. */
static void ev_l2_access(void *ctx, uint64_t arg) {
  struct mctx *c = ctx;
  enum l2_op op = l2_unpack_op(arg);
  /* A load's context waits for it, still working for the same items. */
  uint32_t tag = !c->acc ? 0 : op == L2_LOAD ? cost_tag(c) : cost_store_pop(c);
  l2_access(c->m->l2, l2_unpack_line(arg), op, l2_unpack_cls(arg), op == L2_LOAD ? c : NULL, tag);
}

/* ---- cores ---- */

static void ev_issue(void *ctx, uint64_t core);

/* Make sure core has an issue event at the first cycle one of its threads can
 * issue (stale events are recognised by their cycle and ignored). */
static void kick(struct machine *m, uint32_t core) {
  struct mcore *k = &m->core[core];
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
  engine_at(m->eng, best, ev_issue, m, core);
}

static void ctx_main(void *arg) {
  struct mctx *c = arg;
  struct mem_port port = {&timed_ops, c};
  c->m->fn(c->m->fn_arg, &c->info, port);
}

static void ev_issue(void *ctx, uint64_t core) {
  struct machine *m = ctx;
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
    kick(m, (uint32_t)core);
    return;
  }
  k->rr = pick;
  struct mthread *th = &m->th[core * T + pick];
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
      cost_flush(c);
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
    th_next(m, th, c->t);
  } else {
    CHECK_EQ(c->state, CTX_WAIT);
    th_next(m, th, c->t);
  }
  kick(m, (uint32_t)core);
  if (m->progress && (m->st.blocks & 0xFFFF) == 0) m->progress(m->progress_ctx, t);
}

/* ---- the door ---- */

static void t_compute(void *ctx, uint64_t cycles) {
  struct mctx *c = ctx;
  c->t += cycles;
  c->slots += cycles;
  c->m->st.computes++;
  cost_charge(c, COST_SLOTS, cycles);
}

/* What a load and a store pay first: one issue slot at the context's time. */
static struct machine *door_issue(struct mctx *c, uint32_t size, unsigned cls) {
  CHECK(!c->parking); /* a parking worker returns without another access */
  CHECK_GT(size, 0);
  CHECK_LT(cls, MEM_CLASS_MAX);
  c->t++;
  c->slots++;
  cost_charge(c, COST_SLOTS, 1);
  return c->m;
}

static void t_load(void *ctx, uint64_t addr, uint32_t size, unsigned cls) {
  struct mctx *c = ctx;
  struct machine *m = door_issue(c, size, cls);
  m->st.loads++;
  struct cache *l1 = m->core[c->info.core].l1;
  uint64_t line = addr >> SIM_LINE_LG2, end = (addr + size - 1) >> SIM_LINE_LG2;
  uint32_t pending = 0;
  for (; line <= end; line++) {
    if (l1) {
      m->st.l1_accesses++;
      if (cache_use(l1, line) != CACHE_NONE) {
        m->st.l1_hits++;
        continue;
      }
    }
    engine_at(m->eng, c->t, ev_l2_access, c, l2_pack(line, L2_LOAD, cls));
    pending++;
  }
  if (!pending) {
    hist_add(&m->st.load_latency, m->p.l1_latency_cycles);
    cost_charge(c, COST_WAIT, m->p.l1_latency_cycles);
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

static void t_store(void *ctx, uint64_t addr, uint32_t size, unsigned cls) {
  struct mctx *c = ctx;
  struct machine *m = door_issue(c, size, cls);
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
    if (c->acc) cost_store_push(c, cost_tag(c));
    engine_at(m->eng, c->t, ev_l2_access, c, l2_pack(line, whole ? L2_STORE_LINE : L2_STORE, cls));
  }
}

static void ev_wake(void *ctx, uint64_t arg) {
  struct mctx *c = ctx;
  (void)arg;
  ray_ready(c->m, c, engine_now(c->m->eng));
}

/* The ray has nothing to do for `cycles`: it waits like a load that touches
 * no memory (its thread may switch to another ray), and takes no issue slot. */
static void t_wait(void *ctx, uint64_t cycles) {
  struct mctx *c = ctx;
  struct machine *m = c->m;
  CHECK(!c->parking);
  m->st.waits++;
  m->st.wait_cycles += cycles;
  c->state = CTX_WAIT;
  engine_at(m->eng, c->t + cycles, ev_wake, c, 0);
  coro_suspend(c->co);
}

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
static void t_wake(void *ctx, uint32_t id) {
  struct mctx *c = ctx;
  struct machine *m = c->m;
  CHECK(!c->parking);
  CHECK_LT(id, m->nctx);
  struct mctx *o = &m->ctx[id];
  CHECK_EQ(o->state, CTX_PARKED);
  m->st.wakes++;
  struct mthread *th = &m->th[o->thread];
  CHECK_GT(th->parked, 0);
  th->parked--;
  ray_ready(m, o, c->t);
}

static const struct mem_ops timed_ops = {t_load, t_store, t_compute, t_wait, t_park, t_wake};

/* ---- the warming door (sampling's fast-forward) ---- */

/* One access through core's warming port: a load fills the L1 on a miss, a
 * store (write-through, no allocation) only refreshes a line it holds; what
 * the L1 did not hold warms the L2 (a store always reaches it). */
static void warm_access(struct mwarm *w, uint64_t addr, uint32_t size, bool store) {
  struct machine *m = w->m;
  m->warm_slots++;
  struct cache *l1 = m->core[w->core].l1;
  for (uint64_t line = addr >> SIM_LINE_LG2, end = (addr + size - 1) >> SIM_LINE_LG2; line <= end;
       line++) {
    if (l1) {
      if (store) cache_use(l1, line);
      else if (cache_fill(l1, line, false)) continue;
    }
    l2_warm(m->l2, line, store);
  }
}

static void w_load(void *ctx, uint64_t addr, uint32_t size, unsigned cls) {
  (void)cls;
  warm_access(ctx, addr, size, false);
}

static void w_store(void *ctx, uint64_t addr, uint32_t size, unsigned cls) {
  (void)cls;
  warm_access(ctx, addr, size, true);
}

static void w_compute(void *ctx, uint64_t cycles) {
  struct mwarm *w = ctx;
  w->m->warm_slots += cycles;
}

static const struct mem_ops warm_ops = {w_load, w_store, w_compute, NULL, NULL, NULL};

struct mem_port machine_warm_port(struct machine *m, uint32_t core) {
  CHECK_LT(core, m->p.cores);
  struct mem_port p = {&warm_ops, &m->warm[core]};
  return p;
}

uint64_t machine_warm_slots(const struct machine *m) { return m->warm_slots; }

static void n_access(void *ctx, uint64_t addr, uint32_t size, unsigned cls) {
  (void)addr;
  (void)size;
  (void)cls;
  ((struct machine *)ctx)->count_slots++;
}

static void n_compute(void *ctx, uint64_t cycles) {
  ((struct machine *)ctx)->count_slots += cycles;
}

static const struct mem_ops count_ops = {n_access, n_access, n_compute, NULL, NULL, NULL};

struct mem_port machine_count_port(struct machine *m) {
  struct mem_port p = {&count_ops, m};
  return p;
}

uint64_t machine_count_slots(const struct machine *m) { return m->count_slots; }

void machine_probe(const struct machine *m, struct machine_probe *out) {
  const struct mctx *c = m->running;
  out->cycle = c ? c->t : engine_now(m->eng);
  out->issue_slots = m->st.issue_slots + (c ? c->slots : 0);
  const struct l2_stats *l = l2_get_stats(m->l2);
  out->dram_bytes = l->fetch_bytes + l->writeback_bytes;
  out->load_latency_sum = m->st.load_latency.sum;
  out->loads_timed = m->st.load_latency.count;
}

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
  struct l2_client lc = {ev_line_done, NULL, NULL};
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
  for (uint32_t i = 0; i < m->p.cores; i++) kick(m, i);
  engine_run(m->eng);
  /* Everything must be over: every ray returned (none parked with nobody left
   * to wake it), no miss outstanding. */
  for (uint32_t i = 0; i < m->nctx; i++) CHECK_NE(m->ctx[i].state, CTX_PARKED);
  for (uint32_t i = 0; i < m->nctx; i++) CHECK_EQ(m->ctx[i].state, CTX_DONE);
  CHECK(l2_quiet(m->l2));
  CHECK_EQ(m->loads_out, m->loads_back);
  dram_finish(m->dram);
  /* The end: the last event (the last data served), the last block's last
   * cycle (blocks run ahead of the engine). */
  uint64_t end = engine_now(m->eng);
  for (uint32_t t = 0; t < m->nth; t++)
    if (m->th[t].since > end) end = m->th[t].since;
  for (uint32_t t = 0; t < m->nth; t++) {
    CHECK_EQ(m->th[t].state, TH_DONE);
    th_account(m, &m->th[t], end);
  }
  l2_finish(m->l2, end);
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
  if (m->cost_acc) cost_finish(m);
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

/* ---- the machine's numbers (README "Numbers") ----
 * The cores' and threads' counters, then at its slots the L1's, the L2's, the
 * DRAM's and the engine's, each from its own table; env->ctx is the machine. */

static double m_ratio(double a, double b) { return b > 0 ? a / b : 0.0; }
#define M_ST(st) ((const struct machine_stats *)(st))
#define M_OF(env) ((const struct machine *)(env)->ctx)
static double m_seconds(const void *st, const struct stats_env *env) {
  return (double)M_ST(st)->cycles / (M_OF(env)->p.clock_ghz * 1e9);
}
static double m_core_utilization(const void *st, const struct stats_env *env) {
  return m_ratio((double)M_ST(st)->issue_slots,
                 (double)M_OF(env)->p.cores * (double)M_ST(st)->cycles);
}
static double m_thread_cycles(const void *st) {
  return (double)M_ST(st)->threads * (double)M_ST(st)->cycles;
}
static double m_busy_fraction(const void *st, const struct stats_env *env) {
  (void)env;
  return m_ratio((double)M_ST(st)->thread_busy_cycles, m_thread_cycles(st));
}
static double m_idle_fraction(const void *st, const struct stats_env *env) {
  (void)env;
  const struct machine_stats *s = st;
  return m_ratio((double)(s->thread_wait_cycles + s->thread_parked_cycles + s->thread_done_cycles),
                 m_thread_cycles(st));
}
static double m_wait_fraction(const void *st, const struct stats_env *env) {
  (void)env;
  return m_ratio((double)M_ST(st)->thread_wait_cycles, m_thread_cycles(st));
}
static double m_parked_fraction(const void *st, const struct stats_env *env) {
  (void)env;
  return m_ratio((double)M_ST(st)->thread_parked_cycles, m_thread_cycles(st));
}
static double m_done_fraction(const void *st, const struct stats_env *env) {
  (void)env;
  return m_ratio((double)M_ST(st)->thread_done_cycles, m_thread_cycles(st));
}
static double m_slots_per_blocking_load(const void *st, const struct stats_env *env) {
  (void)env;
  return m_ratio((double)M_ST(st)->issue_slots, (double)M_ST(st)->blocking_loads);
}
static double m_load_latency_mean(const void *st, const struct stats_env *env) {
  (void)env;
  return hist_mean(&M_ST(st)->load_latency);
}
static uint64_t m_load_latency_p95(const void *st, const struct stats_env *env) {
  (void)env;
  return hist_quantile(&M_ST(st)->load_latency, 0.95);
}

enum { M_SLOT_L1 = 1, M_SLOT_L2, M_SLOT_DRAM, M_SLOT_ENGINE };

#define MS struct machine_stats
static const struct stats_desc machine_desc[] = {
    STATS_FIELD(MS, cycles, "cycles", "cycles", "the run: last ray done and the DRAM drained"),
    STATS_F64(MS, cycles, m_seconds, "seconds", "seconds", "the run at clock_ghz"),
    STATS_SLOT(MACHINE_STATS_SLOT_RUN),
    STATS_FIELD(MS, contexts, "ray_contexts", "count", "ray contexts: cores x threads x rays"),
    STATS_FIELD(MS, threads, "threads", "count", "hardware threads: cores x threads_per_core"),
    STATS_FIELD(MS, issue_slots, "issue_slots", "cycles",
                "issue slots used (compute, loads, stores)"),
    STATS_F64(MS, issue_slots, m_core_utilization, "core_utilization", "fraction",
              "issue slots used / cores x cycles"),
    STATS_F64(MS, thread_busy_cycles, m_busy_fraction, "thread_busy_fraction", "fraction",
              "thread-cycles with a ray ready, running or being switched to"),
    STATS_F64(MS, thread_done_cycles, m_idle_fraction, "thread_idle_fraction", "fraction",
              "thread-cycles with no ray ready: waiting, parked or done"),
    STATS_F64(MS, thread_wait_cycles, m_wait_fraction, "thread_wait_fraction", "fraction",
              "thread-cycles with live rays, all waiting on memory (or mem_wait)"),
    STATS_F64(MS, thread_parked_cycles, m_parked_fraction, "thread_parked_fraction", "fraction",
              "thread-cycles with live rays, all parked (no work)"),
    STATS_F64(MS, thread_done_cycles, m_done_fraction, "thread_done_fraction", "fraction",
              "thread-cycles with no work left"),
    STATS_FIELD(MS, ray_switches, "ray_switches", "count",
                "a thread taking another ray than its last"),
    STATS_FIELD(MS, switch_cycles, "ray_switch_cycles", "cycles", "thread cycles paid for them"),
    STATS_FIELD(MS, blocks, "ray_blocks", "count",
                "runs of a ray between waits: issuing until it waits, parks or ends"),
    STATS_FIELD(MS, waits, "waits", "count", "mem_wait calls: a worker idle by its own choice"),
    STATS_FIELD(MS, wait_cycles, "wait_cycles", "cycles", "cycles they asked for"),
    STATS_FIELD(MS, parks, "parks", "count", "mem_park calls: a context leaving with no work"),
    STATS_FIELD(MS, wakes, "wakes", "count", "mem_wake calls"),
    STATS_FIELD(MS, loads, "loads", "count", "loads issued"),
    STATS_FIELD(MS, stores, "stores", "count", "stores issued"),
    STATS_FIELD(MS, computes, "computes", "count",
                "compute steps issued (their cycles are in issue_slots)"),
    STATS_FIELD(MS, blocking_loads, "blocking_loads", "count",
                "loads that left the L1 and suspended their ray"),
    STATS_F64(MS, blocking_loads, m_slots_per_blocking_load, "issue_slots_per_blocking_load",
              "cycles", "issue slots / blocking loads"),
    STATS_SLOT(MACHINE_STATS_SLOT_RUN_MISSES),
    STATS_SLOT(M_SLOT_L1),
    STATS_SLOT(M_SLOT_L2),
    STATS_SLOT(M_SLOT_DRAM),
    STATS_F64(MS, load_latency, m_load_latency_mean, "load_latency_mean", "cycles",
              "loads, issue to data (L1 hits too): mean"),
    STATS_U64(MS, load_latency, m_load_latency_p95, "load_latency_p95", "cycles",
              "the same, 95th percentile"),
    STATS_FIELD(MS, load_latency.max, "load_latency_max", "cycles", "the same, most"),
    STATS_SLOT(M_SLOT_ENGINE),
    STATS_FIELD(MS, stacks_max, "coroutine_stacks_max", "count",
                "coroutine stacks alive at once (parked contexts hold none)"),
};
static const struct stats_skip machine_skip[] = {
    STATS_SKIP_BY(MS, l1_accesses, machine_l1_stats_descs),
    STATS_SKIP_BY(MS, l1_hits, machine_l1_stats_descs),
    STATS_SKIP_BY(MS, l2, l2_stats_descs),
    STATS_SKIP_BY(MS, dram, dram_stats_descs),
    STATS_SKIP_BY(MS, events, machine_engine_stats_descs),
};
const struct stats_descs machine_stats_descs = {
    "machine",  machine_desc, STATS_COUNT(machine_desc),
    sizeof(MS), machine_skip, STATS_COUNT(machine_skip)};

/* The L1s' counters, kept by the machine in its own stats (NOTE: fields of
 * struct machine_stats, listed there as skips naming this table). */
static const struct stats_desc l1_desc[] = {
    STATS_FIELD(MS, l1_accesses, "l1_accesses", "count", "loads that looked in an L1"),
    STATS_FIELD(MS, l1_hits, "l1_hits", "count", "those that found their line"),
};
const struct stats_descs machine_l1_stats_descs = {"l1", l1_desc, STATS_COUNT(l1_desc), 0, NULL, 0};

static const struct stats_desc engine_desc[] = {
    STATS_FIELD(MS, events, "events", "count", "events the engine handled"),
};
const struct stats_descs machine_engine_stats_descs = {
    "engine", engine_desc, STATS_COUNT(engine_desc), 0, NULL, 0};

/* The DRAM's share of its peak, for the levels that do not report their own
 * (the channel does: dram_channel_stats_descs). */
static bool m_dram_util_present(const void *st, const struct stats_env *env) {
  (void)st;
  const struct machine_params *p = &M_OF(env)->p;
  return machine_dram_peak_bytes_per_cycle(p) > 0 &&
         machine_fidelity_dram(p->fidelity) != DRAM_MODEL_CHANNEL;
}
static double m_dram_utilization(const void *st, const struct stats_env *env) {
  const struct machine_stats *s = st;
  const double b = (double)(s->dram.read_bytes + s->dram.write_bytes);
  return m_ratio(b, (double)s->cycles) / machine_dram_peak_bytes_per_cycle(&M_OF(env)->p);
}
static const struct stats_desc dram_util_desc[] = {
    {.name = "dram_utilization",
     .unit = "fraction",
     .desc = "DRAM bytes per cycle / the level's peak (banked)",
     .how = STATS_HOW_F64,
     .f64 = m_dram_utilization,
     .present = m_dram_util_present},
};
const struct stats_descs machine_dram_util_stats_descs = {
    "dram", dram_util_desc, STATS_COUNT(dram_util_desc), 0, NULL, 0};
#undef MS

struct m_emit {
  const struct machine *m;
  stats_slot_fn run;
  const void *run_ctx;
};

static void m_slot(const struct stats_env *env, int slot, struct stats_table *t) {
  const struct m_emit *x = env->slot_ctx;
  const struct machine *m = x->m;
  struct stats_env sub = *env;
  switch (slot) {
  case MACHINE_STATS_SLOT_RUN:
  case MACHINE_STATS_SLOT_RUN_MISSES:
    if (!x->run) return;
    sub.slot_ctx = x->run_ctx;
    x->run(&sub, slot, t);
    return;
  case M_SLOT_L1: stats_emit(t, &machine_l1_stats_descs, &m->st, env); return;
  case M_SLOT_L2: stats_emit(t, &l2_stats_descs, &m->st.l2, env); return;
  case M_SLOT_DRAM: stats_emit(t, &dram_stats_descs, &m->st.dram, env); return;
  case DRAM_STATS_SLOT_UTILIZATION:
    stats_emit(t, &machine_dram_util_stats_descs, &m->st, env);
    return;
  case DRAM_STATS_SLOT_LEVEL: dram_report(m->dram, t, m->st.cycles); return;
  case M_SLOT_ENGINE: stats_emit(t, &machine_engine_stats_descs, &m->st, env); return;
  default: CHECK(!"a slot the machine knows");
  }
}

void machine_stats_emit(const struct machine *m, struct stats_table *t,
                        const char *const *class_names, unsigned classes, stats_slot_fn run,
                        const void *run_ctx) {
  const struct m_emit x = {m, run, run_ctx};
  const struct stats_env env = {.cycles = m->st.cycles,
                                .ctx = m,
                                .class_names = class_names,
                                .classes = classes,
                                .slot = m_slot,
                                .slot_ctx = &x};
  stats_emit(t, &machine_stats_descs, &m->st, &env);
}

/* The timeline's columns (enum machine_tl_col), as timeline.csv writes them. */
const struct timeline_col machine_tl_cols[] = {
    {"dram_read_bytes", "bytes",
     "bytes the DRAM delivered in the window (at fidelity channel each transfer spread over its "
     "cycles on the channel; else whole lines at the cycle served)",
     MACHINE_TL_DRAM_READ_BYTES, 1, 2, false, false},
    {"dram_write_bytes", "bytes", "bytes the DRAM wrote in the window (the same way)",
     MACHINE_TL_DRAM_WRITE_BYTES, 1, 2, false, false},
    {"read_%s_bytes", "bytes", "of the bytes read, those of each data class",
     MACHINE_TL_READ_CLASS0, MEM_CLASS_MAX, 2, true, false},
    {"l2_accesses", "count", "accesses that reached the L2", MACHINE_TL_L2_ACCESSES, 1, 0, false,
     false},
    {"l2_misses", "count", "those that missed", MACHINE_TL_L2_MISSES, 1, 0, false, false},
    {"issued_ops", "cycles", "issue slots used, all cores", MACHINE_TL_ISSUED_OPS, 1, 0, false,
     false},
    {"busy_threads", "threads", "mean threads with a ray ready, running or being switched to",
     MACHINE_TL_BUSY_THREAD_CYCLES, 1, 4, false, true},
};
const unsigned machine_tl_col_count = sizeof machine_tl_cols / sizeof machine_tl_cols[0];
