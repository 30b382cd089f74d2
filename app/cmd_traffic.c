/* rtsim traffic and rtsim trace: DRAM-to-L2 traffic of the scheduling policies
 * for every cache size at once (functional backend, one-pass LRU analysis), and
 * the raw access stream as a Dinero IV din trace. */
#include "app/app.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "app/opts.h"
#include "app/outguard.h"
#include "renderer/bvh.h"
#include "renderer/framebuffer.h"
#include "renderer/policy/policy.h"
#include "renderer/policy/qpoint.h"
#include "renderer/shade.h"
#include "renderer/trace.h"
#include "sim/din.h"
#include "sim/err.h"
#include "sim/lru_stack.h"
#include "sim/mem_functional.h"
#include "sim/outfile.h"

#define MIB (1024.0 * 1024.0)

static const char TRAFFIC_HELP[] =
    "usage: rtsim traffic SCENE.yaml --rays CONFIG [options] -o TABLE.csv\n"
    "\n"
    "Measure the traffic from DRAM into a fully associative LRU L2 with 64-byte lines\n"
    "for every size from 1 KB to 4 MB (powers of two) in one pass over the access\n"
    "stream, for each scheduling policy, as the paper's Figures 5-7. The recursive and\n"
    "packet schedules do not depend on the cache size and run once; the dynamic and\n"
    "treelet ones are made for a cache size, so they run once per size.\n"
    "\n"
    "example (the paper's Figure 5, primary rays, on a small scene):\n"
    "  rtsim traffic scenes/small/sphereflake.yaml --rays primary -o build/traffic.csv\n"
    "\n"
    "options:\n"
    "  --rays CONFIG       the paper's configurations: primary; shadow (primary + hard\n"
    "                      shadows); specular (+ shadows + specular); diffuse (+ shadows\n"
    "                      + diffuse); or an explicit list such as primary,diffuse\n"
    "  --policy P          a policy or all (default: the paper's three, recursive,\n"
    "                      packet and dynamic; relative columns need recursive):\n"
    "                        {policies}\n"
    "  --width W --height H  image size (default: the scene's)\n"
    "  --accel A           the structure traced: kd, bvh2 or bvh8 (default: the scene's\n"
    "                      accel key)\n"
    "  --dyn-batch N       dynamic: admit N primary rays at a time, each batch traced\n"
    "                      through all its generations (default 0: all at once)\n"
    "  --dyn-ray-buffer B  dynamic: bytes of cache reserved for the rays being traced\n"
    "                      (default 4096: 64 rays; 0: one ray, as rtsim run's)\n"
    "  --threads N         host threads: 2 runs the cache analyser beside the tracer\n"
    "                      (default: 2 when this process may use two host CPUs)\n"
    "  -o, --output FILE   CSV to write (required), one row per policy and cache size\n"
    "  -h, --help          this text; --help-full: also the columns\n"
    "\f"
    "\n"
    "--dyn-ray-buffer is also the rays streamed at once against a block of an\n"
    "oversized leaf's geometry. --threads 2 gives the same numbers, in less time\n"
    "with a host core to spare; 1 runs tracer and analyser on one.\n"
    "\n"
    "Columns: scene, rays, width, height, policy, cache_bytes; frac_pot_vis (cache size\n"
    "over the potentially visible geometry's bytes); geometry_mb (triangles + k-d nodes\n"
    "and leaf lists) and total_mb fetched from DRAM (MB = 2^20 bytes); rel_geometry and\n"
    "rel_total (over recursive at the same size); then fetched bytes by data class\n"
    "(fetch_geometry ... fetch_other), dirty write-back bytes (writeback_bytes), line\n"
    "accesses, and the potentially visible triangles and their bytes; last, the\n"
    "dynamic policy's settings as given (dyn_batch, dyn_ray_buffer_bytes: the same on\n"
    "every row; they change the dynamic rows only); and kd_splits, the scene's k-d\n"
    "tree (whole: PBRT's, the paper's; clipped: perfect splits; scene key kd_tree), and\n"
    "accel, the structure traced (kd, bvh2 or bvh8: the scene's accel key; geometry_mb\n"
    "then counts the BVH's nodes and leaf lists).\n";

/* The paper's ray configurations by name, or an explicit list, into a
 * uint32_t mask (an option's value: opts.h). */
static bool parse_config(const char *s, void *dst) {
  uint32_t *mask = dst;
  const uint32_t P = RAY_MASK(RAY_PRIMARY), S = RAY_MASK(RAY_SHADOW);
  if (!strcmp(s, "primary")) *mask = P;
  else if (!strcmp(s, "shadow")) *mask = P | S;
  else if (!strcmp(s, "specular")) *mask = P | S | RAY_MASK(RAY_SPECULAR);
  else if (!strcmp(s, "diffuse")) *mask = P | S | RAY_MASK(RAY_DIFFUSE);
  else return shade_parse_rays(s, mask);
  return true;
}
#define CONFIG_EXPECT "primary, shadow, specular, diffuse or a comma-separated list of ray types"

/* The options traffic and trace share besides their own. */
#define TRAFFIC_OPTS(width, height, mask, pp, threads)                                             \
  OPTS_U64("width", 0, width, 1, 16384), OPTS_U64("height", 0, height, 1, 16384),                  \
      OPTS_PARSE("rays", 0, mask, parse_config, CONFIG_EXPECT),                                    \
      OPTS_U64("dyn-batch", 0, &(pp)->dyn_batch_rays, 0, UINT32_MAX),                              \
      OPTS_U64("dyn-ray-buffer", 0, &(pp)->dyn_ray_buffer_bytes, 0, 1ull << 32),                   \
      OPTS_U64("threads", 0, threads, 1, 2)

/* One functional run of policy k; analyser results, and the potentially
 * visible triangles counted. din may be NULL. */
struct fn_run {
  struct lru_stack_results res;
  struct render_stats st;
  uint64_t pot_vis_tris;
};

static void run_functional(const struct app_world *w, enum policy_kind k, uint32_t mask,
                           uint32_t width, uint32_t height, const struct policy_params *pp,
                           const struct lru_stack_params *lp, struct din_writer *din,
                           uint64_t threads, const uint32_t *subtree_tris, struct fn_run *out) {
  struct mem_functional *b = mem_functional_create(lp, din, threads > 1);
  struct app_render ar;
  app_render_init(&ar, w, mask, w->scene.seed, width, height);
  uint64_t words = ((uint64_t)w->scene.tri_count + 63) / 64;
  uint64_t *tested = xcalloc(words, sizeof *tested);
  ar.setup.tested = tested;
  ar.setup.subtree_tris = subtree_tris;
  policy_run(k, &ar.setup, pp, mem_functional_port(b), &out->st, NULL);
  lru_stack_finish(mem_functional_stack(b));
  lru_stack_get_results(mem_functional_stack(b), &out->res);
  out->pot_vis_tris = 0;
  for (uint64_t i = 0; i < words; i++)
    out->pot_vis_tris += (uint64_t)__builtin_popcountll(tested[i]);
  free(tested);
  app_render_fini(&ar);
  mem_functional_destroy(b);
}

static uint64_t fetched(const struct lru_stack_size_stats *s, unsigned cls, unsigned lg2_line) {
  return s->misses[cls] << lg2_line;
}

struct row {
  enum policy_kind policy;
  struct lru_stack_size_stats s;
  uint64_t pot_vis_tris;
};

static double geometry_bytes(const struct row *r, unsigned lg2) {
  return (double)(fetched(&r->s, TRACE_CLASS_GEOMETRY, lg2) +
                  fetched(&r->s, TRACE_CLASS_NODE, lg2));
}

static double total_bytes(const struct row *r, unsigned lg2) {
  uint64_t t = 0;
  for (unsigned c = 0; c < TRACE_CLASS_COUNT; c++) t += fetched(&r->s, c, lg2);
  return (double)t;
}

static void progress_line(const char *what, unsigned done, unsigned total) {
  if (!isatty(2)) return;
  fprintf(stderr, "\rtraffic: %-28s %3u/%u", what, done, total);
  if (done == total) fputc('\n', stderr);
  fflush(stderr);
}

/* --policy of traffic: one policy (and recursive, the baseline) or all, into
 * a bool want[POLICY_COUNT]. */
static bool parse_policies(const char *s, void *dst) {
  bool *want = dst;
  enum policy_kind pk;
  for (int p = 0; p < POLICY_COUNT; p++) want[p] = !strcmp(s, "all");
  if (want[0]) return true;
  if (!policy_parse(s, &pk)) return false;
  want[pk] = want[POLICY_RECURSIVE] = true;
  return true;
}

/* The table: its header, then a row a policy and cache size, each against
 * recursive at the same size (the paper's relative columns). */
static void write_table(FILE *f, const struct row *rows, unsigned nrows, const char *scene_name,
                        const char *names, uint32_t W, uint32_t H, unsigned lg2,
                        const struct policy_params *pp, const struct scene *sc) {
  fprintf(f, "scene,rays,width,height,policy,cache_bytes,frac_pot_vis,geometry_mb,total_mb,"
             "rel_geometry,rel_total");
  for (unsigned cl = 0; cl < TRACE_CLASS_COUNT; cl++)
    fprintf(f, ",fetch_%s", trace_class_names[cl]);
  fprintf(
      f, ",writeback_bytes,line_accesses,pot_vis_tris,pot_vis_bytes,dyn_batch,dyn_ray_buffer_bytes,"
         "kd_splits,accel\n");
  struct trace_layout layout;
  trace_layout_default(&layout);
  const uint64_t tri_bytes = layout.tri_bytes;
  /* The buffer the dynamic runs reserved (one worker: 0 is one ray). */
  const uint64_t dyn_ray_buffer = pp->dyn_ray_buffer_bytes ? pp->dyn_ray_buffer_bytes : 64;
  for (unsigned i = 0; i < nrows; i++) {
    const struct row *r = &rows[i];
    const struct row *base = NULL;
    for (unsigned j = 0; j < nrows; j++)
      if (rows[j].policy == POLICY_RECURSIVE && rows[j].s.capacity_bytes == r->s.capacity_bytes)
        base = &rows[j];
    uint64_t pv_bytes = r->pot_vis_tris * tri_bytes, wb = 0, acc = 0;
    for (unsigned cl = 0; cl < TRACE_CLASS_COUNT; cl++) {
      wb += r->s.writebacks[cl] << lg2;
      acc += r->s.accesses[cl];
    }
    double g = geometry_bytes(r, lg2), t = total_bytes(r, lg2);
    double bg = base ? geometry_bytes(base, lg2) : 0, bt = base ? total_bytes(base, lg2) : 0;
    fprintf(f, "%s,%s,%u,%u,%s,%llu,%.6f,%.4f,%.4f,%.4f,%.4f", scene_name, names, W, H,
            policy_name(r->policy), (unsigned long long)r->s.capacity_bytes,
            pv_bytes ? (double)r->s.capacity_bytes / (double)pv_bytes : 0.0, g / MIB, t / MIB,
            bg > 0 ? g / bg : 0.0, bt > 0 ? t / bt : 0.0);
    for (unsigned cl = 0; cl < TRACE_CLASS_COUNT; cl++)
      fprintf(f, ",%llu", (unsigned long long)fetched(&r->s, cl, lg2));
    fprintf(f, ",%llu,%llu,%llu,%llu,%llu,%llu,%s,%s\n", (unsigned long long)wb,
            (unsigned long long)acc, (unsigned long long)r->pot_vis_tris,
            (unsigned long long)pv_bytes, (unsigned long long)pp->dyn_batch_rays,
            (unsigned long long)dyn_ray_buffer, sc->kd_clip ? "clipped" : "whole",
            accel_names[sc->accel]);
  }
}

int cmd_traffic(int argc, char **argv) {
  const char *out = NULL;
  uint32_t mask = 0; /* 0: no --rays */
  uint64_t width = 0, height = 0;
  uint64_t threads = mem_functional_host_cpus() > 1 ? 2 : 1;
  /* The paper's three unless asked: results/traffic reproduces its figures. */
  bool want[POLICY_COUNT] = {true, true, true, false};
  int accel = -1;
  struct policy_params pp;
  policy_params_default(&pp);
  char policy_expect[160];
  app_policy_expect(policy_expect, sizeof policy_expect, ", all");
  const struct opts_spec spec[] = {OPTS_STR("output", 'o', &out),
                                   TRAFFIC_OPTS(&width, &height, &mask, &pp, &threads),
                                   OPTS_PARSE("policy", 0, want, parse_policies, policy_expect),
                                   APP_ACCEL_OPT(&accel), OPTS_END};
  struct opts_args args;
  char help[sizeof TRAFFIC_HELP + 1024];
  app_help(help, sizeof help, TRAFFIC_HELP);
  int rc = opts_parse("traffic", help, spec, argc, argv, &args);
  if (rc != OPTS_GO) return rc;
  const char *scene_path = opts_one_scene(&args);
  if (!scene_path) return APP_EXIT_USAGE;
  if (!out) return app_usage_error("traffic", "missing -o TABLE.csv");
  if (!mask)
    return app_usage_error("traffic", "missing --rays (primary, shadow, specular or diffuse)");

  struct app_world w;
  if (!app_world_load_as(&w, scene_path, accel)) return 2;
  uint32_t W = width ? (uint32_t)width : w.scene.width;
  uint32_t H = height ? (uint32_t)height : w.scene.height;
  struct lru_stack_params lp = lru_stack_params_default();
  const unsigned nsizes = lp.lg2_max - lp.lg2_min + 1;
  struct row *rows = xcalloc((uint64_t)POLICY_COUNT * nsizes, sizeof *rows);
  unsigned nrows = 0, done = 0,
           runs = (want[POLICY_RECURSIVE] ? 1 : 0) + (want[POLICY_PACKET] ? 1 : 0) +
                  (want[POLICY_DYNAMIC] ? nsizes : 0) + (want[POLICY_TREELET] ? nsizes : 0);
  struct fn_run fr;
  const double t0 = app_now();
  /* The queue points' subtree counts depend on the tree alone: counted once
   * for the runs of every cache size. */
  uint32_t *subtree_tris = NULL;
  if (want[POLICY_DYNAMIC] || want[POLICY_TREELET]) {
    const struct bvh *bvh = app_world_bvh(&w);
    subtree_tris = xmalloc(
        (uint64_t)(bvh ? qpoint_bvh_places(bvh) : w.kd.node_count) * sizeof *subtree_tris + 1);
    if (bvh) qpoint_bvh_subtree_tris(bvh, subtree_tris);
    else qpoint_subtree_tris(&w.kd, subtree_tris);
  }
  for (int p = 0; p < POLICY_COUNT; p++) {
    if (!want[p]) continue;
    if (!policy_queues((enum policy_kind)p)) {
      progress_line(policy_name((enum policy_kind)p), done, runs);
      run_functional(&w, (enum policy_kind)p, mask, W, H, &pp, &lp, NULL, threads, subtree_tris,
                     &fr);
      done++;
      for (unsigned k = 0; k < nsizes; k++)
        rows[nrows++] = (struct row){(enum policy_kind)p, fr.res.size[k], fr.pot_vis_tris};
    } else {
      for (unsigned k = 0; k < nsizes; k++) {
        char what[64];
        snprintf(what, sizeof what, "%s %llu KB", policy_name((enum policy_kind)p),
                 (unsigned long long)(1ull << (lp.lg2_min + k)) / 1024);
        progress_line(what, done, runs);
        /* Only this size's counts are kept, so analyse this size alone: the
         * same counts (LRU has the inclusion property), at a fraction of the
         * cost for small caches, whose stacks fit in the host's L1. */
        struct lru_stack_params one = lp;
        one.lg2_min = one.lg2_max = lp.lg2_min + k;
        pp.cache_bytes = 1ull << (lp.lg2_min + k);
        run_functional(&w, (enum policy_kind)p, mask, W, H, &pp, &one, NULL, threads, subtree_tris,
                       &fr);
        done++;
        rows[nrows++] = (struct row){(enum policy_kind)p, fr.res.size[0], fr.pot_vis_tris};
      }
    }
  }
  progress_line("done", runs, runs);
  const double runs_s = app_now() - t0;
  free(subtree_tris);

  struct err e = {0};
  struct outfile o;
  outguard_beside(out); /* a signal while it is written removes its temporary */
  if (!outfile_open(&o, out, "the table", &e)) {
    outguard_clear();
    free(rows);
    app_world_fini(&w);
    return app_report(&e);
  }
  FILE *f = o.f;
  char names[64];
  shade_rays_name(mask, names, sizeof names);
  for (char *q = names; *q; q++)
    if (*q == ',') *q = '+'; /* a CSV field */
  const char *scene_name = w.scene.name[0] ? w.scene.name : scene_path;
  write_table(f, rows, nrows, scene_name, names, W, H, lp.lg2_line, &pp, &w.scene);
  bool committed = outfile_commit(&o, &e);
  outguard_clear();
  if (!committed) {
    free(rows);
    app_world_fini(&w);
    return app_report(&e);
  }
  printf("scene: %s\nrays: %s\nimage: %ux%u\nruns: %u\n", scene_name, names, W, H, runs);
  const uint64_t dyn_ray_buffer = pp.dyn_ray_buffer_bytes ? pp.dyn_ray_buffer_bytes : 64;
  if (want[POLICY_DYNAMIC] || want[POLICY_TREELET]) {
    printf("dyn_batch: %llu%s\n", (unsigned long long)pp.dyn_batch_rays,
           pp.dyn_batch_rays ? " primary rays at a time" : " (all primary rays at once)");
    printf("dyn_ray_buffer_bytes: %llu\n", (unsigned long long)dyn_ray_buffer);
  }
  printf("runs_s: %.3f (wall seconds of the runs, without loading the scene)\n", runs_s);
  printf("output: %s\n", out);
  free(rows);
  app_world_fini(&w);
  return 0;
}

static const char TRACE_HELP[] =
    "usage: rtsim trace SCENE.yaml --policy P --rays CONFIG --din FILE [options]\n"
    "\n"
    "Write the access stream of one run as a Dinero IV din trace: records\n"
    "'LABEL ADDRESS' (label 0 read, 1 write; address in hex), one per 64-byte line\n"
    "touched; print the Dinero IV command that replays it for the --cache size on\n"
    "stderr, and on stdout, as CSV, what rtsim's one-pass analyser counted for\n"
    "each cache size, to check the replay against.\n"
    "\n"
    "example:\n"
    "  rtsim trace scenes/small/room.yaml --policy packet --rays primary \\\n"
    "      --width 64 --height 64 --din build/room.din\n"
    "\n"
    "options:\n"
    "  --policy P          one of (required):\n"
    "                        {policies}\n"
    "  --rays CONFIG       primary, shadow, specular, diffuse or a list (required)\n"
    "  --din FILE          trace to write (required); written whole or not at all\n"
    "  --cache BYTES       the cache size of the printed replay command and, for\n"
    "                      dynamic and treelet, the size the schedule is made for (default\n"
    "                      524288); a power of two from 1024 to 4194304\n"
    "  --threads N         host threads: 2 runs the analyser beside the tracer, 1 on\n"
    "                      the same (default: 2 when two host CPUs are available)\n"
    "  --dyn-batch N       dynamic: admit N primary rays at a time (default 0: all)\n"
    "  --dyn-ray-buffer B  dynamic: bytes reserved for the rays being traced (default\n"
    "                      4096; 0: one ray)\n"
    "  --width W --height H  image size (default: the scene's)\n"
    "  --accel A           the structure traced: kd, bvh2 or bvh8 (default: the scene's\n"
    "                      accel key)\n"
    "  -h, --help          this text; --help-full: also the records in detail\n"
    "\f"
    "\n"
    "A store that covers a line whole is one write record (the line is allocated\n"
    "without a fetch); a store to part of a line is a read record, then a write\n"
    "record. So Dinero IV 7 with 64-byte blocks, full associativity, LRU,\n"
    "write-back and write-allocate without fetch counts exactly our fetches and\n"
    "write-backs. Dinero takes associativity as a number of ways (0 means its\n"
    "default, direct-mapped), so full associativity is one way per line: for a\n"
    "512 KB cache,\n"
    "  dineroIV -informat d -l1-ubsize 64 -l1-usize 512k -l1-uassoc 8192\n"
    "           -l1-urepl l -l1-uwback a -l1-uwalloc f < FILE\n";

/* The Dinero IV 7 command that replays a din trace of lines of 2^lg2_line
 * bytes as the analyser's fully associative LRU cache of `bytes` (a multiple of
 * 1024). NOTE: Dinero takes associativity as a number of ways and treats 0 as
 * its default of 1 (direct-mapped): full associativity is bytes / line ways. */
static void dinero_command(uint64_t bytes, unsigned lg2_line, const char *din, char *out,
                           size_t cap) {
  snprintf(out, cap,
           "dineroIV -informat d -l1-ubsize %llu -l1-usize %lluk -l1-uassoc %llu -l1-urepl l "
           "-l1-uwback a -l1-uwalloc f < %s",
           1ull << lg2_line, (unsigned long long)(bytes >> 10),
           (unsigned long long)(bytes >> lg2_line), din);
}

/* --cache of trace: a power of two from 1 KiB to 4 MiB, into a uint64_t. */
static bool parse_cache(const char *s, void *dst) {
  uint64_t v;
  if (!opts_u64(s, 1024, 4194304, &v) || (v & (v - 1))) return false;
  *(uint64_t *)dst = v;
  return true;
}

int cmd_trace(int argc, char **argv) {
  const char *din_path = NULL;
  uint32_t mask = 0; /* 0: no --rays */
  uint64_t width = 0, height = 0, cache = 512 * 1024;
  uint64_t threads = mem_functional_host_cpus() > 1 ? 2 : 1;
  enum policy_kind pk = POLICY_RECURSIVE;
  bool have_policy = false;
  int accel = -1;
  struct policy_params pp;
  policy_params_default(&pp);
  char policy_expect[160];
  app_policy_expect(policy_expect, sizeof policy_expect, "");
  const struct opts_spec spec[] = {
      OPTS_STR("din", 0, &din_path),
      TRAFFIC_OPTS(&width, &height, &mask, &pp, &threads),
      OPTS_PARSE_GIVEN("policy", 0, &pk, app_parse_policy, policy_expect, &have_policy),
      OPTS_PARSE("cache", 0, &cache, parse_cache, "a power of two from 1024 to 4194304"),
      APP_ACCEL_OPT(&accel),
      OPTS_END};
  struct opts_args args;
  char help[sizeof TRACE_HELP + 1024];
  app_help(help, sizeof help, TRACE_HELP);
  int rc = opts_parse("trace", help, spec, argc, argv, &args);
  if (rc != OPTS_GO) return rc;
  const char *scene_path = opts_one_scene(&args);
  if (!scene_path) return APP_EXIT_USAGE;
  if (!din_path) return app_usage_error("trace", "missing --din FILE");
  if (!have_policy) {
    char list[128];
    policy_list(list, sizeof list, " or ");
    return app_usage_error("trace", "missing --policy (%s)", list);
  }
  if (!mask)
    return app_usage_error("trace", "missing --rays (primary, shadow, specular or diffuse)");
  struct app_world w;
  if (!app_world_load_as(&w, scene_path, accel)) return 2;
  uint32_t W = width ? (uint32_t)width : w.scene.width;
  uint32_t H = height ? (uint32_t)height : w.scene.height;
  struct lru_stack_params lp = lru_stack_params_default();
  struct err e;
  memset(&e, 0, sizeof e);
  struct din_writer *din = din_writer_open(din_path, lp.lg2_line, &e);
  if (!din) {
    app_world_fini(&w);
    return app_report(&e);
  }
  struct fn_run fr;
  pp.cache_bytes = cache;
  run_functional(&w, pk, mask, W, H, &pp, &lp, din, threads, NULL, &fr);
  uint64_t records = din_writer_records(din);
  bool ok = din_writer_close(din, &e);
  app_world_fini(&w);
  if (!ok) return app_report(&e);
  printf("cache_bytes,misses,writebacks\n");
  for (unsigned k = 0; k < fr.res.size_count; k++) {
    uint64_t m = 0, wb = 0;
    for (unsigned cl = 0; cl < TRACE_CLASS_COUNT; cl++) {
      m += fr.res.size[k].misses[cl];
      wb += fr.res.size[k].writebacks[cl];
    }
    printf("%llu,%llu,%llu\n", (unsigned long long)fr.res.size[k].capacity_bytes,
           (unsigned long long)m, (unsigned long long)wb);
  }
  fprintf(stderr, "trace: %llu records written to %s\n", (unsigned long long)records, din_path);
  char replay[1400];
  dinero_command(cache, lp.lg2_line, din_path, replay, sizeof replay);
  fprintf(stderr, "replay (%llu-byte cache): %s\n", (unsigned long long)cache, replay);
  return 0;
}
