/* Shared pieces of the rtsim command-line program. Commands return an exit
 * code: 0 success, 2 bad input (message already printed), 1 other failure. */
#ifndef RTSIM_APP_APP_H
#define RTSIM_APP_APP_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "app/sample.h"
#include "renderer/bvh.h"
#include "renderer/framebuffer.h"
#include "renderer/kdtree.h"
#include "renderer/policy/policy.h"
#include "renderer/scene.h"
#include "renderer/shade.h"
#include "sim/analytic.h"

struct err;

#define APP_EXIT_USAGE 2

int cmd_render(int argc, char **argv);
int cmd_export(int argc, char **argv);
int cmd_hits(int argc, char **argv);
int cmd_bench(int argc, char **argv);
int cmd_traffic(int argc, char **argv);
int cmd_trace(int argc, char **argv);
int cmd_run(int argc, char **argv);
int cmd_sweep(int argc, char **argv);
int cmd_merge(int argc, char **argv);
int cmd_plot(int argc, char **argv);
int cmd_dram_replay(int argc, char **argv);

/* A command of the program: its name, its entry, its lines in the usage. */
struct app_command {
  const char *name;
  int (*run)(int argc, char **argv);
  const char *usage;
};
/* rtsim --man (app/man.c): the manual page in roff on f, from usage (the
 * program's) and each of cmds[0..n)'s --help-full. The exit code. */
int app_man(FILE *f, const char *usage, const struct app_command *cmds, unsigned n);

/* Print "rtsim: <formatted err>" once to stderr; returns APP_EXIT_USAGE. */
int app_report(const struct err *e);
/* Print "rtsim CMD: message" plus a hint to run --help; returns APP_EXIT_USAGE. */
int app_usage_error(const char *cmd, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* Option values several commands take (app/opts.h, OPTS_KIND_PARSE): ray
 * types, comma-separated, into a uint32_t mask (shade_parse_rays); a policy
 * name into an enum policy_kind. */
bool app_parse_rays(const char *text, void *mask);
#define APP_RAYS_EXPECT "a comma-separated list of primary, shadow, specular, diffuse"
bool app_parse_policy(const char *text, void *kind);
/* --accel: kd, bvh2 or bvh8 into an int (enum accel_kind). */
bool app_parse_accel(const char *text, void *accel);
#define APP_ACCEL_EXPECT "one of kd, bvh2, bvh8"
/* --accel ACCEL (int *accel, set to -1 beforehand: the scene's own). */
#define APP_ACCEL_OPT(accel) OPTS_PARSE("accel", 0, accel, app_parse_accel, APP_ACCEL_EXPECT)
/* What --policy takes, "one of: recursive, ..." and then `more` (", all"). */
void app_policy_expect(char *buf, size_t cap, const char *more);
/* A command's help text with every line "{policies}" (after any indent) made
 * the table of policies, a line each at that indent: name and what it does
 * (renderer/policy), so that a policy added there is in every help. Into
 * buf (cut to cap). */
void app_help(char *buf, size_t cap, const char *text);
/* The opts.h table entries render and run share: --width, --height (uint64_t),
 * --rays (uint32_t mask), --seed (uint64_t, and a bool set when given),
 * --policy (enum policy_kind; policy_expect: app_policy_expect's text). */
#define APP_RENDER_OPTS(width, height, mask, seed, have_seed, policy, policy_expect)               \
  OPTS_U64("width", 0, width, 1, 16384), OPTS_U64("height", 0, height, 1, 16384),                  \
      OPTS_PARSE("rays", 0, mask, app_parse_rays, APP_RAYS_EXPECT),                                \
      {.name = "seed",                                                                             \
       .kind = OPTS_KIND_U64,                                                                      \
       .dst = (seed),                                                                              \
       .hi = UINT64_MAX,                                                                           \
       .given = (have_seed)},                                                                      \
      OPTS_PARSE("policy", 0, policy, app_parse_policy, policy_expect)

/* The source revision this program was built from: `git describe --always
 * --dirty` of the source tree at build time, or "unknown" outside a git
 * checkout (cmake/revision.cmake writes it; the program never calls git). */
extern const char app_revision[];

/* Host wall clock in seconds (for reports only; the model never reads it). */
double app_now(void);

/* A loaded scene and its acceleration structure (the scene's accel: the k-d
 * tree, or a BVH and then kd is empty), with the host times they took. */
struct app_world {
  struct scene scene;
  struct kd_tree kd;
  struct bvh bvh;
  double load_s, build_s;
};

/* Load path and build the tree; on bad input prints and returns false. */
bool app_world_load(struct app_world *w, const char *path);
/* The same with the structure accel (enum accel_kind) in place of the
 * scene's accel key; accel < 0: the scene's. */
bool app_world_load_as(struct app_world *w, const char *path, int accel);
void app_world_fini(struct app_world *w);
/* The BVH w's scene is traced through, or NULL for the k-d tree (what a
 * tracer's trace_ctx.bvh takes). */
const struct bvh *app_world_bvh(const struct app_world *w);

struct trace_ctx;
/* rtsim hits after its set-up: the rays CSV read from in (named <stdin> in
 * messages), each row's nearest hit written to out. Returns 0, or 2 after
 * printing one message (tests/fuzz runs it on a world loaded once). */
int app_hits_answer(struct trace_ctx *tr, FILE *in, FILE *out);

/* What a render of a world needs besides the policy and the memory port: the
 * shading context, the framebuffer and the policy setup that points at them
 * (so it must not move once set up). One setup for render, traffic, bench and
 * run, so that they all render the same memory image. */
struct app_render {
  struct shade_ctx sc;
  struct framebuffer fb;
  struct policy_setup setup;
};

/* Set up a width x height render of w: the default layout, the ray types in
 * mask shaded with seed, the framebuffer at layout.fb_base. No progress
 * callback and no tested set: set them in r->setup if wanted (a tested set
 * stays the caller's). w must outlive r. */
void app_render_init(struct app_render *r, const struct app_world *w, uint32_t mask, uint64_t seed,
                     uint32_t width, uint32_t height);
void app_render_fini(struct app_render *r);

struct machine;
struct machine_params;
struct machine_trace_params;
struct machine_cfg_work;
struct machine_cfg_sample;
/* One render on the timed machine: the machine (its statistics and timeline),
 * the framebuffer in ar, the render's counters and the host seconds it took. */
struct app_timed {
  struct app_render ar;
  struct machine *m;
  struct sampler sample; /* sample.fraction < 1 (sampled): the plan and probes */
  bool sampled;
  bool costs; /* per-pixel costs counted (machine_get_costs) */
  struct render_stats st;
  struct trace_stats ts;
  double wall_s;
};
/* Render a width x height image of w with policy k on machine mp (which must
 * pass machine_params_problem), one worker per ray context; the compute the
 * renderer announces and the dynamic policy's sharing come from work; the run
 * is sampled as `sample` says (sample_problem must pass it). progress: a
 * progress line on stderr. costs: count what every pixel cost the machine
 * (machine_get_costs; a whole run only, not a sampled one). events: the
 * trace layer's window and cores (machine_trace_enable; NULL: none). */
void app_timed_run(struct app_timed *t, const struct app_world *w, uint32_t mask, uint64_t seed,
                   uint32_t width, uint32_t height, enum policy_kind k,
                   const struct machine_params *mp, const struct machine_cfg_work *work,
                   const struct machine_cfg_sample *sample, bool progress, FILE *dram_trace,
                   bool costs, const struct machine_trace_params *events);
void app_timed_fini(struct app_timed *t);
/* The work items a render of policy k at width x height takes (sampling's
 * population: pixels, or tiles for packet). */
uint64_t app_work_items(enum policy_kind k, uint32_t width, uint32_t height);

/* The fidelity ladder's analytic rung (app/run_analytic.c): the same render
 * with one worker on one core through sim/analytic.h's counting backend (the
 * dynamic policy's queue points made for mp's L2), then the estimate. No
 * machine is built. */
struct app_analytic {
  struct app_render ar;
  struct analytic_counts counts;
  struct analytic_estimate est;
  struct render_stats st;
  struct trace_stats ts;
  double wall_s;
};
void app_analytic_run(struct app_analytic *a, const struct app_world *w, uint32_t mask,
                      uint64_t seed, uint32_t width, uint32_t height, enum policy_kind k,
                      const struct machine_params *mp, const struct machine_cfg_work *work);
void app_analytic_fini(struct app_analytic *a);

/* Repeatable --set KEY=VALUE options, in order (argv's strings): an
 * OPTS_PARSE destination (app_sets_add) sized for argc entries. */
struct app_sets {
  const char **v;
  unsigned n;
};
bool app_sets_add(const char *text, void *dst);
/* The default machine, then the config file at path, then the --set
 * assignments, then the relations between keys: false (e filled) on the
 * first problem. */
struct machine_cfg;
bool app_machine_load(struct machine_cfg *mc, const char *path, const struct app_sets *sets,
                      struct err *e);

#endif
