/* Sphereflake: the Standard Procedural Databases "balls" scene (E. Haines).
 * Sphere centres, radii and the order they are emitted in follow SPD's
 * balls.c (floor first, then a depth-first walk from the root), with its
 * row-vector matrix convention; positions are computed in double and rounded
 * to float only in the emitted triangles. */
#include "renderer/scene/gen.h"

#include <math.h>

#include "renderer/scene.h"
#include "renderer/scene/gen_util.h"
#include "sim/err.h"

/* SPD matrices act on row vectors: p' = p M. */
typedef double flake_mat[3][3];

struct flake_ctx {
  struct scene *s;
  uint32_t tess, mat;
  gen_d3 objset[9]; /* the 9 child directions for growth along +Z */
};

static gen_d3 flake_xform(gen_d3 p, flake_mat m) {
  return gen_d3_make(p.x * m[0][0] + p.y * m[1][0] + p.z * m[2][0],
                     p.x * m[0][1] + p.y * m[1][1] + p.z * m[2][1],
                     p.x * m[0][2] + p.y * m[1][2] + p.z * m[2][2]);
}

/* SPD lib_create_axis_rotate_matrix: rotate by `angle` about unit `axis`. */
static void flake_axis_rotate(flake_mat m, gen_d3 a, double angle) {
  double c = cos(angle), s = sin(angle), t = 1.0 - c;
  m[0][0] = a.x * a.x + (1.0 - a.x * a.x) * c;
  m[0][1] = a.x * a.y * t + a.z * s;
  m[0][2] = a.x * a.z * t - a.y * s;
  m[1][0] = a.x * a.y * t - a.z * s;
  m[1][1] = a.y * a.y + (1.0 - a.y * a.y) * c;
  m[1][2] = a.y * a.z * t + a.x * s;
  m[2][0] = a.x * a.z * t + a.y * s;
  m[2][1] = a.y * a.z * t - a.x * s;
  m[2][2] = a.z * a.z + (1.0 - a.z * a.z) * c;
}

/* SPD create_objset: three directions tilted about (1,-1,0), copied at 0, 120
 * and 240 degrees about Z. */
static void flake_objset(gen_d3 out[9]) {
  double d = 1.0 / sqrt(2.0);
  gen_d3 trio[3] = {gen_d3_make(d, d, 0.0), gen_d3_make(d, 0.0, -d), gen_d3_make(0.0, d, -d)};
  flake_mat m;
  flake_axis_rotate(m, gen_d3_norm(gen_d3_make(1.0, -1.0, 0.0)), asin(2.0 / sqrt(6.0)));
  for (int i = 0; i < 3; i++) trio[i] = flake_xform(trio[i], m);
  for (int set = 0; set < 3; set++) {
    flake_axis_rotate(m, gen_d3_make(0, 0, 1), set * 2.0 * GEN_PI / 3.0);
    for (int i = 0; i < 3; i++) out[set * 3 + i] = flake_xform(trio[i], m);
  }
}

/* SPD output_object: emit this sphere, then its 9 children (radius ratio
 * `ratio`, 1/3) around growth direction `dir`. */
static void flake_object(struct flake_ctx *c, uint32_t depth, gen_d3 centre, double radius,
                         gen_d3 dir, double ratio) {
  gen_sphere(c->s, centre, radius, c->tess, c->mat);
  if (depth == 0) return;
  flake_mat m;
  /* Rotation taking +Z onto dir. SPD tests with an epsilon because a child's
   * direction may be slightly shorter than 1. */
  if (dir.z >= 0.9999) {
    flake_axis_rotate(m, gen_d3_make(0, 0, 1), 0.0);
  } else if (dir.z <= -0.9999) {
    flake_axis_rotate(m, gen_d3_make(0, 1, 0), GEN_PI);
  } else {
    gen_d3 axis = gen_d3_norm(gen_d3_cross(gen_d3_make(0, 0, 1), dir));
    flake_axis_rotate(m, axis, acos(dir.z));
  }
  double scale = radius * (1.0 + ratio);
  for (int i = 0; i < 9; i++) {
    gen_d3 child = gen_d3_add(gen_d3_scale(flake_xform(c->objset[i], m), scale), centre);
    gen_d3 child_dir = gen_d3_scale(gen_d3_sub(child, centre), 1.0 / scale);
    flake_object(c, depth - 1, child, radius * ratio, child_dir, ratio);
  }
}

uint64_t gen_sphereflake_tri_count(uint32_t levels, uint32_t tess) {
  uint64_t spheres = 0, level = 1;
  for (uint32_t i = 0; i <= levels; i++, level *= 9) spheres += level;
  return spheres * gen_sphere_tri_count(tess) + 2;
}

void gen_sphereflake(struct scene *s, uint32_t levels, uint32_t tess) {
  CHECK_GE(tess, 1);
  uint32_t flake = scene_material_or_default(s, "flake", v3(1.0f, 0.9f, 0.7f), 0.5f, 0.5f);
  uint32_t floor_mat = scene_material_or_default(s, "floor", v3(1.0f, 0.75f, 0.33f), 1.0f, 0.0f);
  /* Floor square at z = -radius/2 of the enclosing unit sphere, facing up. */
  gen_quad(s, gen_d3_make(-12, -12, -0.5), gen_d3_make(12, -12, -0.5), gen_d3_make(12, 12, -0.5),
           gen_d3_make(-12, 12, -0.5), floor_mat);
  struct flake_ctx c;
  c.s = s;
  c.tess = tess;
  c.mat = flake;
  flake_objset(c.objset);
  flake_object(&c, levels, gen_d3_make(0, 0, 0), 0.5, gen_d3_make(0, 0, 1), 1.0 / 3.0);
}
