/* Mesh builders shared by the procedural generators (declared in gen_util.h).
 * Every builder computes each shared vertex once, or from the same integer
 * inputs by the same expression, so neighbouring triangles see bit-identical
 * floats: the precondition of a watertight ray/triangle test. The generators
 * themselves live in gen_sphereflake.c, gen_grove.c and gen_room.c. */
#include "renderer/scene/gen.h"

#include <math.h>
#include <stddef.h>
#include <stdlib.h>

#include "renderer/scene.h"
#include "renderer/scene/gen_util.h"
#include "sim/err.h"

struct gen_frame gen_frame_at(gen_d3 o) {
  struct gen_frame f;
  f.o = o;
  f.u = gen_d3_make(1, 0, 0);
  f.v = gen_d3_make(0, 1, 0);
  f.w = gen_d3_make(0, 0, 1);
  return f;
}

struct gen_frame gen_frame_along(gen_d3 o, gen_d3 w) {
  struct gen_frame f;
  f.o = o;
  f.w = gen_d3_norm(w);
  /* Any helper axis not near w works; picking it from w alone keeps the frame
   * (and so every vertex) a pure function of the inputs. */
  gen_d3 helper = fabs(f.w.z) < 0.9 ? gen_d3_make(0, 0, 1) : gen_d3_make(1, 0, 0);
  f.u = gen_d3_norm(gen_d3_cross(helper, f.w));
  f.v = gen_d3_cross(f.w, f.u);
  return f;
}

gen_d3 gen_frame_dir(const struct gen_frame *f, double x, double y, double z) {
  gen_d3 p = gen_d3_scale(f->u, x);
  p = gen_d3_add(p, gen_d3_scale(f->v, y));
  p = gen_d3_add(p, gen_d3_scale(f->w, z));
  return p;
}

gen_d3 gen_frame_point(const struct gen_frame *f, double x, double y, double z) {
  return gen_d3_add(f->o, gen_frame_dir(f, x, y, z));
}

void gen_tri(struct scene *s, gen_d3 a, gen_d3 b, gen_d3 c, uint32_t mat) {
  scene_add_tri(s, gen_d3_to_f(a), gen_d3_to_f(b), gen_d3_to_f(c), NULL, mat);
}

void gen_quad(struct scene *s, gen_d3 a, gen_d3 b, gen_d3 c, gen_d3 d, uint32_t mat) {
  gen_tri(s, a, b, c, mat);
  gen_tri(s, a, c, d, mat);
}

void gen_grid(struct scene *s, gen_d3 o, gen_d3 eu, gen_d3 ev, uint32_t nu, uint32_t nv,
              uint32_t mat) {
  CHECK_GE(nu, 1);
  CHECK_GE(nv, 1);
  for (uint32_t j = 0; j < nv; j++)
    for (uint32_t i = 0; i < nu; i++) {
      gen_d3 c[4];
      for (int k = 0; k < 4; k++) {
        /* Corner order i,j / i+1,j / i+1,j+1 / i,j+1 (counter-clockwise). */
        uint32_t ci = i + (uint32_t)(k == 1 || k == 2), cj = j + (uint32_t)(k >= 2);
        c[k] = gen_d3_add(
            o, gen_d3_add(gen_d3_scale(eu, (double)ci / nu), gen_d3_scale(ev, (double)cj / nv)));
      }
      gen_quad(s, c[0], c[1], c[2], c[3], mat);
    }
}

/* Emit the 6 faces of a box from its corners; corner b has +x if bit 0, +y if
 * bit 1, +z if bit 2 (in the box's own axes, which must be right-handed). */
static void box_faces(struct scene *s, const gen_d3 c[8], uint32_t mat) {
  static const int faces[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                  {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  for (int f = 0; f < 6; f++)
    gen_quad(s, c[faces[f][0]], c[faces[f][1]], c[faces[f][2]], c[faces[f][3]], mat);
}

void gen_box(struct scene *s, const struct gen_frame *f, double hx, double hy, double hz,
             uint32_t mat) {
  gen_d3 c[8];
  for (int b = 0; b < 8; b++)
    c[b] = gen_frame_point(f, (b & 1) ? hx : -hx, (b & 2) ? hy : -hy, (b & 4) ? hz : -hz);
  box_faces(s, c, mat);
}

void gen_box_aa(struct scene *s, gen_d3 lo, gen_d3 hi, uint32_t mat) {
  gen_d3 c[8];
  for (int b = 0; b < 8; b++)
    c[b] = gen_d3_make((b & 1) ? hi.x : lo.x, (b & 2) ? hi.y : lo.y, (b & 4) ? hi.z : lo.z);
  box_faces(s, c, mat);
}

uint64_t gen_sphere_tri_count(uint32_t tess) { return 12ull * tess * tess; }

/* Unit direction of cube-surface grid point idx (each 0..tess): a function of
 * the integer triple only, so a point on an edge shared by two cube faces gets
 * the same value from both. */
static gen_d3 sphere_dir(const uint32_t idx[3], uint32_t tess) {
  double t = (double)tess;
  gen_d3 c = gen_d3_make((2.0 * idx[0] - t) / t, (2.0 * idx[1] - t) / t, (2.0 * idx[2] - t) / t);
  return gen_d3_scale(c, 1.0 / sqrt(c.x * c.x + c.y * c.y + c.z * c.z));
}

void gen_sphere(struct scene *s, gen_d3 centre, double radius, uint32_t tess, uint32_t mat) {
  CHECK_GE(tess, 1);
  for (int axis = 0; axis < 3; axis++)
    for (int side = 0; side < 2; side++) {
      /* Walk the face along (a, b) with e_a x e_b pointing outward, so quads
       * listed counter-clockwise in (a, b) face out. */
      int a = (axis + 1) % 3, b = (axis + 2) % 3;
      if (side == 0) {
        int t = a;
        a = b;
        b = t;
      }
      for (uint32_t j = 0; j < tess; j++)
        for (uint32_t i = 0; i < tess; i++) {
          vec3 p[4], n[4];
          for (int k = 0; k < 4; k++) {
            uint32_t idx[3];
            idx[axis] = side ? tess : 0;
            idx[a] = i + (uint32_t)(k == 1 || k == 2);
            idx[b] = j + (uint32_t)(k >= 2);
            gen_d3 d = sphere_dir(idx, tess);
            p[k] = gen_d3_to_f(gen_d3_add(centre, gen_d3_scale(d, radius)));
            n[k] = gen_d3_to_f(d);
          }
          vec3 n0[3] = {n[0], n[1], n[2]}, n1[3] = {n[0], n[2], n[3]};
          scene_add_tri(s, p[0], p[1], p[2], n0, mat);
          scene_add_tri(s, p[0], p[2], p[3], n1, mat);
        }
    }
}

uint64_t gen_lathe_tri_count(const double *r, uint32_t n, uint32_t sides) {
  uint64_t t = 0;
  for (uint32_t i = 0; i + 1 < n; i++) {
    if (r[i] == 0.0 && r[i + 1] == 0.0) continue;
    t += (r[i] == 0.0 || r[i + 1] == 0.0) ? sides : 2ull * sides;
  }
  return t;
}

void gen_lathe(struct scene *s, const struct gen_frame *f, const double *r, const double *z,
               uint32_t n, uint32_t sides, uint32_t mat) {
  CHECK_GE(n, 2);
  CHECK_GE(sides, 3);
  /* Ring vertices are computed once into this table and reused by every
   * triangle that touches them; index j == sides wraps to 0. */
  gen_d3 *ring = xmalloc((unsigned long long)n * sides * sizeof *ring);
  double *cs = xmalloc(2ull * sides * sizeof *cs);
  for (uint32_t j = 0; j < sides; j++) {
    double th = 2.0 * GEN_PI * (double)j / (double)sides;
    cs[2 * j] = cos(th);
    cs[2 * j + 1] = sin(th);
  }
  for (uint32_t i = 0; i < n; i++)
    for (uint32_t j = 0; j < sides; j++)
      ring[i * sides + j] = r[i] == 0.0
                                ? gen_frame_point(f, 0, 0, z[i])
                                : gen_frame_point(f, r[i] * cs[2 * j], r[i] * cs[2 * j + 1], z[i]);
  for (uint32_t i = 0; i + 1 < n; i++) {
    if (r[i] == 0.0 && r[i + 1] == 0.0) continue;
    /* Outward normal of this profile segment in the (r, z) plane: the solid
     * is on the left of the walk, so the normal is the walk turned right. */
    double dr = r[i + 1] - r[i], dz = z[i + 1] - z[i];
    double len = sqrt(dr * dr + dz * dz);
    double nr = len > 0 ? dz / len : 0, nz = len > 0 ? -dr / len : 1;
    for (uint32_t j = 0; j < sides; j++) {
      uint32_t j1 = (j + 1) % sides;
      gen_d3 A = ring[i * sides + j], B = ring[i * sides + j1];
      gen_d3 C = ring[(i + 1) * sides + j1], D = ring[(i + 1) * sides + j];
      vec3 nA = gen_d3_to_f(gen_frame_dir(f, nr * cs[2 * j], nr * cs[2 * j + 1], nz));
      vec3 nB = gen_d3_to_f(gen_frame_dir(f, nr * cs[2 * j1], nr * cs[2 * j1 + 1], nz));
      if (r[i] == 0.0) {
        vec3 nn[3] = {v3_norm(v3_add(nA, nB)), nB, nA};
        scene_add_tri(s, gen_d3_to_f(A), gen_d3_to_f(C), gen_d3_to_f(D), nn, mat);
      } else if (r[i + 1] == 0.0) {
        vec3 nn[3] = {nA, nB, v3_norm(v3_add(nA, nB))};
        scene_add_tri(s, gen_d3_to_f(A), gen_d3_to_f(B), gen_d3_to_f(C), nn, mat);
      } else {
        vec3 n0[3] = {nA, nB, nB}, n1[3] = {nA, nB, nA};
        scene_add_tri(s, gen_d3_to_f(A), gen_d3_to_f(B), gen_d3_to_f(C), n0, mat);
        scene_add_tri(s, gen_d3_to_f(A), gen_d3_to_f(C), gen_d3_to_f(D), n1, mat);
      }
    }
  }
  free(cs);
  free(ring);
}

void gen_cylinder(struct scene *s, const struct gen_frame *f, double r0, double r1, double h,
                  uint32_t sides, uint32_t mat) {
  double r[4] = {0, r0, r1, 0}, z[4] = {0, 0, h, h};
  gen_lathe(s, f, r, z, 4, sides, mat);
}
