/* The timed many-core machine: C cores x T hardware threads x R ray contexts,
 * optional private L1s, a shared banked L2 with MSHRs, and one DRAM channel.
 * Each ray context is a stackful coroutine running a worker function the
 * caller supplies; the memory port it is handed suspends it inside a load
 * until the cycle the load completes. Knows nothing of rays: a worker is any
 * function that talks to memory through sim/mem.h.
 *
 * The model, in one place (docs/machine.md says the same in prose):
 * - A core issues one operation per cycle: compute(n) takes n issue slots, a
 *   load or store one. Threads get the issue port round robin, one block at a
 *   time: a block is what a ray runs between two waits (its compute, L1 hits
 *   and posted stores), and holds the port for its slots. L1 hit latencies
 *   delay the thread, not the port.
 * - A load that leaves the L1 suspends its ray; the thread switches to another
 *   ready ray of its own, paying costs.ray_switch cycles (thread busy, port
 *   free); with none ready it idles. Resuming the ray it last ran is free.
 * - Stores are posted: they take their slot and go on to the L1 (write-through,
 *   no allocation) and the L2; the ray does not wait.
 * - A ray context with no work may park (sim/mem.h): it leaves the machine,
 *   its stack goes back to the pool, and it makes no event and takes no slot
 *   until another context wakes it; its worker function then starts again.
 * - L2: sim/l2.h. DRAM: sim/dram.h (one level of detail: the fidelity key's
 *   timed rungs; its cheapest rung, analytic, is sim/analytic.h, no machine). */
#ifndef RTSIM_SIM_MACHINE_H
#define RTSIM_SIM_MACHINE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "sim/chip_energy.h"
#include "sim/dram.h"
#include "sim/hist.h"
#include "sim/l2.h"
#include "sim/line.h"
#include "sim/mem.h"
#include "sim/stats.h"
#include "sim/timeline.h"

struct timeline;

#define MACHINE_MAX_CONTEXTS (1u << 20) /* cores x threads_per_core x rays_per_thread */

/* The fidelity ladder's rungs, cheapest first (docs/fidelity-and-sampling.md): an
 * analytic estimate from a functional pass (sim/analytic.h: no machine is
 * built), then the timed machine with each DRAM level of sim/dram.h. */
enum machine_fidelity {
  MACHINE_FIDELITY_ANALYTIC,
  MACHINE_FIDELITY_FIXED,
  MACHINE_FIDELITY_CHANNEL,
  MACHINE_FIDELITY_BANKED,
  MACHINE_FIDELITY_COUNT
};

/* The DRAM level of a timed rung; for analytic the channel, whose figures
 * (dram.latency, dram.bytes_per_cycle) its bounds read. */
static inline enum dram_model machine_fidelity_dram(uint32_t fidelity) {
  return fidelity == MACHINE_FIDELITY_FIXED    ? DRAM_MODEL_FIXED
         : fidelity == MACHINE_FIDELITY_BANKED ? DRAM_MODEL_BANKED
                                               : DRAM_MODEL_CHANNEL;
}

struct machine_params {
  double clock_ghz;
  uint32_t cores, threads_per_core, rays_per_thread;
  uint64_t l1_size_bytes; /* 0: no L1 */
  uint32_t l1_ways;       /* 0: fully associative */
  uint32_t l1_latency_cycles;
  uint64_t l2_size_bytes;
  uint32_t l2_ways; /* 0: fully associative */
  uint32_t l2_latency_cycles, l2_banks, l2_mshrs, l2_write_buffer;
  uint32_t fidelity; /* enum machine_fidelity; a timed rung picks the DRAM level */
  uint64_t dram_latency_cycles;
  double dram_bytes_per_cycle;
  uint32_t dram_queue_depth;
  uint32_t dram_clock_mhz;
  struct dram_banked_params dram_banked; /* fidelity banked (its clock: dram_clock_mhz) */
  /* A thread's switch to another ray's registers. (The compute the renderer
   * announces per step is the renderer's: struct machine_cfg_work; how a run
   * is sampled is the run's: struct machine_cfg_sample.) */
  uint32_t cost_ray_switch_cycles;
  uint64_t timeline_window_cycles;
  struct chip_energy_params energy; /* the timed rungs' chip energy (energy.* keys) */
};

/* Columns of a timeline row (values are per window; see machine.c). */
enum machine_tl_col {
  MACHINE_TL_DRAM_READ_BYTES,
  MACHINE_TL_DRAM_WRITE_BYTES,
  MACHINE_TL_READ_CLASS0, /* MEM_CLASS_MAX columns: read bytes by class */
  MACHINE_TL_L2_ACCESSES = MACHINE_TL_READ_CLASS0 + MEM_CLASS_MAX,
  MACHINE_TL_L2_MISSES,
  MACHINE_TL_ISSUED_OPS,
  MACHINE_TL_BUSY_THREAD_CYCLES,
  /* Energy, J, sampled at the windows' ends (machine_energy.c); power: the
   * window's joules x the clock's hertz, written per cycle (W). */
  MACHINE_TL_DRAM_ENERGY,
  MACHINE_TL_CHIP_DYNAMIC_ENERGY,
  MACHINE_TL_CHIP_LEAKAGE_ENERGY,
  MACHINE_TL_ENERGY,
  MACHINE_TL_POWER,
  MACHINE_TL_COLS
};

struct machine_stats {
  uint64_t cycles; /* last ray done and the channel drained */
  uint64_t contexts, threads;
  uint64_t issue_slots;          /* used, of cores x cycles */
  uint64_t thread_busy_cycles;   /* a ray ready, running or being switched to */
  uint64_t thread_wait_cycles;   /* live rays, all waiting on memory (or mem_wait) */
  uint64_t thread_parked_cycles; /* live rays, all parked (mem_park: no work) */
  uint64_t thread_done_cycles;   /* no work left */
  uint64_t ray_switches, switch_cycles;
  uint64_t blocks; /* runs of a ray between waits */
  uint64_t loads, stores, computes;
  uint64_t blocking_loads;     /* loads that left the L1 and suspended their ray */
  uint64_t waits, wait_cycles; /* mem_wait: a worker idle by its own choice */
  uint64_t parks, wakes;       /* mem_park and mem_wake */
  uint64_t l1_accesses, l1_hits;
  struct l2_stats l2;       /* sim/l2.h, as of the end of the run */
  struct dram_stats dram;   /* sim/dram.h, likewise (the level's own: machine_dram) */
  struct hist load_latency; /* cycles from a load's issue to its data (L1 hits too) */
  uint64_t events;
  uint64_t stacks_max; /* coroutine stacks alive at once (parked contexts hold none) */
};

/* NULL if p is usable, else a description naming the key (for config errors
 * without a position; the config reader checks each value where it is), in
 * buf or a constant. Each key's range is its row in the key table
 * (machine_cfg_range_problem); the components add the rules between keys. */
#define MACHINE_PROBLEM_MAX 256
const char *machine_params_problem(const struct machine_params *p, char *buf, size_t cap);

/* The DRAM's parameters in p (for fidelity analytic, the channel's: the
 * figures its bounds read), and the core clock in whole kHz as the DRAM
 * converts it (for a DRAM built alone: rtsim dram-replay). */
struct dram_params machine_dram_params(const struct machine_params *p);
uint64_t machine_core_khz(const struct machine_params *p);
/* The DRAM's peak bytes a core cycle: the channel's bytes_per_cycle; for the
 * banked level every channel's data bus busy (bus_bytes, twice a DRAM clock);
 * 0 for the fixed latency, which has no limit. */
double machine_dram_peak_bytes_per_cycle(const struct machine_params *p);

struct machine;

/* What a worker is told about where it runs. */
struct machine_worker_info {
  uint32_t id; /* 0 .. contexts-1: core-major, then thread, then ray */
  uint32_t core, thread, ray;
};
typedef void (*machine_worker_fn)(void *arg, const struct machine_worker_info *info,
                                  struct mem_port port);
/* Called now and then (about every 2^16 blocks) with the current cycle. */
typedef void (*machine_progress_fn)(void *ctx, uint64_t cycle);

/* p must pass machine_params_problem and be a timed rung (fidelity not
 * analytic), both CHECKed. stack_bytes: coroutine stack
 * size (0: coro_default_stack_bytes). Caller destroys. */
struct machine *machine_create(const struct machine_params *p, uint64_t stack_bytes);
void machine_destroy(struct machine *m); /* NULL ok */

/* Run fn on every ray context until all have returned and memory is quiet.
 * A context that parked (mem_park) before returning runs fn again, from the
 * start, when another wakes it; one still parked at the end is a CHECK
 * failure (nobody was left to wake it). Once per machine. */
void machine_run(struct machine *m, machine_worker_fn fn, void *arg, machine_progress_fn progress,
                 void *progress_ctx);

/* A host-speed hint, before machine_run: context i's worker keeps the state
 * it reads first when it runs again at base + i x stride (its tracer, say).
 * When a context's load comes back the machine fetches the first host lines
 * there into the host cache, ahead of running it: with thousands of contexts
 * that state is far from the host's near caches. Nothing simulated changes. */
void machine_worker_state(struct machine *m, const void *base, uint64_t stride);

const struct machine_stats *machine_get_stats(const struct machine *m);

/* The machine's numbers (sim/stats.h), over a struct machine_stats; the L1's
 * and the engine's, whose counters it keeps, and the DRAM utilization it
 * computes for the levels without their own. */
extern const struct stats_descs machine_stats_descs, machine_l1_stats_descs,
    machine_engine_stats_descs, machine_dram_util_stats_descs;
/* The places in the machine's order where the run registers its own
 * numbers: after `seconds`, and after issue_slots_per_blocking_load. */
#define MACHINE_STATS_AT_RUN "run"
#define MACHINE_STATS_AT_RUN_MISSES "run_misses"
/* After machine_run: append every number of the machine and its components
 * to t, in their tables' order; per-class numbers for `classes` data classes
 * named class_names; the caller's parts (n of them, for the places above;
 * their ctx NULL: the machine) at their places. */
void machine_stats_emit(const struct machine *m, struct stats_table *t,
                        const char *const *class_names, unsigned classes,
                        const struct stats_part *parts, unsigned n);

/* ---- sampling (docs/fidelity-and-sampling.md) ----
 * The counters of a running machine at the current cycle: what a window of
 * the run did is the difference of two probes. */
struct machine_probe {
  uint64_t cycle;       /* the running ray's clock (inside a block), else the engine's */
  uint64_t issue_slots; /* used so far, the running block's included */
  uint64_t dram_bytes;  /* asked of the DRAM so far: L2 fetches and write-backs */
  uint64_t load_latency_sum, loads_timed; /* the load latency histogram's sum and count */
};
void machine_probe(const struct machine *m, struct machine_probe *out);
/* The run's energy so far, J (the chip's and the DRAM's, as the timeline's
 * energy columns price it: sim/machine_energy.c), at cycle t with
 * issue_slots used (a probe's two figures). After the run, at its cycles and
 * issue slots: the energy_j its stats give. */
double machine_energy_j(const struct machine *m, uint64_t t, uint64_t issue_slots);

/* A port that warms the caches instead of timing (sampling's fast-forward):
 * a load or store updates `core`'s L1 (a load that misses fills it) and the
 * L2's tags (l2_warm), takes no time and never suspends; compute and wait do
 * nothing. Its issue slots (computes + loads + stores) are counted apart,
 * machine_warm_slots. Valid while m lives. */
struct mem_port machine_warm_port(struct machine *m, uint32_t core);
uint64_t machine_warm_slots(const struct machine *m);
/* A port that only counts issue slots (computes + loads + stores), apart:
 * machine_count_slots. No cache sees the accesses; no time passes. */
struct mem_port machine_count_port(struct machine *m);
uint64_t machine_count_slots(const struct machine *m);

/* ---- per-item costs (docs/outputs.md "Cost in the picture") ----
 * The work of a run charged to items (pixels, to the renderer; integers here)
 * so that every item's costs sum, over the items, to the run's totals:
 * issue slots (= issue_slots), load latency from issue to data, L1 hits
 * included (= load_latency.sum), DRAM lines read by class (x 64 =
 * l2.fetch_bytes_by_class) and written back (x 64 = l2.writeback_bytes).
 * A ray context is told whom its work is for (machine_attribute); from then
 * on its slots, its loads' waits and the DRAM reads of the misses its loads
 * make are charged to those items, split evenly among them (integer shares,
 * the remainder one each to the first listed) when it is told anew. What
 * reaches the DRAM after the context may have moved on (a store's miss, the
 * write-back of a dirty line an access evicted) goes to the first item
 * listed when the access was issued. Every access must be attributed
 * (CHECKed). */
struct machine_costs {
  uint64_t items;
  unsigned classes;                    /* data classes counted, < MEM_CLASS_MAX */
  uint64_t *issue_slots;               /* per item */
  uint64_t *load_wait_cycles;          /* per item */
  uint32_t *read_lines[MEM_CLASS_MAX]; /* per item, DRAM lines read by class */
  uint32_t *write_lines;               /* per item, DRAM lines written back */
};

/* Count costs for `items` items and data classes below `classes` (before
 * machine_run; host memory: 16 + 4 x (classes + 1) bytes an item). */
void machine_costs_enable(struct machine *m, uint64_t items, unsigned classes);
/* Ray context `ctx` (the running one) works for items[0..n) from now on
 * (n = 0: nobody; its next access is a CHECK failure). n = 1: the item is
 * copied; else items must stay as they are until the next call. A context
 * whose worker function returns must not be left working for several. Does
 * nothing unless costs are enabled. */
void machine_attribute(struct machine *m, uint32_t ctx, const uint32_t *items, uint32_t n);
/* After machine_run: the costs per item, or NULL when not enabled. */
const struct machine_costs *machine_get_costs(const struct machine *m);

/* ---- trace events (README "Trace events") ----
 * The run's activity as Chrome trace-event JSON (chrome://tracing,
 * ui.perfetto.dev): per traced core, each hardware thread's state over time
 * as slices that tile the window (MACHINE_TRACE_KINDS: running a block,
 * switching, ready for the port, waiting by cause, parked, done), and the
 * L2's and the DRAM's occupancy and bandwidth as counters. 1 microsecond of
 * trace time is 1 core cycle. Installed only when asked (a layer, like
 * costs): without it the machine carries nothing of it. The slices of a
 * state sum, over the traced threads, to its thread_*_cycles counter when
 * the window is the whole run and every core is traced. */
struct machine_trace_params {
  uint64_t from_cycle, to_cycle;  /* the window [from, to); to UINT64_MAX: the end */
  uint32_t cores;                 /* the first `cores` cores (more: all of them) */
  uint64_t counter_period_cycles; /* counters sampled about this often (>= 1) */
  uint64_t max_events;            /* events at most (>= 1000): the file's bound */
};
/* Before machine_run; once. */
void machine_trace_enable(struct machine *m, const struct machine_trace_params *tp);
/* After machine_run: events kept; whether max_events cut the window short,
 * and where (the cycle the trace then ends at). */
uint64_t machine_trace_events(const struct machine *m, bool *capped, uint64_t *cut_cycle);
/* After machine_run: the JSON to f (the caller checks f for errors). */
void machine_trace_write(const struct machine *m, FILE *f);
/* The slices' names, by kind: the states a thread's slices name. */
enum {
  MACHINE_TRACE_RUN,          /* a ray's block holds the issue port (its L1 hits too) */
  MACHINE_TRACE_SWITCH,       /* switching to another ray's registers */
  MACHINE_TRACE_READY,        /* a ray ready, the port another thread's */
  MACHINE_TRACE_WAIT_LOAD,    /* every live ray waits; a load in the L2 or the DRAM */
  MACHINE_TRACE_WAIT_MSHR,    /* a ray's load queued at the L2 behind a miss with no MSHR */
  MACHINE_TRACE_WAIT_SET,     /* ... behind a miss whose set has every way pending */
  MACHINE_TRACE_WAIT_WBUF,    /* ... behind a dirty victim with the write buffer full */
  MACHINE_TRACE_WAIT_DRAM,    /* ... while the DRAM refuses requests (back-pressure) */
  MACHINE_TRACE_WAIT_MEMWAIT, /* every waiting ray is in mem_wait (the kernel's own) */
  MACHINE_TRACE_PARKED,       /* every live ray parked: no work */
  MACHINE_TRACE_DONE,         /* no work left */
  MACHINE_TRACE_KINDS
};
extern const char *const machine_trace_kind_names[MACHINE_TRACE_KINDS];

/* The timeline: rows of MACHINE_TL_COLS values (sim/timeline.h), and its
 * columns as timeline.csv writes them, each declared once. */
const struct timeline *machine_timeline(const struct machine *m);
extern const struct timeline_col machine_tl_cols[];
extern const unsigned machine_tl_col_count;
/* The DRAM (its level's numbers: dram_report; its trace: dram_trace_to). */
struct dram *machine_dram(const struct machine *m);

/* The deepest coroutine stack use seen, in bytes (painted stacks only: set
 * paint with machine_create_painted; else 0). */
struct machine *machine_create_painted(const struct machine_params *p, uint64_t stack_bytes);
uint64_t machine_stack_used_max(const struct machine *m);

#endif
