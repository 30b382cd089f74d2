/* The timeline's energy columns (docs/outputs.md): at each window's end the
 * engine's tick (engine_tick) reads the run's energy so far, the chip's from
 * the counters chip_energy_compute prices and the DRAM's from its level
 * (dram_energy_so_far), and adds what grew since the last end to the window
 * that closed. Holds: a window's figure is the difference of one cumulative
 * figure at its two ends, and the last end is the run's, priced from the
 * counts the stats price, so the windows sum to stats.json's energy (to the
 * rounding of doubles). Costs the hot path one comparison where engine time
 * moves, and a sample a window. Work is placed by engine time: a block's
 * issue slots count in the window its issue event fell in. */
#include "sim/machine_state.h"

#include "sim/derived.h"
#include "sim/dram.h"
#include "sim/engine.h"
#include "sim/l2.h"

/* The run's energy at cycle t by the counters as they stand, `slots` issue
 * slots used: the chip's dynamic and leakage, the DRAM's. */
static void energy_at(const struct machine *m, uint64_t t, uint64_t slots, double *dynamic_j,
                      double *leakage_j, double *dram_j) {
  const struct machine_params *p = &m->p;
  const struct l2_stats *l2 = l2_get_stats(m->l2);
  const struct chip_energy_counts c = {.cores = p->cores,
                                       .l1_size_bytes = p->l1_size_bytes,
                                       .l2_size_bytes = p->l2_size_bytes,
                                       .seconds = derived_seconds((double)t, p->clock_ghz),
                                       .issue_slots = slots,
                                       .loads = m->st.loads,
                                       .stores = m->st.stores,
                                       .ray_switches = m->st.ray_switches,
                                       .l1_accesses = m->st.l1_accesses,
                                       .l1_hits = m->st.l1_hits,
                                       .l2_accesses = l2->accesses,
                                       .l2_misses = l2->misses,
                                       .l2_writeback_lines = l2->writeback_bytes / SIM_LINE_BYTES};
  struct chip_energy e;
  chip_energy_compute(&m->en.ep, &c, &e);
  *dynamic_j = e.l1_dynamic_j + e.l2_dynamic_j + e.cores_dynamic_j;
  *leakage_j = e.l1_leakage_j + e.l2_leakage_j + e.cores_leakage_j;
  *dram_j = dram_energy_so_far(m->dram, t);
}

/* Sample at cycle t (> the last sample's, or the run's end): what grew since
 * goes to the window holding cycle t - 1. */
static void sample(struct machine *m, uint64_t t) {
  double dyn, leak, dram;
  energy_at(m, t, m->st.issue_slots, &dyn, &leak, &dram);
  const double d_dyn = dyn - m->en.dynamic_j, d_leak = leak - m->en.leakage_j,
               d_dram = dram - m->en.dram_j, all = d_dyn + d_leak + d_dram;
  const uint64_t at = t ? t - 1 : 0;
  timeline_point(&m->tl, MACHINE_TL_DRAM_ENERGY, at, d_dram);
  timeline_point(&m->tl, MACHINE_TL_CHIP_DYNAMIC_ENERGY, at, d_dyn);
  timeline_point(&m->tl, MACHINE_TL_CHIP_LEAKAGE_ENERGY, at, d_leak);
  timeline_point(&m->tl, MACHINE_TL_ENERGY, at, all);
  timeline_point(&m->tl, MACHINE_TL_POWER, at, all * derived_hz(m->p.clock_ghz));
  m->en = (struct menergy){m->en.ep, t, dyn, leak, dram};
}

/* The first window end after cycle t (the window may have doubled). */
static uint64_t next_end(const struct machine *m, uint64_t t) {
  return (t / m->tl.window + 1) * m->tl.window;
}

/* Every window end up to now, then the next tick. */
static void tick(void *ctx, uint64_t now) {
  struct machine *m = ctx;
  for (uint64_t b = next_end(m, m->en.at); b <= now; b = next_end(m, b)) sample(m, b);
  engine_tick(m->eng, next_end(m, m->en.at), tick, m);
}

void machine_energy_start(struct machine *m) {
  const struct machine_params *p = &m->p;
  m->en = (struct menergy){chip_energy_resolve(&p->energy, p->l1_size_bytes, p->l2_size_bytes), 0,
                           0, 0, 0};
  engine_tick(m->eng, next_end(m, 0), tick, m);
}

void machine_energy_finish(struct machine *m, uint64_t end) {
  engine_tick(m->eng, UINT64_MAX, NULL, NULL);
  /* Window ends the engine did not pass (the last events' cycles end before
   * the last block does), then the end itself. */
  for (uint64_t b = next_end(m, m->en.at); b < end; b = next_end(m, b)) sample(m, b);
  sample(m, end);
}

double machine_energy_j(const struct machine *m, uint64_t t, uint64_t issue_slots) {
  double dyn, leak, dram;
  energy_at(m, t, issue_slots, &dyn, &leak, &dram);
  return dyn + leak + dram;
}
