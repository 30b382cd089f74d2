/* The energy stats add up in every run (docs/stats.md, energy): at every rung
 * and policy, the DRAM's six parts give dram_energy_j, the chip's six give
 * chip_energy_j, their sum is energy_j, and the frame, power and rays-per-joule
 * figures are energy_j's in their units; stats.csv holds the same numbers as
 * stats.json. Each run is a real one (tiny.yaml, the small grove). */
#include <math.h>
#include <string.h>

#include "testing.h"

#define TMP RTSIM_TMP "/energy_sums"

static char out[1 << 14];

static const char *const DRAM_PARTS[] = {
    "dram_energy_activate_j", "dram_energy_read_j",           "dram_energy_write_j",
    "dram_energy_refresh_j",  "dram_energy_active_standby_j", "dram_energy_precharge_standby_j"};
static const char *const CHIP_PARTS[] = {
    "chip_energy_l1_dynamic_j", "chip_energy_l2_dynamic_j", "chip_energy_cores_dynamic_j",
    "chip_energy_l1_leakage_j", "chip_energy_l2_leakage_j", "chip_energy_cores_leakage_j"};

/* a and b agree to rounding: a few ulps of the larger. */
static bool near(double a, double b) { return fabs(a - b) <= 1e-12 * fmax(fabs(a), fabs(b)); }

static double sum_of(const char *dir, const char *const *names, unsigned n) {
  double s = 0;
  for (unsigned i = 0; i < n; i++) {
    const double v = testing_json_num(dir, names[i]);
    EXPECTF(v >= 0, "%s: %s = %g, not a non-negative energy", dir, names[i], v);
    s += v;
  }
  return s;
}

static void check_run(const char *fidelity, const char *policy) {
  char dir[256];
  snprintf(dir, sizeof dir, "%s/%s-%s", TMP, fidelity, policy);
  const int rc =
      testing_runf(out, sizeof out,
                   "%s run %s/configs/tiny.yaml %s/scenes/small/grove.yaml --width 16 "
                   "--height 16 --policy %s --set fidelity=%s -o %s 2>&1",
                   RTSIM_BINARY, RTSIM_SOURCE_DIR, RTSIM_SOURCE_DIR, policy, fidelity, dir);
  EXPECTF(rc == 0, "%s: exit %d: %s", dir, rc, out);
  if (rc) return;
  const double dram = testing_json_num(dir, "dram_energy_j");
  const double dsum = sum_of(dir, DRAM_PARTS, 6);
  EXPECTF(dram > 0 && near(dsum, dram), "%s: DRAM parts %.17g, dram_energy_j %.17g", dir, dsum,
          dram);
  /* The DRAM's power is over its own time: the run's, in whole DRAM cycles
   * (the banked level's last cycle may fall a cycle or two from the cores'). */
  static struct testing_csv csv;
  char path[300];
  snprintf(path, sizeof path, "%s/stats.csv", dir);
  EXPECTF(testing_csv_load(path, &csv), "%s: no stats.csv", dir);
  const double dram_s = dram / testing_json_num(dir, "dram_power_w");
  const double dram_cycle_s = 1 / (testing_csv_num(&csv, "dram.clock_mhz") * 1e6);
  EXPECTF(fabs(dram_s - testing_json_num(dir, "seconds")) <= 2 * dram_cycle_s,
          "%s: dram_energy_j / dram_power_w is %.9g s, the run %.9g s", dir, dram_s,
          testing_json_num(dir, "seconds"));
  const double chip = testing_json_num(dir, "chip_energy_j");
  const double csum = sum_of(dir, CHIP_PARTS, 6);
  EXPECTF(chip > 0 && near(csum, chip), "%s: chip parts %.17g, chip_energy_j %.17g", dir, csum,
          chip);
  const double e = testing_json_num(dir, "energy_j");
  EXPECTF(near(e, chip + dram), "%s: energy_j %.17g, chip + DRAM %.17g", dir, e, chip + dram);
  EXPECTF(near(testing_json_num(dir, "energy_mj_per_frame"), 1e3 * e),
          "%s: energy_mj_per_frame is not 1000 x energy_j", dir);
  EXPECTF(near(testing_json_num(dir, "power_w"), e / testing_json_num(dir, "seconds")),
          "%s: power_w is not energy_j / seconds", dir);
  EXPECTF(near(testing_json_num(dir, "rays_per_joule"), testing_json_num(dir, "rays_traced") / e),
          "%s: rays_per_joule is not rays_traced / energy_j", dir);
  /* stats.csv carries the same figures. */
  const char *names[] = {"energy_j", "chip_energy_j", "dram_energy_j"};
  for (unsigned i = 0; i < 3; i++) {
    const double c = testing_csv_num(&csv, names[i]), j = testing_json_num(dir, names[i]);
    EXPECTF(near(c, j), "%s: %s is %.17g in stats.csv, %.17g in stats.json", dir, names[i], c, j);
  }
}

int main(void) {
  testing_runf(out, sizeof out, "rm -rf %s && mkdir -p %s", TMP, TMP);
  const char *rungs[] = {"analytic", "fixed", "channel", "banked"};
  const char *policies[] = {"recursive", "packet", "dynamic", "treelet"};
  for (unsigned r = 0; r < 4; r++)
    for (unsigned p = 0; p < 4; p++) check_run(rungs[r], policies[p]);
  return testing_done("test_energy_sums");
}
