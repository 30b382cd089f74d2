/* The recursive policy: single rays in Hilbert order, each primary ray's
 * secondary rays traced depth-first before the pixel is done (Whitted).
 * A work item is a pixel: workers take the next one in Hilbert order from the
 * job's shared counter, each tracing its pixels' ray trees on its own stack.
 * The depth-first stack is an explicit array of 64-byte rays that lives in the
 * simulated memory image, in the worker's ray region (a push is a store, a pop
 * a load), so a coroutine can suspend anywhere and its ray traffic is counted
 * like any other data. */
#include "renderer/policy/policy_impl.h"

#include <stdlib.h>

#include "renderer/camera.h"
#include "renderer/framebuffer.h"
#include "renderer/policy/policy.h"
#include "renderer/scene.h"
#include "renderer/shade.h"
#include "renderer/trace.h"
#include "sim/err.h"

/* Depth-first stack bound: each of up to SHADE_MAX_DEPTH + 1 levels holds the
 * siblings spawned by one hit. */
#define RECURSIVE_STACK ((SHADE_MAX_DEPTH + 2) * SHADE_MAX_SPAWN)

/* A worker's own: the host copy of its stack, and what a hit spawns. */
struct rec_scratch {
  struct ray stack[RECURSIVE_STACK], spawn[SHADE_MAX_SPAWN];
};

/* Shared: the pixel order (job->shared). */
static void rec_create(struct policy_job *job) {
  const uint32_t w = job->setup.fb->width, h = job->setup.fb->height;
  job->total = (uint64_t)w * h;
  job->progress_every = 4096;
  uint32_t *order = xmalloc(job->total * sizeof *order);
  camera_hilbert_order(w, h, order);
  job->shared = order;
}

static void rec_destroy(struct policy_job *job) { free(job->shared); }

static void rec_scratch_free(void *scratch) { free(scratch); }

static bool rec_step(struct policy_job *job, struct policy_worker *wk) {
  uint64_t k;
  if (policy_job_claim(job, 1, &k) == 0) return false;
  struct mem_port own;
  const enum policy_item how = policy_item_begin(job, wk, k, &own);
  if (how == POLICY_ITEM_SKIP) {
    policy_job_done(job, 1);
    return true;
  }
  const bool detail = how == POLICY_ITEM_DETAIL;
  if (!wk->scratch) wk->scratch = xmalloc(sizeof(struct rec_scratch));
  struct rec_scratch *x = wk->scratch;
  struct ray *stack = x->stack;
  struct trace_ctx *tr = &wk->tr;
  struct render_stats *st = &wk->st;
  const struct shade_ctx *sc = job->setup.sc;
  struct framebuffer *fb = job->setup.fb;
  const struct mem_port *mem = &tr->mem;
  const uint64_t stack_addr = tr->layout.ray_base;
  const uint32_t w = fb->width;
  const uint32_t pix = ((const uint32_t *)job->shared)[k];

  /* The pixel's cost: this worker's own work in between (nobody else counts
   * into its tracer, whatever runs while it waits). */
  uint64_t nodes0 = tr->stats.node_visits, tris0 = tr->stats.tri_tests;
  uint32_t top = 0;
  trace_attribute(tr, &pix, 1); /* all its rays are the pixel's */
  policy_primary(job, wk, pix % w, pix / w, &stack[top]);
  mem_store(mem, stack_addr, sizeof(struct ray), TRACE_CLASS_RAY);
  top++;
  if (st->ray_slots_max == 0) st->ray_slots_max = 1;
  st->spawned++;
  while (top > 0) {
    struct ray r = stack[--top];
    mem_load(mem, stack_addr + (uint64_t)top * sizeof r, sizeof r, TRACE_CLASS_RAY);
    st->rays[r.type]++;
    st->terminated++;
    if (r.type == RAY_SHADOW) {
      shade_shadow(&r, trace_any(tr, &r), fb, mem);
      continue;
    }
    struct trace_hit hit;
    trace_closest(tr, &r, &hit);
    uint32_t n = shade_hit(sc, &r, &hit, fb, mem, x->spawn);
    CHECK_LE(top + n, RECURSIVE_STACK);
    /* Push in reverse so the first spawned (shadow rays) are traced first. */
    for (uint32_t i = n; i-- > 0;) {
      mem_store(mem, stack_addr + (uint64_t)top * sizeof r, sizeof r, TRACE_CLASS_RAY);
      stack[top++] = x->spawn[i];
    }
    if (top > st->ray_slots_max) st->ray_slots_max = top;
    st->spawned += n;
  }
  fb->cost_nodes[pix] += (uint32_t)(tr->stats.node_visits - nodes0);
  fb->cost_tris[pix] += (uint32_t)(tr->stats.tri_tests - tris0);
  policy_item_end(job, wk, k, &own, detail);
  policy_job_done(job, 1);
  return true;
}

const struct policy_module policy_recursive_module = {
    .region_bytes = RECURSIVE_STACK * sizeof(struct ray),
    .max_workers = 0, /* as many as the ray regions allow */
    .create = rec_create,
    .destroy = rec_destroy,
    .step = rec_step,
    .scratch_free = rec_scratch_free,
};
