/* The spot-check (docs/fidelity-and-sampling.md): `rtsim run --spot-check F`
 * at a cheaper rung writes the estimates of a banked sample of the same point,
 * the very numbers `--set fidelity=banked --set sample.fraction=F` writes, and
 * the cheap run's errors against them with intervals computed from theirs;
 * what cannot be spot-checked is refused before anything runs. */
#include <math.h>
#include <string.h>
#include <unistd.h>

#include "testing.h"

static char out[1 << 14];

#define TMP RTSIM_TMP "/spot"

/* rtsim run configs/tiny.yaml on the small grove at 32 x 32 with more options
 * into TMP/dir; the exit code. */
static int run(const char *more, const char *dir) {
  return testing_runf(out, sizeof out,
                      "%s run %s/configs/tiny.yaml %s/scenes/small/grove.yaml --width 32 "
                      "--height 32 --rays primary,shadow %s -o %s/%s 2>&1",
                      RTSIM_BINARY, RTSIM_SOURCE_DIR, RTSIM_SOURCE_DIR, more, TMP, dir);
}

static double num(const char *dir, const char *name) {
  char d[256];
  snprintf(d, sizeof d, "%s/%s", TMP, dir);
  return testing_json_num(d, name);
}

/* cheap / est - 1 and the ends from the interval, as written. */
static void expect_error(const char *cheap_name, const char *est_name, const char *err_name) {
  char n[128];
  const double cheap = num("spot", cheap_name), est = num("spot", est_name);
  snprintf(n, sizeof n, "%s_ci95_low", est_name);
  const double lo = num("spot", n);
  snprintf(n, sizeof n, "%s_ci95_high", est_name);
  const double hi = num("spot", n);
  const double err = num("spot", err_name);
  snprintf(n, sizeof n, "%s_ci95_low", err_name);
  const double elo = num("spot", n);
  snprintf(n, sizeof n, "%s_ci95_high", err_name);
  const double ehi = num("spot", n);
  EXPECTF(err == cheap / est - 1, "%s %.17g, want %.17g", err_name, err, cheap / est - 1);
  EXPECTF(elo == cheap / hi - 1 && ehi == cheap / lo - 1, "%s [%g, %g], want [%g, %g]", err_name,
          elo, ehi, cheap / hi - 1, cheap / lo - 1);
  EXPECTF(lo <= est && est <= hi && elo <= err && err <= ehi, "%s: intervals out of order",
          err_name);
}

int main(void) {
  testing_runf(out, sizeof out, "rm -rf %s && mkdir -p %s", TMP, TMP);
  /* tiny.yaml is at fidelity channel: the cheap run with its spot-check, and
   * the banked sample alone. */
  int rc = run("--spot-check 0.25", "spot");
  EXPECTF(rc == 0 && strstr(out, "spot_check: this rung against a banked sample"), "%d: %s", rc,
          out);
  rc = run("--set fidelity=banked --set sample.fraction=0.25", "banked");
  EXPECTF(rc == 0, "%d: %s", rc, out);
  /* The same sample, so the same estimates, bit for bit. */
  static const char *const SAME[][2] = {
      {"spot_banked_cycles", "cycles"},
      {"spot_banked_cycles_ci95_low", "cycles_ci95_low"},
      {"spot_banked_cycles_ci95_high", "cycles_ci95_high"},
      {"spot_banked_dram_bytes", "dram_bytes"},
      {"spot_banked_dram_bytes_ci95_low", "dram_bytes_ci95_low"},
      {"spot_banked_dram_bytes_ci95_high", "dram_bytes_ci95_high"},
  };
  for (size_t i = 0; i < sizeof SAME / sizeof SAME[0]; i++)
    EXPECTF(num("spot", SAME[i][0]) == num("banked", SAME[i][1]), "%s %.17g, the sample's %s %.17g",
            SAME[i][0], num("spot", SAME[i][0]), SAME[i][1], num("banked", SAME[i][1]));
  EXPECT(num("spot", "spot_check_fraction") == 0.25);
  expect_error("cycles", "spot_banked_cycles", "spot_cycles_error");
  expect_error("dram_bytes", "spot_banked_dram_bytes", "spot_dram_bytes_error");
  /* A run without the option writes none of it. */
  rc = run("", "plain");
  EXPECT(rc == 0 && isnan(num("plain", "spot_cycles_error")));

  /* Refused before anything is written: exit 2, one message, no OUTDIR. */
  /* The options, and what the message must hold. */
  static const char *const bad[][2] = {
      {"--spot-check 0.25 --set fidelity=banked", "at fidelity banked already"},
      {"--spot-check 0.25 --policy dynamic", "sample"},
      {"--spot-check 0.25 --set sample.fraction=0.5", "the run is sampled"},
      {"--spot-check 0.01", "--spot-check 0.01"},
      {"--spot-check 1", "a fraction above 0 and below 1"},
      {"--spot-check x", "a fraction above 0 and below 1"},
  };
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    rc = run(bad[i][0], "bad");
    EXPECTF(rc == 2 && strstr(out, bad[i][1]), "'%s': %d: %s", bad[i][0], rc, out);
    char d[256];
    snprintf(d, sizeof d, "%s/bad", TMP);
    EXPECTF(access(d, F_OK) != 0, "'%s' left %s", bad[i][0], d);
  }
  return testing_done("test_spot_check");
}
