/* The timeline's energy columns (sim/machine_energy.c) on synthetic kernels:
 * a hand-timed kernel whose every window's chip energy is known by hand and
 * whose DRAM energy is the estimate's over that window's cycles alone; and at
 * every DRAM level, the windows sum to the run's figures (the chip's priced
 * from the run's counters, the DRAM's as its stats give it), and each
 * window's power is its energy over its seconds. */
#include <math.h>
#include <string.h>

#include "sim/chip_energy.h"
#include "sim/dram.h"
#include "sim/dram_energy_estimate.h"
#include "sim/l2.h"
#include "sim/line.h"
#include "sim/machine.h"
#include "sim/machine_cfg.h"
#include "sim/mem.h"
#include "sim/stats.h"
#include "sim/timeline.h"
#include "testing.h"

static struct machine_params base(enum machine_fidelity f) {
  struct machine_cfg c;
  machine_cfg_defaults(&c);
  struct machine_params p = c.p;
  p.fidelity = f;
  p.cores = 2;
  p.threads_per_core = 2;
  p.rays_per_thread = 2;
  p.l1_size_bytes = 4096;
  p.l2_size_bytes = 64 * 1024;
  p.timeline_window_cycles = 1000;
  return p;
}

static bool close_to(double a, double b, double rel) {
  return fabs(a - b) <= rel * fabs(b) + 1e-30;
}

/* Kernel: `iters` times, c issue slots of compute, then wait w cycles. */
struct beat {
  uint64_t iters, c, w;
};
static void beat_worker(void *arg, const struct machine_worker_info *info, struct mem_port port) {
  const struct beat *k = arg;
  (void)info;
  for (uint64_t i = 0; i < k->iters; i++) {
    mem_compute(&port, k->c);
    mem_wait(&port, k->w);
  }
}

/* One ray computing 10 slots every 100 cycles, a slot 1 nJ, the core leaking
 * 1 W, nothing else charged: a window of 1000 cycles at 1 GHz has 100 slots
 * (1e-7 J) and leaks 1e-6 J. Its DRAM takes no request: its energy in a
 * window is the estimate's for no request over the window's end less that
 * over its start (refresh and standby alone). */
static void test_hand_timed(void) {
  struct machine_params p = base(MACHINE_FIDELITY_CHANNEL);
  p.cores = p.threads_per_core = p.rays_per_thread = 1;
  p.clock_ghz = 1.0;
  memset(&p.energy, 0, sizeof p.energy);
  p.energy.compute_nj = 1.0;
  p.energy.core_leakage_mw = 1000.0;
  struct beat k = {500, 10, 90};
  struct machine *m = machine_create(&p, 0);
  machine_run(m, beat_worker, &k, NULL, NULL);
  const struct machine_stats *st = machine_get_stats(m);
  EXPECTF(st->cycles == 50000, "cycles %llu, expected 50000", (unsigned long long)st->cycles);
  const struct timeline *tl = machine_timeline(m);
  EXPECTF(tl->rows == 50 && tl->window == 1000, "%llu rows of %llu cycles",
          (unsigned long long)tl->rows, (unsigned long long)tl->window);
  struct dram_banked_params dp = p.dram_banked;
  dp.clock_mhz = p.dram_clock_mhz;
  const double dram_per_core = (double)p.dram_clock_mhz / (p.clock_ghz * 1e3);
  for (uint64_t i = 0; i < tl->rows; i++) {
    const double *r = timeline_row(tl, i);
    struct dram_banked_energy a, b;
    dram_energy_estimate(&dp, 0, 0, (double)(i * 1000) * dram_per_core, &a);
    dram_energy_estimate(&dp, 0, 0, (double)((i + 1) * 1000) * dram_per_core, &b);
    const double dram = b.total_j - a.total_j;
    EXPECTF(close_to(r[MACHINE_TL_CHIP_DYNAMIC_ENERGY], 1e-7, 1e-12), "window %llu: dynamic %.17g",
            (unsigned long long)i, r[MACHINE_TL_CHIP_DYNAMIC_ENERGY]);
    EXPECTF(close_to(r[MACHINE_TL_CHIP_LEAKAGE_ENERGY], 1e-6, 1e-12), "window %llu: leakage %.17g",
            (unsigned long long)i, r[MACHINE_TL_CHIP_LEAKAGE_ENERGY]);
    EXPECTF(close_to(r[MACHINE_TL_DRAM_ENERGY], dram, 1e-9),
            "window %llu: DRAM %.17g, expected %.17g", (unsigned long long)i,
            r[MACHINE_TL_DRAM_ENERGY], dram);
    EXPECTF(close_to(r[MACHINE_TL_ENERGY], 1.1e-6 + dram, 1e-9), "window %llu: energy %.17g",
            (unsigned long long)i, r[MACHINE_TL_ENERGY]);
    /* The power column holds J x Hz, written per cycle: W. */
    EXPECTF(close_to(r[MACHINE_TL_POWER] / 1000.0, (1.1e-6 + dram) / 1e-6, 1e-9),
            "window %llu: power %.17g W", (unsigned long long)i, r[MACHINE_TL_POWER] / 1000.0);
  }
  machine_destroy(m);
}

/* Kernel: loads of lines never seen before and stores, some computing. */
struct mix {
  uint64_t iters;
};
static void mix_worker(void *arg, const struct machine_worker_info *info, struct mem_port port) {
  const struct mix *k = arg;
  for (uint64_t i = 0; i < k->iters; i++) {
    const uint64_t a = ((uint64_t)info->id << 32 | (i * 7919 % 4096)) << 6;
    mem_compute(&port, 1 + i % 5);
    mem_load(&port, a, 8, (unsigned)(i % 3));
    if (i % 4 == 0) mem_store(&port, a + 64 * 4096, 64, 1);
  }
}

/* The run's chip energy from its counters, as rtsim run's stats price them. */
static double chip_total(const struct machine *m, const struct machine_params *p) {
  const struct machine_stats *s = machine_get_stats(m);
  const struct chip_energy_params ep =
      chip_energy_resolve(&p->energy, p->l1_size_bytes, p->l2_size_bytes);
  const struct chip_energy_counts c = {p->cores,
                                       p->l1_size_bytes,
                                       p->l2_size_bytes,
                                       (double)s->cycles / (p->clock_ghz * 1e9),
                                       s->issue_slots,
                                       s->loads,
                                       s->stores,
                                       s->ray_switches,
                                       s->l1_accesses,
                                       s->l1_hits,
                                       s->l2.accesses,
                                       s->l2.misses,
                                       s->l2.writeback_bytes / SIM_LINE_BYTES};
  struct chip_energy e;
  chip_energy_compute(&ep, &c, &e);
  return chip_energy_total_j(&e);
}

/* The DRAM's energy as its stats give it: the banked level's own table, or
 * the cheaper rungs' estimate table (dram_level_stats). */
static double dram_total(const struct machine *m) {
  struct stats_part parts[2];
  const unsigned n = dram_level_stats(machine_dram(m), parts);
  double v = NAN;
  for (unsigned i = 0; i < n; i++) {
    struct stats_table t = {0};
    const struct stats_env env = {.cycles = machine_get_stats(m)->cycles, .ctx = parts[i].ctx};
    stats_emit(&t, parts[i].g, parts[i].st, &env);
    const double x = testing_stat(&t, "dram_energy_j");
    if (!isnan(x)) v = x;
    stats_fini(&t);
  }
  return v;
}

static void test_sums(void) {
  static const enum machine_fidelity F[] = {MACHINE_FIDELITY_FIXED, MACHINE_FIDELITY_CHANNEL,
                                            MACHINE_FIDELITY_BANKED};
  for (unsigned f = 0; f < 3; f++)
    for (unsigned w = 0; w < 2; w++) {
      struct machine_params p = base(F[f]);
      /* 37 cycles: windows that split blocks; 1: rows past TIMELINE_MAX_ROWS
       * (the window doubles and rows merge). */
      p.timeline_window_cycles = w ? 1 : 37;
      struct mix k = {3000};
      struct machine *m = machine_create(&p, 0);
      machine_run(m, mix_worker, &k, NULL, NULL);
      const struct machine_stats *st = machine_get_stats(m);
      const struct timeline *tl = machine_timeline(m);
      double sum[MACHINE_TL_COLS] = {0};
      for (uint64_t i = 0; i < tl->rows; i++) {
        const double *r = timeline_row(tl, i);
        for (unsigned c = MACHINE_TL_DRAM_ENERGY; c < MACHINE_TL_COLS; c++) sum[c] += r[c];
        const double parts = r[MACHINE_TL_DRAM_ENERGY] + r[MACHINE_TL_CHIP_DYNAMIC_ENERGY] +
                             r[MACHINE_TL_CHIP_LEAKAGE_ENERGY];
        EXPECTF(close_to(r[MACHINE_TL_ENERGY], parts, 1e-12) &&
                    close_to(r[MACHINE_TL_POWER], r[MACHINE_TL_ENERGY] * p.clock_ghz * 1e9, 1e-12),
                "fidelity %u window %llu: energy %.17g, parts %.17g, power %.17g", F[f],
                (unsigned long long)i, r[MACHINE_TL_ENERGY], parts, r[MACHINE_TL_POWER]);
        EXPECTF(r[MACHINE_TL_CHIP_DYNAMIC_ENERGY] >= -1e-18, "fidelity %u window %llu: dynamic %g",
                F[f], (unsigned long long)i, r[MACHINE_TL_CHIP_DYNAMIC_ENERGY]);
      }
      const double chip = chip_total(m, &p), dram = dram_total(m);
      printf("fidelity %u, window %llu (%llu rows, %llu cycles): chip %.9g J, DRAM %.9g J\n", F[f],
             (unsigned long long)tl->window, (unsigned long long)tl->rows,
             (unsigned long long)st->cycles, chip, dram);
      EXPECTF(w == 0 || tl->window > 1, "fidelity %u: the window never doubled", F[f]);
      EXPECTF(chip > 0 && dram > 0, "fidelity %u: chip %g, DRAM %g", F[f], chip, dram);
      const double got = sum[MACHINE_TL_CHIP_DYNAMIC_ENERGY] + sum[MACHINE_TL_CHIP_LEAKAGE_ENERGY];
      EXPECTF(close_to(got, chip, 1e-12), "fidelity %u: windows' chip %.17g, run's %.17g", F[f],
              got, chip);
      EXPECTF(close_to(sum[MACHINE_TL_DRAM_ENERGY], dram, 1e-12),
              "fidelity %u: windows' DRAM %.17g, run's %.17g", F[f], sum[MACHINE_TL_DRAM_ENERGY],
              dram);
      EXPECTF(close_to(sum[MACHINE_TL_ENERGY], chip + dram, 1e-12),
              "fidelity %u: windows' energy %.17g, run's %.17g", F[f], sum[MACHINE_TL_ENERGY],
              chip + dram);
      machine_destroy(m);
    }
}

int main(void) {
  test_hand_timed();
  test_sums();
  return testing_done("test_machine_energy");
}
