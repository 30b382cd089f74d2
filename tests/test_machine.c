/* The timed machine against closed forms, on synthetic kernels that talk to it
 * through the same door as the renderer: core utilization from compute between
 * misses and the miss latency, a saturated channel, M/D/1 queueing, Little's
 * law, determinism and extremes. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sim/coro.h"
#include "sim/engine.h"
#include "sim/machine.h"
#include "sim/machine_cfg.h"
#include "sim/mem.h"
#include "sim/stats.h"
#include "sim/timeline.h"
#include "testing.h"

static struct machine_params base(void) {
  struct machine_params p;
  memset(&p, 0, sizeof p);
  p.clock_ghz = 1.0;
  p.cores = 1;
  p.threads_per_core = 1;
  p.rays_per_thread = 1;
  p.l2_size_bytes = 1u << 20;
  p.l2_ways = 0;
  p.l2_latency_cycles = 10;
  p.l2_banks = 8;
  p.l2_mshrs = 4096;
  p.l2_write_buffer = 4096;
  p.fidelity = MACHINE_FIDELITY_CHANNEL;
  p.dram_latency_cycles = 200;
  p.dram_bytes_per_cycle = 64; /* one line a cycle */
  p.dram_queue_depth = 4096;
  p.dram_clock_mhz = 1000;
  struct machine_cfg c; /* the banked level's defaults (one DDR4-2400 channel) */
  machine_cfg_defaults(&c);
  p.dram_banked = c.p.dram_banked;
  p.timeline_window_cycles = 1000;
  return p;
}

/* A number the DRAM level reports (dram_report), by name; NAN if absent. */
static double level_stat(const struct machine *m, const char *name) {
  struct stats_table t = {0};
  dram_report(machine_dram(m), &t, machine_get_stats(m)->cycles);
  const double v = testing_stat(&t, name);
  stats_fini(&t);
  return v;
}

/* Kernel: `iters` times, compute(c - 1) then load a line never seen before
 * (c issue slots between misses). */
struct miss_kernel {
  uint64_t iters, c;
};

static void miss_worker(void *arg, const struct machine_worker_info *info, struct mem_port port) {
  const struct miss_kernel *k = arg;
  for (uint64_t i = 0; i < k->iters; i++) {
    if (k->c > 1) mem_compute(&port, k->c - 1);
    mem_load(&port, ((uint64_t)info->id << 32 | i) << 6, 4, 0);
  }
}

/* Closed form: a ray alternates c issue slots with a wait of L cycles; with no
 * switch cost N = T R rays keep the port busy min(1, N c / (c + L)) of the
 * time. L here: l2.latency + one transfer cycle + dram.latency. */
static void test_utilization(void) {
  const uint64_t c = 70;
  const uint32_t cases[][2] = {{1, 1}, {1, 2}, {1, 3}, {2, 2}, {1, 4},
                               {4, 1}, {2, 4}, {4, 4}, {8, 2}};
  for (unsigned i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    struct machine_params p = base();
    p.threads_per_core = cases[i][0];
    p.rays_per_thread = cases[i][1];
    struct miss_kernel k = {2000, c};
    struct machine *m = machine_create(&p, 0);
    machine_run(m, miss_worker, &k, NULL, NULL);
    const struct machine_stats *st = machine_get_stats(m);
    double L = (double)(p.l2_latency_cycles + 1 + p.dram_latency_cycles);
    double n = (double)p.threads_per_core * p.rays_per_thread;
    double model = fmin(1.0, n * (double)c / ((double)c + L));
    double util = (double)st->issue_slots / (double)st->cycles;
    printf("T=%u R=%u: utilization %.4f, model %.4f\n", p.threads_per_core, p.rays_per_thread, util,
           model);
    EXPECTF(fabs(util - model) <= 0.02 * model, "T=%u R=%u: utilization %.4f, model %.4f",
            p.threads_per_core, p.rays_per_thread, util, model);
    EXPECT(st->l2.misses == (uint64_t)n * k.iters);
    EXPECT(st->dram.read_bytes == st->l2.misses * 64);
    machine_destroy(m);
  }
}

/* With a switch cost s, one thread of R rays (R c + R s < c + L) spends
 * c + s per ray per round: utilization R c / (c + L + s) when the latency
 * is not hidden (each ray's period is c + s + L: after its wait it pays one
 * switch to come back). */
static void test_switch_cost(void) {
  struct machine_params p = base();
  p.rays_per_thread = 2;
  p.cost_ray_switch_cycles = 5;
  const uint64_t c = 40;
  struct miss_kernel k = {2000, c};
  struct machine *m = machine_create(&p, 0);
  machine_run(m, miss_worker, &k, NULL, NULL);
  const struct machine_stats *st = machine_get_stats(m);
  double L = (double)(p.l2_latency_cycles + 1 + p.dram_latency_cycles);
  double model = 2.0 * (double)c / ((double)c + L + 5.0);
  double util = (double)st->issue_slots / (double)st->cycles;
  EXPECTF(fabs(util - model) <= 0.02 * model, "utilization %.4f, model %.4f", util, model);
  EXPECT(st->ray_switches >= 2 * k.iters - 2);
  machine_destroy(m);
}

/* Many rays missing all the time: the channel runs at its bandwidth; no
 * window of the timeline carries more than bandwidth x window (each line is
 * spread over the cycles its transfer holds the channel), and the busiest
 * come within a line of it; the FIFO never holds more than its depth, the
 * rest wait at the L2. */
static void test_saturation(void) {
  struct machine_params p = base();
  p.threads_per_core = 8;
  p.rays_per_thread = 8;
  p.dram_bytes_per_cycle = 6.4; /* 10 cycles a line */
  p.dram_queue_depth = 16;      /* and back-pressure */
  p.timeline_window_cycles = 777;
  struct miss_kernel k = {1000, 2};
  struct machine *m = machine_create(&p, 0);
  machine_run(m, miss_worker, &k, NULL, NULL);
  const struct machine_stats *st = machine_get_stats(m);
  double rate = (double)st->dram.read_bytes / (double)st->cycles;
  EXPECTF(fabs(rate - 6.4) <= 0.01 * 6.4, "channel %.4f bytes/cycle, bandwidth 6.4", rate);
  const struct timeline *tl = machine_timeline(m);
  double worst = 0, sum = 0;
  for (uint64_t i = 0; i < tl->rows; i++) {
    const double *r = timeline_row(tl, i);
    double b = r[MACHINE_TL_DRAM_READ_BYTES] + r[MACHINE_TL_DRAM_WRITE_BYTES];
    sum += r[MACHINE_TL_DRAM_READ_BYTES];
    if (b > worst) worst = b;
  }
  EXPECTF(worst <= 6.4 * (double)tl->window + 1e-6 && worst >= 6.4 * (double)tl->window - 64,
          "a window of %llu cycles moved %.6f bytes", (unsigned long long)tl->window, worst);
  EXPECT(fabs(sum - (double)st->dram.read_bytes) < 1e-6 * sum);
  EXPECTF(level_stat(m, "dram_fifo_length_max") <= 16, "FIFO held %.0f",
          level_stat(m, "dram_fifo_length_max"));
  /* The rest waited at the L2 (back-pressure), and held its input. */
  EXPECT(st->l2.miss_queue.wait_sum > 0 && st->l2.stall_cycles[L2_STALL_DRAM] > 0);
  /* Little's law on the FIFO: time-integral of occupancy = sum of waits. */
  double area = level_stat(m, "dram_fifo_length_mean") * (double)st->cycles;
  double waits = level_stat(m, "dram_fifo_wait_mean") * (double)(st->dram.reads + st->dram.writes);
  EXPECTF(fabs(area - waits) <= 0.01 * waits, "area %.1f, waits %.1f", area, waits);
  machine_destroy(m);
}

/* Open arrivals: one ray posts partial stores to fresh lines (each a DRAM read
 * it does not wait for) with geometric gaps, i.e. Bernoulli arrivals, close to
 * Poisson for gaps of hundreds of cycles. Service is deterministic, D cycles:
 * M/D/1 mean wait rho D / (2 (1 - rho)). */
struct poisson_kernel {
  uint64_t n, seed;
  double gap; /* mean cycles between stores */
};

static void poisson_worker(void *arg, const struct machine_worker_info *info,
                           struct mem_port port) {
  const struct poisson_kernel *k = arg;
  (void)info;
  uint64_t s = k->seed;
  for (uint64_t i = 0; i < k->n; i++) {
    s = s * 6364136223846793005ull + 1442695040888963407ull;
    double u = ((double)(s >> 11) + 0.5) / 9007199254740992.0;
    /* Geometric gap >= 1 with the given mean (the store takes one slot). */
    double q = 1.0 / k->gap;
    uint64_t g = (uint64_t)floor(log(u) / log(1.0 - q));
    if (g) mem_compute(&port, g);
    mem_store(&port, i << 6, 4, 1);
  }
}

static void test_md1(void) {
  const double D = 100.0, rhos[] = {0.3, 0.6, 0.9};
  for (unsigned i = 0; i < 3; i++) {
    struct machine_params p = base();
    p.l2_size_bytes = 64u << 20; /* every line stays: no write-backs */
    p.dram_bytes_per_cycle = 64.0 / D;
    struct poisson_kernel k = {400000, 12345 + i, D / rhos[i]};
    struct machine *m = machine_create(&p, 0);
    machine_run(m, poisson_worker, &k, NULL, NULL);
    const struct machine_stats *st = machine_get_stats(m);
    EXPECT(st->dram.writes == 0 && st->dram.reads == k.n);
    double w = level_stat(m, "dram_fifo_wait_mean");
    double model = rhos[i] * D / (2.0 * (1.0 - rhos[i]));
    double area = level_stat(m, "dram_fifo_length_mean") * (double)st->cycles;
    double waits = w * (double)st->dram.reads;
    printf("rho %.1f: mean wait %.2f, M/D/1 %.2f; Little area %.0f waits %.0f\n", rhos[i], w, model,
           area, waits);
    EXPECTF(fabs(w - model) <= 0.05 * model, "rho %.1f: mean wait %.2f, M/D/1 %.2f", rhos[i], w,
            model);
    EXPECTF(fabs(area - waits) <= 0.01 * waits, "Little: area %.1f, waits %.1f", area, waits);
    machine_destroy(m);
  }
}

/* Every number a run reports is finite; the timeline covers the run. */
static void expect_sane(const struct machine *m, const char *what) {
  const struct machine_stats *st = machine_get_stats(m);
  EXPECTF(st->cycles > 0, "%s: no cycles", what);
  const struct timeline *tl = machine_timeline(m);
  uint64_t rows = tl->rows, w = tl->window;
  EXPECTF(rows <= TIMELINE_MAX_ROWS && rows * w >= st->cycles, "%s: %llu rows of %llu", what,
          (unsigned long long)rows, (unsigned long long)w);
  double busy = 0;
  int finite = 1;
  for (uint64_t i = 0; i < rows; i++) {
    const double *r = timeline_row(tl, i);
    for (unsigned c = 0; c < MACHINE_TL_COLS; c++) finite &= isfinite(r[c]) && r[c] >= 0;
    busy += r[MACHINE_TL_BUSY_THREAD_CYCLES];
  }
  EXPECTF(finite, "%s: a timeline value is not finite", what);
  EXPECTF(fabs(busy - (double)st->thread_busy_cycles) <= 1e-6 * busy + 1, "%s: busy %.0f vs %llu",
          what, busy, (unsigned long long)st->thread_busy_cycles);
  double util = (double)st->issue_slots / ((double)st->cycles * (double)tl->rows / (double)rows);
  EXPECTF(isfinite(util) && util >= 0, "%s: utilization", what);
}

static void run_extreme(struct machine_params p, uint64_t iters, uint64_t c, const char *what) {
  struct miss_kernel k = {iters, c};
  struct machine *m = machine_create(&p, 0);
  machine_run(m, miss_worker, &k, NULL, NULL);
  expect_sane(m, what);
  const struct machine_stats *st = machine_get_stats(m);
  EXPECTF(st->l2.misses + st->l2.hits + st->l2.mshr_merges == st->l2.accesses, "%s: L2 counts",
          what);
  EXPECTF(st->loads == (uint64_t)p.cores * p.threads_per_core * p.rays_per_thread * iters,
          "%s: loads", what);
  machine_destroy(m);
}

static void test_extremes(void) {
  struct machine_params p = base();
  run_extreme(p, 100, 5, "1x1x1");
  p.cores = 256;
  p.threads_per_core = 8;
  p.rays_per_thread = 8;
  run_extreme(p, 3, 5, "256x8x8");
  p = base();
  p.dram_latency_cycles = 0;
  run_extreme(p, 1000, 3, "latency 0");
  p.dram_latency_cycles = 1000000;
  run_extreme(p, 5000, 3, "latency 10^6");
  {
    struct miss_kernel k = {5000, 3};
    struct machine *m = machine_create(&p, 0);
    machine_run(m, miss_worker, &k, NULL, NULL);
    EXPECTF(machine_get_stats(m)->cycles > (1ull << 32), "a run past 2^32 cycles: %llu",
            (unsigned long long)machine_get_stats(m)->cycles);
    machine_destroy(m);
  }
  p = base();
  p.threads_per_core = 4;
  p.dram_bytes_per_cycle = 0.01;
  run_extreme(p, 50, 3, "bandwidth 0.01");
  p.dram_bytes_per_cycle = 1e4;
  run_extreme(p, 1000, 3, "bandwidth 10^4");
  p = base();
  p.threads_per_core = 4;
  p.l2_size_bytes = 64; /* one line: every miss waits for the previous fill */
  p.l2_mshrs = 1;
  p.dram_queue_depth = 1;
  run_extreme(p, 200, 3, "L2 of one line");
  p = base();
  p.l1_size_bytes = 64;
  p.l1_ways = 1;
  p.l1_latency_cycles = 1;
  run_extreme(p, 200, 3, "L1 of one line");
}

/* Same inputs, same numbers, whatever else ran before in the process. */
static void test_determinism(void) {
  struct machine_params p = base();
  p.threads_per_core = 4;
  p.rays_per_thread = 3;
  p.cores = 3;
  p.dram_bytes_per_cycle = 3.3;
  p.l2_size_bytes = 8192;
  p.l2_ways = 4;
  p.l2_mshrs = 5;
  p.dram_queue_depth = 4;
  struct machine_stats a, b;
  for (int i = 0; i < 2; i++) {
    struct poisson_kernel k = {3000, 99, 20.0};
    struct machine *m = machine_create(&p, 0);
    machine_run(m, poisson_worker, &k, NULL, NULL);
    memcpy(i ? &b : &a, machine_get_stats(m), sizeof a);
    machine_destroy(m);
  }
  EXPECT(memcmp(&a, &b, sizeof a) == 0);
  EXPECT(a.l2.stalls > 0 && a.dram.writes > 0);
}

/* mem_wait: a ray that waits takes no issue slot and comes back after exactly
 * the cycles it asked for (one ray: the wait is the whole run). */
static void wait_worker(void *arg, const struct machine_worker_info *info, struct mem_port port) {
  (void)arg;
  (void)info;
  mem_compute(&port, 10);
  mem_wait(&port, 1000);
  mem_compute(&port, 10);
}

static void test_wait(void) {
  struct machine_params p = base();
  struct machine *m = machine_create(&p, 0);
  machine_run(m, wait_worker, NULL, NULL, NULL);
  const struct machine_stats *st = machine_get_stats(m);
  EXPECTF(st->cycles == 1020 && st->issue_slots == 20 && st->waits == 1, "cycles %llu slots %llu",
          (unsigned long long)st->cycles, (unsigned long long)st->issue_slots);
  machine_destroy(m);
}

/* Kernel: one ray in four loads one line over and over (hits after the
 * first), 25 x iters times; the others load lines never seen before (misses),
 * iters times. */
static void mixed_worker(void *arg, const struct machine_worker_info *info, struct mem_port port) {
  const struct miss_kernel *k = arg;
  bool hitter = info->id % 4 == 0;
  for (uint64_t i = 0; i < (hitter ? 25 * k->iters : k->iters); i++) {
    mem_compute(&port, k->c);
    mem_load(&port, hitter ? 0 : ((uint64_t)info->id << 32 | (i + 1)) << 6, 4, 0);
  }
}

/* The back-pressure is real: on a saturated channel a shallow FIFO holds
 * misses at the L2, whose in-order input then holds the hits behind them, so
 * the depth changes the run's length. Each queue obeys Little's law, and the
 * stall time splits by reason into exactly the time the input was stalled. */
static void test_queue_depth(void) {
  uint64_t cycles[2] = {0, 0};
  const uint32_t depth[2] = {1, 64};
  for (int i = 0; i < 2; i++) {
    struct machine_params p = base();
    p.threads_per_core = 4;
    p.rays_per_thread = 4;
    p.l2_mshrs = 64;
    p.dram_latency_cycles = 20;
    p.dram_bytes_per_cycle = 3.2; /* 20 cycles a line: 12 missing rays need more */
    p.dram_queue_depth = depth[i];
    struct miss_kernel k = {200, 4};
    struct machine *m = machine_create(&p, 0);
    machine_run(m, mixed_worker, &k, NULL, NULL);
    const struct machine_stats *st = machine_get_stats(m);
    cycles[i] = st->cycles;
    const struct qmeter *q[] = {&st->l2.stall_queue, &st->l2.miss_queue, &st->l2.write_buffer};
    for (unsigned j = 0; j < 3; j++)
      EXPECTF(q[j]->area == q[j]->wait_sum && q[j]->entered == q[j]->left,
              "depth %u queue %u: area %llu, waits %llu", depth[i], j,
              (unsigned long long)q[j]->area, (unsigned long long)q[j]->wait_sum);
    EXPECTF(level_stat(m, "dram_fifo_length_max") <= depth[i], "depth %u: FIFO held %.0f", depth[i],
            level_stat(m, "dram_fifo_length_max"));
    uint64_t by_reason = 0;
    for (unsigned r = 0; r < L2_STALL_COUNT; r++) by_reason += st->l2.stall_cycles[r];
    EXPECTF(by_reason <= st->l2.stall_queue.wait_sum && (by_reason > 0) == (st->l2.stalls > 0),
            "depth %u: stall cycles %llu, stalled waits %llu", depth[i],
            (unsigned long long)by_reason, (unsigned long long)st->l2.stall_queue.wait_sum);
    if (i == 0) EXPECT(st->l2.stall_cycles[L2_STALL_DRAM] > 0 && st->l2.miss_queue.wait_sum > 0);
    machine_destroy(m);
  }
  printf("queue depth 1: %llu cycles, 64: %llu\n", (unsigned long long)cycles[0],
         (unsigned long long)cycles[1]);
  EXPECTF(cycles[0] > cycles[1] + cycles[1] / 50, "depth 1: %llu cycles, 64: %llu",
          (unsigned long long)cycles[0], (unsigned long long)cycles[1]);
}

/* No load is answered sooner than an L2 hit: with memory that answers at
 * once (fixed, latency 0), loads merging into a pending line would otherwise
 * come back a few cycles after they reach the L2. */
static void shared_worker(void *arg, const struct machine_worker_info *info, struct mem_port port) {
  const struct miss_kernel *k = arg;
  mem_compute(&port, 1 + 3 * info->id);
  for (uint64_t i = 0; i < k->iters; i++) {
    mem_load(&port, (i + 1) << 6, 4, 0);
    mem_compute(&port, k->c);
  }
}

static void test_merge_latency(void) {
  struct machine_params p = base();
  p.threads_per_core = 4;
  p.fidelity = MACHINE_FIDELITY_FIXED;
  p.dram_latency_cycles = 0;
  struct miss_kernel k = {500, 2};
  struct machine *m = machine_create(&p, 0);
  machine_run(m, shared_worker, &k, NULL, NULL);
  const struct machine_stats *st = machine_get_stats(m);
  uint64_t early = 0;
  for (unsigned b = 0; b < p.l2_latency_cycles; b++) early += st->load_latency.bucket[b];
  EXPECTF(early == 0, "%llu loads answered in under l2.latency", (unsigned long long)early);
  EXPECTF(st->l2.mshr_merges > 0 && st->l2.merges_held > 0, "merges %llu, held %llu",
          (unsigned long long)st->l2.mshr_merges, (unsigned long long)st->l2.merges_held);
  machine_destroy(m);
}

/* Park and wake (sim/mem.h). Kernel: context 0 misses `iters` times, then
 * wakes every other context; each other parks in its first call and, woken,
 * computes 10 cycles and returns. calls counts each context's calls. */
struct park_kernel {
  uint64_t iters;
  uint32_t contexts;
  uint32_t *calls;
};

static void park_worker(void *arg, const struct machine_worker_info *info, struct mem_port port) {
  struct park_kernel *k = arg;
  const uint32_t call = k->calls[info->id]++;
  if (info->id == 0) {
    for (uint64_t i = 0; i < k->iters; i++) mem_load(&port, (i + 1) << 6, 4, 0);
    mem_compute(&port, 100);
    for (uint32_t i = 1; i < k->contexts; i++) mem_wake(&port, i);
    return;
  }
  if (call == 0) {
    mem_compute(&port, 1);
    CHECK(mem_park(&port));
    return;
  }
  mem_compute(&port, 10);
}

static struct machine_stats park_run(const struct machine_params *p, uint64_t iters,
                                     uint32_t **calls) {
  struct park_kernel k = {iters, p->cores * p->threads_per_core * p->rays_per_thread, NULL};
  k.calls = calloc(k.contexts, sizeof *k.calls);
  struct machine *m = machine_create(p, 0);
  machine_run(m, park_worker, &k, NULL, NULL);
  struct machine_stats st = *machine_get_stats(m);
  machine_destroy(m);
  *calls = k.calls;
  return st;
}

static void test_park(void) {
  /* By hand, one core of two threads, one context each (a miss takes 211
   * cycles: l2.latency 10 + one transfer cycle + dram.latency 200): cycle 0
   * context 0 issues its load; cycle 1 context 1 computes and parks (thread
   * 1 parked from cycle 2); the line is back at 1 + 211 = 212, context 0
   * computes 100 and wakes context 1 at 312, which computes 10: 322 cycles,
   * thread 1 parked 310 of them, context 1 called twice. */
  struct machine_params p = base();
  p.threads_per_core = 2;
  uint32_t *calls;
  struct machine_stats st = park_run(&p, 1, &calls);
  EXPECTF(st.cycles == 322 && st.thread_parked_cycles == 310 && st.issue_slots == 112 &&
              st.parks == 1 && st.wakes == 1 && calls[0] == 1 && calls[1] == 2,
          "cycles %llu, parked %llu, slots %llu, parks %llu, wakes %llu, calls %u %u",
          (unsigned long long)st.cycles, (unsigned long long)st.thread_parked_cycles,
          (unsigned long long)st.issue_slots, (unsigned long long)st.parks,
          (unsigned long long)st.wakes, calls[0], calls[1]);
  free(calls);

  /* Many parked contexts make no events while parked: 16 cores x 4 x 4 = 256
   * contexts, context 0 missing 200 times (over 42,000 cycles) while 255
   * are parked. Each parked context costs two issue events (its first call,
   * its call after the wake) and nothing in between, whatever the run's
   * length; the wakes may leave one stale issue event a core. And a parked
   * context holds no stack: at most context 0's (suspended in a miss) and the
   * running one's are alive at once. */
  struct machine_params one = base(), many = base();
  many.cores = 16;
  many.threads_per_core = 4;
  many.rays_per_thread = 4;
  const uint32_t n = 256;
  struct machine_stats s1 = park_run(&one, 200, &calls);
  free(calls);
  struct machine_stats sn = park_run(&many, 200, &calls);
  uint32_t twice = 0;
  for (uint32_t i = 1; i < n; i++) twice += calls[i] == 2;
  free(calls);
  EXPECTF(sn.events >= s1.events + 2 * (n - 1) && sn.events <= s1.events + 2 * (n - 1) + many.cores,
          "%llu events with 255 parked contexts, %llu alone", (unsigned long long)sn.events,
          (unsigned long long)s1.events);
  EXPECTF(sn.parks == n - 1 && sn.wakes == n - 1 && twice == n - 1,
          "parks %llu wakes %llu, %u called twice", (unsigned long long)sn.parks,
          (unsigned long long)sn.wakes, twice);
  EXPECTF(sn.stacks_max <= 2, "%llu stacks alive at once", (unsigned long long)sn.stacks_max);
  EXPECT(sn.cycles >= s1.cycles && sn.thread_parked_cycles > 0);
}

int main(void) {
  test_queue_depth();
  test_merge_latency();
  test_utilization();
  test_switch_cost();
  test_saturation();
  test_md1();
  test_extremes();
  test_determinism();
  test_wait();
  test_park();
  return testing_done("test_machine");
}
