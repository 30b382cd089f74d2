/* Which subtrees of the binary BVH become the 8-wide BVH's nodes and leaves:
 * the collapse's choice, apart from its layout and quantization (bvh8.c).
 * Two choosers: Ylitie, Karras and Laine's SAH collapse (HPG 2017, section
 * 3.1; bvh8_plan.c) with bvh.h's BVH_SAH_NODE and BVH_SAH_PRIM, the default,
 * and the greedy one that opens the largest interior child until a node has
 * eight (bvh8_greedy_children), kept for the comparison tests/test_bvh8_plan.c
 * makes (the SAH collapse's tree costs no more than the greedy one's).
 * Private to renderer/. */
#ifndef RTSIM_RENDERER_BVH8_PLAN_H
#define RTSIM_RENDERER_BVH8_PLAN_H

#include <stdint.h>

#include "renderer/bvh.h"

/* A child of an 8-wide node as the binary BVH holds it: its exact box, and
 * an interior binary node (count 0, ref its index) or a leaf of the entries
 * [ref, ref + count) of the binary BVH's prims (count <= BVH_LEAF_MAX). */
struct bvh8_child {
  float lo[3], hi[3];
  uint32_t ref, count;
};

/* The children of the 8-wide node made of binary node ni: out[0..n), n
 * returned (1..8). ctx is the chooser's state. */
typedef uint32_t (*bvh8_chooser)(const void *ctx, const struct bvh *b2, uint32_t ni,
                                 struct bvh8_child out[8]);

/* The SAH collapse's decisions over the binary BVH b2 (which must outlive
 * it): for each binary node and i = 1..8, the cheapest way to represent its
 * subtree with at most i roots (one leaf of <= BVH_LEAF_MAX triangles, one
 * 8-wide node, or the i split between its two children). Allocation failure
 * is fatal. */
struct bvh8_plan;
struct bvh8_plan *bvh8_plan_create(const struct bvh *b2);
void bvh8_plan_destroy(struct bvh8_plan *p); /* NULL ok */

/* The chooser of a plan (ctx: the plan). */
uint32_t bvh8_plan_children(const void *plan, const struct bvh *b2, uint32_t ni,
                            struct bvh8_child out[8]);

/* The SAH cost the plan found for the whole tree (the root an 8-wide node),
 * relative to the root box's area: what bvh_stats.sah_cost of the BVH8
 * built from it is, up to rounding. */
double bvh8_plan_cost(const struct bvh8_plan *p);

/* Collapse the binary BVH b2 into b (kind BVH8) with a chooser; b2 is
 * unchanged. bvh8_collapse is this with the SAH plan. */
void bvh8_collapse_with(struct bvh *b, const struct bvh *b2, bvh8_chooser choose, const void *ctx);

/* The greedy chooser (ctx unused). */
uint32_t bvh8_greedy_children(const void *ctx, const struct bvh *b2, uint32_t ni,
                              struct bvh8_child out[8]);

#endif
