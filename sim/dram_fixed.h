/* The fixed-latency level (fidelity: fixed): every request is served
 * latency_cycles after it is taken, however many are in flight. No bandwidth
 * limit, no queue, never refuses: the cheapest timed rung of the ladder, and
 * the ideal memory of the cross-checks (latency 0). */
#ifndef RTSIM_SIM_DRAM_FIXED_H
#define RTSIM_SIM_DRAM_FIXED_H

#include <stdint.h>

#include "sim/dram_level.h"

struct dram_fixed;

struct dram_fixed *dram_fixed_create(uint64_t latency_cycles, struct engine *e,
                                     const struct dram_client *client);
extern const struct dram_level_ops dram_fixed_ops; /* self: a struct dram_fixed * */

#endif
