/* The DRAM channel: requests wait in a FIFO of bounded depth, then cross the
 * channel one at a time at bytes_per_cycle (fractional allowed), and their data
 * is delivered latency_cycles after the transfer ends. A request finding the
 * FIFO full waits outside it (back-pressure on the L2) until a place frees.
 * Reads and write-backs share the FIFO and the bandwidth.
 *
 * Requests must be submitted in non-decreasing arrival cycles (the machine
 * submits from events, in time order). The FIFO is deterministic, so a request's
 * whole timing is known when it is submitted. Time inside the channel is kept
 * in ticks of 2^-DRAM_TICK_BITS cycle, so fractional transfer times add up
 * without drift (2^44 cycles of range).
 *
 * This is the small interface a banked, row-buffer model would replace. */
#ifndef RTSIM_SIM_DRAM_H
#define RTSIM_SIM_DRAM_H

#include <stdbool.h>
#include <stdint.h>

#define DRAM_TICK_BITS 20

struct dram_params {
  uint64_t latency_cycles;
  double bytes_per_cycle; /* > 0 */
  uint32_t queue_depth;   /* requests that may wait for the channel, >= 1 */
};

/* NULL if usable, else what is wrong. */
const char *dram_params_problem(const struct dram_params *p);

/* The timing of one request. Cycles are whole (rounded up from ticks). */
struct dram_timing {
  uint64_t start_ticks, end_ticks; /* the transfer on the channel */
  uint64_t wait_cycles;            /* from arrival to the start of the transfer (rounded up) */
  uint64_t done_cycle;             /* data delivered (end + latency) */
};

struct dram_stats {
  uint64_t reads, writes, read_bytes, write_bytes;
  uint64_t wait_ticks_sum;      /* sum of waits, in ticks (exact) */
  uint64_t backpressure_cycles; /* of which spent outside a full FIFO */
  uint64_t busy_ticks;          /* transfer time */
  /* The FIFO itself, for Little's law: the sum over requests of the time spent
   * inside it (entry to start), and the time integral of its occupancy,
   * measured apart by sweeping entries and starts in time order (in cycles x
   * requests; complete after dram_finish). */
  double fifo_wait_cycles_sum, fifo_area;
  uint32_t fifo_max;            /* most requests inside the FIFO at once */
  uint64_t last_end_ticks;      /* when the channel is next free */
};

struct dram;

struct dram *dram_create(const struct dram_params *p); /* p CHECKed; caller destroys */
void dram_destroy(struct dram *d);                     /* NULL ok */

/* Submit a request of `bytes` (addr: for models that decode it) arriving at
 * cycle `at`. Fills *out. */
void dram_submit(struct dram *d, uint64_t at, uint64_t addr, uint32_t bytes, bool write,
                 struct dram_timing *out);

/* Close the occupancy integral (call once, after the last submission). */
void dram_finish(struct dram *d);

const struct dram_stats *dram_get_stats(const struct dram *d);

static inline uint64_t dram_ticks_to_cycles_ceil(uint64_t ticks) {
  return (ticks + ((1ull << DRAM_TICK_BITS) - 1)) >> DRAM_TICK_BITS;
}

#endif
