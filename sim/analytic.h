/* The fidelity ladder's cheapest rung (fidelity: analytic): a counting backend
 * behind the memory door, fed by one worker, that charges issue slots as the
 * timed machine does (compute(n): n, a load or a store: 1) and keeps one L1
 * and the L2 of the machine config (sim/cache.h: LRU, the L2 write-back and
 * write-allocate, a store covering a whole line allocating it without a
 * fetch); then a closed-form estimate of the timed machine's cycles from its
 * counts. No engine, no coroutines, no time: seconds where a timed run takes
 * minutes. docs/fidelity-and-sampling.md states the formula and what it ignores. */
#ifndef RTSIM_SIM_ANALYTIC_H
#define RTSIM_SIM_ANALYTIC_H

#include <stdint.h>

#include "sim/mem.h"

struct machine_params;

/* What one worker's accesses did to one core's L1 and the L2. */
struct analytic_counts {
  uint64_t issue_slots; /* compute cycles + one per load and store */
  uint64_t loads, stores, computes;
  uint64_t blocking_loads;       /* loads with a line the L1 did not hold */
  uint64_t blocking_l2_misses;   /* blocking loads with a line the L2 fetched */
  uint64_t l1_hit_loads;         /* loads answered by the L1 (l1.latency each) */
  uint64_t l1_accesses, l1_hits; /* lines of loads, as the timed machine counts */
  uint64_t l2_accesses, l2_hits, l2_misses, l2_whole_line_allocs;
  uint64_t fetch_bytes, writeback_bytes; /* DRAM reads and writes, in bytes */
  uint64_t fetch_bytes_by_class[MEM_CLASS_MAX];
};

/* The estimate (docs/fidelity-and-sampling.md): per core n = threads_per_core x
 * rays_per_thread ray contexts; c = issue slots per blocking load; L = the
 * cycles a ray gives up its issue slots per blocking load: l2.latency + (the
 * share of blocking loads that miss the L2) x dram.latency + the L1 hits'
 * latency between two blocking loads; core utilization u = min(1, n c / (c +
 * L)); cycles = max(issue slots / (cores x u), DRAM bytes /
 * dram.bytes_per_cycle). */
struct analytic_estimate {
  double contexts_per_core;      /* n */
  double slots_per_blocking;     /* c (0 when no load blocks) */
  double blocking_miss_rate;     /* share of blocking loads that miss the L2 */
  double load_latency_cycles;    /* L */
  double core_utilization;       /* u */
  double latency_bound_cycles;   /* issue slots / (cores x u) */
  double bandwidth_bound_cycles; /* DRAM bytes / dram.bytes_per_cycle */
  uint64_t cycles;               /* the larger bound, rounded up */
};

struct analytic;

/* A counting backend for machine p (its l1.* and l2.* sizes and ways; p
 * must pass machine_params_problem, CHECKed). Caller destroys. */
struct analytic *analytic_create(const struct machine_params *p);
void analytic_destroy(struct analytic *a); /* NULL ok */

/* The port one worker renders through; valid while a lives. Its wait
 * operation CHECKs (one worker never waits for others). */
struct mem_port analytic_port(struct analytic *a);

const struct analytic_counts *analytic_get_counts(const struct analytic *a);

/* The estimate of counts c on machine p. */
void analytic_estimate(const struct machine_params *p, const struct analytic_counts *c,
                       struct analytic_estimate *out);

#endif
