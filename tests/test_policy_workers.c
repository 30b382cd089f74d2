/* Workers of one render (renderer/policy/policy.h) against one worker (the oracle):
 * for recursive and packet, several workers give the bit-identical
 * framebuffer (colour and per-pixel cost), ray counts, trace counts and tested
 * set, whether they run one after another, take items in turn, or run inside
 * one another's accesses, the way a suspended coroutine lets others run. A
 * recording port per worker checks that a lone worker makes exactly
 * policy_run's accesses, that idle workers make none, and that a worker's rays
 * stay in its own ray region. The dynamic policy's workers share a batch and
 * wait for one another, which needs the machine (test_run); here its batches
 * go to workers one after another and in turn, the shared queues carried over
 * from batch to batch. */
#include <stdlib.h>
#include <string.h>

#include "renderer/framebuffer.h"
#include "renderer/kdtree.h"
#include "renderer/policy/policy.h"
#include "renderer/scene.h"
#include "renderer/shade.h"
#include "renderer/trace.h"
#include "sim/err.h"
#include "testing.h"

#define WORKERS 3

/* A port that records one worker's accesses: their count and a hash of the
 * sequence, ray accesses outside the camera array and outside the worker's
 * own region. To stand in for a suspension, it may run one work item of
 * another worker (`next`) inside this one's access: at every `every`-th
 * access, and at every other primary-ray load, the first access of a work
 * item (where a policy that claimed its item late would hand it out twice). */
struct rec {
  uint64_t count, hash;
  uint64_t cam_lo, cam_hi, own_lo, own_hi;
  uint64_t ray_accesses, ray_outside, cam_loads;
  struct policy_job *job;
  struct policy_worker *next;
  struct rec *next_rec;
  uint64_t every;
  bool running; /* inside a step (a worker is never re-entered) */
  uint64_t nested_steps;
};

static void on_access(struct rec *c, uint64_t addr, uint32_t size, unsigned cls, unsigned store) {
  c->count++;
  uint64_t v[4] = {addr, size, cls, store};
  for (int i = 0; i < 4; i++) c->hash = (c->hash ^ v[i]) * 0x100000001b3ull + 0x9e3779b97f4a7c15ull;
  bool cam = addr >= c->cam_lo && addr < c->cam_hi;
  c->cam_loads += cam;
  if (cls == TRACE_CLASS_RAY && !cam) {
    c->ray_accesses++;
    c->ray_outside += addr < c->own_lo || addr + size > c->own_hi;
  }
  bool nest = c->every && (c->count % c->every == 0 || (cam && c->cam_loads % 2 == 1));
  if (c->next && nest && !c->next_rec->running) {
    c->next_rec->running = true;
    c->nested_steps += policy_job_step(c->job, c->next);
    c->next_rec->running = false;
  }
}

static void on_load(void *ctx, uint64_t addr, uint32_t size, unsigned cls) {
  on_access(ctx, addr, size, cls, 0);
}
static void on_store(void *ctx, uint64_t addr, uint32_t size, unsigned cls) {
  on_access(ctx, addr, size, cls, 1);
}
static const struct mem_ops REC_OPS = {on_load, on_store, NULL, NULL, NULL, NULL};

struct world {
  struct scene s;
  struct kd_tree kd;
};

/* One render's outputs. */
struct result {
  struct framebuffer fb;
  struct render_stats st;
  struct trace_stats ts;
  uint64_t *tested;
};

struct render {
  struct shade_ctx sc;
  struct policy_setup ps;
  struct policy_params pp;
  struct result res;
};

static void render_init(struct render *r, struct world *w, uint32_t width, uint32_t height) {
  memset(r, 0, sizeof *r);
  r->sc = (struct shade_ctx){&w->s,
                             RAY_MASK(RAY_PRIMARY) | RAY_MASK(RAY_SHADOW) | RAY_MASK(RAY_SPECULAR) |
                                 RAY_MASK(RAY_DIFFUSE),
                             7, 0};
  testing_policy_setup(&r->ps, &w->s, &w->kd, &r->sc, &r->res.fb);
  fb_init(&r->res.fb, width, height, r->ps.layout.fb_base);
  r->res.tested = xcalloc(w->s.tri_count / 64 + 1, sizeof *r->res.tested);
  r->ps.tested = r->res.tested;
  policy_params_default(&r->pp);
}

static void render_fini(struct render *r) {
  fb_fini(&r->res.fb);
  free(r->res.tested);
}

static void rec_init(struct rec *c, const struct render *r, enum policy_kind k, uint32_t id) {
  memset(c, 0, sizeof *c);
  c->hash = 0xcbf29ce484222325ull;
  c->cam_lo = r->ps.layout.camera_base;
  c->cam_hi = c->cam_lo + 64ull * r->res.fb.width * r->res.fb.height;
  c->own_lo = r->ps.layout.ray_base + id * policy_ray_region_bytes(k);
  c->own_hi = c->own_lo + policy_ray_region_bytes(k);
  if (k == POLICY_DYNAMIC || k == POLICY_TREELET) { /* its rays wait in the shared queues */
    c->own_lo = r->ps.layout.queue_base;
    c->own_hi = r->ps.layout.ray_base;
  }
}

/* Same picture, costs, ray and trace counts and tested set. (ray_slots_max
 * is not compared: workers hold their rays in separate regions, so theirs add
 * up.) */
static int same_result(const struct result *a, const struct result *b, uint32_t tri_count) {
  uint64_t npix = (uint64_t)a->fb.width * a->fb.height;
  return memcmp(a->fb.acc, b->fb.acc, 3 * npix * sizeof *a->fb.acc) == 0 &&
         memcmp(a->fb.cost_nodes, b->fb.cost_nodes, npix * sizeof *a->fb.cost_nodes) == 0 &&
         memcmp(a->fb.cost_tris, b->fb.cost_tris, npix * sizeof *a->fb.cost_tris) == 0 &&
         memcmp(a->st.rays, b->st.rays, sizeof a->st.rays) == 0 && a->st.spawned == b->st.spawned &&
         a->st.terminated == b->st.terminated && a->ts.node_visits == b->ts.node_visits &&
         a->ts.tri_tests == b->ts.tri_tests &&
         memcmp(a->tested, b->tested, (tri_count / 64 + 1) * sizeof *a->tested) == 0;
}

enum schedule {
  ONE_AFTER_ANOTHER, /* worker 0 runs the loop to the end, then the others */
  IN_TURN,           /* one item each in turn */
  NESTED,            /* worker 0 runs; inside its accesses worker 1 steps, inside 1's worker 2 */
  SCHEDULE_COUNT
};
static const char *const SCHEDULE_NAMES[SCHEDULE_COUNT] = {"one after another", "in turn",
                                                           "nested"};

/* The dynamic policy's primary rays admitted this many at a time, so that its
 * batches are work items that workers take in turn. */
#define DYN_BATCH 37

static void run_workers(struct world *w, enum policy_kind k, uint32_t width, uint32_t height,
                        enum schedule sch, const struct render *ref, const struct rec *ref_rec) {
  struct render r;
  render_init(&r, w, width, height);
  r.pp.dyn_batch_rays = DYN_BATCH;
  struct policy_job *job = policy_job_create(k, &r.ps, &r.pp, WORKERS, 2);
  struct policy_worker wk[WORKERS];
  struct rec rc[WORKERS];
  for (uint32_t i = 0; i < WORKERS; i++) {
    rec_init(&rc[i], &r, k, i);
    struct mem_port port = {&REC_OPS, &rc[i]};
    policy_worker_init(&wk[i], job, i, i % 2, i / 2, port);
    EXPECT(wk[i].tr.layout.ray_base == r.ps.layout.ray_base + i * policy_ray_region_bytes(k) &&
           wk[i].scratch == NULL);
  }
  uint64_t steps[WORKERS] = {0};
  switch (sch) {
  case ONE_AFTER_ANOTHER:
    for (uint32_t i = 0; i < WORKERS; i++) policy_job_work(job, &wk[i]);
    break;
  case IN_TURN:
    for (bool any = true; any;) {
      any = false;
      for (uint32_t i = 0; i < WORKERS; i++)
        if (policy_job_step(job, &wk[i])) {
          steps[i]++;
          any = true;
        }
    }
    break;
  case NESTED:
    for (uint32_t i = 0; i + 1 < WORKERS; i++) {
      rc[i].job = job;
      rc[i].next = &wk[i + 1];
      rc[i].next_rec = &rc[i + 1];
      rc[i].every = 997 + 500 * i;
    }
    rc[0].running = true;
    while (policy_job_step(job, &wk[0])) steps[0]++;
    for (uint32_t i = 1; i < WORKERS; i++) EXPECT(!policy_job_step(job, &wk[i]));
    break;
  default: break;
  }
  EXPECT(!policy_job_step(job, &wk[0])); /* the list stays empty */
  bool scratch[WORKERS];
  for (uint32_t i = 0; i < WORKERS; i++) {
    scratch[i] = wk[i].scratch != NULL;
    policy_worker_fini(job, &wk[i]);
  }
  policy_job_finish(job, &r.res.st, &r.res.ts);
  policy_job_destroy(job);

  const char *what = SCHEDULE_NAMES[sch];
  EXPECTF(same_result(&r.res, &ref->res, w->s.tri_count),
          "%s, %u workers %s: framebuffer or counts differ from one worker's", policy_name(k),
          WORKERS, what);
  for (uint32_t i = 0; i < WORKERS; i++) {
    EXPECTF(rc[i].ray_outside == 0,
            "%s %s: worker %u made %llu of %llu ray accesses outside its region", policy_name(k),
            what, i, (unsigned long long)rc[i].ray_outside, (unsigned long long)rc[i].ray_accesses);
    EXPECTF(scratch[i] == (rc[i].count > 0), "%s %s: worker %u scratch %d with %llu accesses",
            policy_name(k), what, i, scratch[i], (unsigned long long)rc[i].count);
  }
  EXPECT(r.res.st.ray_slots_max >= ref->res.st.ray_slots_max);
  if (sch == ONE_AFTER_ANOTHER) {
    /* Worker 0 did it all, exactly as policy_run; the others found nothing. */
    EXPECT(r.res.st.ray_slots_max == ref->res.st.ray_slots_max);
    EXPECTF(rc[0].count == ref_rec->count && rc[0].hash == ref_rec->hash,
            "%s: worker 0's accesses differ from policy_run's (%llu vs %llu)", policy_name(k),
            (unsigned long long)rc[0].count, (unsigned long long)ref_rec->count);
    for (uint32_t i = 1; i < WORKERS; i++) EXPECT(rc[i].count == 0 && !scratch[i]);
  } else if (sch == IN_TURN) {
    for (uint32_t i = 0; i < WORKERS; i++)
      EXPECTF(steps[i] > 0 && rc[i].ray_accesses > 0, "%s in turn: worker %u took no item",
              policy_name(k), i);
  } else {
    for (uint32_t i = 0; i + 1 < WORKERS; i++)
      EXPECTF(rc[i].nested_steps > 0 && rc[i + 1].count > 0,
              "%s nested: worker %u never ran inside worker %u", policy_name(k), i + 1, i);
  }
  render_fini(&r);
}

static void check_policy(struct world *w, enum policy_kind k, uint32_t width, uint32_t height) {
  struct render ref;
  render_init(&ref, w, width, height);
  struct rec ref_rec;
  rec_init(&ref_rec, &ref, k, 0);
  struct mem_port port = {&REC_OPS, &ref_rec};
  ref.pp.dyn_batch_rays = DYN_BATCH;
  if (k == POLICY_DYNAMIC || k == POLICY_TREELET) {
    /* Its queue points are made for the job's workers and cores: the oracle is
     * worker 0 of such a job, alone. */
    struct policy_job *job = policy_job_create(k, &ref.ps, &ref.pp, WORKERS, 2);
    struct policy_worker w0;
    policy_worker_init(&w0, job, 0, 0, 0, port);
    policy_job_work(job, &w0);
    policy_worker_fini(job, &w0);
    policy_job_finish(job, &ref.res.st, &ref.res.ts);
    policy_job_destroy(job);
  } else {
    policy_run(k, &ref.ps, &ref.pp, port, &ref.res.st, &ref.res.ts);
  }
  EXPECT(ref_rec.ray_outside == 0 && ref_rec.ray_accesses > 0);
  for (int s = 0; s < SCHEDULE_COUNT; s++)
    if ((k != POLICY_DYNAMIC && k != POLICY_TREELET) ||
        s != NESTED) /* a nested dynamic worker would wait on its host */
      run_workers(w, k, width, height, (enum schedule)s, &ref, &ref_rec);
  render_fini(&ref);
}

static void check_interface(struct world *w) {
  EXPECT(!policy_workers_supported(POLICY_RECURSIVE, 0));
  EXPECT(policy_workers_supported(POLICY_RECURSIVE, 1000));
  EXPECT(policy_workers_supported(POLICY_PACKET, 64));
  EXPECT(policy_workers_supported(POLICY_DYNAMIC, 1));
  EXPECT(policy_workers_supported(POLICY_DYNAMIC, 1u << 20));
  for (int k = 0; k < POLICY_COUNT; k++) {
    uint64_t region = policy_ray_region_bytes((enum policy_kind)k);
    if (region == 0) continue;
    /* Regions may not run into the next region of the layout. */
    uint64_t most = (1ull << TRACE_REGION_SHIFT) / region;
    EXPECT(most <= UINT32_MAX);
    EXPECT(policy_workers_supported((enum policy_kind)k, (uint32_t)most));
    EXPECT(!policy_workers_supported((enum policy_kind)k, (uint32_t)most + 1));
  }
  /* Work items: pixels, or tiles of packet_dim x packet_dim. */
  struct render r;
  render_init(&r, w, 20, 9);
  struct policy_job *job = policy_job_create(POLICY_PACKET, &r.ps, &r.pp, 1, 1);
  EXPECT(policy_job_total(job) == 3 * 2);
  policy_job_destroy(job);
  job = policy_job_create(POLICY_RECURSIVE, &r.ps, &r.pp, 1, 1);
  EXPECT(policy_job_total(job) == 20 * 9);
  policy_job_destroy(job);
  /* The dynamic policy through the job interface is policy_run. */
  struct render a;
  render_init(&a, w, 20, 9);
  policy_run(POLICY_DYNAMIC, &a.ps, &a.pp, mem_port_native(), &a.res.st, &a.res.ts);
  job = policy_job_create(POLICY_DYNAMIC, &r.ps, &r.pp, 1, 1);
  struct policy_worker wk;
  policy_worker_init(&wk, job, 0, 0, 0, mem_port_native());
  policy_job_work(job, &wk);
  policy_worker_fini(job, &wk);
  policy_job_finish(job, &r.res.st, &r.res.ts);
  policy_job_destroy(job);
  EXPECT(same_result(&r.res, &a.res, w->s.tri_count));
  render_fini(&a);
  render_fini(&r);
}

int main(void) {
  struct world w;
  if (!testing_load_world(&w.s, &w.kd, RTSIM_SOURCE_DIR "/scenes/small/room.yaml")) return 1;
  check_interface(&w);
  /* Sizes that leave partial tiles, so tiles differ in work. */
  check_policy(&w, POLICY_RECURSIVE, 23, 17);
  check_policy(&w, POLICY_PACKET, 23, 17);
  check_policy(&w, POLICY_DYNAMIC, 23, 17);
  check_policy(&w, POLICY_TREELET, 23, 17);
  kd_fini(&w.kd);
  scene_fini(&w.s);
  return testing_done("test_policy_workers");
}
