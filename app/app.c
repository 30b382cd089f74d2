/* The shared pieces of the rtsim program (app.h): error reporting, option
 * values several commands take, the world a command loads, the one render
 * setup, and a render on the timed machine. main.c only dispatches. */
#include "app/app.h"

#include "app/sample_aux.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "renderer/policy/policy.h"
#include "renderer/scene/scene_file.h"
#include "renderer/shade.h"
#include "renderer/trace.h"
#include "sim/derived.h"
#include "sim/err.h"
#include "sim/machine.h"
#include "sim/machine_cfg.h"

int app_report(const struct err *e) {
  char buf[ERR_FILE_MAX + ERR_MSG_MAX + 64];
  err_format(e, buf, sizeof buf);
  fprintf(stderr, "%s\n", buf);
  return APP_EXIT_USAGE;
}

int app_usage_error(const char *cmd, const char *fmt, ...) {
  char raw[1024], msg[1024];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(raw, sizeof raw, fmt, ap);
  va_end(ap);
  err_escape(msg, sizeof msg, raw); /* one line, whatever the user typed */
  fprintf(stderr, "rtsim %s: error: %s (see 'rtsim %s --help')\n", cmd, msg, cmd);
  return APP_EXIT_USAGE;
}

bool app_parse_rays(const char *text, void *mask) { return shade_parse_rays(text, mask); }

bool app_parse_policy(const char *text, void *kind) { return policy_parse(text, kind); }

bool app_parse_accel(const char *text, void *accel) {
  for (int k = 0; k < ACCEL_COUNT; k++)
    if (!strcmp(text, accel_names[k])) {
      *(int *)accel = k;
      return true;
    }
  return false;
}

void app_policy_expect(char *buf, size_t cap, const char *more) {
  char list[128];
  policy_list(list, sizeof list, ", ");
  snprintf(buf, cap, "one of: %s%s", list, more);
}

void app_help(char *buf, size_t cap, const char *text) {
  static const char mark[] = "{policies}\n";
  size_t n = 0;
  buf[0] = '\0';
  while (*text && n < cap) {
    const size_t len = strcspn(text, "\n") + (text[strcspn(text, "\n")] == '\n');
    const size_t indent = strspn(text, " ");
    if (!strncmp(text + indent, mark, sizeof mark - 1)) {
      for (int k = 0; k < POLICY_COUNT && n < cap; k++)
        n += (size_t)snprintf(buf + n, cap - n, "%*s%-10s %s\n", (int)indent, "",
                              policy_name((enum policy_kind)k), policy_about((enum policy_kind)k));
    } else {
      n += (size_t)snprintf(buf + n, cap - n, "%.*s", (int)len, text);
    }
    text += len;
  }
}

double app_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

bool app_world_load(struct app_world *w, const char *path) {
  return app_world_load_as(w, path, -1);
}

bool app_world_load_as(struct app_world *w, const char *path, int accel) {
  memset(w, 0, sizeof *w);
  struct err e;
  memset(&e, 0, sizeof e);
  double t0 = app_now();
  if (!scene_file_load(&w->scene, path, &e)) {
    app_report(&e);
    return false;
  }
  if (accel >= 0) {
    CHECK_LT(accel, ACCEL_COUNT);
    w->scene.accel = (uint8_t)accel;
  }
  double t1 = app_now();
  if (w->scene.accel != ACCEL_KD) {
    bvh_build(&w->bvh, &w->scene, (enum accel_kind)w->scene.accel);
    w->load_s = t1 - t0;
    w->build_s = app_now() - t1;
    return true;
  }
  struct kd_build_params p;
  kd_build_params_default(&p);
  p.clip = w->scene.kd_clip;
  unsigned long long bytes = 0;
  if (!kd_build(&w->kd, &w->scene, &p, &bytes)) {
    err_set(&e, path, 0, 0,
            "out of host memory building the k-d tree over the scene's %u "
            "triangles (an allocation of %llu bytes failed; docs/inputs.md, Limits)",
            w->scene.tri_count, bytes);
    app_report(&e);
    scene_fini(&w->scene);
    return false;
  }
  w->load_s = t1 - t0;
  w->build_s = app_now() - t1;
  return true;
}

void app_world_fini(struct app_world *w) {
  kd_fini(&w->kd);
  bvh_fini(&w->bvh);
  scene_fini(&w->scene);
}

const struct bvh *app_world_bvh(const struct app_world *w) {
  return w->scene.accel != ACCEL_KD ? &w->bvh : NULL;
}

/* ---- the one render setup (struct app_render) --------------------------------- */

void app_render_init(struct app_render *r, const struct app_world *w, uint32_t mask, uint64_t seed,
                     uint32_t width, uint32_t height) {
  memset(r, 0, sizeof *r);
  r->sc.scene = &w->scene;
  r->sc.ray_mask = mask;
  r->sc.seed = seed;
  struct policy_setup *s = &r->setup;
  s->scene = &w->scene;
  s->kd = &w->kd;
  s->bvh = app_world_bvh(w);
  trace_layout_default(&s->layout);
  s->sc = &r->sc;
  fb_init(&r->fb, width, height, s->layout.fb_base);
  s->fb = &r->fb;
}

void app_render_fini(struct app_render *r) { fb_fini(&r->fb); }

/* ---- one render on the timed machine (struct app_timed), for run and bench ---- */

struct timed_ctx {
  struct machine *m;
  struct policy_job *job;
  struct policy_worker *workers;
  uint64_t done, total; /* as the policy reports them (work items, or rays for dynamic) */
  double t0;
};

/* The rays every worker has traced so far (sampling's probes). */
static uint64_t rays_now(void *ctx) {
  const struct timed_ctx *r = ctx;
  const uint32_t n = machine_get_stats(r->m)->contexts;
  uint64_t sum = 0;
  for (uint32_t i = 0; i < n; i++) sum += render_stats_total(&r->workers[i].st);
  return sum;
}

static void run_worker(void *arg, const struct machine_worker_info *info, struct mem_port port) {
  struct timed_ctx *r = arg;
  struct policy_worker *w = &r->workers[info->id];
  /* Called again after a wake when the worker parked (policy_job_work). */
  if (!w->parked) policy_worker_init(w, r->job, info->id, info->core, info->thread, port);
  if (policy_job_work(r->job, w)) return;
  policy_worker_fini(r->job, w);
}

/* The policy's word on whom a worker's accesses are for, to its ray context
 * (worker ids are the machine's context ids). */
static void timed_attribute(void *ctx, uint32_t worker, const uint32_t *pixels, uint32_t n) {
  machine_attribute(((struct timed_ctx *)ctx)->m, worker, pixels, n);
}

static void work_progress(void *ctx, uint64_t done, uint64_t total) {
  struct timed_ctx *r = ctx;
  r->done = done;
  r->total = total;
}

static void cycle_progress(void *ctx, uint64_t cycle) {
  struct timed_ctx *r = ctx;
  double el = app_now() - r->t0, total = (double)r->total;
  double frac = total > 0 ? (double)r->done / total : 0;
  char eta[32] = "ETA ?";
  if (frac > 0) snprintf(eta, sizeof eta, "ETA %.0f s", el * (1 - frac) / frac);
  fprintf(stderr, "\rrun: %.4g Mcycles simulated, work %5.1f%%, %.3g Mcycles/s, %s   ",
          (double)cycle / 1e6, 100 * frac, el > 0 ? (double)cycle / el / 1e6 : 0.0, eta);
  fflush(stderr);
}

void app_timed_run(struct app_timed *t, const struct app_world *w, uint32_t mask, uint64_t seed,
                   uint32_t width, uint32_t height, enum policy_kind k,
                   const struct machine_params *mp, const struct machine_cfg_work *work,
                   const struct machine_cfg_sample *sample, bool progress, FILE *dram_trace,
                   bool costs, const struct machine_trace_params *events) {
  app_render_init(&t->ar, w, mask, seed, width, height);
  t->ar.setup.layout.node_cycles = work->cost_node_cycles;
  t->ar.setup.layout.tri_cycles = work->cost_triangle_cycles;
  t->ar.sc.shade_cycles = work->cost_shade_cycles;
  struct policy_params pp;
  policy_params_machine(&pp, mp->l2_size_bytes);
  pp.dyn_sharing = work->dyn_sharing;
  const uint32_t n = (uint32_t)derived_contexts(mp);
  struct timed_ctx r = {0};
  t->ar.setup.progress = work_progress;
  t->ar.setup.progress_ctx = &r;
  t->sampled = sample->fraction < 1;
  if (t->sampled) {
    t->ar.setup.item = sample_item;
    t->ar.setup.item_done = sample_item_done;
    t->ar.setup.item_ctx = &t->sample;
  }
  /* Per-pixel costs: whole runs only (a sampled run times a share of the
   * work; its other items go through ports that count nothing per pixel). */
  t->costs = costs && !t->sampled;
  if (t->costs) {
    t->ar.setup.attribute = timed_attribute;
    t->ar.setup.attribute_ctx = &r;
  }
  r.job = policy_job_create(k, &t->ar.setup, &pp, n, mp->cores);
  r.workers = xcalloc(n, sizeof *r.workers);
  t->m = r.m = machine_create(mp, 0);
  machine_worker_state(t->m, r.workers, sizeof *r.workers); /* its tracer first */
  if (t->costs) machine_costs_enable(t->m, (uint64_t)width * height, TRACE_CLASS_COUNT);
  if (t->sampled) {
    char why[512];
    CHECK(sample_problem(sample, mp->fidelity, k, policy_job_total(r.job), n, why, sizeof why) ==
          NULL);
    sample_init(&t->sample, sample, mp->cores, mp->clock_ghz, policy_job_total(r.job), n);
    t->sample.m = t->m;
    t->sample.rays_now = rays_now;
    t->sample.rays_ctx = &r;
  }
  if (dram_trace) dram_trace_to(machine_dram(t->m), dram_trace);
  if (events) machine_trace_enable(t->m, events);
  r.t0 = app_now();
  /* The pre-pass is part of what a sampled run costs: inside wall_s. */
  if (t->sampled && !sample->whole_image && sample->prepass) {
    const struct sample_aux_plan sp = sample_aux_plan_of(sample, n);
    sample_aux_run(&t->sample, &sp, sample->seed, mp, w, mask, seed, width, height, k, &pp, work);
  }
  machine_run(t->m, run_worker, &r, progress ? cycle_progress : NULL, &r);
  t->wall_s = app_now() - r.t0;
  if (progress) fputc('\n', stderr);
  policy_job_finish(r.job, &t->st, &t->ts);
  if (t->sampled) {
    sample_finish(&t->sample, render_stats_total(&t->st));
  }
  free(r.workers);
  policy_job_destroy(r.job);
}

void app_timed_fini(struct app_timed *t) {
  if (t->sampled) sample_fini(&t->sample);
  machine_destroy(t->m);
  app_render_fini(&t->ar);
}

uint64_t app_work_items(enum policy_kind k, uint32_t width, uint32_t height) {
  if (k != POLICY_PACKET) return (uint64_t)width * height;
  struct policy_params pp;
  policy_params_default(&pp);
  const uint32_t d = pp.packet_dim;
  return (uint64_t)((width + d - 1) / d) * ((height + d - 1) / d);
}

bool app_sets_add(const char *text, void *dst) {
  struct app_sets *s = dst;
  s->v[s->n++] = text;
  return true;
}

bool app_machine_load(struct machine_cfg *mc, const char *path, const struct app_sets *sets,
                      struct err *e) {
  machine_cfg_defaults(mc);
  if (!machine_cfg_load(mc, path, e)) return false;
  for (unsigned i = 0; sets && i < sets->n; i++)
    if (!machine_cfg_set(mc, sets->v[i], e)) return false;
  return machine_cfg_check(mc, e);
}
