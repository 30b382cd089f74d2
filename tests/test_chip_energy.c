/* The chip's energy model (sim/chip_energy.c) against hand-computed cases:
 * the 65 nm table at its cited points and between them, and a tiny run's
 * counts turned into joules by hand, as the stats write them. */
#include <math.h>
#include <string.h>

#include "sim/chip_energy.h"
#include "sim/stats.h"
#include "testing.h"

static bool near_rel(double got, double want) {
  return fabs(got - want) <= 1e-12 * fabs(want) + 1e-18;
}

/* The cited points exactly; between them linear in log2(size): 64 KiB is
 * halfway from 8 KiB to 512 KiB (0.119 + 0.461 / 2), 1 MiB a third of the way
 * from 512 KiB to 4 MiB (0.58 + 1.02 / 3); beyond 4 MiB along that segment
 * (8 MiB: 1.6 + 0.34); below 8 KiB in proportion to the size. */
static void test_table(void) {
  static const struct {
    uint64_t bytes;
    double nj;
  } cases[] = {{8192, 0.119},          {512 << 10, 0.58}, {4 << 20, 1.6}, {64 << 10, 0.3495},
               {1 << 20, 0.58 + 0.34}, {8 << 20, 1.94},   {4096, 0.0595}, {0, 0.0}};
  for (unsigned i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    const double got = chip_energy_sram_read_nj(cases[i].bytes);
    EXPECTF(near_rel(got, cases[i].nj), "%llu bytes: got %.17g nJ, expected %.17g",
            (unsigned long long)cases[i].bytes, got, cases[i].nj);
  }
  EXPECT(chip_energy_sram_read_nj(8192) == 0.119);
  EXPECT(chip_energy_sram_read_nj(4 << 20) == 1.6);
}

/* A negative figure takes the table's (write and fill as a read, a tag probe
 * a tenth); a figure given stays. */
static void test_resolve(void) {
  struct chip_energy_params p = {.l1 = {-1, -1, -1, -1}, .l2 = {2.5, -1, 0, -1}};
  const struct chip_energy_params r = chip_energy_resolve(&p, 8192, 4 << 20);
  EXPECT(r.l1.read_nj == 0.119 && r.l1.write_nj == 0.119 && r.l1.fill_nj == 0.119);
  EXPECT(near_rel(r.l1.tag_nj, 0.0119));
  EXPECT(r.l2.read_nj == 2.5 && r.l2.write_nj == 1.6 && r.l2.fill_nj == 0.0);
  EXPECT(near_rel(r.l2.tag_nj, 0.16));
}

static const struct chip_energy_params PARAMS = {
    .l1 = {.read_nj = 0.1, .write_nj = 0.2, .fill_nj = 0.3, .tag_nj = 0.01},
    .l2 = {.read_nj = 1, .write_nj = 2, .fill_nj = 3, .tag_nj = 0.5},
    .sram_leakage_mw_per_kib = 0.5,
    .compute_nj = 0.05,
    .load_nj = 0.04,
    .store_nj = 0.03,
    .ray_switch_nj = 0.02,
    .core_leakage_mw = 10};

/* Two cores, 8 KiB L1s, a 4 MiB L2, 1 ms. By hand, nJ:
 *   L1: 90 hits x 0.1 + 20 misses x (0.01 + 0.3) + 20 stores x 0.2 = 19.2
 *   L2: 40 accesses, 5 misses, 20 stores: 15 reads x 1 + 20 writes x 2
 *       + 5 x (0.5 + 3) + 2 write-backs x 1 = 74.5
 *   cores: 1000 slots - 100 loads - 20 stores = 880 computes x 0.05
 *       + 100 x 0.04 + 20 x 0.03 + 10 switches x 0.02 = 48.8
 * leakage, J: L1s 2 x 8 KiB x 0.5 mW x 1 ms = 8e-6; L2 4096 KiB x 0.5 mW x
 * 1 ms = 2.048e-3; cores 2 x 10 mW x 1 ms = 2e-5. */
static const struct chip_energy_counts COUNTS = {.cores = 2,
                                                 .l1_size_bytes = 8192,
                                                 .l2_size_bytes = 4 << 20,
                                                 .seconds = 1e-3,
                                                 .issue_slots = 1000,
                                                 .loads = 100,
                                                 .stores = 20,
                                                 .ray_switches = 10,
                                                 .l1_accesses = 110,
                                                 .l1_hits = 90,
                                                 .l2_accesses = 40,
                                                 .l2_misses = 5,
                                                 .l2_writeback_lines = 2};
static const double CHIP_J = 142.5e-9 + 8e-6 + 2.048e-3 + 2e-5;

static void test_counts(void) {
  struct chip_energy e;
  chip_energy_compute(&PARAMS, &COUNTS, &e);
  EXPECTF(near_rel(e.l1_dynamic_j, 19.2e-9), "%.17g", e.l1_dynamic_j);
  EXPECTF(near_rel(e.l2_dynamic_j, 74.5e-9), "%.17g", e.l2_dynamic_j);
  EXPECTF(near_rel(e.cores_dynamic_j, 48.8e-9), "%.17g", e.cores_dynamic_j);
  EXPECTF(near_rel(e.l1_leakage_j, 8e-6), "%.17g", e.l1_leakage_j);
  EXPECTF(near_rel(e.l2_leakage_j, 2.048e-3), "%.17g", e.l2_leakage_j);
  EXPECTF(near_rel(e.cores_leakage_j, 2e-5), "%.17g", e.cores_leakage_j);
  EXPECTF(near_rel(chip_energy_total_j(&e), CHIP_J), "%.17g", chip_energy_total_j(&e));
  /* No L1: nothing of it, dynamic or leaking. */
  struct chip_energy_counts c = COUNTS;
  c.l1_size_bytes = 0;
  chip_energy_compute(&PARAMS, &c, &e);
  EXPECT(e.l1_dynamic_j == 0.0 && e.l1_leakage_j == 0.0);
  EXPECT(near_rel(e.l2_dynamic_j, 74.5e-9));
}

static double stat(const struct stats_table *t, const char *name) {
  const double v = testing_stat(t, name);
  EXPECTF(!isnan(v), "no stat %s", name);
  return v;
}

/* The stats: the total with the DRAM's 1 mJ and without it, mJ a frame,
 * watts over the 1 ms, 1000 rays over the joules; the parts add to the total. */
static void test_stats(void) {
  for (int dram = 0; dram < 2; dram++) {
    struct chip_energy_report r = {.has_dram = dram, .dram_j = 1e-3, .seconds = 1e-3, .rays = 1000};
    chip_energy_compute(&PARAMS, &COUNTS, &r.chip);
    struct stats_table t = {0};
    stats_emit(&t, &chip_energy_stats_descs, &r, &(struct stats_env){0});
    const double total = CHIP_J + (dram ? 1e-3 : 0.0);
    EXPECT(near_rel(stat(&t, "chip_energy_j"), CHIP_J));
    EXPECTF(near_rel(stat(&t, "energy_j"), total), "%.17g", stat(&t, "energy_j"));
    EXPECT(near_rel(stat(&t, "energy_mj_per_frame"), total * 1e3));
    EXPECT(near_rel(stat(&t, "power_w"), total / 1e-3));
    EXPECT(near_rel(stat(&t, "rays_per_joule"), 1000 / total));
    const double parts =
        stat(&t, "chip_energy_l1_dynamic_j") + stat(&t, "chip_energy_l2_dynamic_j") +
        stat(&t, "chip_energy_cores_dynamic_j") + stat(&t, "chip_energy_l1_leakage_j") +
        stat(&t, "chip_energy_l2_leakage_j") + stat(&t, "chip_energy_cores_leakage_j");
    EXPECT(near_rel(parts, CHIP_J));
    stats_fini(&t);
  }
}

int main(void) {
  test_table();
  test_resolve();
  test_counts();
  test_stats();
  return testing_done("chip_energy");
}
