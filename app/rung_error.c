/* A cheaper rung's measured error by regime: the nearest regime of the
 * committed table, the warning line, and the stats it writes. The table is
 * data (results/speed-accuracy/rung-errors.csv, remeasured by rung-errors.sh);
 * nothing here models an error, it only says what was measured nearest. */
#include "app/rung_error.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "sim/machine.h"
#include "sim/machine_cfg.h"
#include "sim/stats.h"

const struct rung_energy_error rung_energy_error_table[] = {
    {"fixed", "recursive", 3, -0.0143, 0.0468},    {"fixed", "packet", 3, -0.1335, 0.0225},
    {"fixed", "dynamic", 3, -0.1370, 0.0313},      {"channel", "recursive", 3, -0.0132, 0.0486},
    {"channel", "packet", 3, -0.1008, 0.0251},     {"channel", "dynamic", 3, -0.0650, 0.0344},
    {"analytic", "recursive", 3, -0.0262, 0.0419}, {"analytic", "packet", 3, -0.4410, -0.2168},
    {"analytic", "dynamic", 3, -0.1437, 0.0297},
};
const unsigned rung_energy_error_rows =
    sizeof rung_energy_error_table / sizeof rung_energy_error_table[0];

/* How far x lies outside [lo, hi). */
static double outside(double x, double lo, double hi) {
  return x < lo ? lo - x : x >= hi ? x - hi : 0;
}

static const char *bound_name(int bandwidth_bound) {
  return bandwidth_bound < 0 ? "-" : bandwidth_bound ? "bandwidth" : "latency";
}

void rung_error_match_in(struct rung_error *r, const struct rung_error_row *rows, unsigned n,
                         const char *rung, const char *policy, int bandwidth_bound,
                         double dram_utilization, double core_utilization) {
  memset(r, 0, sizeof *r);
  r->rung = rung;
  r->policy = policy;
  r->bandwidth_bound = bandwidth_bound;
  r->dram_utilization = dram_utilization;
  r->core_utilization = core_utilization;
  const char *bound = bound_name(bandwidth_bound);
  for (unsigned i = 0; i < n; i++) {
    const struct rung_error_row *w = &rows[i];
    if (strcmp(w->rung, rung) || strcmp(w->policy, policy) || strcmp(w->bound, bound)) continue;
    /* Inside the bands first (on a high end is outside, at distance 0), then
     * the nearest. */
    bool in = dram_utilization >= w->dram_low && dram_utilization < w->dram_high &&
              core_utilization >= w->core_low && core_utilization < w->core_high;
    double d = outside(dram_utilization, w->dram_low, w->dram_high) +
               outside(core_utilization, w->core_low, w->core_high);
    if (!r->row || (in && !r->inside) || (in == r->inside && d < r->distance)) {
      r->row = w;
      r->inside = in;
      r->distance = d;
    }
  }
  for (unsigned i = 0; i < rung_energy_error_rows; i++)
    if (!strcmp(rung_energy_error_table[i].rung, rung) &&
        !strcmp(rung_energy_error_table[i].policy, policy))
      r->energy = &rung_energy_error_table[i];
  const struct rung_error_row *w = r->row;
  r->warn = !w || !r->inside || fmax(fabs(w->cycles_min), fabs(w->cycles_max)) > RUNG_ERROR_WARN ||
            fmax(fabs(w->dram_bytes_min), fabs(w->dram_bytes_max)) > RUNG_ERROR_WARN;
}

void rung_error_match(struct rung_error *r, const struct machine_params *p, const char *policy,
                      int bandwidth_bound, uint64_t cycles, uint64_t issue_slots,
                      uint64_t dram_bytes) {
  /* The same yardstick at every rung: the banked DRAM this config describes
   * (fixed has no peak of its own, the channel's differs). */
  struct machine_params banked = *p;
  banked.fidelity = MACHINE_FIDELITY_BANKED;
  const double peak = machine_dram_peak_bytes_per_cycle(&banked);
  const double c = cycles ? (double)cycles : 1;
  rung_error_match_in(r, rung_error_table, rung_error_table_rows,
                      machine_cfg_fidelity_name(p->fidelity), policy, bandwidth_bound,
                      (double)dram_bytes / c / peak, (double)issue_slots / ((double)p->cores * c));
}

/* "0.3-0.6" or "0.6 and above". */
static void band(char *buf, size_t cap, double lo, double hi) {
  if (isinf(hi)) snprintf(buf, cap, "%.2g and above", lo);
  else snprintf(buf, cap, "%.2g-%.2g", lo, hi);
}

void rung_error_warning(const struct rung_error *r, char *buf, size_t cap) {
  buf[0] = '\0';
  if (!r->warn) return;
  static const char todo[] = "for a figure to trust, run fidelity=banked";
  char what[200];
  snprintf(what, sizeof what, "%s policy%s, DRAM utilization %.2f, core utilization %.2f",
           r->policy,
           r->bandwidth_bound < 0 ? ""
           : r->bandwidth_bound   ? ", estimate at its bandwidth bound"
                                  : ", estimate at its latency bound",
           r->dram_utilization, r->core_utilization);
  const struct rung_error_row *w = r->row;
  if (!w) {
    snprintf(buf, cap,
             "fidelity %s: no run like this one (%s) was measured against banked in %s, so its "
             "error is unknown; %s",
             r->rung, what, RUNG_ERROR_TABLE_PATH, todo);
    return;
  }
  char db[48], cb[48];
  band(db, sizeof db, w->dram_low, w->dram_high);
  band(cb, sizeof cb, w->core_low, w->core_high);
  snprintf(buf, cap,
           "fidelity %s: %s (%s): %s regime measured against banked (DRAM utilization %s, core "
           "utilization %s; %u run%s) was off by %+.1f%% to %+.1f%% in cycles and %+.1f%% to "
           "%+.1f%% in DRAM bytes%s; %s",
           r->rung, r->inside ? "error above 5%" : "outside every measured regime", what,
           r->inside ? "its" : "the nearest", db, cb, w->points, w->points == 1 ? "" : "s",
           100 * w->cycles_min, 100 * w->cycles_max, 100 * w->dram_bytes_min,
           100 * w->dram_bytes_max, r->inside ? "" : ", and here the error is unknown", todo);
}

/* ---- its stats (docs/stats.md, component rung) ---- */

static bool has_row(const void *st, const struct stats_env *env) {
  (void)env;
  return ((const struct rung_error *)st)->row != NULL;
}
static bool has_energy(const void *st, const struct stats_env *env) {
  (void)env;
  return ((const struct rung_error *)st)->energy != NULL;
}
static bool is_analytic(const void *st, const struct stats_env *env) {
  (void)env;
  return ((const struct rung_error *)st)->bandwidth_bound >= 0;
}
static bool dram_high_finite(const void *st, const struct stats_env *env) {
  return has_row(st, env) && !isinf(((const struct rung_error *)st)->row->dram_high);
}
static bool core_high_finite(const void *st, const struct stats_env *env) {
  return has_row(st, env) && !isinf(((const struct rung_error *)st)->row->core_high);
}
#define RE_F64(fnname, expr)                                                                       \
  static double fnname(const void *st, const struct stats_env *env) {                              \
    (void)env;                                                                                     \
    const struct rung_error *r = st;                                                               \
    return (expr);                                                                                 \
  }
RE_F64(re_dram_util, r->dram_utilization)
RE_F64(re_dram_low, r->row->dram_low)
RE_F64(re_dram_high, r->row->dram_high)
RE_F64(re_core_low, r->row->core_low)
RE_F64(re_core_high, r->row->core_high)
RE_F64(re_distance, r->distance)
RE_F64(re_cycles_min, r->row->cycles_min)
RE_F64(re_cycles_max, r->row->cycles_max)
RE_F64(re_bytes_min, r->row->dram_bytes_min)
RE_F64(re_bytes_max, r->row->dram_bytes_max)
RE_F64(re_energy_min, r->energy->min)
RE_F64(re_energy_max, r->energy->max)
#undef RE_F64
static uint64_t re_bound(const void *st, const struct stats_env *env) {
  (void)env;
  return (uint64_t)((const struct rung_error *)st)->bandwidth_bound;
}
static uint64_t re_points(const void *st, const struct stats_env *env) {
  (void)env;
  return ((const struct rung_error *)st)->row->points;
}
static uint64_t re_warn(const void *st, const struct stats_env *env) {
  (void)env;
  return ((const struct rung_error *)st)->warn;
}

#define RE(fn, nm, un, ds, pres)                                                                   \
  { .name = nm, .unit = un, .desc = ds, .how = STATS_HOW_F64, .f64 = fn, .present = pres }
#define RE_U(fn, nm, un, ds, pres)                                                                 \
  { .name = nm, .unit = un, .desc = ds, .how = STATS_HOW_U64, .u64 = fn, .present = pres }
static const struct stats_desc rung_desc[] = {
    RE(re_dram_util, "rung_dram_utilization", "fraction",
       "DRAM bytes per cycle / the peak of the config's banked DRAM: where the run falls", NULL),
    RE_U(re_bound, "rung_bandwidth_bound", "flag",
         "fidelity analytic: 1 when its estimate took the bandwidth bound, 0 the latency bound",
         is_analytic),
    RE_U(
        re_points, "rung_regime_points", "count",
        "runs measured against banked in the regime matched: of the run's rung, policy and bound, the one holding it, else the nearest",
        has_row),
    RE(re_dram_low, "rung_regime_dram_utilization_low", "fraction",
       "the regime's band of rung_dram_utilization: its low end", has_row),
    RE(re_dram_high, "rung_regime_dram_utilization_high", "fraction",
       "its high end, excluded (absent: the top band, no end)", dram_high_finite),
    RE(re_core_low, "rung_regime_core_utilization_low", "fraction",
       "the regime's band of core_utilization: its low end", has_row),
    RE(re_core_high, "rung_regime_core_utilization_high", "fraction",
       "its high end, excluded (absent: the top band, no end)", core_high_finite),
    RE(re_distance, "rung_regime_distance", "fraction",
       "utilization outside the regime's bands, DRAM's plus the cores' (0: inside, or on a high end)",
       has_row),
    RE(re_cycles_min, "rung_cycles_error_min", "fraction",
       "the regime's lowest signed error of cycles against banked, (rung - banked) / banked",
       has_row),
    RE(re_cycles_max, "rung_cycles_error_max", "fraction", "its highest", has_row),
    RE(re_bytes_min, "rung_dram_bytes_error_min", "fraction",
       "the regime's lowest signed error of DRAM bytes read and written", has_row),
    RE(re_bytes_max, "rung_dram_bytes_error_max", "fraction", "its highest", has_row),
    RE(re_energy_min, "rung_dram_energy_error_min", "fraction",
       "the rung and policy's lowest signed error of dram_energy_j (its estimate) against "
       "banked's, on " RUNG_ENERGY_ERROR_PATH "'s three scenes (absent: not measured)",
       has_energy),
    RE(re_energy_max, "rung_dram_energy_error_max", "fraction", "its highest", has_energy),
    RE_U(re_warn, "rung_error_warning", "flag",
         "1: outside every measured regime, or an error above 5% in it (and a line on stderr)",
         NULL),
};
#undef RE
#undef RE_U
const struct stats_descs rung_error_stats_descs = {"rung", rung_desc, STATS_COUNT(rung_desc),
                                                   0,      NULL,      0};
