/* Ray/triangle test and hit-point tests against hand-computed cases: exact t,
 * watertight shared edges and vertices, parallel, grazing and zero-area cases,
 * tmin/tmax boundaries, and self-intersection of offset secondary rays. Every
 * geometric case also runs with coordinates scaled by 1e-4 and 1e4. */
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "renderer/kdtree.h"
#include "renderer/ray.h"
#include "renderer/rng.h"
#include "renderer/scene.h"
#include "renderer/trace.h"
#include "testing.h"

static const float scales[] = {1.0f, 1e-4f, 1e4f};
#define NSCALES 3

static vec3 sc(vec3 v, float s) { return v3_scale(v, s); }

static bool tri_hit(vec3 a, vec3 b, vec3 c, vec3 o, vec3 d, float tmin, float tmax, float *t,
                    float *b1, float *b2) {
  struct trace_isect_ray r;
  trace_isect_prepare(&r, o, d);
  return trace_isect_tri(&r, a, b, c, tmin, tmax, t, b1, b2);
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

/* Unit direction with the given cosine to n (n unit), random azimuth. */
static vec3 dir_around(vec3 n, float cos_t, float phi) {
  vec3 a = fabsf(n.x) > 0.5f ? v3(0, 1, 0) : v3(1, 0, 0);
  vec3 u = v3_norm(v3_cross(n, a)), w = v3_cross(n, u);
  float sin_t = sqrtf(fmaxf(0.0f, 1.0f - cos_t * cos_t));
  return v3_norm(v3_add(v3_scale(n, cos_t),
                        v3_add(v3_scale(u, sin_t * cosf(phi)), v3_scale(w, sin_t * sinf(phi)))));
}

/* A random direction within acos(cos_lo) of n: phi drawn first, as rnd_v3's NOTE. */
static vec3 rnd_around(struct rng *g, vec3 n, float cos_lo) {
  float phi = rnd(g, 0, 6.3f);
  float cos_t = rnd(g, cos_lo, 1.0f);
  return dir_around(n, cos_t, phi);
}

static void test_exact_hits(void) {
  vec3 a = v3(0, 0, 0), b = v3(1, 0, 0), c = v3(0, 1, 0);
  float t, b1, b2;
  /* Scale 1: every quantity is exact. */
  EXPECT(tri_hit(a, b, c, v3(0.25f, 0.25f, 2), v3(0, 0, -1), 0, INFINITY, &t, &b1, &b2));
  EXPECT(t == 2.0f && b1 == 0.25f && b2 == 0.25f);
  EXPECT(tri_hit(a, b, c, v3(0.25f, 0.5f, 2), v3(0, 0, -2), 0, INFINITY, &t, &b1, &b2));
  EXPECT(t == 1.0f && b1 == 0.25f && b2 == 0.5f);
  /* Oblique, from below (back face: no culling). */
  EXPECT(tri_hit(a, b, c, v3(-0.75f, 0.25f, -1), v3(1, 0, 1), 0, INFINITY, &t, &b1, &b2));
  EXPECT(t == 1.0f && b1 == 0.25f && b2 == 0.25f);
  /* Misses beside the triangle. */
  EXPECT(!tri_hit(a, b, c, v3(0.75f, 0.75f, 2), v3(0, 0, -1), 0, INFINITY, &t, &b1, &b2));
  EXPECT(!tri_hit(a, b, c, v3(-0.25f, 0.25f, 2), v3(0, 0, -1), 0, INFINITY, &t, &b1, &b2));
  /* Behind the origin. */
  EXPECT(!tri_hit(a, b, c, v3(0.25f, 0.25f, 2), v3(0, 0, 1), 0, INFINITY, &t, &b1, &b2));
  for (int k = 0; k < NSCALES; k++) {
    float s = scales[k];
    bool ok = tri_hit(sc(a, s), sc(b, s), sc(c, s), sc(v3(0.25f, 0.25f, 2), s), v3(0, 0, -1), 0,
                      INFINITY, &t, &b1, &b2);
    EXPECTF(ok && fabsf(t - 2.0f * s) <= 4e-7f * s && fabsf(b1 - 0.25f) < 1e-6f &&
                fabsf(b2 - 0.25f) < 1e-6f,
            "scale %g: t %.9g b %g %g", s, t, b1, b2);
    ok = tri_hit(sc(a, s), sc(b, s), sc(c, s), sc(v3(0.3f, 0.2f, 1.5f), s), v3(-0.1f, 0.2f, -1.0f),
                 0, INFINITY, &t, &b1, &b2);
    /* o + 1.5 d = (0.15, 0.5, 0) in unscaled units. */
    EXPECTF(ok && fabsf(t - 1.5f * s) <= 1e-6f * s && fabsf(b1 - 0.15f) < 1e-5f &&
                fabsf(b2 - 0.5f) < 1e-5f,
            "scale %g oblique: t %.9g b %g %g", s, t, b1, b2);
  }
}

static void test_tmin_tmax(void) {
  vec3 a = v3(0, 0, 0), b = v3(1, 0, 0), c = v3(0, 1, 0), o = v3(0.25f, 0.25f, 2), d = v3(0, 0, -1);
  float t, b1, b2;
  EXPECT(!tri_hit(a, b, c, o, d, 0, 2.0f, &t, &b1, &b2));
  EXPECT(tri_hit(a, b, c, o, d, 0, nextafterf(2.0f, INFINITY), &t, &b1, &b2) && t == 2.0f);
  EXPECT(!tri_hit(a, b, c, o, d, 2.0f, INFINITY, &t, &b1, &b2));
  EXPECT(tri_hit(a, b, c, o, d, nextafterf(2.0f, 0), INFINITY, &t, &b1, &b2) && t == 2.0f);
  EXPECT(!tri_hit(a, b, c, o, d, 3.0f, 4.0f, &t, &b1, &b2));
  EXPECT(!tri_hit(a, b, c, o, d, 0.0f, 1.0f, &t, &b1, &b2));

  /* Scene level: tie rule (equal t -> smaller id) and ignore_prim. */
  struct scene s;
  scene_init(&s);
  scene_add_tri(&s, a, b, c, NULL, 0);
  scene_add_tri(&s, a, b, c, NULL, 0);
  scene_add_tri(&s, v3(0, 0, 1), v3(1, 0, 1), v3(0, 1, 1), NULL, 0);
  struct ray r = make_ray(o, d, 0, INFINITY);
  struct trace_hit h;
  EXPECT(trace_brute(&s, &r, &h) && h.prim == 2 && h.t == 1.0f);
  r.ignore_prim = 2;
  EXPECT(trace_brute(&s, &r, &h) && h.prim == 0 && h.t == 2.0f);
  r.ignore_prim = 0;
  r.tmin = 1.0f;
  EXPECT(trace_brute(&s, &r, &h) && h.prim == 1 && h.t == 2.0f);
  r.tmax = 2.0f;
  EXPECT(!trace_brute(&s, &r, &h) && h.prim == -1);
  /* A degenerate ray direction hits nothing. */
  r = make_ray(o, v3(0, 0, 0), 0, INFINITY);
  EXPECT(!trace_brute(&s, &r, &h));
  scene_fini(&s);
}

/* Two coplanar triangles sharing the diagonal (0,0,0)-(1,1,0) of the unit
 * square, and the same pair folded (far vertex of the second raised). Rays
 * through points of the shared edge must hit at least one of them. */
static void test_shared_edge(void) {
  struct rng g = rng_make(11, 1);
  for (int fold = 0; fold < 2; fold++)
    for (int k = 0; k < NSCALES; k++) {
      float s = scales[k];
      vec3 p0 = sc(v3(0, 0, 0), s), p1 = sc(v3(1, 0, 0), s), p2 = sc(v3(1, 1, 0), s),
           p3 = sc(v3(0, 1, fold ? 0.3f : 0.0f), s);
      int neither = 0, both = 0, bad_t = 0, n = 0;
      for (int i = 0; i < 3000; i++) {
        /* Points on the edge: the exact midpoint, dyadic points, random ones. */
        float u = i == 0 ? 0.5f : (i < 64 ? (float)i / 64.0f : rnd(&g, 0.01f, 0.99f));
        vec3 q = v3(u * s, u * s, 0);
        vec3 d;
        if (i < 200) d = v3(0, 0, -1);
        else if (i < 400) {                /* Grazing: elevation down to ~1e-3 rad. */
          float e = rnd(&g, -3.0f, -1.0f); /* z first, as rnd_v3's NOTE */
          float ay = rnd(&g, 0, 6.3f);
          float ax = rnd(&g, 0, 6.3f);
          d = v3_norm(v3(cosf(ax), sinf(ay), -powf(10.0f, e)));
        } else d = rnd_around(&g, v3(0, 0, -1), fold ? 0.8f : 0.05f);
        if (fold && d.z > -0.8f) continue; /* the fold is only crossed by steep rays */
        float back = rnd(&g, 0.5f, 4.0f) * s;
        vec3 o = v3_sub(q, v3_scale(d, back));
        float t1, t2, b1, b2;
        bool h1 = tri_hit(p0, p1, p2, o, d, 0, INFINITY, &t1, &b1, &b2);
        bool h2 = tri_hit(p0, p2, p3, o, d, 0, INFINITY, &t2, &b1, &b2);
        n++;
        neither += !h1 && !h2;
        both += h1 && h2;
        float t = h1 ? t1 : t2;
        if ((h1 || h2) && !(fabsf(t - back) <= 1e-5f * back)) bad_t++;
      }
      EXPECTF(neither == 0, "fold %d scale %g: %d of %d rays through the shared edge hit neither",
              fold, s, neither, n);
      EXPECTF(bad_t == 0, "fold %d scale %g: %d hits with a wrong t", fold, s, bad_t);
      (void)both;
    }
  /* The exact midpoint straight down hits both (both edge functions are 0). */
  float t, b1, b2;
  vec3 o = v3(0.5f, 0.5f, 1), d = v3(0, 0, -1);
  EXPECT(tri_hit(v3(0, 0, 0), v3(1, 0, 0), v3(1, 1, 0), o, d, 0, INFINITY, &t, &b1, &b2) &&
         t == 1.0f);
  EXPECT(tri_hit(v3(0, 0, 0), v3(1, 1, 0), v3(0, 1, 0), o, d, 0, INFINITY, &t, &b1, &b2) &&
         t == 1.0f);
}

/* A fan of 6 triangles around a shared centre vertex: rays through the centre
 * (and very near it) never leak. */
static void test_shared_vertex(void) {
  struct rng g = rng_make(12, 1);
  for (int k = 0; k < NSCALES; k++) {
    float s = scales[k];
    vec3 ctr = sc(v3(0.5f, 0.25f, 0.0f), s), ring[6];
    for (int j = 0; j < 6; j++) {
      float ang = (float)j * 1.0471976f + 0.1f;
      ring[j] = v3_add(ctr, sc(v3(cosf(ang), sinf(ang), 0.05f * (float)(j % 2)), s));
    }
    int leaks = 0, n = 0;
    for (int i = 0; i < 4000; i++) {
      vec3 q = ctr;
      if (i >= 2000) {                     /* near the centre too */
        float dy = rnd(&g, -1e-5f, 1e-5f); /* y first, as rnd_v3's NOTE */
        float dx = rnd(&g, -1e-5f, 1e-5f);
        q = v3_add(ctr, sc(v3(dx, dy, 0), s));
      }
      vec3 d = rnd_around(&g, v3(0, 0, i % 2 ? -1 : 1), 0.9f);
      vec3 o = v3_sub(q, v3_scale(d, rnd(&g, 0.5f, 3.0f) * s));
      bool any = false;
      for (int j = 0; j < 6 && !any; j++) {
        float t, b1, b2;
        any = tri_hit(ctr, ring[j], ring[(j + 1) % 6], o, d, 0, INFINITY, &t, &b1, &b2);
      }
      leaks += !any;
      n++;
    }
    EXPECTF(leaks == 0, "scale %g: %d of %d rays through the fan centre leaked", s, leaks, n);
  }
}

static void test_parallel_and_grazing(void) {
  float t, b1, b2;
  for (int k = 0; k < NSCALES; k++) {
    float s = scales[k];
    vec3 a = sc(v3(0, 0, 0), s), b = sc(v3(1, 0, 0), s), c = sc(v3(0, 1, 0), s);
    /* In the plane z = 0, through the interior; just above; just below. */
    EXPECT(!tri_hit(a, b, c, sc(v3(-1, 0.25f, 0), s), v3(1, 0, 0), 0, INFINITY, &t, &b1, &b2));
    EXPECT(!tri_hit(a, b, c, sc(v3(-1, 0.25f, 1e-7f), s), v3(1, 0, 0), 0, INFINITY, &t, &b1, &b2));
    EXPECT(
        !tri_hit(a, b, c, sc(v3(-1, 0.25f, -1e-7f), s), v3(1, 0.3f, 0), 0, INFINITY, &t, &b1, &b2));
    /* Grazing along edges, in the plane: along a-b, along the hypotenuse. */
    EXPECT(!tri_hit(a, b, c, sc(v3(-1, 0, 0), s), v3(1, 0, 0), 0, INFINITY, &t, &b1, &b2));
    EXPECT(!tri_hit(a, b, c, sc(v3(2, -1, 0), s), v3(-1, 1, 0), 0, INFINITY, &t, &b1, &b2));
    EXPECT(!tri_hit(a, b, c, sc(v3(0, -1, 0), s), v3(0, 1, 0), 0, INFINITY, &t, &b1, &b2));
    /* Along an edge but lifted off the plane. */
    EXPECT(!tri_hit(a, b, c, sc(v3(-1, 0, 1e-6f), s), v3(1, 0, 0), 0, INFINITY, &t, &b1, &b2));
    /* A tilted plane x + y = 1 containing the ray exactly, and parallel off it. */
    vec3 ta = sc(v3(1, 0, 0), s), tb = sc(v3(0, 1, 0), s), tc = sc(v3(0.5f, 0.5f, 1), s);
    EXPECT(!tri_hit(ta, tb, tc, sc(v3(2, -1, 0.3f), s), v3(-1, 1, 0), 0, INFINITY, &t, &b1, &b2));
    EXPECT(
        !tri_hit(ta, tb, tc, sc(v3(2, -0.999f, 0.3f), s), v3(-1, 1, 0), 0, INFINITY, &t, &b1, &b2));
    EXPECT(!tri_hit(ta, tb, tc, sc(v3(1.5f, -0.5f, 0.25f), s), v3(-1, 1, 0), 0, INFINITY, &t, &b1,
                    &b2));
  }
}

static void test_zero_area(void) {
  struct rng g = rng_make(13, 1);
  for (int k = 0; k < NSCALES; k++) {
    float s = scales[k];
    /* Collinear (c = 2b - a exactly), along a diagonal, and repeated vertices. */
    vec3 tris[5][3] = {
        {v3(0, 0, 0), v3(1, 1, 0), v3(2, 2, 0)},
        {v3(0, 0, 0), v3(1, 1, 1), v3(2, 2, 2)},
        {v3(0.25f, 0.5f, 0.75f), v3(0.5f, 1.0f, 1.5f), v3(1.0f, 2.0f, 3.0f)},
        {v3(0, 0, 0), v3(0, 0, 0), v3(1, 0.5f, 0)},
        {v3(0.5f, 0.5f, 0.5f), v3(0.5f, 0.5f, 0.5f), v3(0.5f, 0.5f, 0.5f)},
    };
    int hits = 0;
    for (int i = 0; i < 5; i++) {
      vec3 a = sc(tris[i][0], s), b = sc(tris[i][1], s), c = sc(tris[i][2], s);
      for (int j = 0; j < 2000; j++) {
        /* Aim at points of the segment, including its vertices. */
        float u = j < 3 ? 0.5f * (float)j : rng_f32(&g);
        vec3 q = v3_add(v3_scale(a, 1.0f - u), v3_scale(c, u));
        if (j == 1) q = b;
        vec3 d = v3_norm(rnd_v3(&g, -1, 1));
        vec3 o = v3_sub(q, v3_scale(d, 2.0f * s));
        float t, b1, b2;
        hits += tri_hit(a, b, c, o, d, 0, INFINITY, &t, &b1, &b2);
        hits += tri_hit(b, c, a, o, d, 0, INFINITY, &t, &b1, &b2);
      }
    }
    EXPECTF(hits == 0, "scale %g: zero-area triangles were hit %d times", s, hits);
  }
}

/* Mesh builders for the self-intersection test. */
static void add_quad(struct scene *s, vec3 a, vec3 b, vec3 c, vec3 d) {
  scene_add_tri(s, a, b, c, NULL, 0);
  scene_add_tri(s, a, c, d, NULL, 0);
}

/* Latitude-longitude sphere: its quads are planar isosceles trapezoids, so the
 * mesh is a convex polyhedron (up to vertex rounding). */
static void build_sphere(struct scene *s, vec3 ctr, float rad, int nlat, int nlon) {
  for (int i = 0; i < nlat; i++)
    for (int j = 0; j < nlon; j++) {
      vec3 p[4];
      for (int k = 0; k < 4; k++) {
        int ii = i + (k == 1 || k == 2), jj = j + (k >= 2);
        double th = 3.14159265358979 * ii / nlat, ph = 2 * 3.14159265358979 * jj / nlon;
        p[k] = v3_add(ctr, v3((float)(rad * sin(th) * cos(ph)), (float)(rad * sin(th) * sin(ph)),
                              (float)(rad * cos(th))));
      }
      if (i == 0) scene_add_tri(s, p[0], p[1], p[2], NULL, 0);
      else if (i == nlat - 1) scene_add_tri(s, p[0], p[1], p[3], NULL, 0);
      else add_quad(s, p[0], p[1], p[2], p[3]);
    }
}

/* A tilted plane (normal ~ (1,2,3)) tessellated n x n, vertices rounded. */
static void build_plane(struct scene *s, vec3 ctr, float size, int n) {
  vec3 nn = v3_norm(v3(1, 2, 3));
  vec3 u = v3_norm(v3_cross(nn, v3(1, 0, 0))), w = v3_cross(nn, u);
  for (int i = 0; i < n; i++)
    for (int j = 0; j < n; j++) {
      vec3 p[4];
      for (int k = 0; k < 4; k++) {
        float x = ((float)(i + (k == 1 || k == 2)) / (float)n - 0.5f) * size;
        float y = ((float)(j + (k >= 2)) / (float)n - 0.5f) * size;
        p[k] = v3_add(ctr, v3_add(v3_scale(u, x), v3_scale(w, y)));
      }
      add_quad(s, p[0], p[1], p[2], p[3]);
    }
}

/* Hit the mesh from outside, spawn rays from the offset hit point into the
 * hemisphere facing the incoming ray (and, for the open plane, the other one
 * too): they must hit nothing (convex sphere outward, plane both sides). */
static void self_isect_case(const char *name, int is_plane, vec3 ctr, float size) {
  struct scene s;
  scene_init(&s);
  if (is_plane) build_plane(&s, ctr, size, 48);
  else build_sphere(&s, ctr, size, 40, 60);
  struct kd_tree kd;
  struct kd_build_params bp;
  kd_build_params_default(&bp);
  kd_build(&kd, &s, &bp, NULL);
  struct trace_ctx tr;
  trace_init(&tr, &s, &kd, mem_port_native(), NULL);
  struct rng g = rng_make(14, (uint64_t)is_plane * 7 + (uint64_t)(size * 1000.0f));
  int primaries = 0, spawned = 0, self_hits = 0, brute_hits = 0, inward_bad = 0;
  for (int i = 0; i < 1500; i++) {
    vec3 aim = v3_add(ctr, v3_scale(rnd_v3(&g, -0.4f, 0.4f), size));
    vec3 d = v3_norm(rnd_v3(&g, -1, 1));
    struct ray r = make_ray(v3_sub(aim, v3_scale(d, 3.0f * size)), d, 0, INFINITY);
    struct trace_hit h;
    if (!trace_closest(&tr, &r, &h)) continue;
    primaries++;
    vec3 err, p = trace_hit_point(&s, &h, &err);
    vec3 n = trace_geom_normal(&s, &h);
    if (v3_dot(n, d) > 0) n = v3_scale(n, -1.0f); /* face the incoming ray */
    for (int j = 0; j < 12; j++) {
      /* Cosines to the normal from grazing (0.01) to straight out. */
      float ct = j < 4 ? 0.01f * (float)(1 + j) : rnd(&g, 0.0f, 1.0f);
      if (ct < 0.005f) ct = 0.005f;
      int side = (is_plane && (j % 3 == 2)) ? -1 : 1;
      vec3 w = dir_around(v3_scale(n, (float)side), ct, rnd(&g, 0, 6.3f));
      vec3 o2 = trace_offset_origin(p, err, n, w);
      struct ray r2 = make_ray(o2, w, 0, INFINITY);
      struct trace_hit h2;
      spawned++;
      if (trace_closest(&tr, &r2, &h2)) self_hits++;
      if (j < 3 && trace_brute(&s, &r2, &h2)) brute_hits++;
      /* With ignore_prim as well (how the renderer spawns them). */
      r2.ignore_prim = h.prim;
      if (trace_any(&tr, &r2)) self_hits++;
    }
    if (!is_plane) {
      /* Inward at >= 30 degrees from the surface: the first hit is far away. */
      vec3 w = rnd_around(&g, v3_scale(n, -1.0f), 0.5f);
      vec3 o2 = trace_offset_origin(p, err, n, w);
      struct ray r2 = make_ray(o2, w, 0, INFINITY);
      struct trace_hit h2;
      if (!trace_closest(&tr, &r2, &h2) || h2.prim == h.prim || h2.t < 0.5f * size) inward_bad++;
    }
  }
  EXPECTF(primaries > 300, "%s: only %d primary hits", name, primaries);
  EXPECTF(self_hits == 0 && brute_hits == 0,
          "%s: %d of %d spawned rays hit the mesh again (%d by brute force)", name, self_hits,
          spawned, brute_hits);
  EXPECTF(inward_bad == 0, "%s: %d inward rays hit near their origin", name, inward_bad);
  kd_fini(&kd);
  scene_fini(&s);
}

static void test_self_intersection(void) {
  for (int k = 0; k < NSCALES; k++) {
    float s = scales[k];
    char name[64];
    snprintf(name, sizeof name, "sphere@%g", s);
    self_isect_case(name, 0, v3(0, 0, 0), s);
    snprintf(name, sizeof name, "far sphere@%g", s);
    self_isect_case(name, 0, sc(v3(100.0f, -50.0f, 20.0f), s), s);
    snprintf(name, sizeof name, "plane@%g", s);
    self_isect_case(name, 1, sc(v3(0.3f, 0.1f, -0.2f), s), 2.0f * s);
    snprintf(name, sizeof name, "far plane@%g", s);
    self_isect_case(name, 1, sc(v3(-300.0f, 40.0f, 75.0f), s), 2.0f * s);
  }
}

static void test_hit_point(void) {
  struct scene s;
  scene_init(&s);
  scene_add_tri(&s, v3(0, 0, 0), v3(4, 0, 0), v3(0, 4, 0), NULL, 0);
  struct ray r = make_ray(v3(1, 2, 5), v3(0, 0, -1), 0, INFINITY);
  struct trace_hit h;
  EXPECT(trace_brute(&s, &r, &h) && h.prim == 0 && h.t == 5.0f);
  vec3 err, p = trace_hit_point(&s, &h, &err);
  EXPECT(p.x == 1.0f && p.y == 2.0f && p.z == 0.0f);
  EXPECT(err.x > 0 && err.x < 1e-5f && err.z == 0.0f);
  vec3 n = trace_geom_normal(&s, &h);
  EXPECT(n.x == 0 && n.y == 0 && n.z == 1.0f);
  /* z is exact here (err.z == 0), so PBRT's offset leaves the point in the
   * plane; a ray leaving it has t == 0 on its own triangle and so misses it. */
  vec3 o = trace_offset_origin(p, err, n, v3(0, 0, 1));
  EXPECT(o.z == 0.0f && o.x == p.x && o.y == p.y);
  r = make_ray(o, v3(0.3f, 0.1f, 1), 0, INFINITY);
  EXPECT(!trace_brute(&s, &r, &h));
  r = make_ray(o, v3(0.3f, 0.1f, -1), 0, INFINITY);
  EXPECT(!trace_brute(&s, &r, &h));
  o = trace_offset_origin(p, v3(1e-3f, 1e-3f, 1e-3f), n, v3(0.3f, 0, -1));
  EXPECT(o.z < -1e-3f && o.x == p.x);
  scene_fini(&s);
}

/* The tracer announces every node, index and triangle access. */
struct count_ctx {
  uint64_t node_loads, idx_loads, tri_loads, cycles, bad;
  struct trace_layout l;
};

static bool in_region(uint64_t addr, uint64_t base) {
  return addr >= base && addr - base < (1ull << TRACE_REGION_SHIFT);
}

static void count_load(void *ctx, uint64_t addr, uint32_t size, unsigned cls) {
  struct count_ctx *c = ctx;
  if (cls == TRACE_CLASS_NODE && size == 8 && in_region(addr, c->l.node_base) &&
      (addr - c->l.node_base) % 8 == 0)
    c->node_loads++;
  else if (cls == TRACE_CLASS_NODE && size == 4 && in_region(addr, c->l.prim_idx_base))
    c->idx_loads++;
  else if (cls == TRACE_CLASS_GEOMETRY && size == c->l.tri_bytes &&
           in_region(addr, c->l.tri_base) && (addr - c->l.tri_base) % c->l.tri_bytes == 0)
    c->tri_loads++;
  else c->bad++;
}

static void count_compute(void *ctx, uint64_t cycles) {
  ((struct count_ctx *)ctx)->cycles += cycles;
}

static void test_memory_announcements(void) {
  struct scene s;
  scene_init(&s);
  build_sphere(&s, v3(0, 0, 0), 1.0f, 10, 16);
  struct kd_tree kd;
  struct kd_build_params bp;
  kd_build_params_default(&bp);
  kd_build(&kd, &s, &bp, NULL);
  struct count_ctx c;
  memset(&c, 0, sizeof c);
  trace_layout_default(&c.l);
  static const struct mem_ops ops = {count_load, NULL, count_compute, NULL, NULL, NULL};
  struct mem_port port = {&ops, &c};
  struct trace_ctx tr;
  trace_init(&tr, &s, &kd, port, NULL);
  struct rng g = rng_make(15, 1);
  int hits = 0;
  for (int i = 0; i < 500; i++) {
    vec3 d = v3_norm(rnd_v3(&g, -1, 1));
    struct ray r = make_ray(v3_scale(d, -3.0f), v3_add(d, v3(0.1f, 0, 0)), 0, INFINITY);
    struct trace_hit h;
    hits += trace_closest(&tr, &r, &h);
    trace_any(&tr, &r);
  }
  EXPECT(hits > 400);
  EXPECT(c.bad == 0);
  EXPECT(c.node_loads == tr.stats.node_visits && c.tri_loads == tr.stats.tri_tests);
  EXPECT(c.idx_loads >= c.tri_loads && c.tri_loads > 0);
  EXPECT(c.cycles == 7 * tr.stats.node_visits + 30 * tr.stats.tri_tests);
  kd_fini(&kd);
  scene_fini(&s);
}

int main(void) {
  test_exact_hits();
  test_tmin_tmax();
  test_shared_edge();
  test_shared_vertex();
  test_parallel_and_grazing();
  test_zero_area();
  test_hit_point();
  test_memory_announcements();
  test_self_intersection();
  return testing_done("test_trace");
}
