/* SAH k-d tree over a scene's triangles, in the spirit of PBRT's KdTreeAccel,
 * with the paper's 8-byte nodes. Splits are stored exactly; bit 2 of w1 is
 * zero in both node kinds. (It held the dynamic policy's queue-point flag, in
 * a copy of the nodes made for every selection, 8 bytes a node; the flags are
 * a bitmap now, qpoint.h. Before that the split's lowest mantissa bit held
 * it; trimming every split to an even mantissa made the candidate planes
 * depend on the float grid, so a scene scaled by 3 or 0.1 built a different
 * tree.)
 *
 * Node layout (two 32-bit words, children by index):
 *   interior: w0 = split as float bits
 *             w1 = (above_child << 3) | axis (0,1,2);
 *             below child = this + 1
 *   leaf:     w0 = offset of its first entry in the primitive index list
 *             w1 = (prim_count << 3) | 3                                          */
#ifndef RTSIM_RENDERER_KDTREE_H
#define RTSIM_RENDERER_KDTREE_H

#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#include "renderer/vec.h"

struct scene;

struct kd_node {
  uint32_t w0, w1;
};
_Static_assert(sizeof(struct kd_node) == 8, "the paper's 8-byte k-d node");

static inline bool kd_is_leaf(struct kd_node n) { return (n.w1 & 3u) == 3u; }
static inline int kd_axis(struct kd_node n) { return (int)(n.w1 & 3u); }
static inline uint32_t kd_above(struct kd_node n) { return n.w1 >> 3; }
static inline uint32_t kd_leaf_count(struct kd_node n) { return n.w1 >> 3; }
static inline uint32_t kd_leaf_offset(struct kd_node n) { return n.w0; }
static inline float kd_split(struct kd_node n) {
  float f;
  memcpy(&f, &n.w0, sizeof f);
  return f;
}

/* Most nodes a tree may have: a child index takes 29 bits of w1. */
#define KD_MAX_NODES (1u << 29)

struct kd_build_params {
  float cost_traversal; /* SAH cost of one traversal step (PBRT: 1) */
  float cost_isect;     /* SAH cost of one triangle test (PBRT: 80) */
  float empty_bonus;    /* SAH bonus for an empty child, in [0,1) (PBRT: 0.5) */
  uint32_t max_prims;   /* make a leaf at or below this many triangles (PBRT: 1) */
  int max_depth;        /* < 0: 8 + 1.3 log2(N) as PBRT */
  bool clip;            /* perfect splits: a triangle cut by a plane is clipped to
                           each child's box and goes on with the bounds of what
                           lies inside it; false (default): with its whole bounds,
                           as PBRT's tree and the paper's */
};

struct kd_stats {
  uint32_t nodes, leaves, empty_leaves, max_depth, max_leaf_prims;
  uint64_t leaf_prim_refs; /* sum of leaf sizes (triangles referenced by several leaves count each
                              time) */
};

struct kd_tree {
  struct kd_node *nodes; /* node 0 is the root */
  uint32_t node_count;
  uint32_t *prims; /* leaf primitive index lists, concatenated */
  uint32_t prim_ref_count;
  vec3 lo, hi; /* root bounds */
  struct kd_stats stats;
};

/* Hard ceiling on a tree's depth (interior levels from the root to the deepest
 * leaf): kd_build clamps max_depth to it, and traversal stacks have this many
 * entries. PBRT's rule gives about 34 levels for 800K triangles. */
#define KD_DEPTH_LIMIT 64

void kd_build_params_default(struct kd_build_params *p);

/* Build over all of s's triangles. The tree owns its arrays (kd_fini frees).
 * An empty scene gives a single empty leaf. False when the host's memory ran
 * out (an allocation of *failed_bytes failed, if given): the build is undone
 * and t is empty. About 250 bytes a triangle at the peak (docs/inputs.md, Limits). */
bool kd_build(struct kd_tree *t, const struct scene *s, const struct kd_build_params *p,
              unsigned long long *failed_bytes);
void kd_fini(struct kd_tree *t);

#endif
