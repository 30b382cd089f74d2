/* A spot-check of a cheaper rung (docs/fidelity-and-sampling.md, "Spot-check"):
 * beside a whole run at analytic, fixed or channel, a sampled run of the same
 * point at banked, the most detailed rung, whose estimates and 95% intervals
 * give the cheap rung's error on this very point instead of in the nearest
 * measured regime. */
#ifndef RTSIM_APP_SPOT_CHECK_H
#define RTSIM_APP_SPOT_CHECK_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "renderer/policy/policy.h"

struct app_world;
struct machine_cfg;
struct stats_descs;

/* A figure and the ends of its 95% interval. */
struct spot_figure {
  double v, lo, hi;
};

struct spot_check {
  double fraction;                         /* the banked sample's sample.fraction */
  double cheap_cycles;                     /* the cheap run's */
  double cheap_dram_bytes;                 /* the cheap run's DRAM bytes read and written */
  struct spot_figure cycles, dram;         /* the banked sample's estimates */
  struct spot_figure cycles_err, dram_err; /* the cheap run's errors against them */
  double host_s;                           /* the sample's host time (stdout only) */
};
/* NULL if a run of policy k at width x height on mc can be spot-checked with
 * a banked sample of `fraction`, else why not (may be written into buf). */
const char *spot_check_problem(double fraction, const struct machine_cfg *mc, enum policy_kind k,
                               uint32_t width, uint32_t height, char *buf, size_t cap);

/* Run the banked sample (spot_check_problem must have said yes; CHECKed) of
 * the render of w that the cheap run made, and keep its estimates beside the
 * cheap run's cycles and DRAM bytes. */
void spot_check_run(struct spot_check *sc, double fraction, const struct app_world *w,
                    uint32_t mask, uint64_t seed, uint32_t width, uint32_t height,
                    enum policy_kind k, const struct machine_cfg *mc, double cheap_cycles,
                    double cheap_dram_bytes);

/* The cheap rung's relative error against the banked estimate,
 * cheap / banked - 1, and its 95% interval (from the estimate's). */
double spot_check_error(double cheap, double est, double lo, double hi, double *err_lo,
                        double *err_hi);

/* One line on f: the errors with their intervals, the sample's host time. */
void spot_check_summary(const struct spot_check *sc, FILE *f);

/* Its numbers: the fraction, the banked estimates, the errors (component
 * "spot"). */
extern const struct stats_descs spot_check_stats_descs;

#endif
