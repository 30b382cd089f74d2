/* Per-pixel costs (docs/outputs.md "Cost in the picture"): the machine's per-item
 * counters add up to the run's totals for every policy, counting them moves
 * no simulated number, a hand-worked case splits as the rule says, and
 * rtsim run's image.exr channels sum to its stats.json. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "renderer/framebuffer.h"
#include "renderer/image.h"
#include "renderer/kdtree.h"
#include "renderer/policy/policy.h"
#include "renderer/scene.h"
#include "renderer/shade.h"
#include "renderer/trace.h"
#include "sim/err.h"
#include "sim/machine.h"
#include "sim/machine_cfg.h"
#include "testing.h"

#define W 16
#define H 12

/* ---- a hand-worked case on a bare machine ---- */

/* One context: item 0 computes 10 and loads a line (a DRAM read); items
 * {1, 2, 3} compute 10 and load another line; item 4 stores 8 bytes into a
 * third line (a partial store: the L2 fetches it, after item 5 has taken
 * over) and item 5 computes 7. */
static void hand_worker(void *arg, const struct machine_worker_info *info, struct mem_port port) {
  struct machine *m = arg;
  static const uint32_t one[] = {0}, group[] = {1, 2, 3}, four[] = {4}, five[] = {5};
  machine_attribute(m, info->id, one, 1);
  mem_compute(&port, 10);
  mem_load(&port, 0, 64, 0);
  machine_attribute(m, info->id, group, 3);
  mem_compute(&port, 10);
  mem_load(&port, 64, 64, 1);
  machine_attribute(m, info->id, four, 1);
  mem_store(&port, 128, 8, 2);
  machine_attribute(m, info->id, five, 1);
  mem_compute(&port, 7);
}

static struct machine_params bare(void) {
  struct machine_cfg c;
  machine_cfg_defaults(&c);
  struct machine_params p = c.p;
  p.cores = p.threads_per_core = p.rays_per_thread = 1;
  p.l1_size_bytes = 0;
  p.fidelity = MACHINE_FIDELITY_FIXED;
  p.dram_latency_cycles = 100;
  return p;
}

static void test_hand(void) {
  struct machine_params p = bare();
  struct machine *m = machine_create(&p, 0);
  machine_costs_enable(m, 6, 3);
  machine_run(m, hand_worker, m, NULL, NULL);
  const struct machine_costs *k = machine_get_costs(m);
  const struct machine_stats *s = machine_get_stats(m);
  /* Slots: item 0 10 + 1 (its load), the group 10 + 1 = 11 split 4, 4, 3,
   * item 4 its store's slot, item 5 7. */
  const uint64_t slots[6] = {11, 4, 4, 3, 1, 7};
  for (int i = 0; i < 6; i++)
    EXPECTF(k->issue_slots[i] == slots[i], "item %d: %llu slots, want %llu", i,
            (unsigned long long)k->issue_slots[i], (unsigned long long)slots[i]);
  EXPECT(s->issue_slots == 30);
  /* Both loads missed alike (l2 latency, DRAM 100, l2 latency back): item 0
   * waited the whole first, the group splits the second. */
  const uint64_t lat = s->load_latency.sum / 2;
  EXPECTF(s->load_latency.count == 2 && lat * 2 == s->load_latency.sum && lat > 100,
          "load latency sum %llu over %llu loads", (unsigned long long)s->load_latency.sum,
          (unsigned long long)s->load_latency.count);
  EXPECT(k->load_wait_cycles[0] == lat);
  EXPECT(k->load_wait_cycles[1] == lat / 3 + (lat % 3 > 0));
  EXPECT(k->load_wait_cycles[2] == lat / 3 + (lat % 3 > 1));
  EXPECT(k->load_wait_cycles[3] == lat / 3);
  EXPECT(k->load_wait_cycles[4] == 0 && k->load_wait_cycles[5] == 0);
  /* DRAM lines: item 0 class 0; the group's one line to its first; the
   * store's fetch to item 4, though item 5 ran when it reached the L2. */
  EXPECT(k->read_lines[0][0] == 1);
  EXPECT(k->read_lines[1][1] == 1 && k->read_lines[1][2] == 0 && k->read_lines[1][3] == 0);
  EXPECT(k->read_lines[2][4] == 1 && k->read_lines[2][5] == 0);
  EXPECT(s->l2.fetch_bytes == 3 * 64);
  machine_destroy(m);
}

/* ---- every policy on a small scene ---- */

struct run {
  struct machine *m;
  struct policy_job *job;
  struct policy_worker *workers;
};

static void worker(void *arg, const struct machine_worker_info *info, struct mem_port port) {
  struct run *r = arg;
  struct policy_worker *w = &r->workers[info->id];
  if (!w->parked) policy_worker_init(w, r->job, info->id, info->core, info->thread, port);
  if (policy_job_work(r->job, w)) return;
  policy_worker_fini(r->job, w);
}

static void attribute(void *ctx, uint32_t worker_id, const uint32_t *pixels, uint32_t n) {
  machine_attribute(((struct run *)ctx)->m, worker_id, pixels, n);
}

struct result {
  struct machine_stats st;
  int64_t *acc;                         /* the framebuffer's sums */
  uint64_t sums[3 + TRACE_CLASS_COUNT]; /* slots, wait, write lines, read lines by class */
  uint64_t nonzero_pixels;              /* with issue slots */
};

static void render(const struct scene *s, const struct kd_tree *kd, enum policy_kind k,
                   const struct machine_cfg *mc, bool costs, struct result *out) {
  const struct machine_params *p = &mc->p;
  struct shade_ctx sc = {0};
  sc.scene = s;
  sc.ray_mask = RAY_MASK(RAY_TYPE_COUNT) - 1;
  sc.seed = s->seed;
  sc.shade_cycles = mc->work.cost_shade_cycles;
  struct framebuffer fb;
  struct policy_setup setup;
  memset(&setup, 0, sizeof setup);
  setup.scene = s;
  setup.kd = kd;
  trace_layout_default(&setup.layout);
  setup.layout.node_cycles = mc->work.cost_node_cycles;
  setup.layout.tri_cycles = mc->work.cost_triangle_cycles;
  setup.sc = &sc;
  fb_init(&fb, W, H, setup.layout.fb_base);
  setup.fb = &fb;
  struct run r = {0};
  if (costs) {
    setup.attribute = attribute;
    setup.attribute_ctx = &r;
  }
  struct policy_params pp;
  policy_params_machine(&pp, p->l2_size_bytes);
  pp.dyn_sharing = mc->work.dyn_sharing;
  const uint32_t n = p->cores * p->threads_per_core * p->rays_per_thread;
  r.job = policy_job_create(k, &setup, &pp, n, p->cores);
  r.workers = calloc(n, sizeof *r.workers);
  r.m = machine_create(p, 0);
  if (costs) machine_costs_enable(r.m, W * H, TRACE_CLASS_COUNT);
  machine_run(r.m, worker, &r, NULL, NULL);
  struct render_stats rs;
  policy_job_finish(r.job, &rs, NULL);
  memset(out, 0, sizeof *out);
  out->st = *machine_get_stats(r.m);
  out->acc = malloc(sizeof *fb.acc * 3 * W * H);
  memcpy(out->acc, fb.acc, sizeof *fb.acc * 3 * W * H);
  const struct machine_costs *c = machine_get_costs(r.m);
  EXPECT((c != NULL) == costs);
  for (uint32_t i = 0; c && i < W * H; i++) {
    out->sums[0] += c->issue_slots[i];
    out->sums[1] += c->load_wait_cycles[i];
    out->sums[2] += c->write_lines[i];
    for (unsigned j = 0; j < TRACE_CLASS_COUNT; j++) out->sums[3 + j] += c->read_lines[j][i];
    out->nonzero_pixels += c->issue_slots[i] > 0;
  }
  machine_destroy(r.m);
  free(r.workers);
  policy_job_destroy(r.job);
  fb_fini(&fb);
}

static bool same_machine(const struct machine_stats *a, const struct machine_stats *b) {
  return a->cycles == b->cycles && a->issue_slots == b->issue_slots && a->events == b->events &&
         a->thread_wait_cycles == b->thread_wait_cycles && a->loads == b->loads &&
         a->stores == b->stores && a->load_latency.sum == b->load_latency.sum &&
         a->l2.fetch_bytes == b->l2.fetch_bytes && a->l2.writeback_bytes == b->l2.writeback_bytes &&
         a->l2.stall_cycles[0] == b->l2.stall_cycles[0] &&
         a->dram.read_bytes == b->dram.read_bytes &&
         a->dram.read_latency.sum == b->dram.read_latency.sum &&
         a->l2.write_buffer_hits == b->l2.write_buffer_hits;
}

static void test_policies(const char *scene, const char *config, uint32_t l2_size) {
  struct scene s;
  struct kd_tree kd;
  if (!testing_load_small(&s, &kd, scene)) return;
  char path[1024];
  snprintf(path, sizeof path, "%s/configs/%s.yaml", RTSIM_SOURCE_DIR, config);
  struct machine_cfg mc;
  machine_cfg_defaults(&mc);
  struct err e;
  memset(&e, 0, sizeof e);
  CHECK(machine_cfg_load(&mc, path, &e));
  if (l2_size) mc.p.l2_size_bytes = l2_size; /* small: many write-backs */
  for (int k = 0; k < POLICY_COUNT; k++) {
    struct result on, off;
    render(&s, &kd, (enum policy_kind)k, &mc, true, &on);
    render(&s, &kd, (enum policy_kind)k, &mc, false, &off);
    const char *pn = policy_name((enum policy_kind)k);
    EXPECTF(same_machine(&on.st, &off.st), "%s %s %s: counting costs moved the machine", scene,
            config, pn);
    EXPECTF(memcmp(on.acc, off.acc, sizeof *on.acc * 3 * W * H) == 0,
            "%s %s %s: counting costs changed the image", scene, config, pn);
    const struct machine_stats *st = &on.st;
    EXPECTF(on.sums[0] == st->issue_slots, "%s %s %s: slots %llu of %llu", scene, config, pn,
            (unsigned long long)on.sums[0], (unsigned long long)st->issue_slots);
    EXPECTF(on.sums[1] == st->load_latency.sum, "%s %s %s: wait %llu of %llu", scene, config, pn,
            (unsigned long long)on.sums[1], (unsigned long long)st->load_latency.sum);
    EXPECTF(on.sums[2] * 64 == st->l2.writeback_bytes && st->l2.writeback_bytes > 0,
            "%s %s %s: write-backs %llu of %llu", scene, config, pn,
            (unsigned long long)on.sums[2] * 64, (unsigned long long)st->l2.writeback_bytes);
    for (unsigned c = 0; c < TRACE_CLASS_COUNT; c++)
      EXPECTF(on.sums[3 + c] * 64 == st->l2.fetch_bytes_by_class[c], "%s %s %s: class %u", scene,
              config, pn, c);
    /* Every pixel's rays did work of their own. */
    EXPECTF(on.nonzero_pixels == W * H, "%s %s %s: %llu pixels with slots", scene, config, pn,
            (unsigned long long)on.nonzero_pixels);
    free(on.acc);
    free(off.acc);
  }
  kd_fini(&kd);
  scene_fini(&s);
}

/* ---- rtsim run: the channels in image.exr sum to stats.json ---- */

/* cost.energy_nj (docs/outputs.md): each pixel is chip_energy_j shared by
 * its issue slots plus dram_energy_j by its DRAM lines, from the image's own
 * channels, to a float's rounding (2^-24 of the pixel); the pixels sum to
 * energy_j in nJ to 2^-24 of it. */
static void check_energy_channel(const struct image *im, const char *dir, const char *what) {
  static const char *const lines_from[] = {
      "cost.dram_write_bytes",    "cost.dram_read_bytes.geometry", "cost.dram_read_bytes.node",
      "cost.dram_read_bytes.ray", "cost.dram_read_bytes.queue",    "cost.dram_read_bytes.other"};
  const int en = image_channel(im, "cost.energy_nj"), sl = image_channel(im, "cost.issue_slots");
  EXPECTF(en >= 0 && sl >= 0, "%s: no cost.energy_nj", what);
  if (en < 0 || sl < 0) return;
  const uint32_t px = im->width * im->height;
  double slots = 0, lines = 0, sum = 0;
  for (uint32_t p = 0; p < px; p++) {
    slots += im->planes[sl][p];
    for (int c = 0; c < 6; c++) lines += im->planes[image_channel(im, lines_from[c])][p];
  }
  const double chip = testing_json_num(dir, "chip_energy_j") * 1e9,
               dram = testing_json_num(dir, "dram_energy_j") * 1e9,
               all = testing_json_num(dir, "energy_j") * 1e9;
  EXPECTF(chip > 0 && dram > 0 && lines > 0, "%s: chip %g nJ, DRAM %g nJ, %g bytes", what, chip,
          dram, lines);
  int bad = 0;
  for (uint32_t p = 0; p < px; p++) {
    double l = 0;
    for (int c = 0; c < 6; c++) l += im->planes[image_channel(im, lines_from[c])][p];
    const double want = chip * im->planes[sl][p] / slots + dram * l / lines;
    const double got = im->planes[en][p];
    sum += got;
    if (fabs(got - want) > ldexp(want, -23)) bad++;
  }
  EXPECTF(bad == 0, "%s: %d of %u pixels' energy is not their share", what, bad, px);
  EXPECTF(fabs(sum - all) <= ldexp(all, -24), "%s: cost.energy_nj sums to %.17g nJ, energy_j %.17g",
          what, sum, all);
}

static void test_command(void) {
  static const char *const policies[] = {"recursive", "packet", "dynamic", "treelet"};
  static const char *const channels[] = {
      "cost.issue_slots",           "cost.load_wait_cycles",
      "cost.dram_write_bytes",      "cost.dram_read_bytes.geometry",
      "cost.dram_read_bytes.node",  "cost.dram_read_bytes.ray",
      "cost.dram_read_bytes.queue", "cost.dram_read_bytes.other"};
  static const char *const totals[] = {
      "issue_slots",      "load_latency_cycles_sum", "l2_writeback_bytes", "fetch_geometry_bytes",
      "fetch_node_bytes", "fetch_ray_bytes",         "fetch_queue_bytes",  "fetch_other_bytes"};
  for (int i = 0; i < 4; i++) {
    char dir[512], cmd[2048], out[4096], png[600];
    snprintf(dir, sizeof dir, "%s/cost_%s", RTSIM_TMP, policies[i]);
    snprintf(png, sizeof png, "%s/cost_%s.png", RTSIM_TMP, policies[i]);
    snprintf(cmd, sizeof cmd,
             "%s run %s/configs/tiny.yaml %s/scenes/small/grove.yaml --width 12 --height 10 "
             "--policy %s -o %s --cost-preview %s --cost-channel cost.dram_read_bytes.geometry "
             "2>&1",
             RTSIM_BINARY, RTSIM_SOURCE_DIR, RTSIM_SOURCE_DIR, policies[i], dir, png);
    int rc = testing_run(cmd, out, sizeof out);
    EXPECTF(rc == 0, "%s: exit %d: %s", cmd, rc, out);
    if (rc) continue;
    FILE *f = fopen(png, "rb");
    unsigned char sig[8] = {0};
    EXPECTF(f && fread(sig, 1, 8, f) == 8 && sig[1] == 'P' && sig[2] == 'N' && sig[3] == 'G',
            "%s: no PNG heat map", png);
    if (f) fclose(f);
    char exr[600];
    snprintf(exr, sizeof exr, "%s/image.exr", dir);
    struct image im;
    struct err e;
    memset(&e, 0, sizeof e);
    EXPECTF(image_read_exr(&im, exr, &e), "%s", e.msg);
    for (int c = 0; c < 8; c++) {
      int ch = image_channel(&im, channels[c]);
      EXPECTF(ch >= 0, "%s: no channel %s", exr, channels[c]);
      if (ch < 0) continue;
      double sum = 0;
      for (uint32_t p = 0; p < im.width * im.height; p++) sum += im.planes[ch][p];
      double want = testing_json_num(dir, totals[c]);
      EXPECTF(sum == want && want == want, "%s %s: pixels sum to %.17g, %s is %.17g", policies[i],
              channels[c], sum, totals[c], want);
    }
    check_energy_channel(&im, dir, policies[i]);
    image_fini(&im);
  }
  /* Refused before anything runs: an unknown channel, a sampled run. */
  char cmd[2048], out[4096];
  snprintf(cmd, sizeof cmd,
           "%s run %s/configs/tiny.yaml %s/scenes/small/grove.yaml --width 8 --height 8 -o "
           "%s/cost_bad --cost-preview %s/cost_bad.png --cost-channel cost.nodes 2>&1",
           RTSIM_BINARY, RTSIM_SOURCE_DIR, RTSIM_SOURCE_DIR, RTSIM_TMP, RTSIM_TMP);
  int rc = testing_run(cmd, out, sizeof out);
  EXPECTF(rc == 2 && strstr(out, "cost-channel"), "exit %d: %s", rc, out);
  snprintf(cmd, sizeof cmd,
           "%s run %s/configs/tiny.yaml %s/scenes/small/grove.yaml --width 8 --height 8 -o "
           "%s/cost_bad --cost-preview %s/cost_bad.png --set sample.fraction=0.5 2>&1",
           RTSIM_BINARY, RTSIM_SOURCE_DIR, RTSIM_SOURCE_DIR, RTSIM_TMP, RTSIM_TMP);
  rc = testing_run(cmd, out, sizeof out);
  EXPECTF(rc == 2 && strstr(out, "whole timed runs"), "exit %d: %s", rc, out);
}

int main(void) {
  test_hand();
  test_policies("room", "tiny", 0);
  test_policies("grove", "default", 64 * 1024);
  test_command();
  return testing_done("test_cost");
}
