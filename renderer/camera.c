/* Pinhole camera and Hilbert-curve pixel order. */
#include "renderer/camera.h"

#include <float.h>
#include <math.h>

#include "renderer/ray.h"
#include "renderer/rng.h"
#include "renderer/scene.h"
#include "sim/err.h"

/* The view direction and the unnormalized right vector: up is scaled by a
 * power of two first (exact), so a tiny or huge up gives the frame a unit up
 * would, without squares that underflow or overflow. */
static void camera_axes(const struct scene_camera *c, vec3 *forward, vec3 *up, vec3 *right) {
  *forward = v3_unit(v3_sub(c->at, c->from));
  *up = v3_pow2_scaled(c->up);
  *right = v3_cross(*forward, *up);
}

enum camera_fault camera_check(const struct scene_camera *c) {
  vec3 f, u, r;
  camera_axes(c, &f, &u, &r);
  if (f.x == 0.0f && f.y == 0.0f && f.z == 0.0f) return CAMERA_NO_VIEW;
  /* Each component of the cross product against a bound on its rounding
   * error (the view direction's normalization, the products and the
   * difference: a few units in the last place of the larger product, 8
   * FLT_EPSILON taken). Where the whole vector is not far above its bound,
   * right's direction, the image's roll, would be rounding noise: up is
   * parallel to the view as far as floats can tell. An exactly parallel or
   * zero up gives a zero cross product, always refused; an up merely tiny or
   * huge is scaled first and passes. */
  /* In double, where no product or square of these floats underflows. */
  const double eps = 8.0 * FLT_EPSILON;
  double bx = eps * (fabs((double)f.y * u.z) + fabs((double)f.z * u.y));
  double by = eps * (fabs((double)f.z * u.x) + fabs((double)f.x * u.z));
  double bz = eps * (fabs((double)f.x * u.y) + fabs((double)f.y * u.x));
  double r2 = (double)r.x * r.x + (double)r.y * r.y + (double)r.z * r.z;
  double b2 = bx * bx + by * by + bz * bz;
  return r2 > 64.0 * 64.0 * b2 ? CAMERA_OK : CAMERA_BAD_UP;
}

void camera_frame_init(struct camera_frame *cf, const struct scene_camera *c, uint32_t width,
                       uint32_t height) {
  float half_h = tanf(c->fov_deg * 0.5f * 3.14159265358979f / 180.0f);
  float half_w = half_h * (float)width / (float)height;
  cf->origin = c->from;
  vec3 up_scaled, right_raw;
  camera_axes(c, &cf->forward, &up_scaled, &right_raw);
  vec3 right = v3_unit(right_raw);
  vec3 up = v3_cross(right, cf->forward);
  cf->right = v3_scale(right, half_w);
  cf->up = v3_scale(up, half_h);
  cf->width = width;
  cf->height = height;
}

void camera_primary(const struct camera_frame *cf, uint32_t x, uint32_t y, uint64_t seed,
                    struct ray *r) {
  float u = ((float)x + 0.5f) / (float)cf->width * 2.0f - 1.0f;
  float v = 1.0f - ((float)y + 0.5f) / (float)cf->height * 2.0f;
  r->o = cf->origin;
  r->d = v3_norm(v3_add(cf->forward, v3_add(v3_scale(cf->right, u), v3_scale(cf->up, v))));
  r->tmin = 0.0f;
  r->tmax = INFINITY;
  r->pixel = y * cf->width + x;
  r->w = v3(1, 1, 1);
  r->ignore_prim = -1;
  r->path = (uint32_t)rng_hash2(seed, r->pixel);
  r->depth = 0;
  r->type = RAY_PRIMARY;
  r->light = 0;
  r->flags = 0;
  r->hit_prim = -1;
}

/* Classic Hilbert index -> (x, y) on an n x n grid, n a power of two. */
static void hilbert_d2xy(uint32_t n, uint64_t d, uint32_t *x, uint32_t *y) {
  uint32_t rx, ry, t;
  uint64_t s;
  *x = *y = 0;
  for (s = 1; s < n; s *= 2) {
    rx = 1u & (uint32_t)(d / 2);
    ry = 1u & (uint32_t)(d ^ rx);
    if (ry == 0) {
      if (rx == 1) {
        *x = (uint32_t)s - 1 - *x;
        *y = (uint32_t)s - 1 - *y;
      }
      t = *x;
      *x = *y;
      *y = t;
    }
    *x += (uint32_t)s * rx;
    *y += (uint32_t)s * ry;
    d /= 4;
  }
}

void camera_hilbert_order(uint32_t width, uint32_t height, uint32_t *order) {
  uint32_t n = 1;
  while (n < width || n < height) n *= 2;
  uint64_t k = 0;
  for (uint64_t d = 0; d < (uint64_t)n * n; d++) {
    uint32_t x, y;
    hilbert_d2xy(n, d, &x, &y);
    if (x < width && y < height) order[k++] = y * width + x;
  }
  CHECK_EQ(k, (uint64_t)width * height);
}
