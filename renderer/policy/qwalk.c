/* The resumable walk (qwalk.h): trace.c's traversal steps (renderer/trav.h),
 * paused at queue points and rebuilt there. */
#include "renderer/policy/qwalk.h"

#include <math.h>

#include "renderer/policy/qpoint.h"
#include "renderer/policy/qwalk_bvh.h"
#include "renderer/ray.h"
#include "renderer/scene.h"
#include "sim/err.h"

/* The segment of shadow ray r reversed: from its end (at the light) back to
 * its origin, stretched by a relative 2^-16 at both ends to absorb the
 * rounding of the end point. False when that is not a valid ray (an infinite
 * segment): the canonical direction is used then. */
static bool reversed(const struct ray *r, struct ray *rv) {
  *rv = *r;
  rv->o = v3_add(r->o, v3_scale(r->d, r->tmax));
  rv->d = v3_scale(r->d, -1.0f);
  float m = r->tmax * (1.0f / 65536.0f);
  rv->tmin = -m;
  rv->tmax = r->tmax + m;
  return isfinite(m) && trav_ray_valid(rv);
}

/* Recompute the hit a record carries (hit_prim) with its canonical ray: the
 * test is deterministic and its t does not depend on the range it is given,
 * so this is the very hit found earlier (t, b1, b2 bit for bit).
 * NOTE: not announced as a load: the host record has no room for t, where a
 * real one would carry it (the paper's rays have spare bytes). */
static void restore_hit(const struct qwalk_tree *t, const struct trace_isect_ray *ir,
                        const struct ray *r, struct trace_hit *h) {
  CHECK_GE(r->hit_prim, 0);
  CHECK_LT((uint32_t)r->hit_prim, t->s->tri_count);
  const struct scene_tri *tri = &t->s->tris[r->hit_prim];
  bool ok =
      trace_isect_tri(ir, tri->v[0], tri->v[1], tri->v[2], r->tmin, r->tmax, &h->t, &h->b1, &h->b2);
  CHECK(ok);
  h->prim = r->hit_prim;
}

bool qwalk_init(const struct qwalk_tree *t, struct qwalk *w, const struct ray *r) {
  /* The structure's root box: the k-d tree's or the BVH's. */
  const uint32_t nodes = t->bvh ? t->bvh->node_count : t->kd->node_count;
  const vec3 lo = t->bvh ? t->bvh->lo : t->kd->lo, hi = t->bvh ? t->bvh->hi : t->kd->hi;
  w->any = r->type == RAY_SHADOW;
  trav_best_init(&w->best, r->tmax);
  w->tmin = r->tmin;
  w->ignore = r->ignore_prim;
  if (!trav_ray_valid(r) || nodes == 0) return false;
  if (!trav_setup_box(&w->tv, lo, hi, r)) return false;
  trace_isect_prepare(&w->ir, r->o, r->d);
  if (w->any) {
    struct ray rv;
    if (reversed(r, &rv) && !trav_setup_box(&w->tv, lo, hi, &rv)) return false;
  } else if (r->hit_prim >= 0) {
    struct trace_hit h;
    restore_hit(t, &w->ir, r, &h);
    trav_best_offer(&w->best, h.t, (uint32_t)h.prim, h.b1, h.b2);
  }
  w->ni = 0;
  w->t0 = w->tv.t0;
  w->t1 = w->tv.t1;
  w->sp = 0;
  return true;
}

bool qwalk_leaf(const struct qwalk_tree *t, struct trace_ctx *tr, struct qwalk *w, uint32_t n,
                uint32_t j0, uint32_t j1) {
  if (t->bvh) return qwalk_bvh_leaf(t, tr, w, n, j0, j1);
  return trav_leaf(tr, &w->ir, w->tmin, w->ignore, w->any, t->nodes[n], j0, j1, &w->best);
}

/* Pop the next pending node above stack depth floor, skipping those entirely
 * beyond the best hit (trace.c's rule). False when none is left. */
static bool walk_pop(struct qwalk *w, int floor) {
  return trav_pop(w->stack, &w->sp, floor, &w->best, &w->ni, &w->t0, &w->t1);
}

enum qwalk_end qwalk_run(const struct qwalk_tree *t, struct trace_ctx *tr, struct qwalk *w,
                         int floor, bool to_queue) {
  if (t->bvh) return qwalk_bvh_run(t, tr, w, floor, to_queue);
  for (;;) {
    trav_announce_node(tr, w->ni, 1);
    struct kd_node nd = t->nodes[w->ni];
    if (to_queue && qpoint_marked(t->mark, w->ni)) return QWALK_QUEUED;
    if (!kd_is_leaf(nd)) {
      if (trav_interior(&w->tv, nd, w->ni, &w->t0, &w->t1, &w->ni, w->stack, &w->sp)) continue;
    } else {
      CHECK(!to_queue || kd_leaf_count(nd) == 0); /* geometry is below queue points */
      if (qwalk_leaf(t, tr, w, w->ni, 0, kd_leaf_count(nd))) return QWALK_HIT;
    }
    if (!walk_pop(w, floor)) return QWALK_DONE;
  }
}

/* Where the path goes to the far child, the uncut traversal had pushed it,
 * finished the near side, and popped it: so pop it here. */
void qwalk_to(const struct qwalk_tree *t, struct trace_ctx *tr, struct qwalk *w, uint32_t q) {
  if (t->bvh) {
    qwalk_bvh_to(t, tr, w, q);
    return;
  }
  while (w->ni != q) {
    trav_announce_node(tr, w->ni, 1);
    struct kd_node nd = t->nodes[w->ni];
    CHECK(!kd_is_leaf(nd));
    uint32_t c = q >= kd_above(nd) ? kd_above(nd) : w->ni + 1, next;
    bool ok = trav_interior(&w->tv, nd, w->ni, &w->t0, &w->t1, &next, w->stack, &w->sp);
    CHECK(ok);
    if (next != c) {
      CHECK_GT(w->sp, 0);
      CHECK_EQ(w->stack[w->sp - 1].node, c);
      w->sp--;
      w->t0 = w->stack[w->sp].t0;
      w->t1 = w->stack[w->sp].t1;
    }
    w->ni = c;
  }
}

enum qwalk_end qwalk_run_treelet(const struct qwalk_tree *t, struct trace_ctx *tr, struct qwalk *w,
                                 const uint32_t *of) {
  if (t->bvh) return qwalk_bvh_run_treelet(t, tr, w, of);
  const uint32_t cur = of[w->ni];
  for (;;) {
    if (of[w->ni] != cur) return QWALK_QUEUED;
    trav_announce_node(tr, w->ni, 1);
    struct kd_node nd = t->nodes[w->ni];
    if (!kd_is_leaf(nd)) {
      if (trav_interior(&w->tv, nd, w->ni, &w->t0, &w->t1, &w->ni, w->stack, &w->sp)) continue;
    } else if (qwalk_leaf(t, tr, w, w->ni, 0, kd_leaf_count(nd))) {
      return QWALK_HIT;
    }
    if (!walk_pop(w, 0)) return QWALK_DONE;
  }
}

enum qwalk_end qwalk_leave_treelet(const struct qwalk_tree *t, struct qwalk *w) {
  return (t->bvh ? qwalk_bvh_pop(w, 0) : walk_pop(w, 0)) ? QWALK_QUEUED : QWALK_DONE;
}

enum qwalk_end qwalk_leave(const struct qwalk_tree *t, struct trace_ctx *tr, struct qwalk *w) {
  if (!(t->bvh ? qwalk_bvh_pop(w, 0) : walk_pop(w, 0))) return QWALK_DONE;
  return qwalk_run(t, tr, w, 0, true);
}
