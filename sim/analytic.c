/* The counting backend and the estimate. The caches mirror the timed
 * machine's rules (sim/machine.c's door, sim/l2.c's access) with time taken
 * out: a line is installed at once where the timed L2 would mark it pending
 * until its fill, and the L1 is filled at the miss rather than when the line
 * comes back. With one ray context neither difference shows: the ray waits
 * for every line of a load before its next access. */
#include "sim/analytic.h"

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>

#include "sim/cache.h"
#include "sim/err.h"
#include "sim/machine.h"

struct analytic {
  struct cache *l1; /* NULL: no L1 */
  struct cache *l2;
  struct analytic_counts n;
};

enum l2_kind { L2K_LOAD, L2K_STORE, L2K_STORE_LINE };

/* One line at the L2: true if it was fetched from DRAM. */
static bool l2_line(struct analytic *a, uint64_t line, enum l2_kind op, unsigned cls) {
  struct analytic_counts *n = &a->n;
  n->l2_accesses++;
  uint32_t s = cache_find(a->l2, line);
  if (s != CACHE_NONE) {
    cache_touch(a->l2, s);
    if (op != L2K_LOAD) cache_set_dirty(a->l2, s);
    n->l2_hits++;
    return false;
  }
  uint32_t v = cache_victim(a->l2, line);
  CHECK_NE(v, CACHE_NONE); /* nothing is ever pending here */
  if (cache_valid(a->l2, v) && cache_dirty(a->l2, v)) n->writeback_bytes += SIM_LINE_BYTES;
  cache_install(a->l2, v, line, op != L2K_LOAD, false);
  if (op == L2K_STORE_LINE) {
    /* Nothing of the old line survives: allocate without a fetch. */
    n->l2_whole_line_allocs++;
    return false;
  }
  n->l2_misses++;
  n->fetch_bytes += SIM_LINE_BYTES;
  n->fetch_bytes_by_class[cls] += SIM_LINE_BYTES;
  return true;
}

static void a_load(void *ctx, uint64_t addr, uint32_t size, unsigned cls) {
  struct analytic *a = ctx;
  CHECK_GT(size, 0);
  CHECK_LT(cls, MEM_CLASS_MAX);
  struct analytic_counts *n = &a->n;
  n->issue_slots++;
  n->loads++;
  uint64_t line = addr >> SIM_LINE_LG2, end = (addr + size - 1) >> SIM_LINE_LG2;
  bool blocks = false, missed = false;
  for (; line <= end; line++) {
    if (a->l1) {
      n->l1_accesses++;
      uint32_t s = cache_find(a->l1, line);
      if (s != CACHE_NONE) {
        cache_touch(a->l1, s);
        n->l1_hits++;
        continue;
      }
      cache_install(a->l1, cache_victim(a->l1, line), line, false, false);
    }
    blocks = true;
    missed |= l2_line(a, line, L2K_LOAD, cls);
  }
  if (!blocks) {
    n->l1_hit_loads++;
    return;
  }
  n->blocking_loads++;
  n->blocking_l2_misses += missed;
}

static void a_store(void *ctx, uint64_t addr, uint32_t size, unsigned cls) {
  struct analytic *a = ctx;
  CHECK_GT(size, 0);
  CHECK_LT(cls, MEM_CLASS_MAX);
  a->n.issue_slots++;
  a->n.stores++;
  const uint64_t last = addr + size - 1, lmask = SIM_LINE_BYTES - 1;
  uint64_t line = addr >> SIM_LINE_LG2, end = last >> SIM_LINE_LG2;
  const uint64_t first_whole = (addr & lmask) ? line + 1 : line;
  const bool last_whole = (last & lmask) == lmask;
  for (; line <= end; line++) {
    if (a->l1) {
      /* Write-through, no allocation: a line the L1 holds is updated. */
      uint32_t s = cache_find(a->l1, line);
      if (s != CACHE_NONE) cache_touch(a->l1, s);
    }
    bool whole = line >= first_whole && (line < end || last_whole);
    l2_line(a, line, whole ? L2K_STORE_LINE : L2K_STORE, cls);
  }
}

static void a_compute(void *ctx, uint64_t cycles) {
  struct analytic *a = ctx;
  a->n.issue_slots += cycles;
  a->n.computes++;
}

static void a_wait(void *ctx, uint64_t cycles) {
  (void)ctx;
  (void)cycles;
  CHECK(!"a single worker waits for no one");
}

static const struct mem_ops analytic_ops = {a_load, a_store, a_compute, a_wait, NULL, NULL};

struct analytic *analytic_create(const struct machine_params *p) {
  char why[MACHINE_PROBLEM_MAX];
  CHECK(machine_params_problem(p, why, sizeof why) == NULL);
  struct analytic *a = xcalloc(1, sizeof *a);
  if (p->l1_size_bytes) {
    struct cache_params l1 = {p->l1_size_bytes, p->l1_ways, SIM_LINE_LG2, false};
    a->l1 = cache_create(&l1);
  }
  struct cache_params l2 = {p->l2_size_bytes, p->l2_ways, SIM_LINE_LG2, true};
  a->l2 = cache_create(&l2);
  return a;
}

void analytic_destroy(struct analytic *a) {
  if (!a) return;
  cache_destroy(a->l1);
  cache_destroy(a->l2);
  free(a);
}

struct mem_port analytic_port(struct analytic *a) {
  struct mem_port port = {&analytic_ops, a};
  return port;
}

const struct analytic_counts *analytic_get_counts(const struct analytic *a) { return &a->n; }

void analytic_estimate(const struct machine_params *p, const struct analytic_counts *c,
                       struct analytic_estimate *out) {
  const double n = (double)p->threads_per_core * p->rays_per_thread;
  const double b = (double)c->blocking_loads, slots = (double)c->issue_slots;
  out->contexts_per_core = n;
  out->slots_per_blocking = b > 0 ? slots / b : 0;
  out->blocking_miss_rate = b > 0 ? (double)c->blocking_l2_misses / b : 0;
  out->load_latency_cycles = b > 0 ? (double)p->l2_latency_cycles +
                                         out->blocking_miss_rate * (double)p->dram_latency_cycles +
                                         (double)c->l1_hit_loads * p->l1_latency_cycles / b
                                   : 0;
  /* A ray issues c slots, then gives the port up for L: n rays keep it busy
   * n c / (c + L) of the time, at most all of it. With no blocking load
   * there is nothing to hide (the L1 latencies alone are then ignored). */
  const double cc = out->slots_per_blocking, L = out->load_latency_cycles;
  out->core_utilization = b > 0 && slots > 0 ? fmin(1.0, n * cc / (cc + L)) : 1.0;
  out->latency_bound_cycles = slots / ((double)p->cores * out->core_utilization);
  out->bandwidth_bound_cycles =
      (double)(c->fetch_bytes + c->writeback_bytes) / p->dram_bytes_per_cycle;
  out->cycles = (uint64_t)ceil(fmax(out->latency_bound_cycles, out->bandwidth_bound_cycles));
}
