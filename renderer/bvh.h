/* Bounding volume hierarchies beside the k-d tree: a binary BVH built with a
 * binned SAH, and a compressed 8-wide BVH collapsed from it after Ylitie,
 * Karras and Laine (HPG 2017). Both are object partitions: every triangle is
 * in exactly one leaf, listed in the leaf index list (prims) as the k-d
 * tree's leaves are, so the triangle records and their layout are the same
 * for every structure. A node holds its children's boxes (one fetch tests
 * them all); the root's box is bvh.lo/hi.
 *
 * Node layouts (sizes are the simulated records', node i at node_base + size i):
 *   bvh2_node, 64 bytes: two exact child boxes (6 floats each), two child
 *     references and counts: count 0 an interior child (ref: its node),
 *     1..BVH_LEAF_MAX a leaf (ref: its first entry in prims), BVH_EMPTY none.
 *   bvh8_node, 80 bytes (Ylitie et al.'s layout): origin p (3 floats), scale
 *     exponents e (3 bytes: the axis's scale is 2^(e - 127)), imask (bit i:
 *     slot i is an interior node), child_base (first interior child: they are
 *     consecutive), prim_base (first leaf entry: the leaves' lists are
 *     consecutive), meta (a byte a slot: 0 empty; 001sssss with sssss = 24 + k
 *     the interior child child_base + k; otherwise a leaf of 1..3 triangles,
 *     count in unary in the top three bits (001, 011, 111) and its first entry
 *     prim_base + the low five bits (< 24)), and the quantized child boxes:
 *     8-bit qlo/qhi per axis and slot, the plane being bvh8_plane(p, q, e).
 *     The quantized box contains the exact one (lo rounded down, hi up, each
 *     checked in the arithmetic traversal uses). */
#ifndef RTSIM_RENDERER_BVH_H
#define RTSIM_RENDERER_BVH_H

#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#include "renderer/vec.h"

struct scene;

/* The acceleration structure a render traces (the scene file's `accel`). */
enum accel_kind { ACCEL_KD = 0, ACCEL_BVH2 = 1, ACCEL_BVH8 = 2, ACCEL_COUNT = 3 };
/* "kd", "bvh2", "bvh8". */
extern const char *const accel_names[ACCEL_COUNT];

/* Most triangles a leaf holds: the BVH8's meta byte counts up to three. */
#define BVH_LEAF_MAX 3u
/* Bins of the SAH sweep per axis and node. */
#define BVH_BINS 32
/* Deepest leaf (levels below the root) either BVH may have: below
 * BVH_SAH_DEPTH levels nodes split at the median, which adds at most
 * ceil(log2(triangles)) <= 27 levels (the scene cap is 10^8 triangles).
 * Traversal stacks have BVH_DEPTH_LIMIT entries a level of (width - 1). */
#define BVH_SAH_DEPTH 36
#define BVH_DEPTH_LIMIT 64
#define BVH_EMPTY UINT32_MAX

struct bvh2_node {
  float lo[2][3], hi[2][3];
  uint32_t ref[2], count[2];
};
_Static_assert(sizeof(struct bvh2_node) == 64, "a binary BVH node is one line");

struct bvh8_node {
  float p[3];
  uint8_t e[3], imask;
  uint32_t child_base, prim_base;
  uint8_t meta[8];
  uint8_t qlo[3][8], qhi[3][8];
};
_Static_assert(sizeof(struct bvh8_node) == 80, "Ylitie et al.'s 80-byte node");

/* The scale of exponent byte e (1..254): 2^(e - 127), an exact power of two
 * (the float whose exponent field is e). */
static inline float bvh8_scale(uint8_t e) {
  const uint32_t u = (uint32_t)e << 23;
  float f;
  memcpy(&f, &u, sizeof f);
  return f;
}
/* Plane q of an axis with origin p and scale s. One expression for the build's
 * check and the traversal, so the check holds for what traversal sees. */
static inline float bvh8_plane(float p, uint8_t q, float s) { return p + (float)q * s; }

/* Half the surface area of box [lo, hi], in double so that sums of many are
 * ordered alike (an axis with hi <= lo adds nothing). */
static inline double bvh_box_area(const float lo[3], const float hi[3]) {
  double d[3];
  for (int a = 0; a < 3; a++) d[a] = hi[a] > lo[a] ? (double)hi[a] - lo[a] : 0.0;
  return d[0] * d[1] + d[1] * d[2] + d[2] * d[0];
}

/* The SAH costs a tree's sah_cost is priced with: a node visit 1, a triangle
 * test 0.3 (Ylitie et al.'s constants, which their collapse minimizes; for
 * either BVH, so that the two compare). */
#define BVH_SAH_NODE 1.0
#define BVH_SAH_PRIM 0.3

struct bvh_stats {
  uint32_t nodes, leaves, max_depth, max_leaf_prims;
  uint64_t node_bytes; /* simulated: nodes x 64 or 80 */
  /* The tree's SAH cost relative to its root box's area, on the exact child
   * boxes: BVH_SAH_NODE x the area of every node (the root included) plus
   * BVH_SAH_PRIM x triangles x the area of every leaf. */
  double sah_cost;
};

struct bvh {
  enum accel_kind kind; /* ACCEL_BVH2 or ACCEL_BVH8 */
  struct bvh2_node *n2; /* kind BVH2: node 0 the root (none for an empty scene) */
  struct bvh8_node *n8; /* kind BVH8: node 0 the root */
  uint32_t node_count;
  uint32_t *prims; /* leaf index lists, concatenated: each triangle once */
  uint32_t prim_count;
  vec3 lo, hi; /* root bounds */
  struct bvh_stats stats;
};

/* Build a BVH of kind (ACCEL_BVH2 or ACCEL_BVH8) over all of s's triangles;
 * the BVH owns its arrays (bvh_fini frees). Allocation failure is fatal. */
void bvh_build(struct bvh *b, const struct scene *s, enum accel_kind kind);
void bvh_fini(struct bvh *b);

/* For bvh_build.c: collapse the binary BVH b2 into b (kind BVH8) by Ylitie
 * et al.'s SAH collapse (bvh8_plan.h); b2 unchanged. */
void bvh8_collapse(struct bvh *b, const struct bvh *b2);

/* Child k of a BVH8 node: true if it exists; *interior, and *ref (its node)
 * or *first and *count (its leaf entries). */
static inline bool bvh8_child(const struct bvh8_node *n, int k, bool *interior, uint32_t *ref,
                              uint32_t *count) {
  const uint8_t m = n->meta[k];
  if (m == 0) return false;
  *interior = (m >> 5) == 1u && (m & 31u) >= 24u;
  if (*interior) {
    *ref = n->child_base + (m & 31u) - 24u;
    *count = 0;
  } else {
    *ref = n->prim_base + (m & 31u);
    *count = (m >> 7) + ((m >> 6) & 1u) + ((m >> 5) & 1u);
  }
  return true;
}

#endif
