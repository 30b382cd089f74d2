/* One render on the timed machine (app.h: struct app_timed), for rtsim run and
 * rtsim bench: a policy job, one worker per ray context, the machine. */
#include "app/app.h"

#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

#include "sim/err.h"
#include "sim/machine.h"

struct timed_ctx {
  struct policy_job *job;
  struct policy_worker *workers;
  uint64_t done, total; /* as the policy reports them (work items, or rays for dynamic) */
  double t0;
};

static void run_worker(void *arg, const struct machine_worker_info *info, struct mem_port port) {
  struct timed_ctx *r = arg;
  struct policy_worker *w = &r->workers[info->id];
  policy_worker_init(w, r->job, info->id, info->core, info->thread, port);
  policy_job_work(r->job, w);
  policy_worker_fini(r->job, w);
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
                   const struct machine_params *mp, bool progress) {
  app_render_init(&t->ar, w, mask, seed, width, height);
  t->ar.setup.layout.node_cycles = mp->cost_node_cycles;
  t->ar.setup.layout.tri_cycles = mp->cost_triangle_cycles;
  t->ar.sc.shade_cycles = mp->cost_shade_cycles;
  struct policy_params pp;
  policy_params_machine(&pp, mp->l2_size_bytes, (uint64_t)mp->l2_latency_cycles + mp->dram_latency_cycles);
  const uint32_t n = mp->cores * mp->threads_per_core * mp->rays_per_thread;
  struct timed_ctx r = {0};
  t->ar.setup.progress = work_progress;
  t->ar.setup.progress_ctx = &r;
  r.job = policy_job_create(k, &t->ar.setup, &pp, n, mp->cores);
  r.workers = xcalloc(n, sizeof *r.workers);
  t->m = machine_create(mp, 0);
  r.t0 = app_now();
  machine_run(t->m, run_worker, &r, progress ? cycle_progress : NULL, &r);
  t->wall_s = app_now() - r.t0;
  if (progress) fputc('\n', stderr);
  policy_job_finish(r.job, &t->st, &t->ts);
  free(r.workers);
  policy_job_destroy(r.job);
}

void app_timed_fini(struct app_timed *t) {
  machine_destroy(t->m);
  app_render_fini(&t->ar);
}
