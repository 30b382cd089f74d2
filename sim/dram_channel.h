/* The FIFO channel level (fidelity: channel): requests wait in a FIFO of
 * queue_depth places, cross the channel one at a time at bytes_per_cycle
 * (fractional allowed), and a read's data is delivered latency_cycles after
 * its transfer ends; a write is served when its transfer ends. Reads and
 * writes share the FIFO and the bandwidth. A full FIFO refuses requests
 * (can_take), so they wait at the L2, in order: the back-pressure.
 *
 * The FIFO is deterministic, so a request's whole timing is known when it is
 * taken. Time inside the channel is kept in ticks of 2^-DRAM_TICK_BITS cycle,
 * so fractional transfer times add up without drift; ticks are 128-bit, so
 * any cycle the engine can reach (a 64-bit count) has its tick. */
#ifndef RTSIM_SIM_DRAM_CHANNEL_H
#define RTSIM_SIM_DRAM_CHANNEL_H

#include <stdint.h>

#include "sim/dram_level.h"
#include "sim/err.h"

#define DRAM_TICK_BITS 20

/* A time in ticks. */
typedef unsigned __int128 dram_tick;

struct dram_channel_params {
  uint64_t latency_cycles;
  double bytes_per_cycle; /* > 0 */
  uint32_t queue_depth;   /* requests that may wait for the channel, >= 1 */
};

struct dram_channel_stats {
  dram_tick busy_ticks;     /* transfer time */
  dram_tick wait_ticks_sum; /* from take to the start of the transfer (the FIFO wait), exact */
  uint64_t requests;        /* the wait's mean's divisor (beside the sum it divides) */
  /* The FIFO's occupancy integral, by time (in cycles x requests), apart from
   * the waits, for Little's law; complete after finish. */
  double fifo_area;
  uint32_t fifo_max;
};

struct dram_channel;

/* p within the key table's ranges (machine_params_problem; bytes_per_cycle
 * and queue_depth positive are CHECKed). Destroy through the ops. */
struct dram_channel *dram_channel_create(const struct dram_channel_params *p, struct engine *e,
                                         const struct dram_client *client);
extern const struct dram_level_ops dram_channel_ops; /* self: a struct dram_channel * */
/* The level's numbers, over its struct dram_channel_stats (sim/stats.h). */
struct stats_descs;
extern const struct stats_descs dram_channel_stats_descs;

static inline uint64_t dram_ticks_to_cycles_ceil(dram_tick ticks) {
  dram_tick c = (ticks + ((1ull << DRAM_TICK_BITS) - 1)) >> DRAM_TICK_BITS;
  CHECK(c <= (dram_tick)UINT64_MAX);
  return (uint64_t)c;
}

#endif
