/* The spot-check: the same render at banked, sampled, and the cheap run's
 * error against it. */
#include "app/spot_check.h"

#include <float.h>
#include <string.h>

#include "app/app.h"
#include "app/sample.h"
#include "sim/machine_cfg.h"
#include "sim/stats.h"

/* The banked, sampled machine a spot-check runs: mc's, at banked, with
 * sample.fraction `fraction` and the whole image traced. */
static void spot_cfg(const struct machine_cfg *mc, double fraction, struct machine_params *p,
                     struct machine_cfg_sample *s) {
  *p = mc->p;
  p->fidelity = MACHINE_FIDELITY_BANKED;
  *s = mc->sample;
  s->fraction = fraction;
  s->whole_image = 1;
}

const char *spot_check_problem(double fraction, const struct machine_cfg *mc, enum policy_kind k,
                               uint32_t width, uint32_t height, char *buf, size_t cap) {
  if (mc->p.fidelity == MACHINE_FIDELITY_BANKED)
    return "--spot-check: the run is at fidelity banked already (the rung a spot-check "
           "measures against)";
  if (mc->sample.fraction < 1)
    return "--spot-check: the run is sampled (sample.fraction below 1); a spot-check sets a "
           "whole run at a cheaper rung against a banked sample";
  struct machine_params p;
  struct machine_cfg_sample s;
  spot_cfg(mc, fraction, &p, &s);
  const uint32_t contexts = p.cores * p.threads_per_core * p.rays_per_thread;
  const char *why =
      sample_problem(&s, p.fidelity, k, app_work_items(k, width, height), contexts, buf, cap);
  if (!why) return NULL;
  if (why != buf) snprintf(buf, cap, "%s", why);
  const size_t n = strlen(buf);
  snprintf(buf + n, cap - n, " (the banked sample of --spot-check %g)", fraction);
  return buf;
}

void spot_check_run(struct spot_check *sc, double fraction, const struct app_world *w,
                    uint32_t mask, uint64_t seed, uint32_t width, uint32_t height,
                    enum policy_kind k, const struct machine_cfg *mc, double cheap_cycles,
                    double cheap_dram_bytes) {
  struct machine_params p;
  struct machine_cfg_sample s;
  spot_cfg(mc, fraction, &p, &s);
  struct app_timed t = {0};
  app_timed_run(&t, w, mask, seed, width, height, k, &p, &mc->work, &s, false, NULL, false, NULL);
  CHECK(t.sampled);
  sc->fraction = fraction;
  sc->cheap_cycles = cheap_cycles;
  sc->cheap_dram_bytes = cheap_dram_bytes;
  struct spot_figure *c = &sc->cycles, *d = &sc->dram;
  c->v = sample_cycles(&t.sample, &c->lo, &c->hi);
  d->v = sample_dram_bytes(&t.sample, &d->lo, &d->hi);
  sc->cycles_err.v =
      spot_check_error(cheap_cycles, c->v, c->lo, c->hi, &sc->cycles_err.lo, &sc->cycles_err.hi);
  sc->dram_err.v =
      spot_check_error(cheap_dram_bytes, d->v, d->lo, d->hi, &sc->dram_err.lo, &sc->dram_err.hi);
  sc->host_s = t.wall_s;
  app_timed_fini(&t);
}

double spot_check_error(double cheap, double est, double lo, double hi, double *err_lo,
                        double *err_hi) {
  /* cheap / x - 1 falls as x grows: the interval's high end gives the low
   * error. A banked figure of 0 (no DRAM traffic in the sample) against a
   * cheap one above 0 is an unbounded error, written as DBL_MAX. */
  const double none = cheap > 0 ? DBL_MAX : 0;
  *err_lo = hi > 0 ? cheap / hi - 1 : none;
  *err_hi = lo > 0 ? cheap / lo - 1 : none;
  return est > 0 ? cheap / est - 1 : none;
}

void spot_check_summary(const struct spot_check *sc, FILE *f) {
  const struct spot_figure *c = &sc->cycles_err, *d = &sc->dram_err;
  fprintf(f,
          "spot_check: this rung against a banked sample (sample.fraction %g, %.1f host "
          "seconds): cycles %+.1f%% [%+.1f%%, %+.1f%%], DRAM bytes %+.1f%% [%+.1f%%, %+.1f%%] "
          "(95%% intervals)\n",
          sc->fraction, sc->host_s, 100 * c->v, 100 * c->lo, 100 * c->hi, 100 * d->v, 100 * d->lo,
          100 * d->hi);
}

/* ---- its numbers (docs/stats.md, component spot) ---- */

/* A figure as three numbers: NAME, NAME_ci95_low, NAME_ci95_high. */
#define SPOT_FIGURE(f, nm, un, ds)                                                                 \
  STATS_DOUBLE(struct spot_check, f.v, nm, un, ds),                                                \
      STATS_DOUBLE(struct spot_check, f.lo, nm "_ci95_low", un, "its 95% interval's low end"),     \
      STATS_DOUBLE(struct spot_check, f.hi, nm "_ci95_high", un, "its 95% interval's high end")
static const struct stats_desc spot_desc[] = {
    STATS_DOUBLE(struct spot_check, fraction, "spot_check_fraction", "fraction",
                 "the banked sample's sample.fraction (--spot-check)"),
    SPOT_FIGURE(cycles, "spot_banked_cycles", "cycles", "the banked sample's estimate of cycles"),
    SPOT_FIGURE(cycles_err, "spot_cycles_error", "fraction", "cycles / spot_banked_cycles - 1"),
    SPOT_FIGURE(dram, "spot_banked_dram_bytes", "bytes", "its estimate of dram_bytes"),
    SPOT_FIGURE(dram_err, "spot_dram_bytes_error", "fraction",
                "dram_bytes / spot_banked_dram_bytes - 1"),
};
const struct stats_descs spot_check_stats_descs = {"spot", spot_desc, STATS_COUNT(spot_desc),
                                                   0,      NULL,      0};
#undef SPOT_FIGURE
