/* rtsim bench --hits: do the three structures, and Embree, find the same
 * nearest hits on the ray sets the renderer makes? For each scene and ray
 * set (primary, shadow, diffuse, random; bench_rays.h) and each structure
 * (kd, bvh2, bvh8): the rays whose nearest triangle differs from the k-d
 * tree's, split into ties (the same t: another triangle at the hit distance)
 * and anything else; the rays whose hit has a tie at all; and, with Embree,
 * the rays whose hit differs from Embree's, decided in double precision. */
#ifndef RTSIM_APP_BENCH_HITS_H
#define RTSIM_APP_BENCH_HITS_H

#include <stdbool.h>
#include <stdint.h>

/* The CSV header line (embree: with Embree's columns). */
void bench_hits_header(bool embree);

/* The rows of one scene at W x H (0: the scene's), on stdout. 0, or the exit
 * code after the error was reported. */
int bench_hits_scene(const char *scene_path, uint64_t width, uint64_t height, bool embree);

struct scene;
struct ray;
struct trace_ctx;
struct trace_hit;
/* True if r's nearest hit h (through tr) has a tie: another triangle, not the
 * one r ignores, hit at exactly h->t (the hit rule then took the smaller
 * id). Found by tracing r again in [h->t, h->t] without h's triangle. */
bool bench_hits_tie(struct trace_ctx *tr, const struct ray *r, const struct trace_hit *h);

/* How a disagreement between two answers a (rtsim's) and b (a peer's) for
 * ray r is decided in double precision (prims -1: a miss). */
enum bench_hits_verdict {
  BENCH_HITS_TIE = 0,  /* both hit, at the same distance within 1e-9 of it */
  BENCH_HITS_EDGE = 1, /* else: a hit within 1e-5 (barycentric) of its edge */
  BENCH_HITS_A = 2,    /* else: a is the nearer hit (or b's is no hit) */
  BENCH_HITS_B = 3,    /* else: b is */
  BENCH_HITS_VERDICTS = 4
};
enum bench_hits_verdict bench_hits_decide(const struct scene *s, const struct ray *r, int32_t a,
                                          int32_t b);

#endif
