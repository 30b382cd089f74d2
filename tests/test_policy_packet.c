/* The packet policy and packet traversal, on the k-d tree and on each BVH.
 * Oracles: single-ray traversal (each ray of a packet must get bit for bit
 * the hit trace_closest / trace_any gives it alone), the recursive policy
 * (same framebuffer, same ray counts), and a counting memory port (coherent
 * primary packets load fewer triangle records; every ray written to a packet
 * buffer is read back once). */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "renderer/bvh.h"
#include "renderer/camera.h"
#include "renderer/framebuffer.h"
#include "renderer/kdtree.h"
#include "renderer/policy/policy.h"
#include "renderer/ray.h"
#include "renderer/rng.h"
#include "renderer/scene.h"
#include "renderer/scene/scene_file.h"
#include "renderer/shade.h"
#include "renderer/trace.h"
#include "sim/err.h"
#include "testing.h"

#define ALL_RAYS                                                                                   \
  (RAY_MASK(RAY_PRIMARY) | RAY_MASK(RAY_SHADOW) | RAY_MASK(RAY_SPECULAR) | RAY_MASK(RAY_DIFFUSE))

struct world {
  const char *name; /* the scene and the structure traced */
  struct scene s;
  struct kd_tree kd;
  const struct bvh *bvh; /* traced instead of kd when not NULL */
};

static int load(struct world *w, const char *name) {
  w->name = name;
  w->bvh = NULL;
  return testing_load_small(&w->s, &w->kd, name);
}

/* A memory port that counts loads and stores by class, and checks that ray
 * traffic stays in the ray region. */
struct counts {
  uint64_t loads[TRACE_CLASS_COUNT], load_bytes[TRACE_CLASS_COUNT];
  uint64_t stores[TRACE_CLASS_COUNT];
  uint64_t ray_lo, ray_hi; /* allowed ray addresses (packet buffers) */
  uint64_t cam_lo, cam_hi; /* the camera's primary rays: loads only */
  uint64_t cam_loads, ray_outside;
};

static void count_load(void *ctx, uint64_t addr, uint32_t size, unsigned cls) {
  struct counts *c = ctx;
  c->loads[cls]++;
  c->load_bytes[cls] += size;
  if (cls == TRACE_CLASS_RAY && addr >= c->cam_lo && addr + size <= c->cam_hi && size == 64) {
    c->cam_loads++;
    return;
  }
  if (cls == TRACE_CLASS_RAY && (addr < c->ray_lo || addr + size > c->ray_hi)) c->ray_outside++;
}

static void count_store(void *ctx, uint64_t addr, uint32_t size, unsigned cls) {
  struct counts *c = ctx;
  c->stores[cls]++;
  if (cls == TRACE_CLASS_RAY && (addr < c->ray_lo || addr + size > c->ray_hi)) c->ray_outside++;
}

static const struct mem_ops COUNT_OPS = {count_load, count_store, NULL, NULL, NULL, NULL};

static int same_hit(const struct trace_hit *a, const struct trace_hit *b) {
  return a->prim == b->prim && memcmp(&a->t, &b->t, sizeof a->t) == 0 &&
         memcmp(&a->b1, &b->b1, sizeof a->b1) == 0 && memcmp(&a->b2, &b->b2, sizeof a->b2) == 0;
}

struct cmp_stats {
  int packets, rays, hits, mismatches;
};

/* Trace rays[0..n) as one packet, closest and any, and compare every ray with
 * its single-ray query. Also: per-ray triangle tests add up to the tracer's. */
static void compare_packet(struct trace_ctx *tr, struct trace_packet *pk, const struct ray *rays,
                           uint32_t n, const char *what, struct cmp_stats *cs) {
  struct trace_hit ph[TRACE_PACKET_MAX], sh;
  bool pocc[TRACE_PACKET_MAX];
  struct trace_packet_cost cost;
  uint64_t tris0 = tr->stats.tri_tests;
  trace_packet_closest(tr, pk, rays, n, ph, &cost);
  uint64_t sum = 0;
  for (uint32_t i = 0; i < n; i++) sum += cost.tris[i];
  EXPECTF(sum == tr->stats.tri_tests - tris0, "%s: per-ray tri tests %llu, tracer %llu", what,
          (unsigned long long)sum, (unsigned long long)(tr->stats.tri_tests - tris0));
  trace_packet_any(tr, pk, rays, n, pocc, NULL);
  cs->packets++;
  for (uint32_t i = 0; i < n; i++) {
    bool hit = trace_closest(tr, &rays[i], &sh);
    bool occ = trace_any(tr, &rays[i]);
    cs->rays++;
    cs->hits += hit;
    if (!same_hit(&ph[i], &sh) || pocc[i] != occ) {
      if (cs->mismatches < 10)
        fprintf(stderr,
                "%s ray %u: packet prim %d t %.9g b %.9g %.9g occ %d; single prim %d t %.9g "
                "b %.9g %.9g occ %d\n",
                what, i, ph[i].prim, ph[i].t, ph[i].b1, ph[i].b2, pocc[i], sh.prim, sh.t, sh.b1,
                sh.b2, occ);
      cs->mismatches++;
    }
  }
}

static struct ray make_ray(vec3 o, vec3 d, float tmin, float tmax) {
  return testing_make_ray(o.x, o.y, o.z, d.x, d.y, d.z, tmin, tmax);
}

static float rnd(struct rng *g, float lo, float hi) { return lo + (hi - lo) * rng_f32(g); }

/* NOTE: a vector's draws one a statement, z first (the cases were tuned with
 * gcc, which took v3's three arguments last first; clang takes them first
 * first, and C leaves it open). */
static vec3 rnd_v3(struct rng *g, float lo, float hi) {
  float z = rnd(g, lo, hi);
  float y = rnd(g, lo, hi);
  float x = rnd(g, lo, hi);
  return v3(x, y, z);
}

static vec3 rnd_dir(struct rng *g) {
  for (;;) {
    vec3 d = rnd_v3(g, -1, 1);
    float l = v3_len(d);
    if (l > 0.05f && l <= 1.0f) return v3_scale(d, 1.0f / l);
  }
}

/* Sizes of partial and full packets used for every ray set. */
static const uint32_t SIZES[] = {1, 7, 64};

static void packets_of(struct trace_ctx *tr, struct trace_packet *pk, const struct ray *rays,
                       uint32_t count, const char *what, struct cmp_stats *cs) {
  char buf[128];
  for (uint32_t z = 0; z < sizeof SIZES / sizeof SIZES[0]; z++)
    for (uint32_t k = 0; k < count; k += SIZES[z]) {
      uint32_t n = count - k < SIZES[z] ? count - k : SIZES[z];
      snprintf(buf, sizeof buf, "%.80s (packets of %u, at %u)", what, SIZES[z], k);
      compare_packet(tr, pk, rays + k, n, buf, cs);
    }
}

#define SET_MAX 4096

/* Packet traversal equals single-ray traversal on one scene. */
static void test_traversal(struct world *w) {
  struct counts cnt;
  memset(&cnt, 0, sizeof cnt);
  cnt.ray_hi = UINT64_MAX;
  struct mem_port port = {&COUNT_OPS, &cnt};
  struct trace_ctx tr;
  trace_init(&tr, &w->s, &w->kd, port, NULL);
  tr.bvh = w->bvh;
  struct trace_packet *pk = trace_packet_create();
  struct ray *set = xmalloc(SET_MAX * sizeof *set);
  struct cmp_stats cs;
  memset(&cs, 0, sizeof cs);
  struct rng g = rng_make(99, 1);
  vec3 lo = w->kd.lo, hi = w->kd.hi, ext = v3_sub(hi, lo);
  float diag = v3_len(ext);
  char what[128];

  /* Coherent: 8x8 camera tiles of a 64x64 image, packet by packet. A tile's
   * packet fetches fewer nodes than its 64 rays do one by one. */
  {
    struct camera_frame cf;
    camera_frame_init(&cf, &w->s.camera, 64, 64);
    uint32_t n = 0;
    for (uint32_t ty = 0; ty < 8; ty++)
      for (uint32_t tx = 0; tx < 8; tx++)
        for (uint32_t y = 0; y < 8; y++)
          for (uint32_t x = 0; x < 8; x++)
            camera_primary(&cf, tx * 8 + x, ty * 8 + y, 3, &set[n++]);
    snprintf(what, sizeof what, "%s camera", w->name);
    packets_of(&tr, pk, set, n, what, &cs);
    uint64_t fewer = 0, packet_total = 0, single_total = 0;
    for (uint32_t k = 0; k < n; k += 64) {
      struct trace_hit hits[64];
      struct trace_hit h;
      uint64_t n0 = cnt.loads[TRACE_CLASS_NODE];
      trace_packet_closest(&tr, pk, set + k, 64, hits, NULL);
      uint64_t packet_loads = cnt.loads[TRACE_CLASS_NODE] - n0;
      n0 = cnt.loads[TRACE_CLASS_NODE];
      for (uint32_t i = 0; i < 64; i++) trace_closest(&tr, &set[k + i], &h);
      fewer += packet_loads <= cnt.loads[TRACE_CLASS_NODE] - n0;
      packet_total += packet_loads;
      single_total += cnt.loads[TRACE_CLASS_NODE] - n0;
    }
    EXPECTF(fewer == n / 64 && packet_total < single_total,
            "%s: %llu of %u camera packets fetch no more nodes than their rays; %llu vs %llu",
            w->name, (unsigned long long)fewer, n / 64, (unsigned long long)packet_total,
            (unsigned long long)single_total);
  }

  /* Incoherent: random origins around the scene, random directions; finite
   * and infinite extents, some with tmin > 0. */
  {
    for (uint32_t i = 0; i < 2048; i++) {
      vec3 o = v3_add(lo, v3_mul(ext, rnd_v3(&g, -0.2f, 1.2f)));
      float tmax = (i % 3 == 0) ? INFINITY : rnd(&g, 0.0f, diag);
      float tmin = (i % 5 == 0) ? rnd(&g, 0.0f, 0.3f * diag) : 0.0f;
      if (!(tmin < tmax)) tmin = 0.0f;
      set[i] = make_ray(o, rnd_dir(&g), tmin, tmax);
    }
    snprintf(what, sizeof what, "%s random", w->name);
    packets_of(&tr, pk, set, 2048, what, &cs);
  }

  /* Axis-parallel rays (the flat traversal path), degenerate and invalid rays,
   * rays that miss the root box, mixed into packets with ordinary ones. */
  {
    uint32_t n = 0;
    static const float axes[6][3] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},
                                     {0, -1, 0}, {0, 0, 1},  {0, 0, -1}};
    for (uint32_t i = 0; i < 384; i++) {
      vec3 o = v3_add(lo, v3_mul(ext, rnd_v3(&g, 0.0f, 1.0f)));
      const float *a = axes[i % 6];
      switch (i % 8) {
      case 0: set[n++] = make_ray(o, v3(0, 0, 0), 0, INFINITY); break;   /* no direction */
      case 1: set[n++] = make_ray(o, v3(NAN, 0, 1), 0, INFINITY); break; /* NaN */
      case 2: set[n++] = make_ray(o, v3(0, 0, 1), 1.0f, 1.0f); break;    /* empty extent */
      case 3: /* beside the box, pointing away */
        set[n++] = make_ray(v3_add(hi, v3(1, 1, 1)), v3(1, 0.5f, 0.25f), 0, INFINITY);
        break;
      case 4: /* diagonal in a plane: flat on one axis */
        set[n++] = make_ray(o, v3(a[0] + a[1], a[1] + a[2], a[2] + a[0]), 0, INFINITY);
        break;
      default: set[n++] = make_ray(o, v3(a[0], a[1], a[2]), 0, INFINITY); break;
      }
    }
    snprintf(what, sizeof what, "%s axis-parallel and invalid", w->name);
    packets_of(&tr, pk, set, n, what, &cs);
  }

  /* Secondary rays from real hits (ignore_prim set, finite tmax for shadow
   * rays), grouped by type and slot as the packet policy groups them, and also
   * all mixed together. */
  {
    struct framebuffer fb;
    fb_init(&fb, 64, 64, 0);
    struct shade_ctx sc = {&w->s, ALL_RAYS, 5, 0};
    struct camera_frame cf;
    camera_frame_init(&cf, &w->s.camera, 64, 64);
    struct ray spawn[SHADE_MAX_SPAWN];
    struct ray *by_kind = xmalloc(SET_MAX * sizeof *by_kind);
    uint32_t n = 0;
    for (uint32_t pix = 0; pix < 64 * 64 && n + SHADE_MAX_SPAWN <= SET_MAX; pix += 3) {
      struct ray r;
      camera_primary(&cf, pix % 64, pix / 64, 5, &r);
      struct trace_hit h;
      trace_closest(&tr, &r, &h);
      uint32_t k = shade_hit(&sc, &r, &h, &fb, &tr.mem, spawn);
      for (uint32_t j = 0; j < k; j++) set[n++] = spawn[j];
    }
    /* Stable sort by (type, light): packets of like rays, as the policy makes. */
    uint32_t m = 0;
    for (uint32_t type = 0; type < RAY_TYPE_COUNT; type++)
      for (uint32_t light = 0; light < SCENE_MAX_LIGHTS; light++)
        for (uint32_t i = 0; i < n; i++)
          if (set[i].type == type && set[i].light == light) by_kind[m++] = set[i];
    CHECK_EQ(m, n);
    snprintf(what, sizeof what, "%s secondary by kind", w->name);
    packets_of(&tr, pk, by_kind, m, what, &cs);
    snprintf(what, sizeof what, "%s secondary mixed", w->name);
    packets_of(&tr, pk, set, n, what, &cs);

    /* Rays leaving a hit with ignore_prim = that triangle and a random direction. */
    uint32_t q = 0;
    for (uint32_t i = 0; i < n && q < 1024; i++) {
      if (set[i].ignore_prim < 0) continue;
      struct ray r = set[i];
      r.d = rnd_dir(&g);
      r.tmax = (q % 2) ? INFINITY : rnd(&g, 0.0f, 0.5f * diag);
      by_kind[q++] = r;
    }
    snprintf(what, sizeof what, "%s ignore_prim", w->name);
    packets_of(&tr, pk, by_kind, q, what, &cs);
    free(by_kind);
    fb_fini(&fb);
  }
  EXPECTF(cs.mismatches == 0, "%s: %d of %d rays differ between packet and single traversal",
          w->name, cs.mismatches, cs.rays);
  EXPECTF(cs.hits > cs.rays / 10, "%s: only %d hits in %d rays", w->name, cs.hits, cs.rays);
  fprintf(stderr, "%s: %d packets, %d rays, %d hits, %d mismatches\n", w->name, cs.packets, cs.rays,
          cs.hits, cs.mismatches);
  free(set);
  trace_packet_destroy(pk);
}

struct run {
  struct framebuffer fb;
  struct render_stats st;
  struct trace_stats ts;
  struct counts cnt;
};

static void render(struct world *w, enum policy_kind k, uint32_t mask, uint32_t width,
                   uint32_t height, struct run *out) {
  memset(out, 0, sizeof *out);
  struct trace_layout l;
  trace_layout_default(&l);
  out->cnt.ray_lo = l.ray_base;
  out->cnt.ray_hi = l.ray_base + (1ull << 24);
  out->cnt.cam_lo = l.camera_base;
  out->cnt.cam_hi = l.camera_base + 64ull * width * height;
  struct mem_port port = {&COUNT_OPS, &out->cnt};
  struct shade_ctx sc = {&w->s, mask, 7, 0};
  fb_init(&out->fb, width, height, l.fb_base);
  struct policy_setup ps;
  testing_policy_setup(&ps, &w->s, &w->kd, &sc, &out->fb);
  ps.bvh = w->bvh;
  struct policy_params pp;
  policy_params_default(&pp);
  policy_run(k, &ps, &pp, port, &out->st, &out->ts);
}

/* The packet policy's picture and ray counts equal the recursive policy's. */
static void test_policy(struct world *w, uint32_t width, uint32_t height) {
  struct run rec, pkt, again;
  render(w, POLICY_RECURSIVE, ALL_RAYS, width, height, &rec);
  render(w, POLICY_PACKET, ALL_RAYS, width, height, &pkt);
  uint64_t npix = (uint64_t)width * height;
  EXPECTF(memcmp(rec.fb.acc, pkt.fb.acc, 3 * npix * sizeof *rec.fb.acc) == 0,
          "%s %ux%u: packet framebuffer differs from recursive", w->name, width, height);
  for (int t = 0; t < RAY_TYPE_COUNT; t++)
    EXPECTF(rec.st.rays[t] == pkt.st.rays[t], "%s %ux%u: %d rays of type %d, recursive %llu",
            w->name, width, height, (int)pkt.st.rays[t], t, (unsigned long long)rec.st.rays[t]);
  EXPECT(pkt.st.spawned == pkt.st.terminated && pkt.st.spawned == rec.st.spawned);
  EXPECT(pkt.st.rays[RAY_PRIMARY] == npix);
  /* Every primary ray is read from the camera's array once; every ray written
   * to a packet buffer is read back once, inside the region. */
  uint64_t total = render_stats_total(&pkt.st);
  EXPECT(pkt.cnt.cam_loads == npix && rec.cnt.cam_loads == npix);
  EXPECTF(pkt.cnt.stores[TRACE_CLASS_RAY] == total &&
              pkt.cnt.loads[TRACE_CLASS_RAY] == total + npix,
          "%s: ray stores %llu loads %llu rays %llu", w->name,
          (unsigned long long)pkt.cnt.stores[TRACE_CLASS_RAY],
          (unsigned long long)pkt.cnt.loads[TRACE_CLASS_RAY], (unsigned long long)total);
  EXPECT(pkt.cnt.ray_outside == 0);
  /* The per-pixel costs account for all of the packet's ray/triangle tests. */
  uint64_t tris = 0, nodes = 0;
  for (uint64_t i = 0; i < npix; i++) {
    tris += pkt.fb.cost_tris[i];
    nodes += pkt.fb.cost_nodes[i];
  }
  EXPECT(tris == pkt.ts.tri_tests);
  EXPECT(nodes >= pkt.ts.node_visits);
  /* Deterministic. */
  render(w, POLICY_PACKET, ALL_RAYS, width, height, &again);
  EXPECT(memcmp(again.fb.acc, pkt.fb.acc, 3 * npix * sizeof *pkt.fb.acc) == 0);
  EXPECT(memcmp(again.fb.cost_nodes, pkt.fb.cost_nodes, npix * sizeof *pkt.fb.cost_nodes) == 0);
  EXPECT(memcmp(again.fb.cost_tris, pkt.fb.cost_tris, npix * sizeof *pkt.fb.cost_tris) == 0);
  EXPECT(memcmp(&again.cnt, &pkt.cnt, sizeof pkt.cnt) == 0);
  fb_fini(&rec.fb);
  fb_fini(&pkt.fb);
  fb_fini(&again.fb);
}

/* Coherence: primary packets load fewer triangle records and nodes. */
static void test_coherence(struct world *w) {
  struct run rec, pkt;
  render(w, POLICY_RECURSIVE, RAY_MASK(RAY_PRIMARY), 64, 64, &rec);
  render(w, POLICY_PACKET, RAY_MASK(RAY_PRIMARY), 64, 64, &pkt);
  EXPECT(memcmp(rec.fb.acc, pkt.fb.acc, 3 * 64 * 64 * sizeof *rec.fb.acc) == 0);
  EXPECTF(pkt.cnt.loads[TRACE_CLASS_GEOMETRY] < rec.cnt.loads[TRACE_CLASS_GEOMETRY],
          "%s: packet loads %llu triangle records, recursive %llu", w->name,
          (unsigned long long)pkt.cnt.loads[TRACE_CLASS_GEOMETRY],
          (unsigned long long)rec.cnt.loads[TRACE_CLASS_GEOMETRY]);
  EXPECT(pkt.cnt.loads[TRACE_CLASS_NODE] < rec.cnt.loads[TRACE_CLASS_NODE]);
  /* Primary rays mostly visit nodes in their own order: about the same tests. */
  EXPECTF(pkt.ts.tri_tests <= rec.ts.tri_tests + rec.ts.tri_tests / 10,
          "%s: %llu tests, recursive %llu", w->name, (unsigned long long)pkt.ts.tri_tests,
          (unsigned long long)rec.ts.tri_tests);
  fprintf(stderr,
          "%s primary 64x64: triangle loads %llu (recursive %llu), node loads %llu (%llu)\n",
          w->name, (unsigned long long)pkt.cnt.loads[TRACE_CLASS_GEOMETRY],
          (unsigned long long)rec.cnt.loads[TRACE_CLASS_GEOMETRY],
          (unsigned long long)pkt.cnt.loads[TRACE_CLASS_NODE],
          (unsigned long long)rec.cnt.loads[TRACE_CLASS_NODE]);
  fb_fini(&rec.fb);
  fb_fini(&pkt.fb);
}

int main(void) {
  static const char *const NAMES[] = {"sphereflake", "grove", "room"};
  for (int k = 0; k < 3; k++) {
    struct world w;
    if (!load(&w, NAMES[k])) {
      EXPECTF(0, "cannot load %s", NAMES[k]);
      continue;
    }
    test_traversal(&w);
    test_policy(&w, 48, 48);
    test_policy(&w, 37, 21);
    test_coherence(&w);
    /* The same on each BVH. */
    const char *scene = w.name;
    for (int a = ACCEL_BVH2; a <= ACCEL_BVH8; a++) {
      struct bvh b;
      bvh_build(&b, &w.s, (enum accel_kind)a);
      char name[64];
      snprintf(name, sizeof name, "%s %s", scene, accel_names[a]);
      w.name = name;
      w.bvh = &b;
      test_traversal(&w);
      test_policy(&w, 48, 48);
      test_policy(&w, 37, 21);
      test_coherence(&w);
      w.bvh = NULL;
      w.name = scene;
      bvh_fini(&b);
    }
    kd_fini(&w.kd);
    scene_fini(&w.s);
  }
  return testing_done("test_policy_packet");
}
