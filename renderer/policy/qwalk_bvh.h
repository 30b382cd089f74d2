/* The resumable walk on a BVH (qwalk.h's, behind its functions when the tree
 * is a BVH): bvh_trav.c's traversal, cut at queue points that are places of
 * the BVH (qpoint.h: nodes, and leaves, slots of their parents). Private to
 * renderer/policy/. */
#ifndef RTSIM_RENDERER_POLICY_QWALK_BVH_H
#define RTSIM_RENDERER_POLICY_QWALK_BVH_H

#include <stdbool.h>
#include <stdint.h>

#include "renderer/policy/qwalk.h"

/* qwalk_leaf, qwalk_run and qwalk_to on a BVH. */
bool qwalk_bvh_leaf(const struct qwalk_tree *t, struct trace_ctx *tr, struct qwalk *w, uint32_t n,
                    uint32_t j0, uint32_t j1);
enum qwalk_end qwalk_bvh_run(const struct qwalk_tree *t, struct trace_ctx *tr, struct qwalk *w,
                             int floor, bool to_queue);
void qwalk_bvh_to(const struct qwalk_tree *t, struct trace_ctx *tr, struct qwalk *w, uint32_t q);

/* qwalk_run_treelet on a BVH. */
enum qwalk_end qwalk_bvh_run_treelet(const struct qwalk_tree *t, struct trace_ctx *tr,
                                     struct qwalk *w, const uint32_t *of);

/* Pop the next pending place above stack depth floor into w->ni, skipping
 * those whose entry lies beyond the best hit. False when none is left. */
bool qwalk_bvh_pop(struct qwalk *w, int floor);

#endif
