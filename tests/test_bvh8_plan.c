/* The SAH collapse of the binary BVH into the 8-wide one (bvh8_plan.c).
 * Oracles: a hand-computed tree; brute force, which lists every way to cut
 * each subtree into at most 8 roots (each a leaf of <= BVH_LEAF_MAX triangles,
 * an 8-wide node, or cut further) and keeps the cheapest, on the binary BVHs
 * of small random soups; the built tree's own SAH cost (bvh_stats.sah_cost,
 * summed over its nodes and leaves as laid out) equal to the plan's; and the
 * greedy collapse, whose trees are among those the plan chooses from, so the
 * plan's never costs more. The trees' validity (every triangle in one leaf,
 * quantized boxes containing the exact ones, at most 8 children) is
 * tests/test_bvh.c's, on the default (SAH) collapse. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "renderer/bvh.h"
#include "renderer/bvh8_plan.h"
#include "renderer/kdtree.h"
#include "renderer/rng.h"
#include "renderer/scene.h"
#include "testing.h"

/* ---- brute force ------------------------------------------------------------ */

/* Every way of representing a subtree with n roots, and its cost. */
struct way {
  int n;
  double cost;
};
struct ways {
  struct way *w;
  size_t n, cap;
};

static void ways_add(struct ways *ws, int n, double cost) {
  if (ws->n == ws->cap) {
    ws->cap = ws->cap ? 2 * ws->cap : 16;
    ws->w = realloc(ws->w, ws->cap * sizeof *ws->w);
  }
  ws->w[ws->n++] = (struct way){n, cost};
}

static uint32_t tris_of(const struct bvh *b2, uint32_t ref, uint32_t count) {
  if (count) return count;
  const struct bvh2_node *nd = &b2->n2[ref];
  return tris_of(b2, nd->ref[0], nd->count[0]) + tris_of(b2, nd->ref[1], nd->count[1]);
}

static void all_ways(const struct bvh *b2, const float lo[3], const float hi[3], uint32_t ref,
                     uint32_t count, struct ways *out);

/* The cheapest 8-wide node made of binary node ni: its area plus the
 * cheapest combination of its children's ways with at most 8 roots. */
static double best_node(const struct bvh *b2, uint32_t ni, double area) {
  const struct bvh2_node *nd = &b2->n2[ni];
  struct ways l = {0}, r = {0};
  all_ways(b2, nd->lo[0], nd->hi[0], nd->ref[0], nd->count[0], &l);
  all_ways(b2, nd->lo[1], nd->hi[1], nd->ref[1], nd->count[1], &r);
  double best = INFINITY;
  for (size_t i = 0; i < l.n; i++)
    for (size_t j = 0; j < r.n; j++)
      if (l.w[i].n + r.w[j].n <= 8 && l.w[i].cost + r.w[j].cost < best)
        best = l.w[i].cost + r.w[j].cost;
  free(l.w);
  free(r.w);
  return area * BVH_SAH_NODE + best;
}

/* Every way (at most 8 roots) of the child with box [lo, hi] and (ref, count). */
static void all_ways(const struct bvh *b2, const float lo[3], const float hi[3], uint32_t ref,
                     uint32_t count, struct ways *out) {
  const double area = bvh_box_area(lo, hi);
  const uint32_t tris = tris_of(b2, ref, count);
  if (tris <= BVH_LEAF_MAX) ways_add(out, 1, area * BVH_SAH_PRIM * tris);
  if (count) return;
  ways_add(out, 1, best_node(b2, ref, area));
  const struct bvh2_node *nd = &b2->n2[ref];
  struct ways l = {0}, r = {0};
  all_ways(b2, nd->lo[0], nd->hi[0], nd->ref[0], nd->count[0], &l);
  all_ways(b2, nd->lo[1], nd->hi[1], nd->ref[1], nd->count[1], &r);
  for (size_t i = 0; i < l.n; i++)
    for (size_t j = 0; j < r.n; j++)
      if (l.w[i].n + r.w[j].n <= 8) ways_add(out, l.w[i].n + r.w[j].n, l.w[i].cost + r.w[j].cost);
  free(l.w);
  free(r.w);
}

/* The brute-force SAH cost of the best BVH8 of b2 (its root an 8-wide node),
 * relative to the root's area. */
static double brute_cost(const struct bvh *b2) {
  const float lo[3] = {b2->lo.x, b2->lo.y, b2->lo.z}, hi[3] = {b2->hi.x, b2->hi.y, b2->hi.z};
  const double area = bvh_box_area(lo, hi);
  double c;
  if (b2->n2[0].count[1] == BVH_EMPTY)
    c = area * BVH_SAH_NODE +
        bvh_box_area(b2->n2[0].lo[0], b2->n2[0].hi[0]) * BVH_SAH_PRIM * b2->n2[0].count[0];
  else c = best_node(b2, 0, area);
  return area > 0 ? c / area : c;
}

/* ---- scenes ------------------------------------------------------------------ */

/* n random triangles in [-1,1]^3, of sizes 0.02 to 0.5. */
static void soup(struct scene *s, uint64_t seed, int n) {
  struct rng g = rng_make(seed, 7);
  for (int i = 0; i < n; i++) {
    vec3 c = v3(2 * rng_f32(&g) - 1, 2 * rng_f32(&g) - 1, 2 * rng_f32(&g) - 1), v[3];
    const float sz = 0.02f + 0.48f * rng_f32(&g);
    for (int k = 0; k < 3; k++)
      v[k] = v3_add(c, v3(sz * (2 * rng_f32(&g) - 1), sz * (2 * rng_f32(&g) - 1),
                          sz * (2 * rng_f32(&g) - 1)));
    scene_add_tri(s, v[0], v[1], v[2], NULL, 0);
  }
}

static bool near(double a, double b) { return fabs(a - b) <= 1e-9 * fmax(1.0, fabs(b)); }

/* The plan, the built tree and brute force (when small) agree, and the greedy
 * tree costs no less. */
static void check_plan(const struct scene *s, const char *what, bool brute) {
  struct bvh b2, b8, g8;
  bvh_build(&b2, s, ACCEL_BVH2);
  struct bvh8_plan *p = bvh8_plan_create(&b2);
  bvh8_collapse_with(&b8, &b2, bvh8_plan_children, p);
  bvh8_collapse_with(&g8, &b2, bvh8_greedy_children, NULL);
  const double plan = bvh8_plan_cost(p);
  EXPECTF(near(b8.stats.sah_cost, plan), "%s: built %.12g, plan %.12g", what, b8.stats.sah_cost,
          plan);
  if (brute) {
    const double bf = brute_cost(&b2);
    EXPECTF(near(plan, bf), "%s: plan %.12g, brute force %.12g", what, plan, bf);
  }
  EXPECTF(b8.stats.sah_cost <= g8.stats.sah_cost * (1 + 1e-12), "%s: SAH %.6g, greedy %.6g", what,
          b8.stats.sah_cost, g8.stats.sah_cost);
  EXPECT(b8.prim_count == s->tri_count && b8.stats.max_leaf_prims <= BVH_LEAF_MAX);
  /* bvh_build's BVH8 is this plan's tree. */
  struct bvh d8;
  bvh_build(&d8, s, ACCEL_BVH8);
  EXPECT(d8.node_count == b8.node_count &&
         !memcmp(d8.n8, b8.n8, (size_t)b8.node_count * sizeof *b8.n8) &&
         !memcmp(d8.prims, b8.prims, (size_t)b8.prim_count * sizeof *b8.prims));
  if (!brute)
    printf("%s: SAH %.3f (%u nodes), greedy %.3f (%u nodes), BVH2 %.3f\n", what, b8.stats.sah_cost,
           b8.stats.nodes, g8.stats.sah_cost, g8.stats.nodes, b2.stats.sah_cost);
  bvh_fini(&d8);
  bvh_fini(&g8);
  bvh_fini(&b8);
  bvh8_plan_destroy(p);
  bvh_fini(&b2);
}

/* Two unit right triangles 10 apart in z = 0: a binary root of two leaves;
 * the 8-wide root holds both, costing 1 + 0.3 (1 + 1) / 11 (half areas: a
 * triangle's box 1 x 1, the root's 11 x 1). A third triangle on the first
 * makes that side a two-triangle leaf or two leaves, whichever is cheaper. */
static void check_hand(void) {
  struct scene s;
  scene_init(&s);
  scene_add_tri(&s, v3(0, 0, 0), v3(1, 0, 0), v3(0, 1, 0), NULL, 0);
  scene_add_tri(&s, v3(10, 0, 0), v3(11, 0, 0), v3(10, 1, 0), NULL, 0);
  struct bvh b2;
  bvh_build(&b2, &s, ACCEL_BVH2);
  EXPECT(b2.node_count == 1 && b2.n2[0].count[0] == 1 && b2.n2[0].count[1] == 1);
  struct bvh8_plan *p = bvh8_plan_create(&b2);
  EXPECTF(near(bvh8_plan_cost(p), 1.0 + 0.3 * 2.0 / 11.0), "two triangles: %.12g",
          bvh8_plan_cost(p));
  EXPECT(near(b2.stats.sah_cost, 1.0 + 0.3 * 2.0 / 11.0));
  bvh8_plan_destroy(p);
  bvh_fini(&b2);
  check_plan(&s, "two triangles", true);
  scene_fini(&s);
}

int main(void) {
  check_hand();
  for (uint64_t seed = 1; seed <= 40; seed++) {
    struct scene s;
    scene_init(&s);
    soup(&s, seed, 1 + (int)(seed % 20) + (seed > 30 ? 8 : 0));
    char what[64];
    snprintf(what, sizeof what, "soup %llu (%u triangles)", (unsigned long long)seed, s.tri_count);
    check_plan(&s, what, true);
    scene_fini(&s);
  }
  static const char *const names[] = {"room", "grove", "sphereflake"};
  for (int i = 0; i < 3; i++) {
    struct scene s;
    struct kd_tree kd;
    if (!testing_load_small(&s, &kd, names[i])) continue;
    check_plan(&s, names[i], false);
    kd_fini(&kd);
    scene_fini(&s);
  }
  return testing_done("bvh8_plan");
}
