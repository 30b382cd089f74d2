/* rtsim bench --hits (see bench_hits.h). Every structure applies one hit
 * rule (renderer/trav.h): the smallest t, and among equal t the smallest
 * primitive id, so two structures can differ only where their traversal
 * skips a triangle it should test; a tie here is another triangle at
 * exactly the hit's float t, found by tracing the ray again in
 * [t, t] without the hit's triangle. */
#include "app/bench_hits.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "app/app.h"
#include "app/bench_embree.h"
#include "app/bench_rays.h"
#include "renderer/bvh.h"
#include "renderer/ray.h"
#include "renderer/scene.h"
#include "renderer/trace.h"
#include "sim/err.h"

void bench_hits_header(bool embree) {
  printf("scene,set,rays,accel,hits,ties,differ_from_kd,differ_at_tie,differ_other%s\n",
         embree ? ",embree_differ,embree_tie,embree_edge,rtsim_nearer,embree_nearer" : "");
}

/* ---- deciding in double precision ------------------------------------------ */

struct exact_hit {
  double t, margin; /* t: inf if not a hit; margin: the least barycentric */
};

static void sub(double o[3], vec3 p, vec3 q) {
  o[0] = (double)p.x - q.x;
  o[1] = (double)p.y - q.y;
  o[2] = (double)p.z - q.z;
}
static void cross(double o[3], const double a[3], const double b[3]) {
  o[0] = a[1] * b[2] - a[2] * b[1];
  o[1] = a[2] * b[0] - a[0] * b[2];
  o[2] = a[0] * b[1] - a[1] * b[0];
}
static double dot(const double a[3], const double b[3]) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* Ray r against triangle p in double: the barycentric weights are the
 * signed volumes d . (b' x c') etc. of the vertices relative to the origin
 * (all of one sign: the ray passes inside), t from the plane. */
static struct exact_hit exact(const struct scene *s, const struct ray *r, int32_t p) {
  struct exact_hit h = {INFINITY, -INFINITY};
  if (p < 0) return h;
  const struct scene_tri *tri = &s->tris[p];
  const vec3 zero = v3(0, 0, 0);
  double a[3], b[3], c[3], d[3], x[3], u[3];
  sub(a, tri->v[0], r->o);
  sub(b, tri->v[1], r->o);
  sub(c, tri->v[2], r->o);
  sub(d, r->d, zero);
  cross(x, b, c);
  u[0] = dot(d, x);
  cross(x, c, a);
  u[1] = dot(d, x);
  cross(x, a, b);
  u[2] = dot(d, x);
  const double det = u[0] + u[1] + u[2];
  if (det == 0) return h;
  h.margin = fmin(u[0] / det, fmin(u[1] / det, u[2] / det));
  double e1[3], e2[3], n[3];
  sub(e1, tri->v[1], tri->v[0]);
  sub(e2, tri->v[2], tri->v[0]);
  cross(n, e1, e2);
  const double nd = dot(n, d);
  const double t = nd != 0 ? dot(n, a) / nd : INFINITY;
  if (h.margin >= 0 && t > r->tmin && t < r->tmax) h.t = t;
  return h;
}

enum bench_hits_verdict bench_hits_decide(const struct scene *s, const struct ray *r, int32_t a,
                                          int32_t b) {
  const struct exact_hit ha = exact(s, r, a), hb = exact(s, r, b);
  if (isfinite(ha.t) && isfinite(hb.t) && fabs(ha.t - hb.t) <= 1e-9 * fmax(ha.t, hb.t))
    return BENCH_HITS_TIE;
  if ((a >= 0 && fabs(ha.margin) < 1e-5) || (b >= 0 && fabs(hb.margin) < 1e-5))
    return BENCH_HITS_EDGE;
  /* Neither is a hit in double: a miss is right, two claimed hits are not. */
  if (ha.t == hb.t) return a < 0 ? BENCH_HITS_A : b < 0 ? BENCH_HITS_B : BENCH_HITS_EDGE;
  return ha.t < hb.t ? BENCH_HITS_A : BENCH_HITS_B;
}

/* ---- one scene --------------------------------------------------------------- */

bool bench_hits_tie(struct trace_ctx *tr, const struct ray *r, const struct trace_hit *h) {
  if (h->prim < 0) return false;
  struct ray q = *r;
  q.ignore_prim = h->prim;
  q.tmin = -float_next_up(-h->t);
  q.tmax = float_next_up(h->t);
  struct trace_hit o;
  return trace_closest(tr, &q, &o) && o.prim != r->ignore_prim && o.t == h->t;
}

struct set {
  const char *name;
  struct ray *rays;
  uint32_t n;
};

/* The rows of one ray set: tr[0..3) the structures, kd first. */
static void set_rows(const char *scene, struct trace_ctx tr[ACCEL_COUNT], struct set *st,
                     struct bench_embree *be) {
  const uint32_t n = st->n;
  struct trace_hit *kd = xmalloc((unsigned long long)(n ? n : 1) * sizeof *kd);
  int32_t *eprim = be ? xmalloc((unsigned long long)(n ? n : 1) * sizeof *eprim) : NULL;
  if (be) bench_embree_trace(be, st->rays, n, eprim, NULL);
  uint64_t hits = 0, ties = 0;
  for (uint32_t i = 0; i < n; i++) {
    trace_closest(&tr[ACCEL_KD], &st->rays[i], &kd[i]);
    hits += kd[i].prim >= 0;
    ties += bench_hits_tie(&tr[ACCEL_KD], &st->rays[i], &kd[i]);
  }
  for (int k = 0; k < ACCEL_COUNT; k++) {
    uint64_t at_tie = 0, other = 0, v[BENCH_HITS_VERDICTS] = {0}, ediff = 0;
    for (uint32_t i = 0; i < n; i++) {
      struct trace_hit h = kd[i];
      if (k != ACCEL_KD) trace_closest(&tr[k], &st->rays[i], &h);
      if (h.prim != kd[i].prim) {
        if (h.t == kd[i].t) at_tie++;
        else other++;
      }
      if (be && h.prim != eprim[i]) {
        ediff++;
        v[bench_hits_decide(tr[0].scene, &st->rays[i], h.prim, eprim[i])]++;
      }
    }
    printf("%s,%s,%u,%s,%llu,%llu,%llu,%llu,%llu", scene, st->name, n, accel_names[k],
           (unsigned long long)hits, (unsigned long long)ties, (unsigned long long)(at_tie + other),
           (unsigned long long)at_tie, (unsigned long long)other);
    if (be)
      printf(",%llu,%llu,%llu,%llu,%llu", (unsigned long long)ediff,
             (unsigned long long)v[BENCH_HITS_TIE], (unsigned long long)v[BENCH_HITS_EDGE],
             (unsigned long long)v[BENCH_HITS_A], (unsigned long long)v[BENCH_HITS_B]);
    printf("\n");
  }
  fflush(stdout);
  free(eprim);
  free(kd);
}

int bench_hits_scene(const char *scene_path, uint64_t width, uint64_t height, bool embree) {
  struct app_world w;
  if (!app_world_load_as(&w, scene_path, ACCEL_KD)) return 2;
  const uint32_t W = width ? (uint32_t)width : w.scene.width;
  const uint32_t H = height ? (uint32_t)height : w.scene.height;
  struct bench_embree *be = NULL;
  double ebuild = 0;
  if (embree && !(be = bench_embree_from_ply(&w.scene, true, &ebuild))) {
    app_world_fini(&w);
    return 1;
  }
  struct bvh bvh[ACCEL_COUNT];
  struct trace_ctx tr[ACCEL_COUNT];
  struct trace_layout lay;
  trace_layout_default(&lay);
  for (int k = 0; k < ACCEL_COUNT; k++) {
    memset(&bvh[k], 0, sizeof bvh[k]);
    if (k != ACCEL_KD) bvh_build(&bvh[k], &w.scene, (enum accel_kind)k);
    trace_init(&tr[k], &w.scene, &w.kd, mem_port_native(), &lay);
    tr[k].bvh = k != ACCEL_KD ? &bvh[k] : NULL;
  }
  struct set sets[4] = {{"primary", bench_rays_primary(&w.scene, W, H), W * H},
                        {"shadow", NULL, 0},
                        {"diffuse", NULL, 0},
                        {"random", NULL, W * H}};
  sets[1].rays = bench_rays_spawned(&tr[0], sets[0].rays, sets[0].n, W, H, RAY_SHADOW, &sets[1].n);
  sets[2].rays = bench_rays_spawned(&tr[0], sets[0].rays, sets[0].n, W, H, RAY_DIFFUSE, &sets[2].n);
  sets[3].rays = bench_rays_random(&w.scene, sets[3].n, w.scene.seed);
  const char *name = w.scene.name[0] ? w.scene.name : scene_path;
  for (int i = 0; i < 4; i++) {
    set_rows(name, tr, &sets[i], be);
    free(sets[i].rays);
  }
  for (int k = 0; k < ACCEL_COUNT; k++) bvh_fini(&bvh[k]);
  bench_embree_destroy(be);
  app_world_fini(&w);
  return 0;
}
