/* What every DRAM level implements, and what it may call back. A level is one
 * model of the memory behind the L2 (a fixed latency, the FIFO channel, banked
 * DDR); sim/dram.h wraps the chosen one for the machine, counting, timing and
 * tracing every request the same way whatever the level.
 *
 * The interface speaks core cycles and the engine's time: a level is asked
 * at engine_now whether it can take a request, is handed it at engine_now, and
 * reports it served (a read's data delivered, a write's data written) from an
 * event it scheduled on the same engine. A level that keeps its own clock
 * converts exactly with struct dram_clock. In the spirit of DRAMsim3's
 * WillAcceptTransaction / AddTransaction / callback. */
#ifndef RTSIM_SIM_DRAM_LEVEL_H
#define RTSIM_SIM_DRAM_LEVEL_H

#include <stdbool.h>
#include <stdint.h>

#include "sim/err.h"

struct engine;
struct stats_part;
struct stats_table;

/* What a level calls back, always from inside an engine event at engine_now. */
struct dram_client {
  void *ctx;
  /* Request `tag` is served now. Called once per request taken. */
  void (*done)(void *ctx, uint64_t tag);
  /* A place freed in the level's queues: a request it refused may fit now.
   * May be called when nothing was refused; must not be called from inside
   * take. */
  void (*space)(void *ctx);
  /* Optional (NULL: not wanted). Called from inside take by a level that
   * models a data channel: request `tag`'s data will hold it over the core
   * cycles [start, end), with fractions. A level without one never calls it. */
  void (*transfer)(void *ctx, uint64_t tag, double start, double end);
};

struct dram_level_ops {
  /* Could the level take a read (write = false) or a write of the line at
   * byte address addr now? (A level with channels answers for addr's.) Not
   * const: a level that decides its cycles lazily (banked) first decides
   * those before now, and may schedule a space callback; the answer and every
   * later result are the same whenever that happens. */
  bool (*can_take)(void *self, uint64_t addr, bool write);
  /* Take one request of one line (SIM_LINE_BYTES) at byte address addr (line aligned)
   * now; only after can_take said yes (CHECKed). tag is the client's. */
  void (*take)(void *self, uint64_t addr, bool write, uint64_t tag);
  /* The run is over (nothing in flight, CHECKed) at core cycle end, at or
   * after engine_now: the level idles to end and closes its time integrals
   * there. */
  void (*finish)(void *self, uint64_t end);
  /* The level's own numbers (dram_row_hits, dram_bank_utilization, ...):
   * its table, its stats struct and its table's ctx into out (out->g NULL:
   * none). Only what the level knows: a level without banks has no bank
   * figure. */
  void (*stats)(const void *self, struct stats_part *out);
  void (*destroy)(void *self); /* NULL ok */
  /* Optional (NULL: the DRAM estimates it, sim/dram_energy_estimate.h): the
   * level's energy so far, J, at core cycle t: what it has counted, its
   * ranks' present states carried on to t (to where its counts reach, if t is
   * before that); after finish, the figure its stats report. Reads only. */
  double (*energy_j)(const void *self, uint64_t t);
};

/* A level's own numbers (ops->stats) alone into t, for a run of `cycles`. */
void dram_level_report(const struct dram_level_ops *ops, const void *level, struct stats_table *t,
                       uint64_t cycles);

/* Exact conversion between core cycles and a level's own clock: core_khz and
 * dram_khz reduced by their gcd, so a DRAM cycle d falls in core cycle
 * ceil(d * num / den) and no error accumulates over a run. */
struct dram_clock {
  uint64_t num, den; /* core cycles per DRAM cycle = num / den */
};

static inline uint64_t dram_gcd(uint64_t a, uint64_t b) {
  while (b) {
    uint64_t t = a % b;
    a = b;
    b = t;
  }
  return a;
}

/* Both clocks in kHz, each 1 to 2^32 (CHECKed; clock_ghz is at most 1000). */
static inline struct dram_clock dram_clock_make(uint64_t core_khz, uint64_t dram_khz) {
  CHECK(core_khz >= 1 && core_khz <= (1ull << 32) && dram_khz >= 1 && dram_khz <= (1ull << 32));
  uint64_t g = dram_gcd(core_khz, dram_khz);
  struct dram_clock c = {core_khz / g, dram_khz / g};
  return c;
}

/* The core cycle in which DRAM cycle d begins (the first core edge at or after
 * it). NOTE: 128-bit products (a GCC and Clang extension), so no time a run
 * can reach overflows. */
static inline uint64_t dram_clock_to_core(struct dram_clock c, uint64_t d) {
  /* (The same value in 64 bits while the product fits: the common case.) */
  if (d < (1ull << 31) && c.num < (1ull << 32)) return (d * c.num + c.den - 1) / c.den;
  return (uint64_t)(((unsigned __int128)d * c.num + c.den - 1) / c.den);
}

/* The first DRAM cycle that begins at or after core cycle t. */
static inline uint64_t dram_clock_from_core(struct dram_clock c, uint64_t t) {
  if (t < (1ull << 31) && c.den < (1ull << 32)) return (t * c.den + c.num - 1) / c.num;
  return (uint64_t)(((unsigned __int128)t * c.den + c.num - 1) / c.num);
}

#endif
