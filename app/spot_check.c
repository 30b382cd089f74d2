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
  sc->cycles = sample_cycles(&t.sample, &sc->cycles_lo, &sc->cycles_hi);
  sc->dram = sample_dram_bytes(&t.sample, &sc->dram_lo, &sc->dram_hi);
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
  double clo, chi, dlo, dhi;
  const double c =
      spot_check_error(sc->cheap_cycles, sc->cycles, sc->cycles_lo, sc->cycles_hi, &clo, &chi);
  const double d =
      spot_check_error(sc->cheap_dram_bytes, sc->dram, sc->dram_lo, sc->dram_hi, &dlo, &dhi);
  fprintf(f,
          "spot_check: this rung against a banked sample (sample.fraction %g, %.1f host "
          "seconds): cycles %+.1f%% [%+.1f%%, %+.1f%%], DRAM bytes %+.1f%% [%+.1f%%, %+.1f%%] "
          "(95%% intervals)\n",
          sc->fraction, sc->host_s, 100 * c, 100 * clo, 100 * chi, 100 * d, 100 * dlo, 100 * dhi);
}

/* ---- its numbers (docs/stats.md, component spot) ---- */

#define SC(st) ((const struct spot_check *)(st))
static double f_fraction(const void *st, const struct stats_env *env) {
  (void)env;
  return SC(st)->fraction;
}
#define SPOT_FIG(name, field)                                                                      \
  static double name(const void *st, const struct stats_env *env) {                                \
    (void)env;                                                                                     \
    return SC(st)->field;                                                                          \
  }
SPOT_FIG(f_cycles, cycles)
SPOT_FIG(f_cycles_lo, cycles_lo)
SPOT_FIG(f_cycles_hi, cycles_hi)
SPOT_FIG(f_dram, dram)
SPOT_FIG(f_dram_lo, dram_lo)
SPOT_FIG(f_dram_hi, dram_hi)
#undef SPOT_FIG
/* The errors: which = 0 the value, 1 the interval's low end, 2 its high. */
static double cycles_err(const struct spot_check *s, int which) {
  double lo, hi;
  const double v =
      spot_check_error(s->cheap_cycles, s->cycles, s->cycles_lo, s->cycles_hi, &lo, &hi);
  return which == 0 ? v : which == 1 ? lo : hi;
}
static double dram_err(const struct spot_check *s, int which) {
  double lo, hi;
  const double v = spot_check_error(s->cheap_dram_bytes, s->dram, s->dram_lo, s->dram_hi, &lo, &hi);
  return which == 0 ? v : which == 1 ? lo : hi;
}
#define SPOT_ERR(name, fn, which)                                                                  \
  static double name(const void *st, const struct stats_env *env) {                                \
    (void)env;                                                                                     \
    return fn(SC(st), which);                                                                      \
  }
SPOT_ERR(f_cycles_err, cycles_err, 0)
SPOT_ERR(f_cycles_err_lo, cycles_err, 1)
SPOT_ERR(f_cycles_err_hi, cycles_err, 2)
SPOT_ERR(f_dram_err, dram_err, 0)
SPOT_ERR(f_dram_err_lo, dram_err, 1)
SPOT_ERR(f_dram_err_hi, dram_err, 2)
#undef SPOT_ERR

static const struct stats_desc spot_desc[] = {
    STATS_FN_F64(f_fraction, "spot_check_fraction", "fraction",
                 "the banked sample's sample.fraction (--spot-check)"),
    STATS_FN_F64(f_cycles, "spot_banked_cycles", "cycles",
                 "the banked sample's estimate of this run's cycles"),
    STATS_FN_F64(f_cycles_lo, "spot_banked_cycles_ci95_low", "cycles",
                 "its 95% interval's low end"),
    STATS_FN_F64(f_cycles_hi, "spot_banked_cycles_ci95_high", "cycles",
                 "its 95% interval's high end"),
    STATS_FN_F64(f_cycles_err, "spot_cycles_error", "fraction",
                 "this run's cycles / spot_banked_cycles - 1: this rung's error on this point"),
    STATS_FN_F64(f_cycles_err_lo, "spot_cycles_error_ci95_low", "fraction",
                 "its 95% interval's low end (from the estimate's)"),
    STATS_FN_F64(f_cycles_err_hi, "spot_cycles_error_ci95_high", "fraction",
                 "its 95% interval's high end"),
    STATS_FN_F64(f_dram, "spot_banked_dram_bytes", "bytes",
                 "the banked sample's estimate of the DRAM bytes read and written"),
    STATS_FN_F64(f_dram_lo, "spot_banked_dram_bytes_ci95_low", "bytes",
                 "its 95% interval's low end"),
    STATS_FN_F64(f_dram_hi, "spot_banked_dram_bytes_ci95_high", "bytes",
                 "its 95% interval's high end"),
    STATS_FN_F64(f_dram_err, "spot_dram_bytes_error", "fraction",
                 "this run's DRAM bytes / spot_banked_dram_bytes - 1"),
    STATS_FN_F64(f_dram_err_lo, "spot_dram_bytes_error_ci95_low", "fraction",
                 "its 95% interval's low end"),
    STATS_FN_F64(f_dram_err_hi, "spot_dram_bytes_error_ci95_high", "fraction",
                 "its 95% interval's high end"),
};
const struct stats_descs spot_check_stats_descs = {"spot", spot_desc, STATS_COUNT(spot_desc),
                                                   0,      NULL,      0};
