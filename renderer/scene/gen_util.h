/* Private mesh builders shared by the procedural generators (gen_*.c). Not a
 * public contract: only renderer/scene/gen*.c include it.
 * Invariant every builder keeps: a vertex shared by several triangles of one
 * mesh is computed once (or by one expression of the same integer inputs), so
 * its float coordinates are bit-identical wherever it appears. The watertight
 * ray/triangle test relies on that. Geometry is computed in double and rounded
 * to float only when a triangle is emitted. */
#ifndef RTSIM_RENDERER_SCENE_GEN_UTIL_H
#define RTSIM_RENDERER_SCENE_GEN_UTIL_H

#include <math.h>
#include <stdint.h>

#include "renderer/vec.h"

struct scene;

/* pi in double; M_PI is not part of strict C11 with only POSIX enabled. */
#define GEN_PI 3.14159265358979323846

/* Double-precision point or direction used while building geometry. */
typedef struct {
  double x, y, z;
} gen_d3;

static inline gen_d3 gen_d3_make(double x, double y, double z) {
  gen_d3 r = {x, y, z};
  return r;
}
static inline gen_d3 gen_d3_add(gen_d3 a, gen_d3 b) {
  return gen_d3_make(a.x + b.x, a.y + b.y, a.z + b.z);
}
static inline gen_d3 gen_d3_sub(gen_d3 a, gen_d3 b) {
  return gen_d3_make(a.x - b.x, a.y - b.y, a.z - b.z);
}
static inline gen_d3 gen_d3_scale(gen_d3 a, double s) {
  return gen_d3_make(a.x * s, a.y * s, a.z * s);
}
static inline double gen_d3_dot(gen_d3 a, gen_d3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline gen_d3 gen_d3_cross(gen_d3 a, gen_d3 b) {
  return gen_d3_make(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static inline double gen_d3_len(gen_d3 a) { return sqrt(gen_d3_dot(a, a)); }
static inline gen_d3 gen_d3_norm(gen_d3 a) {
  double l = gen_d3_len(a);
  return l > 0.0 ? gen_d3_scale(a, 1.0 / l) : a;
}
static inline vec3 gen_d3_to_f(gen_d3 a) { return v3((float)a.x, (float)a.y, (float)a.z); }

/* An orthonormal frame: origin o and axes u, v, w (w is the "up" or axis of
 * revolution). Builders take local coordinates and map them through it. */
struct gen_frame {
  gen_d3 o, u, v, w;
};

/* Axis-aligned frame at `o`. */
struct gen_frame gen_frame_at(gen_d3 o);
/* Frame at `o` whose w axis is the direction `w` (normalised here); u, v are
 * chosen deterministically from w alone. */
struct gen_frame gen_frame_along(gen_d3 o, gen_d3 w);
/* Local point (x, y, z) to world. */
gen_d3 gen_frame_point(const struct gen_frame *f, double x, double y, double z);
/* Local direction (x, y, z) to world (no translation). */
gen_d3 gen_frame_dir(const struct gen_frame *f, double x, double y, double z);

/* One triangle with flat normal (counter-clockwise seen from the front). */
void gen_tri(struct scene *s, gen_d3 a, gen_d3 b, gen_d3 c, uint32_t mat);
/* Quad a, b, c, d (counter-clockwise from the front) as triangles abc, acd. */
void gen_quad(struct scene *s, gen_d3 a, gen_d3 b, gen_d3 c, gen_d3 d, uint32_t mat);
/* Rectangle o, o+eu, o+eu+ev, o+ev split into nu x nv cells (2 triangles each);
 * front side is eu x ev. 2 nu nv triangles. */
void gen_grid(struct scene *s, gen_d3 o, gen_d3 eu, gen_d3 ev, uint32_t nu, uint32_t nv,
              uint32_t mat);
/* Closed box with half extents (hx, hy, hz) about the frame origin, outward
 * winding, flat normals. 12 triangles. */
void gen_box(struct scene *s, const struct gen_frame *f, double hx, double hy, double hz,
             uint32_t mat);
/* Axis-aligned closed box spanning lo..hi. 12 triangles. */
void gen_box_aa(struct scene *s, gen_d3 lo, gen_d3 hi, uint32_t mat);
/* Sphere as the 6 faces of a cube projected onto it, each face tess x tess
 * quads: 12 tess^2 triangles, closed, outward, normals radial. */
void gen_sphere(struct scene *s, gen_d3 centre, double radius, uint32_t tess, uint32_t mat);
uint64_t gen_sphere_tri_count(uint32_t tess);

/* Surface of revolution about the frame's w axis: profile points (r[i], z[i]),
 * i < n, revolved with `sides` segments. Walk the profile with the solid on the
 * left (r to the right, z up) so faces point outward; a point with r == 0 is a
 * single apex vertex. Normals are smooth around the axis, flat along the
 * profile. Triangles: gen_lathe_tri_count. */
void gen_lathe(struct scene *s, const struct gen_frame *f, const double *r, const double *z,
               uint32_t n, uint32_t sides, uint32_t mat);
uint64_t gen_lathe_tri_count(const double *r, uint32_t n, uint32_t sides);
/* Closed cylinder (or frustum) of radii r0 (base) and r1 (top) and height h
 * along the frame's w axis, from the origin up. 4 sides triangles. */
void gen_cylinder(struct scene *s, const struct gen_frame *f, double r0, double r1, double h,
                  uint32_t sides, uint32_t mat);

#endif
