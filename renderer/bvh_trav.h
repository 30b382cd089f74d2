/* The BVH traversals behind trace_closest and trace_any, and behind the
 * packet queries, when the tracer has a BVH (trace_ctx.bvh): the same hit
 * rule, announcements and answers as the k-d traversals. Private to
 * renderer/. */
#ifndef RTSIM_RENDERER_BVH_TRAV_H
#define RTSIM_RENDERER_BVH_TRAV_H

#include <stdbool.h>
#include <stdint.h>

struct trace_ctx;
struct ray;
struct trace_hit;
struct trace_packet_cost;

/* Nearest hit along r through tr->bvh (any: true at the first hit found).
 * Returns whether a hit was found; h as trace_closest's. */
bool bvh_traverse(struct trace_ctx *tr, const struct ray *r, bool any, struct trace_hit *h);

/* Scratch of the packet traversal (about 120 KB; fatal on allocation
 * failure). One per concurrent caller. */
struct bvh_packet;
struct bvh_packet *bvh_packet_create(void);
void bvh_packet_destroy(struct bvh_packet *bp); /* NULL ok */

/* The packet queries through tr->bvh: rays[0..n) (n <= TRACE_PACKET_MAX)
 * traced together, any_hit false: hits[i] as trace_closest's; true: occ[i]
 * as trace_any's. cost as trace_packet_closest's (may be NULL). */
void bvh_packet_traverse(struct trace_ctx *tr, struct bvh_packet *bp, const struct ray *rays,
                         uint32_t n, bool any_hit, struct trace_hit *hits, bool *occ,
                         struct trace_packet_cost *cost);

#endif
