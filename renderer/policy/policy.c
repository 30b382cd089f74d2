/* Policy dispatch, the shared work list, workers, names and defaults. */
#include "renderer/policy/policy.h"

#include <stdlib.h>
#include <string.h>

#include "renderer/bvh.h"
#include "renderer/camera.h"
#include "renderer/framebuffer.h"
#include "renderer/policy/policy_impl.h"
#include "renderer/scene.h"
#include "renderer/shade.h"
#include "renderer/trace.h"
#include "sim/err.h"

static const char *const NAMES[POLICY_COUNT] = {"recursive", "packet", "dynamic", "treelet"};
/* One line each for help texts (at most 60 characters). */
static const char *const ABOUT[POLICY_COUNT] = {
    "single rays, a pixel at a time in Hilbert order",
    "8x8 tiles of rays traced as packets",
    "rays queued at queue points made for the L2 (the paper's)",
    "the dynamic policy's queues at treelets sized to the L2",
};

static const struct policy_module *const MODULES[POLICY_COUNT] = {
    &policy_recursive_module, &policy_packet_module, &policy_dynamic_module,
    &policy_treelet_module};

void policy_params_default(struct policy_params *p) {
  memset(p, 0, sizeof *p);
  p->packet_dim = 8;
  p->cache_bytes = 512u * 1024u;
  p->dyn_node_share = 4;
  p->dyn_table_share = 16;
  p->dyn_ray_share = 16;
  p->dyn_ray_buffer_bytes = 4096;
  p->dyn_batch_rays = 0;
}

void policy_params_machine(struct policy_params *p, uint64_t l2_bytes) {
  policy_params_default(p);
  p->cache_bytes = l2_bytes;
  p->dyn_ray_buffer_bytes = 0;
}

const char *policy_name(enum policy_kind k) { return (unsigned)k < POLICY_COUNT ? NAMES[k] : "?"; }

const char *policy_about(enum policy_kind k) { return (unsigned)k < POLICY_COUNT ? ABOUT[k] : "?"; }

bool policy_parse(const char *name, enum policy_kind *k) {
  for (int i = 0; i < POLICY_COUNT; i++)
    if (strcmp(name, NAMES[i]) == 0) {
      *k = (enum policy_kind)i;
      return true;
    }
  return false;
}

void policy_list(char *buf, size_t cap, const char *last) {
  size_t n = 0;
  buf[0] = '\0';
  for (int i = 0; i < POLICY_COUNT && n < cap; i++)
    n += (size_t)snprintf(buf + n, cap - n, "%s%s",
                          i == 0                 ? ""
                          : i + 1 < POLICY_COUNT ? ", "
                                                 : last,
                          NAMES[i]);
}

/* ---- the work list ----------------------------------------------------------- */

uint64_t policy_job_claim(struct policy_job *job, uint64_t n, uint64_t *first) {
  uint64_t left = job->total - job->next;
  if (n > left) n = left;
  *first = job->next;
  job->next += n;
  return n;
}

void policy_job_done(struct policy_job *job, uint64_t n) {
  uint64_t before = job->done;
  job->done += n;
  CHECK_LE(job->done, job->total);
  const struct policy_setup *s = &job->setup;
  if (!s->progress || job->progress_every == 0) return;
  if (job->done / job->progress_every != before / job->progress_every || job->done == job->total)
    s->progress(s->progress_ctx, job->done, job->total);
}

enum policy_item policy_item_begin(struct policy_job *job, struct policy_worker *w, uint64_t k,
                                   struct mem_port *own) {
  const struct policy_setup *s = &job->setup;
  *own = w->tr.mem;
  if (!s->item) return POLICY_ITEM_DETAIL;
  for (uint64_t wait = 64;; wait = wait < 4096 ? 2 * wait : wait) {
    struct mem_port other = {0};
    const enum policy_item how = s->item(s->item_ctx, k, w->core, &other);
    switch (how) {
    case POLICY_ITEM_HOLD: mem_wait(own, wait); break;
    case POLICY_ITEM_PORT: w->tr.mem = other; return how;
    default: return how;
    }
  }
}

void policy_item_end(struct policy_job *job, struct policy_worker *w, uint64_t k,
                     const struct mem_port *own, bool detail) {
  w->tr.mem = *own;
  const struct policy_setup *s = &job->setup;
  if (detail && s->item_done) s->item_done(s->item_ctx, k);
}

void policy_primary(const struct policy_job *job, struct policy_worker *w, uint32_t x, uint32_t y,
                    struct ray *r) {
  const struct trace_ctx *tr = &w->tr;
  uint64_t pix = (uint64_t)y * job->setup.fb->width + x;
  mem_load(&tr->mem, tr->layout.camera_base + pix * sizeof *r, sizeof *r, TRACE_CLASS_RAY);
  camera_primary(&job->cf, x, y, job->setup.sc->seed, r);
}

/* ---- jobs and workers --------------------------------------------------------- */

uint64_t policy_ray_region_bytes(enum policy_kind k) {
  CHECK_LT((unsigned)k, POLICY_COUNT);
  return MODULES[k]->region_bytes;
}

bool policy_workers_supported(enum policy_kind k, uint32_t workers) {
  if ((unsigned)k >= POLICY_COUNT || workers == 0) return false;
  const struct policy_module *m = MODULES[k];
  if (m->max_workers && workers > m->max_workers) return false;
  /* Every worker's region must end before the next region of the layout. */
  return (uint64_t)workers * m->region_bytes <= 1ull << TRACE_REGION_SHIFT;
}

struct policy_job *policy_job_create(enum policy_kind k, const struct policy_setup *s,
                                     const struct policy_params *p, uint32_t workers,
                                     uint32_t cores) {
  CHECK(policy_workers_supported(k, workers));
  CHECK_GE(cores, 1);
  CHECK_EQ(s->sc->scene, s->scene);
  CHECK(!s->item || !policy_queues(k));
  struct policy_job *job = xcalloc(1, sizeof *job);
  job->mod = MODULES[k];
  job->setup = *s;
  job->params = *p;
  job->workers = workers;
  job->cores = cores;
  camera_frame_init(&job->cf, &s->scene->camera, s->fb->width, s->fb->height);
  job->mod->create(job);
  return job;
}

void policy_job_destroy(struct policy_job *job) {
  if (!job) return;
  job->mod->destroy(job);
  free(job);
}

uint64_t policy_job_total(const struct policy_job *job) { return job->total; }

void policy_worker_init(struct policy_worker *w, struct policy_job *job, uint32_t id, uint32_t core,
                        uint32_t thread, struct mem_port port) {
  CHECK_LT(id, job->workers);
  CHECK_LT(core, job->cores);
  const struct policy_setup *s = &job->setup;
  memset(w, 0, sizeof *w);
  trace_init(&w->tr, s->scene, s->kd, port, &s->layout);
  w->tr.bvh = s->bvh;
  w->tr.tested = s->tested;
  w->tr.attribute = s->attribute;
  w->tr.attribute_ctx = s->attribute_ctx;
  w->tr.worker = id;
  w->tr.layout.ray_base += (uint64_t)id * job->mod->region_bytes;
  w->id = id;
  w->core = core;
  w->thread = thread;
  job->live++;
}

bool policy_job_step(struct policy_job *job, struct policy_worker *w) {
  return job->mod->step(job, w);
}

bool policy_job_work(struct policy_job *job, struct policy_worker *w) {
  w->parked = false;
  while (policy_job_step(job, w))
    if (w->parked) return true;
  return false;
}

void policy_worker_fini(struct policy_job *job, struct policy_worker *w) {
  CHECK_GT(job->live, 0);
  job->mod->scratch_free(w->scratch);
  w->scratch = NULL;
  render_stats_add(&job->st, &w->st);
  job->ts.node_visits += w->tr.stats.node_visits;
  job->ts.tri_tests += w->tr.stats.tri_tests;
  job->live--;
}

void policy_job_finish(struct policy_job *job, struct render_stats *st, struct trace_stats *ts) {
  CHECK_EQ(job->live, 0);
  CHECK_EQ(job->next, job->total);
  CHECK_EQ(job->done, job->total);
  *st = job->st;
  if (job->mod->finish) job->mod->finish(job, st);
  CHECK_EQ(st->spawned, st->terminated);
  if (ts) *ts = job->ts;
}

void policy_run(enum policy_kind k, const struct policy_setup *s, const struct policy_params *p,
                struct mem_port port, struct render_stats *st, struct trace_stats *ts) {
  struct policy_job *job = policy_job_create(k, s, p, 1, 1);
  struct policy_worker w;
  policy_worker_init(&w, job, 0, 0, 0, port);
  CHECK(!policy_job_work(job, &w)); /* one worker never waits for another */
  policy_worker_fini(job, &w);
  policy_job_finish(job, st, ts);
  policy_job_destroy(job);
}
