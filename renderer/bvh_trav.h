/* The BVH traversal behind trace_closest and trace_any when the tracer has a
 * BVH (trace_ctx.bvh): the same hit rule, announcements and answers as the
 * k-d traversal. Private to renderer/. */
#ifndef RTSIM_RENDERER_BVH_TRAV_H
#define RTSIM_RENDERER_BVH_TRAV_H

#include <stdbool.h>

struct trace_ctx;
struct ray;
struct trace_hit;

/* Nearest hit along r through tr->bvh (any: true at the first hit found).
 * Returns whether a hit was found; h as trace_closest's. */
bool bvh_traverse(struct trace_ctx *tr, const struct ray *r, bool any, struct trace_hit *h);

#endif
