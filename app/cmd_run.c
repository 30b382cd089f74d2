/* rtsim run: render a scene on the timed machine and write what it measured.
 * Glue only: parse, load the machine config and the scene, run one policy
 * worker per ray context on the machine, hand the numbers to run_output.c. */
#include "app/app.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "app/opts.h"
#include "app/outdir.h"
#include "app/outguard.h"
#include "app/run_output.h"
#include "app/rung_error.h"
#include "app/spot_check.h"
#include "renderer/policy/policy.h"
#include "renderer/shade.h"
#include "renderer/trace.h"
#include "sim/coro.h"
#include "sim/err.h"
#include "sim/machine.h"
#include "sim/machine_cfg.h"
#include "sim/outfile.h"
#include "sim/scalar.h"

/* The screen (--help), then after the form feed the reference (--help-full,
 * the man page). */
static const char HELP[] =
    "usage: rtsim run MACHINE.yaml SCENE.yaml -o OUTDIR [options]\n"
    "\n"
    "Render SCENE.yaml on the timed many-core machine MACHINE.yaml (configs/), each\n"
    "ray context a coroutine whose loads wait for the L1, the L2 and the DRAM; the\n"
    "fidelity key picks the rung: analytic, fixed, channel or banked (the default).\n"
    "Writes OUTDIR/image.exr, stats.json, stats.csv, timeline.csv and traffic.png,\n"
    "all or none; a summary with units on stdout, progress on stderr.\n"
    "\n"
    "example:\n"
    "  rtsim run configs/default.yaml scenes/small/room.yaml --width 32 --height 32 \\\n"
    "      --policy dynamic --set l2.size=1MiB -o build/run-room\n"
    "\n"
    "options:\n"
    "  -o, --output DIR      output directory (required)\n"
    "  --policy P            how rays are scheduled (default recursive):\n"
    "                          {policies}\n"
    "  --rays LIST           ray types from primary,shadow,specular,diffuse (default all)\n"
    "  --width W, --height H image size (default: the scene's)\n"
    "  --seed S              diffuse sampling seed (default: the scene's)\n"
    "  --accel A             the structure traced: kd, bvh2 or bvh8 (default: the scene's)\n"
    "  --set KEY=VALUE       override a machine config key (repeatable)\n"
    "  --dram-trace FILE     also write every DRAM request (not at fidelity analytic)\n"
    "  --trace-events FILE   also write the run's activity as Chrome trace-event JSON\n"
    "                        for Perfetto (not at fidelity analytic), bounded by:\n"
    "  --trace-events-window FROM:TO  only cycles [FROM, TO) (FROM: to the end)\n"
    "  --trace-events-cores N         only the first N cores (default 2)\n"
    "  --trace-events-period C        counters every C cycles (default 1000)\n"
    "  --trace-events-max N           at most N events, ~65 bytes each (default 1000000)\n"
    "  --spot-check F        at a cheaper rung, also run a banked sample (sample.fraction\n"
    "                        F) of this point: this rung's error here, with intervals\n"
    "  --cost-preview PNG    also draw one per-pixel cost channel as a heat map\n"
    "  --cost-channel C      the channel it draws (default cost.issue_slots)\n"
    "  --cost-max X          its colour bar's top (default: the largest pixel)\n"
    "  --help-keys           every machine config key: default, range, unit, meaning\n"
    "  --help-stats          every number stats.json and stats.csv hold, with units\n"
    "  --help-stats-markdown the same as Markdown table rows\n"
    "  -h, --help            this text; --help-full: also the outputs in detail\n"
    "\f"
    "\n"
    "outputs: OUTDIR is written as a fresh sibling put in its place at the end, so it\n"
    "is absent or the earlier run until then, whole, never a mix; a run that fails\n"
    "or is stopped (SIGINT, SIGTERM) leaves it as it was and nothing else behind\n"
    "(docs/outputs.md):\n"
    "  image.exr     the picture, bit-identical in RGB to rtsim render's\n"
    "  stats.json    resolved config, scene, seed, wall time, every measured number\n"
    "  stats.csv     the same numbers as one tidy row (no wall time: bit-identical\n"
    "                run to run)\n"
    "  timeline.csv  one row per timeline.window cycles: DRAM bytes by class, L2\n"
    "                accesses and misses, issued operations, busy threads\n"
    "  traffic.png   DRAM bytes per cycle over the run by data class (gnuplot)\n"
    "At fidelity analytic: no timed machine, one worker's counts and a closed-form\n"
    "estimate of the cycles (no timeline.csv or traffic.png, and only the numbers\n"
    "it knows). At the timed rungs, a whole run (not sampled) also writes per-pixel\n"
    "costs in image.exr, each summing over the pixels to the run's total\n"
    "(docs/outputs.md: Cost in the picture): cost.issue_slots, cost.load_wait_cycles,\n"
    "cost.dram_read_bytes.<class> (geometry, node, ray, queue, other),\n"
    "cost.dram_write_bytes.\n"
    "--set takes every key of configs/default.yaml, e.g. --set l2.size=1MiB --set\n"
    "rays_per_thread=4 (--help-keys; docs/config-keys.md). With\n"
    "--set dynamic.sharing=chip the dynamic policy's cores share its queue points.\n"
    "--dram-trace writes each request's address, READ or WRITE, arrival in DRAM\n"
    "cycles, arrival and completion in core cycles, in arrival order\n"
    "(docs/dram-traces.md); rtsim dram-replay reads it.\n"
    "--trace-events: for ui.perfetto.dev or chrome://tracing, per core, each\n"
    "thread's state over time (run, switch, ready, wait by cause, parked, done) and\n"
    "counters of the L2 and the DRAM; 1 us of trace time = 1 cycle (docs/outputs.md:\n"
    "Timelines in Perfetto). When --trace-events-max is reached the trace ends there and a\n"
    "warning says at which cycle (the default, 1000000 events, is about 65 MB).\n";

static bool parse_cost_max(const char *text, void *dst) {
  double v;
  if (scalar_f64(text, &v) != SCALAR_OK || !(v > 0) || v > 1e300) return false;
  *(double *)dst = v;
  return true;
}

static bool parse_spot(const char *text, void *dst) {
  double v;
  if (scalar_f64(text, &v) != SCALAR_OK || !(v > 0 && v < 1)) return false;
  *(double *)dst = v;
  return true;
}

static bool parse_cost_channel(const char *text, void *dst) {
  if (!run_output_is_cost_channel(text)) return false;
  *(const char **)dst = text;
  return true;
}

/* --trace-events-window FROM:TO (cycles, FROM < TO; TO empty: the end). */
static bool parse_trace_window(const char *text, void *dst) {
  struct machine_trace_params *tp = dst;
  const char *colon = strchr(text, ':');
  uint64_t from, to = UINT64_MAX;
  if (!colon || scalar_u64_n(text, (size_t)(colon - text), &from) != SCALAR_OK) return false;
  if (colon[1] && (scalar_u64(colon + 1, &to) != SCALAR_OK || to <= from)) return false;
  tp->from_cycle = from;
  tp->to_cycle = to;
  return true;
}

/* What rtsim run was asked: its options and files (argv's strings). */
struct run_plan {
  const char *out, *machine_path, *scene_path;
  uint32_t mask;
  uint64_t width, height, seed;
  bool have_seed;
  enum policy_kind policy;
  const char *trace_path, *cost_preview, *cost_channel;
  double cost_max;
  const char *events_path; /* --trace-events; tev its window, the rest below */
  double spot;             /* --spot-check: the banked sample's fraction (0: none) */
  struct machine_trace_params tev;
  uint64_t tev_cores, tev_period, tev_max;
  bool help_keys, help_stats, help_stats_md;
  int accel;            /* --accel (enum accel_kind), -1: the scene's */
  struct app_sets sets; /* sized by the caller for argc entries */
};

/* Parse argv into pl. OPTS_GO to go on; else the exit code, after the help
 * asked for on stdout or a usage error on stderr. */
static int run_plan_parse(struct run_plan *pl, int argc, char **argv) {
  char policy_expect[160];
  app_policy_expect(policy_expect, sizeof policy_expect, "");
  const struct opts_spec spec[] = {
      OPTS_STR("output", 'o', &pl->out),
      APP_RENDER_OPTS(&pl->width, &pl->height, &pl->mask, &pl->seed, &pl->have_seed, &pl->policy,
                      policy_expect),
      APP_ACCEL_OPT(&pl->accel),
      OPTS_PARSE("set", 0, &pl->sets, app_sets_add, "KEY=VALUE"),
      OPTS_STR("dram-trace", 0, &pl->trace_path),
      OPTS_STR("trace-events", 0, &pl->events_path),
      OPTS_PARSE("trace-events-window", 0, &pl->tev, parse_trace_window,
                 "FROM:TO, whole cycles with FROM below TO, or FROM: (to the end)"),
      OPTS_U64("trace-events-cores", 0, &pl->tev_cores, 1, MACHINE_MAX_CONTEXTS),
      OPTS_U64("trace-events-period", 0, &pl->tev_period, 1, UINT64_MAX),
      OPTS_U64("trace-events-max", 0, &pl->tev_max, 1000, 1000000000),
      OPTS_PARSE("spot-check", 0, &pl->spot, parse_spot, "a fraction above 0 and below 1"),
      OPTS_STR("cost-preview", 0, &pl->cost_preview),
      OPTS_PARSE("cost-channel", 0, &pl->cost_channel, parse_cost_channel,
                 "one of: cost.issue_slots, cost.load_wait_cycles, cost.dram_read_bytes.geometry, "
                 ".node, .ray, .queue, .other, cost.dram_write_bytes, cost.energy_nj"),
      OPTS_PARSE("cost-max", 0, &pl->cost_max, parse_cost_max, "a number above 0"),
      OPTS_FLAG("help-keys", 0, &pl->help_keys),
      OPTS_FLAG("help-stats", 0, &pl->help_stats),
      OPTS_FLAG("help-stats-markdown", 0, &pl->help_stats_md),
      OPTS_END};
  struct opts_args args;
  char help[sizeof HELP + 1024];
  app_help(help, sizeof help, HELP);
  int rc = opts_parse("run", help, spec, argc, argv, &args);
  if (rc != OPTS_GO) return rc;
  if (pl->help_keys) {
    machine_cfg_write_keys(stdout);
    return 0;
  }
  if (pl->help_stats || pl->help_stats_md) {
    run_output_stats_help(stdout, pl->help_stats_md);
    return fflush(stdout) == 0 ? 0 : 1;
  }
  if (args.n != 2)
    return app_usage_error("run", "expected MACHINE.yaml SCENE.yaml, got %d file%s", args.n,
                           args.n == 1 ? "" : "s");
  pl->machine_path = args.v[0];
  pl->scene_path = args.v[1];
  if (!pl->out) return app_usage_error("run", "missing -o OUTDIR");
  pl->tev.cores = (uint32_t)pl->tev_cores;
  pl->tev.counter_period_cycles = pl->tev_period;
  pl->tev.max_events = pl->tev_max;
  return OPTS_GO;
}

/* The options pl gives that machine mc cannot take, as a usage error; false
 * after reporting one. */
static bool run_plan_fits(const struct run_plan *pl, const struct machine_cfg *mc) {
  if (pl->cost_preview &&
      (mc->p.fidelity == MACHINE_FIDELITY_ANALYTIC || mc->sample.fraction < 1)) {
    app_usage_error("run", "--cost-preview: per-pixel costs are counted by whole timed runs only "
                           "(not at fidelity analytic, not with sample.fraction below 1)");
    return false;
  }
  if (pl->trace_path && mc->p.fidelity == MACHINE_FIDELITY_ANALYTIC) {
    app_usage_error("run", "--dram-trace: fidelity analytic makes no DRAM requests (choose a "
                           "timed rung: --set fidelity=fixed, channel or banked)");
    return false;
  }
  if (pl->events_path && mc->p.fidelity == MACHINE_FIDELITY_ANALYTIC) {
    app_usage_error("run", "--trace-events: fidelity analytic runs no machine (choose a timed "
                           "rung: --set fidelity=fixed, channel or banked)");
    return false;
  }
  if (pl->events_path && 2 * (uint64_t)mc->p.threads_per_core *
                                     (pl->tev.cores < mc->p.cores ? pl->tev.cores : mc->p.cores) +
                                 2 >=
                             pl->tev.max_events) {
    app_usage_error("run", "--trace-events-max %llu: too few for two events a traced thread",
                    (unsigned long long)pl->tev.max_events);
    return false;
  }
  return true;
}

/* What the config asks that cannot run here (a W x H render of pl on mc),
 * refused at the key that asks it before anything runs: false after
 * reporting it. */
static bool run_plan_runs_here(const struct run_plan *pl, const struct machine_cfg *mc, uint32_t W,
                               uint32_t H, struct err *e) {
  char whybuf[512];
  const char *key = "sample.fraction";
  const uint32_t contexts = mc->p.cores * mc->p.threads_per_core * mc->p.rays_per_thread;
  const char *why =
      sample_problem(&mc->sample, mc->p.fidelity, pl->policy, app_work_items(pl->policy, W, H),
                     contexts, whybuf, sizeof whybuf);
  if (!why && pl->spot > 0)
    why = spot_check_problem(pl->spot, mc, pl->policy, W, H, whybuf, sizeof whybuf);
  if (!why && mc->sample.fraction < 1 && pl->trace_path)
    why = "sample.fraction: --dram-trace records a whole run; a sampled run skips most of the work";
  /* Every ray context may hold a coroutine stack at once (the timed rungs). */
  const uint64_t stack_limit = coro_host_stack_limit();
  if (!why && mc->p.fidelity != MACHINE_FIDELITY_ANALYTIC && contexts > stack_limit) {
    snprintf(whybuf, sizeof whybuf,
             "cores x threads_per_core x rays_per_thread = %u ray contexts, and this host lets "
             "a process map the stacks of at most %llu (vm.max_map_count: two mappings a "
             "stack); fewer contexts, or raise the limit (sysctl vm.max_map_count)",
             contexts, (unsigned long long)stack_limit);
    why = whybuf;
    key = "cores";
  }
  if (!why) return true;
  const struct machine_cfg_origin *o = &mc->at[machine_cfg_find(key)];
  err_set(e, o->file[0] ? o->file : pl->machine_path, o->line, o->col, "%s", why);
  app_report(e);
  return false;
}

/* The files a run writes besides OUTDIR's own (struct run_extras). */
enum { EXTRA_DRAM_TRACE, EXTRA_HEAT, EXTRA_EVENTS, EXTRAS };

/* Open the DRAM trace, the heat map and the trace events: in od's sibling
 * when asked for in OUTDIR, else beside their names, committed only when
 * every output is written. False after reporting why not. */
static bool run_open_extras(const struct run_plan *pl, struct outdir *od, struct outfile *x,
                            struct err *e) {
  const char *const extra[EXTRAS] = {pl->trace_path, pl->cost_preview, pl->events_path};
  static const char *const option[EXTRAS] = {"--dram-trace", "--cost-preview", "--trace-events"};
  static const char *const what[EXTRAS] = {"the DRAM trace", "the heat map", "the trace events"};
  for (int k = 0; k < EXTRAS; k++) {
    if (!extra[k]) continue;
    char place[OUTDIR_PATH_MAX + 300];
    if (!outdir_place(od, extra[k], place, sizeof place)) {
      app_usage_error("run", "%s %s: that is one of the run's own outputs in OUTDIR", option[k],
                      extra[k]);
      return false;
    }
    if (strcmp(place, extra[k]) == 0) outguard_beside(place);
    bool opened = k == EXTRA_HEAT ? outfile_open_named(&x[k], place, what[k], e)
                                  : outfile_open(&x[k], place, what[k], e);
    if (!opened) {
      outdir_name_in_err(od, e);
      app_report(e);
      return false;
    }
  }
  return true;
}

/* Write rep's outputs, then commit the trace and the heat map (if pl asked
 * for them) and od; on success the rung's warning (if any) on stderr and the
 * summary on stdout. The exit code. */
static int run_write(const struct run_plan *pl, struct run_output_report *rep,
                     const struct rung_error *rung, struct outdir *od, struct outfile *x,
                     struct err *e) {
  /* The files outside OUTDIR before OUTDIR itself: a complete OUTDIR means
   * every output is in place. */
  bool ok = run_output_write(rep, e) &&
            (!pl->trace_path || outfile_commit(&x[EXTRA_DRAM_TRACE], e)) &&
            (!pl->cost_preview || outfile_commit(&x[EXTRA_HEAT], e)) &&
            (!pl->events_path || outfile_commit(&x[EXTRA_EVENTS], e)) && outdir_commit(od, e);
  if (!ok) outdir_name_in_err(od, e);
  int rc = ok ? 0 : app_report(e);
  if (rc == 0 && rung && rung->warn) {
    char line[1024];
    rung_error_warning(rung, line, sizeof line);
    fprintf(stderr, "rtsim run: warning: %s\n", line);
  }
  rep->out_dir = pl->out;
  if (rc == 0) run_output_summary(rep, stdout);
  if (rc == 0 && rep->spot) spot_check_summary(rep->spot, stdout);
  return rc;
}

/* The trace events of the run on m into f; a warning on stderr when the
 * cap cut them short. */
static void run_write_events(const struct run_plan *pl, const struct machine *m, FILE *f) {
  machine_trace_write(m, f);
  bool capped;
  uint64_t cut;
  const uint64_t n = machine_trace_events(m, &capped, &cut);
  if (capped)
    fprintf(stderr,
            "rtsim run: warning: --trace-events: %llu events, the cap (--trace-events-max): the "
            "trace ends at cycle %llu; narrow --trace-events-window or --trace-events-cores, or "
            "raise the cap\n",
            (unsigned long long)n, (unsigned long long)cut);
  (void)pl;
}

/* Run pl's W x H render of w on mc and write its outputs (run_write). The
 * exit code. */
static int run_render(const struct run_plan *pl, const struct machine_cfg *mc,
                      const struct app_world *w, uint32_t W, uint32_t H, struct outdir *od,
                      struct outfile *x, struct err *e) {
  const bool analytic = mc->p.fidelity == MACHINE_FIDELITY_ANALYTIC;
  const uint64_t seed = pl->have_seed ? pl->seed : w->scene.seed;
  struct app_timed t = {0};
  struct app_analytic a;
  if (analytic) app_analytic_run(&a, w, pl->mask, seed, W, H, pl->policy, &mc->p, &mc->work);
  else
    app_timed_run(&t, w, pl->mask, seed, W, H, pl->policy, &mc->p, &mc->work, &mc->sample,
                  isatty(2), x[EXTRA_DRAM_TRACE].f, true, pl->events_path ? &pl->tev : NULL);
  if (!analytic && pl->events_path) run_write_events(pl, t.m, x[EXTRA_EVENTS].f);
  /* A whole run at a cheaper rung says how wrong that rung was measured to be
   * in runs like it (docs/fidelity-and-sampling.md). */
  struct rung_error rung = {0};
  const bool cheaper = mc->p.fidelity != MACHINE_FIDELITY_BANKED && !t.sampled;
  if (cheaper && analytic) {
    rung_error_match(&rung, &mc->p, policy_name(pl->policy),
                     a.est.bandwidth_bound_cycles > a.est.latency_bound_cycles, a.est.cycles,
                     a.counts.issue_slots, a.counts.fetch_bytes + a.counts.writeback_bytes);
  } else if (cheaper) {
    const struct machine_stats *s = machine_get_stats(t.m);
    rung_error_match(&rung, &mc->p, policy_name(pl->policy), -1, s->cycles, s->issue_slots,
                     s->dram.read_bytes + s->dram.write_bytes);
  }
  struct spot_check spot;
  if (pl->spot > 0) {
    const struct machine_stats *s = analytic ? NULL : machine_get_stats(t.m);
    spot_check_run(&spot, pl->spot, w, pl->mask, seed, W, H, pl->policy, mc,
                   analytic ? a.est.cycles : (double)s->cycles,
                   analytic ? (double)(a.counts.fetch_bytes + a.counts.writeback_bytes)
                            : (double)(s->dram.read_bytes + s->dram.write_bytes));
  }
  struct run_output_report rep = {
      .out_dir = od->write,
      .machine_path = pl->machine_path,
      .scene_path = pl->scene_path,
      .scene_name = w->scene.name[0] ? w->scene.name : "unnamed",
      .policy = policy_name(pl->policy),
      .mask = pl->mask,
      .width = W,
      .height = H,
      .seed = analytic ? a.ar.sc.seed : t.ar.sc.seed,
      .scene_hash = scene_hash(&w->scene),
      .kd_splits = w->scene.kd_clip ? "clipped" : "whole",
      .accel = accel_names[w->scene.accel],
      .cfg = mc,
      .machine = t.m,
      .sample = t.sampled ? &t.sample : NULL,
      .rung = cheaper ? &rung : NULL,
      .spot = pl->spot > 0 ? &spot : NULL,
      .analytic = analytic ? &a : NULL,
      .rstats = analytic ? &a.st : &t.st,
      .tstats = analytic ? &a.ts : &t.ts,
      .fb = analytic ? &a.ar.fb : &t.ar.fb,
      .costs = !analytic && t.costs ? machine_get_costs(t.m) : NULL,
      .cost_preview = pl->cost_preview ? &x[EXTRA_HEAT] : NULL,
      .cost_channel = pl->cost_channel,
      .cost_max = pl->cost_max,
      .wall_s = analytic ? a.wall_s : t.wall_s,
  };
  int rc = run_write(pl, &rep, cheaper ? &rung : NULL, od, x, e);
  if (analytic) app_analytic_fini(&a);
  else app_timed_fini(&t);
  return rc;
}

int cmd_run(int argc, char **argv) {
  struct run_plan pl = {
      .mask = RAY_MASK(RAY_TYPE_COUNT) - 1, /* every ray type */
      .policy = POLICY_RECURSIVE,
      .accel = -1,
      .cost_channel = "cost.issue_slots",
      .tev = {.to_cycle = UINT64_MAX},
      .tev_cores = 2,
      .tev_period = 1000,
      .tev_max = 1000000,
      .sets = {xcalloc((size_t)argc + 1, sizeof *pl.sets.v), 0}}; /* at most one an argument */
  struct outfile x[EXTRAS] = {{0}};
  struct outdir od = {0};
  struct app_world w;
  bool have_world = false;
  struct machine_cfg mc;
  struct err e;
  memset(&e, 0, sizeof e);
  int rc = run_plan_parse(&pl, argc, argv);
  if (rc != OPTS_GO) goto done;
  rc = APP_EXIT_USAGE;
  if (!app_machine_load(&mc, pl.machine_path, &pl.sets, &e)) {
    app_report(&e);
    goto done;
  }
  if (!run_plan_fits(&pl, &mc)) goto done;
  /* Everything that can refuse the run is checked before OUTDIR is touched:
   * the config, the scene, then what the host cannot run. */
  if (!(have_world = app_world_load_as(&w, pl.scene_path, pl.accel))) goto done;
  const uint32_t W = pl.width ? (uint32_t)pl.width : w.scene.width;
  const uint32_t H = pl.height ? (uint32_t)pl.height : w.scene.height;
  if (!run_plan_runs_here(&pl, &mc, W, H, &e)) goto done;
  /* The outputs go to a fresh sibling of OUTDIR put in its place at the end;
   * a signal from here on removes it (app/outdir.h). */
  if (!outdir_begin(&od, pl.out, run_output_files, &e)) {
    app_report(&e);
    goto done;
  }
  if (!run_open_extras(&pl, &od, x, &e)) goto done;
  rc = run_render(&pl, &mc, &w, W, H, &od, x, &e);
done:
  if (have_world) app_world_fini(&w);
  for (int k = 0; k < EXTRAS; k++) outfile_abort(&x[k]);
  outdir_abort(&od);
  outguard_clear();
  free(pl.sets.v);
  return rc;
}
