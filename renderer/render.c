/* The recursive policy: one pixel at a time, depth-first. */
#include "renderer/render.h"

#include <stdlib.h>
#include <string.h>

#include "renderer/camera.h"
#include "renderer/framebuffer.h"
#include "renderer/scene.h"
#include "renderer/shade.h"
#include "renderer/trace.h"
#include "sim/err.h"

/* Depth-first stack bound: each of up to SHADE_MAX_DEPTH + 1 levels holds the
 * siblings spawned by one hit. */
#define RENDER_STACK ((SHADE_MAX_DEPTH + 2) * SHADE_MAX_SPAWN)

uint64_t render_stats_total(const struct render_stats *st) {
  uint64_t n = 0;
  for (int t = 0; t < RAY_TYPE_COUNT; t++) n += st->rays[t];
  return n;
}

void render_recursive(struct tracer *tr, const struct shade_ctx *sc, struct framebuffer *fb,
                      struct render_stats *st, render_progress_fn progress, void *progress_ctx) {
  const uint32_t w = fb->width, h = fb->height;
  const uint64_t npix = (uint64_t)w * h;
  uint32_t *order = xmalloc(npix * sizeof *order);
  camera_hilbert_order(w, h, order);
  struct camera_frame cf;
  camera_frame_init(&cf, &sc->scene->camera, w, h);
  struct ray stack[RENDER_STACK], spawn[SHADE_MAX_SPAWN];

  for (uint64_t k = 0; k < npix; k++) {
    uint32_t pix = order[k];
    uint64_t nodes0 = tr->stats.node_visits, tris0 = tr->stats.tri_tests;
    uint32_t top = 0;
    camera_primary(&cf, pix % w, pix / w, sc->seed, &stack[top++]);
    st->spawned++;
    while (top > 0) {
      struct ray r = stack[--top];
      st->rays[r.type]++;
      st->terminated++;
      if (r.type == RAY_SHADOW) {
        shade_shadow(&r, trace_any(tr, &r), fb, &tr->mem);
        continue;
      }
      struct hit hit;
      trace_closest(tr, &r, &hit);
      uint32_t n = shade_hit(sc, &r, &hit, fb, &tr->mem, spawn);
      CHECK(top + n <= RENDER_STACK);
      /* Push in reverse so the first spawned (shadow rays) are traced first. */
      for (uint32_t i = n; i-- > 0;) stack[top++] = spawn[i];
      st->spawned += n;
    }
    fb->cost_nodes[pix] += (uint32_t)(tr->stats.node_visits - nodes0);
    fb->cost_tris[pix] += (uint32_t)(tr->stats.tri_tests - tris0);
    if (progress && (k & 4095) == 4095) progress(progress_ctx, k + 1, npix);
  }
  if (progress) progress(progress_ctx, npix, npix);
  CHECK(st->spawned == st->terminated);
  free(order);
}
