/* Sampling's ports into the machine (app/sample.c): the warming door (a
 * core's L1 and the L2's tags updated as the accesses would, no time passing,
 * nothing counted but issue slots), the counting door (issue slots only) and
 * the probe of the running totals. */
#include "sim/machine_state.h"

#include "sim/cache.h"
#include "sim/engine.h"
#include "sim/l2.h"

/* One access through core's warming port: a load fills the L1 on a miss, a
 * store (write-through, no allocation) only refreshes a line it holds; what
 * the L1 did not hold warms the L2 (a store always reaches it). */
static void warm_access(struct mwarm *w, uint64_t addr, uint32_t size, bool store) {
  struct machine *m = w->m;
  m->warm_slots++;
  struct cache *l1 = m->core[w->core].l1;
  for (uint64_t line = addr >> SIM_LINE_LG2, end = (addr + size - 1) >> SIM_LINE_LG2; line <= end;
       line++) {
    if (l1) {
      if (store) cache_use(l1, line);
      else if (cache_fill(l1, line, false)) continue;
    }
    l2_warm(m->l2, line, store);
  }
}

static void w_load(void *ctx, uint64_t addr, uint32_t size, unsigned cls) {
  (void)cls;
  warm_access(ctx, addr, size, false);
}

static void w_store(void *ctx, uint64_t addr, uint32_t size, unsigned cls) {
  (void)cls;
  warm_access(ctx, addr, size, true);
}

static void w_compute(void *ctx, uint64_t cycles) {
  struct mwarm *w = ctx;
  w->m->warm_slots += cycles;
}

static const struct mem_ops warm_ops = {w_load, w_store, w_compute, NULL, NULL, NULL};

struct mem_port machine_warm_port(struct machine *m, uint32_t core) {
  CHECK_LT(core, m->p.cores);
  struct mem_port p = {&warm_ops, &m->warm[core]};
  return p;
}

uint64_t machine_warm_slots(const struct machine *m) { return m->warm_slots; }

static void n_access(void *ctx, uint64_t addr, uint32_t size, unsigned cls) {
  (void)addr;
  (void)size;
  (void)cls;
  ((struct machine *)ctx)->count_slots++;
}

static void n_compute(void *ctx, uint64_t cycles) {
  ((struct machine *)ctx)->count_slots += cycles;
}

static const struct mem_ops count_ops = {n_access, n_access, n_compute, NULL, NULL, NULL};

struct mem_port machine_count_port(struct machine *m) {
  struct mem_port p = {&count_ops, m};
  return p;
}

uint64_t machine_count_slots(const struct machine *m) { return m->count_slots; }

void machine_probe(const struct machine *m, struct machine_probe *out) {
  const struct mctx *c = m->running;
  out->cycle = c ? c->t : engine_now(m->eng);
  out->issue_slots = m->st.issue_slots + (c ? c->slots : 0);
  const struct l2_stats *l = l2_get_stats(m->l2);
  out->dram_bytes = l->fetch_bytes + l->writeback_bytes;
  out->load_latency_sum = m->st.load_latency.sum;
  out->loads_timed = m->st.load_latency.count;
}
