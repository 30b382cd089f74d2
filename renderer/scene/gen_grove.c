/* Grove: branching trees on a flat ground grid, spread over a 36 x 36 area so
 * that geometry recedes far into the image (the paper's grove has most of its
 * triangles potentially visible). z is up, the ground is z = 0.
 * Every tree has the same topology (fixed branching, fixed leaves per tip); the
 * seed only moves, bends and sizes things. So the triangle count depends on
 * `detail` alone: trees * GROVE_TREE_TRIS + ground. */
#include "renderer/scene/gen.h"

#include <math.h>
#include <stdlib.h>

#include "renderer/rng.h"
#include "renderer/scene.h"
#include "renderer/scene/gen_util.h"
#include "sim/err.h"

#define GROVE_TREES_AT_DETAIL_1 40 /* 40 trees of 4101 triangles + ground = 164,552 */
#define GROVE_DEPTH 4              /* branch levels below the trunk */
#define GROVE_CHILDREN 3           /* one continuation + two side branches */
#define GROVE_LEAVES_PER_TIP 16
#define GROVE_HALF_EXTENT 18.0 /* trees stand in [-18, 18]^2 */
#define GROVE_GROUND_HALF 40.0 /* ground reaches well past the trees */
#define GROVE_GROUND_CELLS 16

/* Sides of the branch tubes per level: thin twigs need few. */
static const uint32_t grove_sides[GROVE_DEPTH + 1] = {8, 6, 5, 4, 4};

struct grove_ctx {
  struct scene *s;
  struct rng rng;
  uint32_t bark, leaf;
};

static double grove_unif(struct rng *r, double lo, double hi) {
  return lo + (hi - lo) * (double)rng_f32(r);
}

static gen_d3 grove_rand_dir(struct rng *r) {
  double z = grove_unif(r, -1.0, 1.0), phi = grove_unif(r, 0.0, 2.0 * GEN_PI);
  double q = sqrt(1.0 - z * z);
  return gen_d3_make(q * cos(phi), q * sin(phi), z);
}

/* A leaf: a flat diamond of 2 triangles from `p` along unit `a`. */
static void grove_leaf(struct grove_ctx *c, gen_d3 p, gen_d3 a, double len, double width) {
  gen_d3 b = gen_d3_cross(a, grove_rand_dir(&c->rng));
  if (gen_d3_len(b) < 1e-3) b = gen_d3_cross(a, gen_d3_make(0, 0, 1));
  if (gen_d3_len(b) < 1e-3) b = gen_d3_make(1, 0, 0);
  b = gen_d3_scale(gen_d3_norm(b), 0.5 * width);
  gen_d3 mid = gen_d3_add(p, gen_d3_scale(a, 0.4 * len));
  gen_d3 tip = gen_d3_add(p, gen_d3_scale(a, len));
  gen_quad(c->s, p, gen_d3_add(mid, b), tip, gen_d3_sub(mid, b), c->leaf);
}

/* A branch from `base` along unit `dir`: a tapered tube with a conical tip
 * cap (3 * sides triangles, open at the base, which sits inside the parent or
 * the ground), then its children, or its leaves at the last level. */
static void grove_branch(struct grove_ctx *c, gen_d3 base, gen_d3 dir, double len, double r0,
                         uint32_t level) {
  double r1 = r0 * (level == GROVE_DEPTH ? 0.45 : 0.62);
  struct gen_frame f = gen_frame_along(base, dir);
  double pr[3] = {r0, r1, 0.0}, pz[3] = {0.0, len, len + r1};
  gen_lathe(c->s, &f, pr, pz, 3, grove_sides[level], c->bark);

  if (level == GROVE_DEPTH) {
    /* Cluster the leaves around the outer part of the twig, pointing roughly
     * outward so crowns read as crowns from a distance. */
    for (int i = 0; i < GROVE_LEAVES_PER_TIP; i++) {
      double t = grove_unif(&c->rng, 0.3, 1.15);
      /* NOTE: one draw a statement (here the offset's length, then its
       * direction): C leaves the order of a call's arguments open, and gcc and
       * clang take them in opposite orders (tests/test_gen.c holds this one). */
      double off_len = grove_unif(&c->rng, 0.05, 0.3) * len;
      gen_d3 off = gen_d3_scale(grove_rand_dir(&c->rng), off_len);
      gen_d3 p = gen_d3_add(gen_frame_point(&f, 0, 0, t * len), off);
      gen_d3 a = gen_d3_norm(gen_d3_add(dir, gen_d3_scale(grove_rand_dir(&c->rng), 0.9)));
      if (gen_d3_len(a) < 0.5) a = dir;
      double leaf_len = grove_unif(&c->rng, 0.22, 0.34);
      grove_leaf(c, p, a, leaf_len, leaf_len * grove_unif(&c->rng, 0.45, 0.6));
    }
    return;
  }

  double phase = grove_unif(&c->rng, 0.0, 2.0 * GEN_PI);
  for (int k = 0; k < GROVE_CHILDREN; k++) {
    double t, tilt, az, len_ratio, rad_ratio;
    if (k == 0) { /* the continuation of this branch */
      t = 0.95;
      tilt = grove_unif(&c->rng, 0.1, 0.3);
      az = grove_unif(&c->rng, 0.0, 2.0 * GEN_PI);
      len_ratio = grove_unif(&c->rng, 0.72, 0.82);
      rad_ratio = 0.85;
    } else {
      t = grove_unif(&c->rng, 0.45, 0.85);
      tilt = grove_unif(&c->rng, 0.55, 0.95);
      az = phase + (k - 1) * (2.0 * GEN_PI / (GROVE_CHILDREN - 1)) + grove_unif(&c->rng, -0.5, 0.5);
      len_ratio = grove_unif(&c->rng, 0.6, 0.75);
      rad_ratio = 0.7;
    }
    /* The child starts on this branch's axis, inside the tube, so the joint
     * needs no extra geometry. A slight upward pull keeps crowns upright. */
    gen_d3 cdir = gen_frame_dir(&f, sin(tilt) * cos(az), sin(tilt) * sin(az), cos(tilt));
    cdir = gen_d3_norm(gen_d3_add(cdir, gen_d3_make(0, 0, 0.2)));
    double r_at = r0 + (r1 - r0) * t;
    grove_branch(c, gen_frame_point(&f, 0, 0, t * len), cdir, len * len_ratio, r_at * rad_ratio,
                 level + 1);
  }
}

/* Place `n` trees in the square by dart throwing with a minimum spacing; a
 * dart that keeps failing takes the best of its tries, so n always fit. The
 * first tree stands near the centre so that a tiny grove is still in view. */
static void grove_place(struct rng *r, uint32_t n, double *xy) {
  const double min_d2 = 3.5 * 3.5;
  for (uint32_t i = 0; i < n; i++) {
    double best = -1.0, half = i == 0 ? 3.0 : GROVE_HALF_EXTENT;
    for (int tries = 0; tries < 40; tries++) {
      double x = grove_unif(r, -half, half);
      double y = grove_unif(r, -half, half);
      double d2 = 1e30;
      for (uint32_t j = 0; j < i; j++) {
        double dx = x - xy[2 * j], dy = y - xy[2 * j + 1];
        if (dx * dx + dy * dy < d2) d2 = dx * dx + dy * dy;
      }
      if (d2 > best) {
        best = d2;
        xy[2 * i] = x;
        xy[2 * i + 1] = y;
      }
      if (d2 >= min_d2) break;
    }
  }
}

/* Trees for `detail`: 40 per unit of detail, at least 1, at most a million. */
static uint32_t grove_tree_count(double detail) {
  double want = floor(GROVE_TREES_AT_DETAIL_1 * detail + 0.5);
  return want < 1.0 ? 1u : want > 1e6 ? 1000000u : (uint32_t)want;
}

/* One tree: each branch is a lathe of 3 * sides triangles (a tube of 2 *
 * sides and a cone of sides, gen_lathe_tri_count on its profile), branches
 * multiply by GROVE_CHILDREN per level, and each tip carries leaves of 2. */
static uint64_t grove_tree_tri_count(void) {
  uint64_t tris = 0, branches = 1;
  for (int level = 0; level <= GROVE_DEPTH; level++, branches *= GROVE_CHILDREN)
    tris += branches * 3 * grove_sides[level];
  return tris + branches / GROVE_CHILDREN * GROVE_LEAVES_PER_TIP * 2;
}

uint64_t gen_grove_tri_count(double detail) {
  return 2ull * GROVE_GROUND_CELLS * GROVE_GROUND_CELLS +
         (uint64_t)grove_tree_count(detail) * grove_tree_tri_count();
}

void gen_grove(struct scene *s, double detail, uint64_t seed) {
  CHECK_GT(detail, 0.0);
  struct grove_ctx c;
  c.s = s;
  c.bark = scene_material_or_default(s, "bark", v3(0.35f, 0.25f, 0.15f), 0.9f, 0.0f);
  c.leaf = scene_material_or_default(s, "leaf", v3(0.25f, 0.55f, 0.15f), 0.9f, 0.0f);
  uint32_t ground = scene_material_or_default(s, "ground", v3(0.4f, 0.35f, 0.25f), 1.0f, 0.0f);

  double h = GROVE_GROUND_HALF;
  gen_grid(s, gen_d3_make(-h, -h, 0), gen_d3_make(2 * h, 0, 0), gen_d3_make(0, 2 * h, 0),
           GROVE_GROUND_CELLS, GROVE_GROUND_CELLS, ground);

  uint32_t n = grove_tree_count(detail);
  double *xy = xmalloc(2ull * n * sizeof *xy);
  struct rng place = rng_make(seed, 0);
  grove_place(&place, n, xy);
  for (uint32_t i = 0; i < n; i++) {
    /* One stream per tree: a tree's shape does not depend on how many
     * trees came before it. */
    c.rng = rng_make(seed, 1 + (uint64_t)i);
    double trunk_len = grove_unif(&c.rng, 2.2, 3.2);
    double trunk_r = grove_unif(&c.rng, 0.14, 0.22);
    /* One draw a statement, y before x (NOTE in grove_branch). */
    double lean_y = grove_unif(&c.rng, -0.08, 0.08);
    double lean_x = grove_unif(&c.rng, -0.08, 0.08);
    gen_d3 lean = gen_d3_make(lean_x, lean_y, 1);
    /* Start below the ground so the open tube end is never seen. */
    grove_branch(&c, gen_d3_make(xy[2 * i], xy[2 * i + 1], -0.2), gen_d3_norm(lean), trunk_len,
                 trunk_r, 0);
  }
  free(xy);
}
