/* Queue-point selection for the dynamic policy (the paper's section 2.1.1 and
 * Figure 1): a queue point is the first node on a root-to-leaf branch whose
 * subtree geometry fits g_max, the cache left for geometry once nodes, the queue
 * table and a ray buffer have their share (section 2.2). A leaf reached without
 * finding one is a queue point whatever its size (its rays are then processed
 * in cache-sized blocks). Subtrees without geometry (empty leaves) hold no
 * queue point: there is nothing to load there, so rays just pass through. */
#ifndef RTSIM_RENDERER_POLICY_QPOINT_H
#define RTSIM_RENDERER_POLICY_QPOINT_H

#include <stdbool.h>
#include <stdint.h>

struct bvh;
struct kd_tree;
struct kd_node;

/* Distinct triangles in each node's subtree: out[n] for n < kd->node_count; a
 * triangle referenced by several leaves of the subtree counts once. Linear in
 * the leaf references (the "distinct colours in a subtree" count: +1 at each
 * leaf holding a triangle, -1 at the lowest common ancestor of consecutive such
 * leaves in depth-first order, then subtree sums). out is caller-owned. */
void qpoint_subtree_tris(const struct kd_tree *kd, uint32_t *out);

/* The cache split of section 2.2. Each reservation is capped by a share of the
 * cache so that a small cache still leaves room for geometry:
 *   node_bytes  = min(8 * nodes,             cache / node_share)
 *   table_bytes = min(8 * queue points,      cache / table_share)
 *   ray_bytes   = min(ray_buffer_bytes,      cache / ray_share)
 *   gmax_bytes  = (cache - node_bytes - table_bytes - ray_bytes) / holders
 *                 (0 if negative)
 * The paper's 4 MB example: 1 MB of nodes (share 4), a 256 KB table (share 16).
 * holders: queue points whose geometry must be resident at once (the cores of
 * a machine that each drain one; 1 for a single thread): the tree, the table
 * and the ray buffer are shared, the geometry is each holder's own. */
struct qpoint_reserve {
  uint64_t cache_bytes;
  uint32_t node_share, table_share, ray_share; /* > 0 */
  uint64_t ray_buffer_bytes;
  uint32_t holders; /* > 0 */
};

struct qpoint_budget {
  uint64_t node_bytes, table_bytes, ray_bytes, gmax_bytes;
};

/* The selection: the queue points as a bitmap over the tree's nodes
 * (qpoint_marked) and in node order. The index of a queue point in qnode[] is
 * its queue-table index. Owns mark, qnode, parent and leaf_count
 * (qpoint_fini); nodes and bvh are the structure's, borrowed.
 *
 * On a BVH (bvh set, nodes NULL) a leaf is no node of its own but a slot of
 * its parent, so places are numbered apart from nodes: node i is place i, the
 * leaf whose entries start at prims[j] is place bvh->node_count + j
 * (qpoint_bvh_place). node_count counts places, and mark, qnode and every
 * array over nodes here are over places. */
struct qpoint_set {
  const struct kd_node *nodes; /* the tree's nodes, node_count of them */
  uint64_t *mark;              /* bit n set: node n is a queue point */
  uint32_t node_count;
  uint32_t *qnode;     /* node index of queue point q, increasing */
  uint32_t count;      /* number of queue points */
  uint64_t gmax_bytes; /* the bound it was made for */
  /* A BVH's (NULL on the k-d tree): its places' parents (the root's
   * UINT32_MAX) and each leaf's triangles (leaf_count[j] for the leaf at
   * prims[j], 0 at the other entries). */
  const struct bvh *bvh;
  uint32_t *parent;
  uint8_t *leaf_count;
};

/* The place of BVH b's child (ref, count): a node (count 0) or a leaf. */
static inline uint32_t qpoint_bvh_place(uint32_t node_count, uint32_t ref, uint32_t count) {
  return count == 0 ? ref : node_count + ref;
}

/* Whether node (place) n of qs is a leaf; if so its entries in the leaf
 * index lists are [*first, *first + *count). */
bool qpoint_leaf(const struct qpoint_set *qs, uint32_t n, uint32_t *first, uint32_t *count);

/* A bitmap of n nodes, all clear (free it). */
uint64_t *qpoint_mark_new(uint32_t n);

static inline bool qpoint_marked(const uint64_t *mark, uint32_t n) {
  return (mark[n >> 6] >> (n & 63u)) & 1u;
}

static inline void qpoint_mark(uint64_t *mark, uint32_t n) { mark[n >> 6] |= 1ull << (n & 63u); }

/* Select for a given bound: node n qualifies when tris[n] * tri_bytes <=
 * gmax_bytes (tris from qpoint_subtree_tris). */
void qpoint_select(struct qpoint_set *qs, const struct kd_tree *kd, const uint32_t *tris,
                   uint32_t tri_bytes, uint64_t gmax_bytes);

/* Select for a cache: computes the budget. The table's reservation needs the
 * number of queue points, which needs g_max: a first selection with the full
 * table share counts them; if their table is smaller, a second selection uses
 * the freed bytes (queue points only move up then, so their table still fits
 * the reservation). With more queue points than the share holds (tiny caches)
 * only the share is reserved, as the paper reserves 256 KB for 32K entries. */
void qpoint_plan(struct qpoint_set *qs, struct qpoint_budget *b, const struct kd_tree *kd,
                 const uint32_t *tris, uint32_t tri_bytes, const struct qpoint_reserve *r);

/* The same on BVH b (places, above): tris over the places
 * (qpoint_bvh_subtree_tris), node bytes at b's node size. */
void qpoint_bvh_select(struct qpoint_set *qs, const struct bvh *b, const uint32_t *tris,
                       uint32_t tri_bytes, uint64_t gmax_bytes);
void qpoint_bvh_plan(struct qpoint_set *qs, struct qpoint_budget *b, const struct bvh *bvh,
                     const uint32_t *tris, uint32_t tri_bytes, const struct qpoint_reserve *r);

/* Set qs's BVH b, and its places' parents and leaves' counts (allocated). */
void qpoint_bvh_tree(struct qpoint_set *qs, const struct bvh *b);

/* Places of BVH b (its nodes and leaves). */
uint32_t qpoint_bvh_places(const struct bvh *b);

/* Triangles below each place of BVH b: out[n] for n < qpoint_bvh_places(b)
 * (each triangle is in one leaf, so a sum). out is caller-owned. */
void qpoint_bvh_subtree_tris(const struct bvh *b, uint32_t *out);

/* Queue index of node n, or -1 when n is not a queue point (binary search). */
int64_t qpoint_index(const struct qpoint_set *qs, uint32_t n);

void qpoint_fini(struct qpoint_set *qs);

#endif
