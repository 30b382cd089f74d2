/* A cheaper rung's measured error (app/rung_error.h): the lookup of the
 * nearest regime against a hand-made table (inside a band, between bands,
 * outside all, another policy or bound), the compiled-in table against the
 * committed CSV it was generated from, and rtsim run at cheaper rungs on a
 * tiny machine: their stats carry the regime the table gives for their own
 * figures and the energy error measured for their rung and policy (the
 * compiled-in one against its CSV), a banked run carries none. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "app/rung_error.h"
#include "testing.h"

static const struct rung_error_row HAND[] = {
    {"channel", "packet", "-", 0, 0.5, 0, 0.9, 3, -0.02, 0.01, -0.001, 0.002},
    {"channel", "packet", "-", 0.6, INFINITY, 0, 0.9, 2, -0.2, -0.08, 0, 0.01},
    {"channel", "packet", "-", 0, 0.5, 0.9, INFINITY, 4, -0.01, 0.01, 0, 0},
    {"analytic", "recursive", "latency", 0, INFINITY, 0.9, INFINITY, 2, -0.007, -0.003, -0.06, 0},
    {"analytic", "recursive", "bandwidth", 0.6, INFINITY, 0, 0.9, 1, -0.37, -0.37, 0, 0},
};
#define NHAND (unsigned)(sizeof HAND / sizeof HAND[0])

/* Match (rung, policy, bound, dram, core) in HAND: the row expected (-1:
 * none), whether inside it, its distance and whether the run warns. */
static void expect_match(const char *rung, const char *policy, int bound, double dram, double core,
                         int row, bool inside, double distance, bool warn) {
  struct rung_error r;
  rung_error_match_in(&r, HAND, NHAND, rung, policy, bound, dram, core);
  int got = r.row ? (int)(r.row - HAND) : -1;
  EXPECTF(got == row, "%s %s %d at (%g, %g): row %d, expected %d", rung, policy, bound, dram, core,
          got, row);
  EXPECTF(!r.row || (r.inside == inside && fabs(r.distance - distance) < 1e-12),
          "%s %s at (%g, %g): inside %d distance %g, expected %d %g", rung, policy, dram, core,
          r.inside, r.distance, inside, distance);
  EXPECTF(r.warn == warn, "%s %s at (%g, %g): warn %d, expected %d", rung, policy, dram, core,
          r.warn, warn);
  char line[1024];
  rung_error_warning(&r, line, sizeof line);
  EXPECTF((line[0] != '\0') == warn && (!warn || strstr(line, "fidelity=banked")),
          "the warning line: '%s'", line);
  EXPECTF(!warn || strstr(line, r.row ? (inside ? "error above 5%" : "outside every measured")
                                      : "was measured against banked"),
          "the warning says why: '%s'", line);
}

static void test_lookup(void) {
  /* Inside a band: errors within 5% are quiet, above warn. */
  expect_match("channel", "packet", -1, 0.3, 0.5, 0, true, 0, false);
  expect_match("channel", "packet", -1, 0.3, 0.95, 2, true, 0, false);
  expect_match("channel", "packet", -1, 0.8, 0.5, 1, true, 0, true);
  /* Half-open: a band's high end belongs to the next band. */
  expect_match("channel", "packet", -1, 0.6, 0.5, 1, true, 0, true);
  expect_match("channel", "packet", -1, 0.3, 0.9, 2, true, 0, false);
  /* Between bands: the nearer, outside (so it warns), distance in DRAM
   * utilization; on its high end (distance 0) still outside. */
  expect_match("channel", "packet", -1, 0.52, 0.5, 0, false, 0.02, true);
  expect_match("channel", "packet", -1, 0.58, 0.5, 1, false, 0.02, true);
  expect_match("channel", "packet", -1, 0.5, 0.5, 0, false, 0, true);
  /* Outside all: distance summed over both figures. */
  expect_match("channel", "packet", -1, 0.55, 0.95, 2, false, 0.05, true);
  /* Another policy or rung has no regime; analytic's bound picks the row. */
  expect_match("channel", "dynamic", -1, 0.3, 0.5, -1, false, 0, true);
  expect_match("fixed", "packet", -1, 0.3, 0.5, -1, false, 0, true);
  expect_match("analytic", "recursive", 0, 0.3, 0.99, 3, true, 0, true); /* DRAM bytes -6% */
  expect_match("analytic", "recursive", 1, 0.87, 0.5, 4, true, 0, true);
  expect_match("analytic", "recursive", 1, 0.3, 0.99, 4, false, 0.3 + 0.09, true);
  expect_match("analytic", "recursive", -1, 0.3, 0.99, -1, false, 0, true);
}

/* The compiled-in table is the committed CSV, row for row. */
static void test_table_is_csv(void) {
  char *csv = testing_slurp(RTSIM_SOURCE_DIR, RUNG_ERROR_TABLE_PATH, NULL);
  EXPECTF(csv != NULL, "%s unreadable", RUNG_ERROR_TABLE_PATH);
  if (!csv) return;
  unsigned n = 0;
  char *save = NULL;
  char *line = strtok_r(csv, "\n", &save);
  EXPECT(line && !strcmp(line, "rung,policy,bound,dram_utilization_low,dram_utilization_high,"
                               "core_utilization_low,core_utilization_high,points,"
                               "cycles_error_min,cycles_error_max,dram_bytes_error_min,"
                               "dram_bytes_error_max"));
  while ((line = strtok_r(NULL, "\n", &save))) {
    EXPECTF(n < rung_error_table_rows, "the CSV has more rows than the table's %u",
            rung_error_table_rows);
    if (n >= rung_error_table_rows) break;
    const struct rung_error_row *w = &rung_error_table[n++];
    char *f[12], *fs = NULL;
    unsigned k = 0;
    for (char *t = strtok_r(line, ",", &fs); t && k < 12; t = strtok_r(NULL, ",", &fs)) f[k++] = t;
    EXPECTF(k == 12, "CSV row %u: %u fields", n, k);
    if (k < 12) continue;
    const double v[] = {w->dram_low,   w->dram_high,      w->core_low,
                        w->core_high,  w->points,         w->cycles_min,
                        w->cycles_max, w->dram_bytes_min, w->dram_bytes_max};
    bool same = !strcmp(f[0], w->rung) && !strcmp(f[1], w->policy) && !strcmp(f[2], w->bound);
    for (unsigned i = 0; i < 9; i++) same = same && strtod(f[3 + i], NULL) == v[i];
    EXPECTF(same, "CSV row %u (%s %s %s) differs from the compiled table's", n, f[0], f[1], f[2]);
    /* Sane rows: bands ordered, errors ordered, points measured. */
    EXPECTF(w->dram_low < w->dram_high && w->core_low < w->core_high && w->points > 0 &&
                w->cycles_min <= w->cycles_max && w->dram_bytes_min <= w->dram_bytes_max,
            "CSV row %u is not a regime", n);
  }
  EXPECTF(n == rung_error_table_rows, "the CSV has %u rows, the table %u", n,
          rung_error_table_rows);
  EXPECTF(n > 0, "%s measures no regime", RUNG_ERROR_TABLE_PATH);
  free(csv);
  /* Issue 36's run: analytic on grove, recursive, 32 cores and a 1 MiB L2,
   * at its bandwidth bound, was 37% low in cycles and said nothing. */
  struct rung_error r;
  rung_error_match_in(&r, rung_error_table, rung_error_table_rows, "analytic", "recursive", 1,
                      0.948, 0.555);
  EXPECT(r.row && r.inside && r.warn && r.row->cycles_min < -0.3);
}

/* The compiled-in energy errors are RUNG_ENERGY_ERROR_PATH's: each rung and
 * policy's lowest and highest energy_error, over its rows. */
static void test_energy_table_is_csv(void) {
  char *csv = testing_slurp(RTSIM_SOURCE_DIR, RUNG_ENERGY_ERROR_PATH, NULL);
  EXPECTF(csv != NULL, "%s unreadable", RUNG_ENERGY_ERROR_PATH);
  if (!csv) return;
  unsigned seen[16] = {0};
  double lo[16], hi[16];
  char *save = NULL;
  char *line = strtok_r(csv, "\n", &save);
  EXPECT(line && strstr(line, ",rung,") && strstr(line, ",energy_error"));
  while ((line = strtok_r(NULL, "\n", &save))) {
    char *f[12], *fs = NULL;
    unsigned k = 0;
    for (char *t = strtok_r(line, ",", &fs); t && k < 12; t = strtok_r(NULL, ",", &fs)) f[k++] = t;
    EXPECTF(k == 12, "%s: a row of %u fields", RUNG_ENERGY_ERROR_PATH, k);
    if (k < 12) continue;
    unsigned i = 0;
    while (i < rung_energy_error_rows && (strcmp(rung_energy_error_table[i].rung, f[2]) ||
                                          strcmp(rung_energy_error_table[i].policy, f[1])))
      i++;
    EXPECTF(i < rung_energy_error_rows, "%s %s: not in the compiled table", f[2], f[1]);
    if (i >= rung_energy_error_rows || i >= 16) continue;
    const double e = strtod(f[11], NULL);
    lo[i] = seen[i] && lo[i] < e ? lo[i] : e;
    hi[i] = seen[i] && hi[i] > e ? hi[i] : e;
    seen[i]++;
  }
  free(csv);
  for (unsigned i = 0; i < rung_energy_error_rows && i < 16; i++) {
    const struct rung_energy_error *w = &rung_energy_error_table[i];
    EXPECTF(seen[i] == w->points && lo[i] == w->min && hi[i] == w->max,
            "%s %s: %u rows, %g to %g in the CSV; the table says %u, %g to %g", w->rung, w->policy,
            seen[i], seen[i] ? lo[i] : 0, seen[i] ? hi[i] : 0, w->points, w->min, w->max);
  }
}

/* rtsim run on tiny.yaml at rung (and more), into dir; the exit code, its
 * stderr and stdout in out. */
static int run(const char *rung, const char *dir, char *out, unsigned cap) {
  int rc = testing_runf(out, cap,
                        "%s run %s/configs/tiny.yaml %s/scenes/small/room.yaml --width 16 "
                        "--height 16 --set fidelity=%s -o %s",
                        RTSIM_BINARY, RTSIM_SOURCE_DIR, RTSIM_SOURCE_DIR, rung, dir);
  EXPECTF(rc == 0, "%s: exit %d: %s", rung, rc, out);
  return rc;
}

static void test_run(void) {
  static char out[1 << 14];
  char banked[2048];
  snprintf(banked, sizeof banked, "%s/rung_error_banked", RTSIM_TMP);
  if (run("banked", banked, out, sizeof out)) return;
  EXPECTF(!strstr(out, "warning"), "banked warned: %s", out);
  char *j = testing_slurp(banked, "stats.json", NULL);
  EXPECT(j && !strstr(j, "\"rung_"));
  free(j);
  /* The banked DRAM's peak, bytes a cycle, from the banked run's figures. */
  const double peak = testing_json_num(banked, "dram_bytes") / testing_json_num(banked, "cycles") /
                      testing_json_num(banked, "dram_utilization");
  EXPECT(peak > 0);
  static const char *const rungs[] = {"analytic", "fixed", "channel"};
  for (unsigned i = 0; i < 3; i++) {
    char dir[2048];
    snprintf(dir, sizeof dir, "%s/rung_error_%s", RTSIM_TMP, rungs[i]);
    if (run(rungs[i], dir, out, sizeof out)) continue;
    const double cycles = testing_json_num(dir, "cycles");
    const double bytes =
        testing_json_num(dir, "dram_read_bytes") + testing_json_num(dir, "dram_write_bytes");
    const double core = testing_json_num(dir, "core_utilization");
    const double util = testing_json_num(dir, "rung_dram_utilization");
    EXPECTF(fabs(util - bytes / cycles / peak) <= 1e-9 * util, "%s: rung_dram_utilization %g",
            rungs[i], util);
    int bound = -1;
    if (i == 0)
      bound = testing_json_num(dir, "analytic_bandwidth_bound_cycles") >
              testing_json_num(dir, "analytic_latency_bound_cycles");
    EXPECTF(i ? isnan(testing_json_num(dir, "rung_bandwidth_bound"))
              : testing_json_num(dir, "rung_bandwidth_bound") == bound,
            "%s: rung_bandwidth_bound", rungs[i]);
    /* What the table says for the run's own figures, in its stats. */
    struct rung_error r;
    rung_error_match_in(&r, rung_error_table, rung_error_table_rows, rungs[i], "recursive", bound,
                        util, core);
    EXPECTF(r.row, "%s recursive: no regime measured", rungs[i]);
    EXPECTF(r.energy && testing_json_num(dir, "rung_dram_energy_error_min") == r.energy->min &&
                testing_json_num(dir, "rung_dram_energy_error_max") == r.energy->max,
            "%s: the energy error measured for its rung and policy", rungs[i]);
    EXPECTF(testing_json_num(dir, "rung_error_warning") == r.warn, "%s: rung_error_warning",
            rungs[i]);
    EXPECTF((strstr(out, "rtsim run: warning: fidelity ") != NULL) == r.warn,
            "%s: the warning line on stderr iff warned: %s", rungs[i], out);
    if (r.row) {
      EXPECT(testing_json_num(dir, "rung_regime_points") == r.row->points);
      EXPECT(testing_json_num(dir, "rung_regime_dram_utilization_low") == r.row->dram_low);
      EXPECT(testing_json_num(dir, "rung_regime_core_utilization_low") == r.row->core_low);
      EXPECT(testing_json_num(dir, "rung_cycles_error_min") == r.row->cycles_min);
      EXPECT(testing_json_num(dir, "rung_cycles_error_max") == r.row->cycles_max);
      EXPECT(testing_json_num(dir, "rung_dram_bytes_error_min") == r.row->dram_bytes_min);
      EXPECT(testing_json_num(dir, "rung_dram_bytes_error_max") == r.row->dram_bytes_max);
      EXPECT(fabs(testing_json_num(dir, "rung_regime_distance") - r.distance) < 1e-12);
    }
    /* stats.csv has the same columns. */
    char *csv = testing_slurp(dir, "stats.csv", NULL);
    EXPECTF(csv && strstr(csv, ",rung_dram_utilization,") && strstr(csv, ",rung_error_warning"),
            "%s: stats.csv lacks the rung columns", rungs[i]);
    free(csv);
  }
}

int main(void) {
  test_lookup();
  test_table_is_csv();
  test_energy_table_is_csv();
  test_run();
  return testing_done("test_rung_error");
}
