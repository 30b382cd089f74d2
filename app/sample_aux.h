/* Sampling's pre-pass (docs/fidelity-and-sampling.md "Sampling"): with a
 * sampled image, before the timed run, one worker traces natively, without
 * time, every item of the middle units' detailed windows and contiguous
 * stretches of the rest of the middle (sample.stretch items, one item in
 * sample.prepass counted, a systematic sample of stretches from a seeded
 * place), each window and stretch preceded by sample.stretch_warming x the ray
 * contexts items that only warm. The items go through a functional model of
 * the L2 the machine shares (sample_fl2.h: the ray contexts run them
 * together), and for each counted item three auxiliary figures are summed:
 * its issue slots, its rays and the DRAM bytes the model charged it. A
 * unit's totals are so known exactly (the model's), the middle's are
 * estimated from the stretches; the ratio estimator (sample.c) then takes the
 * units' value per auxiliary unit times the middle's auxiliary total: the
 * units' cycles per modelled DRAM byte times the middle's modelled bytes,
 * which carries what neighbouring items share in the L2, and the units'
 * measured bytes per modelled byte, which calibrates the model against the
 * timed machine. */
#ifndef RTSIM_APP_SAMPLE_AUX_H
#define RTSIM_APP_SAMPLE_AUX_H

#include <stdint.h>

#include "app/sample.h"

struct app_world;
struct policy_params;
struct machine_cfg_work;
struct machine_cfg_sample;
struct machine_params;

/* The middle's items [lo, hi) a sampler's pre-pass covers: after the first
 * unit, up to the last unit's measured window. Stretch i counts the items
 * [lo + phase + (i - 1) x period, + len) of the middle outside the units'
 * windows (period: len x every). */
struct sample_aux {
  uint32_t every;       /* one item in this many of the rest counted */
  uint64_t len, period; /* a stretch's items and the distance between two */
  uint64_t phase;       /* [0, period): where the stretches fall (seeded) */
  uint64_t warm;        /* items warmed before each stretch and unit window */
  uint64_t lo, hi;
  double *unit;         /* [h x SA_COUNT]: middle unit h's detailed items' totals (exact) */
  double *sparse;       /* [i x SA_COUNT]: stretch i's counted items' totals, in order */
  uint64_t *sparse_n;   /* [i]: its counted items (NULL: one each) */
  uint64_t n_sparse;    /* stretches (clusters) */
  uint32_t dense_every; /* the dense sample: one item in this many of the rest (0: none) */
  uint64_t dense_phase; /* items k with (k + dense_phase) % dense_every == 0 */
  double *dense;        /* [i x SA_COUNT]: its items' slots and rays, in order */
  uint64_t n_dense;
  uint64_t pop;           /* items of the rest: the middle less the middle units' windows */
  double exact[SA_COUNT]; /* the middle units' windows' totals */
  uint64_t traced;        /* items the pre-pass traced (counted and warming) */
  uint64_t replayed;      /* line accesses the L2 model replayed */
  double wall_s;          /* its host seconds */
};

/* The stretches' shape: c's sample.prepass (every, at least 1),
 * sample.stretch and sample.stretch_warming on a machine of `contexts` ray
 * contexts. */
struct sample_aux_plan {
  uint32_t every;
  uint64_t len, warm;
};
struct sample_aux_plan sample_aux_plan_of(const struct machine_cfg_sample *c, uint32_t contexts);

/* Trace the pre-pass for s (planned by sample_init, sample.image sampled)
 * over the render the timed run makes (w, mask, seed, width x height, policy
 * k with p, work's compute costs; mp the machine whose L2 is modelled) into
 * s->aux (allocated; sample_fini frees it). seed_units: sample.seed. */
void sample_aux_run(struct sampler *s, const struct sample_aux_plan *sp, uint64_t seed_units,
                    const struct machine_params *mp, const struct app_world *w, uint32_t mask,
                    uint64_t seed, uint32_t width, uint32_t height, enum policy_kind k,
                    const struct policy_params *p, const struct machine_cfg_work *work);

/* The middle's total of auxiliary a: the windows' exact totals plus the
 * rest's stretches expanded by their items (pop x sum of totals / sum of
 * counted items: a ratio to size, the stretches' counts differing where a
 * unit's window cuts one). */
double sample_aux_total(const struct sample_aux *x, unsigned a);

/* The variance of sample_aux_total's estimate of sum_a g[a] x total_a (a
 * systematic sample of clusters: the linearized residuals e_i = v_i - R m_i
 * of each stretch's v_i = sum_a g[a] x value_a against its counted items
 * m_i, from successive differences, with the finite population
 * correction). */
double sample_aux_var(const struct sample_aux *x, const double g[SA_COUNT]);

void sample_aux_free(struct sample_aux *x);

#endif
