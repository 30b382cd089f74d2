/* The cheaper rungs' DRAM energy estimate (sim/dram_energy_estimate.h): one
 * formula for fixed, channel and analytic, so the rungs compare by the same
 * columns as the banked level. Holds: each part is a count the rung has, or
 * one the assumptions derive from them, times the banked level's increment
 * for it, so the estimate and the banked figure differ only by the counts. */
#include "sim/dram_energy_estimate.h"

#include <math.h>

#include "sim/stats.h"

void dram_energy_estimate(const struct dram_banked_params *p, uint64_t reads, uint64_t writes,
                          double dram_cycles, struct dram_banked_energy *out) {
  struct dram_banked_costs k;
  dram_banked_costs_of(p, &k);
  const double requests = (double)reads + (double)writes;
  const double acts = requests * (1 - DRAM_ENERGY_ESTIMATE_ROW_HIT_RATE);
  /* One REF a refresh interval on each channel: the ranks take turns. */
  const uint32_t every = p->tREFI / p->ranks;
  const double refs = every ? floor(dram_cycles / every) * p->channels : 0;
  const double rank_cycles = dram_cycles * p->ranks * p->channels;
  out->activate_j = acts * k.act;
  out->read_j = (double)reads * k.read;
  out->write_j = (double)writes * k.write;
  out->refresh_j = refs * k.ref;
  out->active_standby_j = rank_cycles * k.act_stb;
  out->precharge_standby_j = 0;
  out->total_j = out->activate_j + out->read_j + out->write_j + out->refresh_j +
                 out->active_standby_j + out->precharge_standby_j;
}

double dram_energy_estimate_power_w(const struct dram_banked_params *p, double joules,
                                    double dram_cycles) {
  return stats_ratio(joules, dram_cycles / ((double)p->clock_mhz * 1e6));
}
