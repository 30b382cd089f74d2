/* The dynamic policy against the recursive one (the oracle), on the k-d tree
 * and on each BVH: bit-identical framebuffers and equal per-type ray counts on the small scenes,
 * every ray type, caches from 1 KB (leaf queue points, oversized leaves in blocks) to 64 MB (the
 * root alone: Whitted). Without shadow rays the closest-hit traversals are the same ones cut at
 * queue points, so the triangle tests and the set of tested triangles are equal too. A counting
 * memory port checks the queue discipline: every ray stored into a queue slot is loaded back
 * exactly once before the slot is reused, table entries stay in the table, and the generation
 * buffers balance. */
#include <stdlib.h>
#include <string.h>

#include "renderer/bvh.h"
#include "renderer/framebuffer.h"
#include "renderer/kdtree.h"
#include "renderer/policy/policy.h"
#include "renderer/policy/qpoint.h"
#include "renderer/scene.h"
#include "renderer/scene/scene_file.h"
#include "renderer/shade.h"
#include "renderer/trace.h"
#include "sim/err.h"
#include "testing.h"

struct world {
  struct scene s;
  struct kd_tree kd;
  const struct bvh *bvh; /* traced instead of kd when not NULL */
};

static int load(struct world *w, const char *path) {
  return testing_load_world(&w->s, &w->kd, path);
}

/* A memory port that checks the queue and buffer discipline. */
struct counter {
  struct trace_layout l;
  uint64_t table_loads, table_stores, table_bad, max_table;
  struct testing_slots slots;
  uint64_t class_bad;
  uint64_t other_ray; /* ray accesses outside the queues and the camera array */
  uint8_t *cam;       /* per pixel: times its primary ray was read */
  uint64_t npix, cam_bad;
};

static void on_access(void *ctx, uint64_t addr, uint32_t size, unsigned cls, int store) {
  struct counter *c = ctx;
  if (addr >= c->l.qtable_base && addr < c->l.queue_base) {
    c->class_bad += cls != TRACE_CLASS_QUEUE || size != 8;
    uint64_t e = (addr - c->l.qtable_base) / 8;
    if (e + 1 > c->max_table) c->max_table = e + 1;
    c->table_bad += (addr - c->l.qtable_base) % 8 != 0;
    if (store) c->table_stores++;
    else c->table_loads++;
  } else if (addr >= c->l.queue_base && addr < c->l.ray_base) {
    c->class_bad += cls != TRACE_CLASS_RAY || size != 64 || (addr - c->l.queue_base) % 64 != 0;
    testing_slots_access(&c->slots, (addr - c->l.queue_base) / 64, store);
  } else if (addr >= c->l.camera_base) {
    uint64_t k = (addr - c->l.camera_base) / 64;
    c->cam_bad += store || cls != TRACE_CLASS_RAY || size != 64 ||
                  (addr - c->l.camera_base) % 64 != 0 || k >= c->npix;
    if (k < c->npix) c->cam[k]++;
  } else if (cls == TRACE_CLASS_RAY) {
    c->other_ray++;
  }
}

static void on_load(void *ctx, uint64_t addr, uint32_t size, unsigned cls) {
  on_access(ctx, addr, size, cls, 0);
}
static void on_store(void *ctx, uint64_t addr, uint32_t size, unsigned cls) {
  on_access(ctx, addr, size, cls, 1);
}

static const struct mem_ops COUNTER_OPS = {on_load, on_store, NULL, NULL, NULL, NULL};

struct result {
  struct framebuffer fb;
  struct render_stats st;
  struct trace_stats ts;
  uint64_t *tested;
};

/* A render; batch: the dynamic policy's primary rays admitted at a time (0: all). */
static void render_batch(struct world *w, enum policy_kind k, uint32_t mask, uint32_t size,
                         uint64_t cache, uint64_t batch, struct counter *cnt, struct result *res) {
  struct shade_ctx sc = {&w->s, mask, 7, 0};
  struct policy_setup ps;
  testing_policy_setup(&ps, &w->s, &w->kd, &sc, &res->fb);
  ps.bvh = w->bvh;
  const struct trace_layout l = ps.layout;
  struct mem_port port = mem_port_native();
  if (cnt) {
    memset(cnt, 0, sizeof *cnt);
    cnt->l = l;
    cnt->npix = (uint64_t)size * size;
    cnt->cam = calloc(cnt->npix, 1);
    port.ops = &COUNTER_OPS;
    port.ctx = cnt;
  }
  res->tested = calloc(w->s.tri_count / 64 + 1, sizeof *res->tested);
  ps.tested = res->tested;
  fb_init(&res->fb, size, size, l.fb_base);
  struct policy_params pp;
  policy_params_default(&pp);
  pp.cache_bytes = cache;
  pp.dyn_batch_rays = batch;
  policy_run(k, &ps, &pp, port, &res->st, &res->ts);
}

static void render(struct world *w, enum policy_kind k, uint32_t mask, uint32_t size,
                   uint64_t cache, struct counter *cnt, struct result *res) {
  render_batch(w, k, mask, size, cache, 0, cnt, res);
}

static void result_fini(struct result *r) {
  fb_fini(&r->fb);
  free(r->tested);
}

/* The schedule's shape at a cache size (what the policy computes). */
static void plan(const struct world *w, uint64_t cache, struct qpoint_set *qs,
                 struct qpoint_budget *b) {
  const uint32_t n = w->bvh ? qpoint_bvh_places(w->bvh) : w->kd.node_count;
  uint32_t *tris = malloc(n * sizeof *tris);
  if (w->bvh) qpoint_bvh_subtree_tris(w->bvh, tris);
  else qpoint_subtree_tris(&w->kd, tris);
  struct policy_params pp;
  policy_params_default(&pp);
  struct qpoint_reserve r = {
      cache, pp.dyn_node_share, pp.dyn_table_share, pp.dyn_ray_share, pp.dyn_ray_buffer_bytes, 1};
  if (w->bvh) qpoint_bvh_plan(qs, b, w->bvh, tris, 128, &r);
  else qpoint_plan(qs, b, &w->kd, tris, 128, &r);
  free(tris);
}

/* The treelet policy at a cache size against the recursive renders ref (all
 * rays) and ref_ns (no shadow rays). */
static void check_treelet(struct world *w, const char *name, uint32_t all, uint32_t noshadow,
                          uint32_t size, uint64_t cache, const struct result *ref,
                          const struct result *ref_ns) {
  const unsigned kb = (unsigned)(cache / 1024);
  const size_t fb_bytes = 3 * sizeof(int64_t) * size * size;
  struct counter tc;
  struct result tl;
  memset(&tc, 0, sizeof tc);
  render(w, POLICY_TREELET, all, size, cache, &tc, &tl);
  EXPECTF(memcmp(tl.fb.acc, ref->fb.acc, fb_bytes) == 0,
          "%s %u KB: treelet image differs from recursive", name, kb);
  EXPECT(memcmp(tl.st.rays, ref->st.rays, sizeof ref->st.rays) == 0);
  EXPECT(tl.st.spawned == ref->st.spawned && tl.st.terminated == ref->st.terminated);
  EXPECTF(testing_slots_left(&tc.slots) == 0 && tc.slots.bad == 0 &&
              tc.slots.loads == tc.slots.stores && tc.slots.stores >= ref->st.rays[RAY_PRIMARY],
          "%s %u KB treelet: queue slots: %llu stores, %llu loads, %llu bad", name, kb,
          (unsigned long long)tc.slots.stores, (unsigned long long)tc.slots.loads,
          (unsigned long long)tc.slots.bad);
  bool tonce = true;
  for (uint64_t k = 0; k < tc.npix; k++) tonce &= tc.cam[k] == 1;
  EXPECT(tonce && tc.other_ray == 0 && tc.table_bad == 0 && tc.class_bad == 0);
  testing_slots_fini(&tc.slots);
  free(tc.cam);
  result_fini(&tl);
  struct result tn;
  render(w, POLICY_TREELET, noshadow, size, cache, NULL, &tn);
  EXPECTF(memcmp(tn.fb.acc, ref_ns->fb.acc, fb_bytes) == 0 &&
              tn.ts.tri_tests == ref_ns->ts.tri_tests &&
              memcmp(tn.fb.cost_tris, ref_ns->fb.cost_tris, sizeof(uint32_t) * size * size) == 0,
          "%s %u KB treelet (no shadows): %llu triangle tests, recursive %llu", name, kb,
          (unsigned long long)tn.ts.tri_tests, (unsigned long long)ref_ns->ts.tri_tests);
  result_fini(&tn);
}

/* The checks on scene `scene` traced through structure accel (enum accel_kind). */
static void check_scene(const char *scene, int accel) {
  char path[1024], name[64];
  snprintf(path, sizeof path, "%s/scenes/small/%s.yaml", RTSIM_SOURCE_DIR, scene);
  snprintf(name, sizeof name, "%s %s", scene, accel_names[accel]);
  struct world w;
  if (!load(&w, path)) {
    EXPECTF(0, "cannot load %s", path);
    return;
  }
  struct bvh bvh;
  w.bvh = NULL;
  if (accel != ACCEL_KD) {
    bvh_build(&bvh, &w.s, (enum accel_kind)accel);
    w.bvh = &bvh;
  }
  const uint32_t all =
      RAY_MASK(RAY_PRIMARY) | RAY_MASK(RAY_SHADOW) | RAY_MASK(RAY_SPECULAR) | RAY_MASK(RAY_DIFFUSE);
  const uint32_t noshadow = all & ~RAY_MASK(RAY_SHADOW);
  const uint32_t size = 40;
  const uint64_t caches[] = {1024, 16384, 256 * 1024, 64u << 20};
  struct result ref, ref_ns;
  render(&w, POLICY_RECURSIVE, all, size, 0, NULL, &ref);
  render(&w, POLICY_RECURSIVE, noshadow, size, 0, NULL, &ref_ns);
  const size_t fb_bytes = 3 * sizeof(int64_t) * size * size;
  const size_t tested_bytes = (w.s.tri_count / 64 + 1) * sizeof(uint64_t);

  for (size_t c = 0; c < sizeof caches / sizeof caches[0]; c++) {
    const unsigned kb = (unsigned)(caches[c] / 1024);
    struct qpoint_set qs;
    struct qpoint_budget b;
    plan(&w, caches[c], &qs, &b);
    if (caches[c] == 1024) {
      /* Queue points down at the leaves, some k-d leaves over g_max
       * (blocked; a BVH leaf holds 3 triangles at most: none). */
      uint32_t leaves = 0, oversized = 0;
      for (uint32_t k = 0; k < qs.count; k++) {
        uint32_t first, cnt;
        if (!qpoint_leaf(&qs, qs.qnode[k], &first, &cnt)) continue;
        leaves++;
        oversized += (uint64_t)cnt * 128 > b.gmax_bytes;
      }
      EXPECTF(leaves > 0 && (oversized > 0) == (accel == ACCEL_KD),
              "%s 1 KB: %u queue points, %u leaves, %u oversized", name, qs.count, leaves,
              oversized);
    }
    if (caches[c] == 64u << 20)
      EXPECTF(qs.count == 1 && qs.qnode[0] == 0, "%s 64 MB: %u queue points", name, qs.count);
    const uint32_t queues = qs.count;
    qpoint_fini(&qs);

    struct counter cnt;
    struct result dy;
    render(&w, POLICY_DYNAMIC, all, size, caches[c], &cnt, &dy);
    EXPECTF(memcmp(dy.fb.acc, ref.fb.acc, fb_bytes) == 0, "%s %u KB: image differs from recursive",
            name, kb);
    EXPECTF(memcmp(dy.st.rays, ref.st.rays, sizeof ref.st.rays) == 0,
            "%s %u KB: rays %llu/%llu/%llu/%llu, recursive %llu/%llu/%llu/%llu", name, kb,
            (unsigned long long)dy.st.rays[0], (unsigned long long)dy.st.rays[1],
            (unsigned long long)dy.st.rays[2], (unsigned long long)dy.st.rays[3],
            (unsigned long long)ref.st.rays[0], (unsigned long long)ref.st.rays[1],
            (unsigned long long)ref.st.rays[2], (unsigned long long)ref.st.rays[3]);
    EXPECT(dy.st.spawned == ref.st.spawned && dy.st.terminated == ref.st.terminated);
    /* Queue discipline. */
    const struct testing_slots *sl = &cnt.slots;
    uint64_t leftover = testing_slots_left(sl);
    EXPECTF(!leftover && sl->bad == 0 && sl->loads == sl->stores && sl->stores > 0,
            "%s %u KB: queue slots: %llu stores, %llu loads, %llu bad, leftover %llu", name, kb,
            (unsigned long long)sl->stores, (unsigned long long)sl->loads,
            (unsigned long long)sl->bad, (unsigned long long)leftover);
    /* Each enqueue reads and writes its table entry; so does each drain. */
    EXPECT(cnt.table_loads == cnt.table_stores && cnt.table_bad == 0 && cnt.class_bad == 0);
    EXPECT(cnt.table_loads >= ref.st.rays[RAY_PRIMARY] / 2);
    EXPECTF(cnt.max_table <= queues, "%s %u KB: table entries %llu of %u", name, kb,
            (unsigned long long)cnt.max_table, queues);
    if (caches[c] == 64u << 20) EXPECT(cnt.max_table == 1);
    /* Rays wait only in queues; each primary ray is read from the camera once. */
    EXPECT(cnt.other_ray == 0 && cnt.cam_bad == 0);
    bool once = true;
    for (uint64_t k = 0; k < cnt.npix; k++) once &= cnt.cam[k] == 1;
    EXPECTF(once, "%s %u KB: a primary ray not read exactly once", name, kb);
    if (caches[c] == 16384) {
      /* Primary rays admitted 7 at a time (not a divisor of the pixel count):
       * the same picture and rays, the same queue discipline, each camera ray
       * read once, and fewer rays queued at once. */
      struct counter cb;
      struct result db;
      render_batch(&w, POLICY_DYNAMIC, all, size, caches[c], 7, &cb, &db);
      EXPECTF(memcmp(db.fb.acc, ref.fb.acc, fb_bytes) == 0,
              "%s batch 7: image differs from recursive", name);
      EXPECT(memcmp(db.st.rays, ref.st.rays, sizeof ref.st.rays) == 0);
      EXPECT(db.st.spawned == ref.st.spawned && db.st.terminated == ref.st.terminated);
      bool once7 = true;
      for (uint64_t k = 0; k < cb.npix; k++) once7 &= cb.cam[k] == 1;
      EXPECT(testing_slots_left(&cb.slots) == 0 && cb.slots.bad == 0 &&
             cb.slots.loads == cb.slots.stores && once7);
      EXPECTF(db.st.ray_slots_max < dy.st.ray_slots_max,
              "%s batch 7: %llu rays queued at most, unbatched %llu", name,
              (unsigned long long)db.st.ray_slots_max, (unsigned long long)dy.st.ray_slots_max);
      testing_slots_fini(&cb.slots);
      free(cb.cam);
      result_fini(&db);
    }
    testing_slots_fini(&cnt.slots);
    free(cnt.cam);
    result_fini(&dy);

    /* Treelet queues (the same machinery, a ray queued again at every treelet
     * it enters): the same picture, rays and triangle tests as recursive, the
     * same queue discipline, each camera ray read once. */
    check_treelet(&w, name, all, noshadow, size, caches[c], &ref, &ref_ns);

    /* No shadow rays: the very same closest-hit work as recursive. */
    struct result dn;
    render(&w, POLICY_DYNAMIC, noshadow, size, caches[c], NULL, &dn);
    EXPECTF(memcmp(dn.fb.acc, ref_ns.fb.acc, fb_bytes) == 0, "%s %u KB (no shadows): image differs",
            name, kb);
    EXPECTF(dn.ts.tri_tests == ref_ns.ts.tri_tests, "%s %u KB: %llu triangle tests, recursive %llu",
            name, kb, (unsigned long long)dn.ts.tri_tests, (unsigned long long)ref_ns.ts.tri_tests);
    EXPECT(memcmp(dn.tested, ref_ns.tested, tested_bytes) == 0);
    EXPECT(dn.ts.node_visits >= ref_ns.ts.node_visits);
    /* Per-pixel triangle tests are the recursive ones too. */
    EXPECT(memcmp(dn.fb.cost_tris, ref_ns.fb.cost_tris, sizeof(uint32_t) * size * size) == 0);
    result_fini(&dn);
  }
  result_fini(&ref);
  result_fini(&ref_ns);

  /* Deterministic: two runs, same image and same counts. */
  struct result a, b2;
  render(&w, POLICY_DYNAMIC, all, size, 16384, NULL, &a);
  render(&w, POLICY_DYNAMIC, all, size, 16384, NULL, &b2);
  EXPECT(memcmp(a.fb.acc, b2.fb.acc, fb_bytes) == 0);
  EXPECT(memcmp(a.fb.cost_nodes, b2.fb.cost_nodes, sizeof(uint32_t) * size * size) == 0);
  EXPECT(a.ts.node_visits == b2.ts.node_visits && a.ts.tri_tests == b2.ts.tri_tests);
  result_fini(&a);
  result_fini(&b2);
  if (w.bvh) bvh_fini(&bvh);
  kd_fini(&w.kd);
  scene_fini(&w.s);
}

int main(void) {
  static const char *const scenes[] = {"sphereflake", "grove", "room"};
  for (int a = ACCEL_KD; a < ACCEL_COUNT; a++)
    for (int k = 0; k < 3; k++) check_scene(scenes[k], a);
  return testing_done("test_policy_dynamic");
}
