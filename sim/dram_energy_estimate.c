/* The cheaper rungs' DRAM energy estimate (sim/dram_energy_estimate.h): one
 * formula for fixed, channel and analytic, so the rungs compare by the same
 * columns as the banked level. Holds: each part is a count the rung has, or
 * one the assumptions derive from them, times the banked level's increment
 * for it, so the estimate and the banked figure differ only by the counts. */
#include "sim/dram_energy_estimate.h"

#include <math.h>

#include "sim/stats.h"

void dram_energy_estimate(const struct dram_banked_params *p, uint64_t reads, uint64_t writes,
                          double dram_cycles, struct dram_banked_energy *out) {
  struct dram_banked_costs k;
  dram_banked_costs_of(p, &k);
  const double requests = (double)reads + (double)writes;
  const double acts = requests * (1 - DRAM_ENERGY_ESTIMATE_ROW_HIT_RATE);
  /* One REF a refresh interval on each channel: the ranks take turns. */
  const uint32_t every = p->tREFI / p->ranks;
  const double refs = every ? floor(dram_cycles / every) * p->channels : 0;
  const double rank_cycles = dram_cycles * p->ranks * p->channels;
  out->activate_j = acts * k.act;
  out->read_j = (double)reads * k.read;
  out->write_j = (double)writes * k.write;
  out->refresh_j = refs * k.ref;
  out->active_standby_j = rank_cycles * k.act_stb;
  out->precharge_standby_j = 0;
  out->total_j = out->activate_j + out->read_j + out->write_j + out->refresh_j +
                 out->active_standby_j + out->precharge_standby_j;
}

double dram_energy_estimate_power_w(const struct dram_banked_params *p, double joules,
                                    double dram_cycles) {
  return stats_ratio(joules, dram_cycles / ((double)p->clock_mhz * 1e6));
}

/* ---- the estimate's numbers (docs/stats.md) ---- */

#define IN(st) ((const struct dram_energy_estimate_in *)(st))
static double est_dram_cycles(const void *st, const struct stats_env *env) {
  return (double)env->cycles * IN(st)->dram_per / IN(st)->core_per;
}
static void est_of(const void *st, const struct stats_env *env, struct dram_banked_energy *out) {
  dram_energy_estimate(&IN(st)->p, IN(st)->reads, IN(st)->writes, est_dram_cycles(st, env), out);
}
#define EST_FN(f)                                                                                  \
  static double est_##f(const void *st, const struct stats_env *env) {                             \
    struct dram_banked_energy en;                                                                  \
    est_of(st, env, &en);                                                                          \
    return en.f;                                                                                   \
  }
EST_FN(activate_j)
EST_FN(read_j)
EST_FN(write_j)
EST_FN(refresh_j)
EST_FN(active_standby_j)
EST_FN(precharge_standby_j)
EST_FN(total_j)
#undef EST_FN
static double est_power_w(const void *st, const struct stats_env *env) {
  return dram_energy_estimate_power_w(&IN(st)->p, est_total_j(st, env), est_dram_cycles(st, env));
}
static uint64_t est_flag(const void *st, const struct stats_env *env) {
  (void)st;
  (void)env;
  return 1;
}
#undef IN
/* Written wherever a rung registers the table (fixed, channel, analytic),
 * never beside the banked level's table of the same names, counted: the
 * names are shared on purpose, and this marks them as one of two. */
static bool est_registered(const void *st, const struct stats_env *env) {
  (void)st;
  (void)env;
  return true;
}

/* An entry written wherever the table is registered: kind STATS_HOW_F64 (f
 * the f64 member) or STATS_HOW_U64 (u64). */
#define EST_ENTRY(nm, un, ds, kind, f, fn)                                                         \
  { .name = nm, .unit = un, .desc = ds, .how = kind, .f = fn, .present = est_registered }
#define EST(fn, nm, ds) EST_ENTRY(nm, "J", ds, STATS_HOW_F64, f64, fn)
static const struct stats_desc estimate_desc[] = {
    EST_ENTRY("dram_energy_estimated", "flag",
              "1: the dram_energy_* figures are a cheaper rung's estimate from its reads, "
              "writes and time, a row-hit rate of 0.5 assumed (absent at banked: counted)",
              STATS_HOW_U64, u64, est_flag),
    EST(est_activate_j, "dram_energy_activate_j",
        "estimate: an activate with its precharge for half the requests (row-hit rate 0.5 "
        "assumed), priced as banked's"),
    EST(est_read_j, "dram_energy_read_j", "estimate: a read burst a 64-byte read"),
    EST(est_write_j, "dram_energy_write_j", "estimate: a write burst a 64-byte write"),
    EST(est_refresh_j, "dram_energy_refresh_j",
        "estimate: a refresh every tREFI / ranks DRAM cycles of the run on each channel"),
    EST(est_active_standby_j, "dram_energy_active_standby_j",
        "estimate: every rank-cycle of the run in active standby"),
    EST(est_precharge_standby_j, "dram_energy_precharge_standby_j",
        "estimate: 0 (no rank-cycle assumed all banks precharged)"),
    EST(est_total_j, "dram_energy_j",
        "estimate: the six above; its error against banked's by rung and policy is "
        "rung_dram_energy_error_min/max (results/dram/README.md)"),
    EST_ENTRY("dram_power_w", "W", "estimate: dram_energy_j over the run's time", STATS_HOW_F64,
              f64, est_power_w),
};
#undef EST_ENTRY
#undef EST
const struct stats_descs dram_energy_estimate_stats_descs = {
    "dram estimate", estimate_desc, STATS_COUNT(estimate_desc), 0, NULL, 0};
