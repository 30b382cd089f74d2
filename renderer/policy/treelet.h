/* Treelets: a partition of the k-d tree into connected pieces of bounded size,
 * after Aila and Karras (Architecture Considerations for Tracing Incoherent
 * Rays, HPG 2010). Where the paper's queue points cut the tree once (the first
 * node on each branch whose subtree fits g_max, and everything above it is
 * traversed freely), treelets cover the whole tree, top included: a ray is
 * always in exactly one treelet, and it is queued again each time its next
 * node lies in another one.
 *
 * Formation (their greedy rule, adapted to a k-d tree): a treelet starts at a
 * root and grows by taking, among the nodes adjacent to it, the one with the
 * largest box surface area (the likeliest to be visited by a ray that enters
 * the root's box), as long as its bytes fit the budget; a node that does not
 * fit starts a treelet of its own later. Adapted: Aila and Karras charge a BVH
 * node's bytes; a k-d node is 8 bytes and its geometry lives in the leaves, so
 * a leaf is charged 8 bytes plus tri_bytes for each triangle not already in the
 * treelet (a triangle referenced by several of its leaves counts once, as the
 * queue points count it). A subtree without triangles never starts a treelet:
 * it joins its parent's whatever the budget, since a ray queued there would
 * find nothing to load. Ties of area go to the lower node index, so the
 * partition is deterministic. The tree's memory layout is not changed (Aila and
 * Karras also lay each treelet out contiguously; here the nodes stay in
 * depth-first order). On a BVH (treelet_bvh_build) the same rule runs over
 * its places (qpoint.h). */
#ifndef RTSIM_RENDERER_POLICY_TREELET_H
#define RTSIM_RENDERER_POLICY_TREELET_H

#include <stdint.h>

struct bvh;
struct kd_tree;

#define TREELET_NONE UINT32_MAX

struct treelet_set {
  uint32_t *of;    /* of[n]: the treelet of node n, n < node_count (a BVH's
                      places that are no leaf's first entry: TREELET_NONE) */
  uint32_t *root;  /* root[t]: the node treelet t starts at; root[0] = 0 */
  uint64_t *bytes; /* bytes[t]: 8 a node + tri_bytes a distinct triangle */
  uint32_t count;  /* treelets (0 for an empty tree) */
  uint32_t node_count;
  uint64_t budget; /* the bound they were made for */
};

/* Partition kd for a budget in bytes. A treelet exceeds the budget only when
 * its root alone does (a leaf with more triangles than fit), or by subtrees
 * without triangles it had to take (8 bytes a node). Treelets are numbered in
 * the order they are started: breadth-first over treelets, from the root. */
void treelet_build(struct treelet_set *ts, const struct kd_tree *kd, uint32_t tri_bytes,
                   uint64_t budget);

/* The same on BVH b (Aila and Karras's own structure): over its places
 * (qpoint.h; node_count counts them), each leaf's triangles in leaf_count
 * (qpoint_set's), a node charged its bytes (64 or 80), a leaf its 4-byte
 * index entries and its triangles (each triangle is in one leaf). */
void treelet_bvh_build(struct treelet_set *ts, const struct bvh *b, const uint8_t *leaf_count,
                       uint32_t tri_bytes, uint64_t budget);

void treelet_fini(struct treelet_set *ts);

#endif
