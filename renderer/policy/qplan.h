/* The plan of the queue policies (policy_dynamic.c, policy_treelet.c): the
 * queue points and the budget the cache and the machine give them (policy.h's
 * rules: g_max, the geometry a queue may hold, is the cache left once the
 * tree's share, the queue table and the ray buffer are reserved, over the
 * cores that hold one at once), and the queue scheduler's block and group
 * sizes. Private to renderer/. */
#ifndef RTSIM_RENDERER_POLICY_QPLAN_H
#define RTSIM_RENDERER_POLICY_QPLAN_H

#include <stdint.h>

struct bvh;
struct kd_tree;
struct policy_job;
struct policy_params;
struct qpoint_budget;
struct qpoint_set;

/* policy_dynamic_plan: the queue points and budget for the cache and the
 * machine, on bvh if not NULL (its places, qpoint.h) or else on kd, with the
 * subtree triangle counts given (tris, qpoint_subtree_tris of kd or
 * qpoint_bvh_subtree_tris of bvh) or counted here (tris NULL). */
void qplan_make(const struct policy_params *p, uint32_t workers, uint32_t cores,
                const struct kd_tree *kd, const struct bvh *bvh, const uint32_t *tris,
                uint32_t tri_bytes, struct qpoint_set *qs, struct qpoint_budget *b,
                uint32_t *block_tris, uint32_t *group);

/* qplan_make for a job: its parameters, machine and setup. */
void qplan_job(const struct policy_job *job, struct qpoint_set *qs, struct qpoint_budget *b,
               uint32_t *block_tris, uint32_t *group);

#endif
