/* The renderer on the timed machine: the 1 x 1 x 1, no-L1, fully associative
 * machine fetches and writes back exactly what the functional model counts, at
 * any DRAM latency and bandwidth, for every policy (dynamic's and treelet's
 * schedules made for that machine on both sides); many workers give the same image as one, and
 * the dynamic policy's queues are each stored before they are read, read once
 * and left empty; its queue points ask no more of the L2 than its rule allows;
 * and rtsim run's outputs (image, determinism, bad input) through the command. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <sys/stat.h>
#include <unistd.h>

#include "renderer/bvh.h"
#include "renderer/framebuffer.h"
#include "renderer/image.h"
#include "renderer/kdtree.h"
#include "renderer/policy/policy.h"
#include "renderer/policy/qpoint.h"
#include "renderer/scene.h"
#include "renderer/shade.h"
#include "renderer/trace.h"
#include "sim/coro.h"
#include "sim/dram.h"
#include "sim/err.h"
#include "sim/lru_stack.h"
#include "sim/machine.h"
#include "sim/machine_cfg.h"
#include "sim/mem_functional.h"
#include "testing.h"

#define W 32
#define H 24

struct world {
  struct scene s;
  struct kd_tree kd;
  const struct bvh *bvh; /* traced instead of kd when set */
};

/* scenes/small/NAME.yaml and its tree; false (a failed check) if it does not load. */
static bool load_small(struct world *w, const char *name) {
  w->bvh = NULL;
  return testing_load_small(&w->s, &w->kd, name);
}

static void world_fini(struct world *w) {
  kd_fini(&w->kd);
  scene_fini(&w->s);
}

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
  r->setup.bvh = w->bvh;
  trace_layout_default(&r->setup.layout);
  r->setup.sc = &r->sc;
  fb_init(&r->fb, W, H, r->setup.layout.fb_base);
  r->setup.fb = &r->fb;
}

/* Functional fetch and write-back bytes of a fully associative LRU cache of
 * 2^lg2 bytes; the dynamic policy's schedule is the one it makes for a
 * 1 x 1 x 1 machine with that L2. */
static void functional(struct world *w, enum policy_kind k, uint32_t mask, unsigned lg2,
                       uint64_t *fetch, uint64_t *wb) {
  struct lru_stack_params lp = lru_stack_params_default();
  struct mem_functional *b = mem_functional_create(&lp, NULL, false);
  struct render r;
  render_init(&r, w, mask);
  struct policy_params pp;
  policy_params_machine(&pp, 1ull << lg2);
  struct render_stats st;
  policy_run(k, &r.setup, &pp, mem_functional_port(b), &st, NULL);
  struct lru_stack_results res;
  lru_stack_get_results(mem_functional_stack(b), &res);
  *fetch = *wb = 0;
  for (unsigned c = 0; c < MEM_CLASS_MAX; c++) {
    *fetch += res.size[lg2 - lp.lg2_min].misses[c] * 64;
    *wb += res.size[lg2 - lp.lg2_min].writebacks[c] * 64;
  }
  fb_fini(&r.fb);
  mem_functional_destroy(b);
}

/* The deepest coroutine stack any run of this test used (painted stacks). */
static uint64_t stack_used_max;

/* The dynamic policy's queue discipline, seen from the accesses the workers
 * issue (in issue order, across all workers): a queue slot is stored before it
 * is loaded, loaded once per store (a blocked leaf pass stores its rays back
 * and loads them again), never overwritten while it holds a ray, and none is
 * left holding one; table entries are those of queue points. */
struct qcheck {
  struct trace_layout l;
  struct testing_slots slots;
  uint64_t bad, table_accesses, table_max;
};

static void qcheck_access(struct qcheck *q, uint64_t addr, unsigned cls, int store) {
  if (addr >= q->l.qtable_base && addr < q->l.queue_base) {
    uint64_t e = (addr - q->l.qtable_base) / 8 + 1;
    if (e > q->table_max) q->table_max = e;
    q->table_accesses++;
    q->bad += cls != TRACE_CLASS_QUEUE;
    return;
  }
  if (addr < q->l.queue_base || addr >= q->l.ray_base) return;
  q->bad += cls != TRACE_CLASS_RAY;
  testing_slots_access(&q->slots, (addr - q->l.queue_base) / 64, store);
}

/* A worker's port: records queue accesses, then passes everything on. */
struct wport {
  struct mem_port in;
  struct qcheck *q;
};

static void w_load(void *ctx, uint64_t addr, uint32_t size, unsigned cls) {
  struct wport *p = ctx;
  qcheck_access(p->q, addr, cls, 0);
  mem_load(&p->in, addr, size, cls);
}
static void w_store(void *ctx, uint64_t addr, uint32_t size, unsigned cls) {
  struct wport *p = ctx;
  qcheck_access(p->q, addr, cls, 1);
  mem_store(&p->in, addr, size, cls);
}
static void w_compute(void *ctx, uint64_t cycles) {
  mem_compute(&((struct wport *)ctx)->in, cycles);
}
static void w_wait(void *ctx, uint64_t cycles) { mem_wait(&((struct wport *)ctx)->in, cycles); }
static void w_park(void *ctx) { CHECK(mem_park(&((struct wport *)ctx)->in)); }
static void w_wake(void *ctx, uint32_t id) { mem_wake(&((struct wport *)ctx)->in, id); }
static const struct mem_ops WPORT_OPS = {w_load, w_store, w_compute, w_wait, w_park, w_wake};

struct timed_ctx {
  struct policy_job *job;
  struct policy_worker *workers;
  struct wport *ports; /* NULL: the machine's ports as they are */
};

static void timed_worker(void *arg, const struct machine_worker_info *info, struct mem_port port) {
  struct timed_ctx *t = arg;
  struct policy_worker *w = &t->workers[info->id];
  if (t->ports) {
    t->ports[info->id].in = port;
    port = (struct mem_port){&WPORT_OPS, &t->ports[info->id]};
  }
  if (!w->parked) policy_worker_init(w, t->job, info->id, info->core, info->thread, port);
  if (policy_job_work(t->job, w)) return; /* parked: called again when woken */
  policy_worker_fini(t->job, w);
}

/* Run on machine p with the policy parameters rtsim run gives it; the
 * machine's stats and the render's are copied out (rs may be NULL), the
 * framebuffer kept in r (caller finishes it). With q, every worker's queue
 * accesses are checked. */
/* A machine and what its config says about the work (costs, sharing). */
struct tcfg {
  struct machine_params p;
  struct machine_cfg_work work;
};

static void timed_q(struct world *w, enum policy_kind k, uint32_t mask, const struct tcfg *c,
                    struct machine_stats *out, struct render *r, struct render_stats *rs,
                    struct qcheck *q) {
  const struct machine_params *p = &c->p;
  render_init(r, w, mask);
  r->setup.layout.node_cycles = c->work.cost_node_cycles;
  r->setup.layout.tri_cycles = c->work.cost_triangle_cycles;
  r->sc.shade_cycles = c->work.cost_shade_cycles;
  struct policy_params pp;
  policy_params_machine(&pp, p->l2_size_bytes);
  pp.dyn_sharing = c->work.dyn_sharing;
  uint32_t n = p->cores * p->threads_per_core * p->rays_per_thread;
  struct timed_ctx t = {policy_job_create(k, &r->setup, &pp, n, p->cores), NULL, NULL};
  t.workers = calloc(n, sizeof *t.workers);
  if (q) {
    memset(q, 0, sizeof *q);
    q->l = r->setup.layout;
    t.ports = calloc(n, sizeof *t.ports);
    for (uint32_t i = 0; i < n; i++) t.ports[i].q = q;
  }
  struct machine *m = machine_create_painted(p, 0);
  machine_run(m, timed_worker, &t, NULL, NULL);
  if (machine_stack_used_max(m) > stack_used_max) stack_used_max = machine_stack_used_max(m);
  struct render_stats st;
  policy_job_finish(t.job, &st, NULL);
  if (rs) *rs = st;
  *out = *machine_get_stats(m);
  machine_destroy(m);
  free(t.workers);
  free(t.ports);
  policy_job_destroy(t.job);
}

static void timed(struct world *w, enum policy_kind k, uint32_t mask, const struct tcfg *c,
                  struct machine_stats *out, struct render *r) {
  timed_q(w, k, mask, c, out, r, NULL, NULL);
}

/* configs/NAME.yaml, resolved (it must load). */
static struct tcfg shipped_config(const char *name) {
  char path[1024];
  snprintf(path, sizeof path, "%s/configs/%s.yaml", RTSIM_SOURCE_DIR, name);
  struct machine_cfg c;
  machine_cfg_defaults(&c);
  struct err e;
  memset(&e, 0, sizeof e);
  CHECK(machine_cfg_load(&c, path, &e));
  return (struct tcfg){c.p, c.work};
}

static struct tcfg one_by_one(uint64_t l2_bytes) {
  struct machine_cfg c;
  machine_cfg_defaults(&c);
  struct tcfg t = {c.p, c.work};
  struct machine_params *p = &t.p;
  p->cores = p->threads_per_core = p->rays_per_thread = 1;
  p->l1_size_bytes = 0;
  p->l2_size_bytes = l2_bytes;
  p->l2_ways = 0;
  return t;
}

static int same_image(const struct framebuffer *a, const struct framebuffer *b) {
  return memcmp(a->acc, b->acc, (size_t)W * H * 3 * sizeof *a->acc) == 0;
}

/* Policies kinds[first..last) of the four below. */
static void test_cross_check(struct world *w, unsigned first, unsigned last) {
  const uint32_t mask = RAY_MASK(RAY_PRIMARY) | RAY_MASK(RAY_SHADOW) | RAY_MASK(RAY_DIFFUSE);
  const enum policy_kind kinds[] = {POLICY_RECURSIVE, POLICY_PACKET, POLICY_DYNAMIC,
                                    POLICY_TREELET};
  const unsigned sizes[] = {12, 16};
  /* Every DRAM level: ideal memory (fixed, latency 0), channels from fast to
   * starved, and banked DDR4 (open page, one channel; close page, two). */
  const struct {
    enum machine_fidelity model;
    uint64_t latency;
    double bw;
    uint32_t mshrs, queue, write_buffer;
    enum dram_banked_page page;
    uint32_t channels;
  } drams[] = {{MACHINE_FIDELITY_FIXED, 0, 1, 64, 1, 16, 0, 1},
               {MACHINE_FIDELITY_CHANNEL, 0, 1e4, 64, 32, 16, 0, 1},
               {MACHINE_FIDELITY_CHANNEL, 200, 16, 64, 32, 16, 0, 1},
               {MACHINE_FIDELITY_CHANNEL, 1000, 0.5, 2, 1, 1, 0, 1},
               {MACHINE_FIDELITY_BANKED, 0, 1, 64, 1, 16, DRAM_BANKED_OPEN_PAGE, 1},
               {MACHINE_FIDELITY_BANKED, 0, 1, 4, 1, 2, DRAM_BANKED_CLOSE_PAGE, 2}};
  const unsigned ndrams = sizeof drams / sizeof drams[0];
  CHECK_LE(last, sizeof kinds / sizeof kinds[0]);
  for (unsigned k = first; k < last; k++)
    for (unsigned s = 0; s < 2; s++) {
      uint64_t fetch, wb;
      functional(w, kinds[k], mask, sizes[s], &fetch, &wb);
      EXPECT(fetch > 0);
      for (unsigned d = 0; d < ndrams; d++) {
        struct tcfg c = one_by_one(1ull << sizes[s]);
        struct machine_params *p = &c.p;
        p->fidelity = drams[d].model;
        p->dram_latency_cycles = drams[d].latency;
        p->dram_bytes_per_cycle = drams[d].bw;
        p->l2_mshrs = drams[d].mshrs;
        p->dram_queue_depth = drams[d].queue;
        p->l2_write_buffer = drams[d].write_buffer;
        p->dram_banked.page = drams[d].page;
        p->dram_banked.channels = drams[d].channels;
        struct machine_stats st;
        struct render r;
        timed(w, kinds[k], mask, &c, &st, &r);
        /* A miss that takes its line back from the write buffer (the DRAM
         * slow to drain it) saves the fetch the functional model makes, and
         * the write-back too unless the line, dirty again, is evicted again
         * before the end. With ideal memory nothing waits to be taken back. */
        const uint64_t back = st.l2.write_buffer_hits * 64;
        EXPECTF(drams[d].latency > 0 || drams[d].model != MACHINE_FIDELITY_FIXED || back == 0,
                "ideal memory, yet %llu lines taken back from the write buffer",
                (unsigned long long)st.l2.write_buffer_hits);
        EXPECTF(st.l2.fetch_bytes + back == fetch && st.l2.writeback_bytes <= wb &&
                    wb <= st.l2.writeback_bytes + back,
                "%s at 2^%u, DRAM %s %llu cycles %.1f B/c: timed %llu/%llu, functional %llu/%llu",
                policy_name(kinds[k]), sizes[s],
                dram_model_names[machine_fidelity_dram(drams[d].model)],
                (unsigned long long)drams[d].latency, drams[d].bw,
                (unsigned long long)st.l2.fetch_bytes, (unsigned long long)st.l2.writeback_bytes,
                (unsigned long long)fetch, (unsigned long long)wb);
        fb_fini(&r.fb);
      }
    }
}

/* Many ray contexts interleaved on the tiny machine: the same picture, every
 * ray accounted for, and the machine busy. The dynamic policy besides on
 * variants that make its cores share small queue points (a 4 KiB L2: leaves
 * over g_max, processed block by block by all of a core's contexts), many
 * contexts on three cores, and one context; its queues checked throughout.
 * With all false (the other scenes): dynamic on tiny.yaml and 1 x 1 x 1 only. */
static void test_many_workers(struct world *w, const char *scene, bool all) {
  const uint32_t mask =
      RAY_MASK(RAY_PRIMARY) | RAY_MASK(RAY_SHADOW) | RAY_MASK(RAY_SPECULAR) | RAY_MASK(RAY_DIFFUSE);
  const struct tcfg tiny = shipped_config("tiny");
  struct render ref;
  struct machine_stats st;
  struct render_stats ref_rs;
  struct tcfg one = one_by_one(1 << 20);
  timed_q(w, POLICY_RECURSIVE, mask, &one, &st, &ref, &ref_rs, NULL);
  for (int k = 0; all && k < 2; k++) {
    struct render r;
    timed(w, k ? POLICY_PACKET : POLICY_RECURSIVE, mask, &tiny, &st, &r);
    EXPECTF(same_image(&ref.fb, &r.fb), "%s on tiny.yaml: image differs",
            k ? "packet" : "recursive");
    EXPECT(st.l2.mshr_merges > 0 && st.l2.misses > 0 && st.issue_slots > 0);
    fb_fini(&r.fb);
  }
  /* Every scene, every policy, on the banked DRAM: the same picture, and the
   * DRAM bytes conserved. */
  struct tcfg banked = tiny;
  banked.p.fidelity = MACHINE_FIDELITY_BANKED;
  const enum policy_kind all_kinds[] = {POLICY_RECURSIVE, POLICY_PACKET, POLICY_DYNAMIC,
                                        POLICY_TREELET};
  for (unsigned k = 0; k < 4; k++) {
    struct render r;
    timed(w, all_kinds[k], mask, &banked, &st, &r);
    EXPECTF(same_image(&ref.fb, &r.fb), "%s, %s on tiny.yaml with banked DRAM: image differs",
            scene, policy_name(all_kinds[k]));
    EXPECT(st.dram.reads > 0 && st.l2.fetch_bytes == st.dram.read_bytes);
    fb_fini(&r.fb);
  }

  struct tcfg small_l2 = tiny, many = tiny;
  small_l2.p.l2_size_bytes = 4096;
  many.p.cores = 3;
  many.p.threads_per_core = 3;
  many.p.rays_per_thread = 3;
  many.p.l2_size_bytes = 16384;
  /* Chip-wide sharing (dynamic.sharing: chip): the cores on one queue point,
   * and with a 4 KiB L2 on the blocks of oversized leaves together. */
  struct tcfg chip = tiny, chip_small = many;
  chip.work.dyn_sharing = chip_small.work.dyn_sharing = POLICY_DYN_CHIP;
  chip_small.p.l2_size_bytes = 4096;
  const struct {
    const char *name;
    const struct tcfg *c;
  } dyn[] = {{"tiny.yaml", &tiny},
             {"tiny.yaml, 4 KiB L2", &small_l2},
             {"tiny.yaml, 3 x 3 x 3, 16 KiB L2", &many},
             {"1 x 1 x 1", &one},
             {"tiny.yaml, chip", &chip},
             {"tiny.yaml, 3 x 3 x 3, 4 KiB L2, chip", &chip_small}};
  for (unsigned i = 0; i < sizeof dyn / sizeof dyn[0]; i++) {
    const struct tcfg *c = dyn[i].c;
    const struct machine_params *p = &c->p;
    if (!all && c != &tiny && c != &one && c != &chip) continue;
    const uint32_t workers = p->cores * p->threads_per_core * p->rays_per_thread;
    /* The plan it runs with: with a 4 KiB L2, some leaves exceed g_max. */
    struct policy_params pp;
    policy_params_machine(&pp, p->l2_size_bytes);
    pp.dyn_sharing = c->work.dyn_sharing;
    struct qpoint_set qs;
    struct qpoint_budget b;
    uint32_t bt, group;
    policy_dynamic_plan(&pp, workers, p->cores, &w->kd, w->bvh, 128, &qs, &b, &bt, &group);
    uint32_t oversized = 0;
    for (uint32_t q = 0; q < qs.count; q++) {
      uint32_t first, cnt;
      oversized += qpoint_leaf(&qs, qs.qnode[q], &first, &cnt) && cnt > bt;
    }
    if ((c == &small_l2 || c == &chip_small) && !w->bvh)
      EXPECTF(oversized > 0, "%s: no leaf over g_max (%u queue points)", dyn[i].name, qs.count);
    EXPECT(group == 1);
    const uint32_t queues = qs.count;
    qpoint_fini(&qs);

    struct render r;
    struct render_stats rs;
    struct qcheck q;
    timed_q(w, POLICY_DYNAMIC, mask, c, &st, &r, &rs, &q);
    EXPECTF(same_image(&ref.fb, &r.fb), "%s, dynamic on %s: image differs from recursive's", scene,
            dyn[i].name);
    EXPECTF(memcmp(rs.rays, ref_rs.rays, sizeof rs.rays) == 0 && rs.spawned == ref_rs.spawned &&
                rs.terminated == rs.spawned,
            "dynamic on %s: rays %llu/%llu/%llu/%llu, spawned %llu, terminated %llu; recursive "
            "%llu/%llu/%llu/%llu, %llu",
            dyn[i].name, (unsigned long long)rs.rays[0], (unsigned long long)rs.rays[1],
            (unsigned long long)rs.rays[2], (unsigned long long)rs.rays[3],
            (unsigned long long)rs.spawned, (unsigned long long)rs.terminated,
            (unsigned long long)ref_rs.rays[0], (unsigned long long)ref_rs.rays[1],
            (unsigned long long)ref_rs.rays[2], (unsigned long long)ref_rs.rays[3],
            (unsigned long long)ref_rs.spawned);
    const struct testing_slots *sl = &q.slots;
    uint64_t left = testing_slots_left(sl);
    EXPECTF(q.bad == 0 && sl->bad == 0 && left == 0 && sl->stores == sl->loads && sl->stores > 0 &&
                q.table_accesses > 0,
            "dynamic on %s: queue slots %llu stored, %llu loaded, %llu out of order, %llu left",
            dyn[i].name, (unsigned long long)sl->stores, (unsigned long long)sl->loads,
            (unsigned long long)(sl->bad + q.bad), (unsigned long long)left);
    EXPECTF(q.table_max <= queues, "dynamic on %s: table entry %llu of %u queue points",
            dyn[i].name, (unsigned long long)q.table_max, queues);
    /* Several contexts share the work: some park until there is some for
     * them, and every one parked is woken; one never parks. Nobody polls. */
    EXPECTF(st.waits == 0 && (workers == 1 ? st.parks == 0 : st.parks > 0) && st.wakes == st.parks,
            "dynamic on %s: %llu waits, %llu parks, %llu wakes", dyn[i].name,
            (unsigned long long)st.waits, (unsigned long long)st.parks,
            (unsigned long long)st.wakes);
    printf("%s, dynamic on %s: %llu cycles, core utilization %.3f, %llu parks, %llu events\n",
           scene, dyn[i].name, (unsigned long long)st.cycles,
           (double)st.issue_slots / ((double)p->cores * (double)st.cycles),
           (unsigned long long)st.parks, (unsigned long long)st.events);
    testing_slots_fini(&q.slots);
    fb_fini(&r.fb);

    /* Treelet queues on the same machine: the same picture and rays, the
     * same queue discipline, every parked context woken (on the small L2,
     * with its oversized leaves, and the many-context machine). */
    if (c != &small_l2 && c != &many && c != &chip_small) continue;
    struct qcheck tq;
    timed_q(w, POLICY_TREELET, mask, c, &st, &r, &rs, &tq);
    EXPECTF(same_image(&ref.fb, &r.fb), "%s, treelet on %s: image differs from recursive's", scene,
            dyn[i].name);
    EXPECTF(memcmp(rs.rays, ref_rs.rays, sizeof rs.rays) == 0 && rs.terminated == rs.spawned,
            "treelet on %s: rays differ from recursive's", dyn[i].name);
    EXPECTF(tq.bad == 0 && tq.slots.bad == 0 && testing_slots_left(&tq.slots) == 0 &&
                tq.slots.stores == tq.slots.loads && st.wakes == st.parks,
            "treelet on %s: queue slots %llu stored, %llu loaded, %llu out of order", dyn[i].name,
            (unsigned long long)tq.slots.stores, (unsigned long long)tq.slots.loads,
            (unsigned long long)(tq.slots.bad + tq.bad));
    testing_slots_fini(&tq.slots);
    fb_fini(&r.fb);
  }
  fb_fini(&ref.fb);
}

/* Queue points made for a machine ask no more of the L2 than the rule of
 * policy.h: g_max = (L2 - nodes - table - ray buffer) / cores, the ray buffer
 * one 64-byte ray per ray context (within its 1/16 share), so that every
 * core's queue point can be resident at once; each queue point's subtree
 * geometry fits g_max, or it is a leaf, whose blocks do. */
static void test_machine_plan(void) {
  const char *cfgs[] = {"tiny", "default", "paper-2007"};
  const char *scenes[] = {"room", "grove", "sphereflake"};
  const uint64_t l2s[] = {0, 4096, 65536};
  for (unsigned si = 0; si < 3; si++) {
    struct world w;
    if (!load_small(&w, scenes[si])) continue;
    uint32_t *tris = malloc(((size_t)w.kd.node_count + 1) * sizeof *tris);
    qpoint_subtree_tris(&w.kd, tris);
    for (unsigned ci = 0; ci < 3; ci++)
      for (unsigned li = 0; li < 3; li++) {
        const struct tcfg cc = shipped_config(cfgs[ci]);
        const struct machine_params *p = &cc.p;
        const uint64_t S = l2s[li] ? l2s[li] : p->l2_size_bytes;
        const uint32_t C = p->cores, workers = C * p->threads_per_core * p->rays_per_thread;
        struct policy_params pp;
        policy_params_machine(&pp, S);
        struct qpoint_set qs;
        struct qpoint_budget b;
        uint32_t bt, group;
        policy_dynamic_plan(&pp, workers, C, &w.kd, NULL, 128, &qs, &b, &bt, &group);
        /* The budget, by hand. */
        uint64_t nodes = 8ull * w.kd.node_count < S / 4 ? 8ull * w.kd.node_count : S / 4;
        uint64_t rays = 64ull * workers < S / 16 ? 64ull * workers : S / 16;
        uint64_t table = 8ull * qs.count < S / 16 ? 8ull * qs.count : S / 16;
        uint64_t used = nodes + rays + b.table_bytes;
        EXPECTF(b.node_bytes == nodes && b.ray_bytes == rays && b.table_bytes <= S / 16 &&
                    b.table_bytes >= table && b.gmax_bytes == (S > used ? (S - used) / C : 0),
                "%s, %s, L2 %llu: budget %llu/%llu/%llu/%llu", scenes[si], cfgs[ci],
                (unsigned long long)S, (unsigned long long)b.node_bytes,
                (unsigned long long)b.table_bytes, (unsigned long long)b.ray_bytes,
                (unsigned long long)b.gmax_bytes);
        /* Every core's queue point resident at once, besides the reservations. */
        EXPECT(C * b.gmax_bytes + b.node_bytes + b.table_bytes + b.ray_bytes <= S);
        /* Chip-wide sharing: one queue point's geometry for the whole chip. */
        {
          struct policy_params pc = pp;
          pc.dyn_sharing = POLICY_DYN_CHIP;
          struct qpoint_set qc;
          struct qpoint_budget bc;
          uint32_t btc, gc;
          policy_dynamic_plan(&pc, workers, C, &w.kd, NULL, 128, &qc, &bc, &btc, &gc);
          const uint64_t usedc = bc.node_bytes + bc.table_bytes + bc.ray_bytes;
          EXPECTF(bc.node_bytes == nodes && bc.ray_bytes == rays &&
                      bc.gmax_bytes == (S > usedc ? S - usedc : 0) && qc.count <= qs.count,
                  "%s, %s, L2 %llu, chip: g_max %llu, %u queue points (partition %u)", scenes[si],
                  cfgs[ci], (unsigned long long)S, (unsigned long long)bc.gmax_bytes, qc.count,
                  qs.count);
          qpoint_fini(&qc);
        }
        EXPECT(bt == (b.gmax_bytes / 128 ? b.gmax_bytes / 128 : 1) && group == 1);
        uint32_t over = 0;
        for (uint32_t q = 0; q < qs.count; q++) {
          uint32_t n = qs.qnode[q];
          bool leaf = kd_is_leaf(qs.nodes[n]);
          if ((uint64_t)tris[n] * 128 <= b.gmax_bytes) continue;
          over++;
          EXPECTF(leaf, "%s, %s, L2 %llu: queue point %u holds %u triangles, g_max %llu",
                  scenes[si], cfgs[ci], (unsigned long long)S, n, tris[n],
                  (unsigned long long)b.gmax_bytes);
          EXPECT((uint64_t)bt * 128 <= b.gmax_bytes || bt == 1);
        }
        if (li == 0)
          printf("%s on %s: %u cores, g_max %llu bytes, %u queue points, %u leaves over g_max\n",
                 scenes[si], cfgs[ci], C, (unsigned long long)b.gmax_bytes, qs.count, over);
        qpoint_fini(&qs);
      }
    free(tris);
    world_fini(&w);
  }
}

static int same_file(const char *a, const char *b, int skip_wall) {
  FILE *fa = fopen(a, "rb"), *fb = fopen(b, "rb");
  int same = fa && fb;
  char la[4096], lb[4096];
  while (same) {
    char *ra = fgets(la, sizeof la, fa), *rb = fgets(lb, sizeof lb, fb);
    if (!ra || !rb) {
      same = !ra && !rb;
      break;
    }
    if (skip_wall && ((strstr(la, "\"wall_s\"") && strstr(lb, "\"wall_s\"")) ||
                      (strstr(la, "\"peak_rss_mb\"") && strstr(lb, "\"peak_rss_mb\""))))
      continue;
    same = !strcmp(la, lb);
  }
  if (fa) fclose(fa);
  if (fb) fclose(fb);
  return same;
}

static int exists(const char *dir, const char *name) {
  char p[2048];
  snprintf(p, sizeof p, "%s/%s", dir, name);
  struct stat sb;
  return stat(p, &sb) == 0;
}

/* rtsim run through the command line: the image of rtsim render, the same
 * bytes twice, every output present; bad input refused with exit 2. */
/* The stdout summary of a run (#40): the policy, the machine, and each
 * number with its unit; DRAM bytes as stats.json has them. */
static void check_summary(const char *out, const char *dir) {
  EXPECTF(strstr(out, "\npolicy: packet\nmachine: "), "the summary's first lines: %s", out);
  EXPECTF(strstr(out, "\nmachine: 3 x 2 x 2 (cores x threads_per_core x rays_per_thread), L2 8 "
                      "KiB, fidelity channel, 1 GHz\n"),
          "the machine line: %s", out);
  char want[256];
  snprintf(want, sizeof want, "\ndram_bytes: %.0f bytes (read %.0f, written %.0f)\n",
           testing_json_num(dir, "dram_bytes"), testing_json_num(dir, "dram_read_bytes"),
           testing_json_num(dir, "dram_write_bytes"));
  EXPECTF(strstr(out, want), "want '%s' in %s", want + 1, out);
  snprintf(want, sizeof want, "\ncycles: %.0f core cycles\n", testing_json_num(dir, "cycles"));
  EXPECTF(strstr(out, want), "want '%s' in %s", want + 1, out);
  EXPECTF(strstr(out, " rays per simulated second\n"), "rays_per_second's unit: %s", out);
  /* The energy line: stats.json's three figures; the chip's parts add to its total. */
  snprintf(want, sizeof want,
           "\nenergy_mj_per_frame: %.6g mJ a frame (power_w %.6g W, rays_per_joule %.6g)\n",
           testing_json_num(dir, "energy_mj_per_frame"), testing_json_num(dir, "power_w"),
           testing_json_num(dir, "rays_per_joule"));
  EXPECTF(strstr(out, want), "want '%s' in %s", want + 1, out);
  static const char *const parts[] = {"chip_energy_l1_dynamic_j",    "chip_energy_l2_dynamic_j",
                                      "chip_energy_cores_dynamic_j", "chip_energy_l1_leakage_j",
                                      "chip_energy_l2_leakage_j",    "chip_energy_cores_leakage_j"};
  double sum = 0;
  for (unsigned i = 0; i < 6; i++) sum += testing_json_num(dir, parts[i]);
  const double chip = testing_json_num(dir, "chip_energy_j");
  EXPECTF(chip > 0 && fabs(sum - chip) <= 1e-12 * chip, "parts %.17g, chip_energy_j %.17g", sum,
          chip);
  /* Every number has a unit: no line ends right after its value. */
  for (const char *l = strstr(out, "\ncycles: "); l && l[1]; l = strchr(l + 1, '\n')) {
    const char *value = strchr(l, ':'), *end = strchr(l + 1, '\n');
    if (!value || !end || !strncmp(l + 1, "output: ", 8)) continue;
    EXPECTF(memchr(value + 2, ' ', (size_t)(end - value - 2)), "a number without a unit: %.*s",
            (int)(end - l - 1), l + 1);
  }
}

static void test_command(void) {
  char cmd[4096], out[8192];
  const char *scene = RTSIM_SOURCE_DIR "/scenes/small/grove.yaml";
  const char *tiny = RTSIM_SOURCE_DIR "/configs/tiny.yaml";
  const char *ref = RTSIM_TMP "/run_ref.exr";
  snprintf(cmd, sizeof cmd, "%s render %s --width 24 --height 16 -o %s", RTSIM_BINARY, scene, ref);
  EXPECT(testing_run(cmd, out, sizeof out) == 0);
  const char *dirs[] = {RTSIM_TMP "/run_a", RTSIM_TMP "/run_b", RTSIM_TMP "/run_p",
                        RTSIM_TMP "/run_d", RTSIM_TMP "/run_e"};
  const char *opts[] = {"", "", "--policy packet --set cores=3 --set l2.size=8KiB",
                        "--policy dynamic --set cores=3", "--policy dynamic --set cores=3"};
  for (int i = 0; i < 5; i++) {
    snprintf(cmd, sizeof cmd, "%s run %s %s --width 24 --height 16 %s -o %s", RTSIM_BINARY, tiny,
             scene, opts[i], dirs[i]);
    int rc = testing_run(cmd, out, sizeof out);
    EXPECTF(rc == 0, "%s: exit %d: %s", cmd, rc, out);
    if (i == 2) check_summary(out, dirs[i]);
    const char *files[] = {"image.exr", "stats.json", "stats.csv", "timeline.csv", "traffic.png"};
    for (int f = 0; f < 5; f++)
      EXPECTF(exists(dirs[i], files[f]), "%s/%s missing", dirs[i], files[f]);
    char img[2048];
    snprintf(img, sizeof img, "%s/image.exr", dirs[i]);
    EXPECTF(testing_same_rgb(ref, img), "%s: RGB differs from rtsim render's", dirs[i]);
  }
  const char *names[] = {"stats.csv", "timeline.csv", "image.exr", "stats.json"};
  for (int d = 0; d < 2; d++) /* recursive, then dynamic: the same bytes twice */
    for (int f = 0; f < 4; f++) {
      char a[2048], b[2048];
      snprintf(a, sizeof a, "%s/%s", dirs[3 * d], names[f]);
      snprintf(b, sizeof b, "%s/%s", dirs[3 * d + 1], names[f]);
      EXPECTF(same_file(a, b, f == 3), "%s differs between two runs (%s)", names[f], dirs[3 * d]);
    }
  /* stats.csv's columns are unique names (a merged table joins them by name). */
  char csvp[2048], hdr[8192];
  snprintf(csvp, sizeof csvp, "%s/stats.csv", dirs[0]);
  FILE *hf = fopen(csvp, "r");
  EXPECT(hf && fgets(hdr, sizeof hdr, hf));
  if (hf) fclose(hf);
  hdr[strcspn(hdr, "\n")] = '\0';
  char *names_at[256];
  unsigned ncols = 0;
  for (char *tok = strtok(hdr, ","); tok && ncols < 256; tok = strtok(NULL, ",")) {
    for (unsigned j = 0; j < ncols; j++)
      EXPECTF(strcmp(names_at[j], tok) != 0, "stats.csv has column '%s' twice", tok);
    names_at[ncols++] = tok;
  }
  EXPECT(ncols > 30);
  /* The override is in the resolved config. */
  char js[2048];
  snprintf(js, sizeof js, "%s/stats.json", dirs[2]);
  FILE *f = fopen(js, "r");
  static char json[1 << 16];
  size_t n = f ? fread(json, 1, sizeof json - 1, f) : 0;
  json[n] = '\0';
  if (f) fclose(f);
  EXPECT(strstr(json, "\"cores\": 3,") && strstr(json, "\"l2.size\": 8192,") &&
         strstr(json, "\"policy\": \"packet\""));
  /* Traceable: the scene's hash (16 hex digits) and the build's revision. */
  const char *hash = strstr(json, "\"scene_hash\": \"");
  EXPECT(hash && strspn(hash + 15, "0123456789abcdef") == 16 && hash[31] == '"');
  EXPECT(strstr(json, "\"kd_splits\": \"whole\""));
  const char *rev = strstr(json, "\"revision\": \"");
  EXPECT(rev && rev[13] != '"');

  static const struct {
    const char *args, *want;
  } bad[] = {
      {"run CFG SCN -o DIR --set cores=0", "--set cores=0: error: cores: out of range (got 0"},
      {"run CFG SCN -o DIR --set l2.size=32", "l2.size: smaller than one 64-byte line"},
      {"run CFG SCN -o DIR --set dram.bytes_per_cycle=0", "dram.bytes_per_cycle: out of range"},
      {"run CFG SCN -o DIR --set l3.size=1", "unknown key 'l3.size'"},
      {"run " RTSIM_TEST_DATA "/configs/bad_size_unit.yaml SCN -o DIR",
       "bad_size_unit.yaml:2:9: error: l2.size"},
      {"run CFG SCN -o DIR --policy fastest", "--policy: got 'fastest'"},
      {"run CFG -o DIR", "expected MACHINE.yaml SCENE.yaml, got 1 file"},
      {"run CFG SCN", "missing -o OUTDIR"},
      {"run CFG SCN -o DIR --width 0", "--width: got '0'"},
      {"run CFG " RTSIM_TEST_DATA "/scenes/bad_color.yaml -o DIR", "bad_color.yaml:"},
  };
  /* More ray contexts than this host can map coroutine stacks for: refused
   * before the run, not a crash inside it (4096 x 4 x 4 = 65,536 stacks). */
  if (coro_host_stack_limit() < 65536) {
    snprintf(cmd, sizeof cmd,
             "%s run %s %s -o %s/run_many --width 8 --height 8 --set cores=4096 "
             "--set threads_per_core=4 --set rays_per_thread=4",
             RTSIM_BINARY, tiny, scene, RTSIM_TMP);
    int rc = testing_run(cmd, out, sizeof out);
    EXPECTF(rc == 2 && strstr(out, "--set cores=4096: error: cores x threads_per_core x "
                                   "rays_per_thread = 65536 ray contexts, and this host"),
            "too many contexts for the host: exit %d, '%s'", rc, out);
  }
  const char *bad_dir = RTSIM_TMP "/run_bad";
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    char args[2048] = "", *o = args;
    for (const char *p = bad[i].args; *p;) {
      if (!strncmp(p, "CFG", 3)) o += sprintf(o, "%s", tiny), p += 3;
      else if (!strncmp(p, "SCN", 3)) o += sprintf(o, "%s", scene), p += 3;
      else if (!strncmp(p, "DIR", 3)) o += sprintf(o, "%s", bad_dir), p += 3;
      else *o++ = *p++;
    }
    *o = '\0';
    snprintf(cmd, sizeof cmd, "%s %s --width 8 --height 8", RTSIM_BINARY, args);
    if (strstr(bad[i].args, "--width")) snprintf(cmd, sizeof cmd, "%s %s", RTSIM_BINARY, args);
    int rc = testing_run(cmd, out, sizeof out);
    EXPECTF(rc == 2 && strstr(out, bad[i].want), "%s: exit %d, '%s'", bad[i].args, rc, out);
    EXPECTF(!exists(bad_dir, "stats.json"), "%s left a stats.json", bad[i].args);
  }
}

/* Idle ray contexts cost nothing while they are parked: the dynamic policy
 * on one pixel (one primary ray) with 32 cores of 1 x 1 and of 4 x 4 ray
 * contexts, no L1 (the ray's accesses reach the L2 alike, whichever context
 * runs it) and a tiny L2 (the same queue points: the ray buffer is capped at
 * 1/16 of the L2 both ways). Each of the 480 more contexts costs two issue
 * events, its first call (it parks) and its call after the wake at the end of
 * the batch, and nothing in between; the wakes may leave one stale issue event
 * a core. Polling contexts would cost events in proportion to the run's
 * length (14,000 cycles here). */
static void test_idle_contexts(void) {
  char cmd[4096], out[8192];
  double ev[2], parks[2], cycles[2];
  const char *shape[2] = {"1", "4"};
  for (int i = 0; i < 2; i++) {
    char dir[1024];
    snprintf(dir, sizeof dir, "%s/run_idle_%d", RTSIM_TMP, i);
    snprintf(
        cmd, sizeof cmd,
        "%s run %s/configs/tiny.yaml %s/scenes/small/room.yaml --policy dynamic --rays primary "
        "--width 1 --height 1 --set cores=32 --set threads_per_core=%s --set rays_per_thread=%s "
        "--set l1.size=0 -o %s",
        RTSIM_BINARY, RTSIM_SOURCE_DIR, RTSIM_SOURCE_DIR, shape[i], shape[i], dir);
    int rc = testing_run(cmd, out, sizeof out);
    EXPECTF(rc == 0, "exit %d: %s", rc, out);
    ev[i] = testing_json_num(dir, "events");
    parks[i] = testing_json_num(dir, "parks");
    cycles[i] = testing_json_num(dir, "cycles");
  }
  const double more = 512 - 32;
  EXPECTF(ev[1] - ev[0] >= 2 * more && ev[1] - ev[0] <= 2 * more + 32,
          "%.0f events with 512 contexts, %.0f with 32", ev[1], ev[0]);
  EXPECTF(parks[1] - parks[0] == more, "%.0f parks with 512 contexts, %.0f with 32", parks[1],
          parks[0]);
  EXPECT(cycles[0] > 10000 && cycles[1] > 10000);
}

/* Whole runs at the machine's extremes: every output written, no nan or inf.
 * The dynamic policy too (16,384 contexts on 24 pixels, nearly all parked;
 * the 64-byte L2 leaves g_max 0: every leaf a queue point, its triangles one
 * block each). */
static void test_command_extremes(void) {
  static const char *const sets[] = {
      "--set cores=1 --set threads_per_core=1 --set rays_per_thread=1",
      "--set cores=256 --set threads_per_core=8 --set rays_per_thread=8",
      "--set dram.latency=0 --set dram.bytes_per_cycle=10000",
      "--set dram.latency=1000000 --set timeline.window=1",
      "--set dram.bytes_per_cycle=0.01 --set l2.size=64 --set l2.ways=full --set l2.mshrs=1",
      /* Simulated time past 2^43 cycles (the channel's ticks were 64-bit). */
      "--set dram.latency=1000000000",
      "--set dram.bytes_per_cycle=0.000001",
      "--policy dynamic --set cores=1 --set threads_per_core=1 --set rays_per_thread=1",
      "--policy dynamic --set cores=256 --set threads_per_core=8 --set rays_per_thread=8",
      "--policy dynamic --set dram.latency=0 --set dram.bytes_per_cycle=10000",
      "--policy dynamic --set dram.latency=1000000 --set timeline.window=1",
      "--policy dynamic --set dram.bytes_per_cycle=0.01 --set l2.size=64 --set l2.ways=full --set l2.mshrs=1",
  };
  char cmd[4096], out[8192];
  const char *dir = RTSIM_TMP "/run_extreme";
  for (unsigned i = 0; i < sizeof sets / sizeof sets[0]; i++) {
    snprintf(cmd, sizeof cmd,
             "%s run %s/configs/tiny.yaml %s/scenes/small/room.yaml --width 6 --height 4 %s -o %s",
             RTSIM_BINARY, RTSIM_SOURCE_DIR, RTSIM_SOURCE_DIR, sets[i], dir);
    int rc = testing_run(cmd, out, sizeof out);
    EXPECTF(rc == 0, "%s: exit %d: %s", sets[i], rc, out);
    const char *files[] = {"stats.json", "stats.csv", "timeline.csv"};
    for (int f = 0; f < 3; f++) {
      char p[2048];
      snprintf(p, sizeof p, "cat %s/%s", dir, files[f]);
      static char text[1 << 20];
      testing_run(p, text, sizeof text);
      EXPECTF(!strstr(text, "nan") && !strstr(text, "inf") && strlen(text) > 10,
              "%s: %s: nan or inf", sets[i], files[f]);
    }
  }
}

/* argv[1]: "cross-a" runs the cross-check of recursive and packet alone,
 * "cross-b" that of dynamic and treelet, "rest" everything else (ctest runs
 * the three as tests of their own, side by side: together they ran past the
 * per-test limit under the sanitizers on a loaded machine); none, all. */
/* test_cross_check's policies first..last-1 on the BVH2 and the BVH8. */
static void cross_check_bvhs(struct world *w, unsigned first, unsigned last) {
  for (int k = ACCEL_BVH2; k <= ACCEL_BVH8; k++) {
    struct bvh b;
    bvh_build(&b, &w->s, (enum accel_kind)k);
    w->bvh = &b;
    test_cross_check(w, first, last);
    w->bvh = NULL;
    bvh_fini(&b);
  }
}

int main(int argc, char **argv) {
  const char *part = argc < 2 ? "all" : argv[1];
  const bool all = !strcmp(part, "all"), rest = all || !strcmp(part, "rest");
  EXPECTF(all || rest || !strcmp(part, "cross-a") || !strcmp(part, "cross-b"), "unknown part '%s'",
          part);
  struct world w;
  if (!load_small(&w, "room")) return testing_done("test_run");
  if (all || !strcmp(part, "cross-a")) {
    test_cross_check(&w, 0, 2);
    /* The recursive and packet policies on each BVH: the same cross-check,
     * and their traversal stacks within the coroutines' margin. */
    cross_check_bvhs(&w, 0, 2);
    EXPECT(stack_used_max > 0 && 4 * stack_used_max <= coro_default_stack_bytes());
  }
  if (all || !strcmp(part, "cross-b")) {
    test_cross_check(&w, 2, 4);
    /* The queue policies on each BVH. */
    cross_check_bvhs(&w, 2, 4);
  }
  if (!rest) {
    world_fini(&w);
    return testing_done("test_run (cross-check)");
  }
  test_many_workers(&w, "room", true);
  {
    /* Many workers on the 8-wide BVH. */
    struct bvh b;
    bvh_build(&b, &w.s, ACCEL_BVH8);
    w.bvh = &b;
    test_many_workers(&w, "room bvh8", false);
    w.bvh = NULL;
    bvh_fini(&b);
  }
  const char *others[] = {"grove", "sphereflake"};
  for (int i = 0; i < 2; i++) {
    struct world o;
    if (!load_small(&o, others[i])) continue;
    test_many_workers(&o, others[i], false);
    world_fini(&o);
  }
  test_machine_plan();
  test_command();
  test_command_extremes();
  test_idle_contexts();
  /* The kernels' deepest stack, against the size the machine gives them: the
   * margin coro.c states (at least 4x) must hold. */
  printf("deepest coroutine stack: %llu bytes of %zu\n", (unsigned long long)stack_used_max,
         coro_default_stack_bytes());
  EXPECT(stack_used_max > 0 && 4 * stack_used_max <= coro_default_stack_bytes());
  world_fini(&w);
  return testing_done("test_run");
}
