/* Embree 3 as the peer of rtsim bench --embree: the same primary rays, one at
 * a time (rtcIntersect1), single thread, robust mode, against the triangles of
 * a scene (in the benchmark, the scene re-read from our exported PLY). Only
 * built with -DRTSIM_EMBREE=ON (Debian's libembree-dev); Embree is a
 * benchmark's peer, never a dependency of the simulator. */
#ifndef RTSIM_APP_BENCH_EMBREE_H
#define RTSIM_APP_BENCH_EMBREE_H

#include <stdbool.h>
#include <stdint.h>

struct scene;
struct ray;
struct bench_embree;

/* False if this build has no Embree. */
bool bench_embree_available(void);

/* Build Embree's BVH over s's triangles (single thread, robust); *build_s is
 * its wall time. With ignore, a ray's ignore_prim never hits (a context
 * filter, as rtsim's secondary rays ignore the triangle they leave);
 * without, the scene has no filter and ignore_prim is not looked at. NULL
 * (with a message on stderr) if Embree fails. */
struct bench_embree *bench_embree_create(const struct scene *s, bool ignore, double *build_s);

/* The same over s's triangles as a PLY file holds them: exported, read back
 * through the importer, the file removed. NULL on failure (reported). */
struct bench_embree *bench_embree_from_ply(const struct scene *s, bool ignore, double *build_s);
void bench_embree_destroy(struct bench_embree *be);

/* Trace rays[0..n) one at a time; prim[i] = the primitive hit, or -1, and
 * (t not NULL) t[i] its distance. Returns the wall time of the loop. */
double bench_embree_trace(struct bench_embree *be, const struct ray *rays, uint32_t n,
                          int32_t *prim, float *t);

#endif
