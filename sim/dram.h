/* The DRAM behind the L2: one level of detail chosen by fidelity (fixed
 * latency, the FIFO channel, or banked DDR; sim/dram_level.h is what each
 * implements), wrapped so that every level is counted, timed and traced the
 * same way: reads and writes, bytes, the latency of each request from the
 * cycle the level took it to the cycle it was served, and on request a trace
 * of every request in arrival order (docs/dram-traces.md). */
#ifndef RTSIM_SIM_DRAM_H
#define RTSIM_SIM_DRAM_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "sim/dram_banked.h"
#include "sim/dram_channel.h"
#include "sim/dram_level.h"
#include "sim/hist.h"

enum dram_model { DRAM_MODEL_FIXED, DRAM_MODEL_CHANNEL, DRAM_MODEL_BANKED, DRAM_MODEL_COUNT };
extern const char *const dram_model_names[DRAM_MODEL_COUNT]; /* "fixed", "channel", "banked" */

struct dram_params {
  enum dram_model model;
  uint64_t latency_cycles; /* fixed and channel: core cycles */
  double bytes_per_cycle;  /* channel */
  uint32_t queue_depth;    /* channel */
  uint32_t clock_mhz;      /* the DRAM's own clock (banked timing; the trace's DRAM cycles) */
  struct dram_banked_params banked; /* banked (its clock_mhz is taken from clock_mhz) */
};

/* NULL if usable, else what is wrong, naming the dram.* key: the banked
 * level's rules between keys (checked whatever the level). Each key's range
 * is the key table's (machine_params_problem). */
const char *dram_params_problem(const struct dram_params *p);

/* Counted here for every level. */
struct dram_stats {
  uint64_t reads, writes, read_bytes, write_bytes;
  struct hist read_latency;  /* cycles from taken to data delivered */
  struct hist write_latency; /* cycles from taken to written */
};

struct dram;

/* p must pass dram_params_problem (CHECKed); core_khz: the core clock in kHz
 * (1 to 2^32). client is told of each request served. Caller destroys. */
struct dram *dram_create(const struct dram_params *p, uint64_t core_khz, struct engine *e,
                         const struct dram_client *client);
void dram_destroy(struct dram *d); /* NULL ok */

/* The level's questions and orders, at engine_now (sim/dram_level.h).
 * Requests are one 64-byte line at a line-aligned byte address; the tag is
 * the client's, handed back in client->done. */
bool dram_can_take(struct dram *d, uint64_t addr, bool write);
void dram_take(struct dram *d, uint64_t addr, bool write, uint64_t tag);
/* After the run (nothing in flight, CHECKed), which ended at core cycle end
 * (engine_now or later: the level idles to it). */
void dram_finish(struct dram *d, uint64_t end);

/* From inside client->done: the core cycles [*start, *end), with fractions,
 * the served request's data held the channel, when the level says so (the
 * channel level); false otherwise (fixed: there is no channel; banked: its
 * bursts are its own). */
bool dram_served_transfer(const struct dram *d, double *start, double *end);

const struct dram_stats *dram_get_stats(const struct dram *d);
/* The DRAM's energy so far at core cycle t, J: the
 * banked level's count (its ranks' present states carried on to t), or at a
 * cheaper level the estimate of its stats (sim/dram_energy_estimate.h) over
 * the requests taken and t's DRAM cycles. After dram_finish at the run's
 * last cycle: the dram_energy_j its stats report. Reads only. */
double dram_energy_so_far(const struct dram *d, uint64_t t);
/* Requests taken and not yet served, now (the level's queues and banks). */
uint64_t dram_in_flight(const struct dram *d);
/* The numbers every level shares, over a struct dram_stats (sim/stats.h),
 * with two places: DRAM_STATS_AT_UTILIZATION, where the owner registers a
 * utilization figure of its own for a level that has none (the channel level
 * reports its own), and DRAM_STATS_AT_LEVEL, the level's own numbers. */
#define DRAM_STATS_AT_UTILIZATION "dram_utilization"
#define DRAM_STATS_AT_LEVEL "dram_level"
/* And DRAM_STATS_AT_ESTIMATE, after the level's: at a cheaper level (fixed,
 * channel) its DRAM energy estimate (sim/dram_energy_estimate.h), under the
 * banked level's names (a struct dram_energy_estimate_in the DRAM fills at
 * dram_finish). */
#define DRAM_STATS_AT_ESTIMATE "dram_energy_estimate"
struct stats_descs;
struct stats_part;
struct stats_table;
extern const struct stats_descs dram_stats_descs;
/* The parts for the places above, into out[0..2), how many: the level's own
 * numbers for DRAM_STATS_AT_LEVEL (none at fixed), then at fixed and channel
 * the energy estimate for DRAM_STATS_AT_ESTIMATE. */
unsigned dram_level_stats(const struct dram *d, struct stats_part *out);
/* The level's own numbers alone into t, for a run of `cycles`. */
void dram_report(const struct dram *d, struct stats_table *t, uint64_t cycles);

/* Write a header line (# ...: the format, the level, both clocks), then every
 * request from now on to f, one line each in arrival order, as soon as it and
 * every earlier one are served (docs/dram-traces.md); the caller owns f and
 * checks it for errors. */
void dram_trace_to(struct dram *d, FILE *f);

#endif
