/* The DRAM's energy as a cheaper rung estimates it (fidelity fixed, channel
 * and analytic: docs/fidelity-and-sampling.md), from the counts every rung
 * has (64-byte reads and writes, the run's length) priced with the banked
 * level's own increments (struct dram_banked_costs, DRAMsim3's model). What
 * only the banked level knows is assumed:
 *   - every request is one burst (RD or WR), none served from a queue;
 *   - a row-hit rate of DRAM_ENERGY_ESTIMATE_ROW_HIT_RATE: an ACT (with its
 *     PRE) for that share's complement of the requests;
 *   - a REF every floor(tREFI / ranks) DRAM cycles on each channel, ranks in
 *     turn, as the banked level issues them (none with tREFI 0);
 *   - every rank-cycle in active standby (an open-page controller keeps a row
 *     open nearly always), so precharge standby is 0.
 * Measured against the banked level's own figure in results/dram/README.md. */
#ifndef RTSIM_SIM_DRAM_ENERGY_ESTIMATE_H
#define RTSIM_SIM_DRAM_ENERGY_ESTIMATE_H

#include <stdint.h>

#include "sim/dram_banked.h"

/* The row-hit rate the estimate assumes (the banked level measures 0.44 to
 * 0.69 on the committed scenes, results/dram/README.md). */
#define DRAM_ENERGY_ESTIMATE_ROW_HIT_RATE 0.5

/* The estimate for `reads` and `writes` requests over `dram_cycles` DRAM
 * cycles (fractions allowed) of the DRAM p describes (its clock_mhz set), by
 * part as the banked level reports it (total_j the six summed). */
void dram_energy_estimate(const struct dram_banked_params *p, uint64_t reads, uint64_t writes,
                          double dram_cycles, struct dram_banked_energy *out);

/* Joules over dram_cycles at p's clock, in watts (0 for no time). */
double dram_energy_estimate_power_w(const struct dram_banked_params *p, double joules,
                                    double dram_cycles);

/* What a rung's estimate is made of, for its stats: the DRAM (its clock_mhz
 * set), the requests, and the DRAM cycles of a run of c core cycles,
 * c x dram_per / core_per. */
struct dram_energy_estimate_in {
  struct dram_banked_params p;
  uint64_t reads, writes;
  double dram_per, core_per;
};
/* The estimate's numbers, named as the banked level's (st: a struct
 * dram_energy_estimate_in; env->cycles: the run's core cycles), with the flag
 * dram_energy_estimated; every cheaper rung registers this one table. */
struct stats_descs;
extern const struct stats_descs dram_energy_estimate_stats_descs;

#endif
