/* Ray queries against the scene: the watertight ray/triangle test (Woop, Benthin
 * and Wald 2013), k-d tree traversal with an explicit per-ray stack, and a brute
 * force reference. Every access of nodes, leaf index lists and triangle records
 * goes through the memory interface at its simulated address.
 *
 * Hit rule everywhere (tree and brute force): the smallest t in (tmin, tmax);
 * among equal t the smallest primitive id; the ray's ignore_prim never hits. */
#ifndef RTSIM_RENDERER_TRACE_H
#define RTSIM_RENDERER_TRACE_H

#include <stdbool.h>
#include <stdint.h>

#include "renderer/vec.h"
#include "sim/mem.h"

struct scene;
struct kd_tree;
struct ray;

struct trace_hit {
  float t;
  int32_t prim; /* -1: miss */
  float b1, b2; /* barycentric weights of vertices 1 and 2 (vertex 0: 1-b1-b2) */
};

/* Per-ray precomputation of the watertight test. */
struct trace_isect_ray {
  vec3 o;
  int kx, ky, kz;
  float sx, sy, sz;
  int perm; /* 2 kz + (kx, ky swapped): which specialised test runs */
};

void trace_isect_prepare(struct trace_isect_ray *r, vec3 o, vec3 d);

/* Watertight test of one triangle. On a hit with tmin < t < tmax sets *t, *b1,
 * *b2 and returns true. Zero-area and edge-on triangles never hit. */
bool trace_isect_tri(const struct trace_isect_ray *r, vec3 a, vec3 b, vec3 c, float tmin,
                     float tmax, float *t, float *b1, float *b2);
/* NOTE: like PBRT-v3, trace_isect_tri also rejects a hit whose t is within its own
 * rounding-error bound of 0 (cannot be sure it lies in front of the origin). */

/* Data classes of the renderer's accesses (small integers to the simulator,
 * below MEM_CLASS_MAX), named in trace_class_names for statistics. */
enum trace_class {
  TRACE_CLASS_GEOMETRY = 0, /* triangle records */
  TRACE_CLASS_NODE = 1,     /* acceleration structure: k-d nodes, leaf index lists */
  TRACE_CLASS_RAY = 2,      /* 64-byte ray records in buffers */
  TRACE_CLASS_QUEUE = 3,    /* ray queues and the queue-point table */
  TRACE_CLASS_OTHER = 4,    /* framebuffer and everything else */
  TRACE_CLASS_COUNT = 5
};

/* "geometry", "node", "ray", "queue", "other". */
extern const char *const trace_class_names[TRACE_CLASS_COUNT];

/* The simulated memory image: where every piece of scene and workload data
 * lives. Regions are 2^40 bytes apart, so none can overlap whatever the scene
 * size; only what is touched exists (the analysers are sparse). */
#define TRACE_REGION_SHIFT 40
struct trace_layout {
  uint64_t tri_base;      /* triangle p at tri_base + tri_bytes p */
  uint64_t node_base;     /* k-d node i at node_base + 8 i (BVH: 64 i or 80 i) */
  uint64_t prim_idx_base; /* leaf index entry j at prim_idx_base + 4 j */
  uint64_t qtable_base;   /* queue-point table: entry q at qtable_base + 8 q */
  uint64_t queue_base;    /* ray queues (64-byte rays) */
  uint64_t ray_base;      /* ray stacks and packet buffers (64-byte rays) */
  uint64_t fb_base;       /* framebuffer: pixel i at fb_base + FB_PIXEL_BYTES i */
  uint64_t camera_base;   /* primary rays as the camera wrote them: pixel i's at
                             camera_base + 64 i, read once by every policy */
  uint32_t tri_bytes;     /* simulated triangle record size (default 128) */
  uint32_t node_cycles;   /* compute cycles announced per traversal step */
  uint32_t tri_cycles;    /* compute cycles announced per triangle test */
};

void trace_layout_default(struct trace_layout *l);

struct trace_stats {
  uint64_t node_visits, tri_tests;
};

struct bvh;
struct trace_ctx {
  const struct scene *scene;
  const struct kd_tree *kd;
  /* The BVH to trace instead of kd (NULL: the k-d tree). Every query takes
   * either. */
  const struct bvh *bvh;
  struct mem_port mem;
  struct trace_layout layout;
  struct trace_stats stats;
  /* Optional bit set, one bit a triangle (set when tested against any ray):
   * the potentially visible geometry. NULL: not tracked. Owned by the caller. */
  uint64_t *tested;
  /* Optional (NULL: nobody listens): told, with `worker`, whom this tracer's
   * accesses are for from now on (policy_setup.attribute). */
  void (*attribute)(void *ctx, uint32_t worker, const uint32_t *pixels, uint32_t n);
  void *attribute_ctx;
  uint32_t worker;
};

/* The accesses through tr from now on are for the rays of pixels[0..n)
 * (policy_setup.attribute says how long the array must last). */
static inline void trace_attribute(const struct trace_ctx *tr, const uint32_t *pixels, uint32_t n) {
  if (tr->attribute) tr->attribute(tr->attribute_ctx, tr->worker, pixels, n);
}

void trace_init(struct trace_ctx *tr, const struct scene *s, const struct kd_tree *kd,
                struct mem_port mem, const struct trace_layout *layout);

/* Nearest hit along r (rule above). Returns false (h->prim = -1) on a miss. */
bool trace_closest(struct trace_ctx *tr, const struct ray *r, struct trace_hit *h);

/* True if any triangle is hit in (tmin, tmax) (shadow rays). */
bool trace_any(struct trace_ctx *tr, const struct ray *r);

/* Packet queries: up to TRACE_PACKET_MAX rays descend the tree together (the
 * classic packet k-d traversal; on a BVH, tr->bvh, its packet form). Each ray
 * keeps its own interval, widened exactly as in the single-ray queries, and a
 * node is visited when any ray still needs it; each ray's result is
 * bit-identical to trace_closest / trace_any of that ray alone. Memory: a node,
 * a leaf index entry and a triangle record are loaded once per packet visit;
 * compute is announced once per step for all the rays it covers (node_cycles or
 * tri_cycles times the rays). tr->stats.node_visits counts packet node visits,
 * tr->stats.tri_tests ray/triangle tests. */
#define TRACE_PACKET_MAX 64

/* Scratch of packet queries (about 41 KB, and 120 KB more at the first BVH
 * query; on the heap so that kernels fit small coroutine stacks). One per
 * concurrent caller. */
struct trace_packet;
struct trace_packet *trace_packet_create(void);     /* fatal on allocation failure */
void trace_packet_destroy(struct trace_packet *pk); /* NULL ok */

/* Optional per-ray work of a packet query: nodes the ray was active in (needed
 * by that ray) and triangles tested against it. */
struct trace_packet_cost {
  uint32_t nodes[TRACE_PACKET_MAX], tris[TRACE_PACKET_MAX];
};

/* hits[i] = what trace_closest(tr, &rays[i]) returns in its hit, for i < n
 * (n <= TRACE_PACKET_MAX). cost may be NULL; if not, its first n entries are
 * overwritten. */
void trace_packet_closest(struct trace_ctx *tr, struct trace_packet *pk, const struct ray *rays,
                          uint32_t n, struct trace_hit *hits, struct trace_packet_cost *cost);

/* occluded[i] = trace_any(tr, &rays[i]), for i < n. cost as above. */
void trace_packet_any(struct trace_ctx *tr, struct trace_packet *pk, const struct ray *rays,
                      uint32_t n, bool *occluded, struct trace_packet_cost *cost);

/* Reference: test every triangle, same hit rule. No memory accesses. */
bool trace_brute(const struct scene *s, const struct ray *r, struct trace_hit *h);

/* Point and geometric normal of a hit, plus a conservative bound on the point's
 * rounding error (PBRT-v3 style), for spawning secondary rays that cannot hit
 * their own surface: offset = trace_offset_origin(p, err, n, d). */
vec3 trace_hit_point(const struct scene *s, const struct trace_hit *h, vec3 *err);
vec3 trace_offset_origin(vec3 p, vec3 err, vec3 n, vec3 d);
/* Unit geometric normal of the hit triangle (cross(v1 - v0, v2 - v0), so its
 * side follows the winding), or {0,0,0} for a zero-area triangle. */
vec3 trace_geom_normal(const struct scene *s, const struct trace_hit *h);

#endif
