/* What every rendering policy reports (render.h). */
#include "renderer/render.h"

uint64_t render_stats_total(const struct render_stats *st) {
  uint64_t n = 0;
  for (int t = 0; t < RAY_TYPE_COUNT; t++) n += st->rays[t];
  return n;
}

void render_stats_add(struct render_stats *sum, const struct render_stats *st) {
  for (int t = 0; t < RAY_TYPE_COUNT; t++) sum->rays[t] += st->rays[t];
  sum->spawned += st->spawned;
  sum->terminated += st->terminated;
  sum->ray_slots_max += st->ray_slots_max;
}
