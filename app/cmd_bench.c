/* rtsim bench: host speed figures (a benchmark, not a test): native render
 * throughput per scene, the functional backend's slowdown against it on the
 * same workload, and the one-pass analyser's own speed. */
#include "app/app.h"

#include <getopt.h> /* optind: the scenes are argv[optind..argc) */
#include <stdio.h>
#include <stdlib.h>

#include "app/bench_embree.h"
#include "app/bench_hits.h"
#include "app/bench_policies.h"
#include "app/bench_rays.h"
#include "app/opts.h"
#include "renderer/policy/policy.h"
#include "renderer/ray.h"
#include "renderer/scene.h"
#include "renderer/shade.h"
#include "renderer/trace.h"
#include "sim/coro.h"
#include "sim/engine.h"
#include "sim/err.h"
#include "sim/lru_stack.h"
#include "sim/machine.h"
#include "sim/machine_cfg.h"
#include "sim/mem_functional.h"
#include "sim/scalar.h"

static const char HELP[] =
    "usage: rtsim bench [options] SCENE.yaml...\n"
    "\n"
    "A benchmark, not a test: for each scene, load it, build its structure (the scene's\n"
    "accel: the k-d tree by default, or a BVH) and render\n"
    "its primary rays with the recursive policy on one host thread under the native\n"
    "backend (nothing per access), best of --repeat; the options below add other\n"
    "backends or time other parts. CSV on stdout: scene, triangles, kd_nodes,\n"
    "kd_build_s, width, height, rays, native_s, rays_per_s, and each option's columns;\n"
    "last, accel (kd, bvh2 or bvh8). On a BVH, kd_nodes and kd_build_s are the BVH's\n"
    "nodes and build time, kd_refs_per_tri 1 and kd_max_leaf its largest leaf.\n"
    "\n"
    "example (the timed machine's slowdown over the renderer alone):\n"
    "  rtsim bench --width 64 --height 64 --timed configs/tiny.yaml scenes/small/room.yaml\n"
    "\n"
    "options:\n"
    "  --width W --height H   image size (default: each scene's)\n"
    "  --rays LIST            ray types (default primary)\n"
    "  --repeat N             renders per scene and backend, best kept (default 3)\n"
    "  --functional           also time the functional backend on the same work\n"
    "  --analyser N           only time the analyser alone on N synthetic line accesses\n"
    "  --engine               only time the event engine and the coroutine switch\n"
    "  --embree               also trace the primary rays with Embree 3 (a build with\n"
    "                         -DRTSIM_EMBREE=ON) beside rtsim's tracer alone\n"
    "  --hits                 only compare nearest hits: k-d tree, BVH2, BVH8 (and with\n"
    "                         --embree, Embree) on four ray sets\n"
    "  --timed MACHINE.yaml   time the timed machine on the same image instead\n"
    "  --sample F             with --timed: also sampled at sample.fraction F\n"
    "  --policies LIST        with --timed: whole 'rtsim run' processes of each policy\n"
    "                         in LIST (two or more), taking turns\n"
    "  --levels LIST          with --timed: as --policies, one policy at each level:\n"
    "                         native or a fidelity rung (analytic, fixed, ...)\n"
    "  --policy P             with --levels: the policy of every run (default\n"
    "                         recursive):\n"
    "                           {policies}\n"
    "  --set KEY=VALUE        with --policies or --levels: a machine key for every run\n"
    "  -h, --help             this text; --help-full: every option and column in detail\n"
    "\f"
    "\n"
    "--functional: also as many renders under the functional backend (every access\n"
    "analysed for all 13 cache sizes), alternating with the native renders, and the\n"
    "best-to-best slowdown; on one host thread, then with its analyser on a second\n"
    "(rtsim traffic --threads 2), each timed until its analysis is done. Adds\n"
    "functional_s, slowdown, line_accesses, accesses_per_s, functional_2t_s,\n"
    "slowdown_2t.\n"
    "\n"
    "--analyser N: accesses per second of the analyser alone.\n"
    "\n"
    "--engine: events per second (20M events, 1024 pending, each scheduling the next\n"
    "1 to 1024 cycles ahead as most of the machine's do; and 1 to 2^20 cycles ahead,\n"
    "mostly past the calendar) and the coroutine switch (ns, best of 5 x 10M\n"
    "switches).\n"
    "\n"
    "--embree: the image's primary rays, in the render's order, one at a time with\n"
    "rtsim's tracer alone (no shading) and with Embree 3 (single thread,\n"
    "rtcIntersect1, robust mode) on the scene exported as PLY and read back; adds\n"
    "kd_splits (the scene's kd_tree.splits), kd_refs_per_tri, kd_max_leaf, trace_s,\n"
    "trace_rays_per_s, embree_build_s, embree_s, embree_rays_per_s, vs_embree\n"
    "(rays_per_s over embree_rays_per_s), trace_vs_embree and prim_mismatches (rays\n"
    "whose hit primitive differs).\n"
    "\n"
    "--hits: no timing; for each scene, its primary rays (W x H), the shadow and\n"
    "diffuse rays their hits spawn and W x H random rays through its box, each\n"
    "traced to its nearest hit through the k-d tree, the BVH2 and the BVH8; a row a\n"
    "scene, set and structure: scene, set, rays, accel, hits, ties (rays whose hit\n"
    "has another triangle at exactly its distance, which the hit rule gives to the\n"
    "smaller id), differ_from_kd (rays whose triangle differs from the k-d tree's),\n"
    "differ_at_tie and differ_other (at the same t or not). With --embree also\n"
    "embree_differ (rays whose triangle differs from Embree's, the triangle a\n"
    "secondary ray leaves ignored by both) and how each is decided in double\n"
    "precision: embree_tie (both hit within 1e-9 of the same t), embree_edge (a hit\n"
    "within 1e-5 of its triangle's edge, barycentric), rtsim_nearer, embree_nearer.\n"
    "\n"
    "--timed MACHINE.yaml: instead of the functional backend, rtsim run's timed\n"
    "machine on the same image, once as configured and once with 1 core x 1 thread\n"
    "x 1 ray of it, each against the best native render; prints scene, width,\n"
    "height, rays, machine, contexts, native_s, timed_s, slowdown, cycles, events,\n"
    "events_per_s, core_utilization, dram_bytes_per_cycle. --sample F adds the\n"
    "machine sampled at F (docs/fidelity-and-sampling.md) against its full run:\n"
    "cycles_ci95_low, cycles_ci95_high, speedup_vs_full (host time) and\n"
    "cycles_error_vs_full.\n"
    "\n"
    "--policies LIST (e.g. dynamic,recursive): whole 'rtsim run' processes (this\n"
    "program, as a user runs it: scene load, k-d build, run and output files), the\n"
    "policies taking turns for --repeat rounds, outputs in a temporary folder; per\n"
    "scene and policy prints scene, width, height, rays, machine, set, policy,\n"
    "rounds, host_s_best and host_s_median (user + system seconds of the process),\n"
    "run_s_best and run_s_median (the run's own wall_s in stats.json, without the\n"
    "load), events, peak_rss_mb, and against the last policy of LIST (base):\n"
    "host_vs_base_median and _max (over the rounds' ratios), run_vs_base_median,\n"
    "events_vs_base, peak_rss_vs_base, and base (its name).\n"
    "\n"
    "--levels LIST (e.g. native,banked,channel): native is rtsim render of the same\n"
    "image, the renderer alone; a rung runs with --set fidelity=L; the column\n"
    "'level' replaces 'policy', and 'set' names the policy.\n";

static double render_once(const struct app_world *w, uint32_t mask, uint32_t W, uint32_t H,
                          struct mem_port port, uint64_t *rays) {
  struct app_render ar;
  app_render_init(&ar, w, mask, w->scene.seed, W, H);
  struct render_stats st;
  struct policy_params pp;
  policy_params_default(&pp);
  double t0 = app_now();
  policy_run(POLICY_RECURSIVE, &ar.setup, &pp, port, &st, NULL);
  double s = app_now() - t0;
  app_render_fini(&ar);
  *rays = render_stats_total(&st);
  return s;
}

/* rtsim's tracer alone on the same rays (native backend); prim[i] its hits. */
static double trace_only(const struct app_world *w, const struct ray *rays, uint32_t n,
                         int32_t *prim) {
  struct trace_ctx tr;
  struct trace_layout lay;
  trace_layout_default(&lay);
  trace_init(&tr, &w->scene, &w->kd, mem_port_native(), &lay);
  tr.bvh = app_world_bvh(w);
  double t0 = app_now();
  for (uint32_t i = 0; i < n; i++) {
    struct trace_hit h;
    trace_closest(&tr, &rays[i], &h);
    prim[i] = h.prim;
  }
  return app_now() - t0;
}

/* The timed machine against the native render of the same image; with
 * sample < 1, also the machine as configured, sampled at that fraction,
 * against its full run. */
static int bench_timed(const char *cfg_path, uint32_t mask, uint64_t width, uint64_t height,
                       uint64_t repeat, double sample, int argc, char **argv) {
  struct machine_cfg mc;
  machine_cfg_defaults(&mc);
  struct err e = {0};
  if (!machine_cfg_load(&mc, cfg_path, &e) || !machine_cfg_check(&mc, &e)) return app_report(&e);
  printf("scene,width,height,rays,machine,contexts,native_s,timed_s,slowdown,cycles,events,"
         "events_per_s,core_utilization,dram_bytes_per_cycle,cycles_ci95_low,cycles_ci95_high,"
         "speedup_vs_full,cycles_error_vs_full\n");
  for (int i = optind; i < argc; i++) {
    struct app_world w;
    if (!app_world_load(&w, argv[i])) return 2;
    uint32_t W = width ? (uint32_t)width : w.scene.width;
    uint32_t H = height ? (uint32_t)height : w.scene.height;
    if (sample < 1) {
      struct machine_cfg_sample sc = mc.sample;
      sc.fraction = sample;
      const struct machine_params *p = &mc.p;
      char why[512];
      const char *bad =
          sample_problem(&sc, p->fidelity, POLICY_RECURSIVE, app_work_items(POLICY_RECURSIVE, W, H),
                         p->cores * p->threads_per_core * p->rays_per_thread, why, sizeof why);
      if (bad) {
        app_world_fini(&w);
        return app_usage_error("bench", "--sample %g on %s at %ux%u: %s", sample, argv[i], W, H,
                               bad);
      }
    }
    double best = 0, full_s = 0, full_cycles = 0;
    uint64_t nrays = 0;
    for (uint64_t k = 0; k < repeat; k++) {
      double s = render_once(&w, mask, W, H, mem_port_native(), &nrays);
      if (k == 0 || s < best) best = s;
    }
    for (int run = 0; run < (sample < 1 ? 3 : 2); run++) {
      const bool one = run == 0, sampled = run == 2;
      struct machine_params p = mc.p;
      struct machine_cfg_sample sc = mc.sample;
      sc.fraction = sampled ? sample : 1;
      if (one) p.cores = p.threads_per_core = p.rays_per_thread = 1;
      struct app_timed t;
      app_timed_run(&t, &w, mask, w.scene.seed, W, H, POLICY_RECURSIVE, &p, &mc.work, &sc, false,
                    NULL, false, NULL);
      const struct machine_stats *st = machine_get_stats(t.m);
      double cycles = (double)st->cycles, lo = 0, hi = 0;
      if (sampled) cycles = sample_cycles(&t.sample, &lo, &hi);
      char name[600];
      snprintf(name, sizeof name, "%s%s", cfg_path, one ? " at 1x1x1" : sampled ? " sampled" : "");
      printf("%s,%u,%u,%llu,%s,%llu,%.4f,%.4f,%.2f,%.0f,%llu,%.0f,%.4f,%.4f",
             w.scene.name[0] ? w.scene.name : argv[i], W, H, (unsigned long long)nrays, name,
             (unsigned long long)st->contexts, best, t.wall_s, best > 0 ? t.wall_s / best : 0.0,
             cycles, (unsigned long long)st->events,
             t.wall_s > 0 ? (double)st->events / t.wall_s : 0.0,
             sampled ? (double)t.sample.slots_total / ((double)p.cores * cycles)
                     : (double)st->issue_slots / ((double)p.cores * cycles),
             sampled ? 0.0 : (double)(st->dram.read_bytes + st->dram.write_bytes) / cycles);
      if (sampled)
        printf(",%.0f,%.0f,%.2f,%+.4f\n", lo, hi, t.wall_s > 0 ? full_s / t.wall_s : 0.0,
               full_cycles > 0 ? (cycles - full_cycles) / full_cycles : 0.0);
      else printf(",,,,\n");
      if (run == 1) {
        full_s = t.wall_s;
        full_cycles = cycles;
      }
      fflush(stdout);
      app_timed_fini(&t);
    }
    app_world_fini(&w);
  }
  return 0;
}

/* A sampling fraction: a plain decimal number above 0 and at most 1. */
static bool parse_fraction(const char *text, void *dst) {
  double v;
  if (scalar_f64(text, &v) != SCALAR_OK || !(v > 0 && v <= 1)) return false;
  *(double *)dst = v;
  return true;
}

/* One row of the native bench for the scene at scene_path: the native render
 * (and the functional model, Embree) timed, best of `repeat`. 0, or the exit
 * code after the error was reported. */
static int bench_native_scene(const char *scene_path, uint32_t mask, uint64_t width,
                              uint64_t height, uint64_t repeat, bool functional, bool embree) {
  struct app_world w;
  if (!app_world_load(&w, scene_path)) return 2;
  uint32_t W = width ? (uint32_t)width : w.scene.width;
  uint32_t H = height ? (uint32_t)height : w.scene.height;
  /* Native and functional renders alternate, so both see the same machine
   * state (the other core's load, frequency); each keeps its best time. */
  double best = 0, fbest = 0, f2best = 0, tbest = 0, ebest = 0, ebuild = 0;
  uint64_t nrays = 0, acc = 0, mismatches = 0;
  struct bench_embree *be = NULL;
  struct ray *prays = NULL;
  int32_t *tprim = NULL, *eprim = NULL;
  uint32_t np = W * H;
  if (embree) {
    be = bench_embree_from_ply(&w.scene, false, &ebuild);
    if (!be) {
      app_world_fini(&w);
      return 1;
    }
    prays = bench_rays_primary(&w.scene, W, H);
    tprim = xmalloc((unsigned long long)np * sizeof *tprim);
    eprim = xmalloc((unsigned long long)np * sizeof *eprim);
  }
  for (uint64_t k = 0; k < repeat; k++) {
    double s = render_once(&w, mask, W, H, mem_port_native(), &nrays);
    if (k == 0 || s < best) best = s;
    if (embree) {
      double ts = trace_only(&w, prays, np, tprim),
             es = bench_embree_trace(be, prays, np, eprim, NULL);
      if (k == 0 || ts < tbest) tbest = ts;
      if (k == 0 || es < ebest) ebest = es;
    }
    if (!functional) continue;
    /* One host thread, then the analyser on a second (rtsim traffic's
     * default with two host CPUs); the time includes waiting for it. */
    for (int th = 0; th < 2; th++) {
      struct lru_stack_params lp = lru_stack_params_default();
      struct mem_functional *b = mem_functional_create(&lp, NULL, th == 1);
      double fs = render_once(&w, mask, W, H, mem_functional_port(b), &nrays);
      const double t0 = app_now();
      mem_functional_stack(b); /* waits for the analyser */
      fs += app_now() - t0;
      double *keep = th ? &f2best : &fbest;
      if (k == 0 || fs < *keep) *keep = fs;
      acc = 0;
      for (unsigned cl = 0; cl < TRACE_CLASS_COUNT; cl++)
        acc += mem_functional_get_stats(b)->line_accesses[cl];
      mem_functional_destroy(b);
    }
  }
  /* The traced structure's figures: the k-d tree's, or the BVH's (each
   * triangle in one leaf). */
  const struct bvh *bv = app_world_bvh(&w);
  const uint32_t nodes = bv ? bv->stats.nodes : w.kd.stats.nodes,
                 max_leaf = bv ? bv->stats.max_leaf_prims : w.kd.stats.max_leaf_prims;
  const double refs = bv                  ? 1.0
                      : w.scene.tri_count ? (double)w.kd.stats.leaf_prim_refs / w.scene.tri_count
                                          : 0.0;
  printf("%s,%u,%u,%.3f,%u,%u,%llu,%.4f,%.0f", w.scene.name[0] ? w.scene.name : scene_path,
         w.scene.tri_count, nodes, w.build_s, W, H, (unsigned long long)nrays, best,
         best > 0 ? (double)nrays / best : 0.0);
  if (functional)
    printf(",%.4f,%.2f,%llu,%.0f,%.4f,%.2f", fbest, best > 0 ? fbest / best : 0.0,
           (unsigned long long)acc, fbest > 0 ? (double)acc / fbest : 0.0, f2best,
           best > 0 ? f2best / best : 0.0);
  if (embree) {
    for (uint32_t j = 0; j < np; j++) mismatches += tprim[j] != eprim[j];
    double rps = best > 0 ? (double)nrays / best : 0.0, trps = tbest > 0 ? np / tbest : 0.0,
           erps = ebest > 0 ? np / ebest : 0.0;
    printf(",%s,%.2f,%u,%.4f,%.0f,%.3f,%.4f,%.0f,%.3f,%.3f,%llu",
           w.scene.kd_clip ? "clipped" : "whole", refs, max_leaf, tbest, trps, ebuild, ebest, erps,
           erps > 0 ? rps / erps : 0.0, erps > 0 ? trps / erps : 0.0,
           (unsigned long long)mismatches);
    bench_embree_destroy(be);
    free(prays);
    free(tprim);
    free(eprim);
  }
  printf(",%s\n", accel_names[w.scene.accel]);
  fflush(stdout);
  app_world_fini(&w);
  return 0;
}

/* cmd_bench with its --set list (sized for argc entries, owned by the caller). */
static int bench_main(int argc, char **argv, struct app_sets *sets) {
  uint64_t width = 0, height = 0, repeat = 3, analyser = 0;
  double sample = 1;
  uint32_t mask = RAY_MASK(RAY_PRIMARY);
  bool functional = false, engine = false, embree = false, hits = false;
  const char *timed = NULL;
  struct bench_policy_list policies = {0};
  struct bench_level_list levels = {0};
  enum policy_kind policy = POLICY_RECURSIVE;
  bool have_policies = false, have_levels = false;
  char policy_expect[160];
  app_policy_expect(policy_expect, sizeof policy_expect, "");
  const struct opts_spec spec[] = {
      OPTS_U64("width", 0, &width, 1, 16384),
      OPTS_U64("height", 0, &height, 1, 16384),
      OPTS_U64("repeat", 0, &repeat, 1, 1000),
      OPTS_PARSE("rays", 0, &mask, app_parse_rays, APP_RAYS_EXPECT),
      OPTS_FLAG("functional", 0, &functional),
      OPTS_U64("analyser", 0, &analyser, 1, 1ull << 40),
      OPTS_FLAG("engine", 0, &engine),
      OPTS_STR("timed", 0, &timed),
      OPTS_PARSE("sample", 0, &sample, parse_fraction, "a fraction above 0 and at most 1"),
      OPTS_FLAG("embree", 0, &embree),
      OPTS_FLAG("hits", 0, &hits),
      OPTS_PARSE_GIVEN("policies", 0, &policies, bench_parse_policies, BENCH_POLICIES_EXPECT,
                       &have_policies),
      OPTS_PARSE_GIVEN("levels", 0, &levels, bench_parse_levels, BENCH_LEVELS_EXPECT, &have_levels),
      OPTS_PARSE("policy", 0, &policy, app_parse_policy, policy_expect),
      OPTS_PARSE("set", 0, sets, app_sets_add, "KEY=VALUE"),
      OPTS_END};
  struct opts_args args;
  char help[sizeof HELP + 1024];
  app_help(help, sizeof help, HELP);
  int rc = opts_parse("bench", help, spec, argc, argv, &args);
  if (rc != OPTS_GO) return rc;
  if (analyser) {
    printf("line_accesses,accesses_per_s\n%llu,%.0f\n", (unsigned long long)analyser,
           lru_stack_bench(analyser, 1));
    return 0;
  }
  if (engine) {
    double near = engine_bench(20000000, 1024, 1024), far = engine_bench(20000000, 1024, 1u << 20);
    double ns = 0;
    for (int k = 0; k < 5; k++) {
      double x = coro_bench_switch_ns(10000000);
      if (k == 0 || x < ns) ns = x;
    }
    printf("engine_events_per_s,engine_far_events_per_s,coroutine_switch_ns\n%.0f,%.0f,%.2f\n",
           near, far, ns);
    return 0;
  }
  if (args.n == 0) return app_usage_error("bench", "missing SCENE.yaml");
  if (have_policies && !timed)
    return app_usage_error("bench", "--policies: give the machine with --timed MACHINE.yaml");
  if (have_levels && !timed)
    return app_usage_error("bench", "--levels: give the machine with --timed MACHINE.yaml");
  if (have_levels && have_policies)
    return app_usage_error("bench", "--levels: not with --policies (give one --policy)");
  if (sets->n && !have_policies && !have_levels)
    return app_usage_error("bench", "--set: only with --timed MACHINE.yaml --policies or --levels");
  if ((have_policies || have_levels) && (sample < 1 || functional || embree))
    return app_usage_error("bench",
                           have_levels ? "--levels: not with --sample, --functional or --embree"
                                       : "--policies: not with --sample, --functional or --embree");
  if (have_policies || have_levels)
    return bench_policies(timed, sets, have_policies ? &policies : NULL, &levels, policy, mask,
                          width, height, repeat, argc, argv, optind);
  if (timed) return bench_timed(timed, mask, width, height, repeat, sample, argc, argv);
  if (embree && !bench_embree_available())
    return app_usage_error("bench", "--embree: this rtsim was built without Embree (install "
                                    "libembree-dev and configure with -DRTSIM_EMBREE=ON)");
  if (hits) {
    if (functional || mask != RAY_MASK(RAY_PRIMARY))
      return app_usage_error("bench", "--hits: not with --functional or --rays (it makes its "
                                      "own ray sets)");
    bench_hits_header(embree);
    for (int i = optind; i < argc; i++) {
      rc = bench_hits_scene(argv[i], width, height, embree);
      if (rc) return rc;
    }
    return 0;
  }
  if (embree && mask != RAY_MASK(RAY_PRIMARY))
    return app_usage_error("bench", "--embree compares primary rays only (--rays primary)");
  printf(
      "scene,triangles,kd_nodes,kd_build_s,width,height,rays,native_s,rays_per_s%s%s,accel\n",
      functional ? ",functional_s,slowdown,line_accesses,accesses_per_s,functional_2t_s,slowdown_2t"
                 : "",
      embree
          ? ",kd_splits,kd_refs_per_tri,kd_max_leaf,trace_s,trace_rays_per_s,embree_build_s,embree_s,"
            "embree_rays_per_s,vs_embree,trace_vs_embree,prim_mismatches"
          : "");
  for (int i = optind; i < argc; i++) {
    rc = bench_native_scene(argv[i], mask, width, height, repeat, functional, embree);
    if (rc) return rc;
  }
  return 0;
}

int cmd_bench(int argc, char **argv) {
  struct app_sets sets = {xcalloc((size_t)argc + 1, sizeof *sets.v),
                          0}; /* at most one an argument */
  int rc = bench_main(argc, argv, &sets);
  free(sets.v);
  return rc;
}
