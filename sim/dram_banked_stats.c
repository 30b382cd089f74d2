/* The banked level's numbers: the table of its figures (names, units,
 * descriptions; docs/stats.md), each computed from its struct
 * dram_banked_stats and the run's length. Holds: every figure is a counter or
 * a ratio of counters the level keeps, so the table reads the same whatever
 * the level's controller structure. */
#include "sim/dram_banked_state.h"

#include <stddef.h>

#include "sim/stats.h"

/* The banked level's numbers (docs/stats.md); env->ctx is the level. */
static double bk_dram_cycles(const struct stats_env *env) {
  const struct dram_banked *d = env->ctx;
  return (double)env->cycles * (double)d->clk.den / (double)d->clk.num;
}
static double bk_row_hit_rate(const void *st, const struct stats_env *env) {
  (void)env;
  const struct dram_banked_stats *s = st;
  return stats_ratio((double)s->row_hits, (double)(s->reads + s->writes));
}
static double bk_bus_utilization(const void *st, const struct stats_env *env) {
  const struct dram_banked *d = env->ctx;
  const struct dram_banked_stats *s = st;
  return stats_ratio((double)s->bus_busy_cycles, bk_dram_cycles(env) * d->p.channels);
}
static double bk_bank_active_fraction(const void *st, const struct stats_env *env) {
  const struct dram_banked *d = env->ctx;
  const struct dram_banked_stats *s = st;
  return stats_ratio((double)s->bank_open_cycles,
                     bk_dram_cycles(env) * d->banks_per_channel * d->p.channels);
}
/* The energy figures (dram_banked_power.c), each one of struct
 * dram_banked_energy's from the stats struct. */
#define BK_ENERGY_FN(f)                                                                            \
  static double bk_energy_##f(const void *st, const struct stats_env *env) {                       \
    struct dram_banked_energy en;                                                                  \
    dram_banked_energy_total(env->ctx, st, &en);                                                   \
    return en.f;                                                                                   \
  }
BK_ENERGY_FN(activate_j)
BK_ENERGY_FN(read_j)
BK_ENERGY_FN(write_j)
BK_ENERGY_FN(refresh_j)
BK_ENERGY_FN(active_standby_j)
BK_ENERGY_FN(precharge_standby_j)
BK_ENERGY_FN(total_j)
/* Joules over the level's own time (its DRAM cycles at clock_mhz). */
static double bk_power_w(const void *st, const struct stats_env *env) {
  const struct dram_banked *d = env->ctx;
  const struct dram_banked_stats *s = st;
  const double seconds =
      (double)(s->rank_cycles / (d->p.ranks * d->p.channels)) / ((double)d->p.clock_mhz * 1e6);
  return stats_ratio(bk_energy_total_j(st, env), seconds);
}
#define BK_QUEUE_FNS(k, n)                                                                         \
  static double bk_queue_length_mean_##k(const void *st, const struct stats_env *env) {            \
    return stats_ratio((double)((const struct dram_banked_stats *)st)->queue_area[k],              \
                       (double)env->cycles);                                                       \
  }                                                                                                \
  static double bk_queue_wait_mean_##k(const void *st, const struct stats_env *env) {              \
    (void)env;                                                                                     \
    const struct dram_banked_stats *s = st;                                                        \
    return stats_ratio((double)s->queue_wait_sum_cycles[k], (double)s->n);                         \
  }
BK_QUEUE_FNS(0, reads)
BK_QUEUE_FNS(1, writes)
#define BK_QUEUE(k, q, what)                                                                       \
  STATS_F64(struct dram_banked_stats, queue_area[k], bk_queue_length_mean_##k,                     \
            "dram_" q "_queue_length_mean", "requests",                                            \
            what " queued, all channels: mean over the run"),                                      \
      STATS_FIELD(struct dram_banked_stats, queue_max[k], "dram_" q "_queue_length_max",           \
                  "requests", what " queued, all channels: most at once"),                         \
      STATS_F64(struct dram_banked_stats, queue_wait_sum_cycles[k], bk_queue_wait_mean_##k,        \
                "dram_" q "_queue_wait_mean_cycles", "cycles",                                     \
                what ", taken to column command: mean"),                                           \
      STATS_FIELD(struct dram_banked_stats, queue_wait_max_cycles[k],                              \
                  "dram_" q "_queue_wait_max_cycles", "cycles",                                    \
                  what ", taken to column command: most")

static const struct stats_desc banked_desc[] = {
    STATS_FIELD(struct dram_banked_stats, row_hits, "dram_row_hits", "count",
                "column commands that found their row open"),
    STATS_FIELD(struct dram_banked_stats, row_misses, "dram_row_misses", "count",
                "column commands whose row had to be opened"),
    STATS_FIELD(struct dram_banked_stats, row_conflicts, "dram_row_conflicts", "count",
                "column commands whose bank had another row open"),
    {.name = "dram_row_hit_rate",
     .unit = "fraction",
     .desc = "row hits / column commands (RD and WR issued), as DRAMsim3 counts: reads "
             "served from the write queue or by another read's RD issue none",
     .how = STATS_HOW_F64,
     .off = offsetof(struct dram_banked_stats, reads), /* reads and writes, side by side */
     .size =
         offsetof(struct dram_banked_stats, row_hits) - offsetof(struct dram_banked_stats, reads),
     .f64 = bk_row_hit_rate},
    STATS_FIELD(struct dram_banked_stats, activates, "dram_activates", "count", "row activations"),
    STATS_FIELD(struct dram_banked_stats, precharges, "dram_precharges", "count",
                "precharges, auto-precharges included"),
    STATS_FIELD(struct dram_banked_stats, refreshes, "dram_refreshes", "count", "refresh commands"),
    STATS_FIELD(struct dram_banked_stats, refresh_cycles, "dram_refresh_cycles", "DRAM cycles",
                "rank-cycles in refresh (DRAM clock)"),
    STATS_FIELD(struct dram_banked_stats, write_drains, "dram_write_drains", "count",
                "turns from reads to writes"),
    STATS_FIELD(struct dram_banked_stats, write_forwards, "dram_write_forwards", "count",
                "reads answered from the write queue (no command)"),
    STATS_FIELD(struct dram_banked_stats, write_merges, "dram_write_merges", "count",
                "writes that found their line in the write queue"),
    STATS_FIELD(struct dram_banked_stats, read_merges, "dram_read_merges", "count",
                "reads served by another queued read's column command"),
    STATS_FIELD(struct dram_banked_stats, writes_left, "dram_writes_left", "count",
                "writes still buffered when the run ended, never written, so in no energy "
                "figure (none unless dram.idle_drain_cycles is 0)"),
    STATS_F64(struct dram_banked_stats, bus_busy_cycles, bk_bus_utilization, "dram_bus_utilization",
              "fraction", "data bus busy, averaged over channels"),
    STATS_F64(struct dram_banked_stats, bank_open_cycles, bk_bank_active_fraction,
              "dram_bank_active_fraction", "fraction", "bank-cycles with a row open"),
    BK_QUEUE(0, "read", "reads"),
    BK_QUEUE(1, "write", "writes"),
    STATS_F64(struct dram_banked_stats, activates, bk_energy_activate_j, "dram_energy_activate_j",
              "J", "activates, each with its precharge: VDD (IDD0 tRC - IDD3N tRAS - IDD2N tRP)"),
    STATS_F64(struct dram_banked_stats, reads, bk_energy_read_j, "dram_energy_read_j", "J",
              "read bursts: VDD (IDD4R - IDD3N) BL/2 each"),
    STATS_F64(struct dram_banked_stats, writes, bk_energy_write_j, "dram_energy_write_j", "J",
              "write bursts: VDD (IDD4W - IDD3N) BL/2 each"),
    STATS_F64(struct dram_banked_stats, refreshes, bk_energy_refresh_j, "dram_energy_refresh_j",
              "J", "refreshes: VDD (IDD5AB - IDD3N) tRFC each"),
    STATS_F64(struct dram_banked_stats, rank_active_cycles, bk_energy_active_standby_j,
              "dram_energy_active_standby_j", "J",
              "background, rank-cycles with a bank open: VDD IDD3N each"),
    STATS_F64(struct dram_banked_stats, rank_cycles, bk_energy_precharge_standby_j,
              "dram_energy_precharge_standby_j", "J",
              "background, rank-cycles with every bank precharged: VDD IDD2N each"),
    STATS_FN_F64(bk_energy_total_j, "dram_energy_j", "J",
                 "the DRAM's energy: the six above (DRAMsim3's model; x devices x tCK)"),
    STATS_FN_F64(bk_power_w, "dram_power_w", "W", "dram_energy_j over the DRAM's time"),
};
const struct stats_descs dram_banked_stats_descs = {"dram banked",
                                                    banked_desc,
                                                    STATS_COUNT(banked_desc),
                                                    sizeof(struct dram_banked_stats),
                                                    NULL,
                                                    0};

void dram_banked_stats_part(const void *self, struct stats_part *out) {
  const struct dram_banked *d = self;
  out->g = &dram_banked_stats_descs;
  out->st = &d->st;
  out->ctx = d;
}

const struct dram_banked_stats *dram_banked_get_stats(const struct dram_banked *d) {
  return &d->st;
}

uint64_t dram_banked_finished_cycles(const struct dram_banked *d) {
  return d->finished_dram_cycles;
}
