/* The timed machine: cores, threads, ray contexts, L1s, the L2 and its MSHRs,
 * wired to the event engine and the DRAM channel; and the timed backend of the
 * memory door (the ops a running ray context calls).
 *
 * Time flows through four kinds of event: a core's issue slot (it resumes one
 * ray for one block), an access arriving at the L2, a miss reaching the DRAM
 * channel (and a write-back), and data coming back (a line done for a waiting
 * ray, or a fill). Only the issue event resumes a coroutine, so everything
 * else may run in any handler without re-entering the renderer. */
#include "sim/machine.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sim/cache.h"
#include "sim/coro.h"
#include "sim/dram.h"
#include "sim/engine.h"
#include "sim/err.h"

#define NONE UINT32_MAX
#define LINE_BYTES (1u << MACHINE_LG2_LINE)

enum ctx_state { CTX_READY, CTX_WAIT, CTX_DONE };
enum th_state { TH_BUSY, TH_WAIT, TH_DONE };
enum op { OP_LOAD = 0, OP_STORE = 1, OP_STORE_LINE = 2 };

struct mctx {
  struct machine *m;
  struct coro *co;
  struct machine_worker_info info;
  uint32_t thread; /* global thread index */
  uint8_t state;
  uint32_t pending;   /* lines of the current load not yet back */
  uint64_t t;         /* the ray's own clock inside a block */
  uint64_t slots;     /* issue slots of the current block */
  uint64_t wait_from; /* cycle its waiting load left the core */
  uint32_t next;      /* ready FIFO of its thread */
};

struct mthread {
  uint32_t core;
  uint32_t cur;  /* the ray the thread runs or switches to; NONE when idle */
  uint32_t last; /* the ray it ran last */
  uint64_t ready_at;
  uint32_t q_head, q_tail; /* rays ready to run, besides cur */
  uint32_t live;           /* rays not done */
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

/* An access waiting for the L2 (stalled input), or a waiter on a pending line. */
struct req {
  uint64_t line;
  uint32_t ctx; /* NONE: a posted store */
  uint8_t op, cls;
  uint32_t next;
};

struct machine {
  struct machine_params p;
  struct engine *eng;
  struct coro_pool *pool;
  struct dram *dram;
  struct cache *l2;
  uint64_t *bank_free;
  uint32_t *waiters;  /* per L2 slot: head of its waiter list (reqs) */
  uint8_t *miss_cls;  /* per L2 slot: class of the access that missed */
  uint32_t mshr_used;
  struct req *reqs;   /* pool: stalled accesses and waiters */
  uint32_t req_free, req_cap;
  uint32_t stall_head, stall_tail;
  struct mctx *ctx;
  struct mthread *th;
  struct mcore *core;
  uint32_t nctx, nth;
  uint64_t stacks_live, painted_max;
  machine_worker_fn fn;
  void *fn_arg;
  machine_progress_fn progress;
  void *progress_ctx;
  bool ran;
  uint64_t loads_out, loads_back; /* conservation: L2 load requests and answers */
  /* timeline */
  double *tl;
  uint64_t tl_rows, tl_cap, tl_window;
  struct machine_stats st;
};

static const struct mem_ops timed_ops;

/* ---- parameters ---- */

const char *machine_params_problem(const struct machine_params *p) {
  if (!(p->clock_ghz > 0) || !isfinite(p->clock_ghz) || p->clock_ghz > 1000)
    return "clock_ghz: must be above 0 and at most 1000";
  if (p->cores < 1 || p->cores > 4096) return "cores: must be 1 to 4096";
  if (p->threads_per_core < 1 || p->threads_per_core > 256) return "threads_per_core: must be 1 to 256";
  if (p->rays_per_thread < 1 || p->rays_per_thread > 256) return "rays_per_thread: must be 1 to 256";
  if ((uint64_t)p->cores * p->threads_per_core * p->rays_per_thread > (1u << 20))
    return "cores x threads_per_core x rays_per_thread: at most 2^20 ray contexts";
  if (p->l1_size_bytes) {
    struct cache_params c = {p->l1_size_bytes, p->l1_ways, MACHINE_LG2_LINE};
    if (cache_params_problem(&c)) return "l1: size and ways do not make a cache of 64-byte lines";
  }
  struct cache_params c = {p->l2_size_bytes, p->l2_ways, MACHINE_LG2_LINE};
  if (cache_params_problem(&c)) return "l2: size and ways do not make a cache of 64-byte lines";
  if (p->l2_banks < 1 || p->l2_banks > 4096) return "l2.banks: must be 1 to 4096";
  if (p->l2_mshrs < 1 || p->l2_mshrs > (1u << 20)) return "l2.mshrs: must be 1 to 2^20";
  struct dram_params d = {p->dram_latency_cycles, p->dram_bytes_per_cycle, p->dram_queue_depth};
  if (dram_params_problem(&d)) return "dram: bad latency, bandwidth or queue depth";
  if (p->timeline_window_cycles < 1) return "timeline.window: must be at least 1";
  return NULL;
}

/* ---- timeline ---- */

static double *tl_row(struct machine *m, uint64_t w) {
  while (w >= MACHINE_TL_MAX_ROWS) {
    /* Coarsen: windows double, pairs of rows merge. */
    uint64_t half = (m->tl_rows + 1) / 2;
    for (uint64_t i = 0; i < half; i++)
      for (unsigned c = 0; c < MACHINE_TL_COLS; c++) {
        double b = 2 * i + 1 < m->tl_rows ? m->tl[(2 * i + 1) * MACHINE_TL_COLS + c] : 0.0;
        m->tl[i * MACHINE_TL_COLS + c] = m->tl[2 * i * MACHINE_TL_COLS + c] + b;
      }
    if (m->tl_rows > half) /* (an empty timeline has no array yet) */
      memset(m->tl + half * MACHINE_TL_COLS, 0,
             (m->tl_rows - half) * MACHINE_TL_COLS * sizeof *m->tl);
    m->tl_rows = half;
    m->tl_window *= 2;
    w /= 2;
  }
  if (w >= m->tl_cap) {
    uint64_t cap = m->tl_cap ? m->tl_cap : 256;
    while (cap <= w) cap *= 2;
    if (cap > MACHINE_TL_MAX_ROWS) cap = MACHINE_TL_MAX_ROWS;
    m->tl = xrealloc(m->tl, cap * MACHINE_TL_COLS * sizeof *m->tl);
    memset(m->tl + m->tl_cap * MACHINE_TL_COLS, 0,
           (cap - m->tl_cap) * MACHINE_TL_COLS * sizeof *m->tl);
    m->tl_cap = cap;
  }
  if (w >= m->tl_rows) m->tl_rows = w + 1;
  return m->tl + w * MACHINE_TL_COLS;
}

/* Add amount at cycle t. */
static void tl_point(struct machine *m, unsigned col, uint64_t t, double amount) {
  tl_row(m, t / m->tl_window)[col] += amount;
}

/* Spread amount evenly over [a, b) ticks (2^DRAM_TICK_BITS a cycle). */
static void tl_span_ticks(struct machine *m, unsigned col, uint64_t a, uint64_t b, double amount) {
  if (b <= a) {
    tl_point(m, col, a >> DRAM_TICK_BITS, amount);
    return;
  }
  const double per_tick = amount / (double)(b - a);
  /* The row of the span's last window first: any coarsening happens now. */
  tl_row(m, ((b - 1) >> DRAM_TICK_BITS) / m->tl_window);
  const uint64_t win = m->tl_window << DRAM_TICK_BITS;
  for (uint64_t x = a; x < b;) {
    uint64_t end = (x / win + 1) * win;
    if (end > b) end = b;
    tl_row(m, x / win)[col] += per_tick * (double)(end - x);
    x = end;
  }
}

static void tl_span(struct machine *m, unsigned col, uint64_t a, uint64_t b, double per_cycle) {
  if (b <= a) return;
  tl_span_ticks(m, col, a << DRAM_TICK_BITS, b << DRAM_TICK_BITS, per_cycle * (double)(b - a));
}

/* ---- threads ---- */

/* Count thread time from th->since to t in its current state. */
static void th_account(struct machine *m, struct mthread *th, uint64_t t) {
  uint64_t d = t - th->since;
  switch (th->state) {
  case TH_BUSY:
    m->st.thread_busy_cycles += d;
    tl_span(m, MACHINE_TL_BUSY_THREAD_CYCLES, th->since, t, 1.0);
    break;
  case TH_WAIT: m->st.thread_wait_cycles += d; break;
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

static bool th_issuable_at(const struct machine *m, const struct mthread *th, uint64_t *at) {
  if (th->cur == NONE || m->ctx[th->cur].state != CTX_READY) return false;
  *at = th->ready_at;
  return true;
}

/* Thread th takes ray c (ready) at cycle t: free if it ran c last. */
static void th_take(struct machine *m, struct mthread *th, uint32_t c, uint64_t t) {
  th->cur = c;
  th->ready_at = t;
  if (th->last != NONE && th->last != c) {
    th->ready_at += m->p.cost_ray_switch_cycles;
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
  th_set(m, th, th->live ? TH_WAIT : TH_DONE, t);
}

/* Ray c's data is back at cycle t. */
static void ray_ready(struct machine *m, struct mctx *c, uint64_t t) {
  c->state = CTX_READY;
  struct mthread *th = &m->th[c->thread];
  uint32_t id = (uint32_t)(c - m->ctx);
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

/* ---- L2 ---- */

static uint32_t req_new(struct machine *m) {
  if (m->req_free == NONE) {
    uint32_t old = m->req_cap;
    m->req_cap = old ? 2 * old : 1024;
    m->reqs = xrealloc(m->reqs, (uint64_t)m->req_cap * sizeof *m->reqs);
    for (uint32_t i = old; i < m->req_cap; i++) m->reqs[i].next = i + 1 < m->req_cap ? i + 1 : NONE;
    m->req_free = old;
  }
  uint32_t r = m->req_free;
  m->req_free = m->reqs[r].next;
  m->reqs[r].next = NONE;
  return r;
}

static void req_release(struct machine *m, uint32_t r) {
  m->reqs[r].next = m->req_free;
  m->req_free = r;
}

static void ev_line_done(void *ctx, uint64_t line);
static void ev_dram_read(void *ctx, uint64_t slot);
static void ev_dram_write(void *ctx, uint64_t line);

/* A line of ray c's load is back at cycle t (fills c's L1). */
static void line_done(struct machine *m, struct mctx *c, uint64_t line, uint64_t t) {
  struct cache *l1 = m->core[c->info.core].l1;
  if (l1) {
    uint32_t s = cache_find(l1, line);
    if (s == CACHE_NONE) cache_install(l1, cache_victim(l1, line), line, false, false);
    else cache_touch(l1, s);
  }
  m->loads_back++;
  CHECK_GT(c->pending, 0);
  if (--c->pending == 0) {
    hist_add(&m->st.load_latency, t - c->wait_from);
    ray_ready(m, c, t);
  }
}

static void evict(struct machine *m, uint32_t slot, uint64_t when) {
  if (!cache_valid(m->l2, slot) || !cache_dirty(m->l2, slot)) return;
  m->st.l2_writeback_bytes += LINE_BYTES;
  engine_at(m->eng, when, ev_dram_write, m, cache_line(m->l2, slot));
}

/* Try one access at cycle t; false if it must wait for a fill (MSHRs full or
 * every way of its set pending). */
static bool l2_try(struct machine *m, const struct req *r, uint64_t t) {
  const uint64_t line = r->line;
  uint32_t slot = cache_find(m->l2, line);
  bool hit = slot != CACHE_NONE;
  uint32_t victim = CACHE_NONE;
  if (!hit) {
    if (r->op != OP_STORE_LINE && m->mshr_used >= m->p.l2_mshrs) return false;
    victim = cache_victim(m->l2, line);
    if (victim == CACHE_NONE) return false;
  }
  uint64_t *bf = &m->bank_free[line % m->p.l2_banks];
  uint64_t start = t > *bf ? t : *bf;
  m->st.l2_bank_wait_cycles += start - t;
  *bf = start + 1;
  uint64_t ready = start + m->p.l2_latency_cycles;
  m->st.l2_accesses++;
  m->st.l2_accesses_by_class[r->cls]++;
  tl_point(m, MACHINE_TL_L2_ACCESSES, start, 1.0);
  struct mctx *c = r->ctx == NONE ? NULL : &m->ctx[r->ctx];
  if (hit) {
    cache_touch(m->l2, slot);
    if (r->op != OP_LOAD) cache_set_dirty(m->l2, slot);
    if (cache_pending(m->l2, slot)) {
      m->st.l2_mshr_merges++;
      if (c) {
        uint32_t w = req_new(m);
        m->reqs[w] = *r;
        m->reqs[w].next = m->waiters[slot];
        m->waiters[slot] = w;
      }
    } else {
      m->st.l2_hits++;
      if (c) engine_at(m->eng, ready, ev_line_done, c, line);
    }
    return true;
  }
  evict(m, victim, ready);
  if (r->op == OP_STORE_LINE) {
    /* Nothing of the old line survives: allocate without a fetch. */
    m->st.l2_whole_line_allocs++;
    cache_install(m->l2, victim, line, true, false);
    return true;
  }
  cache_install(m->l2, victim, line, r->op != OP_LOAD, true);
  m->mshr_used++;
  m->st.l2_misses++;
  m->st.l2_fetch_bytes += LINE_BYTES;
  m->st.fetch_bytes_by_class[r->cls] += LINE_BYTES;
  tl_point(m, MACHINE_TL_L2_MISSES, start, 1.0);
  m->miss_cls[victim] = r->cls;
  m->waiters[victim] = NONE;
  if (c) {
    uint32_t w = req_new(m);
    m->reqs[w] = *r;
    m->reqs[w].next = NONE;
    m->waiters[victim] = w;
  }
  engine_at(m->eng, ready, ev_dram_read, m, victim);
  return true;
}

static void stall_push(struct machine *m, const struct req *r) {
  uint32_t i = req_new(m);
  m->reqs[i] = *r;
  m->reqs[i].next = NONE;
  if (m->stall_tail == NONE) m->stall_head = i;
  else m->reqs[m->stall_tail].next = i;
  m->stall_tail = i;
  m->st.l2_stalls++;
}

/* Retry stalled accesses, oldest first, until one must still wait. */
static void stall_retry(struct machine *m, uint64_t t) {
  while (m->stall_head != NONE) {
    uint32_t i = m->stall_head;
    struct req r = m->reqs[i];
    if (!l2_try(m, &r, t)) return;
    m->stall_head = r.next;
    if (m->stall_head == NONE) m->stall_tail = NONE;
    req_release(m, i);
  }
}

static void ev_l2_access(void *ctx, uint64_t arg) {
  struct mctx *c = ctx;
  struct machine *m = c->m;
  struct req r;
  r.line = arg >> 8;
  r.op = (uint8_t)((arg >> 4) & 3);
  r.cls = (uint8_t)(arg & 15);
  r.ctx = r.op == OP_LOAD ? (uint32_t)(c - m->ctx) : NONE;
  r.next = NONE;
  /* In order: while anything is stalled, later accesses queue behind it. */
  if (m->stall_head != NONE || !l2_try(m, &r, engine_now(m->eng))) stall_push(m, &r);
}

static void dram_account(struct machine *m, const struct dram_timing *tm, unsigned col, int cls) {
  hist_add(&m->st.queue_delay, tm->wait_cycles);
  tl_span_ticks(m, col, tm->start_ticks, tm->end_ticks, LINE_BYTES);
  if (cls >= 0)
    tl_span_ticks(m, MACHINE_TL_READ_CLASS0 + (unsigned)cls, tm->start_ticks, tm->end_ticks,
                  LINE_BYTES);
}

static void ev_fill(void *ctx, uint64_t slot);

static void ev_dram_read(void *ctx, uint64_t slot) {
  struct machine *m = ctx;
  struct dram_timing tm;
  dram_submit(m->dram, engine_now(m->eng), cache_line(m->l2, (uint32_t)slot) << MACHINE_LG2_LINE,
              LINE_BYTES, false, &tm);
  dram_account(m, &tm, MACHINE_TL_DRAM_READ_BYTES, m->miss_cls[slot]);
  engine_at(m->eng, tm.done_cycle, ev_fill, m, slot);
}

static void ev_dram_write(void *ctx, uint64_t line) {
  struct machine *m = ctx;
  struct dram_timing tm;
  dram_submit(m->dram, engine_now(m->eng), line << MACHINE_LG2_LINE, LINE_BYTES, true, &tm);
  dram_account(m, &tm, MACHINE_TL_DRAM_WRITE_BYTES, -1);
}

static void ev_fill(void *ctx, uint64_t slot) {
  struct machine *m = ctx;
  const uint64_t t = engine_now(m->eng);
  const uint32_t s = (uint32_t)slot;
  cache_set_pending(m->l2, s, false);
  m->mshr_used--;
  uint32_t w = m->waiters[s];
  m->waiters[s] = NONE;
  /* Waiters were pushed newest first: answer them oldest first. */
  uint32_t prev = NONE;
  while (w != NONE) {
    uint32_t n = m->reqs[w].next;
    m->reqs[w].next = prev;
    prev = w;
    w = n;
  }
  for (w = prev; w != NONE;) {
    uint32_t n = m->reqs[w].next;
    line_done(m, &m->ctx[m->reqs[w].ctx], m->reqs[w].line, t);
    req_release(m, w);
    w = n;
  }
  stall_retry(m, t);
}

static void ev_line_done(void *ctx, uint64_t line) {
  struct mctx *c = ctx;
  line_done(c->m, c, line, engine_now(c->m->eng));
}

/* ---- cores ---- */

static void ev_issue(void *ctx, uint64_t core);

/* Make sure core has an issue event at the first cycle one of its threads can
 * issue (stale events are recognised by their cycle and ignored). */
static void kick(struct machine *m, uint32_t core) {
  struct mcore *k = &m->core[core];
  const uint32_t T = m->p.threads_per_core;
  uint64_t best = UINT64_MAX, at;
  for (uint32_t i = 0; i < T; i++)
    if (th_issuable_at(m, &m->th[core * T + i], &at) && at < best) best = at;
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
    uint32_t j = (k->rr + i) % T;
    uint64_t at;
    if (th_issuable_at(m, &m->th[core * T + j], &at) && at <= t) pick = j;
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
  coro_resume(c->co);
  m->st.blocks++;
  k->port_free = t + c->slots;
  m->st.issue_slots += c->slots;
  tl_span(m, MACHINE_TL_ISSUED_OPS, t, t + c->slots, 1.0);
  if (coro_finished(c->co)) {
    c->state = CTX_DONE;
    if (m->painted_max < coro_stack_used(c->co)) m->painted_max = coro_stack_used(c->co);
    coro_destroy(c->co);
    c->co = NULL;
    m->stacks_live--;
    th->live--;
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
}

/* What a load and a store pay first: one issue slot at the context's time. */
static struct machine *door_issue(struct mctx *c, uint32_t size, unsigned cls) {
  CHECK_GT(size, 0);
  CHECK_LT(cls, MEM_CLASS_MAX);
  c->t++;
  c->slots++;
  return c->m;
}

static void t_load(void *ctx, uint64_t addr, uint32_t size, unsigned cls) {
  struct mctx *c = ctx;
  struct machine *m = door_issue(c, size, cls);
  m->st.loads++;
  struct cache *l1 = m->core[c->info.core].l1;
  uint64_t line = addr >> MACHINE_LG2_LINE, end = (addr + size - 1) >> MACHINE_LG2_LINE;
  uint32_t pending = 0;
  for (; line <= end; line++) {
    if (l1) {
      m->st.l1_accesses++;
      uint32_t s = cache_find(l1, line);
      if (s != CACHE_NONE) {
        cache_touch(l1, s);
        m->st.l1_hits++;
        continue;
      }
    }
    engine_at(m->eng, c->t, ev_l2_access, c, line << 8 | (uint64_t)OP_LOAD << 4 | cls);
    pending++;
  }
  if (!pending) {
    hist_add(&m->st.load_latency, m->p.l1_latency_cycles);
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
  const uint64_t last = addr + size - 1, lmask = LINE_BYTES - 1;
  uint64_t line = addr >> MACHINE_LG2_LINE, end = last >> MACHINE_LG2_LINE;
  const uint64_t first_whole = (addr & lmask) ? line + 1 : line;
  const bool last_whole = (last & lmask) == lmask;
  for (; line <= end; line++) {
    if (l1) {
      /* Write-through, no allocation: a line the L1 holds is updated. */
      uint32_t s = cache_find(l1, line);
      if (s != CACHE_NONE) cache_touch(l1, s);
    }
    bool whole = line >= first_whole && (line < end || last_whole);
    uint64_t op = whole ? OP_STORE_LINE : OP_STORE;
    engine_at(m->eng, c->t, ev_l2_access, c, line << 8 | op << 4 | cls);
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
  m->st.waits++;
  m->st.wait_cycles += cycles;
  c->state = CTX_WAIT;
  engine_at(m->eng, c->t + cycles, ev_wake, c, 0);
  coro_suspend(c->co);
}

static const struct mem_ops timed_ops = {t_load, t_store, t_compute, t_wait};

/* ---- machine ---- */

static struct machine *create(const struct machine_params *p, uint64_t stack_bytes, bool paint) {
  CHECK(machine_params_problem(p) == NULL);
  struct machine *m = xcalloc(1, sizeof *m);
  m->p = *p;
  m->eng = engine_create();
  m->pool = coro_pool_create(stack_bytes ? stack_bytes : coro_default_stack_bytes(), paint);
  struct dram_params dp = {p->dram_latency_cycles, p->dram_bytes_per_cycle, p->dram_queue_depth};
  m->dram = dram_create(&dp);
  struct cache_params l2 = {p->l2_size_bytes, p->l2_ways, MACHINE_LG2_LINE};
  m->l2 = cache_create(&l2);
  uint64_t lines = cache_lines(m->l2);
  m->waiters = xmalloc(lines * sizeof *m->waiters);
  m->miss_cls = xcalloc(lines, 1);
  m->bank_free = xcalloc(p->l2_banks, sizeof *m->bank_free);
  m->req_free = NONE;
  m->stall_head = m->stall_tail = NONE;
  m->nth = p->cores * p->threads_per_core;
  m->nctx = m->nth * p->rays_per_thread;
  m->core = xcalloc(p->cores, sizeof *m->core);
  m->th = xcalloc(m->nth, sizeof *m->th);
  m->ctx = xcalloc(m->nctx, sizeof *m->ctx);
  for (uint32_t i = 0; i < p->cores; i++) {
    m->core[i].rr = p->threads_per_core - 1;
    if (p->l1_size_bytes) {
      struct cache_params l1 = {p->l1_size_bytes, p->l1_ways, MACHINE_LG2_LINE};
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
  m->tl_window = p->timeline_window_cycles;
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
  for (uint32_t i = 0; i < m->p.cores; i++) cache_destroy(m->core[i].l1);
  free(m->core);
  free(m->th);
  free(m->ctx);
  free(m->reqs);
  free(m->bank_free);
  free(m->miss_cls);
  free(m->waiters);
  free(m->tl);
  cache_destroy(m->l2);
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
  /* Everything must be over: every ray returned, no miss outstanding. */
  for (uint32_t i = 0; i < m->nctx; i++) CHECK_EQ(m->ctx[i].state, CTX_DONE);
  CHECK_EQ(m->mshr_used, 0);
  CHECK_EQ(m->stall_head, NONE);
  CHECK_EQ(m->loads_out, m->loads_back);
  dram_finish(m->dram);
  const struct dram_stats *ds = dram_get_stats(m->dram);
  /* The end: the last event, the last block's last cycle (blocks run ahead
   * of the engine), the channel drained. */
  uint64_t end = engine_now(m->eng);
  uint64_t drained = dram_ticks_to_cycles_ceil(ds->last_end_ticks);
  if (drained > end) end = drained;
  for (uint32_t t = 0; t < m->nth; t++)
    if (m->th[t].since > end) end = m->th[t].since;
  for (uint32_t t = 0; t < m->nth; t++) {
    CHECK_EQ(m->th[t].state, TH_DONE);
    th_account(m, &m->th[t], end);
  }
  struct machine_stats *st = &m->st;
  st->cycles = end;
  st->dram_reads = ds->reads;
  st->dram_writes = ds->writes;
  st->dram_read_bytes = ds->read_bytes;
  st->dram_write_bytes = ds->write_bytes;
  st->dram_busy_ticks = ds->busy_ticks;
  st->dram_wait_ticks_sum = ds->wait_ticks_sum;
  st->dram_fifo_wait_cycles_sum = ds->fifo_wait_cycles_sum;
  st->dram_fifo_area = ds->fifo_area;
  st->dram_fifo_max = ds->fifo_max;
  st->events = engine_events(m->eng);
  /* Conservation: bytes asked of DRAM are the bytes it moved. */
  CHECK_EQ(st->dram_read_bytes, st->l2_fetch_bytes);
  CHECK_EQ(st->dram_write_bytes, st->l2_writeback_bytes);
  CHECK_EQ(st->thread_busy_cycles + st->thread_wait_cycles + st->thread_done_cycles,
           (uint64_t)m->nth * end);
  /* The timeline covers the whole run. */
  if (end > 0) tl_row(m, (end - 1) / m->tl_window);
}

const struct machine_stats *machine_get_stats(const struct machine *m) { return &m->st; }
uint64_t machine_timeline_window(const struct machine *m) { return m->tl_window; }
uint64_t machine_timeline_rows(const struct machine *m) { return m->tl_rows; }
const double *machine_timeline_row(const struct machine *m, uint64_t i) {
  CHECK_LT(i, m->tl_rows);
  return m->tl + i * MACHINE_TL_COLS;
}
