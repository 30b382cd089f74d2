/* The plan of the queue policies (qplan.h): policy.h's rules turned into
 * qpoint_plan's reserve, and the budget it leaves into the drains' block and
 * group sizes. */
#include "renderer/policy/qplan.h"

#include <stdlib.h>

#include "renderer/kdtree.h"
#include "renderer/policy/policy.h"
#include "renderer/policy/policy_impl.h"
#include "renderer/policy/qpoint.h"
#include "renderer/trace.h"
#include "sim/err.h"

static uint32_t clamp_u32(uint64_t v) {
  return v == 0 ? 1 : (v > UINT32_MAX ? UINT32_MAX : (uint32_t)v);
}

void qplan_make(const struct policy_params *p, uint32_t workers, uint32_t cores,
                const struct kd_tree *kd, const struct bvh *bvh, const uint32_t *tris,
                uint32_t tri_bytes, struct qpoint_set *qs, struct qpoint_budget *b,
                uint32_t *block_tris, uint32_t *group) {
  CHECK_GE(workers, 1);
  CHECK_GE(cores, 1);
  CHECK_LE(cores, workers);
  CHECK_GT(tri_bytes, 0);
  uint32_t *counted = NULL;
  if (!tris) {
    const uint32_t n = bvh ? qpoint_bvh_places(bvh) : kd->node_count;
    counted = xmalloc((uint64_t)n * sizeof *counted + 1);
    if (bvh) qpoint_bvh_subtree_tris(bvh, counted);
    else qpoint_subtree_tris(kd, counted);
    tris = counted;
  }
  const uint64_t rays =
      p->dyn_ray_buffer_bytes ? p->dyn_ray_buffer_bytes : (uint64_t)workers * sizeof(struct ray);
  /* Geometry resident at once: one queue point a core, or one for the chip. */
  const uint32_t holders = p->dyn_sharing == POLICY_DYN_CHIP ? 1 : cores;
  struct qpoint_reserve res = {
      p->cache_bytes, p->dyn_node_share, p->dyn_table_share, p->dyn_ray_share, rays, holders};
  if (bvh) qpoint_bvh_plan(qs, b, bvh, tris, tri_bytes, &res);
  else qpoint_plan(qs, b, kd, tris, tri_bytes, &res);
  *block_tris = clamp_u32(b->gmax_bytes / tri_bytes);
  *group = clamp_u32(b->ray_bytes / sizeof(struct ray) / workers);
  free(counted);
}

void qplan_job(const struct policy_job *job, struct qpoint_set *qs, struct qpoint_budget *b,
               uint32_t *block_tris, uint32_t *group) {
  const struct policy_setup *s = &job->setup;
  qplan_make(&job->params, job->workers, job->cores, s->kd, s->bvh, s->subtree_tris,
             s->layout.tri_bytes, qs, b, block_tris, group);
}
