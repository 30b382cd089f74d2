/* Sampling's pre-pass (docs/fidelity-and-sampling.md "Sampling"): with a
 * sampled image, before the timed run, one worker traces natively, without
 * time, every item of the middle units' measured windows and one item in
 * sample.prepass of the rest of the middle (a systematic sample from a seeded
 * place), and counts for each item three auxiliary figures that depend on
 * the item alone, never on what was traced around it: its issue slots, its
 * rays and its footprint (the distinct 64-byte lines it touches). A unit's
 * auxiliary totals are so exact, and the middle's are estimated from the
 * systematic sample; the ratio estimator (sample.c) then takes the units'
 * value per auxiliary unit times the middle's auxiliary total, which removes
 * the difference in work between the units (a unit of sky against a unit of
 * trees) that an expansion by items leaves in. */
#ifndef RTSIM_APP_SAMPLE_AUX_H
#define RTSIM_APP_SAMPLE_AUX_H

#include <stdint.h>

#include "app/sample.h"

struct app_world;
struct policy_params;
struct machine_cfg_work;

/* The middle's items [lo, hi) a sampler's pre-pass covers: after the first
 * unit, up to the last unit's measured window. */
struct sample_aux {
  uint32_t every, phase; /* the systematic sample: items k with (k + phase) % every == 0 */
  uint64_t lo, hi;
  double *unit;           /* [h x SA_COUNT]: middle unit h's measured items' totals (exact) */
  double *sparse;         /* [i x SA_COUNT]: the sampled items of the rest, in work-list order */
  uint64_t n_sparse;      /* items sampled from the rest */
  uint64_t pop;           /* items of the rest: the middle less the middle units' windows */
  double exact[SA_COUNT]; /* the middle units' windows' totals */
  uint64_t traced;        /* items the pre-pass traced */
  double wall_s;          /* its host seconds */
};

/* Trace the pre-pass for s (planned by sample_init, sample.image sampled)
 * over the render the timed run makes (w, mask, seed, width x height, policy
 * k with p, work's compute costs) into s->aux (allocated; sample_fini frees
 * it). every: one item in this many of the rest (at least 1). */
void sample_aux_run(struct sampler *s, uint32_t every, uint64_t seed_units,
                    const struct app_world *w, uint32_t mask, uint64_t seed, uint32_t width,
                    uint32_t height, enum policy_kind k, const struct policy_params *p,
                    const struct machine_cfg_work *work);

/* The middle's total of auxiliary a: the windows' exact totals plus the
 * rest's sample expanded by its items (pop / n_sparse). */
double sample_aux_total(const struct sample_aux *x, unsigned a);

/* The variance of sample_aux_total's estimate of sum_a g[a] x total_a (the
 * systematic sample's, from successive differences of the sampled items'
 * sum_a g[a] x value_a, with the finite population correction). */
double sample_aux_var(const struct sample_aux *x, const double g[SA_COUNT]);

void sample_aux_free(struct sample_aux *x);

#endif
