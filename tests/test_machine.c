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
#include "sim/mem.h"
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
  p.dram_latency_cycles = 200;
  p.dram_bytes_per_cycle = 64; /* one line a cycle */
  p.dram_queue_depth = 4096;
  p.timeline_window_cycles = 1000;
  return p;
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
  const uint32_t cases[][2] = {{1, 1}, {1, 2}, {1, 3}, {2, 2}, {1, 4}, {4, 1}, {2, 4}, {4, 4}, {8, 2}};
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
    printf("T=%u R=%u: utilization %.4f, model %.4f\n", p.threads_per_core, p.rays_per_thread, util, model);
    EXPECTF(fabs(util - model) <= 0.02 * model, "T=%u R=%u: utilization %.4f, model %.4f",
            p.threads_per_core, p.rays_per_thread, util, model);
    EXPECT(st->l2_misses == (uint64_t)n * k.iters);
    EXPECT(st->dram_read_bytes == st->l2_misses * 64);
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

/* Many rays missing all the time: the channel runs at its bandwidth and no
 * window of the timeline carries more than bandwidth x window. */
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
  double rate = (double)st->dram_read_bytes / (double)st->cycles;
  EXPECTF(fabs(rate - 6.4) <= 0.01 * 6.4, "channel %.4f bytes/cycle, bandwidth 6.4", rate);
  uint64_t rows = machine_timeline_rows(m), w = machine_timeline_window(m);
  double worst = 0, sum = 0;
  for (uint64_t i = 0; i < rows; i++) {
    const double *r = machine_timeline_row(m, i);
    double b = r[MACHINE_TL_DRAM_READ_BYTES] + r[MACHINE_TL_DRAM_WRITE_BYTES];
    sum += r[MACHINE_TL_DRAM_READ_BYTES];
    if (b / (double)w > worst) worst = b / (double)w;
  }
  EXPECTF(worst <= 6.4 * (1 + 1e-9), "a window moved %.6f bytes/cycle", worst);
  EXPECT(fabs(sum - (double)st->dram_read_bytes) < 1e-6 * sum);
  EXPECT(st->dram_fifo_max <= 16);
  /* Little's law on the FIFO: time-integral of occupancy = sum of waits. */
  EXPECTF(fabs(st->dram_fifo_area - st->dram_fifo_wait_cycles_sum) <=
              0.01 * st->dram_fifo_wait_cycles_sum,
          "area %.1f, waits %.1f", st->dram_fifo_area, st->dram_fifo_wait_cycles_sum);
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

static void poisson_worker(void *arg, const struct machine_worker_info *info, struct mem_port port) {
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
    EXPECT(st->dram_writes == 0 && st->dram_reads == k.n);
    double w = (double)st->dram_wait_ticks_sum / (double)(1ull << 20) / (double)st->dram_reads;
    double model = rhos[i] * D / (2.0 * (1.0 - rhos[i]));
    printf("rho %.1f: mean wait %.2f, M/D/1 %.2f; Little area %.0f waits %.0f\n", rhos[i], w, model, st->dram_fifo_area, st->dram_fifo_wait_cycles_sum);
    EXPECTF(fabs(w - model) <= 0.05 * model, "rho %.1f: mean wait %.2f, M/D/1 %.2f", rhos[i], w,
            model);
    EXPECTF(fabs(st->dram_fifo_area - st->dram_fifo_wait_cycles_sum) <=
                0.01 * st->dram_fifo_wait_cycles_sum,
            "Little: area %.1f, waits %.1f", st->dram_fifo_area, st->dram_fifo_wait_cycles_sum);
    machine_destroy(m);
  }
}

/* Every number a run reports is finite; the timeline covers the run. */
static void expect_sane(const struct machine *m, const char *what) {
  const struct machine_stats *st = machine_get_stats(m);
  EXPECTF(st->cycles > 0, "%s: no cycles", what);
  uint64_t rows = machine_timeline_rows(m), w = machine_timeline_window(m);
  EXPECTF(rows <= MACHINE_TL_MAX_ROWS && rows * w >= st->cycles, "%s: %llu rows of %llu", what,
          (unsigned long long)rows, (unsigned long long)w);
  double busy = 0;
  int finite = 1;
  for (uint64_t i = 0; i < rows; i++) {
    const double *r = machine_timeline_row(m, i);
    for (unsigned c = 0; c < MACHINE_TL_COLS; c++) finite &= isfinite(r[c]) && r[c] >= 0;
    busy += r[MACHINE_TL_BUSY_THREAD_CYCLES];
  }
  EXPECTF(finite, "%s: a timeline value is not finite", what);
  EXPECTF(fabs(busy - (double)st->thread_busy_cycles) <= 1e-6 * busy + 1, "%s: busy %.0f vs %llu",
          what, busy, (unsigned long long)st->thread_busy_cycles);
  double util = (double)st->issue_slots / ((double)st->cycles * (double)machine_timeline_rows(m) / (double)rows);
  EXPECTF(isfinite(util) && util >= 0, "%s: utilization", what);
}

static void run_extreme(struct machine_params p, uint64_t iters, uint64_t c, const char *what) {
  struct miss_kernel k = {iters, c};
  struct machine *m = machine_create(&p, 0);
  machine_run(m, miss_worker, &k, NULL, NULL);
  expect_sane(m, what);
  const struct machine_stats *st = machine_get_stats(m);
  EXPECTF(st->l2_misses + st->l2_hits + st->l2_mshr_merges == st->l2_accesses, "%s: L2 counts", what);
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
  EXPECT(a.l2_stalls > 0 && a.dram_writes > 0);
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

int main(void) {
  test_utilization();
  test_switch_cost();
  test_saturation();
  test_md1();
  test_extremes();
  test_determinism();
  test_wait();
  return testing_done("test_machine");
}
