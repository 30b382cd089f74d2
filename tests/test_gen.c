/* Procedural generators: triangle counts against their formulas, sphereflake
 * geometry against SPD's hand-computed child positions, the watertightness
 * precondition (every edge of a closed mesh used twice, in opposite directions,
 * with bit-identical vertices), target sizes of grove and room, determinism,
 * the order of grove's random draws, the committed scenes' hashes. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "renderer/rng.h"
#include "renderer/scene.h"
#include "renderer/scene/gen.h"
#include "renderer/scene/gen_util.h"
#include "renderer/scene/scene_file.h"
#include "sim/err.h"
#include "testing.h"

/* A directed edge as raw vertex bits: equal only if bit-identical. */
struct edge {
  float a[3], b[3];
};

static int edge_cmp(const void *x, const void *y) { return memcmp(x, y, sizeof(struct edge)); }

static void edge_set(struct edge *e, vec3 a, vec3 b) {
  memset(e, 0, sizeof *e);
  e->a[0] = a.x, e->a[1] = a.y, e->a[2] = a.z;
  e->b[0] = b.x, e->b[1] = b.y, e->b[2] = b.z;
}

/* True if triangles [first, first+count) form a closed, consistently oriented
 * mesh: each directed edge appears once and its reverse appears once. */
static bool mesh_closed(const struct scene *s, uint32_t first, uint32_t count) {
  uint64_t n = 3ull * count;
  struct edge *e = malloc(n * sizeof *e);
  for (uint32_t t = 0; t < count; t++)
    for (int k = 0; k < 3; k++) {
      const struct scene_tri *tr = &s->tris[first + t];
      edge_set(&e[3ull * t + k], tr->v[k], tr->v[(k + 1) % 3]);
    }
  qsort(e, n, sizeof *e, edge_cmp);
  bool ok = true;
  for (uint64_t i = 0; i < n && ok; i++) {
    if (i + 1 < n && edge_cmp(&e[i], &e[i + 1]) == 0) ok = false; /* used twice one way */
    struct edge r;
    memcpy(r.a, e[i].b, sizeof r.a);
    memcpy(r.b, e[i].a, sizeof r.b);
    if (!bsearch(&r, e, n, sizeof *e, edge_cmp)) ok = false; /* no opposite partner */
  }
  free(e);
  return ok;
}

static double tri_area2(const struct scene_tri *t) {
  double ux = (double)t->v[1].x - t->v[0].x, uy = (double)t->v[1].y - t->v[0].y,
         uz = (double)t->v[1].z - t->v[0].z;
  double vx = (double)t->v[2].x - t->v[0].x, vy = (double)t->v[2].y - t->v[0].y,
         vz = (double)t->v[2].z - t->v[0].z;
  double cx = uy * vz - uz * vy, cy = uz * vx - ux * vz, cz = ux * vy - uy * vx;
  return sqrt(cx * cx + cy * cy + cz * cz);
}

static uint32_t degenerate_count(const struct scene *s) {
  uint32_t n = 0;
  for (uint32_t i = 0; i < s->tri_count; i++) n += tri_area2(&s->tris[i]) <= 0.0;
  return n;
}

/* Mean of the vertices of triangles [first, first+count): the centre of a
 * cube-projected sphere, whose vertex set is symmetric about it. */
static gen_d3 mesh_mean(const struct scene *s, uint32_t first, uint32_t count) {
  gen_d3 m = gen_d3_make(0, 0, 0);
  for (uint32_t t = first; t < first + count; t++)
    for (int k = 0; k < 3; k++)
      m = gen_d3_add(m, gen_d3_make(s->tris[t].v[k].x, s->tris[t].v[k].y, s->tris[t].v[k].z));
  return gen_d3_scale(m, 1.0 / (3.0 * count));
}

/* Largest relative deviation of the vertices from radius r about c, and
 * whether every triangle faces away from c with radial shading normals. */
static double sphere_check(const struct scene *s, uint32_t first, uint32_t count, gen_d3 c,
                           double r, bool *outward) {
  double worst = 0;
  *outward = true;
  for (uint32_t t = first; t < first + count; t++) {
    const struct scene_tri *tr = &s->tris[t];
    vec3 gn = v3_cross(v3_sub(tr->v[1], tr->v[0]), v3_sub(tr->v[2], tr->v[0]));
    gen_d3 mid = gen_d3_make(0, 0, 0);
    for (int k = 0; k < 3; k++) {
      gen_d3 d = gen_d3_sub(gen_d3_make(tr->v[k].x, tr->v[k].y, tr->v[k].z), c);
      worst = fmax(worst, fabs(gen_d3_len(d) - r) / r);
      mid = gen_d3_add(mid, d);
      gen_d3 dn = gen_d3_norm(d);
      double dot = dn.x * tr->n[k].x + dn.y * tr->n[k].y + dn.z * tr->n[k].z;
      if (dot < 0.9999) *outward = false;
    }
    if (gn.x * mid.x + gn.y * mid.y + gn.z * mid.z <= 0) *outward = false;
  }
  return worst;
}

static void test_sphereflake_counts(void) {
  static const uint32_t cases[][2] = {{0, 1}, {0, 3}, {1, 1}, {1, 2}, {2, 3}, {1, 5}, {3, 2}};
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    struct scene s;
    scene_init(&s);
    gen_sphereflake(&s, cases[i][0], cases[i][1]);
    EXPECTF(s.tri_count == gen_sphereflake_tri_count(cases[i][0], cases[i][1]),
            "levels %u tess %u: %u triangles", cases[i][0], cases[i][1], s.tri_count);
    EXPECTF(degenerate_count(&s) == 0, "levels %u tess %u", cases[i][0], cases[i][1]);
    scene_fini(&s);
  }
  /* Hand-computed: 10 spheres of 12 t^2 triangles, and the paper's 797K. */
  EXPECT(gen_sphereflake_tri_count(1, 3) == 10 * 108 + 2);
  EXPECT(gen_sphereflake_tri_count(1, 2) == 10 * 48 + 2);
  EXPECT(gen_sphereflake_tri_count(0, 1) == 12 + 2);
  EXPECT(gen_sphereflake_tri_count(4, 3) == 797150);
  struct scene s;
  scene_init(&s);
  gen_sphereflake(&s, 4, 3);
  EXPECTF(s.tri_count == 797150, "%u", s.tri_count);
  EXPECT(s.mat_count == 2 && scene_find_material(&s, "flake") >= 0 &&
         scene_find_material(&s, "floor") >= 0);
  scene_fini(&s);
}

static void test_sphereflake_geometry(void) {
  struct scene s;
  scene_init(&s);
  gen_sphereflake(&s, 0, 4);
  /* Floor first (as SPD emits it), facing up at z = -0.5, corners at +-12. */
  vec3 lo, hi;
  scene_bounds(&s, &lo, &hi);
  EXPECT(lo.x == -12 && lo.y == -12 && lo.z == -0.5f && hi.x == 12 && hi.y == 12 && hi.z == 0.5f);
  EXPECT(s.tris[0].n[0].z == 1.0f && s.tris[1].n[0].z == 1.0f);
  bool outward;
  double dev = sphere_check(&s, 2, 12 * 16, gen_d3_make(0, 0, 0), 0.5, &outward);
  EXPECTF(dev < 1e-5, "root radius deviation %g", dev);
  EXPECT(outward);
  scene_fini(&s);

  /* Level 1, SPD's balls.c worked by hand: children of radius 1/6 at 2/3 from
   * the origin; the first at elevation asin(sqrt(2/3)) and azimuth 45
   * degrees; six on the equator and three at z = (2/3) sqrt(2/3). */
  const uint32_t tess = 3, per = 12 * tess * tess;
  scene_init(&s);
  gen_sphereflake(&s, 1, tess);
  int equator = 0, raised = 0;
  double worst = 0;
  for (uint32_t k = 1; k <= 9; k++) {
    uint32_t first = 2 + k * per;
    gen_d3 c = mesh_mean(&s, first, per);
    worst = fmax(worst, fabs(gen_d3_len(c) - 2.0 / 3.0));
    if (fabs(c.z) < 1e-6) equator++;
    if (fabs(c.z - 2.0 / 3.0 * sqrt(2.0 / 3.0)) < 1e-6) raised++;
    double dev_k = sphere_check(&s, first, per, c, 1.0 / 6.0, &outward);
    EXPECTF(dev_k < 1e-5 && outward, "child %u: deviation %g", k, dev_k);
    if (k == 1) {
      double e = 2.0 / 3.0 / sqrt(6.0);
      EXPECTF(fabs(c.x - e) < 1e-6 && fabs(c.y - e) < 1e-6, "first child %g %g %g", c.x, c.y, c.z);
    }
  }
  EXPECTF(worst < 1e-6, "child distance off by %g", worst);
  EXPECT(equator == 6 && raised == 3);
  scene_fini(&s);

  /* Level 2: grandchildren of radius 1/18 at 1/6 * 4/3 from their parent. */
  scene_init(&s);
  gen_sphereflake(&s, 2, 2);
  const uint32_t per2 = 48;
  gen_d3 parent = mesh_mean(&s, 2 + 1 * per2, per2);
  gen_d3 child = mesh_mean(&s, 2 + 2 * per2, per2);
  EXPECTF(fabs(gen_d3_len(gen_d3_sub(child, parent)) - 2.0 / 9.0) < 1e-6, "%g",
          gen_d3_len(gen_d3_sub(child, parent)));
  scene_fini(&s);
}

static void test_watertight(void) {
  /* Every sphere of a small flake, including ones off the origin where the
   * centre + offset rounding would expose any non-shared vertex. */
  static const uint32_t tess_cases[] = {1, 2, 3, 5};
  for (size_t i = 0; i < sizeof tess_cases / sizeof tess_cases[0]; i++) {
    uint32_t t = tess_cases[i], per = 12 * t * t;
    struct scene s;
    scene_init(&s);
    gen_sphereflake(&s, 2, t);
    uint32_t spheres = (s.tri_count - 2) / per, open = 0;
    for (uint32_t k = 0; k < spheres; k++) open += !mesh_closed(&s, 2 + k * per, per);
    EXPECTF(open == 0, "tess %u: %u of %u spheres not closed", t, open, spheres);
    scene_fini(&s);
  }
  /* The shared builders used by grove and room. */
  struct scene s;
  scene_init(&s);
  struct gen_frame f = gen_frame_along(gen_d3_make(1.3, -2.7, 0.4), gen_d3_make(0.3, -0.5, 0.8));
  gen_box(&s, &f, 0.3, 0.2, 0.7, 0);
  EXPECT(s.tri_count == 12 && mesh_closed(&s, 0, 12));
  uint32_t at = s.tri_count;
  gen_box_aa(&s, gen_d3_make(0.1, 0.2, 0.3), gen_d3_make(1.7, 0.9, 2.2), 0);
  EXPECT(mesh_closed(&s, at, 12));
  at = s.tri_count;
  gen_cylinder(&s, &f, 0.25, 0.1, 1.5, 7, 0);
  EXPECT(s.tri_count - at == 28 && mesh_closed(&s, at, 28));
  /* A cup: revolved profile with an inner wall, like the room's. */
  double r[6] = {0, 0.04, 0.043, 0.037, 0.034, 0}, z[6] = {0, 0, 0.09, 0.09, 0.006, 0.006};
  at = s.tri_count;
  gen_lathe(&s, &f, r, z, 6, 19, 0);
  EXPECT(s.tri_count - at == gen_lathe_tri_count(r, 6, 19));
  EXPECT(mesh_closed(&s, at, s.tri_count - at));
  at = s.tri_count;
  gen_sphere(&s, gen_d3_make(3.1, 7.7, -0.9), 0.37, 6, 0);
  EXPECT(mesh_closed(&s, at, s.tri_count - at));
  bool outward;
  double dev = sphere_check(&s, at, s.tri_count - at, gen_d3_make(3.1, 7.7, -0.9), 0.37, &outward);
  EXPECT(dev < 1e-5 && outward);
  EXPECT(degenerate_count(&s) == 0);
  scene_fini(&s);
}

static bool same_tris(const struct scene *a, const struct scene *b) {
  return a->tri_count == b->tri_count &&
         memcmp(a->tris, b->tris, (size_t)a->tri_count * sizeof *a->tris) == 0;
}

typedef void (*gen_fn)(struct scene *, double, uint64_t);

static uint32_t gen_count(gen_fn fn, double detail, uint64_t seed) {
  struct scene s;
  scene_init(&s);
  fn(&s, detail, seed);
  uint32_t n = s.tri_count;
  scene_fini(&s);
  return n;
}

static void test_procedural(const char *name, gen_fn fn, double target, double small_detail,
                            const char *const *mats, int mat_count, vec3 lo_bound, vec3 hi_bound) {
  struct scene a, b, c;
  scene_init(&a);
  scene_init(&b);
  scene_init(&c);
  fn(&a, 1.0, 7);
  fn(&b, 1.0, 7);
  fn(&c, 1.0, 8);
  EXPECTF(fabs(a.tri_count - target) <= 0.05 * target, "%s: %u triangles at detail 1", name,
          a.tri_count);
  EXPECTF(same_tris(&a, &b) && scene_hash(&a) == scene_hash(&b), "%s: not deterministic", name);
  EXPECTF(!same_tris(&a, &c), "%s: seed has no effect", name);
  EXPECTF(degenerate_count(&a) == 0, "%s: %u degenerate triangles", name, degenerate_count(&a));
  for (int i = 0; i < mat_count; i++) {
    int id = scene_find_material(&a, mats[i]);
    uint32_t used = 0;
    for (uint32_t t = 0; id >= 0 && t < a.tri_count; t++)
      used += a.tris[t].material == (uint32_t)id;
    EXPECTF(id >= 0 && used > 0, "%s: material %s unused", name, mats[i]);
  }
  vec3 lo, hi;
  scene_bounds(&a, &lo, &hi);
  EXPECTF(lo.x >= lo_bound.x && lo.y >= lo_bound.y && lo.z >= lo_bound.z && hi.x <= hi_bound.x &&
              hi.y <= hi_bound.y && hi.z <= hi_bound.z,
          "%s: bounds (%g %g %g)-(%g %g %g)", name, lo.x, lo.y, lo.z, hi.x, hi.y, hi.z);
  scene_fini(&a);
  scene_fini(&b);
  scene_fini(&c);

  /* Small detail: a few thousand triangles; roughly linear in between. */
  uint32_t small = gen_count(fn, small_detail, 7);
  EXPECTF(small >= 1000 && small <= 8000, "%s: %u triangles at detail %g", name, small,
          small_detail);
  uint32_t half = gen_count(fn, 0.5, 7);
  EXPECTF(fabs(half - 0.5 * target) <= 0.15 * target, "%s: %u triangles at detail 0.5", name, half);
  EXPECT(gen_count(fn, 2.0, 7) > 1.7 * target);

  /* A material the scene already defines is used, not replaced. */
  struct scene d;
  scene_init(&d);
  uint32_t pre = scene_material_or_default(&d, mats[0], v3(1, 0, 1), 0.25f, 0.5f);
  fn(&d, small_detail, 7);
  EXPECT(d.mats[pre].color.y == 0.0f && d.mats[pre].mirror == 0.5f);
  EXPECT(d.mat_count == (uint32_t)mat_count);
  scene_fini(&d);
}

/* The closed-form counts the scene loader checks before building, against the
 * triangles actually built: every detail the thinning, the rounding of
 * tessellation levels and their clamps treat differently, several seeds. */
static void test_count_formulas(void) {
  static const double details[] = {1e-4, 0.013, 0.1, 0.37, 0.5, 0.618, 0.99,
                                   1.0,  1.3,   2.0, 3.7,  9.0, 24.5};
  for (size_t i = 0; i < sizeof details / sizeof details[0]; i++)
    for (uint64_t seed = 1; seed <= 2; seed++) {
      double d = details[i];
      uint32_t room = gen_count(gen_room, d, seed * 77);
      EXPECTF(room == gen_room_tri_count(d), "room detail %g seed %llu: built %u, formula %llu", d,
              (unsigned long long)seed, room, (unsigned long long)gen_room_tri_count(d));
      if (d > 3.0) continue; /* 40 trees per unit of detail: the small ones tell */
      uint32_t grove = gen_count(gen_grove, d, seed * 77);
      EXPECTF(grove == gen_grove_tri_count(d), "grove detail %g seed %llu: built %u, formula %llu",
              d, (unsigned long long)seed, grove, (unsigned long long)gen_grove_tri_count(d));
    }
  /* Hand-computed: a tree is 3 (8 + 3*6 + 9*5 + 27*4 + 81*4) + 81*16*2 = 4101
   * triangles and the ground 16*16*2; one tree below detail 1/80. */
  EXPECT(gen_grove_tri_count(1.0) == 40 * 4101 + 512);
  EXPECT(gen_grove_tri_count(0.001) == 4101 + 512);
  EXPECT(gen_grove_tri_count(200.0) == 8000ull * 4101 + 512);
  /* The room's tessellation levels stop at 256, so its count stops growing. */
  EXPECT(gen_room_tri_count(200.0) > gen_room_tri_count(24.5));
  EXPECT(gen_room_tri_count(1e6) == gen_room_tri_count(1e5));
}

/* grove's uniform draw: lo + (hi - lo) u, u from rng_f32. */
static double grove_draw(struct rng *r, double lo, double hi) {
  return lo + (hi - lo) * (double)rng_f32(r);
}

/* The order of grove's draws, worked by hand for the one tree of seed 1: the
 * placement stream (seed, 0) gives the foot's x, then y, in [-3, 3]; the
 * tree's stream (seed, 1) the trunk's length, its radius r0, then the lean's
 * y, then its x. The trunk (the 3 * 8 triangles after the ground's 512) ends
 * in a cone whose apex is foot + (length + 0.62 r0) unit(lean x, lean y, 1).
 * With the two leans drawn the other way round (as clang did while they were
 * one call's arguments), the apex moves by 0.07. */
static void test_grove_draw_order(void) {
  struct rng place = rng_make(1, 0), tree = rng_make(1, 1);
  double x = grove_draw(&place, -3.0, 3.0);
  double y = grove_draw(&place, -3.0, 3.0);
  double len = grove_draw(&tree, 2.2, 3.2);
  double r0 = grove_draw(&tree, 0.14, 0.22);
  double lean_y = grove_draw(&tree, -0.08, 0.08);
  double lean_x = grove_draw(&tree, -0.08, 0.08);
  EXPECTF(fabs(lean_x - lean_y) > 0.01, "leans %g %g: the case tells no order", lean_x, lean_y);
  gen_d3 w = gen_d3_norm(gen_d3_make(lean_x, lean_y, 1.0));
  gen_d3 apex = gen_d3_add(gen_d3_make(x, y, -0.2), gen_d3_scale(w, len + 0.62 * r0));

  struct scene s;
  scene_init(&s);
  gen_grove(&s, 0.001, 1);
  double nearest = INFINITY;
  for (uint32_t t = 512; t < 512 + 3 * 8 && t < s.tri_count; t++)
    for (int k = 0; k < 3; k++) {
      const vec3 v = s.tris[t].v[k];
      nearest = fmin(nearest, gen_d3_len(gen_d3_sub(gen_d3_make(v.x, v.y, v.z), apex)));
    }
  EXPECTF(nearest < 1e-5, "trunk apex (%g %g %g) is %g from every trunk vertex", apex.x, apex.y,
          apex.z, nearest);
  scene_fini(&s);
}

/* The committed scenes' hashes: the big three's as the committed results
 * record them (results/, column scene_hash), the small ones' as gcc and clang
 * both make them. A generator that draws its random numbers in another order,
 * or computes a coordinate another way, makes other triangles and moves every
 * result of its scenes: one draw a statement, as C leaves the order of a
 * call's arguments and of an initializer's expressions open. On purpose, a
 * new hash goes here with the results made again. They hold on x86-64 with
 * glibc's libm (docs/testing.md, Same bits from any compiler); elsewhere untested. */
static void test_scene_hashes(void) {
#if defined(__x86_64__) && defined(__GLIBC__)
  static const struct {
    const char *file;
    uint64_t hash;
  } cases[] = {
      {"scenes/grove.yaml", 0xe9b902b54a20257dull},
      {"scenes/room.yaml", 0xac49e6e3f8eec8cdull},
      {"scenes/sphereflake.yaml", 0x31de3b7d1efdd032ull},
      {"scenes/small/grove.yaml", 0x27bbefb6e72eabceull},
      {"scenes/small/room.yaml", 0x5e66fbfee3ee7081ull},
      {"scenes/small/sphereflake.yaml", 0xfb5f9a2eb8e1bdbeull},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    char path[512];
    snprintf(path, sizeof path, "%s/%s", RTSIM_SOURCE_DIR, cases[i].file);
    struct scene s;
    struct err e;
    memset(&e, 0, sizeof e);
    bool ok = scene_file_load(&s, path, &e);
    EXPECTF(ok, "%s: %s:%d:%d %s", path, e.file, e.line, e.col, e.msg);
    if (!ok) continue;
    EXPECTF(scene_hash(&s) == cases[i].hash, "%s: scene_hash %016llx, expected %016llx",
            cases[i].file, (unsigned long long)scene_hash(&s), (unsigned long long)cases[i].hash);
    scene_fini(&s);
  }
#endif
}

int main(void) {
  test_count_formulas();
  test_sphereflake_counts();
  test_sphereflake_geometry();
  test_watertight();
  static const char *const grove_mats[] = {"bark", "leaf", "ground"};
  test_procedural("grove", gen_grove, 164000, 0.02, grove_mats, 3, v3(-40, -40, -0.3),
                  v3(40, 40, 20));
  static const char *const room_mats[] = {"wall",   "floor", "ceiling", "wood",
                                          "fabric", "metal", "mirror",  "ceramic"};
  test_procedural("room", gen_room, 47000, 0.05, room_mats, 8, v3(-0.06f, -0.06f, -0.06f),
                  v3(8.06f, 6.06f, 3.06f));
  /* A different seed moves trees but keeps the grove's size. */
  EXPECT(gen_count(gen_grove, 1.0, 1) == gen_count(gen_grove, 1.0, 12345));
  EXPECT(gen_count(gen_grove, 0.001, 3) > 0);
  test_grove_draw_order();
  test_scene_hashes();
  return testing_done("test_gen");
}
