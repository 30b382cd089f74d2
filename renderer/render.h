/* Rendering a whole image with the recursive policy: single rays in Hilbert
 * order, each primary ray's secondary rays traced depth-first (a per-pixel
 * explicit stack; no C recursion, so a coroutine can suspend anywhere). */
#ifndef RTSIM_RENDERER_RENDER_H
#define RTSIM_RENDERER_RENDER_H

#include <stdint.h>

#include "renderer/ray.h"

struct tracer;
struct shade_ctx;
struct framebuffer;

struct render_stats {
  uint64_t rays[RAY_TYPE_COUNT]; /* rays traced, by type */
  uint64_t spawned, terminated;  /* conservation: equal at the end */
};

/* Called every few thousand pixels with (pixels done, total); may be NULL. */
typedef void (*render_progress_fn)(void *ctx, uint64_t done, uint64_t total);

/* Trace every pixel of fb (fb's size is the image size) in Hilbert order. */
void render_recursive(struct tracer *tr, const struct shade_ctx *sc, struct framebuffer *fb,
                      struct render_stats *st, render_progress_fn progress, void *progress_ctx);

uint64_t render_stats_total(const struct render_stats *st);

#endif
