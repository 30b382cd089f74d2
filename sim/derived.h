/* The figures every rung derives from its counts, one formula each: the
 * timed machine's numbers (sim/machine_stats.c), the analytic estimate's
 * (app/run_output.c) and a sampled run's (app/sample.c) call these, so
 * `seconds`, `core_utilization`, `rays_per_second`, `threads` and
 * `ray_contexts` mean the same whichever rung wrote them (ratios: stats_ratio). */
#ifndef RTSIM_SIM_DERIVED_H
#define RTSIM_SIM_DERIVED_H

#include <stdint.h>

#include "sim/machine.h"
#include "sim/stats.h"

/* The core clock in cycles a second. */
static inline double derived_hz(double clock_ghz) { return clock_ghz * 1e9; }

static inline double derived_seconds(double cycles, double clock_ghz) {
  return cycles / derived_hz(clock_ghz);
}

/* Issue slots used of the cores x cycles there were. */
static inline double derived_core_utilization(double issue_slots, double cores, double cycles) {
  return stats_ratio(issue_slots, cores * cycles);
}

/* Rays traced a simulated second. */
static inline double derived_rays_per_second(double rays, double seconds) {
  return stats_ratio(rays, seconds);
}

/* Hardware threads (cores x threads_per_core) and ray contexts (x rays_per_thread). */
static inline uint64_t derived_threads(const struct machine_params *p) {
  return (uint64_t)p->cores * p->threads_per_core;
}
static inline uint64_t derived_contexts(const struct machine_params *p) {
  return derived_threads(p) * p->rays_per_thread;
}

#endif
