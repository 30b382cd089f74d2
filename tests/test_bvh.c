/* BVH tests. Oracles: the triangles themselves (each in exactly one leaf, each
 * child box the union of its subtree's triangle bounds for the binary BVH and
 * containing it after quantization for the 8-wide one), brute force over all
 * triangles (same primitive and bit-identical t, b1, b2 from trace_closest,
 * same answer from trace_any, on random rays including axis-parallel ones and
 * ones starting inside), the k-d tree's rendered image (the same sums in every
 * pixel), and the layout: every access of a BVH render lands in its region at
 * its record's stride and class. */
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "renderer/bvh.h"
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

struct exact {
  float lo[3], hi[3];
};

static void exact_empty(struct exact *b) {
  for (int a = 0; a < 3; a++) {
    b->lo[a] = FLT_MAX;
    b->hi[a] = -FLT_MAX;
  }
}

static void exact_leaf(const struct scene *s, const struct bvh *b, uint32_t first, uint32_t count,
                       uint32_t *seen, struct exact *out) {
  exact_empty(out);
  for (uint32_t j = first; j < first + count; j++) {
    const uint32_t p = b->prims[j];
    EXPECT(p < s->tri_count);
    if (p >= s->tri_count) continue;
    seen[p]++;
    for (int k = 0; k < 3; k++)
      for (int a = 0; a < 3; a++) {
        const float x = v3_get(s->tris[p].v[k], a);
        out->lo[a] = fminf(out->lo[a], x);
        out->hi[a] = fmaxf(out->hi[a], x);
      }
  }
}

static void exact_grow(struct exact *b, const struct exact *o) {
  for (int a = 0; a < 3; a++) {
    b->lo[a] = fminf(b->lo[a], o->lo[a]);
    b->hi[a] = fmaxf(b->hi[a], o->hi[a]);
  }
}

/* The exact box of binary node ni's subtree; checks each child box equals
 * its subtree's, leaves' sizes, and the depth bound. Recursion is fine here:
 * the depth is at most BVH_DEPTH_LIMIT. */
static struct exact walk2(const struct scene *s, const struct bvh *b, uint32_t ni, uint32_t depth,
                          uint32_t *seen, uint32_t *visits) {
  struct exact box;
  exact_empty(&box);
  EXPECT(ni < b->node_count && depth < BVH_DEPTH_LIMIT);
  if (ni >= b->node_count || depth >= BVH_DEPTH_LIMIT) return box;
  visits[ni]++;
  const struct bvh2_node *nd = &b->n2[ni];
  for (int k = 0; k < 2; k++) {
    if (nd->count[k] == BVH_EMPTY) continue;
    struct exact c;
    if (nd->count[k] == 0) {
      c = walk2(s, b, nd->ref[k], depth + 1, seen, visits);
    } else {
      EXPECT(nd->count[k] <= BVH_LEAF_MAX);
      exact_leaf(s, b, nd->ref[k], nd->count[k], seen, &c);
    }
    for (int a = 0; a < 3; a++) EXPECT(nd->lo[k][a] == c.lo[a] && nd->hi[k][a] == c.hi[a]);
    exact_grow(&box, &c);
  }
  return box;
}

/* The same for a BVH8 node: the dequantized child boxes contain the exact
 * ones (and counts the slack they add, in units of the node's extent). */
static struct exact walk8(const struct scene *s, const struct bvh *b, uint32_t ni, uint32_t depth,
                          uint32_t *seen, uint32_t *visits, double *slack_sum, uint64_t *slack_n) {
  struct exact box;
  exact_empty(&box);
  EXPECT(ni < b->node_count && depth < BVH_DEPTH_LIMIT);
  if (ni >= b->node_count || depth >= BVH_DEPTH_LIMIT) return box;
  visits[ni]++;
  const struct bvh8_node *nd = &b->n8[ni];
  uint32_t interior = 0;
  for (int k = 0; k < 8; k++) {
    bool in;
    uint32_t ref, count;
    if (!bvh8_child(nd, k, &in, &ref, &count)) continue;
    EXPECT(((nd->imask >> k) & 1u) == (in ? 1u : 0u));
    struct exact c;
    if (in) {
      EXPECT(ref == nd->child_base + interior);
      interior++;
      c = walk8(s, b, ref, depth + 1, seen, visits, slack_sum, slack_n);
    } else {
      EXPECT(count >= 1 && count <= BVH_LEAF_MAX);
      exact_leaf(s, b, ref, count, seen, &c);
    }
    for (int a = 0; a < 3; a++) {
      const float sc = bvh8_scale(nd->e[a]);
      const float lo = bvh8_plane(nd->p[a], nd->qlo[a][k], sc);
      const float hi = bvh8_plane(nd->p[a], nd->qhi[a][k], sc);
      EXPECTF(lo <= c.lo[a] && hi >= c.hi[a], "node %u slot %d axis %d: [%g, %g] vs [%g, %g]", ni,
              k, a, lo, hi, c.lo[a], c.hi[a]);
      *slack_sum += ((double)c.lo[a] - lo + (double)hi - c.hi[a]) / (255.0 * sc);
      ++*slack_n;
    }
    exact_grow(&box, &c);
  }
  return box;
}

/* Every triangle in exactly one leaf, every node reached once, root box exact. */
static void check_structure(const struct scene *s, const struct bvh *b, const char *what) {
  uint32_t *seen = calloc(s->tri_count + 1, sizeof *seen);
  uint32_t *visits = calloc(b->node_count + 1, sizeof *visits);
  double slack = 0;
  uint64_t slack_n = 0;
  struct exact root = b->kind == ACCEL_BVH2 ? walk2(s, b, 0, 0, seen, visits)
                                            : walk8(s, b, 0, 0, seen, visits, &slack, &slack_n);
  uint32_t bad = 0;
  for (uint32_t p = 0; p < s->tri_count; p++) bad += seen[p] != 1;
  EXPECTF(bad == 0, "%s: %u triangles not in exactly one leaf", what, bad);
  bad = 0;
  for (uint32_t i = 0; i < b->node_count; i++) bad += visits[i] != 1;
  EXPECTF(bad == 0, "%s: %u nodes not reached exactly once", what, bad);
  EXPECT(b->prim_count == s->tri_count);
  EXPECT(root.lo[0] == b->lo.x && root.lo[1] == b->lo.y && root.lo[2] == b->lo.z);
  EXPECT(root.hi[0] == b->hi.x && root.hi[1] == b->hi.y && root.hi[2] == b->hi.z);
  EXPECT(b->stats.max_leaf_prims <= BVH_LEAF_MAX && b->stats.max_depth <= BVH_DEPTH_LIMIT);
  if (slack_n)
    printf("%s: %u nodes, %u leaves, depth %u, quantization slack %.3f steps a plane\n", what,
           b->stats.nodes, b->stats.leaves, b->stats.max_depth, slack / (double)slack_n * 255.0);
  else
    printf("%s: %u nodes, %u leaves, depth %u\n", what, b->stats.nodes, b->stats.leaves,
           b->stats.max_depth);
  free(seen);
  free(visits);
}

/* ---- scenes ---------------------------------------------------------------- */

static float rnd(struct rng *g, float lo, float hi) { return lo + (hi - lo) * rng_f32(g); }
static vec3 rnd_v3(struct rng *g, float lo, float hi) {
  const float z = rnd(g, lo, hi);
  const float y = rnd(g, lo, hi);
  const float x = rnd(g, lo, hi);
  return v3(x, y, z);
}

/* Random triangles in [-1,1]^3: small, a tenth large, some degenerate, some
 * duplicated, some in the plane z = 0.25 (coplanar, hit at equal t). */
static void soup(struct scene *s, uint64_t seed, int n) {
  struct rng g = rng_make(seed, 1);
  for (int i = 0; i < n; i++) {
    const vec3 c = rnd_v3(&g, -1, 1);
    const float sz = i % 10 == 0 ? 1.0f : rnd(&g, 0.02f, 0.25f);
    vec3 v[3];
    for (int k = 0; k < 3; k++) v[k] = v3_add(c, rnd_v3(&g, -sz, sz));
    if (i % 37 == 0) v[2] = v[1];
    if (i % 13 == 0)
      for (int k = 0; k < 3; k++) v[k].z = 0.25f;
    scene_add_tri(s, v[0], v[1], v[2], NULL, 0);
    if (i % 29 == 0) scene_add_tri(s, v[0], v[1], v[2], NULL, 0);
  }
}

/* ---- traversal against brute force ----------------------------------------- */

static uint32_t fbits(float f) {
  uint32_t u;
  memcpy(&u, &f, sizeof u);
  return u;
}

/* n random rays through s's box (a third axis-parallel in some component,
 * some starting inside), traced through b and by brute force. */
static void check_rays(const struct scene *s, const struct bvh *b, uint64_t seed, int n,
                       const char *what) {
  struct trace_ctx tr;
  trace_init(&tr, s, NULL, mem_port_native(), NULL);
  tr.bvh = b;
  vec3 lo, hi;
  scene_bounds(s, &lo, &hi);
  const vec3 c = v3_scale(v3_add(lo, hi), 0.5f), ext = v3_sub(hi, lo);
  const float r = fmaxf(ext.x, fmaxf(ext.y, ext.z));
  struct rng g = rng_make(seed, 2);
  int bad = 0, bad_any = 0, hits = 0, ties = 0;
  for (int i = 0; i < n; i++) {
    struct ray ray;
    memset(&ray, 0, sizeof ray);
    const bool inside = i % 3 == 0;
    ray.o = v3_add(c, rnd_v3(&g, inside ? -0.5f * r : -1.5f * r, inside ? 0.5f * r : 1.5f * r));
    const vec3 to = v3_add(c, rnd_v3(&g, -0.5f * r, 0.5f * r));
    ray.d = inside ? rnd_v3(&g, -1, 1) : v3_sub(to, ray.o);
    if (i % 5 == 1) ray.d.x = 0.0f;
    if (i % 7 == 2) ray.d.y = 0.0f, ray.d.z = 0.0f;
    ray.tmin = 0.0f;
    ray.tmax = i % 11 == 3 ? 0.5f : INFINITY;
    ray.ignore_prim = i % 4 == 0 ? (int32_t)(i % s->tri_count) : -1;
    ray.hit_prim = -1;
    struct trace_hit hb, hr;
    const bool fb = trace_closest(&tr, &ray, &hb), fr = trace_brute(s, &ray, &hr);
    if (fb != fr || hb.prim != hr.prim || fbits(hb.t) != fbits(hr.t) ||
        fbits(hb.b1) != fbits(hr.b1) || fbits(hb.b2) != fbits(hr.b2)) {
      if (bad < 5)
        fprintf(stderr, "%s ray %d: bvh %d t=%a, brute %d t=%a\n", what, i, hb.prim, hb.t, hr.prim,
                hr.t);
      bad++;
    }
    bad_any += trace_any(&tr, &ray) != fr;
    hits += fr;
    /* A tie: another triangle hit at the winner's t (the rule takes the
     * smaller id, in every structure and in brute force alike). */
    if (fr) {
      struct ray r2 = ray;
      r2.ignore_prim = hr.prim;
      struct trace_hit h2;
      if (ray.ignore_prim < 0 && trace_brute(s, &r2, &h2) && h2.t == hr.t) ties++;
    }
  }
  EXPECTF(bad == 0, "%s: %d of %d rays differ from brute force", what, bad, n);
  EXPECTF(bad_any == 0, "%s: %d any-hit answers differ", what, bad_any);
  EXPECT(hits > n / 10);
  printf("%s: %d rays, %d hits, %d tied hits (same answer)\n", what, n, hits, ties);
}

/* ---- the layout a render's accesses see ------------------------------------ */

struct layout_check {
  struct trace_layout l;
  const struct bvh *b;
  uint32_t tris;
  uint64_t nodes, entries, geometry, bad;
};

static void lc_load(void *ctx, uint64_t addr, uint32_t size, unsigned cls) {
  struct layout_check *c = ctx;
  const uint64_t nb = c->b->kind == ACCEL_BVH8 ? 80 : 64;
  if (addr >= c->l.node_base && addr < c->l.node_base + nb * c->b->node_count) {
    c->nodes++;
    c->bad += cls != TRACE_CLASS_NODE || size != nb || (addr - c->l.node_base) % nb != 0;
  } else if (addr >= c->l.prim_idx_base && addr < c->l.prim_idx_base + 4ull * c->b->prim_count) {
    c->entries++;
    c->bad += cls != TRACE_CLASS_NODE || size != 4 || (addr - c->l.prim_idx_base) % 4 != 0;
  } else if (addr >= c->l.tri_base && addr < c->l.tri_base + (uint64_t)c->l.tri_bytes * c->tris) {
    c->geometry++;
    c->bad += cls != TRACE_CLASS_GEOMETRY || size != c->l.tri_bytes;
  } else if (cls == TRACE_CLASS_NODE || cls == TRACE_CLASS_GEOMETRY) {
    c->bad++; /* scene data outside its regions */
  }
}
static void lc_store(void *ctx, uint64_t addr, uint32_t size, unsigned cls) {
  (void)addr;
  (void)size;
  struct layout_check *c = ctx;
  c->bad += cls == TRACE_CLASS_NODE || cls == TRACE_CLASS_GEOMETRY; /* read-only data */
}

/* ---- render: the same image from every structure --------------------------- */

static void render(const struct scene *s, const struct kd_tree *kd, const struct bvh *b,
                   struct mem_port port, struct framebuffer *fb, struct trace_stats *ts) {
  struct shade_ctx sc = {s, RAY_MASK(RAY_TYPE_COUNT) - 1, s->seed, 0};
  fb_init(fb, 24, 24, 0);
  struct policy_setup ps;
  testing_policy_setup(&ps, s, kd, &sc, fb);
  ps.bvh = b;
  fb->base_addr = ps.layout.fb_base;
  struct policy_params pp;
  policy_params_default(&pp);
  struct render_stats st;
  policy_run(POLICY_RECURSIVE, &ps, &pp, port, &st, ts);
}

static void check_scene(const char *name) {
  struct scene s;
  struct kd_tree kd;
  if (!testing_load_small(&s, &kd, name)) return;
  struct framebuffer ref;
  struct trace_stats tk;
  render(&s, &kd, NULL, mem_port_native(), &ref, &tk);
  for (int k = ACCEL_BVH2; k <= ACCEL_BVH8; k++) {
    char what[64];
    snprintf(what, sizeof what, "%s %s", name, accel_names[k]);
    struct bvh b;
    bvh_build(&b, &s, (enum accel_kind)k);
    check_structure(&s, &b, what);
    check_rays(&s, &b, 7u + (uint64_t)k, 3000, what);
    struct layout_check lc = {.b = &b, .tris = s.tri_count};
    trace_layout_default(&lc.l);
    static const struct mem_ops ops = {.load = lc_load, .store = lc_store};
    struct framebuffer fb;
    struct trace_stats tb;
    render(&s, &kd, &b, (struct mem_port){&ops, &lc}, &fb, &tb);
    uint32_t diff = 0;
    for (uint32_t i = 0; i < 3u * fb.width * fb.height; i++) diff += fb.acc[i] != ref.acc[i];
    EXPECTF(diff == 0, "%s: %u pixel sums differ from the k-d tree's image", what, diff);
    EXPECTF(lc.bad == 0, "%s: %llu accesses outside their region, stride or class", what,
            (unsigned long long)lc.bad);
    EXPECT(lc.nodes == tb.node_visits && lc.geometry == tb.tri_tests && lc.entries >= lc.geometry);
    printf("%s: image equal to kd's; node visits %llu (kd %llu), triangle tests %llu (kd %llu)\n",
           what, (unsigned long long)tb.node_visits, (unsigned long long)tk.node_visits,
           (unsigned long long)tb.tri_tests, (unsigned long long)tk.tri_tests);
    fb_fini(&fb);
    bvh_fini(&b);
  }
  fb_fini(&ref);
  kd_fini(&kd);
  scene_fini(&s);
}

/* Hand-made: one triangle (a root leaf), four in a row (one split), none. */
static void check_tiny(void) {
  for (int n = 0; n <= 4; n += 1) {
    struct scene s;
    scene_init(&s);
    for (int i = 0; i < n; i++)
      scene_add_tri(&s, v3((float)i, 0, 0), v3((float)i + 0.5f, 0, 0), v3((float)i, 1, 0), NULL, 0);
    for (int k = ACCEL_BVH2; k <= ACCEL_BVH8; k++) {
      struct bvh b;
      bvh_build(&b, &s, (enum accel_kind)k);
      EXPECT(n == 0 ? b.node_count == 0 : b.node_count >= 1);
      if (n > 0) {
        check_structure(&s, &b, n == 1 ? "one triangle" : "a row");
        struct trace_ctx tr;
        trace_init(&tr, &s, NULL, mem_port_native(), NULL);
        tr.bvh = &b;
        for (int i = 0; i < n; i++) {
          struct ray r = testing_make_ray((float)i + 0.1f, 0.2f, 1, 0, 0, -1, 0, INFINITY);
          struct trace_hit h;
          EXPECT(trace_closest(&tr, &r, &h) && h.prim == i && h.t == 1.0f);
        }
      } else {
        struct trace_ctx tr;
        trace_init(&tr, &s, NULL, mem_port_native(), NULL);
        tr.bvh = &b;
        struct ray r = testing_make_ray(0, 0, 1, 0, 0, -1, 0, INFINITY);
        struct trace_hit h;
        EXPECT(!trace_closest(&tr, &r, &h) && h.prim == -1);
      }
      bvh_fini(&b);
    }
    scene_fini(&s);
  }
}

int main(void) {
  check_tiny();
  for (uint64_t seed = 1; seed <= 3; seed++) {
    struct scene s;
    scene_init(&s);
    soup(&s, seed, seed == 3 ? 3000 : 400);
    for (int k = ACCEL_BVH2; k <= ACCEL_BVH8; k++) {
      char what[64];
      snprintf(what, sizeof what, "soup %llu %s", (unsigned long long)seed, accel_names[k]);
      struct bvh b;
      bvh_build(&b, &s, (enum accel_kind)k);
      check_structure(&s, &b, what);
      check_rays(&s, &b, seed * 10 + (uint64_t)k, 4000, what);
      bvh_fini(&b);
    }
    scene_fini(&s);
  }
  check_scene("room");
  check_scene("grove");
  check_scene("sphereflake");
  return testing_done("bvh");
}
