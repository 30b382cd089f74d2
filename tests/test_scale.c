/* Scale invariance: a scene written in other units (every position times k)
 * must build the same k-d tree and find the same hits, so the same rays,
 * scaled alike, must visit the same nodes and test the same triangles.
 * Oracle: the scene at scale 1. By a power of two every float scales exactly,
 * so every count must be equal; by any other factor the scaled coordinates
 * are rounded, which may still move a SAH near-tie deep in the tree, so node
 * visits and triangle tests must agree within 0.1%, hits and occlusions too.
 * Both split rules, on the three small scenes. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>

#include "renderer/camera.h"
#include "renderer/kdtree.h"
#include "renderer/ray.h"
#include "renderer/scene.h"
#include "renderer/scene/scene_file.h"
#include "renderer/trace.h"
#include "sim/err.h"
#include "sim/mem.h"
#include "testing.h"

#define SCALE_W 96
#define SCALE_H 72

struct scale_counts {
  uint64_t node_visits, tri_tests, hits, occluded;
};

/* Multiply every position of s by k (in double, rounded once to float, as a
 * scene written in the other unit would be). */
static vec3 scaled(vec3 v, double k) {
  return v3((float)(v.x * k), (float)(v.y * k), (float)(v.z * k));
}
static void scale_scene(struct scene *s, double k) {
  for (uint32_t i = 0; i < s->tri_count; i++)
    for (int j = 0; j < 3; j++) s->tris[i].v[j] = scaled(s->tris[i].v[j], k);
  s->camera.from = scaled(s->camera.from, k);
  s->camera.at = scaled(s->camera.at, k);
  for (uint32_t i = 0; i < s->light_count; i++) s->lights[i].pos = scaled(s->lights[i].pos, k);
}

/* Primary rays of a SCALE_W x SCALE_H image and, from each hit, a shadow ray
 * to every light: the counts of the k-d traversal. False if the scene fails to load. */
static bool measure(const char *path, double k, bool clip, struct scale_counts *c) {
  struct scene s;
  struct err e;
  scene_init(&s);
  if (!scene_file_load(&s, path, &e)) {
    fprintf(stderr, "%s:%d:%d: %s\n", e.file, e.line, e.col, e.msg);
    scene_fini(&s);
    return false;
  }
  /* The camera's rays at scale 1, origins scaled: the same rays. (A camera
   * frame built from the scaled camera would round its directions differently.) */
  struct camera_frame cf;
  camera_frame_init(&cf, &s.camera, SCALE_W, SCALE_H);
  scale_scene(&s, k);
  struct kd_build_params bp;
  kd_build_params_default(&bp);
  bp.clip = clip;
  struct kd_tree kd;
  kd_build(&kd, &s, &bp, NULL);
  struct trace_ctx tr;
  trace_init(&tr, &s, &kd, mem_port_native(), NULL);
  c->hits = c->occluded = 0;
  for (uint32_t y = 0; y < SCALE_H; y++)
    for (uint32_t x = 0; x < SCALE_W; x++) {
      struct ray r;
      camera_primary(&cf, x, y, 0, &r);
      r.o = scaled(r.o, k);
      struct trace_hit h;
      if (!trace_closest(&tr, &r, &h)) continue;
      c->hits++;
      vec3 err, p = trace_hit_point(&s, &h, &err), n = trace_geom_normal(&s, &h);
      for (uint32_t l = 0; l < s.light_count; l++) {
        vec3 d = v3_sub(s.lights[l].pos, p);
        vec3 o = trace_offset_origin(p, err, n, d);
        struct ray sr = testing_make_ray(o.x, o.y, o.z, d.x, d.y, d.z, 0.0f, 1.0f);
        sr.ignore_prim = h.prim;
        c->occluded += trace_any(&tr, &sr);
      }
    }
  c->node_visits = tr.stats.node_visits;
  c->tri_tests = tr.stats.tri_tests;
  kd_fini(&kd);
  scene_fini(&s);
  return true;
}

static double rel(uint64_t x, uint64_t ref) {
  return ref ? fabs((double)x - (double)ref) / (double)ref : (x ? 1.0 : 0.0);
}

static void check_scene(const char *file, bool clip) {
  char path[512];
  snprintf(path, sizeof path, "%s/scenes/small/%s", RTSIM_SOURCE_DIR, file);
  const char *splits = clip ? "clipped" : "whole";
  struct scale_counts ref;
  EXPECTF(measure(path, 1.0, clip, &ref), "%s: cannot load", path);
  if (ref.hits == 0) return;
  fprintf(stderr,
          "%s %s scale 1: %llu node visits, %llu triangle tests, %llu hits, %llu occluded\n", file,
          splits, (unsigned long long)ref.node_visits, (unsigned long long)ref.tri_tests,
          (unsigned long long)ref.hits, (unsigned long long)ref.occluded);
  static const double exact[] = {0x1p-10, 0.5, 8.0};
  for (size_t i = 0; i < sizeof exact / sizeof exact[0]; i++) {
    struct scale_counts c;
    if (!measure(path, exact[i], clip, &c)) continue;
    EXPECTF(c.node_visits == ref.node_visits && c.tri_tests == ref.tri_tests &&
                c.hits == ref.hits && c.occluded == ref.occluded,
            "%s %s scale %g: %llu visits, %llu tests, %llu hits, %llu occluded", file, splits,
            exact[i], (unsigned long long)c.node_visits, (unsigned long long)c.tri_tests,
            (unsigned long long)c.hits, (unsigned long long)c.occluded);
  }
  static const double other[] = {1e-4, 0.1, 3.0, 1e4};
  const double tol = 0.001;
  for (size_t i = 0; i < sizeof other / sizeof other[0]; i++) {
    struct scale_counts c;
    if (!measure(path, other[i], clip, &c)) continue;
    double dv = rel(c.node_visits, ref.node_visits), dt = rel(c.tri_tests, ref.tri_tests);
    fprintf(
        stderr,
        "%s %s scale %g: node visits %+.4f%%, triangle tests %+.4f%%, hits %llu, occluded %llu\n",
        file, splits, other[i], 100.0 * ((double)c.node_visits / (double)ref.node_visits - 1.0),
        100.0 * ((double)c.tri_tests / (double)ref.tri_tests - 1.0), (unsigned long long)c.hits,
        (unsigned long long)c.occluded);
    EXPECTF(dv <= tol && dt <= tol,
            "%s %s scale %g: node visits off by %.4f%%, triangle tests by %.4f%%", file, splits,
            other[i], 100.0 * dv, 100.0 * dt);
    /* Rounding the scaled vertices may move an edge by a float: a ray may change. */
    EXPECTF(rel(c.hits, ref.hits) <= tol && rel(c.occluded, ref.occluded) <= tol,
            "%s %s scale %g: %llu hits (%llu at scale 1), %llu occluded (%llu)", file, splits,
            other[i], (unsigned long long)c.hits, (unsigned long long)ref.hits,
            (unsigned long long)c.occluded, (unsigned long long)ref.occluded);
  }
}

int main(void) {
  static const char *const files[] = {"room.yaml", "grove.yaml", "sphereflake.yaml"};
  for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
    check_scene(files[i], false);
    check_scene(files[i], true);
  }
  return testing_done("test_scale");
}
