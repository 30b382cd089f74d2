/* The dynamic policy (the paper's section 2): rays wait in queues at queue
 * points, nodes whose subtree geometry fits the cache (qpoint.h), and a queue
 * is processed as a whole so that its subtree's geometry is loaded once for
 * all its rays. Rays are traced in generations (section 2.1.2): the closest
 * hits of a generation, then its shadow rays (traced from the light toward the
 * points), then the next generation's reflection rays, until none are left.
 * Primary rays are admitted all at once, or dyn_batch_rays at a time with each
 * batch traced through all its generations (policy.h); a batch is a work
 * item. A queue is read newest ray first (cur_newest). One worker for now:
 * the queues are the job's (struct dyn), the pending spawned rays and the
 * counters the worker's (struct dyn_worker).
 *
 * Same image as the recursive policy, bit for bit:
 * - A closest-hit ray makes exactly the traversal trace_closest makes, only
 *   cut into pieces at queue points. A k-d traversal's pending stack is a
 *   function of the path from the root to the current node (the far children
 *   of the ancestors where it went near), so a dequeued ray rebuilds it by
 *   re-descending from the root to its queue point with the same arithmetic;
 *   its best hit so far travels in the record (hit_prim). So every ray tests
 *   the same triangles in the same order as under trace_closest.
 * - A shadow ray's record keeps the canonical ray that shade_hit made; the
 *   schedule and the memory accesses follow the same segment reversed (from
 *   its end at the light back to the point, widened like trace.c), but every
 *   triangle is tested with the canonical ray. Occlusion is whether any
 *   triangle crossing the segment is hit, and the reversed traversal visits
 *   every leaf the segment crosses, so the answer is trace_any's.
 *
 * A ray that ends is shaded at once (section 2.1.1: "shade the intersection
 * point immediately"), and the rays it spawns are taken down to their first
 * queue point and queued for their phase: each queue point has a queue for
 * this generation's closest-hit rays, one for its shadow rays (drained once
 * all closest-hit rays are done, so they queue up in full before any is
 * traced) and one for the next generation. So a ray waits in memory only in a
 * queue, and the picture is still the recursive policy's: shading is linear
 * and the framebuffer sums in fixed point, so order does not matter.
 *
 * Simulated memory (besides nodes, leaf lists and triangles, as trace.c):
 * - primary rays are read from the camera's array (policy_primary);
 * - queue table at qtable_base: entry q (8 bytes: its buffer's tail) is loaded
 *   and stored on each enqueue, and when the queue is drained;
 * - queue buffers at queue_base: chunks of DYN_CHUNK_RAYS 64-byte rays,
 *   chunk c at queue_base + 4096 c; a queue is a list of chunks, drained
 *   chunks go to a last-in-first-out free list, new chunks come from it first
 *   (so the arena stays as small as the most rays ever queued at once). An
 *   enqueue writes a whole line, which the cache allocates without a fetch. */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "renderer/camera.h"
#include "renderer/framebuffer.h"
#include "renderer/kdtree.h"
#include "renderer/policy.h"
#include "renderer/policy_impl.h"
#include "renderer/qpoint.h"
#include "renderer/scene.h"
#include "renderer/shade.h"
#include "renderer/trace.h"
#include "renderer/trav.h"
#include "sim/err.h"

#define DYN_CHUNK_RAYS 64u
#define DYN_CHUNK_BYTES (DYN_CHUNK_RAYS * sizeof(struct ray))
#define DYN_NONE UINT32_MAX
/* Host-only mark of a ray that ended during a blocked pass (never simulated). */
#define DYN_FLAG_DEAD 0x80u

/* Traversal steps (trav_setup, trav_interior, announce_*) come from
 * renderer/trav.h, shared with trace.c: the same arithmetic gives the same hits. */

/* ---- policy state ---------------------------------------------------------- */

struct dyn_queue {
  uint32_t head, tail;  /* chunks, DYN_NONE when empty */
  uint32_t tail_fill;   /* rays in the tail chunk */
  uint32_t count;       /* rays queued */
  int64_t heap_pos;     /* position in the heap, -1 when not in it */
};

struct ray_buf {
  struct ray *r;
  uint64_t n, cap;
};

/* The job's shared state: queue points, queues and their arena, the heap,
 * the primary rays' order. (When several workers share it, the queues will
 * belong to cores: a core owns a queue point and its threads drain it.) */
struct dyn {
  const struct trace_layout *l; /* the job's layout (queue and table addresses) */
  const struct kd_tree *kd;
  const struct scene *s;
  struct qpoint_set qs;
  uint32_t block_tris; /* triangles of an oversized leaf processed at once */
  uint32_t ray_block;  /* rays streamed at once against such a block */
  /* Queues: the phase being drained (q, ordered by the heap), this
   * generation's shadow rays (qsh), the next generation (qn); and their chunk
   * arena. */
  struct dyn_queue *q, *qsh, *qn;
  struct ray *pool;      /* chunk c: pool[c * DYN_CHUNK_RAYS ...] */
  uint32_t *chunk_next;  /* next chunk of the same queue, or of the free list */
  uint32_t chunks, chunk_cap, free_head;
  /* Non-empty queues: a max-heap on (count, -index). */
  uint32_t *heap;
  uint32_t heap_n;
  uint32_t *order;  /* primary rays (work items) in Hilbert order */
  uint64_t batch;   /* primary rays a work item admits */
};

/* A worker's own (its scratch): where its accesses and counts go, and the
 * rays its shading spawned, started once the ray that spawned them is done
 * (so each ray's cost is its own). Set up afresh by each step. */
struct dyn_worker {
  struct dyn *d;
  struct policy_job *job;
  struct tracer *tr;
  struct render_stats *st;
  struct ray_buf pend;
  uint64_t progress_at;
};

/* One ray's traversal state: the scheduling traversal (for a shadow ray the
 * reversed segment), the canonical ray's test, the best hit so far. */
struct walk {
  struct trav_ray tv;
  struct isect_ray ir;
  float tmin;
  int32_t ignore;
  bool any;
  struct trav_best best;
  uint32_t ni;
  float t0, t1;
  int sp;
  struct trav_entry stack[KD_DEPTH_LIMIT];
};

enum walk_end { WALK_DONE, WALK_QUEUED, WALK_HIT };

static void buf_push(struct ray_buf *b, const struct ray *r) {
  if (b->n == b->cap) {
    b->cap = b->cap ? 2 * b->cap : 4096;
    b->r = xrealloc(b->r, b->cap * sizeof *b->r);
  }
  b->r[b->n++] = *r;
}

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
  return isfinite(m) && ray_valid(rv);
}

/* Recompute the hit a record carries (hit_prim) with its canonical ray: the
 * test is deterministic and its t does not depend on the range it is given,
 * so this is the very hit found earlier (t, b1, b2 bit for bit).
 * NOTE: not announced as a load: the host record has no room for t, where a
 * real one would carry it (the paper's rays have spare bytes). */
static void restore_hit(const struct dyn *d, const struct isect_ray *ir, const struct ray *r,
                        struct hit *h) {
  CHECK(r->hit_prim >= 0 && (uint32_t)r->hit_prim < d->s->tri_count);
  const struct scene_tri *tri = &d->s->tris[r->hit_prim];
  bool ok = isect_tri(ir, tri->v[0], tri->v[1], tri->v[2], r->tmin, r->tmax, &h->t, &h->b1, &h->b2);
  CHECK(ok);
  h->prim = r->hit_prim;
}

/* Prepare r's traversal at the root. False when r ends without one, exactly
 * when trace.c's would (invalid ray, empty tree, root box missed). */
static bool walk_init(const struct dyn *d, struct walk *w, const struct ray *r) {
  const struct kd_tree *kd = d->kd;
  w->any = r->type == RAY_SHADOW;
  trav_best_init(&w->best, r->tmax);
  w->tmin = r->tmin;
  w->ignore = r->ignore_prim;
  if (!ray_valid(r) || kd->node_count == 0) return false;
  if (!trav_setup(&w->tv, kd, r)) return false;
  isect_prepare(&w->ir, r->o, r->d);
  if (w->any) {
    struct ray rv;
    if (reversed(r, &rv) && !trav_setup(&w->tv, kd, &rv)) return false;
  } else if (r->hit_prim >= 0) {
    struct hit h;
    restore_hit(d, &w->ir, r, &h);
    trav_best_offer(&w->best, h.t, (uint32_t)h.prim, h.b1, h.b2);
  }
  w->ni = 0;
  w->t0 = w->tv.t0;
  w->t1 = w->tv.t1;
  w->sp = 0;
  return true;
}

/* Test entries [j0, j1) of leaf nd as trace.c does. True: a shadow ray is
 * occluded. */
static bool walk_leaf(struct tracer *tr, struct walk *w, struct kd_node nd, uint32_t j0,
                      uint32_t j1) {
  return trav_leaf(tr, &w->ir, w->tmin, w->ignore, w->any, nd, j0, j1, &w->best);
}

/* Pop the next pending node above stack depth floor, skipping those entirely
 * beyond the best hit (trace.c's rule). False when none is left. */
static bool walk_pop(struct walk *w, int floor) {
  return trav_pop(w->stack, &w->sp, floor, &w->best, &w->ni, &w->t0, &w->t1);
}

/* Traverse from the current node. In a queue point's subtree (to_queue false)
 * run until its pending nodes (those above floor) are done; above the queue
 * points (to_queue true) stop at the first queue point reached. */
static enum walk_end walk_run(const struct dyn *d, struct tracer *tr, struct walk *w, int floor,
                              bool to_queue) {
  for (;;) {
    announce_node(tr, w->ni, 1);
    struct kd_node nd = d->qs.nodes[w->ni];
    if (to_queue && kd_is_queue_point(nd)) return WALK_QUEUED;
    if (!kd_is_leaf(nd)) {
      if (trav_interior(&w->tv, nd, w->ni, &w->t0, &w->t1, &w->ni, w->stack, &w->sp)) continue;
    } else {
      CHECK(!to_queue || kd_leaf_count(nd) == 0); /* geometry is below queue points */
      if (walk_leaf(tr, w, nd, 0, kd_leaf_count(nd))) return WALK_HIT;
    }
    if (!walk_pop(w, floor)) return WALK_DONE;
  }
}

/* Rebuild the traversal state at queue point q: descend from the root along
 * the path to q, pushing what the original traversal pushed there. Where the
 * path goes to the far child, the traversal had pushed it, finished the near
 * side, and popped it: so pop it here. */
static void walk_to(const struct dyn *d, struct tracer *tr, struct walk *w, uint32_t q) {
  while (w->ni != q) {
    announce_node(tr, w->ni, 1);
    struct kd_node nd = d->qs.nodes[w->ni];
    CHECK(!kd_is_leaf(nd));
    uint32_t c = q >= kd_above(nd) ? kd_above(nd) : w->ni + 1, next;
    bool ok = trav_interior(&w->tv, nd, w->ni, &w->t0, &w->t1, &next, w->stack, &w->sp);
    CHECK(ok);
    if (next != c) {
      CHECK(w->sp > 0 && w->stack[w->sp - 1].node == c);
      w->sp--;
      w->t0 = w->stack[w->sp].t0;
      w->t1 = w->stack[w->sp].t1;
    }
    w->ni = c;
  }
}

/* After a queue point's subtree: on to the next queue point, or the end. */
static enum walk_end walk_leave(const struct dyn *d, struct tracer *tr, struct walk *w) {
  if (!walk_pop(w, 0)) return WALK_DONE;
  return walk_run(d, tr, w, 0, true);
}

/* ---- queues ---------------------------------------------------------------- */

static bool heap_above(const struct dyn *d, uint32_t a, uint32_t b) {
  uint32_t ca = d->q[a].count, cb = d->q[b].count;
  return ca > cb || (ca == cb && a < b);
}

static void heap_set(struct dyn *d, uint32_t pos, uint32_t qi) {
  d->heap[pos] = qi;
  d->q[qi].heap_pos = pos;
}

static void heap_up(struct dyn *d, uint32_t pos) {
  uint32_t qi = d->heap[pos];
  while (pos > 0) {
    uint32_t parent = (pos - 1) / 2;
    if (!heap_above(d, qi, d->heap[parent])) break;
    heap_set(d, pos, d->heap[parent]);
    pos = parent;
  }
  heap_set(d, pos, qi);
}

static uint32_t heap_pop(struct dyn *d) {
  uint32_t top = d->heap[0];
  d->q[top].heap_pos = -1;
  uint32_t last = d->heap[--d->heap_n];
  if (d->heap_n > 0) {
    uint32_t pos = 0;
    for (;;) {
      uint32_t c = 2 * pos + 1;
      if (c >= d->heap_n) break;
      if (c + 1 < d->heap_n && heap_above(d, d->heap[c + 1], d->heap[c])) c++;
      if (!heap_above(d, d->heap[c], last)) break;
      heap_set(d, pos, d->heap[c]);
      pos = c;
    }
    heap_set(d, pos, last);
  }
  return top;
}

static uint32_t chunk_alloc(struct dyn *d) {
  uint32_t c;
  if (d->free_head != DYN_NONE) {
    c = d->free_head;
    d->free_head = d->chunk_next[c];
  } else {
    if (d->chunks == d->chunk_cap) {
      d->chunk_cap = d->chunk_cap ? 2 * d->chunk_cap : 256;
      d->pool = xrealloc(d->pool, (uint64_t)d->chunk_cap * DYN_CHUNK_RAYS * sizeof *d->pool);
      d->chunk_next = xrealloc(d->chunk_next, (uint64_t)d->chunk_cap * sizeof *d->chunk_next);
    }
    c = d->chunks++;
  }
  d->chunk_next[c] = DYN_NONE;
  return c;
}

static void chunk_free(struct dyn *d, uint32_t c) {
  d->chunk_next[c] = d->free_head;
  d->free_head = c;
}

static uint64_t slot_addr(const struct dyn *d, uint32_t c, uint32_t i) {
  return d->l->queue_base + (uint64_t)c * DYN_CHUNK_BYTES + (uint64_t)i * sizeof(struct ray);
}

static uint64_t table_addr(const struct dyn *d, uint32_t qi) {
  return d->l->qtable_base + 8ull * qi;
}

/* Append r to queue qi of queue set qset (d->q, d->qsh or d->qn): the table
 * entry is loaded, the ray stored in its slot, the entry stored. The slot is
 * claimed (counts, host copy, heap) before the first access, as any of them
 * may suspend this worker and the next enqueue must find the slot taken. */
static void enqueue(struct dyn_worker *x, uint32_t qi, const struct ray *r,
                    struct dyn_queue *qset) {
  struct dyn *d = x->d;
  const struct mem_port *mem = &x->tr->mem;
  struct dyn_queue *q = &qset[qi];
  CHECK(!(r->flags & DYN_FLAG_DEAD));
  if (q->tail == DYN_NONE || q->tail_fill == DYN_CHUNK_RAYS) {
    uint32_t c = chunk_alloc(d);
    if (q->tail == DYN_NONE)
      q->head = c;
    else
      d->chunk_next[q->tail] = c;
    q->tail = c;
    q->tail_fill = 0;
  }
  const uint32_t c = q->tail, i = q->tail_fill;
  d->pool[(uint64_t)c * DYN_CHUNK_RAYS + i] = *r;
  q->tail_fill++;
  q->count++;
  if (qset == d->q) { /* the heap orders the phase being drained only */
    if (q->heap_pos < 0) {
      d->heap[d->heap_n] = qi;
      q->heap_pos = d->heap_n++;
    }
    heap_up(d, (uint32_t)q->heap_pos);
  }
  mem_load(mem, table_addr(d, qi), 8, TRACE_CLASS_QUEUE);
  mem_store(mem, slot_addr(d, c, i), sizeof *r, TRACE_CLASS_RAY);
  mem_store(mem, table_addr(d, qi), 8, TRACE_CLASS_QUEUE);
}

/* ---- ray ends ---------------------------------------------------------------- */

static void progress(struct dyn_worker *x) {
  const struct policy_setup *s = &x->job->setup;
  const struct render_stats *st = x->st;
  if (s->progress && st->terminated >= x->progress_at && st->terminated < st->spawned) {
    s->progress(s->progress_ctx, st->terminated, st->spawned);
    x->progress_at = st->terminated + (1u << 16);
  }
}

/* A ray ends: a shadow ray adds its light, any other is shaded now (its hit
 * is the walk's best; a miss has t = tmax, as trace_closest gives it) and its
 * children wait in pend until this ray's work is counted. */
static void terminate(struct dyn_worker *x, struct ray *r, const struct walk *w, enum walk_end e) {
  const struct policy_setup *s = &x->job->setup;
  x->st->rays[r->type]++;
  x->st->terminated++;
  if (r->type == RAY_SHADOW) {
    shade_shadow(r, e == WALK_HIT, s->fb, &x->tr->mem);
  } else {
    struct hit h;
    trav_best_hit(&w->best, &h);
    r->hit_prim = -1;
    struct ray spawn[SHADE_MAX_SPAWN];
    uint32_t n = shade_hit(s->sc, r, &h, s->fb, &x->tr->mem, spawn);
    x->st->spawned += n;
    for (uint32_t k = 0; k < n; k++) buf_push(&x->pend, &spawn[k]);
  }
  progress(x);
}

/* Where a ray goes after a walk: a queue of set qset, or its end. */
static void route(struct dyn_worker *x, struct ray *r, const struct walk *w, enum walk_end e,
                  struct dyn_queue *qset) {
  if (e == WALK_QUEUED) {
    int64_t qi = qpoint_index(&x->d->qs, w->ni);
    CHECK(qi >= 0);
    r->hit_prim = w->best.found ? (int32_t)w->best.p : -1;
    enqueue(x, (uint32_t)qi, r, qset);
  } else {
    terminate(x, r, w, e);
  }
}

/* Per-pixel cost: the work this worker's tracer counted for a ray since the
 * marks (its own counters: others' work never lands in them). */
static void cost_add(const struct dyn_worker *x, uint32_t pixel, uint64_t nodes0,
                     uint64_t tris0) {
  struct framebuffer *fb = x->job->setup.fb;
  fb->cost_nodes[pixel] += (uint32_t)(x->tr->stats.node_visits - nodes0);
  fb->cost_tris[pixel] += (uint32_t)(x->tr->stats.tri_tests - tris0);
}

/* A new ray: found its first queue point (the one holding its origin, for a
 * ray that starts inside the scene) and queue it there, or end it. Primary
 * rays join the queues being filled for generation 0, shadow rays this
 * generation's shadow queues, reflection rays the next generation's.
 * The walk that finds the queue point is not charged to memory: it follows
 * the path from the root to that queue point, which the ray loads when it is
 * dequeued there (walk_to), so charging it here would count the path twice.
 * It runs on a native copy of the worker's tracer (its counts are kept), so
 * the worker's port is never changed. (The paper starts a new ray at the
 * queue point holding its origin.) */
static void start(struct dyn_worker *x, struct ray *r) {
  struct dyn *d = x->d;
  struct tracer *tr = x->tr;
  uint64_t n0 = tr->stats.node_visits, t0 = tr->stats.tri_tests;
  struct walk w;
  struct dyn_queue *qset = r->type == RAY_PRIMARY ? d->q : r->type == RAY_SHADOW ? d->qsh : d->qn;
  if (!walk_init(d, &w, r)) {
    terminate(x, r, &w, WALK_DONE);
  } else {
    struct tracer quiet = *tr;
    quiet.mem = mem_port_native();
    enum walk_end e = walk_run(d, &quiet, &w, 0, true);
    tr->stats = quiet.stats;
    route(x, r, &w, e, qset);
  }
  cost_add(x, r->pixel, n0, t0);
}

/* Start the rays that this worker's shading spawned, and any that they spawn
 * in turn when they end at once (pend grows meanwhile: n is re-read). */
static void flush(struct dyn_worker *x) {
  for (uint64_t i = 0; i < x->pend.n; i++) {
    struct ray r = x->pend.r[i];
    start(x, &r);
  }
  x->pend.n = 0;
}

/* ---- draining a queue ---------------------------------------------------------- */

/* A ray of interior queue point node: its subtree, then onward. */
static void process_subtree(struct dyn_worker *x, struct ray *r, uint32_t node) {
  struct dyn *d = x->d;
  struct tracer *tr = x->tr;
  uint64_t n0 = tr->stats.node_visits, t0 = tr->stats.tri_tests;
  struct walk w;
  CHECK(walk_init(d, &w, r));
  walk_to(d, tr, &w, node);
  enum walk_end e = walk_run(d, tr, &w, w.sp, false);
  if (e == WALK_DONE) e = walk_leave(d, tr, &w);
  route(x, r, &w, e, d->q);
  cost_add(x, r->pixel, n0, t0);
  flush(x);
}

/* Load (announce) entries [j0, j1) of a leaf's geometry, as the paper does on
 * opening a queue at a leaf: it will all be tested. */
static void preload_leaf(struct tracer *tr, struct kd_node nd, uint32_t j0, uint32_t j1) {
  uint32_t off = kd_leaf_offset(nd);
  for (uint32_t j = j0; j < j1; j++) {
    uint32_t p = trav_leaf_prim(tr, off + j);
    mem_load(&tr->mem, tr->layout.tri_base + (uint64_t)tr->layout.tri_bytes * p, tr->layout.tri_bytes,
             TRACE_CLASS_GEOMETRY);
  }
}

/* Step a cursor over a detached queue's slots, newest first: the tail chunk
 * from its last ray down, then each earlier chunk from its last slot down. The
 * newest rays are the likeliest to be still in the cache, so they are read
 * before the queue's own work evicts them. */
struct slot_cur {
  uint32_t c, i;
  uint64_t left; /* slots from here to the end of the queue */
};

static uint64_t cur_index(const struct slot_cur *k) { return (uint64_t)k->c * DYN_CHUNK_RAYS + k->i; }

/* Reverse a detached queue's chunk list (host bookkeeping only) and return a
 * cursor at its newest ray. */
static struct slot_cur cur_newest(struct dyn *d, uint32_t head, uint32_t tail_fill, uint64_t count) {
  uint32_t prev = DYN_NONE;
  for (uint32_t c = head; c != DYN_NONE;) {
    uint32_t nc = d->chunk_next[c];
    d->chunk_next[c] = prev;
    prev = c;
    c = nc;
  }
  struct slot_cur k = {prev, tail_fill - 1, count};
  return k;
}

/* Advance; with release, a chunk is freed once the cursor leaves it (its rays
 * may go on to other queues meanwhile, which may reuse it). */
static void cur_next(struct dyn *d, struct slot_cur *k, bool release) {
  k->left--;
  if (k->i == 0 || k->left == 0) {
    uint32_t nc = d->chunk_next[k->c];
    if (release) chunk_free(d, k->c);
    k->c = nc;
    k->i = DYN_CHUNK_RAYS - 1;
  } else {
    k->i--;
  }
}

/* A queue at a leaf. Its geometry is loaded in blocks of block_tris triangles
 * (one block unless the leaf exceeds g_max: the paper's "separate scheduling
 * problem"); each block is tested against all the queue's rays, streamed
 * ray_block at a time (loaded, tested, stored back with their best hit). After
 * the last block each ray goes on. Every ray still tests the leaf's triangles
 * in the leaf's order, so its hit is the one a single traversal finds. */
static void drain_leaf(struct dyn_worker *x, uint32_t node, struct slot_cur first) {
  struct dyn *d = x->d;
  struct tracer *tr = x->tr;
  const struct mem_port *mem = &tr->mem;
  struct kd_node nd = d->qs.nodes[node];
  uint32_t cnt = kd_leaf_count(nd), bt = d->block_tris;
  uint32_t blocks = cnt == 0 ? 1 : (cnt + bt - 1) / bt;
  for (uint32_t b = 0; b < blocks; b++) {
    uint32_t j0 = b * bt, j1 = cnt - j0 > bt ? j0 + bt : cnt;
    bool last = b + 1 == blocks;
    preload_leaf(tr, nd, j0, j1);
    struct slot_cur k = first;
    while (k.left > 0) {
      struct slot_cur blk = k;
      uint64_t n = k.left < d->ray_block ? k.left : d->ray_block;
      for (uint64_t t = 0; t < n; t++, cur_next(d, &k, last)) {
        struct ray r = d->pool[cur_index(&k)];
        if (r.flags & DYN_FLAG_DEAD) continue;
        uint64_t n0 = tr->stats.node_visits, t0 = tr->stats.tri_tests;
        mem_load(mem, slot_addr(d, k.c, k.i), sizeof r, TRACE_CLASS_RAY);
        struct walk w;
        CHECK(walk_init(d, &w, &r));
        if (walk_leaf(tr, &w, nd, j0, j1)) {
          terminate(x, &r, &w, WALK_HIT);
          d->pool[cur_index(&k)].flags |= DYN_FLAG_DEAD;
        } else if (!last) {
          d->pool[cur_index(&k)].hit_prim = w.best.found ? (int32_t)w.best.p : -1;
        } else {
          walk_to(d, tr, &w, node);
          route(x, &r, &w, walk_leave(d, tr, &w), d->q);
        }
        cost_add(x, r.pixel, n0, t0);
        flush(x);
      }
      /* Store the block back with its best hits (the last pass moved them on). */
      for (uint64_t t = 0; !last && t < n; t++, cur_next(d, &blk, false))
        if (!(d->pool[cur_index(&blk)].flags & DYN_FLAG_DEAD))
          mem_store(mem, slot_addr(d, blk.c, blk.i), sizeof(struct ray), TRACE_CLASS_RAY);
    }
  }
}

static void drain(struct dyn_worker *x, uint32_t qi) {
  struct dyn *d = x->d;
  const struct mem_port *mem = &x->tr->mem;
  struct dyn_queue *q = &d->q[qi];
  uint32_t node = d->qs.qnode[qi];
  struct slot_cur first = cur_newest(d, q->head, q->tail_fill, q->count);
  /* Detach the list: no ray comes back to a queue point it has left (a
   * traversal visits a node once), so nothing joins it while it drains. */
  q->head = q->tail = DYN_NONE;
  q->tail_fill = q->count = 0;
  mem_load(mem, table_addr(d, qi), 8, TRACE_CLASS_QUEUE);
  mem_store(mem, table_addr(d, qi), 8, TRACE_CLASS_QUEUE);
  if (kd_is_leaf(d->qs.nodes[node])) {
    drain_leaf(x, node, first);
    return;
  }
  for (struct slot_cur k = first; k.left > 0; cur_next(d, &k, true)) {
    struct ray r = d->pool[cur_index(&k)];
    mem_load(mem, slot_addr(d, k.c, k.i), sizeof r, TRACE_CLASS_RAY);
    process_subtree(x, &r, node);
  }
}

/* Process queues until all are empty, the fullest first (ties: the lower
 * index). The fullest queue amortises its subtree's geometry over the most
 * rays, and meanwhile the others fill up. */
static void drain_all(struct dyn_worker *x) {
  while (x->d->heap_n > 0) drain(x, heap_pop(x->d));
}

/* ---- generations ----------------------------------------------------------- */

/* Make queue set *other the one being drained (the drained set, empty now,
 * takes its place) and order its non-empty queues in the heap. */
static void activate(struct dyn *d, struct dyn_queue **other) {
  CHECK(d->heap_n == 0);
  struct dyn_queue *t = d->q;
  d->q = *other;
  *other = t;
  for (uint32_t i = 0; i < d->qs.count; i++)
    if (d->q[i].count > 0) {
      d->heap[d->heap_n] = i;
      d->q[i].heap_pos = d->heap_n++;
      heap_up(d, (uint32_t)d->q[i].heap_pos);
    }
}

/* ---- the module --------------------------------------------------------------- */

static void dyn_create(struct policy_job *job) {
  const struct policy_params *p = &job->params;
  struct dyn *d = xcalloc(1, sizeof *d);
  d->l = &job->setup.layout;
  d->kd = job->setup.kd;
  d->s = job->setup.scene;
  d->free_head = DYN_NONE;

  /* Queue points for the cache. */
  const uint32_t tri_bytes = d->l->tri_bytes;
  uint32_t *tris = xmalloc((uint64_t)d->kd->node_count * sizeof *tris + 1);
  qpoint_subtree_tris(d->kd, tris);
  struct qpoint_reserve res = {p->cache_bytes, p->dyn_node_share, p->dyn_table_share,
                               p->dyn_ray_share, p->dyn_ray_buffer_bytes, 1};
  struct qpoint_budget bud;
  qpoint_plan(&d->qs, &bud, d->kd, tris, tri_bytes, &res);
  free(tris);
  uint64_t bt = bud.gmax_bytes / tri_bytes;
  d->block_tris = bt == 0 ? 1 : (bt > UINT32_MAX ? UINT32_MAX : (uint32_t)bt);
  uint64_t rb = bud.ray_bytes / sizeof(struct ray);
  d->ray_block = rb == 0 ? 1 : (rb > UINT32_MAX ? UINT32_MAX : (uint32_t)rb);
  d->q = xmalloc((uint64_t)d->qs.count * sizeof *d->q + 1);
  d->qsh = xmalloc((uint64_t)d->qs.count * sizeof *d->qsh + 1);
  d->qn = xmalloc((uint64_t)d->qs.count * sizeof *d->qn + 1);
  for (uint32_t i = 0; i < d->qs.count; i++) {
    d->q[i].head = d->q[i].tail = DYN_NONE;
    d->q[i].tail_fill = d->q[i].count = 0;
    d->q[i].heap_pos = -1;
    d->qsh[i] = d->qn[i] = d->q[i];
  }
  d->heap = xmalloc((uint64_t)d->qs.count * sizeof *d->heap + 1);

  /* The work items: primary rays in Hilbert order, admitted a batch at a time. */
  const uint32_t w = job->setup.fb->width, h = job->setup.fb->height;
  job->total = (uint64_t)w * h;
  job->progress_every = 0; /* progress counts rays (progress()) */
  d->order = xmalloc(job->total * sizeof *d->order + 1);
  camera_hilbert_order(w, h, d->order);
  d->batch = p->dyn_batch_rays ? p->dyn_batch_rays : job->total;
  job->shared = d;
}

static void dyn_destroy(struct policy_job *job) {
  struct dyn *d = job->shared;
  if (!d) return;
  free(d->order);
  free(d->heap);
  free(d->q);
  free(d->qsh);
  free(d->qn);
  free(d->pool);
  free(d->chunk_next);
  qpoint_fini(&d->qs);
  free(d);
}

static void dyn_scratch_free(void *scratch) {
  struct dyn_worker *x = scratch;
  if (!x) return;
  free(x->pend.r);
  free(x);
}

/* One batch of primary rays, each to its first queue, then all their
 * generations: closest-hit rays, their shadow rays, the next generation. */
static bool dyn_step(struct policy_job *job, struct policy_worker *wk) {
  struct dyn *d = job->shared;
  uint64_t k0, n = policy_job_claim(job, d->batch, &k0);
  if (n == 0) return false;
  if (!wk->scratch) wk->scratch = xcalloc(1, sizeof(struct dyn_worker));
  struct dyn_worker *x = wk->scratch;
  x->d = d;
  x->job = job;
  x->tr = &wk->tr;
  x->st = &wk->st;
  const uint32_t w = job->setup.fb->width;
  for (uint64_t k = k0; k < k0 + n; k++) {
    struct ray r;
    policy_primary(job, wk, d->order[k] % w, d->order[k] / w, &r);
    x->st->spawned++;
    start(x, &r);
    flush(x);
  }
  for (;;) {
    drain_all(x); /* this generation's closest-hit rays */
    activate(d, &d->qsh);
    drain_all(x); /* their shadow rays (which spawn nothing) */
    activate(d, &d->qn);
    if (d->heap_n == 0) break; /* no next generation */
  }
  policy_job_done(job, n);
  const struct policy_setup *s = &job->setup;
  if (job->done == job->total && s->progress)
    s->progress(s->progress_ctx, x->st->terminated, x->st->terminated);
  return true;
}

/* The queue arena at its largest: the rays in flight. */
static void dyn_finish(struct policy_job *job, struct render_stats *st) {
  const struct dyn *d = job->shared;
  st->ray_slots_max += (uint64_t)d->chunks * DYN_CHUNK_RAYS;
}

const struct policy_module policy_dynamic_module = {
    .region_bytes = 0, /* its rays wait in the queues, at queue_base */
    .max_workers = 1,  /* the queues are not yet shared between workers */
    .create = dyn_create,
    .destroy = dyn_destroy,
    .step = dyn_step,
    .scratch_free = dyn_scratch_free,
    .finish = dyn_finish,
};
