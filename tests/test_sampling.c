/* Sampling through rtsim run (docs/fidelity-and-sampling.md): a sampled run traces every
 * work item, so its image, rays and issue slots are the full run's exactly;
 * its estimates of cycles, DRAM bytes and load latency fall near the full
 * run's on every small scene, with intervals that are intervals (low <=
 * estimate <= high); the same seed gives the same bytes, another seed other
 * units; and what cannot be sampled is refused before anything runs. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "app/sample.h"
#include "app/sample_aux.h"
#include "app/sample_fl2.h"
#include "renderer/rng.h"
#include "sim/machine.h"
#include "testing.h"

#define EXPECT_NEAR(a, b, tol)                                                                     \
  EXPECTF(fabs((a) - (b)) <= (tol), "%s = %.17g, expected %.17g", #a, (double)(a), (double)(b))

static const char *const SCENES[] = {"grove", "room", "sphereflake"};

/* rtsim run configs/tiny.yaml on scenes/small/SCENE.yaml at w x h with more
 * options into dir; the exit code (output in out). */
static int run(const char *scene, const char *policy, unsigned w, unsigned h, const char *more,
               const char *dir, char *out, unsigned cap) {
  char cmd[4096];
  snprintf(cmd, sizeof cmd,
           "%s run %s/configs/tiny.yaml %s/scenes/small/%s.yaml --width %u --height %u "
           "--policy %s --rays primary,shadow,diffuse %s -o %s",
           RTSIM_BINARY, RTSIM_SOURCE_DIR, RTSIM_SOURCE_DIR, scene, w, h, policy, more, dir);
  return testing_run(cmd, out, cap);
}

/* Estimate `name` of the sampled run in s against the full run's in f:
 * relative error within tol, and its interval ordered around it. */
static void expect_near(const char *f, const char *s, const char *name, double tol) {
  char lo_name[96], hi_name[96];
  snprintf(lo_name, sizeof lo_name, "%s_ci95_low", name);
  snprintf(hi_name, sizeof hi_name, "%s_ci95_high", name);
  double full = testing_json_num(f, name), est = testing_json_num(s, name);
  double lo = testing_json_num(s, lo_name), hi = testing_json_num(s, hi_name);
  double err = (est - full) / full;
  printf("%s: %s full %.6g, sampled %.6g [%.6g, %.6g], error %+.2f%%\n", s, name, full, est, lo, hi,
         100 * err);
  EXPECTF(fabs(err) <= tol, "%s: %s %.6g against the full run's %.6g (%+.2f%%, tolerance %.0f%%)",
          s, name, est, full, 100 * err, 100 * tol);
  EXPECTF(lo <= est && est <= hi && lo < hi, "%s: %s's interval [%g, %g] around %g", s, name, lo,
          hi, est);
}

/* The energy estimate's tolerance against the full run's energy_j and
 * power_w (measured at 64x64: -2.4% to +0.3%, each interval holding the
 * full run's figure). */
#define ENERGY_TOL 0.05

static void test_against_full(void) {
  char out[8192];
  for (size_t i = 0; i < sizeof SCENES / sizeof SCENES[0]; i++) {
    char full[512], samp[512];
    snprintf(full, sizeof full, "%s/smp_%s_full", RTSIM_TMP, SCENES[i]);
    snprintf(samp, sizeof samp, "%s/smp_%s_s", RTSIM_TMP, SCENES[i]);
    int rc = run(SCENES[i], "recursive", 64, 64, "", full, out, sizeof out);
    EXPECTF(rc == 0, "full run of %s: exit %d: %s", SCENES[i], rc, out);
    rc = run(SCENES[i], "recursive", 64, 64, "--set sample.fraction=0.2", samp, out, sizeof out);
    EXPECTF(rc == 0, "sampled run of %s: exit %d: %s", SCENES[i], rc, out);
    if (rc) continue;
    /* Every item traced: the image, the rays and the issue slots exact. */
    char a[600], b[600];
    snprintf(a, sizeof a, "%s/image.exr", full);
    snprintf(b, sizeof b, "%s/image.exr", samp);
    EXPECTF(testing_same_rgb(a, b), "%s: the sampled run's image differs from the full run's",
            SCENES[i]);
    const char *exact[] = {"rays_traced", "issue_slots", "ray_contexts"};
    for (size_t k = 0; k < 3; k++)
      EXPECTF(testing_json_num(full, exact[k]) == testing_json_num(samp, exact[k]),
              "%s: %s %g sampled, %g full", SCENES[i], exact[k], testing_json_num(samp, exact[k]),
              testing_json_num(full, exact[k]));
    /* A fifth of the items in 34 units: cycles within 3%, the memory
     * figures (noisier per unit) within 25% and 15%. Measured: cycles -0.9%
     * to +0.1%, DRAM bytes -18% to +2.5%, load latency -10% to +1.1%. */
    expect_near(full, samp, "cycles", 0.03);
    expect_near(full, samp, "core_utilization", 0.03);
    expect_near(full, samp, "dram_bytes", 0.25);
    expect_near(full, samp, "load_latency_mean", 0.15);
    expect_near(full, samp, "energy_j", ENERGY_TOL);
    expect_near(full, samp, "power_w", ENERGY_TOL);
    EXPECTF(testing_json_num(samp, "sample_detailed_fraction") > 0.15 &&
                testing_json_num(samp, "sample_detailed_fraction") < 0.25,
            "%s: detailed fraction %g for sample.fraction 0.2", SCENES[i],
            testing_json_num(samp, "sample_detailed_fraction"));
    /* 819 detailed items, units of at least 3 x 8 ray contexts: 34. */
    EXPECTF(testing_json_num(samp, "sample_units_measured") == 34, "%s: %g units", SCENES[i],
            testing_json_num(samp, "sample_units_measured"));
    /* No timeline: its time would be the units' only. */
    char *tl = testing_slurp(samp, "timeline.csv", NULL);
    EXPECTF(tl == NULL, "%s: a sampled run wrote timeline.csv", SCENES[i]);
    free(tl);
  }
}

static void test_seeds(void) {
  char out[8192], d1[512], d2[512], d3[512];
  snprintf(d1, sizeof d1, "%s/smp_seed1", RTSIM_TMP);
  snprintf(d2, sizeof d2, "%s/smp_seed1b", RTSIM_TMP);
  snprintf(d3, sizeof d3, "%s/smp_seed2", RTSIM_TMP);
  const char *s1 = "--set sample.fraction=0.2 --set sample.seed=1";
  EXPECT(run("sphereflake", "recursive", 64, 64, s1, d1, out, sizeof out) == 0);
  EXPECT(run("sphereflake", "recursive", 64, 64, s1, d2, out, sizeof out) == 0);
  EXPECT(run("sphereflake", "recursive", 64, 64, "--set sample.fraction=0.2 --set sample.seed=2",
             d3, out, sizeof out) == 0);
  char *a = testing_slurp(d1, "stats.csv", NULL), *b = testing_slurp(d2, "stats.csv", NULL);
  char *c = testing_slurp(d3, "stats.csv", NULL);
  EXPECTF(a && b && !strcmp(a, b), "the same seed gave different stats.csv");
  EXPECTF(a && c && strcmp(a, c) != 0, "another seed gave the same stats.csv");
  free(a);
  free(b);
  free(c);
}

/* Packet: the items are tiles (1024 at 256x256); half of them make 21 units
 * (measured: cycles +3.0%, its interval [-3.4%, +9.5%]). */
static void test_packet(void) {
  char out[8192], full[512], samp[512];
  snprintf(full, sizeof full, "%s/smp_pk_full", RTSIM_TMP);
  snprintf(samp, sizeof samp, "%s/smp_pk_s", RTSIM_TMP);
  EXPECT(run("sphereflake", "packet", 256, 256, "", full, out, sizeof out) == 0);
  int rc =
      run("sphereflake", "packet", 256, 256, "--set sample.fraction=0.5", samp, out, sizeof out);
  EXPECTF(rc == 0, "sampled packet run: exit %d: %s", rc, out);
  if (rc) return;
  EXPECT(testing_json_num(full, "issue_slots") == testing_json_num(samp, "issue_slots"));
  expect_near(full, samp, "cycles", 0.05);
  const double c = testing_json_num(full, "cycles");
  EXPECTF(testing_json_num(samp, "cycles_ci95_low") <= c &&
              c <= testing_json_num(samp, "cycles_ci95_high"),
          "packet: the full run's cycles %g outside the sampled interval", c);
}

/* Sampling on each BVH, single rays and packets (256 x 256 of the tiny
 * room: enough tiles for packet's units): every item traced, so the image,
 * the rays and the issue slots are the full run's exactly. */
static void test_bvh(void) {
  char out[8192], cmd[4096], dir[2][512];
  static const char *const accel[] = {"bvh2", "bvh8"}, *const policy[] = {"recursive", "packet"};
  for (int a = 0; a < 2; a++)
    for (int p = 0; p < 2; p++) {
      for (int s = 0; s < 2; s++) {
        snprintf(dir[s], sizeof dir[s], "%s/smp_%s_%s_%d", RTSIM_TMP, accel[a], policy[p], s);
        snprintf(cmd, sizeof cmd,
                 "%s run %s/configs/tiny.yaml %s/scenes/good_room_tiny_%s.yaml --width 256 "
                 "--height 256 --policy %s --rays primary,shadow,diffuse %s -o %s",
                 RTSIM_BINARY, RTSIM_SOURCE_DIR, RTSIM_TEST_DATA, accel[a], policy[p],
                 s ? "--set sample.fraction=0.5" : "", dir[s]);
        const int rc = testing_run(cmd, out, sizeof out);
        EXPECTF(rc == 0, "%s %s %s: exit %d: %s", accel[a], policy[p], s ? "sampled" : "full", rc,
                out);
      }
      char x[600], y[600];
      snprintf(x, sizeof x, "%s/image.exr", dir[0]);
      snprintf(y, sizeof y, "%s/image.exr", dir[1]);
      EXPECTF(testing_same_rgb(x, y), "%s %s: the sampled run's image differs", accel[a],
              policy[p]);
      const char *exact[] = {"rays_traced", "issue_slots"};
      for (size_t k = 0; k < 2; k++)
        EXPECTF(testing_json_num(dir[0], exact[k]) == testing_json_num(dir[1], exact[k]),
                "%s %s: %s %g sampled, %g full", accel[a], policy[p], exact[k],
                testing_json_num(dir[1], exact[k]), testing_json_num(dir[0], exact[k]));
      EXPECT(testing_json_num(dir[1], "sample_units_measured") >= 8);
    }
}

/* An issue-bound run (every core busy every cycle): the raw estimate of the
 * cycles falls below the issue slots over the cores and its interval's top
 * of the core utilization above 1 (measured: the unclamped estimate 0.3%
 * under the bound); both are clamped to what the run can be. */
static void test_clamped(void) {
  char out[8192], dir[512];
  snprintf(dir, sizeof dir, "%s/smp_clamp", RTSIM_TMP);
  char cmd[4096];
  snprintf(cmd, sizeof cmd,
           "%s run %s/configs/tiny.yaml %s/scenes/small/room.yaml --width 64 --height 64 --rays "
           "primary --set costs.node=2000 --set sample.fraction=0.5 -o %s",
           RTSIM_BINARY, RTSIM_SOURCE_DIR, RTSIM_SOURCE_DIR, dir);
  int rc = testing_run(cmd, out, sizeof out);
  EXPECTF(rc == 0, "issue-bound sampled run: exit %d: %s", rc, out);
  if (rc) return;
  const double bound = testing_json_num(dir, "issue_slots") / 2; /* tiny.yaml: 2 cores */
  EXPECTF(testing_json_num(dir, "cycles_ci95_low") >= bound &&
              testing_json_num(dir, "cycles") >= bound,
          "cycles %g [%g, ...] below the issue bound %g", testing_json_num(dir, "cycles"),
          testing_json_num(dir, "cycles_ci95_low"), bound);
  EXPECTF(testing_json_num(dir, "core_utilization_ci95_high") <= 1 &&
              testing_json_num(dir, "core_utilization") <= 1,
          "core utilization %g [.., %g] above 1", testing_json_num(dir, "core_utilization"),
          testing_json_num(dir, "core_utilization_ci95_high"));
  EXPECTF(testing_json_num(dir, "cycles_ci95_high") > testing_json_num(dir, "cycles_ci95_low"),
          "a clamped interval is still an interval");
}

/* sample.image sampled: only the units and their warming windows are traced;
 * the rays and issue slots become estimates whose intervals hold the full
 * run's counts, and the image is not the full run's (pixels left black). */
static void test_sampled_image(void) {
  char out[8192], full[512], samp[512];
  snprintf(full, sizeof full, "%s/smp_img_full", RTSIM_TMP);
  snprintf(samp, sizeof samp, "%s/smp_img_s", RTSIM_TMP);
  EXPECT(run("room", "recursive", 64, 64, "", full, out, sizeof out) == 0);
  int rc = run("room", "recursive", 64, 64,
               "--set sample.fraction=0.2 --set sample.warming=1 --set sample.image=sampled", samp,
               out, sizeof out);
  EXPECTF(rc == 0, "sampled image: exit %d: %s", rc, out);
  if (rc) return;
  const double traced = testing_json_num(samp, "sample_traced_fraction");
  EXPECTF(traced > 0.2 && traced < 0.6, "traced fraction %g for 0.2 detailed, 0.2 warmed", traced);
  /* The pre-pass: the middle units' detailed items (32 of 34 units of a
   * fifth of their strata: 0.19) and one in 4 of the rest (0.2) in
   * stretches of 8 items (the ray contexts), each with 8 items warmed before
   * and 4 after: at most 0.19 + 0.81 x 20 / 32. */
  const double pre = testing_json_num(samp, "sample_prepass_fraction");
  EXPECTF(pre > 0.39 && pre < 0.7, "pre-pass fraction %g, expected 0.39 to 0.7", pre);
  const char *counts[] = {"issue_slots", "rays_traced", "cycles"};
  for (size_t i = 0; i < 3; i++) {
    char lo[96], hi[96];
    snprintf(lo, sizeof lo, "%s_ci95_low", counts[i]);
    snprintf(hi, sizeof hi, "%s_ci95_high", counts[i]);
    const double f = testing_json_num(full, counts[i]);
    printf("sampled image: %s full %.6g, estimate %.6g [%.6g, %.6g]\n", counts[i], f,
           testing_json_num(samp, counts[i]), testing_json_num(samp, lo),
           testing_json_num(samp, hi));
    EXPECTF(testing_json_num(samp, lo) <= f && f <= testing_json_num(samp, hi) &&
                testing_json_num(samp, lo) < testing_json_num(samp, hi),
            "sampled image: %s's interval misses the full run's %g", counts[i], f);
  }
  char a[600], b[600];
  snprintf(a, sizeof a, "%s/image.exr", full);
  snprintf(b, sizeof b, "%s/image.exr", samp);
  EXPECTF(!testing_same_rgb(a, b), "sampled image: the image is the full run's");
}

static void test_refusals(void) {
  static const struct {
    const char *policy, *more, *want;
  } bad[] = {
      {"dynamic", "--set sample.fraction=0.5", "sampling needs a policy that takes its work item"},
      {"recursive", "--set sample.fraction=0.01", "too few detailed items"},
      {"recursive", "--set sample.fraction=0.5 --set sample.units=3", "at least 8 units"},
      {"recursive", "--set sample.fraction=0.5 --set fidelity=analytic", "a timed fidelity"},
      {"recursive", "--set sample.fraction=0.5 --dram-trace " RTSIM_TMP "/smp.trace",
       "--dram-trace records a whole run"},
      {"recursive", "--set sample.fraction=0", "sample.fraction"},
      {"recursive", "--set sample.fraction=0.5 --set sample.image=half",
       "--set sample.image=half: error: sample.image: unknown value (got 'half', expected one of: sampled, whole)"},
      {"recursive", "--set sample.fraction=1.5", "sample.fraction"},
  };
  char out[8192];
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    int rc = run("room", bad[i].policy, 32, 32, bad[i].more, RTSIM_TMP "/smp_bad", out, sizeof out);
    EXPECTF(rc == 2 && strstr(out, bad[i].want) && strstr(out, "error:"),
            "'%s %s': exit %d, output: %s", bad[i].policy, bad[i].more, rc, out);
  }
  char *left = testing_slurp(RTSIM_TMP "/smp_bad", "stats.json", NULL);
  EXPECTF(left == NULL, "a refused run left stats.json");
  free(left);
  /* A sweep checks every point's sampling before anything runs. */
  FILE *f = fopen(RTSIM_TMP "/smp_sweep.yaml", "w");
  EXPECT(f != NULL);
  if (!f) return;
  fprintf(f,
          "machine: %s/configs/tiny.yaml\nworkload:\n  scene: %s/scenes/small/room.yaml\n"
          "  width: 32\n  height: 32\nset:\n  sample.fraction: 0.5\naxes:\n"
          "  policy: [recursive, dynamic]\n",
          RTSIM_SOURCE_DIR, RTSIM_SOURCE_DIR);
  fclose(f);
  int rc = testing_run(RTSIM_BINARY " sweep " RTSIM_TMP "/smp_sweep.yaml -o " RTSIM_TMP "/smp_sw",
                       out, sizeof out);
  EXPECTF(rc == 2 && strstr(out, "smp_sweep.yaml:7:20: error: sample.fraction: sampling needs") &&
              strstr(out, "[point policy=dynamic]"),
          "sweep with a dynamic point sampled: exit %d: %s", rc, out);
}

/* A machine of `cores` x 1 thread x `rays` contexts with an L2 of l2_lines
 * lines of `ways` ways and no L1 (l1_lines 0) or an L1 of l1_lines lines,
 * fully associative. */
static struct machine_params model_machine(uint32_t cores, uint32_t rays, uint64_t l1_lines,
                                           uint64_t l2_lines, uint32_t ways) {
  struct machine_params p;
  memset(&p, 0, sizeof p);
  p.cores = cores;
  p.threads_per_core = 1;
  p.rays_per_thread = rays;
  p.l1_size_bytes = l1_lines * 64;
  p.l2_size_bytes = l2_lines * 64;
  p.l2_ways = ways;
  return p;
}

/* A reference LRU of n lines in sets of `ways` (set: line % (n / ways)),
 * write-back, write-allocate: the DRAM bytes of one access (a fetch unless
 * the store covers the whole line, plus a dirty victim). */
struct ref_lru {
  uint64_t line[64], age[64], clock;
  bool valid[64], dirty[64];
  unsigned n, ways;
};

static unsigned ref_access(struct ref_lru *r, uint64_t line, bool store, bool whole) {
  const unsigned sets = r->n / r->ways, base = (unsigned)(line % sets) * r->ways;
  unsigned victim = base;
  r->clock++;
  for (unsigned i = base; i < base + r->ways; i++) {
    if (r->valid[i] && r->line[i] == line) {
      r->age[i] = r->clock;
      r->dirty[i] |= store;
      return 0;
    }
    if (!r->valid[i] || (r->valid[victim] && r->age[i] < r->age[victim])) victim = i;
  }
  const unsigned wb = r->valid[victim] && r->dirty[victim] ? 64 : 0;
  r->valid[victim] = true;
  r->line[victim] = line;
  r->dirty[victim] = store;
  r->age[victim] = r->clock;
  return wb + (whole ? 0 : 64);
}

/* One context and no L1: the model is an LRU replay of the accesses in
 * order, each item charged its own misses and dirty victims (checked against
 * the reference on random streams of loads, partial and whole-line stores,
 * in a fully associative and a 4-way L2). */
static void test_model_lru(void) {
  for (unsigned ways = 4; ways <= 16; ways += 12) {
    struct machine_params p = model_machine(1, 1, 0, 16, ways);
    struct sfl2 *x = sfl2_create(&p, 1, 0);
    struct ref_lru r = {.n = 16, .ways = ways};
    double got[8] = {0}, want[8] = {0};
    uint64_t h = ways;
    for (unsigned it = 0; it < 8; it++) {
      sfl2_item(x, &got[it]);
      for (unsigned a = 0; a < 60; a++) {
        h = rng_hash2(h, a);
        const uint64_t line = h % 40;
        const unsigned kind = (unsigned)(h >> 20) % 3; /* load, store 8 bytes, store a line */
        sfl2_access(x, line * 64 + (kind == 1 ? 8 : 0), kind == 2 ? 64 : 8, kind != 0);
        want[it] += ref_access(&r, line, kind != 0, kind == 2);
      }
    }
    sfl2_pump(x, SFL2_DRAIN);
    for (unsigned it = 0; it < 8; it++)
      EXPECTF(got[it] == want[it], "%u ways, item %u: %g bytes, the LRU's %g", ways, it, got[it],
              want[it]);
    sfl2_destroy(x);
  }
}

/* Two contexts on one core take turns, each up to its first load its L1
 * misses. By hand, with an L1 of 2 lines and an L2 of 2 lines (both fully
 * associative): item A loads lines 1, 1, 2 (the second 1 is the same line
 * at once: recorded once); B loads 3, 1; C (warming, counted nowhere) loads
 * 4. Turns: A 1 (misses both: A 64); B 3 (misses both: B 64; L1 and L2 hold
 * 1, 3); A 2 (misses both, 1 leaves each: A 128; A ends); B 1 (misses both,
 * 3 leaves each: B 128; B ends); the other context takes C. A model of the
 * even lines only (sets_every 2) sees A's 2 and charges it twice (128), B
 * nothing. */
static void test_model_turns(void) {
  struct machine_params p = model_machine(1, 2, 2, 2, 0);
  double got[2] = {0};
  struct sfl2 *x = sfl2_create(&p, 1, 0);
  const uint64_t lines[3][3] = {{1, 1, 2}, {3, 1, 0}, {4, 0, 0}};
  const unsigned n[3] = {3, 2, 1};
  for (unsigned it = 0; it < 3; it++) {
    sfl2_item(x, it < 2 ? &got[it] : NULL);
    for (unsigned a = 0; a < n[it]; a++) sfl2_access(x, lines[it][a] * 64, 8, false);
  }
  sfl2_pump(x, SFL2_DRAIN);
  EXPECTF(got[0] == 128 && got[1] == 128, "A %g, B %g bytes (expected 128, 128)", got[0], got[1]);
  sfl2_destroy(x);
  double half[2] = {0};
  x = sfl2_create(&p, 2, 0);
  for (unsigned it = 0; it < 3; it++) {
    sfl2_item(x, it < 2 ? &half[it] : NULL);
    for (unsigned a = 0; a < n[it]; a++) sfl2_access(x, lines[it][a] * 64, 8, false);
  }
  sfl2_pump(x, SFL2_MORE); /* (a pump that is not final leaves the rest for later) */
  sfl2_pump(x, SFL2_DRAIN);
  EXPECTF(half[0] == 128 && half[1] == 0, "even lines: A %g, B %g (expected 128, 0)", half[0],
          half[1]);
  sfl2_destroy(x);
}

/* How a batch ends, by hand: one core, two contexts, no L1 (every load ends
 * a turn), an L2 of 2 lines (fully associative). Item A (counted) loads 1,
 * 2, 1; B (warming) loads 4. Turns: A 1 (miss: A 64; L2 1); B 4 (miss; L2
 * 1, 4; B ends); A 2 (miss, 1 leaves: A 128; L2 4, 2). Drained: the second
 * context idles, A 1 misses again (4 leaves): A 192. Refilled: the second
 * context takes a filler, the batch's first item again (A, counted
 * nowhere): it loads 1 (miss, 4 leaves; L2 2, 1), so A's 1 hits: A 128;
 * the batch ends when A does, the filler unfinished. */
static void test_model_refill(void) {
  struct machine_params p = model_machine(1, 2, 0, 2, 0);
  const uint64_t lines[2][3] = {{1, 2, 1}, {4, 0, 0}};
  const unsigned n[2] = {3, 1};
  const enum sfl2_end ends[2] = {SFL2_DRAIN, SFL2_REFILL};
  const double want[2] = {192, 128};
  for (unsigned e = 0; e < 2; e++) {
    double got = 0;
    struct sfl2 *x = sfl2_create(&p, 1, 0);
    for (unsigned it = 0; it < 2; it++) {
      sfl2_item(x, it == 0 ? &got : NULL);
      for (unsigned a = 0; a < n[it]; a++) sfl2_access(x, lines[it][a] * 64, 8, false);
    }
    sfl2_pump(x, ends[e]);
    EXPECTF(got == want[e], "%s: A %g bytes (expected %g)", e ? "refilled" : "drained", got,
            want[e]);
    /* The batch ended: the next starts from the caches it left (L2 2, 1
     * either way: 2 hits, 3 misses and 1 leaves; from empty caches both
     * would miss, 128). */
    double again = 0;
    sfl2_item(x, &again);
    sfl2_access(x, 2 * 64, 8, false);
    sfl2_access(x, 3 * 64, 8, false);
    sfl2_pump(x, ends[e]);
    EXPECTF(again == 64, "after the batch: %g bytes (expected 64)", again);
    sfl2_destroy(x);
  }
}

/* Stretches as clusters, by hand: two stretches of 2 and 1 counted items
 * with totals 10 and 8 of a rest of 6 items: R = 18 / 3 = 6, total 36 (+ the
 * windows' 5); residuals e = 10 - 6 x 2 = -2 and 8 - 6 = 2, s^2 = (2 - -2)^2
 * / 2 = 8, N = 6 / (3 / 2) = 4 clusters, variance 4^2 x (1 - 2/4) x 8 / 2 =
 * 32. */
static void test_aux_clusters(void) {
  double sparse[2 * SA_COUNT] = {10, 0, 0, 8, 0, 0};
  uint64_t sn[2] = {2, 1};
  struct sample_aux x = {.sparse = sparse, .sparse_n = sn, .n_sparse = 2, .pop = 6};
  x.exact[SA_SLOTS] = 5;
  const double g[SA_COUNT] = {1, 0, 0};
  EXPECT_NEAR(sample_aux_total(&x, SA_SLOTS), 41, 1e-12);
  EXPECT_NEAR(sample_aux_var(&x, g), 32, 1e-9);
}

/* The dense sample carries the rest's issue slots and the stretches the
 * modelled DRAM bytes per slot, by hand: a rest of 8 items, dense items of 4
 * and 6 slots (mean 5: 40 slots), one stretch of 10 slots and 30 modelled
 * bytes (3 a slot): 120 bytes. Their variance: the dense items' 3 x slots,
 * 12 and 18, s^2 = 6^2 / 2 = 18, 8^2 x (1 - 2/8) x 18 / 2 = 432; one stretch
 * gives no variance of its own. */
static void test_aux_dense(void) {
  double sparse[SA_COUNT] = {10, 0, 30}, dense[2 * SA_COUNT] = {4, 1, 0, 6, 2, 0};
  uint64_t sn[1] = {3};
  struct sample_aux x = {.sparse = sparse,
                         .sparse_n = sn,
                         .n_sparse = 1,
                         .pop = 8,
                         .dense_every = 4,
                         .dense = dense,
                         .n_dense = 2};
  const double g[SA_COUNT] = {0, 0, 1};
  EXPECT_NEAR(sample_aux_total(&x, SA_SLOTS), 40, 1e-12);
  EXPECT_NEAR(sample_aux_total(&x, SA_RAYS), 12, 1e-12);
  EXPECT_NEAR(sample_aux_total(&x, SA_DRAM), 120, 1e-12);
  EXPECT_NEAR(sample_aux_var(&x, g), 432, 1e-9);
}

/* The pre-pass's totals and their variance, by hand: 10 slots in the units'
 * items, two items sampled from a rest of 8 (3 and 5 slots): 10 + 8 x 8 / 2
 * = 42; successive differences (5 - 3)^2 = 4 give s^2 = 2, and the
 * variance 8^2 x (1 - 2/8) x 2 / 2 = 48. A census of the rest (every item
 * sampled) is exact: variance 0. */
static void test_aux_total(void) {
  double sparse[2 * SA_COUNT] = {3, 1, 7, 5, 2, 9};
  struct sample_aux x = {.every = 4, .sparse = sparse, .n_sparse = 2, .pop = 8};
  x.exact[SA_SLOTS] = 10;
  x.exact[SA_DRAM] = 4;
  const double g[SA_COUNT] = {1, 0, 0};
  EXPECT_NEAR(sample_aux_total(&x, SA_SLOTS), 42, 1e-12);
  EXPECT_NEAR(sample_aux_total(&x, SA_DRAM), 4 + 16 * 4, 1e-12);
  EXPECT_NEAR(sample_aux_var(&x, g), 48, 1e-9);
  x.pop = 2;
  EXPECT_NEAR(sample_aux_total(&x, SA_SLOTS), 18, 1e-12);
  EXPECT_NEAR(sample_aux_var(&x, g), 0, 1e-12);
}

/* A hand-made run of 8 units whose DRAM bytes are 128 x what the L2 model
 * charged their items (over their detailed items and over their windows
 * alike) and whose cycles are 5 / 128 a DRAM byte, while their work (issue
 * slots) per byte varies: the ratio estimator on the model's bytes is exact
 * whatever the units' mix, it is the auxiliary the cycles get (narrower
 * than the slots'), and the units add nothing to the interval: it is the
 * pre-pass's own. */
static void test_ratio_exact(void) {
  enum { N = 8 };
  struct sample_unit u[N];
  bool drained[N] = {0};
  memset(u, 0, sizeof u);
  double unit[N * SA_COUNT] = {0};
  double sparse[3 * SA_COUNT] = {40, 4, 10, 90, 9, 12, 60, 6, 30};
  struct sample_aux x = {.every = 10, .unit = unit, .sparse = sparse, .n_sparse = 3, .pop = 30};
  const double slots[N] = {100, 120, 400, 90, 310, 150, 220, 100};
  const double lines[N] = {10, 30, 20, 45, 12, 60, 25, 10};
  for (unsigned h = 0; h < N; h++) {
    u[h].stratum_lo = 100 * h;
    u[h].stratum_hi = 100 * (h + 1);
    u[h].start = 100 * h + (h ? 20 : 0);
    u[h].measure = u[h].start + (h ? 10 : 0);
    u[h].end = h + 1 < N ? u[h].start + 30 : 800;
    u[h].at1[SQ_SLOTS] = (uint64_t)slots[h];
    u[h].at1[SQ_CYCLES] = (uint64_t)(5 * lines[h]);
    u[h].at1[SQ_DRAM_BYTES] = (uint64_t)(128 * lines[h]);
    /* The machine's DRAM bytes at the claim of each unit's first item. */
    u[h].at_start[SQ_DRAM_BYTES] =
        h ? u[h - 1].at_start[SQ_DRAM_BYTES] + 128 * (uint64_t)lines[h - 1] : 0;
    u[h].at1[SQ_RAYS] = (uint64_t)(slots[h] / 10);
    u[h].at1[SQ_LAT_N] = 1;
    u[h].have0 = u[h].have1 = true;
    if (h == 0 || h + 1 == N) continue;
    unit[h * SA_COUNT + SA_SLOTS] = slots[h];
    unit[h * SA_COUNT + SA_RAYS] = slots[h] / 10;
    unit[h * SA_COUNT + SA_DRAM] = lines[h];
    for (unsigned a = 0; a < SA_COUNT; a++) x.exact[a] += unit[h * SA_COUNT + a];
  }
  struct sampler s = {.total = 800,
                      .n = N,
                      .u = u,
                      .drained = drained,
                      .cores = 1,
                      .hz = 1e9,
                      .aux = &x,
                      .slots_total = 1};
  sample_settle(&s);
  EXPECT(s.cyc_aux == SA_DRAM);
  const double edge_lines = lines[0] + lines[N - 1], X = sample_aux_total(&x, SA_DRAM);
  double lo, hi;
  const double c = sample_cycles(&s, &lo, &hi), d = sample_dram_bytes(&s, &lo, &hi);
  EXPECT_NEAR(c, 5 * (edge_lines + X), 1e-6 * c);
  EXPECT_NEAR(d, 128 * (edge_lines + X), 1e-6 * d);
  EXPECTF(lo <= d && d <= hi && lo < hi, "DRAM bytes %g [%g, %g]", d, lo, hi);
  /* The pre-pass's own variance is the interval's (every unit on the line). */
  const double g[SA_COUNT] = {0, 0, 128};
  const double half = sample_t975(N - 3) * sqrt(sample_aux_var(&x, g));
  EXPECT_NEAR(hi - d, half, 1e-3 * half);
}

int main(void) {
  test_model_lru();
  test_model_turns();
  test_model_refill();
  test_aux_clusters();
  test_aux_dense();
  test_aux_total();
  test_ratio_exact();
  test_against_full();
  test_seeds();
  test_packet();
  test_bvh();
  test_clamped();
  test_sampled_image();
  test_refusals();
  return testing_done("test_sampling");
}
