/* The renderer on the timed machine: the 1 x 1 x 1, no-L1, fully associative
 * machine fetches and writes back exactly what the functional model counts, at
 * any DRAM latency and bandwidth; many workers give the same image as one; and
 * rtsim run's outputs (image, determinism, bad input) through the command. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "renderer/framebuffer.h"
#include "renderer/kdtree.h"
#include "renderer/policy.h"
#include "renderer/scene.h"
#include "renderer/shade.h"
#include "renderer/trace.h"
#include "sim/lru_stack.h"
#include "sim/machine.h"
#include "sim/machine_cfg.h"
#include "sim/mem_functional.h"
#include "testing.h"

#define W 48
#define H 32

struct world {
  struct scene s;
  struct kd_tree kd;
};

struct render {
  struct shade_ctx sc;
  struct framebuffer fb;
  struct policy_setup setup;
};

static void render_init(struct render *r, struct world *w, uint32_t mask) {
  memset(r, 0, sizeof *r);
  r->sc.scene = &w->s;
  r->sc.ray_mask = mask;
  r->sc.seed = w->s.seed;
  r->setup.scene = &w->s;
  r->setup.kd = &w->kd;
  trace_layout_default(&r->setup.layout);
  r->setup.sc = &r->sc;
  fb_init(&r->fb, W, H, r->setup.layout.fb_base);
  r->setup.fb = &r->fb;
}

/* Functional fetch and write-back bytes of a fully associative LRU cache of
 * 2^lg2 bytes. */
static void functional(struct world *w, enum policy_kind k, uint32_t mask, unsigned lg2,
                       uint64_t *fetch, uint64_t *wb) {
  struct lru_stack_params lp = lru_stack_params_default();
  struct fn_backend *b = fn_backend_create(&lp, NULL);
  struct render r;
  render_init(&r, w, mask);
  struct policy_params pp;
  policy_params_default(&pp);
  struct render_stats st;
  policy_run(k, &r.setup, &pp, fn_backend_port(b), &st, NULL);
  struct lru_stack_results res;
  lru_stack_get_results(fn_backend_stack(b), &res);
  *fetch = *wb = 0;
  for (unsigned c = 0; c < MEM_CLASS_MAX; c++) {
    *fetch += res.size[lg2 - lp.lg2_min].misses[c] * 64;
    *wb += res.size[lg2 - lp.lg2_min].writebacks[c] * 64;
  }
  fb_fini(&r.fb);
  fn_backend_destroy(b);
}

struct timed_ctx {
  struct policy_job *job;
  struct policy_worker *workers;
};

static void timed_worker(void *arg, const struct machine_worker_info *info, struct mem_port port) {
  struct timed_ctx *t = arg;
  struct policy_worker *w = &t->workers[info->id];
  policy_worker_init(w, t->job, info->id, info->core, info->thread, port);
  policy_job_work(t->job, w);
  policy_worker_fini(t->job, w);
}

/* Run on machine p; the machine's stats are copied out, the framebuffer kept
 * in r (caller finishes it). */
static void timed(struct world *w, enum policy_kind k, uint32_t mask, const struct machine_params *p,
                  struct machine_stats *out, struct render *r) {
  render_init(r, w, mask);
  r->setup.layout.node_cycles = p->cost_node_cycles;
  r->setup.layout.tri_cycles = p->cost_triangle_cycles;
  r->sc.shade_cycles = p->cost_shade_cycles;
  struct policy_params pp;
  policy_params_default(&pp);
  uint32_t n = p->cores * p->threads_per_core * p->rays_per_thread;
  struct timed_ctx t = {policy_job_create(k, &r->setup, &pp, n, p->cores), NULL};
  t.workers = calloc(n, sizeof *t.workers);
  struct machine *m = machine_create(p, 0);
  machine_run(m, timed_worker, &t, NULL, NULL);
  struct render_stats st;
  policy_job_finish(t.job, &st, NULL);
  *out = *machine_get_stats(m);
  machine_destroy(m);
  free(t.workers);
  policy_job_destroy(t.job);
}

static struct machine_params one_by_one(uint64_t l2_bytes) {
  struct machine_cfg c;
  machine_cfg_defaults(&c);
  struct machine_params p = c.p;
  p.cores = p.threads_per_core = p.rays_per_thread = 1;
  p.l1_size_bytes = 0;
  p.l2_size_bytes = l2_bytes;
  p.l2_ways = 0;
  return p;
}

static int same_image(const struct framebuffer *a, const struct framebuffer *b) {
  return memcmp(a->acc, b->acc, (size_t)W * H * 3 * sizeof *a->acc) == 0;
}

static void test_cross_check(struct world *w) {
  const uint32_t mask = RAY_MASK(RAY_PRIMARY) | RAY_MASK(RAY_SHADOW) | RAY_MASK(RAY_DIFFUSE);
  const enum policy_kind kinds[] = {POLICY_RECURSIVE, POLICY_PACKET};
  const unsigned sizes[] = {12, 16};
  const struct {
    uint64_t latency;
    double bw;
    uint32_t mshrs, queue;
  } drams[] = {{0, 1e4, 64, 32}, {200, 16, 64, 32}, {1000, 0.5, 2, 1}};
  for (unsigned k = 0; k < 2; k++)
    for (unsigned s = 0; s < 2; s++) {
      uint64_t fetch, wb;
      functional(w, kinds[k], mask, sizes[s], &fetch, &wb);
      EXPECT(fetch > 0);
      for (unsigned d = 0; d < 3; d++) {
        struct machine_params p = one_by_one(1ull << sizes[s]);
        p.dram_latency_cycles = drams[d].latency;
        p.dram_bytes_per_cycle = drams[d].bw;
        p.l2_mshrs = drams[d].mshrs;
        p.dram_queue_depth = drams[d].queue;
        struct machine_stats st;
        struct render r;
        timed(w, kinds[k], mask, &p, &st, &r);
        EXPECTF(st.l2_fetch_bytes == fetch && st.l2_writeback_bytes == wb,
                "%s at 2^%u, DRAM %llu cycles %.1f B/c: timed %llu/%llu, functional %llu/%llu",
                policy_name(kinds[k]), sizes[s], (unsigned long long)drams[d].latency, drams[d].bw,
                (unsigned long long)st.l2_fetch_bytes, (unsigned long long)st.l2_writeback_bytes,
                (unsigned long long)fetch, (unsigned long long)wb);
        fb_fini(&r.fb);
      }
    }
}

/* Many ray contexts interleaved on the tiny machine: the same picture, every
 * ray accounted for, and the machine busy. */
static void test_many_workers(struct world *w) {
  const uint32_t mask = RAY_MASK(RAY_PRIMARY) | RAY_MASK(RAY_SHADOW) | RAY_MASK(RAY_SPECULAR) |
                        RAY_MASK(RAY_DIFFUSE);
  struct machine_cfg c;
  machine_cfg_defaults(&c);
  struct err e;
  memset(&e, 0, sizeof e);
  CHECK(machine_cfg_load(&c, RTSIM_SOURCE_DIR "/configs/tiny.yaml", &e));
  struct render ref;
  struct machine_stats st;
  struct machine_params one = one_by_one(1 << 20);
  timed(w, POLICY_RECURSIVE, mask, &one, &st, &ref);
  for (int k = 0; k < 2; k++) {
    struct render r;
    timed(w, k ? POLICY_PACKET : POLICY_RECURSIVE, mask, &c.p, &st, &r);
    EXPECTF(same_image(&ref.fb, &r.fb), "%s on tiny.yaml: image differs", k ? "packet" : "recursive");
    EXPECT(st.l2_mshr_merges > 0 && st.l2_misses > 0 && st.issue_slots > 0);
    fb_fini(&r.fb);
  }
  fb_fini(&ref.fb);
}

int main(void) {
  struct world w;
  if (!testing_load_world(&w.s, &w.kd, RTSIM_SOURCE_DIR "/scenes/small/room.yaml")) return 1;
  test_cross_check(&w);
  test_many_workers(&w);
  kd_fini(&w.kd);
  scene_fini(&w.s);
  return testing_done("test_run");
}
