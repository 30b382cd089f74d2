/* One event per request, at taken + latency. */
#include "sim/dram_fixed.h"

#include <stdlib.h>

#include "sim/engine.h"
#include "sim/stats.h"

struct dram_fixed {
  uint64_t latency;
  struct engine *eng;
  struct dram_client client;
};

static void ev_done(void *ctx, uint64_t tag) {
  struct dram_fixed *d = ctx;
  d->client.done(d->client.ctx, tag);
}

static bool fx_can_take(void *self, uint64_t addr, bool write) {
  (void)self;
  (void)addr;
  (void)write;
  return true;
}

static void fx_take(void *self, uint64_t addr, bool write, uint64_t tag) {
  struct dram_fixed *d = self;
  (void)addr;
  (void)write;
  engine_at(d->eng, engine_now(d->eng) + d->latency, ev_done, d, tag);
}

static void fx_finish(void *self, uint64_t end) { (void)self, (void)end; }

static void fx_stats(const void *self, struct stats_part *out) {
  (void)self;
  out->g = NULL;
}

static void fx_destroy(void *self) { free(self); }

const struct dram_level_ops dram_fixed_ops = {fx_can_take, fx_take,    fx_finish,
                                              fx_stats,    fx_destroy, NULL};

struct dram_fixed *dram_fixed_create(uint64_t latency_cycles, struct engine *e,
                                     const struct dram_client *client) {
  struct dram_fixed *d = xcalloc(1, sizeof *d);
  d->latency = latency_cycles;
  d->eng = e;
  d->client = *client;
  return d;
}
