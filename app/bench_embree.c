/* The Embree peer of rtsim bench --embree (see bench_embree.h). */
#include "app/bench_embree.h"

#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

#include "app/app.h"
#include "renderer/scene.h"
#include "renderer/scene/meshio.h"
#include "sim/err.h"

struct bench_embree *bench_embree_from_ply(const struct scene *s, bool ignore, double *build_s) {
  const char *td = getenv("TMPDIR");
  char dir[4096];
  snprintf(dir, sizeof dir, "%s/rtsim-bench-XXXXXX", td && *td ? td : "/tmp");
  if (!mkdtemp(dir)) {
    perror("rtsim bench: cannot make a temporary directory");
    return NULL;
  }
  char ply[4200];
  snprintf(ply, sizeof ply, "%s/scene.ply", dir);
  struct err e = {0};
  struct scene back;
  scene_init(&back);
  struct meshio_xform xf = {1.0f, v3(0, 0, 0)};
  struct bench_embree *be = NULL;
  if (meshio_export_ply(s, ply, &e) && meshio_import(&back, ply, &xf, 0, UINT32_MAX, &e)) {
    if (back.tri_count != s->tri_count)
      fprintf(stderr, "rtsim bench: %s: read back %u triangles, wrote %u\n", ply, back.tri_count,
              s->tri_count);
    else be = bench_embree_create(&back, ignore, build_s);
  } else {
    app_report(&e);
  }
  scene_fini(&back);
  unlink(ply);
  rmdir(dir);
  return be;
}

#ifdef RTSIM_HAVE_EMBREE

#include <embree3/rtcore.h>

#include "renderer/ray.h"

struct bench_embree {
  RTCDevice dev;
  RTCScene scn;
};

bool bench_embree_available(void) { return true; }

static void on_error(void *user, enum RTCError code, const char *msg) {
  (void)user;
  fprintf(stderr, "rtsim bench: embree error %d: %s\n", (int)code, msg ? msg : "");
}

/* An intersect context that carries the ray's ignored primitive to the
 * filter (Embree hands the filter the context it was given). */
struct ignore_ctx {
  struct RTCIntersectContext ctx;
  int32_t ignore;
};

static void ignore_filter(const struct RTCFilterFunctionNArguments *args) {
  const struct ignore_ctx *ic = (const struct ignore_ctx *)args->context;
  /* RTCHitN is N lanes of each field, primID the sixth (rtcore_ray.h's
   * RTCHitN_primID, which is C++ only). */
  const unsigned *prim = (const unsigned *)(const void *)args->hit + 5u * args->N;
  for (unsigned i = 0; i < args->N; i++)
    if (args->valid[i] && (int32_t)prim[i] == ic->ignore) args->valid[i] = 0;
}

struct bench_embree *bench_embree_create(const struct scene *s, bool ignore, double *build_s) {
  struct bench_embree *be = xcalloc(1, sizeof *be);
  be->dev = rtcNewDevice("threads=1");
  if (!be->dev) {
    fprintf(stderr, "rtsim bench: embree: cannot create a device\n");
    free(be);
    return NULL;
  }
  rtcSetDeviceErrorFunction(be->dev, on_error, NULL);
  double t0 = app_now();
  be->scn = rtcNewScene(be->dev);
  rtcSetSceneFlags(be->scn, ignore ? RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION
                                   : RTC_SCENE_FLAG_ROBUST);
  RTCGeometry g = rtcNewGeometry(be->dev, RTC_GEOMETRY_TYPE_TRIANGLE);
  uint32_t n = s->tri_count;
  float *v = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                     3 * sizeof(float), 3ull * n);
  unsigned *ix = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                         3 * sizeof(unsigned), n);
  if (!v || !ix) {
    rtcReleaseGeometry(g);
    bench_embree_destroy(be);
    return NULL;
  }
  for (uint32_t i = 0; i < n; i++)
    for (int k = 0; k < 3; k++) {
      vec3 p = s->tris[i].v[k];
      v[9ull * i + 3 * k + 0] = p.x;
      v[9ull * i + 3 * k + 1] = p.y;
      v[9ull * i + 3 * k + 2] = p.z;
      ix[3ull * i + k] = 3 * i + (unsigned)k;
    }
  rtcCommitGeometry(g);
  rtcAttachGeometry(be->scn, g);
  rtcReleaseGeometry(g);
  rtcCommitScene(be->scn);
  *build_s = app_now() - t0;
  if (rtcGetDeviceError(be->dev) != RTC_ERROR_NONE) {
    bench_embree_destroy(be);
    return NULL;
  }
  return be;
}

void bench_embree_destroy(struct bench_embree *be) {
  if (!be) return;
  if (be->scn) rtcReleaseScene(be->scn);
  rtcReleaseDevice(be->dev);
  free(be);
}

double bench_embree_trace(struct bench_embree *be, const struct ray *rays, uint32_t n,
                          int32_t *prim, float *t) {
  struct ignore_ctx ic;
  rtcInitIntersectContext(&ic.ctx);
  double t0 = app_now();
  for (uint32_t i = 0; i < n; i++) {
    const struct ray *r = &rays[i];
    ic.ignore = r->ignore_prim;
    ic.ctx.filter = r->ignore_prim >= 0 ? ignore_filter : NULL;
    struct RTCRayHit rh;
    rh.ray.org_x = r->o.x;
    rh.ray.org_y = r->o.y;
    rh.ray.org_z = r->o.z;
    rh.ray.dir_x = r->d.x;
    rh.ray.dir_y = r->d.y;
    rh.ray.dir_z = r->d.z;
    rh.ray.tnear = r->tmin;
    rh.ray.tfar = r->tmax;
    rh.ray.time = 0.0f;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.ray.id = i;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(be->scn, &ic.ctx, &rh);
    prim[i] = rh.hit.geomID == RTC_INVALID_GEOMETRY_ID ? -1 : (int32_t)rh.hit.primID;
    if (t) t[i] = rh.ray.tfar;
  }
  return app_now() - t0;
}

#else

bool bench_embree_available(void) { return false; }

struct bench_embree *bench_embree_create(const struct scene *s, bool ignore, double *build_s) {
  (void)s;
  (void)ignore;
  *build_s = 0;
  return NULL;
}

void bench_embree_destroy(struct bench_embree *be) { (void)be; }

double bench_embree_trace(struct bench_embree *be, const struct ray *rays, uint32_t n,
                          int32_t *prim, float *t) {
  (void)be;
  (void)rays;
  for (uint32_t i = 0; i < n; i++) prim[i] = -1;
  if (t)
    for (uint32_t i = 0; i < n; i++) t[i] = 0;
  return 0;
}

#endif
