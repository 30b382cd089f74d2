/* What every rendering policy reports, and its progress callback. */
#ifndef RTSIM_RENDERER_RENDER_H
#define RTSIM_RENDERER_RENDER_H

#include <stdint.h>

#include "renderer/ray.h"

struct render_stats {
  uint64_t rays[RAY_TYPE_COUNT]; /* rays traced, by type */
  uint64_t spawned, terminated;  /* conservation: equal at the end (checked) */
  /* The most 64-byte ray slots the policy's buffers (stack, packet buffers,
   * queue chunks) held at once: the rays in flight, for the memory budget. */
  uint64_t ray_slots_max;
};

/* Called now and then with (work done, total work); may be NULL. */
typedef void (*render_progress_fn)(void *ctx, uint64_t done, uint64_t total);

uint64_t render_stats_total(const struct render_stats *st);

/* Add st's counters to sum (ray_slots_max too: separate buffers add up). */
void render_stats_add(struct render_stats *sum, const struct render_stats *st);

#endif
