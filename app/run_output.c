/* The run's numbers: scalars computed once from the machine's counters, then
 * written as stats.json members and one stats.csv row in the same order. */
#include "app/run_output.h"

#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

#include "app/app.h"
#include "app/gnuplot.h"
#include "app/preview.h"
#include "app/rung_error.h"
#include "app/sample.h"
#include "app/spot_check.h"
#include "renderer/framebuffer.h"
#include "renderer/image.h"
#include "renderer/render.h"
#include "renderer/shade.h"
#include "renderer/trace.h"
#include "sim/analytic.h"
#include "sim/chip_energy.h"
#include "sim/derived.h"
#include "sim/dram.h"
#include "sim/dram_energy_estimate.h"
#include "sim/err.h"
#include "sim/hist.h"
#include "sim/line.h"
#include "sim/machine.h"
#include "sim/machine_cfg.h"
#include "sim/outfile.h"
#include "sim/stats.h"
#include "sim/timeline.h"

const char *const run_output_files[] = {"image.exr",   "stats.csv",  "timeline.csv",
                                        "traffic.png", "stats.json", NULL};

/* ---- the image and its cost channels ---- */

/* Issue slots, load wait, DRAM bytes read by class (trace_class_names'
 * order), DRAM bytes written back, energy. */
const char *const run_output_cost_channels[] = {"cost.issue_slots",
                                                "cost.load_wait_cycles",
                                                "cost.dram_read_bytes.geometry",
                                                "cost.dram_read_bytes.node",
                                                "cost.dram_read_bytes.ray",
                                                "cost.dram_read_bytes.queue",
                                                "cost.dram_read_bytes.other",
                                                "cost.dram_write_bytes",
                                                "cost.energy_nj",
                                                NULL};
#define COST_CHANNELS 9
_Static_assert(TRACE_CLASS_COUNT == 5, "a cost channel for each data class");

bool run_output_is_cost_channel(const char *name) {
  for (int i = 0; run_output_cost_channels[i]; i++)
    if (!strcmp(name, run_output_cost_channels[i])) return true;
  return false;
}

static struct chip_energy run_chip_energy(const struct run_output_report *r);

/* A pixel's DRAM lines, read and written. */
static uint64_t pixel_lines(const struct machine_costs *k, uint64_t i) {
  uint64_t n = k->write_lines[i];
  for (unsigned c = 0; c < k->classes; c++) n += k->read_lines[c][i];
  return n;
}

/* cost.energy_nj: the run's energy_j shared out, in nJ: the chip's (dynamic
 * and leakage) in proportion to the pixel's issue slots, the DRAM's to its
 * DRAM lines read and written (to its slots in a run that moved none). Each
 * pixel's share is a double rounded to a float. */
static void energy_plane(const struct run_output_report *r, float *plane) {
  const struct machine_costs *k = r->costs;
  const struct chip_energy ce = run_chip_energy(r);
  const double chip = chip_energy_total_j(&ce),
               dram = dram_energy_so_far(machine_dram(r->machine),
                                         machine_get_stats(r->machine)->cycles);
  uint64_t slots = 0, lines = 0;
  for (uint64_t i = 0; i < k->items; i++) {
    slots += k->issue_slots[i];
    lines += pixel_lines(k, i);
  }
  for (uint64_t i = 0; i < k->items; i++) {
    const double s = stats_ratio((double)k->issue_slots[i], (double)slots);
    const double l = lines ? (double)pixel_lines(k, i) / (double)lines : s;
    plane[i] = (float)((chip * s + dram * l) * 1e9);
  }
}

void run_output_image(const struct run_output_report *r, struct image *im) {
  struct image fb;
  fb_to_image(r->fb, &fb);
  if (!r->costs) {
    *im = fb;
    return;
  }
  const char *names[IMAGE_MAX_CHANNELS];
  uint32_t n = fb.channel_count;
  for (uint32_t c = 0; c < n; c++) names[c] = fb.names[c];
  for (int c = 0; c < COST_CHANNELS; c++) names[n + c] = run_output_cost_channels[c];
  image_init(im, fb.width, fb.height, n + COST_CHANNELS, names);
  const uint64_t px = (uint64_t)fb.width * fb.height;
  for (uint32_t c = 0; c < n; c++) memcpy(im->planes[c], fb.planes[c], px * sizeof(float));
  image_fini(&fb);
  const struct machine_costs *k = r->costs;
  CHECK_EQ(k->items, px);
  CHECK_EQ(k->classes, TRACE_CLASS_COUNT);
  /* NOTE: 32-bit floats, like cost.nodes: exact integers up to 2^24 a pixel. */
  for (uint64_t i = 0; i < px; i++) {
    im->planes[n][i] = (float)k->issue_slots[i];
    im->planes[n + 1][i] = (float)k->load_wait_cycles[i];
    for (unsigned c = 0; c < TRACE_CLASS_COUNT; c++)
      im->planes[n + 2 + c][i] = (float)((uint64_t)k->read_lines[c][i] * 64);
    im->planes[n + 7][i] = (float)((uint64_t)k->write_lines[i] * 64);
  }
  energy_plane(r, im->planes[n + 8]);
}

/* The workload's identity (first columns) and the resolved config. */
static void identity(const struct run_output_report *r, struct stats_table *t) {
  char rays[64];
  shade_rays_name(r->mask, rays, sizeof rays);
  char hash[24];
  snprintf(hash, sizeof hash, "%016llx", (unsigned long long)r->scene_hash);
  stats_str(t, "scene", r->scene_name);
  stats_str(t, "scene_hash", hash);
  stats_str(t, "accel", r->accel);
  stats_str(t, "kd_splits", r->kd_splits);
  stats_str(t, "policy", r->policy);
  stats_str(t, "rays", rays);
  stats_u64(t, "width", r->width);
  stats_u64(t, "height", r->height);
  stats_u64(t, "seed", r->seed);
}

static void energy_emit(const struct run_output_report *r, const struct chip_energy *chip,
                        double seconds, uint64_t cycles, struct stats_table *t);
static struct chip_energy analytic_chip_energy(const struct run_output_report *r);

/* ---- the run's own numbers, at the machine's slots (docs/stats.md) ----
 * The workload's counts (the renderer's) and figures of the machine that need
 * the renderer's data classes; st: the struct run_output_report. */

static double run_seconds(const struct run_output_report *r) {
  return derived_seconds((double)machine_get_stats(r->machine)->cycles, r->cfg->p.clock_ghz);
}
static uint64_t run_rays(const void *st, const struct stats_env *env) {
  (void)env;
  return render_stats_total(((const struct run_output_report *)st)->rstats);
}
static double run_rays_per_second(const void *st, const struct stats_env *env) {
  return derived_rays_per_second((double)run_rays(st, env), run_seconds(st));
}
static uint64_t run_node_visits(const void *st, const struct stats_env *env) {
  (void)env;
  return ((const struct run_output_report *)st)->tstats->node_visits;
}
static uint64_t run_tri_tests(const void *st, const struct stats_env *env) {
  (void)env;
  return ((const struct run_output_report *)st)->tstats->tri_tests;
}
static double run_slots_per_geometry_miss(const void *st, const struct stats_env *env) {
  (void)env;
  const struct machine_stats *s =
      machine_get_stats(((const struct run_output_report *)st)->machine);
  const uint64_t *by = s->l2.fetch_bytes_by_class;
  uint64_t geo_misses = (by[TRACE_CLASS_GEOMETRY] + by[TRACE_CLASS_NODE]) / SIM_LINE_BYTES;
  return stats_ratio((double)s->issue_slots, (double)geo_misses);
}

static const struct stats_desc run_desc[] = {
    STATS_FN_U64(run_rays, "rays_traced", "count", "rays traced, every kind"),
    STATS_FN_F64(run_rays_per_second, "rays_per_second", "per second", "rays traced / seconds"),
    STATS_FN_U64(run_node_visits, "kd_node_visits", "count",
                 "nodes of the traced structure visited (accel: k-d tree or BVH nodes)"),
    STATS_FN_U64(run_tri_tests, "triangle_tests", "count", "ray-triangle tests"),
};
static const struct stats_desc run_misses_desc[] = {
    STATS_FN_F64(run_slots_per_geometry_miss, "issue_slots_per_geometry_miss", "cycles",
                 "issue slots / lines of triangles or k-d nodes read from the DRAM"),
};
const struct stats_descs run_output_stats_descs = {"run", run_desc, STATS_COUNT(run_desc),
                                                   0,     NULL,     0};
const struct stats_descs run_output_misses_stats_descs = {
    "run", run_misses_desc, STATS_COUNT(run_misses_desc), 0, NULL, 0};

/* ---- fidelity analytic's numbers ----
 * What its counts and estimate know, under the timed rungs' names and in
 * their order; what only time tells (threads' idle time, switches, waits,
 * merges, stalls, queues, latencies, events) is absent. Then its own numbers,
 * analytic_* (docs/fidelity-and-sampling.md). st: the struct app_analytic; env->ctx:
 * the struct run_output_report. */

#define AN(f) offsetof(struct app_analytic, f), STATS_FIELD_SIZE(struct app_analytic, f)
static const struct analytic_counts *an_n(const void *st) {
  return &((const struct app_analytic *)st)->counts;
}
static const struct machine_params *an_p(const struct stats_env *env) {
  return &((const struct run_output_report *)env->ctx)->cfg->p;
}
static uint64_t an_threads(const void *st, const struct stats_env *env) {
  (void)st;
  return derived_threads(an_p(env));
}
static uint64_t an_contexts(const void *st, const struct stats_env *env) {
  (void)st;
  return derived_contexts(an_p(env));
}
static double an_seconds(const void *st, const struct stats_env *env) {
  (void)st;
  return derived_seconds((double)env->cycles, an_p(env)->clock_ghz);
}
static uint64_t an_rays(const void *st, const struct stats_env *env) {
  (void)st;
  return run_rays(env->ctx, env);
}
static double an_rays_per_second(const void *st, const struct stats_env *env) {
  return derived_rays_per_second((double)an_rays(st, env), an_seconds(st, env));
}
static uint64_t an_node_visits(const void *st, const struct stats_env *env) {
  (void)st;
  return run_node_visits(env->ctx, env);
}
static uint64_t an_tri_tests(const void *st, const struct stats_env *env) {
  (void)st;
  return run_tri_tests(env->ctx, env);
}
static double an_core_utilization(const void *st, const struct stats_env *env) {
  return derived_core_utilization((double)an_n(st)->issue_slots, (double)an_p(env)->cores,
                                  (double)env->cycles);
}
static double an_slots_per_blocking_load(const void *st, const struct stats_env *env) {
  (void)env;
  return stats_ratio((double)an_n(st)->issue_slots, (double)an_n(st)->blocking_loads);
}
static double an_slots_per_geometry_miss(const void *st, const struct stats_env *env) {
  (void)env;
  const uint64_t *by = an_n(st)->fetch_bytes_by_class;
  uint64_t geo_misses = (by[TRACE_CLASS_GEOMETRY] + by[TRACE_CLASS_NODE]) / SIM_LINE_BYTES;
  return stats_ratio((double)an_n(st)->issue_slots, (double)geo_misses);
}
static double an_l2_miss_rate(const void *st, const struct stats_env *env) {
  (void)env;
  return stats_ratio((double)an_n(st)->l2_misses, (double)an_n(st)->l2_accesses);
}
static uint64_t an_dram_reads(const void *st, const struct stats_env *env) {
  (void)env;
  return an_n(st)->fetch_bytes / 64;
}
static uint64_t an_dram_writes(const void *st, const struct stats_env *env) {
  (void)env;
  return an_n(st)->writeback_bytes / 64;
}
static double an_dram_bytes_per_cycle(const void *st, const struct stats_env *env) {
  return stats_ratio((double)(an_n(st)->fetch_bytes + an_n(st)->writeback_bytes),
                     (double)env->cycles);
}
#define AN_EST(f)                                                                                  \
  static double an_est_##f(const void *st, const struct stats_env *env) {                          \
    (void)env;                                                                                     \
    return ((const struct app_analytic *)st)->est.f;                                               \
  }
AN_EST(slots_per_blocking)
AN_EST(blocking_miss_rate)
AN_EST(load_latency_cycles)
AN_EST(core_utilization)
AN_EST(latency_bound_cycles)
AN_EST(bandwidth_bound_cycles)
#undef AN_EST

#define AN_FIELD(f, nm, un, ds) STATS_FIELD(struct app_analytic, f, nm, un, ds)
#define AN_U64(f, fn, nm, un, ds)                                                                  \
  { .name = nm, .unit = un, .desc = ds, .how = STATS_HOW_U64, AN(f), .u64 = fn }
#define AN_F64(f, fn, nm, un, ds)                                                                  \
  { .name = nm, .unit = un, .desc = ds, .how = STATS_HOW_F64, AN(f), .f64 = fn }
static const struct stats_desc analytic_desc[] = {
    AN_FIELD(est.cycles, "cycles", "cycles", "the estimate: the larger of its two bounds"),
    STATS_FN_F64(an_seconds, "seconds", "seconds", "the estimate at clock_ghz"),
    STATS_FN_U64(an_rays, "rays_traced", "count", "rays traced, every kind"),
    STATS_FN_F64(an_rays_per_second, "rays_per_second", "per second", "rays traced / seconds"),
    STATS_FN_U64(an_node_visits, "kd_node_visits", "count",
                 "nodes of the traced structure visited (accel: k-d tree or BVH nodes)"),
    STATS_FN_U64(an_tri_tests, "triangle_tests", "count", "ray-triangle tests"),
    STATS_FN_U64(an_contexts, "ray_contexts", "count", "ray contexts: cores x threads x rays"),
    STATS_FN_U64(an_threads, "threads", "count", "hardware threads: cores x threads_per_core"),
    AN_FIELD(counts.issue_slots, "issue_slots", "cycles",
             "issue slots the work takes (compute, loads, stores)"),
    AN_F64(counts.issue_slots, an_core_utilization, "core_utilization", "fraction",
           "issue slots / cores x cycles"),
    AN_FIELD(counts.loads, "loads", "count", "loads"),
    AN_FIELD(counts.stores, "stores", "count", "stores"),
    AN_FIELD(counts.blocking_loads, "blocking_loads", "count",
             "loads of a line the L1 did not hold"),
    AN_F64(counts.blocking_loads, an_slots_per_blocking_load, "issue_slots_per_blocking_load",
           "cycles", "issue slots / blocking loads"),
    AN_F64(counts.fetch_bytes_by_class, an_slots_per_geometry_miss, "issue_slots_per_geometry_miss",
           "cycles", "issue slots / lines of triangles or k-d nodes read from the DRAM"),
    AN_FIELD(counts.l1_accesses, "l1_accesses", "count", "lines of loads reaching the L1s"),
    AN_FIELD(counts.l1_hits, "l1_hits", "count", "those the L1 held"),
    AN_FIELD(counts.l2_accesses, "l2_accesses", "count", "accesses that reached the L2"),
    AN_FIELD(counts.l2_hits, "l2_hits", "count", "those the L2 held"),
    AN_FIELD(counts.l2_misses, "l2_misses", "count", "those it fetched from the DRAM"),
    AN_F64(counts.l2_misses, an_l2_miss_rate, "l2_miss_rate", "fraction",
           "l2_misses / l2_accesses"),
    AN_FIELD(counts.l2_whole_line_allocs, "l2_whole_line_allocs", "count",
             "lines a store wrote whole, allocated without a fetch"),
    AN_FIELD(counts.fetch_bytes, "l2_fetch_bytes", "bytes", "bytes the L2 fetched from the DRAM"),
    AN_FIELD(counts.writeback_bytes, "l2_writeback_bytes", "bytes",
             "bytes the L2 wrote back to the DRAM"),
    {.name = "fetch_%s_bytes",
     .unit = "bytes",
     .desc = "of the bytes fetched, those of each data class",
     .how = STATS_HOW_FIELD,
     AN(counts.fetch_bytes_by_class),
     .per_class = true},
    AN_U64(counts.fetch_bytes, an_dram_reads, "dram_reads", "count", "lines read from the DRAM"),
    AN_U64(counts.writeback_bytes, an_dram_writes, "dram_writes", "count",
           "lines written to the DRAM"),
    AN_FIELD(counts.fetch_bytes, "dram_read_bytes", "bytes", "bytes read from the DRAM"),
    AN_FIELD(counts.writeback_bytes, "dram_write_bytes", "bytes", "bytes written to the DRAM"),
    AN_F64(counts.fetch_bytes, an_dram_bytes_per_cycle, "dram_bytes_per_cycle", "bytes/cycle",
           "DRAM bytes read and written / cycles"),
    STATS_AT("dram_energy"),
    AN_F64(est.slots_per_blocking, an_est_slots_per_blocking, "analytic_slots_per_blocking_load",
           "cycles", "c: issue slots per blocking load (0 when no load blocks)"),
    AN_F64(est.blocking_miss_rate, an_est_blocking_miss_rate, "analytic_blocking_miss_rate",
           "fraction", "the share of blocking loads that miss the L2"),
    AN_F64(est.load_latency_cycles, an_est_load_latency_cycles, "analytic_load_latency_cycles",
           "cycles", "L: the cycles a ray gives up its issue slots per blocking load"),
    AN_F64(est.core_utilization, an_est_core_utilization, "analytic_core_utilization", "fraction",
           "u = min(1, n c / (c + L)), n the ray contexts a core"),
    AN_F64(est.latency_bound_cycles, an_est_latency_bound_cycles, "analytic_latency_bound_cycles",
           "cycles", "issue slots / (cores x u)"),
    AN_F64(est.bandwidth_bound_cycles, an_est_bandwidth_bound_cycles,
           "analytic_bandwidth_bound_cycles", "cycles", "DRAM bytes / dram.bytes_per_cycle"),
};
#undef AN
#undef AN_FIELD
#undef AN_U64
#undef AN_F64
const struct stats_descs run_output_analytic_stats_descs = {
    "analytic", analytic_desc, STATS_COUNT(analytic_desc), 0, NULL, 0};

/* ---- what only stats.json holds of a whole timed run ---- (st: the
 * struct run_output_report; then its histograms) */
static uint64_t json_latency_sum(const void *st, const struct stats_env *env) {
  (void)env;
  return machine_get_stats(((const struct run_output_report *)st)->machine)->load_latency.sum;
}
static uint64_t json_window(const void *st, const struct stats_env *env) {
  (void)env;
  return machine_timeline(((const struct run_output_report *)st)->machine)->window;
}
static const struct stats_desc json_desc[] = {
    {.name = "load_latency_cycles_sum",
     .unit = "cycles",
     .desc = "loads' latencies summed: the exact total the cost.load_wait_cycles channel sums to "
             "(stats.json only)",
     .how = STATS_HOW_U64,
     .u64 = json_latency_sum},
    {.name = "timeline_window_cycles",
     .unit = "cycles",
     .desc = "a timeline.csv row's window at the end of the run (stats.json only)",
     .how = STATS_HOW_U64,
     .u64 = json_window},
};
const struct stats_descs run_output_json_stats_descs = {"run", json_desc, STATS_COUNT(json_desc),
                                                        0,     NULL,      0};

/* Every measured scalar, units in the names. */
void run_output_measured(const struct run_output_report *r, struct stats_table *t) {
  if (r->analytic) {
    struct stats_env env = {.cycles = r->analytic->est.cycles,
                            .ctx = r,
                            .class_names = trace_class_names,
                            .classes = TRACE_CLASS_COUNT};
    /* The DRAM energy estimate every cheaper rung makes, over the estimate's
     * cycles (sim/dram_energy_estimate.h). */
    const struct machine_params *p = &r->cfg->p;
    struct dram_energy_estimate_in in = {.p = p->dram_banked,
                                         .reads = r->analytic->counts.fetch_bytes / 64,
                                         .writes = r->analytic->counts.writeback_bytes / 64,
                                         .dram_per = p->dram_clock_mhz,
                                         .core_per = p->clock_ghz * 1000};
    in.p.clock_mhz = p->dram_clock_mhz;
    const struct stats_part part = {"dram_energy", &dram_energy_estimate_stats_descs, &in, NULL};
    env.parts = &part;
    env.nparts = 1;
    stats_emit(t, &run_output_analytic_stats_descs, r->analytic, &env);
    env.parts = NULL;
    env.nparts = 0;
    const struct chip_energy chip = analytic_chip_energy(r);
    energy_emit(r, &chip, derived_seconds(r->analytic->est.cycles, p->clock_ghz),
                (uint64_t)llround(r->analytic->est.cycles), t);
    if (r->rung) stats_emit(t, &rung_error_stats_descs, r->rung, &env);
    if (r->spot) stats_emit(t, &spot_check_stats_descs, r->spot, &env);
    return;
  }
  const struct machine_stats *s = machine_get_stats(r->machine);
  const struct machine_params *p = &r->cfg->p;
  const double peak = machine_dram_peak_bytes_per_cycle(p);
  if (r->sample) {
    /* Estimates with their intervals; the machine's own counters cover only
     * the detailed units, so they are not written. */
    sample_stats(r->sample, p->clock_ghz, peak, s->contexts, s->threads, t);
    return;
  }
  const struct stats_part run_parts[] = {
      {MACHINE_STATS_AT_RUN, &run_output_stats_descs, r, NULL},
      {MACHINE_STATS_AT_RUN_MISSES, &run_output_misses_stats_descs, r, NULL},
  };
  machine_stats_emit(r->machine, t, trace_class_names, TRACE_CLASS_COUNT, run_parts,
                     STATS_COUNT(run_parts));
  const struct chip_energy chip = run_chip_energy(r);
  energy_emit(r, &chip, run_seconds(r), s->cycles, t);
  if (r->rung) stats_emit(t, &rung_error_stats_descs, r->rung, &(struct stats_env){0});
  if (r->spot) stats_emit(t, &spot_check_stats_descs, r->spot, &(struct stats_env){0});
}

/* The run's energy (sim/chip_energy.h) after the machine's numbers: the
 * chip's as given, the DRAM's as its level (or the cheaper rung's estimate)
 * wrote it in t (dram_energy_j). */
static void energy_emit(const struct run_output_report *r, const struct chip_energy *chip,
                        double seconds, uint64_t cycles, struct stats_table *t) {
  struct chip_energy_report rep = {
      .chip = *chip, .seconds = seconds, .rays = render_stats_total(r->rstats)};
  for (unsigned i = 0; i < t->n; i++)
    if (!strcmp(t->e[i].name, "dram_energy_j") && t->e[i].kind == STATS_F64) {
      rep.has_dram = true;
      rep.dram_j = t->e[i].f;
    }
  stats_emit(t, &chip_energy_stats_descs, &rep, &(struct stats_env){.cycles = cycles});
}

/* The chip's energy from counts c (the machine's shape filled in here), with
 * the config's figures. */
static struct chip_energy chip_energy_of(const struct machine_params *p,
                                         struct chip_energy_counts c) {
  c.cores = p->cores;
  c.l1_size_bytes = p->l1_size_bytes;
  c.l2_size_bytes = p->l2_size_bytes;
  const struct chip_energy_params ep =
      chip_energy_resolve(&p->energy, p->l1_size_bytes, p->l2_size_bytes);
  struct chip_energy e;
  chip_energy_compute(&ep, &c, &e);
  return e;
}

/* At fidelity analytic: the counting backend's counts over the estimate's
 * time. It models no ray switch; a thread gives up its slots at each
 * blocking load (the estimate's own rule), so each counts as one. */
static struct chip_energy analytic_chip_energy(const struct run_output_report *r) {
  const struct machine_params *p = &r->cfg->p;
  const struct analytic_counts *n = &r->analytic->counts;
  const struct chip_energy_counts c = {.seconds =
                                           derived_seconds(r->analytic->est.cycles, p->clock_ghz),
                                       .issue_slots = n->issue_slots,
                                       .loads = n->loads,
                                       .stores = n->stores,
                                       .ray_switches = n->blocking_loads,
                                       .l1_accesses = n->l1_accesses,
                                       .l1_hits = n->l1_hits,
                                       .l2_accesses = n->l2_accesses,
                                       .l2_misses = n->l2_misses,
                                       .l2_writeback_lines = n->writeback_bytes / SIM_LINE_BYTES};
  return chip_energy_of(p, c);
}

static struct chip_energy run_chip_energy(const struct run_output_report *r) {
  const struct machine_stats *s = machine_get_stats(r->machine);
  const struct machine_params *p = &r->cfg->p;
  const struct chip_energy_counts c = {.seconds = run_seconds(r),
                                       .issue_slots = s->issue_slots,
                                       .loads = s->loads,
                                       .stores = s->stores,
                                       .ray_switches = s->ray_switches,
                                       .l1_accesses = s->l1_accesses,
                                       .l1_hits = s->l1_hits,
                                       .l2_accesses = s->l2.accesses,
                                       .l2_misses = s->l2.misses,
                                       .l2_writeback_lines =
                                           s->l2.writeback_bytes / SIM_LINE_BYTES};
  return chip_energy_of(p, c);
}

/* Start OUTDIR/name through a temporary (commit with outfile_commit). */
static bool open_out(struct outfile *o, const struct run_output_report *r, const char *name,
                     struct err *e) {
  char path[4200];
  snprintf(path, sizeof path, "%s/%s", r->out_dir, name);
  return outfile_open(o, path, "the file", e);
}

static bool write_csv(const struct run_output_report *r, struct err *e) {
  struct outfile o;
  if (!open_out(&o, r, "stats.csv", e)) return false;
  struct stats_table t = {0};
  identity(r, &t);
  machine_cfg_to_stats(r->cfg, &t);
  run_output_measured(r, &t);
  stats_write_csv_header(&t, o.f);
  stats_write_csv_row(&t, o.f);
  stats_fini(&t);
  return outfile_commit(&o, e);
}

static bool write_timeline(const struct run_output_report *r, struct err *e) {
  struct outfile o;
  if (!open_out(&o, r, "timeline.csv", e)) return false;
  timeline_write_csv(machine_timeline(r->machine), machine_tl_cols, machine_tl_col_count,
                     trace_class_names, TRACE_CLASS_COUNT, machine_get_stats(r->machine)->cycles,
                     o.f);
  return outfile_commit(&o, e);
}

/* timeline.csv's header of the machine's timeline column col. */
static void tl_header(unsigned col, char *buf, size_t len) {
  timeline_col_header(machine_tl_cols, machine_tl_col_count, col, trace_class_names, buf, len);
}

/* The plot's second panel: power over the run, the whole and its three parts
 * (a part's joules in a window over the window's seconds), from timeline.csv's
 * energy columns by name, into cmd; x: the time axis's expression. */
static void power_panel(const struct run_output_report *r, const char *csv, const char *x,
                        char *cmd, size_t cap) {
  static const struct {
    unsigned col;
    const char *colour, *title;
  } PARTS[] = {{MACHINE_TL_DRAM_ENERGY, "#0072B2", "DRAM"},
               {MACHINE_TL_CHIP_DYNAMIC_ENERGY, "#D55E00", "chip dynamic (L1s, L2, cores)"},
               {MACHINE_TL_CHIP_LEAKAGE_ENERGY, "#009E73", "chip leakage"}};
  char col[64];
  tl_header(MACHINE_TL_POWER, col, sizeof col);
  int n = snprintf(cmd, cap,
                   "set title 'Power: the energy of each window over its seconds'\n"
                   "set ylabel 'watts'\n"
                   "plot '%s' using %s:(column(\"%s\")) with steps lw 2 lc rgb 'black' "
                   "title 'all'",
                   csv, x, col);
  for (unsigned i = 0; i < sizeof PARTS / sizeof PARTS[0]; i++) {
    tl_header(PARTS[i].col, col, sizeof col);
    n += snprintf(cmd + n, cap - (size_t)n,
                  ", '' using %s:(column(\"%s\")/column(\"cycles\")*%.17g) with steps lw 1.5 "
                  "lc rgb '%s' title '%s'",
                  x, col, derived_hz(r->cfg->p.clock_ghz), PARTS[i].colour, PARTS[i].title);
  }
  snprintf(cmd + n, cap - (size_t)n, "\nunset multiplot\n");
}

/* DRAM bytes per cycle over the run by data class, read from timeline.csv by
 * the columns' header names (from the machine's column table), so a column
 * added to the timeline cannot shift the plot. The legend sits under the
 * plot (beside it, it took a third of the width); the classes take Okabe and
 * Ito's colour-blind-safe colours (gnuplot's own gave two classes near-equal
 * yellows); a dashed line marks the DRAM's peak, where it has one. */
static bool write_plot(const struct run_output_report *r, struct err *e) {
  static const char *const COLOURS[] = {"#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00"};
  char csv[4200], final[4200], cmd[8192];
  snprintf(csv, sizeof csv, "%s/timeline.csv", r->out_dir);
  snprintf(final, sizeof final, "%s/traffic.png", r->out_dir);
  struct outfile o;
  if (!outfile_open_named(&o, final, "the plot", e)) return false;
  struct gnuplot gnu;
  if (!gnuplot_open(&gnu, true)) {
    outfile_abort(&o);
    return err_set(e, final, 0, 0, "cannot run gnuplot (install gnuplot-nox)");
  }
  char rd[64], wr[64], cls[64];
  tl_header(MACHINE_TL_DRAM_READ_BYTES, rd, sizeof rd);
  tl_header(MACHINE_TL_DRAM_WRITE_BYTES, wr, sizeof wr);
  /* The window's middle, in millions of cycles (timeline_write_csv's first two
   * columns: the window's start and length). */
  static const char x[] = "((column(\"cycle\")+column(\"cycles\")/2)/1e6)";
  int n = snprintf(
      cmd, sizeof cmd,
      "set terminal pngcairo size 1000,1000 noenhanced font ',12'\nset output '%s'\n"
      "set datafile separator ','\nset datafile columnheaders\n"
      "set multiplot layout 2,1\nset lmargin 12\nset rmargin 4\n"
      "set key outside bottom center horizontal Left reverse samplen 3 spacing 1.2\n"
      "set title 'DRAM traffic per cycle: %s, %s policy, %ux%u (window %llu cycles)'\n"
      "set xlabel 'simulated time (million cycles)'\n"
      "set ylabel 'DRAM bytes per cycle'\nset grid\nset yrange [0:*]\n"
      "plot '%s' using %s:((column(\"%s\")+column(\"%s\"))/column(\"cycles\")) with steps lw 2 "
      "lc rgb 'black' title 'all (read + write)'",
      o.tmp, r->scene_name, r->policy, r->width, r->height,
      (unsigned long long)machine_timeline(r->machine)->window, csv, x, rd, wr);
  for (unsigned c = 0; c < TRACE_CLASS_COUNT; c++) {
    tl_header(MACHINE_TL_READ_CLASS0 + c, cls, sizeof cls);
    n += snprintf(cmd + n, sizeof cmd - (size_t)n,
                  ", '' using %s:(column(\"%s\")/column(\"cycles\")) with steps lw 1.5 lc rgb '%s' "
                  "title 'read: %s'",
                  x, cls, COLOURS[c % 5], trace_class_names[c]);
  }
  n += snprintf(cmd + n, sizeof cmd - (size_t)n,
                ", '' using %s:(column(\"%s\")/column(\"cycles\")) with steps lw 1.5 lc rgb "
                "'#56B4E9' title 'write-backs'",
                x, wr);
  /* The peak as a constant function, so the y range reaches it. */
  const double peak = machine_dram_peak_bytes_per_cycle(&r->cfg->p);
  if (peak > 0)
    n += snprintf(cmd + n, sizeof cmd - (size_t)n,
                  ", %.17g with lines dt 2 lw 2 lc rgb 'gray20' title 'DRAM peak (%.4g bytes per "
                  "cycle)'",
                  peak, peak);
  n += snprintf(cmd + n, sizeof cmd - (size_t)n, "\n");
  power_panel(r, csv, x, cmd + n, sizeof cmd - (size_t)n);
  fputs(cmd, gnu.in);
  if (!gnuplot_close(&gnu)) {
    outfile_abort(&o);
    return err_set(e, final, 0, 0, "gnuplot could not draw the plot (is gnuplot-nox installed?)");
  }
  return outfile_commit(&o, e);
}

static bool write_json(const struct run_output_report *r, struct err *e) {
  struct outfile o;
  if (!open_out(&o, r, "stats.json", e)) return false;
  FILE *f = o.f;
  struct stats_table t = {0};
  identity(r, &t);
  fputs("{\n  \"tool\": \"rtsim run\",\n  \"machine_file\": ", f);
  stats_write_json_str(f, r->machine_path);
  fputs(",\n  \"scene_file\": ", f);
  stats_write_json_str(f, r->scene_path);
  fputs(",\n", f);
  stats_write_json_members(&t, f, "  ");
  stats_fini(&t);
  fputs(",\n  \"config\": {\n", f);
  machine_cfg_write_json(r->cfg, f, "    ");
  fputs("\n  },\n", f);
  run_output_measured(r, &t);
  stats_write_json_members(&t, f, "  ");
  stats_fini(&t);
  if (r->machine && !r->sample) { /* a whole timed run: its timeline and latency histograms */
    const struct machine_stats *s = machine_get_stats(r->machine);
    const struct stats_env env = {.cycles = s->cycles};
    stats_emit(&t, &run_output_json_stats_descs, r, &env);
    fputs(",\n", f);
    stats_write_json_members(&t, f, "  ");
    stats_fini(&t);
    fputs(",\n  \"load_latency_histogram_cycles\": ", f);
    hist_write_json(&s->load_latency, f);
    fputs(",\n  \"dram_read_latency_histogram_cycles\": ", f);
    hist_write_json(&s->dram.read_latency, f);
  }
  fputs(",\n  \"revision\": ", f);
  stats_write_json_str(f, app_revision);
  /* Which machine ran it, for a sweep's provenance (rtsim merge). */
  char host[256] = "";
  if (gethostname(host, sizeof host - 1) != 0) host[0] = '\0';
  fputs(",\n  \"host\": ", f);
  stats_write_json_str(f, host[0] ? host : "unknown");
  fputs(",\n  \"wall_s\": ", f);
  stats_write_json_f64(f, r->wall_s);
  struct rusage ru;
  if (getrusage(RUSAGE_SELF, &ru) == 0)
    fprintf(f, ",\n  \"peak_rss_mb\": %.1f", (double)ru.ru_maxrss / 1024.0);
  fputs("\n}\n", f);
  return outfile_commit(&o, e);
}

bool run_output_write(const struct run_output_report *r, struct err *e) {
  char path[4200];
  snprintf(path, sizeof path, "%s/image.exr", r->out_dir);
  struct image im;
  run_output_image(r, &im);
  bool ok = image_write_exr(&im, path, false, e);
  if (ok && r->cost_preview && r->costs) {
    char title[128], sub[256], units[64];
    snprintf(title, sizeof title, "%s per pixel", r->cost_channel);
    snprintf(sub, sizeof sub, "%s, %s policy, %ux%u", r->scene_name, r->policy, r->width,
             r->height);
    const char *u = strstr(r->cost_channel, "bytes")    ? "bytes"
                    : strstr(r->cost_channel, "slots")  ? "issue slots (core cycles)"
                    : strstr(r->cost_channel, "energy") ? "nJ"
                                                        : "cycles";
    snprintf(units, sizeof units, "%s a pixel", u);
    ok = preview_write_heat_png(&im, r->cost_channel, title, sub, units, r->cost_max,
                                r->cost_preview, e);
  }
  image_fini(&im);
  /* stats.json last: it marks the directory complete. At fidelity analytic
   * there is no time line to write or plot, and a sampled run's is the
   * detailed units' time only (an earlier run's is not carried over into the
   * new directory: app/outdir.h). */
  ok = ok && write_csv(r, e);
  if (ok && r->machine && !r->sample) ok = write_timeline(r, e) && write_plot(r, e);
  return ok && write_json(r, e);
}

/* Every table of numbers a run writes, in the order machine_stats_emit fills
 * the machine's slots: what --help-stats prints and run_output_unit_of reads. */
static const struct stats_descs *const STATS_TABLES[] = {&machine_stats_descs,
                                                         &run_output_stats_descs,
                                                         &run_output_misses_stats_descs,
                                                         &machine_l1_stats_descs,
                                                         &l2_stats_descs,
                                                         &dram_stats_descs,
                                                         &machine_dram_util_stats_descs,
                                                         &dram_channel_stats_descs,
                                                         &dram_banked_stats_descs,
                                                         &dram_energy_estimate_stats_descs,
                                                         &machine_engine_stats_descs,
                                                         &chip_energy_stats_descs,
                                                         &run_output_json_stats_descs,
                                                         &run_output_analytic_stats_descs,
                                                         &sample_stats_descs,
                                                         &rung_error_stats_descs,
                                                         &spot_check_stats_descs};
#define STATS_TABLE_COUNT (sizeof STATS_TABLES / sizeof STATS_TABLES[0])

void run_output_stats_help(FILE *f, bool markdown) {
  for (unsigned i = 0; i < STATS_TABLE_COUNT; i++)
    (markdown ? stats_write_markdown : stats_write_help)(STATS_TABLES[i], f);
  timeline_write_help(machine_tl_cols, machine_tl_col_count, markdown, f);
}

/* Whether name is format (one %s: a data class) with a class put in. Class
 * names are lowercase words (trace_class_names; per_class names take the
 * renderer's at run time, so any such word is one): a class part of other
 * characters, or none, is no match. */
static bool per_class_match(const char *format, const char *name) {
  const char *pc = strstr(format, "%s");
  if (!pc) return false;
  size_t pre = (size_t)(pc - format), suf = strlen(pc + 2), n = strlen(name);
  if (n <= pre + suf || strncmp(name, format, pre) || strcmp(name + n - suf, pc + 2)) return false;
  for (size_t i = pre; i < n - suf; i++)
    if (!((name[i] >= 'a' && name[i] <= 'z') || (name[i] >= '0' && name[i] <= '9'))) return false;
  return true;
}

/* A name the tables hold under one unit: the first match wins (a name in two
 * tables, seconds in the machine's and the sampled run's, has one unit). */
static const char *unit_in_tables(const char *name, bool per_class) {
  for (unsigned t = 0; t < STATS_TABLE_COUNT; t++)
    for (unsigned i = 0; i < STATS_TABLES[t]->n; i++) {
      const struct stats_desc *d = &STATS_TABLES[t]->d[i];
      if (d->how == STATS_HOW_AT || d->per_class != per_class) continue;
      if (per_class ? per_class_match(d->name, name) : !strcmp(d->name, name)) return d->unit;
    }
  for (unsigned j = 0; j < machine_tl_col_count; j++) {
    const struct timeline_col *c = &machine_tl_cols[j];
    if (c->per_class != per_class) continue;
    if (per_class ? per_class_match(c->name, name) : !strcmp(c->name, name)) return c->unit;
  }
  return NULL;
}

const char *run_output_unit_of(const char *name) {
  for (unsigned i = 0; i < machine_cfg_count(); i++)
    if (!strcmp(machine_cfg_key(i), name)) return machine_cfg_unit(i);
  /* Whole names first: a fixed name never yields to a class pattern it fits. */
  const char *u = unit_in_tables(name, false);
  return u ? u : unit_in_tables(name, true);
}
