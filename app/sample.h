/* Sampling a timed run (docs/fidelity-and-sampling.md): the work list (pixels or tiles in
 * the policy's order) is cut into sample.units strata of equal size; in each,
 * one unit of detailed items: its first items (two a ray context) warm the
 * machine's pipeline (rays in flight, MSHRs, DRAM queues), the rest (at
 * least one a context) are measured. The first
 * unit starts the run (measured from cycle 0, as the full run starts cold),
 * the last ends it (its drain measured, not guessed); the others fall at a
 * seeded random place in their strata. After a unit the machine drains (a
 * worker that claims an item outside the units waits until no detailed item
 * is left in flight: the unit's last items run on caches as they were, not
 * warmed for the next unit). Then, before the next unit, sample.warming times
 * its detailed items go through the warming port (caches updated, no time);
 * with sample.image whole, every other item through a port that only counts
 * issue slots (every item traced: the image, the rays and the issue slots
 * exact, the time estimated; the default); with sample.image sampled every other
 * item is skipped, not traced at all (its pixels black), and the rays and
 * issue slots are estimated too. A unit's measurement is the difference of two
 * machine probes: at the claim of its first measured item and at the claim of
 * the first item after it (the end of the run for the last unit).
 *
 * Estimates: the first and last units' own values plus, for the rest of the
 * run, with the whole image, the middle units' cycles (DRAM bytes, load
 * latencies) per issue slot times the issue slots the rest takes (a ratio
 * estimator on an exactly known total); with a sampled image, the middle
 * units' values per item times the items the rest holds (an expansion
 * estimator, stratified). The 95% intervals: linearization, the middle units' variance from
 * successive differences (a systematic sample), Student's t with
 * middle units - 1 degrees of freedom; figures made of cycles add a
 * systematic 0.5% in quadrature (a bias common to all windows, which their
 * spread cannot show). */
#ifndef RTSIM_APP_SAMPLE_H
#define RTSIM_APP_SAMPLE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "renderer/policy/policy.h"
#include "sim/machine_cfg.h"

struct stats_table;
struct err;

/* What a unit measured, per quantity (differences of two probes). */
enum sample_q {
  SQ_CYCLES,
  SQ_SLOTS,
  SQ_DRAM_BYTES,
  SQ_LAT_SUM,
  SQ_LAT_N,
  SQ_RAYS,
  SQ_ENERGY_FJ, /* the run's energy so far (machine_energy_j), femtojoules */
  SQ_COUNT
};

/* The pre-pass's auxiliary figures of an item (sample_aux.h): issue slots,
 * rays, the DRAM bytes the functional L2 model charged it. */
enum sample_a { SA_SLOTS, SA_RAYS, SA_DRAM, SA_COUNT };

struct sample_unit {
  uint64_t stratum_lo, stratum_hi; /* the stratum's items [lo, hi) */
  uint64_t warm_from, start, measure,
      end; /* warmed [warm_from, start), detailed [start, end), measured [measure, end) */
  uint64_t at0[SQ_COUNT], at1[SQ_COUNT];
  uint64_t at_start[SQ_COUNT]; /* a probe at the claim of its first detailed item */
  bool have0, have1;
};

struct sampler {
  struct machine *m;
  uint64_t total; /* work items */
  uint32_t n;     /* units */
  struct sample_unit *u;
  uint32_t cur; /* the unit the next claims belong to (claims come in order) */
  uint64_t detailed, warmed, measured; /* items */
  uint64_t in_flight;                  /* detailed items claimed and not finished */
  bool *drained;                       /* [h]: the gap before unit h has seen the pipeline empty */
  uint32_t cores;
  double hz;
  bool whole;      /* sample.image whole: every item traced (else skipped) */
  uint64_t traced; /* items traced (detailed, warmed, counted) */
  /* The rays traced so far (set by the caller before the run). */
  uint64_t (*rays_now)(void *ctx);
  void *rays_ctx;
  /* After the run (sample_finish): the totals of what was traced. */
  uint64_t rays_total, slots_total, slots_detailed;
  double mid_scale; /* a middle stratum's items x this: the items its unit stands for */
  /* With a sampled image and a pre-pass (sample.prepass > 0): the auxiliary
   * figures (sample_aux.h; NULL: none, the expansion estimator), and the one
   * the cycles and the energy are taken in ratio to (enum sample_a: slots or
   * modelled DRAM bytes, whichever gives the narrower interval; sample_finish chooses). */
  struct sample_aux *aux;
  unsigned cyc_aux;
};

/* The fewest units a run may sample: 6 middle units, Student's t at 5 degrees
 * of freedom (2.57, 1.3 x the normal's 1.96). With fewer, the variance comes
 * from one to three differences and t from 3.2 up to 12.7: an interval wide
 * enough to reach below zero, not a measurement. */
#define SAMPLE_MIN_UNITS 8u

/* The units a job of `total` items gets on a machine of `contexts` ray
 * contexts (sample.units, or when 0 as many as fit, at most 40). */
uint32_t sample_units(const struct machine_cfg_sample *c, uint64_t total, uint32_t contexts);

/* NULL if a job of `total` items can be sampled with c's sample.* keys on a
 * machine of `contexts` ray contexts at `fidelity` (enum machine_fidelity) by
 * policy k, else why not (naming the key; may be written into buf). */
const char *sample_problem(const struct machine_cfg_sample *c, uint32_t fidelity,
                           enum policy_kind k, uint64_t total, uint32_t contexts, char *buf,
                           size_t cap);

/* Plan the units for a machine of `cores` cores at clock_ghz (sample_problem
 * must have said yes; CHECKed). */
void sample_init(struct sampler *s, const struct machine_cfg_sample *c, uint32_t cores,
                 double clock_ghz, uint64_t total, uint32_t contexts);
void sample_fini(struct sampler *s);

/* The policy_setup.item and item_done hooks: ctx is the sampler. */
enum policy_item sample_item(void *ctx, uint64_t k, uint32_t core, struct mem_port *port);
void sample_item_done(void *ctx, uint64_t k);

/* After machine_run: the last unit's end is the end of the run. */
void sample_finish(struct sampler *s, uint64_t rays_total);
/* The part of sample_finish after the probes (every unit's at0 and at1, and
 * slots_total, set): the middle's scale and the cycles' auxiliary figure. */
void sample_settle(struct sampler *s);

/* The run's shape (contexts, threads), the estimates as stats members (name,
 * name_ci95_low, name_ci95_high) and the sampling's own figures, as
 * sample_stats_descs declares them. clock_ghz: the cores' clock;
 * peak_bytes_per_cycle: the DRAM's peak (0: none, no utilization). */
void sample_stats(const struct sampler *s, double clock_ghz, double peak_bytes_per_cycle,
                  uint64_t contexts, uint64_t threads, struct stats_table *t);
struct stats_descs;
extern const struct stats_descs sample_stats_descs;

/* The estimate of the run's cycles and its 95% interval (after sample_finish). */
double sample_cycles(const struct sampler *s, double *lo, double *hi);
/* The same for the DRAM bytes read and written. */
double sample_dram_bytes(const struct sampler *s, double *lo, double *hi);

/* Student's t quantile for probability 0.975 and dof degrees of freedom (>= 1). */
double sample_t975(unsigned dof);

#endif
