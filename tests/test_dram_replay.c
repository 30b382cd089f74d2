/* rtsim dram-replay against oracles: a fixed latency, the channel and the
 * banked DDR4 level worked out by hand; a round trip through rtsim run's
 * --dram-trace, which must give every request the cycles the run gave it; the
 * three trace formats, converted with the manual's awk commands, giving the
 * same numbers; and every bad input one file:line:col message and exit 2.
 * Fixtures live in tests/data/dram_traces. */
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "testing.h"

#define DT RTSIM_TEST_DATA "/dram_traces/"
#define SRC RTSIM_SOURCE_DIR "/"
#define TMP RTSIM_TMP "/dram_replay_"

/* The manual's conversions of an rtsim trace (docs/dram-traces.md). */
#define AWK_DRAMSIM3 "awk '!/^#/ && NF { print $1, $2, $3 }'"
#define AWK_RAMULATOR "awk '!/^#/ && NF { print $1, substr($2, 1, 1) }'"

/* ---- helpers ---- */

static int count_lines(const char *s) {
  int n = 0;
  for (; *s; s++) n += *s == '\n';
  return n;
}

/* rtsim dram-replay ARGS, stdout into csv; stderr into msg. Returns the exit code. */
static int replay(const char *args, const char *csv, char *msg, unsigned cap) {
  char cmd[4096];
  snprintf(cmd, sizeof cmd, "(%s dram-replay %s > %s)", RTSIM_BINARY, args, csv);
  return testing_run(cmd, msg, cap);
}

/* Expect column `name` of c to read `want` exactly. */
#define EXPECT_COL(c, name, want)                                                                  \
  EXPECTF(!strcmp(testing_csv_get(c, name), want), "%s: got %s, want %s", name,                    \
          testing_csv_get(c, name), want)

/* A per-request file: index arrival taken done. */
struct per {
  uint64_t idx, arrival, taken, done;
};

/* Rows of a per-request file (caller frees); *n their count. */
static struct per *per_load(const char *path, size_t *n) {
  *n = 0;
  FILE *f = fopen(path, "r");
  if (!f) return NULL;
  size_t cap = 64;
  struct per *r = malloc(cap * sizeof *r);
  char line[256];
  while (fgets(line, sizeof line, f)) {
    if (line[0] == '#') continue;
    if (*n == cap) r = realloc(r, (cap *= 2) * sizeof *r);
    struct per *p = &r[*n];
    if (sscanf(line, "%" SCNu64 " %" SCNu64 " %" SCNu64 " %" SCNu64, &p->idx, &p->arrival,
               &p->taken, &p->done) == 4)
      (*n)++;
  }
  fclose(f);
  return r;
}

/* The whole of a small file as a string (caller frees); NULL if unreadable. */
static char *slurp(const char *path) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  size_t cap = 1 << 16, n = 0;
  char *s = malloc(cap);
  size_t k;
  while ((k = fread(s + n, 1, cap - n - 1, f)) > 0) {
    n += k;
    if (n + 1 == cap) s = realloc(s, cap *= 2);
  }
  s[n] = '\0';
  fclose(f);
  return s;
}

/* ---- 1. fixed latency ---- */

static void test_fixed(void) {
  const char *csv = TMP "fixed.csv", *perf = TMP "fixed.per";
  char msg[4096];
  int rc = replay(SRC "configs/tiny.yaml " DT "fixed.trace --set fidelity=fixed "
                      "--set dram.latency=100 --per-request " TMP "fixed.per",
                  csv, msg, sizeof msg);
  EXPECTF(rc == 0, "exit %d: %s", rc, msg);
  static struct testing_csv c;
  EXPECT(testing_csv_load(csv, &c));
  EXPECT_COL(&c, "trace_format", "rtsim");
  EXPECT_COL(&c, "fidelity", "fixed");
  EXPECT_COL(&c, "requests", "5");
  EXPECT_COL(&c, "reads", "4");
  EXPECT_COL(&c, "writes", "1");
  /* Every request is served 100 cycles after it arrives; nothing is refused. */
  static const char *const hundred[] = {"read_latency_mean",      "read_latency_p50",
                                        "read_latency_p95",       "read_latency_p99",
                                        "read_latency_max",       "read_latency_taken_mean",
                                        "read_latency_taken_max", "write_latency_mean"};
  for (size_t i = 0; i < sizeof hundred / sizeof hundred[0]; i++) EXPECT_COL(&c, hundred[i], "100");
  EXPECT_COL(&c, "refused_wait_mean", "0");
  /* The span: the last arrival (1000) + 100 - the first (5). */
  EXPECT_COL(&c, "first_arrival_cycle", "5");
  EXPECT_COL(&c, "last_done_cycle", "1100");
  EXPECT_COL(&c, "cycles", "1095");
  EXPECTF(testing_csv_num(&c, "bytes_per_cycle") == 5 * 64 / 1095.0, "bytes_per_cycle %s",
          testing_csv_get(&c, "bytes_per_cycle"));
  /* tiny.yaml: 1 GHz core, 1200 MHz DRAM: 100 core cycles are 120 DRAM cycles. */
  EXPECT_COL(&c, "read_latency_mean_dram_cycles", "120");
  EXPECT_COL(&c, "read_latency_p99_dram_cycles", "120");
  size_t n;
  struct per *p = per_load(perf, &n);
  EXPECT(n == 5);
  static const uint64_t arrival[5] = {5, 5, 17, 40, 1000};
  for (size_t i = 0; i < n && i < 5; i++) {
    EXPECT(p[i].idx == i);
    EXPECT(p[i].arrival == arrival[i] && p[i].taken == arrival[i]);
    EXPECT(p[i].done == arrival[i] + 100);
  }
  free(p);
}

/* ---- 2. the channel ---- */

/* bytes_per_cycle 64: a 64-byte transfer takes one cycle; latency 50 after
 * it for a read, none for a write; the FIFO holds 2 requests not yet started.
 * All five arrive in cycle 10. The first starts at once (10-11, done 61), so
 * its place is free again in cycle 10: the second (11-12, 62) and the third
 * (12-13, 63) are taken in cycle 10 too. The fourth finds the FIFO full
 * (second and third waiting) until the second starts in cycle 11: taken 11,
 * transfer 13-14, done 64. The fifth, a write, waits for the third to start
 * in cycle 12: taken 12, transfer 14-15, written 15. */
static void test_channel(void) {
  const char *csv = TMP "channel.csv", *perf = TMP "channel.per";
  char msg[4096];
  int rc = replay(SRC "configs/tiny.yaml " DT "channel.trace --set fidelity=channel "
                      "--set dram.bytes_per_cycle=64 --set dram.latency=50 "
                      "--set dram.queue_depth=2 --per-request " TMP "channel.per",
                  csv, msg, sizeof msg);
  EXPECTF(rc == 0, "exit %d: %s", rc, msg);
  size_t n;
  struct per *p = per_load(perf, &n);
  static const struct per want[5] = {
      {0, 10, 10, 61}, {1, 10, 10, 62}, {2, 10, 10, 63}, {3, 10, 11, 64}, {4, 10, 12, 15}};
  EXPECT(n == 5);
  for (size_t i = 0; i < n && i < 5; i++)
    EXPECTF(!memcmp(&p[i], &want[i], sizeof want[i]),
            "request %zu: got %" PRIu64 " %" PRIu64 " %" PRIu64 ", want %" PRIu64 " %" PRIu64
            " %" PRIu64,
            i, p[i].arrival, p[i].taken, p[i].done, want[i].arrival, want[i].taken, want[i].done);
  free(p);
  static struct testing_csv c;
  EXPECT(testing_csv_load(csv, &c));
  /* Reads from arrival: 51, 52, 53, 54; from taken: 51, 52, 53, 53. */
  EXPECT_COL(&c, "read_latency_mean", "52.5");
  EXPECT_COL(&c, "read_latency_max", "54");
  EXPECT_COL(&c, "read_latency_taken_mean", "52.25");
  EXPECT_COL(&c, "read_latency_taken_max", "53");
  EXPECT_COL(&c, "write_latency_mean", "5");
  /* Waits to be taken: 0, 0, 0, 1, 2. */
  EXPECT_COL(&c, "refused_wait_mean", "0.6");
  EXPECT_COL(&c, "cycles", "54");
  EXPECT_COL(&c, "dram_fifo_length_max", "2");
}

/* ---- 3. banked DDR4 ---- */

/* configs/dram/ddr4-2400.yaml at clock_ghz 1.2: core and DRAM cycles are one.
 * A read to an idle bank: its first command controller_cycles = 2 after it is
 * taken, ACT in cycle 2, RD tRCD = 17 later, its last beat tCL + BL/2 = 17 + 4
 * after that: 40. A read to the same (open) row in cycle 1000 (before the
 * first refresh, due at tREFI / ranks = 4680): RD at 1002, done tCL + BL/2 =
 * 21 later, 1023. */
static void test_banked(void) {
  const char *csv = TMP "banked.csv", *perf = TMP "banked.per";
  char msg[4096];
  int rc = replay(SRC "configs/dram/ddr4-2400.yaml " DT "banked.trace --set clock_ghz=1.2 "
                      "--per-request " TMP "banked.per",
                  csv, msg, sizeof msg);
  EXPECTF(rc == 0, "exit %d: %s", rc, msg);
  size_t n;
  struct per *p = per_load(perf, &n);
  EXPECT(n == 2);
  if (n == 2) {
    EXPECT(p[0].arrival == 0 && p[0].taken == 0 && p[0].done == 40);
    EXPECT(p[1].arrival == 1000 && p[1].taken == 1000 && p[1].done == 1023);
  }
  free(p);
  static struct testing_csv c;
  EXPECT(testing_csv_load(csv, &c));
  EXPECT_COL(&c, "trace_format", "dramsim3");
  EXPECT_COL(&c, "fidelity", "banked");
  EXPECT_COL(&c, "read_latency_max", "40");
  EXPECT_COL(&c, "read_latency_p50", "23");
  EXPECT_COL(&c, "read_latency_mean", "31.5");
  EXPECT_COL(&c, "read_latency_mean_dram_cycles", "31.5");
  EXPECT_COL(&c, "dram_row_misses", "1");
  EXPECT_COL(&c, "dram_row_hits", "1");
  EXPECT_COL(&c, "dram_row_conflicts", "0");
  EXPECT_COL(&c, "cycles", "1023");
  /* Energy (DRAMsim3's model, the preset's currents: 8 x8 devices at 1.2 V,
   * tCK 1/1.2 ns, so 8 pJ a mA-cycle): one ACT 8 (48 x 56 - 43 x 39 - 34 x 17)
   * = 3464 pJ, two RDs 2 x 8 (135 - 43) 4 = 5888 pJ; the level ends at DRAM
   * cycle 1024 (the last answer's, 1023, handled): rank 0 active from its ACT
   * at 2, 1022 x 8 x 43 = 351568 pJ; precharged rank 0's first 2 cycles and
   * rank 1's 1024, 1026 x 8 x 34 = 279072 pJ; no refresh falls due (4680). */
  const double part[][2] = {{testing_csv_num(&c, "dram_energy_activate_j"), 3464e-12},
                            {testing_csv_num(&c, "dram_energy_read_j"), 5888e-12},
                            {testing_csv_num(&c, "dram_energy_write_j"), 0},
                            {testing_csv_num(&c, "dram_energy_refresh_j"), 0},
                            {testing_csv_num(&c, "dram_energy_active_standby_j"), 351568e-12},
                            {testing_csv_num(&c, "dram_energy_precharge_standby_j"), 279072e-12},
                            {testing_csv_num(&c, "dram_energy_j"), 639992e-12}};
  for (unsigned i = 0; i < sizeof part / sizeof part[0]; i++)
    EXPECTF(fabs(part[i][0] - part[i][1]) <= 1e-12 * part[i][1],
            "energy part %u: %.15g J, want %.15g", i, part[i][0], part[i][1]);
}

/* The same preset's idle write drain, honoured by dram-replay (--set
 * dram.idle_drain_cycles): two writes to one row arrive after DRAM cycles 100
 * and 101 (served, posted, at 102 and 103). Drained after 1000 idle cycles:
 * the drain starts at the end of 1101, ACT 1102, WR 1119
 * (tRCD 17) and 1125 (tCCD_L 6), the level's last cycle; it ends at 1126:
 * rank 0 active 1102 to 1126, 24 x 344 = 8256 pJ; precharged rank 0's first
 * 1102 cycles and rank 1's 1126, 2228 x 272 = 606016 pJ; ACT 3464 pJ, two WRs
 * 2 x 8 (123 - 43) 4 = 5120 pJ. Never drained (0, the preset's and
 * DRAMsim3's): no command,
 * the level ends after the second write is served (cycle 103 handled: 104),
 * 2 x 104 x 272 = 56576 pJ precharged, and both writes left. */
static void test_banked_idle_drain(void) {
  const char *csv = TMP "idle.csv";
  static const struct {
    const char *set, *left;
    double act, wr, act_stb, pre_stb;
  } runs[] = {{"--set dram.idle_drain_cycles=1000", "0", 3464e-12, 5120e-12, 8256e-12, 606016e-12},
              {"", "2", 0, 0, 0, 56576e-12}};
  for (unsigned r = 0; r < 2; r++) {
    char args[1024], msg[4096];
    snprintf(args, sizeof args,
             SRC "configs/dram/ddr4-2400.yaml " DT "idle_writes.trace --set clock_ghz=1.2 %s",
             runs[r].set);
    int rc = replay(args, csv, msg, sizeof msg);
    EXPECTF(rc == 0, "exit %d: %s", rc, msg);
    static struct testing_csv c;
    EXPECT(testing_csv_load(csv, &c));
    EXPECT_COL(&c, "writes", "2");
    EXPECT_COL(&c, "dram_writes_left", runs[r].left);
    const double part[][2] = {
        {testing_csv_num(&c, "dram_energy_activate_j"), runs[r].act},
        {testing_csv_num(&c, "dram_energy_read_j"), 0},
        {testing_csv_num(&c, "dram_energy_write_j"), runs[r].wr},
        {testing_csv_num(&c, "dram_energy_refresh_j"), 0},
        {testing_csv_num(&c, "dram_energy_active_standby_j"), runs[r].act_stb},
        {testing_csv_num(&c, "dram_energy_precharge_standby_j"), runs[r].pre_stb}};
    for (unsigned i = 0; i < sizeof part / sizeof part[0]; i++)
      EXPECTF(fabs(part[i][0] - part[i][1]) <= 1e-12 * part[i][1],
              "idle drain '%s', energy part %u: %.15g J, want %.15g", runs[r].set, i, part[i][0],
              part[i][1]);
  }
}

/* ---- 4. round trip through rtsim run ---- */

/* The trace records each request at the cycle the DRAM took it (a request
 * the run's DRAM refused waited at the L2, and appears when taken), so
 * replaying it offers the DRAM the same requests at the same cycles: each
 * must be taken on arrival and served in the cycle the run served it. */
static void test_round_trip(void) {
  const char *dir = TMP "run", *trace = TMP "run.trace", *csv = TMP "run.csv",
             *perf = TMP "run.per";
  char cmd[4096], msg[8192];
  snprintf(cmd, sizeof cmd,
           "%s run " SRC "configs/tiny.yaml " SRC "scenes/small/room.yaml --width 16 --height 12 "
           "--set fidelity=banked --dram-trace %s -o %s > /dev/null",
           RTSIM_BINARY, trace, dir);
  int rc = testing_run(cmd, msg, sizeof msg);
  EXPECTF(rc == 0, "run: exit %d: %s", rc, msg);
  rc = replay(SRC "configs/tiny.yaml " TMP "run.trace --set fidelity=banked --per-request " TMP
                  "run.per",
              csv, msg, sizeof msg);
  EXPECTF(rc == 0, "replay: exit %d: %s", rc, msg);

  size_t n;
  struct per *p = per_load(perf, &n);
  FILE *f = fopen(trace, "r");
  EXPECT(f != NULL);
  char line[512];
  size_t i = 0, bad = 0, reads = 0;
  uint64_t sum = 0, max = 0;
  while (f && fgets(line, sizeof line, f)) {
    if (line[0] == '#') continue;
    char op[8];
    uint64_t addr, dram_at, at, done;
    if (sscanf(line, "%" SCNx64 " %7s %" SCNu64 " %" SCNu64 " %" SCNu64, &addr, op, &dram_at, &at,
               &done) != 5) {
      bad++;
      continue;
    }
    if (!strcmp(op, "READ")) {
      reads++;
      sum += done - at;
      if (done - at > max) max = done - at;
    }
    if (i >= n || p[i].arrival != at || p[i].taken != at || p[i].done != done) {
      if (bad < 5)
        fprintf(stderr,
                "request %zu: run %" PRIu64 " -> %" PRIu64 ", replay %" PRIu64 " %" PRIu64
                " -> %" PRIu64 "\n",
                i, at, done, i < n ? p[i].arrival : 0, i < n ? p[i].taken : 0,
                i < n ? p[i].done : 0);
      bad++;
    }
    i++;
  }
  if (f) fclose(f);
  free(p);
  EXPECTF(bad == 0, "%zu of %zu requests differ", bad, i);
  EXPECTF(i == n && n > 10000, "%zu requests in the trace, %zu replayed", i, n);

  static struct testing_csv c, run;
  EXPECT(testing_csv_load(csv, &c));
  char want[64];
  snprintf(want, sizeof want, "%zu", n);
  EXPECT_COL(&c, "requests", want);
  /* The run's figures: from the trace, and from its stats.csv. */
  EXPECTF(testing_csv_num(&c, "read_latency_taken_mean") == (double)sum / (double)reads,
          "taken mean %s, run's %.17g", testing_csv_get(&c, "read_latency_taken_mean"),
          (double)sum / (double)reads);
  snprintf(want, sizeof want, "%" PRIu64, max);
  EXPECT_COL(&c, "read_latency_taken_max", want);
  EXPECT_COL(&c, "refused_wait_mean", "0");
  EXPECT(testing_csv_load(TMP "run/stats.csv", &run));
  EXPECT_COL(&c, "read_latency_taken_mean", testing_csv_get(&run, "dram_read_latency_mean"));
  EXPECT_COL(&c, "read_latency_taken_max", testing_csv_get(&run, "dram_read_latency_max"));
  EXPECT_COL(&c, "reads", testing_csv_get(&run, "dram_reads"));
  EXPECT_COL(&c, "writes", testing_csv_get(&run, "dram_writes"));

  /* Deterministic: the same inputs give the same bytes. */
  rc = replay(SRC "configs/tiny.yaml " TMP "run.trace --set fidelity=banked --per-request " TMP
                  "run2.per",
              TMP "run2.csv", msg, sizeof msg);
  EXPECT(rc == 0);
  char *a = slurp(csv), *b = slurp(TMP "run2.csv"), *pa = slurp(perf), *pb = slurp(TMP "run2.per");
  EXPECT(a && b && !strcmp(a, b));
  EXPECT(pa && pb && !strcmp(pa, pb));
  free(a);
  free(b);
  free(pa);
  free(pb);
}

/* ---- 5. three formats ---- */

/* mixed.trace (rtsim's format, one request a cycle at equal clocks, so
 * Ramulator's one request a DRAM cycle says the same) converted with the
 * manual's commands (docs/dram-traces.md): all three give the same row (but for the trace's name
 * and format) and the same cycles for every request. */
static void test_formats(void) {
  char *readme = slurp(SRC "docs/dram-traces.md");
  EXPECTF(readme && strstr(readme, AWK_DRAMSIM3 " run.trace > dramsim3.trace"),
          "docs/dram-traces.md lacks: %s", AWK_DRAMSIM3);
  EXPECTF(readme && strstr(readme, AWK_RAMULATOR " run.trace > ramulator.trace"),
          "docs/dram-traces.md lacks: %s", AWK_RAMULATOR);
  free(readme);

  char msg[4096];
  int rc =
      testing_run(AWK_DRAMSIM3 " " DT "mixed.trace > " TMP "mixed_dramsim3.trace && " AWK_RAMULATOR
                               " " DT "mixed.trace > " TMP "mixed_ramulator.trace",
                  msg, sizeof msg);
  EXPECTF(rc == 0, "awk: exit %d: %s", rc, msg);
  static const char *const name[3] = {"rtsim", "dramsim3", "ramulator"};
  static const char *const trace[3] = {DT "mixed.trace", TMP "mixed_dramsim3.trace",
                                       TMP "mixed_ramulator.trace"};
  static struct testing_csv c[3];
  char *per[3];
  for (int k = 0; k < 3; k++) {
    char args[2048], csv[1024], perf[1024];
    snprintf(csv, sizeof csv, TMP "mixed_%s.csv", name[k]);
    snprintf(perf, sizeof perf, TMP "mixed_%s.per", name[k]);
    snprintf(args, sizeof args,
             SRC "configs/dram/ddr4-2400.yaml %s --set clock_ghz=1.2 --per-request %s", trace[k],
             perf);
    rc = replay(args, csv, msg, sizeof msg);
    EXPECTF(rc == 0, "%s: exit %d: %s", name[k], rc, msg);
    EXPECT(testing_csv_load(csv, &c[k]));
    EXPECT_COL(&c[k], "trace_format", name[k]);
    per[k] = slurp(perf);
  }
  EXPECT_COL(&c[0], "requests", "256");
  /* The DRAM's queues fill: requests wait to be taken. */
  EXPECTF(testing_csv_num(&c[0], "refused_wait_mean") > 100, "refused_wait_mean %s",
          testing_csv_get(&c[0], "refused_wait_mean"));
  for (int k = 1; k < 3; k++) {
    EXPECT(c[k].n == c[0].n);
    for (int i = 0; i < c[0].n && i < c[k].n; i++) {
      if (!strcmp(c[0].name[i], "trace") || !strcmp(c[0].name[i], "trace_format")) continue;
      EXPECTF(!strcmp(c[0].name[i], c[k].name[i]) && !strcmp(c[0].value[i], c[k].value[i]),
              "%s: %s = %s, rtsim's %s = %s", name[k], c[k].name[i], c[k].value[i], c[0].name[i],
              c[0].value[i]);
    }
    EXPECTF(per[0] && per[k] && !strcmp(per[0], per[k]), "%s: per-request files differ", name[k]);
  }
  for (int k = 0; k < 3; k++) free(per[k]);

  /* Unequal clocks (tiny.yaml: 1 GHz core, 1200 MHz DRAM): DRAM cycle d
   * arrives in core cycle ceil(d / 1.2). */
  static const struct {
    const char *file;
    uint64_t arrival[8];
    size_t n;
  } clocks[] = {{"clock.trace", {9, 10, 11}, 3},
                {"clock_ramulator.trace", {0, 1, 2, 3, 4, 5, 5}, 7}};
  for (size_t k = 0; k < 2; k++) {
    char args[2048];
    snprintf(args, sizeof args,
             SRC "configs/tiny.yaml " DT "%s --set fidelity=fixed --per-request " TMP "clock.per",
             clocks[k].file);
    rc = replay(args, TMP "clock.csv", msg, sizeof msg);
    EXPECTF(rc == 0, "%s: exit %d: %s", clocks[k].file, rc, msg);
    size_t n;
    struct per *p = per_load(TMP "clock.per", &n);
    EXPECT(n == clocks[k].n);
    for (size_t i = 0; i < n && i < clocks[k].n; i++)
      EXPECTF(p[i].arrival == clocks[k].arrival[i],
              "%s: request %zu arrives in %" PRIu64 ", want %" PRIu64, clocks[k].file, i,
              p[i].arrival, clocks[k].arrival[i]);
    free(p);
  }
}

/* ---- 6. bad inputs ---- */

static void test_bad(void) {
  static const struct {
    const char *args, *want;
  } cases[] = {
      {DT "bad_op.trace", "bad_op.trace:3:6: error: operation: unknown (got 'RD', expected READ, "
                          "WRITE, R or W)"},
      {DT "bad_address.trace", "bad_address.trace:2:1: error: address: not a number (got "
                               "'0x12g4', expected 0x and hexadecimal digits, or decimal digits"},
      {DT "bad_decreasing.trace", "bad_decreasing.trace:3:11: error: arrival DRAM cycle: earlier "
                                  "than the request before (got 9, expected at least 10)"},
      {DT "bad_few_fields.trace", "bad_few_fields.trace:2:7: error: too few fields (got 1, "
                                  "expected 2 (0xADDR R|W), 3"},
      {DT "bad_four_fields.trace", "bad_four_fields.trace:2:12: error: wrong number of fields "
                                   "(got 4, expected 2"},
      {DT "bad_mixed_formats.trace", "bad_mixed_formats.trace:3:7: error: wrong number of fields "
                                     "(got 2, expected 3 as on line 2"},
      {DT "bad_cycle.trace", "bad_cycle.trace:2:13: error: arrival cycle: not a cycle (got '-4', "
                             "expected a whole number from 0 to 1099511627776)"},
      {DT "bad_long_line.trace", "bad_long_line.trace:2:4097: error: line too long (got more "
                                 "than 4096 bytes, expected at most 4096)"},
      {DT "bad_refresh_span.trace --set fidelity=banked",
       "bad_refresh_span.trace:5:11: error: arrival DRAM cycle: too late for the replay (got DRAM "
       "cycle 4907335681, expected at most 4907335680: the DRAM refreshes every tREFI / ranks = "
       "4680 DRAM cycles"},
      {DT "empty.trace", "empty.trace: error: no request in the trace"},
      {DT "no_such.trace", "no_such.trace: error: cannot open: No such file or directory"},
      {DT "fixed.trace --set fidelity=dimm",
       "--set fidelity=dimm: error: fidelity: unknown value (got 'dimm', expected one of: "
       "analytic, fixed, channel, banked)"},
      {DT "fixed.trace --set dram.model=fixed",
       "--set dram.model=fixed: error: dram.model: renamed to fidelity"},
      {DT "fixed.trace --set fidelity=analytic",
       "--set fidelity=analytic: error: fidelity: analytic has no DRAM to replay a trace on"},
      {DT "fixed.trace --set dram.latency=-1", "--set dram.latency=-1: error: dram.latency"},
  };
  const char *perf = TMP "bad.per";
  char args[2048], msg[8192];
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    unlink(perf);
    snprintf(args, sizeof args, SRC "configs/tiny.yaml %s --per-request %s", cases[i].args, perf);
    int rc = replay(args, TMP "bad.csv", msg, sizeof msg);
    EXPECTF(rc == 2, "%s: exit %d: %s", cases[i].args, rc, msg);
    EXPECTF(strstr(msg, cases[i].want) != NULL, "%s: got '%s', want '%s'", cases[i].args, msg,
            cases[i].want);
    EXPECTF(count_lines(msg) == 1, "%s: expected one line, got: %s", cases[i].args, msg);
    EXPECTF(access(perf, F_OK) != 0 && testing_temps_of(perf) == 0,
            "%s: per-request file or temporary left behind", cases[i].args);
    char *out = slurp(TMP "bad.csv");
    EXPECTF(out && !out[0], "%s: output on stdout: %s", cases[i].args, out ? out : "(none)");
    free(out);
  }

  /* A banked replay steps through every refresh: the trace that reaches the
   * last DRAM cycle allowed replays (2^20 refreshes, a fraction of a second),
   * and without refresh, or at the channel rung, so does a later one. */
  static const char *const fine[] = {"refresh_span.trace --set fidelity=banked",
                                     "bad_refresh_span.trace --set fidelity=banked "
                                     "--set dram.tREFI=0",
                                     "bad_refresh_span.trace"};
  for (size_t i = 0; i < sizeof fine / sizeof fine[0]; i++) {
    snprintf(args, sizeof args, SRC "configs/tiny.yaml " DT "%s", fine[i]);
    int rc = replay(args, TMP "span.csv", msg, sizeof msg);
    EXPECTF(rc == 0, "%s: exit %d: %s", fine[i], rc, msg);
  }

  /* The command line. */
  static const struct {
    const char *args, *want;
    int rc;
  } usage[] = {
      {"--help", "usage: rtsim dram-replay MACHINE.yaml TRACE", 0},
      {SRC "configs/tiny.yaml", "expected MACHINE.yaml TRACE, got 1 file", 2},
      {SRC "configs/tiny.yaml " DT "fixed.trace --per-request", "needs a value", 2},
  };
  for (size_t i = 0; i < sizeof usage / sizeof usage[0]; i++) {
    char cmd[4096];
    snprintf(cmd, sizeof cmd, "%s dram-replay %s", RTSIM_BINARY, usage[i].args);
    int rc = testing_run(cmd, msg, sizeof msg);
    EXPECTF(rc == usage[i].rc, "%s: exit %d: %s", usage[i].args, rc, msg);
    EXPECTF(strstr(msg, usage[i].want) != NULL, "%s: got '%s', want '%s'", usage[i].args, msg,
            usage[i].want);
  }
}

int main(void) {
  test_fixed();
  test_channel();
  test_banked();
  test_banked_idle_drain();
  test_round_trip();
  test_formats();
  test_bad();
  return testing_done("dram_replay");
}
