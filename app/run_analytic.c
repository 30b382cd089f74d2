/* rtsim run at fidelity analytic: the render every rung makes, through one
 * worker and the counting backend of sim/analytic.h, then its estimate. The
 * image is the same as at every other rung (the renderer is). */
#include "app/app.h"

#include <string.h>

#include "renderer/policy/policy.h"
#include "renderer/trace.h"
#include "sim/analytic.h"
#include "sim/machine.h"
#include "sim/machine_cfg.h"

void app_analytic_run(struct app_analytic *a, const struct app_world *w, uint32_t mask,
                      uint64_t seed, uint32_t width, uint32_t height, enum policy_kind k,
                      const struct machine_params *mp, const struct machine_cfg_work *work) {
  memset(a, 0, sizeof *a);
  app_render_init(&a->ar, w, mask, seed, width, height);
  a->ar.setup.layout.node_cycles = work->cost_node_cycles;
  a->ar.setup.layout.tri_cycles = work->cost_triangle_cycles;
  a->ar.sc.shade_cycles = work->cost_shade_cycles;
  struct policy_params pp;
  policy_params_machine(&pp, mp->l2_size_bytes);
  pp.dyn_sharing = work->dyn_sharing; /* one core: either way the same */
  /* One worker on one core. NOTE: the dynamic policy's queue points are then
   * made for the whole L2 (g_max not divided among the cores, a one-ray ray
   * buffer), so it may do somewhat different work than on the timed machine;
   * a plan for C cores needs at least C workers. */
  struct policy_job *job = policy_job_create(k, &a->ar.setup, &pp, 1, 1);
  struct analytic *be = analytic_create(mp);
  double t0 = app_now();
  struct policy_worker wk;
  policy_worker_init(&wk, job, 0, 0, 0, analytic_port(be));
  CHECK(!policy_job_work(job, &wk)); /* one worker never parks */
  policy_worker_fini(job, &wk);
  policy_job_finish(job, &a->st, &a->ts);
  a->counts = *analytic_get_counts(be);
  analytic_estimate(mp, &a->counts, &a->est);
  a->wall_s = app_now() - t0;
  analytic_destroy(be);
  policy_job_destroy(job);
}

void app_analytic_fini(struct app_analytic *a) { app_render_fini(&a->ar); }
