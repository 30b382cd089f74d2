/* Small 3-vector helpers on float[3]-like structs. Header-only because they are
 * tiny and sit on every hot path. */
#ifndef RTSIM_RENDERER_VEC_H
#define RTSIM_RENDERER_VEC_H

#include <math.h>
#include <stdint.h>

typedef struct {
  float x, y, z;
} vec3;

static inline vec3 v3(float x, float y, float z) {
  vec3 r = {x, y, z};
  return r;
}
static inline vec3 v3_add(vec3 a, vec3 b) { return v3(a.x + b.x, a.y + b.y, a.z + b.z); }
static inline vec3 v3_sub(vec3 a, vec3 b) { return v3(a.x - b.x, a.y - b.y, a.z - b.z); }
static inline vec3 v3_mul(vec3 a, vec3 b) { return v3(a.x * b.x, a.y * b.y, a.z * b.z); }
static inline vec3 v3_scale(vec3 a, float s) { return v3(a.x * s, a.y * s, a.z * s); }
static inline float v3_dot(vec3 a, vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline vec3 v3_cross(vec3 a, vec3 b) {
  return v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static inline float v3_len(vec3 a) { return sqrtf(v3_dot(a, a)); }
static inline vec3 v3_norm(vec3 a) {
  float l = v3_len(a);
  return l > 0.0f ? v3_scale(a, 1.0f / l) : a;
}
/* a scaled by the power of two that brings its largest component into [1, 2):
 * exact (only exponents change), so a direction computed from the result is
 * the one computed from a, without the underflow or overflow of squaring very
 * small or large components. a itself when it is zero or not finite. */
static inline vec3 v3_pow2_scaled(vec3 a) {
  float m = fmaxf(fabsf(a.x), fmaxf(fabsf(a.y), fabsf(a.z)));
  if (!(m > 0.0f) || !isfinite(m)) return a;
  int e;
  (void)frexpf(m, &e); /* m = f 2^e, f in [0.5, 1) */
  return v3(ldexpf(a.x, 1 - e), ldexpf(a.y, 1 - e), ldexpf(a.z, 1 - e));
}
/* a / |a| at any scale (v3_norm's bits wherever v3_norm neither underflows
 * nor overflows); the zero vector stays zero. */
static inline vec3 v3_unit(vec3 a) { return v3_norm(v3_pow2_scaled(a)); }
/* max and min of two non-NaN floats: one compare, where fmaxf and fminf are
 * library calls (their NaN rule keeps the compiler from using maxss). A tie
 * gives b: max_nonnan(+0, -0) is -0 from any compiler, where fmaxf leaves the
 * sign to the library or the compiler (on x86-64 glibc's gives b, clang's
 * inline code a). */
static inline float max_nonnan(float a, float b) { return a > b ? a : b; }
static inline float min_nonnan(float a, float b) { return a < b ? a : b; }

/* The next float above x (finite): nextafterf(x, INFINITY) without the call. */
static inline float float_next_up(float x) {
  union {
    float f;
    uint32_t u;
  } v = {x};
  if (x == 0.0f) return 0x1p-149f;
  v.u = x > 0.0f ? v.u + 1 : v.u - 1;
  return v.f;
}

static inline float v3_get(vec3 a, int axis) { return axis == 0 ? a.x : axis == 1 ? a.y : a.z; }
/* Componentwise min and max of vectors without NaN (ties as min_nonnan's). */
static inline vec3 v3_min(vec3 a, vec3 b) {
  return v3(min_nonnan(a.x, b.x), min_nonnan(a.y, b.y), min_nonnan(a.z, b.z));
}
static inline vec3 v3_max(vec3 a, vec3 b) {
  return v3(max_nonnan(a.x, b.x), max_nonnan(a.y, b.y), max_nonnan(a.z, b.z));
}

#endif
