/* The timed machine's inside: the state its files share and the calls
 * between them. Private to the machine: only sim/machine*.c include it; the
 * contract is sim/machine.h. The files:
 *   machine.c        cores, threads and ray contexts; the timed door (the ops
 *                    a running ray calls); lines back from the L2; a run
 *   machine_cost.c   per-item cost attribution (machine_costs_enable)
 *   machine_ports.c  sampling's warming and counting ports, and the probe
 *   machine_stats.c  the machine's numbers and timeline columns
 *   machine_energy.c the timeline's energy columns, sampled at windows' ends
 *   machine_trace.c  the trace layer: threads' states and counters over time
 *                    (machine_trace_enable); machine_trace_json.c writes it */
#ifndef RTSIM_SIM_MACHINE_STATE_H
#define RTSIM_SIM_MACHINE_STATE_H

#include <stdbool.h>
#include <stdint.h>

#include "sim/err.h"
#include "sim/line.h"
#include "sim/machine.h"
#include "sim/ring.h"
#include "sim/timeline.h"

struct cache;
struct coro;
struct coro_pool;
struct dram;
struct engine;
struct l2;
struct mtrace;

#define NONE UINT32_MAX

/* The timeline's energy (machine_energy.c): the chip's figures resolved, and
 * the run's energy so far at the last window end sampled, J. */
struct menergy {
  struct chip_energy_params ep;
  uint64_t at;
  double dynamic_j, leakage_j, dram_j;
};

/* The L2's cost hook (struct l2_client's cost). */
typedef void (*l2_cost_fn)(void *cost_ctx, void *waiter, uint32_t tag, unsigned cls, bool write);

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
  const struct mem_ops *ops;  /* the door: timed, or with the cost layer */
  struct machine_costs costs; /* per item (machine_costs_enable) */
  uint64_t *cost_acc;         /* every context's counters; NULL: costs not counted */
  unsigned cost_stride;       /* counters a context */
  void *cost_ctx;             /* the cost layer's L2 hook (machine_door_costed) */
  l2_cost_fn cost_fn;
  struct mtrace *trace; /* the trace layer (machine_trace_enable); NULL: none */
  struct menergy en;
};

/* A core's warming port (machine_warm_port). */
struct mwarm {
  struct machine *m;
  uint32_t core;
};

/* ---- machine_cost.c: per-item costs ----
 * The helpers below are called by the door's costed instance alone
 * (machine.c), so every context has its counters (c->acc). */

/* c's own work (slots, waits, its loads' DRAM reads), charged when told anew. */
static inline void cost_charge(struct mctx *c, unsigned ch, uint64_t v) {
  CHECK_GT(c->nitems, 0); /* every access is attributed */
  c->acc[ch] += v;
}

/* The tag an access of c carries to the L2: the first item it works for. */
static inline uint32_t cost_tag(const struct mctx *c) {
  CHECK_GT(c->nitems, 0);
  return c->items[0];
}

/* A store's tag joins c's FIFO (its L2 access comes later: ev_l2_access). */
static inline void cost_store_push(struct mctx *c, uint32_t tag) {
  if (ring_len(&c->runs) && RING_BACK(&c->runs, struct tagrun)->tag == tag) {
    RING_BACK(&c->runs, struct tagrun)->n++;
    return;
  }
  *RING_PUSH(&c->runs, struct tagrun) = (struct tagrun){tag, 1};
}

/* NOTE: a context's L2 accesses leave in issue order (its clock never goes
 * back, and events of one cycle keep their order), so a FIFO finds each
 * store's tag. */
static inline uint32_t cost_store_pop(struct mctx *c) {
  CHECK_GT(ring_len(&c->runs), 0);
  struct tagrun *h = RING_HEAD(&c->runs, struct tagrun);
  const uint32_t tag = h->tag;
  if (--h->n == 0) ring_pop(&c->runs);
  return tag;
}

/* Install the cost layer (machine.c): the door's costed instance, and an L2
 * client that hears every transfer through `cost`. Before the run. */
void machine_door_costed(struct machine *m, void *cost_ctx, l2_cost_fn cost);
/* Charge what c has cost since it was told whom it works for to its items. */
void machine_cost_flush(struct mctx *c);
/* The end of a run that counted costs (CHECKs conservation). */
void machine_cost_finish(struct machine *m);

/* ---- machine_energy.c: the timeline's energy ---- */

/* Start sampling at the first window's end (machine creation). */
void machine_energy_start(struct machine *m);
/* The run's end at cycle end, after dram_finish: its last sample. */
void machine_energy_finish(struct machine *m, uint64_t end);

/* ---- machine_trace.c: the trace layer ----
 * Called by the door's and the events' traced instances alone (machine.c),
 * so m->trace is set; each ignores threads outside the traced cores. */

/* Install the trace layer's instances (machine.c), keeping the cost layer's. */
void machine_door_traced(struct machine *m);
/* Thread th takes a ray at cycle t, after a switch to its registers if switched. */
void trace_take(struct machine *m, uint32_t th, uint64_t t, bool switched);
/* Thread th went idle at cycle t (its state: waiting, parked or done). */
void trace_idle(struct machine *m, uint32_t th, uint64_t t);
/* Thread th's ray runs a block from cycle t (engine time: counters too). */
void trace_issue(struct machine *m, uint32_t th, uint64_t t);
/* The engine reached cycle t: the counters' sample, when one is due. */
void trace_tick(struct machine *m, uint64_t t);
/* The L2's stall hook (struct l2_client's stall; stall_ctx: the machine). */
void trace_l2_stall(void *ctx, void *waiter, int what);
/* The run ended at cycle end: every thread's last slice. */
void trace_finish(struct machine *m, uint64_t end);
void trace_destroy(struct mtrace *t); /* NULL ok */

#endif
