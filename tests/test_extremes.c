/* The machine at its extremes, through the real binary: every accepted config
 * runs or is refused before it starts (docs/config-keys.md "Config keys").
 * 1. Every numeric machine key at both ends of its range (the range read from
 *    the binary's own refusal of a value outside it): the run either ends
 *    (exit 0) with whole outputs that keep the invariants below, or is refused
 *    before it starts (exit 2, one line naming the key, no stats.json). One
 *    step outside either end is refused naming the key. Every value of every
 *    enumerated key runs the same way.
 * 2. The same scene in other units (1e-4 to 1e4): the same cycles.
 * 3. A table of extremes chosen by hand: the smallest machine on a 1x1 image,
 *    the most ray contexts this host can map stacks for and one more, caches
 *    of one line and the largest accepted, DRAM latency and bandwidth at both
 *    ends together.
 * Invariants of a finished run (stats.json): the image is the reference
 * render's, bit for bit in RGB; 0 <= core_utilization <= 1; idle = wait + parked + done;
 * l2_miss_rate = misses / accesses; DRAM bytes = 64 x requests, and their
 * per-cycle figure; the timeline's DRAM bytes add up to the totals, and its
 * energy columns to energy_j, dram_energy_j and chip_energy_j (each window
 * written to 10 significant digits); no nan or inf in any output. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sim/coro.h"
#include "sim/machine_cfg.h"
#include "testing.h"

#define W 4
#define H 4

static const char *const TINY = RTSIM_SOURCE_DIR "/configs/tiny.yaml";
static const char *const SCENE = RTSIM_SOURCE_DIR "/scenes/small/room.yaml";
static const char *const REF = RTSIM_TMP "/extremes_ref.exr";
static const char *const DIR = RTSIM_TMP "/extremes_run";

static char out[1 << 16];

static int run(const char *args, int w, int h) {
  char cmd[4096];
  snprintf(cmd, sizeof cmd, "rm -rf %s && timeout 120 %s run %s %s --width %d --height %d -o %s %s",
           DIR, RTSIM_BINARY, TINY, SCENE, w, h, DIR, args);
  return testing_run(cmd, out, sizeof out);
}

static bool near(double a, double b) { return fabs(a - b) <= 1e-9 * (fabs(a) + fabs(b)) + 1e-9; }

/* Sum of a timeline.csv column. */
static double timeline_sum(const char *col) {
  char *t = testing_slurp(DIR, "timeline.csv", NULL);
  if (!t) return NAN;
  int at = -1, k = 0;
  char *save = NULL, *line = strtok_r(t, "\n", &save);
  for (char *p = line; p && *p; k++) {
    size_t n = strcspn(p, ",");
    if (n == strlen(col) && !strncmp(p, col, n)) at = k;
    p += n + (p[n] == ',');
  }
  double sum = 0;
  while (at >= 0 && (line = strtok_r(NULL, "\n", &save))) {
    char *p = line;
    for (int i = 0; i < at && p; i++) p = strchr(p, ','), p = p ? p + 1 : p;
    sum += p ? strtod(p, NULL) : NAN;
  }
  free(t);
  return at < 0 ? NAN : sum;
}

/* a and b agree to the timeline's 10 significant digits a window. */
static bool near_sum(double a, double b) { return fabs(a - b) <= 1e-9 * fabs(b) + 1e-30; }

static void check_energy_windows(const char *what) {
  const double e = timeline_sum("energy_j"), d = timeline_sum("dram_energy_j"),
               c = timeline_sum("chip_dynamic_energy_j") + timeline_sum("chip_leakage_energy_j");
  const double je = testing_json_num(DIR, "energy_j"), jd = testing_json_num(DIR, "dram_energy_j"),
               jc = testing_json_num(DIR, "chip_energy_j");
  EXPECTF(near_sum(e, je) && near_sum(d, jd) && near_sum(c, jc),
          "%s: timeline energy %.10g J (DRAM %.10g, chip %.10g), stats.json %.10g (%.10g, %.10g)",
          what, e, d, c, je, jd, jc);
}

static void check_finished(const char *what, bool image) {
  /* The analytic rung writes no timeline and no thread figures (docs/fidelity-and-sampling.md:
   * "what it cannot know is absent"). */
  char *json = testing_slurp(DIR, "stats.json", NULL);
  const bool timed = !json || !strstr(json, "\"fidelity\": \"analytic\"");
  free(json);
  static const char *const files[] = {"stats.json", "stats.csv", "timeline.csv"};
  for (int f = 0; f < (timed ? 3 : 2); f++) {
    char *t = testing_slurp(DIR, files[f], NULL);
    EXPECTF(t && !strstr(t, "nan") && !strstr(t, "inf"), "%s: %s missing or has nan/inf", what,
            files[f]);
    free(t);
  }
  if (image) {
    char img[2048];
    snprintf(img, sizeof img, "%s/image.exr", DIR);
    EXPECTF(testing_same_rgb(REF, img), "%s: the image is not the reference render's", what);
  }
  double u = testing_json_num(DIR, "core_utilization");
  EXPECTF(u >= 0 && u <= 1, "%s: core_utilization %g", what, u);
  double idle = testing_json_num(DIR, "thread_idle_fraction"),
         wait = testing_json_num(DIR, "thread_wait_fraction"),
         parked = testing_json_num(DIR, "thread_parked_fraction"),
         done = testing_json_num(DIR, "thread_done_fraction");
  if (timed)
    EXPECTF(fabs(idle - wait - parked - done) < 1e-9,
            "%s: idle %g != wait %g + parked %g + done %g", what, idle, wait, parked, done);
  else
    EXPECTF(isnan(idle) && isnan(wait) && isnan(done), "%s: analytic states thread figures", what);
  double acc = testing_json_num(DIR, "l2_accesses"), miss = testing_json_num(DIR, "l2_misses"),
         rate = testing_json_num(DIR, "l2_miss_rate");
  EXPECTF(acc > 0 && miss <= acc && near(rate, miss / acc), "%s: l2 %g misses of %g, rate %g", what,
          miss, acc, rate);
  double rb = testing_json_num(DIR, "dram_read_bytes"),
         wb = testing_json_num(DIR, "dram_write_bytes"), rd = testing_json_num(DIR, "dram_reads"),
         wr = testing_json_num(DIR, "dram_writes"), cyc = testing_json_num(DIR, "cycles"),
         bpc = testing_json_num(DIR, "dram_bytes_per_cycle");
  EXPECTF(rb == 64 * rd && wb == 64 * wr && cyc > 0 && near(bpc, (rb + wb) / cyc),
          "%s: DRAM %g/%g bytes for %g/%g requests, %g a cycle over %g cycles", what, rb, wb, rd,
          wr, bpc, cyc);
  /* The timeline splits a transfer across windows to two decimals. */
  double tr = timeline_sum("dram_read_bytes"), tw = timeline_sum("dram_write_bytes");
  if (timed)
    EXPECTF(fabs(tr - rb) <= 0.01 * (rd + 1) && fabs(tw - wb) <= 0.01 * (wr + 1),
            "%s: timeline %g/%g DRAM bytes, totals %g/%g", what, tr, tw, rb, wb);
  if (timed) check_energy_windows(what);
  EXPECTF(testing_json_num(DIR, "rays_traced") > 0, "%s: no rays", what);
}

static void check_refused(const char *what, const char *key) {
  size_t len = strlen(out);
  while (len && out[len - 1] == '\n') out[--len] = '\0';
  EXPECTF(strchr(out, '\n') == NULL && strstr(out, key) && strstr(out, "error"),
          "%s: refusal is not one line naming %s: '%s'", what, key, out);
  char *t = testing_slurp(DIR, "stats.json", NULL);
  EXPECTF(t == NULL, "%s: refused but left a stats.json", what);
  free(t);
}

/* Run with args: exit 0 and every invariant, or exit 2 naming key. */
static void runs_or_refused(const char *what, const char *args, const char *key, int w, int h) {
  int rc = run(args, w, h);
  EXPECTF(rc == 0 || rc == 2, "%s: exit %d: %s", what, rc, out);
  if (rc == 0) check_finished(what, w == W && h == H);
  if (rc == 2) check_refused(what, key);
}

/* The range the binary states for key: "expected LO to HI". */
static bool key_range(const char *key, char *lo, char *hi, size_t cap) {
  char args[256];
  const char *p = NULL;
  /* A huge number, then a huge size (sizes refuse "1e300" as not a size). */
  static const char *const probes[] = {"1e300", "1048576GiB"};
  for (int i = 0; i < 2 && !p; i++) {
    snprintf(args, sizeof args, "--set %s=%s", key, probes[i]);
    if (run(args, W, H) != 2) return false;
    p = strstr(out, "expected ");
    if (p && !strstr(p, " to ")) p = NULL;
  }
  if (!p) {
    snprintf(args, sizeof args, "--set %s=1e300", key);
    run(args, W, H); /* the enumerated keys' list, for the caller */
    return false;
  }
  p += 9;
  const char *to = strstr(p, " to ");
  if (!to || (size_t)(to - p) >= cap) return false;
  memcpy(lo, p, (size_t)(to - p));
  lo[to - p] = '\0';
  to += 4;
  size_t n = strcspn(to, " )");
  if (n >= cap) return false;
  memcpy(hi, to, n);
  hi[n] = '\0';
  return true;
}

static void check_every_key(void) {
  int ranged = 0;
  for (unsigned i = 0; machine_cfg_key(i); i++) {
    const char *key = machine_cfg_key(i);
    char lo[64], hi[64], args[512], what[512];
    if (!key_range(key, lo, hi, sizeof lo)) {
      /* Enumerated or structured: every value its refusal lists. */
      const char *list = strstr(out, "expected one of: ");
      if (!list) continue;
      char vals[512];
      snprintf(vals, sizeof vals, "%s", list + 17);
      vals[strcspn(vals, ")\n")] = '\0';
      char *save = NULL;
      for (char *v = strtok_r(vals, ", ", &save); v; v = strtok_r(NULL, ", ", &save)) {
        snprintf(args, sizeof args, "--set %s=%s", key, v);
        snprintf(what, sizeof what, "%s", args);
        runs_or_refused(what, args, key, W, H);
      }
      continue;
    }
    ranged++;
    const char *ends[2] = {lo, hi};
    for (int e = 0; e < 2; e++) {
      snprintf(args, sizeof args, "--set %s=%s", key, ends[e]);
      snprintf(what, sizeof what, "%s", args);
      runs_or_refused(what, args, key, W, H);
    }
    /* One step outside: below the low end (when it is above zero) and above the high. */
    double l = strtod(lo, NULL), h = strtod(hi, NULL);
    char outside[2][64];
    int n = 0;
    if (l > 0) snprintf(outside[n++], 64, "%.17g", l < 1 ? l / 2 : l - 1);
    snprintf(outside[n++], 64, "%.17g", h < 1 ? h * 2 : h + 1);
    for (int k = 0; k < n; k++) {
      snprintf(args, sizeof args, "--set %s=%s", key, outside[k]);
      int rc = run(args, W, H);
      EXPECTF(rc == 2, "%s: exit %d", args, rc);
      check_refused(args, key);
    }
  }
  EXPECTF(ranged > 40, "only %d keys with a stated range", ranged);
}

static void check_table(void) {
  static const struct {
    const char *what, *args, *key;
    int w, h;
  } rows[] = {
      {"smallest machine, 1x1 image",
       "--set cores=1 --set threads_per_core=1 --set rays_per_thread=1", "cores", 1, 1},
      {"caches of one line",
       "--set l1.size=64 --set l1.ways=1 --set l2.size=64 --set l2.ways=full --set l2.mshrs=1 --set l2.write_buffer=1",
       "l2.size", W, H},
      {"largest caches", "--set l1.size=1GiB --set l2.size=16GiB", "l2.size", W, H},
      {"largest caches, many cores", "--set cores=4096 --set l1.size=1GiB --set l2.size=16GiB",
       "cores", W, H},
      {"fully associative 16 GiB L2", "--set l2.size=16GiB --set l2.ways=full", "l2.size", W, H},
      {"no DRAM latency, widest channel",
       "--set fidelity=channel --set dram.latency=0 --set dram.bytes_per_cycle=1e6", "dram.latency",
       W, H},
      {"slowest DRAM",
       "--set fidelity=channel --set dram.latency=1000000000 --set dram.bytes_per_cycle=1e-6",
       "dram.latency", W, H},
      {"fixed latency 0", "--set fidelity=fixed --set dram.latency=0", "dram.latency", W, H},
      {"dynamic, smallest machine",
       "--policy dynamic --set cores=1 --set threads_per_core=1 --set rays_per_thread=1", "cores",
       W, H},
      {"dynamic, one-line L2", "--policy dynamic --set l2.size=64 --set l2.ways=full", "l2.size", W,
       H},
      {"packet, one-line caches",
       "--policy packet --set l1.size=64 --set l1.ways=1 --set l2.size=64 --set l2.ways=full",
       "l2.size", W, H},
  };
  for (size_t i = 0; i < sizeof rows / sizeof rows[0]; i++)
    runs_or_refused(rows[i].what, rows[i].args, rows[i].key, rows[i].w, rows[i].h);
  /* The most ray contexts this host maps stacks for runs; one more is refused. */
  uint64_t limit = coro_host_stack_limit();
  if (limit > (1u << 20)) limit = 1u << 20;
  char args[256];
  uint64_t cores = limit / 4;
  if (cores > 4096) cores = 4096;
  snprintf(args, sizeof args, "--set cores=%llu --set threads_per_core=2 --set rays_per_thread=2",
           (unsigned long long)cores);
  int rc = run(args, W, H);
  EXPECTF(rc == 0, "%s (%llu contexts, host limit %llu): exit %d: %s", args,
          (unsigned long long)(4 * cores), (unsigned long long)limit, rc, out);
  if (rc == 0) check_finished(args, true);
  if (limit < 4096ull * 256) {
    uint64_t t = limit / 4096 + 1; /* 4096 cores x t threads x 1 ray > limit */
    snprintf(args, sizeof args,
             "--set cores=4096 --set threads_per_core=%llu --set rays_per_thread=1",
             (unsigned long long)t);
    rc = run(args, W, H);
    EXPECTF(rc == 2, "%s: exit %d", args, rc);
    check_refused(args, "cores");
  }
}

/* Scale invariance on the machine (docs/renderer.md "Rendering model"): the small
 * room, exported as a mesh and written at scales 1e-4 to 1e4 (mesh `scale`,
 * camera and lights multiplied alike), makes the same triangle tests and
 * simulated cycles: exactly by a power of two, within 0.1% otherwise (DRAM
 * bytes within 0.5%). On the tiny machine with a 4 MiB L2: a SAH near-tie
 * that rounding flips deep in the tree renumbers the nodes after it, and on
 * tiny's own 32 KiB L2 the moved addresses change conflict misses by up to
 * 3% (cycles 0.2%); on 16 cores at 32x32 the end of the run moves cycles by
 * up to 3% (docs/renderer.md). */
static void check_scales(void) {
  const char *ply = RTSIM_TMP "/extremes_room.ply", *yaml = RTSIM_TMP "/extremes_scaled.yaml";
  char cmd[4096];
  snprintf(cmd, sizeof cmd, "%s export %s -o %s", RTSIM_BINARY, SCENE, ply);
  EXPECT(testing_run(cmd, out, sizeof out) == 0);
  static const double scales[] = {1, 0.5, 8, 1e-4, 0.1, 3, 1e4};
  static const double from[3] = {0.7, 0.6, 1.6}, at[3] = {5.5, 4.6, 0.9};
  static const double lights[3][3] = {{3.6, 2.8, 2.1}, {2.0, 1.5, 2.7}, {6.0, 4.5, 2.7}};
  static const double power[3] = {0.45, 0.3, 0.3};
  double ref_cycles = 0, ref_tests = 0, ref_bytes = 0;
  for (size_t i = 0; i < sizeof scales / sizeof scales[0]; i++) {
    const double k = scales[i];
    FILE *f = fopen(yaml, "w");
    if (!f) {
      EXPECT(f != NULL);
      return;
    }
    fprintf(
        f,
        "camera: {from: [%.17g, %.17g, %.17g], at: [%.17g, %.17g, %.17g], up: [0, 0, 1], fov_deg: 60}\n",
        from[0] * k, from[1] * k, from[2] * k, at[0] * k, at[1] * k, at[2] * k);
    fprintf(f, "background: [0.6, 0.75, 0.95]\nambient: 0.15\nlights:\n");
    for (int l = 0; l < 3; l++)
      fprintf(f, "  - {position: [%.17g, %.17g, %.17g], intensity: [%g, %g, %g]}\n",
              lights[l][0] * k, lights[l][1] * k, lights[l][2] * k, power[l], power[l], power[l]);
    fprintf(f, "geometry:\n  - {mesh: extremes_room.ply, scale: %.17g}\n", k);
    fclose(f);
    snprintf(cmd, sizeof cmd,
             "rm -rf %s && %s run %s %s --width 32 --height 32 --set l2.size=4MiB -o %s", DIR,
             RTSIM_BINARY, TINY, yaml, DIR);
    int rc = testing_run(cmd, out, sizeof out);
    EXPECTF(rc == 0, "scale %g: exit %d: %s", k, rc, out);
    double cycles = testing_json_num(DIR, "cycles"),
           tests = testing_json_num(DIR, "triangle_tests"),
           bytes =
               testing_json_num(DIR, "dram_read_bytes") + testing_json_num(DIR, "dram_write_bytes");
    if (i == 0) {
      ref_cycles = cycles;
      ref_tests = tests;
      ref_bytes = bytes;
      EXPECT(cycles > 0 && tests > 0 && bytes > 0);
      continue;
    }
    printf("scale %g: cycles %+.3f%%, triangle tests %+.3f%%, DRAM bytes %+.3f%%\n", k,
           100 * (cycles / ref_cycles - 1), 100 * (tests / ref_tests - 1),
           100 * (bytes / ref_bytes - 1));
    bool pow2 = k == 0.5 || k == 8;
    double tol = pow2 ? 0 : 0.001;
    EXPECTF(
        fabs(cycles - ref_cycles) <= tol * ref_cycles &&
            fabs(tests - ref_tests) <= tol * ref_tests &&
            fabs(bytes - ref_bytes) <= (pow2 ? 0 : 0.005) * ref_bytes,
        "scale %g: %.0f cycles, %.0f triangle tests, %.0f DRAM bytes; at scale 1 %.0f, %.0f, %.0f",
        k, cycles, tests, bytes, ref_cycles, ref_tests, ref_bytes);
  }
}

int main(void) {
  char cmd[4096];
  snprintf(cmd, sizeof cmd, "%s render %s --width %d --height %d -o %s", RTSIM_BINARY, SCENE, W, H,
           REF);
  if (testing_run(cmd, out, sizeof out) != 0) {
    EXPECTF(0, "reference render: %s", out);
    return testing_done("test_extremes");
  }
  check_scales();
  check_table();
  check_every_key();
  return testing_done("test_extremes");
}
