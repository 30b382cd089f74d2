/* The recursive policy: single rays in Hilbert order, each primary ray's
 * secondary rays traced depth-first before the next pixel starts (Whitted).
 * The depth-first stack is an explicit array of 64-byte rays that lives in the
 * simulated memory image (a push is a store, a pop a load), so a coroutine can
 * suspend anywhere and its ray traffic is counted like any other data. */
#include <stdlib.h>

#include "renderer/camera.h"
#include "renderer/framebuffer.h"
#include "renderer/policy.h"
#include "renderer/scene.h"
#include "renderer/shade.h"
#include "renderer/trace.h"
#include "sim/err.h"

/* Depth-first stack bound: each of up to SHADE_MAX_DEPTH + 1 levels holds the
 * siblings spawned by one hit. */
#define RECURSIVE_STACK ((SHADE_MAX_DEPTH + 2) * SHADE_MAX_SPAWN)

void policy_recursive_run(const struct policy_env *env, const struct policy_params *p) {
  (void)p;
  struct tracer *tr = env->tr;
  const struct shade_ctx *sc = env->sc;
  struct framebuffer *fb = env->fb;
  struct render_stats *st = env->st;
  const struct mem_port *mem = &tr->mem;
  const uint64_t stack_addr = tr->layout.ray_base;
  const uint32_t w = fb->width, h = fb->height;
  const uint64_t npix = (uint64_t)w * h;
  uint32_t *order = xmalloc(npix * sizeof *order);
  camera_hilbert_order(w, h, order);
  struct camera_frame cf;
  camera_frame_init(&cf, &sc->scene->camera, w, h);
  struct ray stack[RECURSIVE_STACK], spawn[SHADE_MAX_SPAWN];

  for (uint64_t k = 0; k < npix; k++) {
    uint32_t pix = order[k];
    uint64_t nodes0 = tr->stats.node_visits, tris0 = tr->stats.tri_tests;
    uint32_t top = 0;
    policy_primary(env, &cf, pix % w, pix / w, &stack[top]);
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
      struct hit hit;
      trace_closest(tr, &r, &hit);
      uint32_t n = shade_hit(sc, &r, &hit, fb, mem, spawn);
      CHECK(top + n <= RECURSIVE_STACK);
      /* Push in reverse so the first spawned (shadow rays) are traced first. */
      for (uint32_t i = n; i-- > 0;) {
        mem_store(mem, stack_addr + (uint64_t)top * sizeof r, sizeof r, TRACE_CLASS_RAY);
        stack[top++] = spawn[i];
      }
      if (top > st->ray_slots_max) st->ray_slots_max = top;
      st->spawned += n;
    }
    fb->cost_nodes[pix] += (uint32_t)(tr->stats.node_visits - nodes0);
    fb->cost_tris[pix] += (uint32_t)(tr->stats.tri_tests - tris0);
    if (env->progress && (k & 4095) == 4095) env->progress(env->progress_ctx, k + 1, npix);
  }
  if (env->progress) env->progress(env->progress_ctx, npix, npix);
  free(order);
}
