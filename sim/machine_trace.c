/* The trace layer (machine_trace_enable): what each traced hardware thread
 * does over time, as slices, and the memory's occupancy as counters. The
 * machine's traced instances call in where a thread's state changes; the
 * L2's stall hook says which loads queue at its input and why. A thread's
 * wait is named, at each cycle, by the first that holds: a ray's load is
 * queued at the L2's input (the stall's reason: MSHRs, a busy set, the write
 * buffer, the DRAM's back-pressure); a ray waits on a load (in the L2 or the
 * DRAM); every waiting ray is in mem_wait. Nothing here changes the run. */
#include "sim/machine_trace.h"

#include <math.h>
#include <stdlib.h>

#include "sim/derived.h"
#include "sim/dram.h"
#include "sim/engine.h"
#include "sim/err.h"
#include "sim/l2.h"
#include "sim/machine_state.h"

const char *const machine_trace_kind_names[MACHINE_TRACE_KINDS] = {
    "run",
    "switch",
    "ready",
    "wait: load",
    "wait: L2 MSHRs full",
    "wait: L2 set busy",
    "wait: L2 write buffer full",
    "wait: DRAM back-pressure",
    "wait: mem_wait",
    "parked",
    "done",
};

const char *const mtrace_counter_names[MTRACE_COUNTERS][2] = {
    {"DRAM read", "bytes/cycle"},       {"DRAM write", "bytes/cycle"},
    {"DRAM requests", "in flight"},     {"L2 MSHRs", "in use"},
    {"L2 input", "stalled accesses"},   {"L2 misses", "held by the DRAM"},
    {"L2 write buffer", "lines taken"}, {"power: chip and DRAM", "W"},
};

/* The wait kind of an L2 stall reason (enum l2_stall). */
static uint8_t stall_kind(int reason) {
  static const uint8_t k[L2_STALL_COUNT] = {MACHINE_TRACE_WAIT_MSHR, MACHINE_TRACE_WAIT_SET,
                                            MACHINE_TRACE_WAIT_WBUF, MACHINE_TRACE_WAIT_DRAM};
  return k[reason];
}

static bool is_wait(uint8_t kind) {
  return kind >= MACHINE_TRACE_WAIT_LOAD && kind <= MACHINE_TRACE_WAIT_MEMWAIT;
}

/* ---- events ---- */

static struct mtrace_ev *ev_push(struct mtrace *tr) {
  CHECK_LT(tr->n, tr->p.max_events);
  if (tr->n == tr->cap) {
    tr->cap = tr->cap ? 2 * tr->cap : 4096;
    if (tr->cap > tr->p.max_events) tr->cap = tr->p.max_events;
    tr->ev = xrealloc(tr->ev, tr->cap * sizeof *tr->ev);
  }
  return &tr->ev[tr->n++];
}

/* Thread th's slice of kind over [a, b), cut to the window. */
static void put_slice(struct mtrace *tr, uint32_t th, uint8_t kind, uint64_t a, uint64_t b) {
  if (a < tr->p.from_cycle) a = tr->p.from_cycle;
  if (b > tr->end) b = tr->end;
  if (a < b) *ev_push(tr) = (struct mtrace_ev){a, {.dur = b - a}, th, kind};
}

static void put_counter(struct mtrace *tr, unsigned k, uint64_t t, double v) {
  if (tr->last_value[k] == v) return; /* a step track: the same value holds */
  tr->last_value[k] = v;
  if (tr->n >= tr->limit) return; /* past the cut: the reserve is the threads' */
  *ev_push(tr) = (struct mtrace_ev){t, {.value = v}, k, MTRACE_COUNTER};
}

/* A switch of thread th that ended before cycle t: the thread has been
 * ready since. */
static void settle(struct mtrace *tr, uint32_t th, uint64_t t) {
  struct mtrack *k = &tr->th[th];
  if (k->kind != MACHINE_TRACE_SWITCH || t <= k->sw_end) return;
  put_slice(tr, th, MACHINE_TRACE_SWITCH, k->from, k->sw_end);
  k->from = k->sw_end;
  k->kind = MACHINE_TRACE_READY;
}

/* max_events less the reserve is reached at the engine's cycle: the window
 * ends there, each thread's slice up to it kept (the reserve: two events a
 * thread), nothing after. */
static void cap_reached(struct machine *m) {
  struct mtrace *tr = m->trace;
  const uint64_t now = engine_now(m->eng);
  tr->capped = true;
  if (now < tr->end) tr->end = now > tr->p.from_cycle ? now : tr->p.from_cycle;
  for (uint32_t i = 0; i < tr->nth; i++) {
    struct mtrack *k = &tr->th[i];
    settle(tr, i, tr->end);
    put_slice(tr, i, k->kind, k->from, tr->end);
  }
  tr->next_sample = UINT64_MAX;
}

/* Thread th's state becomes kind at cycle t. A cycle before the slice's
 * start (its last block ran ahead of the engine) renames that slice. */
static void mark(struct machine *m, uint32_t th, uint8_t kind, uint64_t t) {
  struct mtrace *tr = m->trace;
  if (tr->capped) return;
  struct mtrack *k = &tr->th[th];
  settle(tr, th, t);
  if (k->kind == kind) return;
  if (t > k->from) {
    put_slice(tr, th, k->kind, k->from, t);
    k->from = t;
  }
  k->kind = kind;
  if (tr->n >= tr->limit) cap_reached(m);
}

/* ---- counters ---- */

/* The DRAM's bytes served a cycle and the power (the run's energy, as the
 * timeline's columns price it, over the seconds) from the previous sample to
 * cycle t, at the previous sample's cycle; t becomes the previous sample. */
static void put_bandwidth(struct machine *m, uint64_t t) {
  struct mtrace *tr = m->trace;
  const struct dram_stats *d = dram_get_stats(m->dram);
  const uint64_t rd = d->read_latency.count * SIM_LINE_BYTES;
  const uint64_t wr = d->write_latency.count * SIM_LINE_BYTES;
  const double energy = machine_energy_j(m, t, m->st.issue_slots);
  if (tr->sampled && t > tr->last_t) {
    const double dt = (double)(t - tr->last_t);
    put_counter(tr, MTRACE_DRAM_READ, tr->last_t, (double)(rd - tr->last_read) / dt);
    put_counter(tr, MTRACE_DRAM_WRITE, tr->last_t, (double)(wr - tr->last_write) / dt);
    put_counter(tr, MTRACE_POWER, tr->last_t,
                (energy - tr->last_energy_j) / derived_seconds(dt, m->p.clock_ghz));
  }
  tr->sampled = true;
  tr->last_t = t;
  tr->last_read = rd;
  tr->last_write = wr;
  tr->last_energy_j = energy;
}

/* What the L2 and the DRAM hold at cycle t (the engine's). */
static void put_occupancy(struct machine *m, uint64_t t) {
  struct mtrace *tr = m->trace;
  struct l2_occupancy o;
  l2_occupancy(m->l2, &o);
  put_counter(tr, MTRACE_DRAM_FLIGHT, t, (double)dram_in_flight(m->dram));
  put_counter(tr, MTRACE_L2_MSHRS, t, o.mshrs);
  put_counter(tr, MTRACE_L2_STALLED, t, o.stalled);
  put_counter(tr, MTRACE_L2_HELD, t, o.misses_held);
  put_counter(tr, MTRACE_L2_WBUF, t, o.write_buffer);
}

static void sample(struct machine *m, uint64_t t) {
  struct mtrace *tr = m->trace;
  if (t < tr->p.from_cycle) {
    tr->next_sample = tr->p.from_cycle;
    return;
  }
  if (t >= tr->end) {
    tr->next_sample = UINT64_MAX;
    return;
  }
  put_bandwidth(m, t);
  put_occupancy(m, t);
  const uint64_t P = tr->p.counter_period_cycles;
  tr->next_sample = t / P * P + P;
}

void trace_tick(struct machine *m, uint64_t t) {
  if (t >= m->trace->next_sample) sample(m, t);
}

/* ---- threads ---- */

/* What idle thread th waits on now (the file's first comment). */
static uint8_t wait_kind(const struct machine *m, uint32_t th) {
  const struct mtrace *tr = m->trace;
  if (tr->th[th].stalled_rays && tr->l2_reason >= 0) return stall_kind(tr->l2_reason);
  const uint32_t R = m->p.rays_per_thread;
  for (uint32_t r = 0; r < R; r++) {
    const struct mctx *c = &m->ctx[th * R + r];
    if (c->state == CTX_WAIT && c->pending) return MACHINE_TRACE_WAIT_LOAD;
  }
  return MACHINE_TRACE_WAIT_MEMWAIT;
}

void trace_take(struct machine *m, uint32_t th, uint64_t t, bool switched) {
  if (th >= m->trace->nth) return;
  switched = switched && m->p.cost_ray_switch_cycles > 0;
  mark(m, th, switched ? MACHINE_TRACE_SWITCH : MACHINE_TRACE_READY, t);
  if (switched) m->trace->th[th].sw_end = t + m->p.cost_ray_switch_cycles;
}

void trace_idle(struct machine *m, uint32_t th, uint64_t t) {
  if (th >= m->trace->nth) return;
  const uint8_t s = m->th[th].state;
  mark(m, th,
       s == TH_DONE     ? MACHINE_TRACE_DONE
       : s == TH_PARKED ? MACHINE_TRACE_PARKED
                        : wait_kind(m, th),
       t);
}

void trace_issue(struct machine *m, uint32_t th, uint64_t t) {
  trace_tick(m, t);
  if (th < m->trace->nth) mark(m, th, MACHINE_TRACE_RUN, t);
}

/* Name again, at the engine's cycle, the wait of thread th if it waits. */
static void rename_wait(struct machine *m, uint32_t th) {
  if (is_wait(m->trace->th[th].kind)) mark(m, th, wait_kind(m, th), engine_now(m->eng));
}

void trace_l2_stall(void *ctx, void *waiter, int what) {
  struct machine *m = ctx;
  struct mtrace *tr = m->trace;
  if (!waiter) {
    tr->l2_reason = what;
    for (uint32_t i = 0; i < tr->nth; i++)
      if (tr->th[i].stalled_rays) rename_wait(m, i);
    return;
  }
  const struct mctx *c = waiter;
  const uint32_t id = c->info.id;
  if (id >= tr->nctx) return;
  const uint32_t before = tr->stalled[id];
  tr->stalled[id] = (uint32_t)((int64_t)before + what);
  if ((before == 0) == (tr->stalled[id] == 0)) return;
  tr->th[c->thread].stalled_rays += before == 0 ? 1 : -1u;
  rename_wait(m, c->thread);
}

void trace_finish(struct machine *m, uint64_t end) {
  struct mtrace *tr = m->trace;
  if (!tr->capped && tr->sampled && end <= tr->end && end > tr->last_t) {
    /* The run ended inside the window: its last bandwidth, and nothing held. */
    put_bandwidth(m, end);
    put_occupancy(m, end);
  }
  for (uint32_t i = 0; i < tr->nth; i++) {
    mark(m, i, MACHINE_TRACE_KINDS, end); /* closes the last slice */
    tr->th[i].kind = MACHINE_TRACE_DONE;
  }
  if (end < tr->end) tr->end = end > tr->p.from_cycle ? end : tr->p.from_cycle;
}

/* ---- life ---- */

void machine_trace_enable(struct machine *m, const struct machine_trace_params *tp) {
  CHECK(!m->ran);
  CHECK(!m->trace);
  CHECK_LE(tp->from_cycle, tp->to_cycle);
  CHECK_GE(tp->counter_period_cycles, 1);
  CHECK_GE(tp->max_events, 1000);
  struct mtrace *tr = xcalloc(1, sizeof *tr);
  tr->p = *tp;
  if (tr->p.cores > m->p.cores) tr->p.cores = m->p.cores;
  tr->nth = tr->p.cores * m->p.threads_per_core;
  tr->nctx = tr->nth * m->p.rays_per_thread;
  tr->th = xcalloc(tr->nth ? tr->nth : 1, sizeof *tr->th);
  tr->stalled = xcalloc(tr->nctx ? tr->nctx : 1, sizeof *tr->stalled);
  for (uint32_t i = 0; i < tr->nth; i++) tr->th[i].kind = MACHINE_TRACE_READY; /* as created */
  tr->l2_reason = -1;
  tr->end = tp->to_cycle;
  for (unsigned k = 0; k < MTRACE_COUNTERS; k++) tr->last_value[k] = NAN; /* none written */
  /* The reserve: a mark's two slices, then the cut's two a thread. */
  CHECK_LT(2 * (uint64_t)tr->nth + 2, tp->max_events);
  tr->limit = tp->max_events - 2 * (uint64_t)tr->nth - 2;
  tr->next_sample = tp->from_cycle;
  m->trace = tr;
  machine_door_traced(m);
}

uint64_t machine_trace_events(const struct machine *m, bool *capped, uint64_t *cut_cycle) {
  const struct mtrace *tr = m->trace;
  CHECK(tr);
  *capped = tr->capped;
  *cut_cycle = tr->end;
  return tr->n;
}

void trace_destroy(struct mtrace *t) {
  if (!t) return;
  free(t->th);
  free(t->stalled);
  free(t->ev);
  free(t);
}
