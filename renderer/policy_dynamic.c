/* The dynamic policy (the paper's section 2): rays wait in queues at queue
 * points, nodes whose subtree geometry fits the cache (qpoint.h), and a queue
 * is processed as a whole so that its subtree's geometry is loaded once for
 * all its rays. Rays are traced in generations (section 2.1.2): the closest
 * hits of a generation, then its shadow rays (traced from the light toward the
 * points), then the next generation's reflection rays, until none are left.
 * Primary rays are admitted all at once, or dyn_batch_rays at a time with each
 * batch traced through all its generations (policy.h); a batch is a work
 * item. A queue is read newest ray first (cur_newest).
 *
 * Many workers (ray contexts of the machine's cores) share one batch: the
 * queues are the job's (struct dyn). A core takes one queue point at a time,
 * the fullest queue no other core holds, into its drain (struct dyn_drain),
 * and its workers hand out the drain's rays among themselves, a ray (or a
 * group of rays, against an oversized leaf's geometry block) at a time; when
 * they are all handed out the core takes the next. A core that finds no free
 * queue joins the drain with the most rays left (its geometry is resident
 * already), so that a scene with fewer queue points than cores (at the
 * extreme, the root alone: Whitted) still keeps every core busy. A batch goes
 * through phases: its primary rays are admitted (each worker takes the next),
 * then each phase (closest hits, shadow rays) drains its own queue set; a
 * phase ends when no ray of it is queued or being traced, and the worker that
 * finds it over starts the next. A worker with nothing to take meanwhile waits
 * dyn_wait_cycles (mem_wait) and looks again. With one worker all this is the
 * single loop it always was: the same accesses in the same order.
 *
 * Same image as the recursive policy, bit for bit:
 * - A closest-hit ray makes exactly the traversal trace_closest makes, only
 *   cut into pieces at queue points. A k-d traversal's pending stack is a
 *   function of the path from the root to the current node (the far children
 *   of the ancestors where it went near), so a dequeued ray rebuilds it by
 *   re-descending from the root to its queue point with the same arithmetic;
 *   its best hit so far travels in the record (hit_prim). So every ray tests
 *   the same triangles as under trace_closest, and the hit rule (trav.h) does
 *   not depend on their order.
 * - A shadow ray's record keeps the canonical ray that shade_hit made; the
 *   schedule and the memory accesses follow the same segment reversed (from
 *   its end at the light back to the point, widened like trace.c), but every
 *   triangle is tested with the canonical ray. Occlusion is whether any
 *   triangle crossing the segment is hit, and the reversed traversal visits
 *   every leaf the segment crosses, so the answer is trace_any's.
 * - Which worker traces a ray, and when, changes nothing: a ray's record is
 *   the host's, written whole when it is queued, and the framebuffer sums
 *   contributions in fixed point.
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
 *   and stored on each enqueue, and when a core takes the queue;
 * - queue buffers at queue_base: chunks of DYN_CHUNK_RAYS 64-byte rays,
 *   chunk c at queue_base + 4096 c; a queue is a list of chunks, drained
 *   chunks go to a last-in-first-out free list, new chunks come from it first
 *   (so the arena stays as small as the most rays ever queued at once). An
 *   enqueue writes a whole line, which the cache allocates without a fetch.
 *
 * Two hazards of interleaved workers, and how they are settled:
 * - An enqueue claims its slot (and writes the host record) before its
 *   accesses, so a core may take the queue and a worker reach the slot while
 *   the enqueuer still waits for its table load, before its store. The image
 *   cannot change (values come from the host record, complete at the claim),
 *   but the load would precede the store it reads: the slot is marked stored
 *   only once its store is issued, and a worker that reaches an unstored slot
 *   waits for it, so every queued ray is loaded after its store.
 * - Work on a ray may suspend, and meanwhile other workers hand out and finish
 *   the rest of its chunk: a chunk is freed (and may be reused by any enqueue)
 *   only when the last ray handed out from it is done (chunk_refs), so the
 *   writes a blocked leaf pass makes into a ray's slot after its accesses (its
 *   best hit, or its end) always land in the ray's own record. */
#include "renderer/policy_impl.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "renderer/camera.h"
#include "renderer/framebuffer.h"
#include "renderer/kdtree.h"
#include "renderer/policy.h"
#include "renderer/qpoint.h"
#include "renderer/scene.h"
#include "renderer/shade.h"
#include "renderer/trace.h"
#include "renderer/trav.h"
#include "sim/err.h"

#define DYN_CHUNK_RAYS 64u
#define DYN_NONE UINT32_MAX
/* A worker that keeps finding nothing to take doubles its wait, up to
 * 2^DYN_WAIT_DOUBLINGS x dyn_wait_cycles (dyn_step). Measured against a fixed
 * wait (tiny and default configs, small grove and room at 64x48): cycles
 * within 0.1%, 3% on default/grove; 11x to 43x fewer waits, and a 64 x 8 x 8
 * machine on a 6x4 image in 1.2 s instead of 13. 3 doublings: cycles within
 * 0.4% but 6x the waits of 6; 9: 8% more cycles on default/grove. */
#define DYN_WAIT_DOUBLINGS 6u
/* Host-only mark of a ray that ended during a blocked pass (never simulated). */
#define DYN_FLAG_DEAD 0x80u

/* Traversal steps (trav_setup, trav_interior, trav_announce_*) come from
 * renderer/trav.h, shared with trace.c: the same arithmetic gives the same hits. */

/* ---- policy state ---------------------------------------------------------- */

struct dyn_queue {
  uint32_t head, tail;  /* chunks, DYN_NONE when empty */
  uint32_t tail_fill;   /* rays in the tail chunk */
  uint32_t count;       /* rays queued */
  int64_t heap_pos;     /* position in the heap, -1 when not in it */
  bool held;            /* a drain has what was queued here (the queue is not in the heap) */
};

struct ray_buf {
  struct ray *r;
  uint64_t n, cap;
};

/* Step a cursor over a detached queue's slots, newest first: the tail chunk
 * from its last ray down, then each earlier chunk from its last slot down. The
 * newest rays are the likeliest to be still in the cache, so they are read
 * before the queue's own work evicts them. */
struct slot_cur {
  uint32_t c, i;
  uint64_t left; /* slots from here to the end of the queue */
};

/* A queue point being drained: the rays detached from its queue, handed out
 * pass by pass (a leaf over g_max takes one pass per block of geometry; any
 * other queue point one pass) to the workers of the core that took it and of
 * any cores that joined it. Drain c is the one core c took (at most one a
 * core: so at most `cores` queue points are drained at once). */
struct dyn_drain {
  uint32_t qi;             /* queue held, DYN_NONE when none */
  uint32_t node;           /* its node */
  uint32_t block, blocks;  /* the pass (geometry block) and how many */
  struct slot_cur first;   /* the held rays' newest: each pass starts there */
  struct slot_cur k;       /* the next slot to hand out in this pass */
  uint32_t busy;           /* claims of this pass not yet done */
  uint32_t seq;            /* bumped by each pass: tells a claim of an earlier one */
  uint32_t take_seq;       /* bumped by each take: tells a core that joined an earlier one */
};

/* Where a core's workers take rays from: drain `drain` as of its take take_seq
 * (DYN_NONE: none). */
struct dyn_core {
  uint32_t drain, take_seq;
};

enum dyn_phase { DYN_ADMIT, DYN_CLOSEST, DYN_SHADOW };

/* The job's shared state: queue points, queues and their arena, the heap,
 * the primary rays' order, the batch and its phase, the cores' queue points. */
struct dyn {
  const struct trace_layout *l; /* the job's layout (queue and table addresses) */
  const struct kd_tree *kd;
  const struct scene *s;
  struct qpoint_set qs;
  uint32_t block_tris; /* triangles of an oversized leaf processed at once */
  uint32_t group;      /* rays a worker streams at once against such a block */
  uint64_t wait_cycles;
  /* Queues: the phase being drained (q, ordered by the heap), this
   * generation's shadow rays (qsh), the next generation (qn); and their chunk
   * arena. */
  struct dyn_queue *q, *qsh, *qn;
  struct ray *pool;      /* chunk c: pool[c * DYN_CHUNK_RAYS ...] */
  uint8_t *stored;       /* per slot: its enqueue has issued its store */
  uint32_t *chunk_next;  /* next chunk of the same queue, or of the free list */
  uint32_t *chunk_refs;  /* a draining cursor in it + its rays handed out, not done */
  uint32_t chunks, chunk_cap, free_head;
  /* Non-empty queues no core holds: a max-heap on (count, -index). */
  uint32_t *heap;
  uint32_t heap_n;
  uint32_t *order;  /* primary rays (work items) in Hilbert order */
  uint64_t batch;   /* primary rays a work item admits */
  /* The batch being traced: primary rays [lo, hi), the next to admit, the
   * admissions under way; its phase; the rays of the phase's queue set that
   * are queued or being traced (a phase ends when none are). */
  bool active;
  uint64_t lo, hi, admit_next, batch_seq;
  uint32_t admitting;
  enum dyn_phase phase;
  uint64_t pending;
  struct dyn_drain *drain; /* one a core */
  struct dyn_core *core;
  uint32_t cores;
  /* Rays spawned and terminated by all workers, for progress. */
  uint64_t spawned, terminated, progress_at;
};

/* The rays a worker took at once from a drain (slot indices, pool[slot]). */
struct dyn_claim {
  uint32_t drain, seq, node, j0, j1;
  bool leaf, last; /* last: the last pass, which lets the rays go on */
  uint32_t n;
  uint64_t *slot;  /* group entries */
};

/* A worker's own (its scratch): where its accesses and counts go, and the
 * rays its shading spawned, started once the ray that spawned them is done
 * (so each ray's cost is its own). */
struct dyn_worker {
  struct dyn *d;
  struct policy_job *job;
  struct policy_worker *wk;
  struct trace_ctx *tr;
  struct render_stats *st;
  struct ray_buf pend;
  struct dyn_claim cl;
};

/* One ray's traversal state: the scheduling traversal (for a shadow ray the
 * reversed segment), the canonical ray's test, the best hit so far. */
struct walk {
  struct trav_ray tv;
  struct trace_isect_ray ir;
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
  return isfinite(m) && trav_ray_valid(rv);
}

/* Recompute the hit a record carries (hit_prim) with its canonical ray: the
 * test is deterministic and its t does not depend on the range it is given,
 * so this is the very hit found earlier (t, b1, b2 bit for bit).
 * NOTE: not announced as a load: the host record has no room for t, where a
 * real one would carry it (the paper's rays have spare bytes). */
static void restore_hit(const struct dyn *d, const struct trace_isect_ray *ir, const struct ray *r,
                        struct trace_hit *h) {
  CHECK_GE(r->hit_prim, 0);
  CHECK_LT((uint32_t)r->hit_prim, d->s->tri_count);
  const struct scene_tri *tri = &d->s->tris[r->hit_prim];
  bool ok = trace_isect_tri(ir, tri->v[0], tri->v[1], tri->v[2], r->tmin, r->tmax, &h->t, &h->b1,
                            &h->b2);
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
  if (!trav_ray_valid(r) || kd->node_count == 0) return false;
  if (!trav_setup(&w->tv, kd, r)) return false;
  trace_isect_prepare(&w->ir, r->o, r->d);
  if (w->any) {
    struct ray rv;
    if (reversed(r, &rv) && !trav_setup(&w->tv, kd, &rv)) return false;
  } else if (r->hit_prim >= 0) {
    struct trace_hit h;
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
static bool walk_leaf(struct trace_ctx *tr, struct walk *w, struct kd_node nd, uint32_t j0,
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
static enum walk_end walk_run(const struct dyn *d, struct trace_ctx *tr, struct walk *w, int floor,
                              bool to_queue) {
  for (;;) {
    trav_announce_node(tr, w->ni, 1);
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
static void walk_to(const struct dyn *d, struct trace_ctx *tr, struct walk *w, uint32_t q) {
  while (w->ni != q) {
    trav_announce_node(tr, w->ni, 1);
    struct kd_node nd = d->qs.nodes[w->ni];
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

/* After a queue point's subtree: on to the next queue point, or the end. */
static enum walk_end walk_leave(const struct dyn *d, struct trace_ctx *tr, struct walk *w) {
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

/* Put queue qi (not held, not empty) into the heap, or move it up after its
 * count grew. */
static void heap_offer(struct dyn *d, uint32_t qi) {
  struct dyn_queue *q = &d->q[qi];
  if (q->heap_pos < 0) {
    d->heap[d->heap_n] = qi;
    q->heap_pos = d->heap_n++;
  }
  heap_up(d, (uint32_t)q->heap_pos);
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
      d->stored = xrealloc(d->stored, (uint64_t)d->chunk_cap * DYN_CHUNK_RAYS);
      d->chunk_next = xrealloc(d->chunk_next, (uint64_t)d->chunk_cap * sizeof *d->chunk_next);
      d->chunk_refs = xrealloc(d->chunk_refs, (uint64_t)d->chunk_cap * sizeof *d->chunk_refs);
    }
    c = d->chunks++;
  }
  d->chunk_next[c] = DYN_NONE;
  d->chunk_refs[c] = 0;
  return c;
}

/* Chunk c is wanted by one more (a draining cursor in it, or a ray handed out
 * from it), or one less: freed at none. Only the last pass over a held queue
 * counts (it frees the chunks behind it); earlier passes keep them all. */
static void chunk_hold(struct dyn *d, uint32_t c) { d->chunk_refs[c]++; }

static void chunk_drop(struct dyn *d, uint32_t c) {
  CHECK_GT(d->chunk_refs[c], 0);
  if (--d->chunk_refs[c] > 0) return;
  d->chunk_next[c] = d->free_head;
  d->free_head = c;
}

static uint64_t slot_addr(const struct dyn *d, uint64_t slot) {
  return d->l->queue_base + slot * sizeof(struct ray);
}

static uint64_t table_addr(const struct dyn *d, uint32_t qi) {
  return d->l->qtable_base + 8ull * qi;
}

/* Append r to queue qi of queue set qset (d->q, d->qsh or d->qn): the table
 * entry is loaded, the ray stored in its slot, the entry stored. The slot is
 * claimed (counts, host copy, heap) before the first access, as any of them
 * may suspend this worker and the next enqueue must find the slot taken; it is
 * marked stored once its store is issued (see the hazards above). */
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
  const uint64_t slot = (uint64_t)q->tail * DYN_CHUNK_RAYS + q->tail_fill;
  d->pool[slot] = *r;
  d->stored[slot] = 0;
  q->tail_fill++;
  q->count++;
  if (qset == d->q) { /* the phase being drained: its heap and its count */
    d->pending++;
    if (!q->held) heap_offer(d, qi);
  }
  mem_load(mem, table_addr(d, qi), 8, TRACE_CLASS_QUEUE);
  mem_store(mem, slot_addr(d, slot), sizeof *r, TRACE_CLASS_RAY);
  d->stored[slot] = 1;
  mem_store(mem, table_addr(d, qi), 8, TRACE_CLASS_QUEUE);
}

/* ---- ray ends ---------------------------------------------------------------- */

/* Progress: rays terminated of rays spawned so far, by all workers. */
static void progress(struct dyn_worker *x) {
  struct dyn *d = x->d;
  const struct policy_setup *s = &x->job->setup;
  if (s->progress && d->terminated >= d->progress_at && d->terminated < d->spawned) {
    s->progress(s->progress_ctx, d->terminated, d->spawned);
    d->progress_at = d->terminated + (1u << 16);
  }
}

/* A ray ends: a shadow ray adds its light, any other is shaded now (its hit
 * is the walk's best; a miss has t = tmax, as trace_closest gives it) and its
 * children wait in pend until this ray's work is counted. */
static void terminate(struct dyn_worker *x, struct ray *r, const struct walk *w, enum walk_end e) {
  const struct policy_setup *s = &x->job->setup;
  x->st->rays[r->type]++;
  x->st->terminated++;
  x->d->terminated++;
  if (r->type == RAY_SHADOW) {
    shade_shadow(r, e == WALK_HIT, s->fb, &x->tr->mem);
  } else {
    struct trace_hit h;
    trav_best_hit(&w->best, &h);
    r->hit_prim = -1;
    struct ray spawn[SHADE_MAX_SPAWN];
    uint32_t n = shade_hit(s->sc, r, &h, s->fb, &x->tr->mem, spawn);
    x->st->spawned += n;
    x->d->spawned += n;
    for (uint32_t k = 0; k < n; k++) buf_push(&x->pend, &spawn[k]);
  }
  progress(x);
}

/* Where a ray goes after a walk: a queue of set qset, or its end. */
static void route(struct dyn_worker *x, struct ray *r, const struct walk *w, enum walk_end e,
                  struct dyn_queue *qset) {
  if (e == WALK_QUEUED) {
    int64_t qi = qpoint_index(&x->d->qs, w->ni);
    CHECK_GE(qi, 0);
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
  struct trace_ctx *tr = x->tr;
  uint64_t n0 = tr->stats.node_visits, t0 = tr->stats.tri_tests;
  struct walk w;
  struct dyn_queue *qset = r->type == RAY_PRIMARY ? d->q : r->type == RAY_SHADOW ? d->qsh : d->qn;
  if (!walk_init(d, &w, r)) {
    terminate(x, r, &w, WALK_DONE);
  } else {
    struct trace_ctx quiet = *tr;
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
  struct trace_ctx *tr = x->tr;
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
static void preload_leaf(struct trace_ctx *tr, struct kd_node nd, uint32_t j0, uint32_t j1) {
  uint32_t off = kd_leaf_offset(nd);
  for (uint32_t j = j0; j < j1; j++) {
    uint32_t p = trav_leaf_prim(tr, off + j);
    mem_load(&tr->mem, tr->layout.tri_base + (uint64_t)tr->layout.tri_bytes * p, tr->layout.tri_bytes,
             TRACE_CLASS_GEOMETRY);
  }
}

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

/* Advance. In a releasing pass (the last over a held queue) the cursor holds
 * the chunk it is in and lets it go when it leaves (chunk_drop). */
static void cur_next(struct dyn *d, struct slot_cur *k, bool release) {
  k->left--;
  if (k->i == 0 || k->left == 0) {
    const uint32_t c = k->c;
    k->c = d->chunk_next[c];
    k->i = DYN_CHUNK_RAYS - 1;
    if (release) {
      if (k->left > 0) chunk_hold(d, k->c);
      chunk_drop(d, c);
    }
  } else {
    k->i--;
  }
}

/* Entries [*j0, *j1) of leaf nd that pass `block` tests. */
static void block_range(const struct dyn *d, struct kd_node nd, uint32_t block, uint32_t *j0,
                        uint32_t *j1) {
  const uint32_t cnt = kd_leaf_count(nd), bt = d->block_tris;
  *j0 = block * bt;
  *j1 = cnt - *j0 > bt ? *j0 + bt : cnt;
}

/* Start pass `block` over the rays of drain dr: from the newest again. */
static void pass_begin(struct dyn *d, struct dyn_drain *dr, uint32_t block) {
  dr->block = block;
  dr->k = dr->first;
  dr->busy = 0;
  dr->seq++;
  if (block + 1 == dr->blocks) chunk_hold(d, dr->k.c); /* the last pass frees behind it */
}

static bool pass_last(const struct dyn_drain *dr) { return dr->block + 1 == dr->blocks; }

/* The drain x's core takes rays from, or NULL: a drain it joined is left
 * once it is over (let go, or taken again by its core). */
static struct dyn_drain *core_drain(struct dyn *d, uint32_t core) {
  struct dyn_core *co = &d->core[core];
  if (co->drain == DYN_NONE) return NULL;
  struct dyn_drain *dr = &d->drain[co->drain];
  if (dr->qi != DYN_NONE && dr->take_seq == co->take_seq) return dr;
  co->drain = DYN_NONE;
  return NULL;
}

static void core_join(struct dyn *d, uint32_t core, uint32_t drain) {
  d->core[core].drain = drain;
  d->core[core].take_seq = d->drain[drain].take_seq;
}

/* x's core takes the fullest queue no core holds into its drain: its rays are
 * detached (rays that arrive meanwhile start a new list, which goes back to
 * the heap when the drain lets go; no ray comes back to a queue point it has
 * left, since a traversal visits a node once), then its table entry is read
 * and written, and at a leaf the first block of geometry is loaded (it will
 * all be tested). The core's workers hand out the rays meanwhile. */
static void take(struct dyn_worker *x) {
  struct dyn *d = x->d;
  const uint32_t core = x->wk->core;
  struct dyn_drain *dr = &d->drain[core];
  CHECK_EQ(dr->qi, DYN_NONE);
  const uint32_t qi = heap_pop(d);
  struct dyn_queue *q = &d->q[qi];
  q->held = true;
  dr->qi = qi;
  dr->node = d->qs.qnode[qi];
  dr->take_seq++;
  dr->first = cur_newest(d, q->head, q->tail_fill, q->count);
  q->head = q->tail = DYN_NONE;
  q->tail_fill = q->count = 0;
  const struct kd_node nd = d->qs.nodes[dr->node];
  const uint32_t cnt = kd_is_leaf(nd) ? kd_leaf_count(nd) : 0;
  dr->blocks = cnt == 0 ? 1 : (cnt + d->block_tris - 1) / d->block_tris;
  pass_begin(d, dr, 0);
  core_join(d, core, core);
  const struct mem_port *mem = &x->tr->mem;
  mem_load(mem, table_addr(d, qi), 8, TRACE_CLASS_QUEUE);
  mem_store(mem, table_addr(d, qi), 8, TRACE_CLASS_QUEUE);
  if (kd_is_leaf(nd)) {
    uint32_t j0, j1;
    block_range(d, nd, 0, &j0, &j1);
    preload_leaf(x->tr, nd, j0, j1);
  }
}

/* Every ray of the pass is handed out and done: start the next pass (the next
 * block of an oversized leaf's geometry, loaded at once). */
static void next_pass(struct dyn_worker *x, struct dyn_drain *dr) {
  struct dyn *d = x->d;
  pass_begin(d, dr, dr->block + 1);
  const struct kd_node nd = d->qs.nodes[dr->node];
  uint32_t j0, j1;
  block_range(d, nd, dr->block, &j0, &j1);
  preload_leaf(x->tr, nd, j0, j1);
}

/* Drain dr's rays are all handed out (their last pass): let the queue point
 * go, back into the heap if rays arrived meanwhile. The cores that take part
 * in it notice (core_drain). */
static void release(struct dyn *d, struct dyn_drain *dr) {
  struct dyn_queue *q = &d->q[dr->qi];
  q->held = false;
  if (q->count > 0) heap_offer(d, dr->qi);
  dr->qi = DYN_NONE;
}

/* A drain with rays to hand out in its current pass, the most of them (ties:
 * the lower core), or DYN_NONE: one that x's core, having nothing of its own
 * and no free queue to take, may join. Its queue point's geometry is resident
 * already, so joining asks nothing more of the L2. */
static uint32_t fullest_drain(const struct dyn *d) {
  uint32_t best = DYN_NONE;
  for (uint32_t c = 0; c < d->cores; c++) {
    const struct dyn_drain *dr = &d->drain[c];
    if (dr->qi != DYN_NONE && dr->k.left > 0 && (best == DYN_NONE || dr->k.left > d->drain[best].k.left))
      best = c;
  }
  return best;
}

/* Hand the next rays of drain dr's pass to x: a group at a leaf (loaded,
 * tested and stored back together), one ray at an interior queue point. */
static void claim(struct dyn_worker *x, struct dyn_drain *dr) {
  struct dyn *d = x->d;
  struct dyn_claim *cl = &x->cl;
  const struct kd_node nd = d->qs.nodes[dr->node];
  cl->drain = (uint32_t)(dr - d->drain);
  cl->seq = dr->seq;
  cl->node = dr->node;
  cl->leaf = kd_is_leaf(nd);
  cl->last = pass_last(dr);
  cl->j0 = cl->j1 = 0;
  if (cl->leaf) block_range(d, nd, dr->block, &cl->j0, &cl->j1);
  const uint32_t n = cl->leaf ? d->group : 1;
  for (cl->n = 0; cl->n < n && dr->k.left > 0; cur_next(d, &dr->k, cl->last)) {
    if (cl->last) chunk_hold(d, dr->k.c);
    cl->slot[cl->n++] = cur_index(&dr->k);
  }
  dr->busy++;
}

/* x is done with its claim's slot t (a last pass frees behind it). */
static void slot_done(struct dyn_worker *x, uint32_t t) {
  if (x->cl.last) chunk_drop(x->d, (uint32_t)(x->cl.slot[t] / DYN_CHUNK_RAYS));
}

/* x is done with its claim: the pass may move on once all of its claims are. */
static void claim_done(struct dyn_worker *x) {
  struct dyn_drain *dr = &x->d->drain[x->cl.drain];
  if (dr->seq == x->cl.seq) {
    CHECK_GT(dr->busy, 0);
    dr->busy--;
  }
}

/* Wait until the ray in slot has been stored by its enqueue (the hazards
 * above). One worker never waits: its enqueues are over before it drains. */
static void wait_stored(struct dyn_worker *x, uint64_t slot) {
  while (!x->d->stored[slot]) {
    CHECK_GT(x->d->wait_cycles, 0);
    mem_wait(&x->tr->mem, x->d->wait_cycles);
  }
}

/* The claimed ray of an interior queue point: its subtree, then onward. */
static void trace_subtree_claim(struct dyn_worker *x) {
  struct dyn *d = x->d;
  const uint64_t slot = x->cl.slot[0];
  wait_stored(x, slot);
  struct ray r = d->pool[slot];
  mem_load(&x->tr->mem, slot_addr(d, slot), sizeof r, TRACE_CLASS_RAY);
  process_subtree(x, &r, x->cl.node);
  d->pending--;
  slot_done(x, 0);
}

/* The claimed rays of a leaf queue point against the pass's block of its
 * geometry (the whole leaf unless it exceeds g_max: the paper's "separate
 * scheduling problem"): each is loaded and tested; before the last pass it is
 * stored back with its best hit (or marked ended), after the last it goes on.
 * Every ray still tests all of the leaf's triangles, so its hit is the one a
 * single traversal finds (the hit rule does not depend on their order). */
static void trace_leaf_claim(struct dyn_worker *x) {
  struct dyn *d = x->d;
  struct trace_ctx *tr = x->tr;
  const struct mem_port *mem = &tr->mem;
  const struct dyn_claim *cl = &x->cl;
  const struct kd_node nd = d->qs.nodes[cl->node];
  for (uint32_t t = 0; t < cl->n; t++) {
    const uint64_t slot = cl->slot[t];
    if (d->pool[slot].flags & DYN_FLAG_DEAD) {
      slot_done(x, t);
      continue;
    }
    wait_stored(x, slot);
    struct ray r = d->pool[slot];
    uint64_t n0 = tr->stats.node_visits, t0 = tr->stats.tri_tests;
    mem_load(mem, slot_addr(d, slot), sizeof r, TRACE_CLASS_RAY);
    struct walk w;
    CHECK(walk_init(d, &w, &r));
    bool over = true;
    if (walk_leaf(tr, &w, nd, cl->j0, cl->j1)) {
      terminate(x, &r, &w, WALK_HIT);
      if (!cl->last) d->pool[slot].flags |= DYN_FLAG_DEAD; /* later passes skip it */
    } else if (!cl->last) {
      d->pool[slot].hit_prim = w.best.found ? (int32_t)w.best.p : -1;
      over = false;
    } else {
      walk_to(d, tr, &w, cl->node);
      route(x, &r, &w, walk_leave(d, tr, &w), d->q);
    }
    cost_add(x, r.pixel, n0, t0);
    flush(x);
    if (over) d->pending--;
    slot_done(x, t);
  }
  /* Store the group back with its best hits (the last pass moved them on). */
  for (uint32_t t = 0; !cl->last && t < cl->n; t++)
    if (!(d->pool[cl->slot[t]].flags & DYN_FLAG_DEAD))
      mem_store(mem, slot_addr(d, cl->slot[t]), sizeof(struct ray), TRACE_CLASS_RAY);
}

/* Admit the batch's next primary ray: read it, take it to its first queue. */
static bool admit(struct dyn_worker *x) {
  struct dyn *d = x->d;
  if (d->admit_next == d->hi) return false;
  const uint64_t k = d->admit_next++;
  d->admitting++;
  const uint32_t w = x->job->setup.fb->width;
  struct ray r;
  policy_primary(x->job, x->wk, d->order[k] % w, d->order[k] / w, &r);
  x->st->spawned++;
  d->spawned++;
  start(x, &r);
  flush(x);
  d->admitting--;
  return true;
}

/* Do one thing for the batch: admit a primary ray; trace rays of the drain
 * x's core takes part in; start its next pass; take the fullest free queue
 * point for the core; or join the drain with the most rays left. False when
 * there is nothing to do now. */
static bool work(struct dyn_worker *x) {
  struct dyn *d = x->d;
  if (d->phase == DYN_ADMIT) return admit(x);
  const uint32_t core = x->wk->core;
  struct dyn_drain *dr = core_drain(d, core);
  if (dr && dr->k.left == 0) { /* this pass is all handed out */
    if (!pass_last(dr)) {
      if (dr->busy == 0) {
        next_pass(x, dr);
        return true;
      }
      /* Its last rays are still being tested: the core that took it waits for
       * them (and starts the next pass); a core that joined looks elsewhere. */
      if (dr == &d->drain[core]) return false;
    } else {
      release(d, dr); /* whichever core sees it first lets it go */
    }
    d->core[core].drain = DYN_NONE;
    dr = NULL;
  }
  if (!dr) {
    if (d->heap_n > 0 && d->drain[core].qi == DYN_NONE) {
      take(x);
      return true;
    }
    const uint32_t j = fullest_drain(d);
    if (j == DYN_NONE) return false;
    core_join(d, core, j);
    dr = &d->drain[j];
  }
  claim(x, dr);
  if (x->cl.leaf)
    trace_leaf_claim(x);
  else
    trace_subtree_claim(x);
  claim_done(x);
  return true;
}

/* ---- phases and generations ------------------------------------------------- */

/* The phase is over: its primary rays are all admitted, or no ray of its queue
 * set is queued or being traced and no core has a pass left over its queue
 * point (passes go on over rays that all ended, as one worker's loop did). */
static bool phase_over(const struct dyn *d) {
  if (d->phase == DYN_ADMIT) return d->admit_next == d->hi && d->admitting == 0;
  if (d->pending > 0 || d->heap_n > 0) return false;
  for (uint32_t c = 0; c < d->cores; c++) {
    const struct dyn_drain *dr = &d->drain[c];
    if (dr->qi != DYN_NONE && (dr->k.left > 0 || !pass_last(dr))) return false;
  }
  return true;
}

/* Make queue set *other the one being drained (the drained set, empty now,
 * takes its place): the cores let their queue points go, and the set's
 * non-empty queues are ordered in the heap. */
static void activate(struct dyn *d, struct dyn_queue **other) {
  CHECK_EQ(d->heap_n, 0);
  CHECK_EQ(d->pending, 0);
  for (uint32_t c = 0; c < d->cores; c++) {
    struct dyn_drain *dr = &d->drain[c];
    d->core[c].drain = DYN_NONE;
    if (dr->qi == DYN_NONE) continue;
    CHECK_EQ(d->q[dr->qi].count, 0);
    release(d, dr);
  }
  struct dyn_queue *t = d->q;
  d->q = *other;
  *other = t;
  for (uint32_t i = 0; i < d->qs.count; i++)
    if (d->q[i].count > 0) {
      heap_offer(d, i);
      d->pending += d->q[i].count;
    }
}

/* Start the phase after the one that is over: closest hits, their shadow rays,
 * the next generation's closest hits; skip those without rays. True when
 * there is none: the batch is done. */
static bool advance(struct dyn *d) {
  for (;;) {
    switch (d->phase) {
    case DYN_ADMIT: d->phase = DYN_CLOSEST; break;
    case DYN_CLOSEST:
      activate(d, &d->qsh);
      d->phase = DYN_SHADOW;
      break;
    case DYN_SHADOW:
      activate(d, &d->qn);
      d->phase = DYN_CLOSEST;
      if (d->heap_n == 0) return true; /* no next generation */
      break;
    }
    if (!phase_over(d)) return false;
  }
}

/* ---- the module --------------------------------------------------------------- */

static uint32_t clamp_u32(uint64_t v) { return v == 0 ? 1 : (v > UINT32_MAX ? UINT32_MAX : (uint32_t)v); }

void policy_dynamic_plan(const struct policy_params *p, uint32_t workers, uint32_t cores,
                         const struct kd_tree *kd, uint32_t tri_bytes, struct qpoint_set *qs,
                         struct qpoint_budget *b, uint32_t *block_tris, uint32_t *group) {
  CHECK_GE(workers, 1);
  CHECK_GE(cores, 1);
  CHECK_LE(cores, workers);
  CHECK_GT(tri_bytes, 0);
  uint32_t *tris = xmalloc((uint64_t)kd->node_count * sizeof *tris + 1);
  qpoint_subtree_tris(kd, tris);
  const uint64_t rays = p->dyn_ray_buffer_bytes ? p->dyn_ray_buffer_bytes
                                                : (uint64_t)workers * sizeof(struct ray);
  struct qpoint_reserve res = {p->cache_bytes, p->dyn_node_share, p->dyn_table_share,
                               p->dyn_ray_share, rays, cores};
  qpoint_plan(qs, b, kd, tris, tri_bytes, &res);
  free(tris);
  *block_tris = clamp_u32(b->gmax_bytes / tri_bytes);
  *group = clamp_u32(b->ray_bytes / sizeof(struct ray) / workers);
}

static void dyn_create(struct policy_job *job) {
  const struct policy_params *p = &job->params;
  struct dyn *d = xcalloc(1, sizeof *d);
  d->l = &job->setup.layout;
  d->kd = job->setup.kd;
  d->s = job->setup.scene;
  d->free_head = DYN_NONE;
  d->wait_cycles = p->dyn_wait_cycles;

  /* Queue points for the cache and the machine (policy.h). */
  struct qpoint_budget bud;
  policy_dynamic_plan(p, job->workers, job->cores, d->kd, d->l->tri_bytes, &d->qs, &bud,
                      &d->block_tris, &d->group);
  d->q = xmalloc((uint64_t)d->qs.count * sizeof *d->q + 1);
  d->qsh = xmalloc((uint64_t)d->qs.count * sizeof *d->qsh + 1);
  d->qn = xmalloc((uint64_t)d->qs.count * sizeof *d->qn + 1);
  for (uint32_t i = 0; i < d->qs.count; i++) {
    d->q[i].head = d->q[i].tail = DYN_NONE;
    d->q[i].tail_fill = d->q[i].count = 0;
    d->q[i].heap_pos = -1;
    d->q[i].held = false;
    d->qsh[i] = d->qn[i] = d->q[i];
  }
  d->heap = xmalloc((uint64_t)d->qs.count * sizeof *d->heap + 1);
  d->cores = job->cores;
  d->drain = xcalloc(d->cores, sizeof *d->drain);
  d->core = xcalloc(d->cores, sizeof *d->core);
  for (uint32_t c = 0; c < d->cores; c++) d->drain[c].qi = d->core[c].drain = DYN_NONE;

  /* The work items: primary rays in Hilbert order, admitted a batch at a time. */
  const uint32_t w = job->setup.fb->width, h = job->setup.fb->height;
  job->total = (uint64_t)w * h;
  job->progress_every = 0; /* progress counts rays (progress()) */
  d->order = xmalloc(job->total * sizeof *d->order + 1);
  camera_hilbert_order(w, h, d->order);
  d->batch = p->dyn_batch_rays ? p->dyn_batch_rays : job->total;
  d->phase = DYN_CLOSEST;
  job->shared = d;
}

static void dyn_destroy(struct policy_job *job) {
  struct dyn *d = job->shared;
  if (!d) return;
  free(d->order);
  free(d->heap);
  free(d->drain);
  free(d->core);
  free(d->q);
  free(d->qsh);
  free(d->qn);
  free(d->pool);
  free(d->stored);
  free(d->chunk_next);
  free(d->chunk_refs);
  qpoint_fini(&d->qs);
  free(d);
}

static void dyn_scratch_free(void *scratch) {
  struct dyn_worker *x = scratch;
  if (!x) return;
  free(x->pend.r);
  free(x->cl.slot);
  free(x);
}

/* The batch is done: count its primary rays as work items done. */
static void batch_end(struct policy_job *job, struct dyn *d) {
  d->active = false;
  d->batch_seq++;
  policy_job_done(job, d->hi - d->lo);
  const struct policy_setup *s = &job->setup;
  if (job->done == job->total && s->progress)
    s->progress(s->progress_ctx, d->terminated, d->terminated);
}

/* Take part in a batch of primary rays until it is done: the first worker to
 * find none under way claims the next (before any access), every worker then
 * does what work() finds, starts the next phase when it finds the phase over,
 * and otherwise waits (longer each time in a row: DYN_WAIT_DOUBLINGS). One
 * worker does the whole batch in the order the single loop did: each primary
 * ray to its first queue, then every generation: closest-hit rays, their
 * shadow rays, the next generation. */
static bool dyn_step(struct policy_job *job, struct policy_worker *wk) {
  struct dyn *d = job->shared;
  if (!d->active) {
    uint64_t k0, n = policy_job_claim(job, d->batch, &k0);
    if (n == 0) return false;
    CHECK_EQ(d->pending, 0);
    CHECK_EQ(d->heap_n, 0);
    d->active = true;
    d->lo = d->admit_next = k0;
    d->hi = k0 + n;
    d->admitting = 0;
    d->phase = DYN_ADMIT;
  }
  if (!wk->scratch) {
    struct dyn_worker *nx = xcalloc(1, sizeof *nx);
    nx->cl.slot = xmalloc((uint64_t)d->group * sizeof *nx->cl.slot);
    wk->scratch = nx;
  }
  struct dyn_worker *x = wk->scratch;
  x->d = d;
  x->job = job;
  x->wk = wk;
  x->tr = &wk->tr;
  x->st = &wk->st;
  const uint64_t seq = d->batch_seq;
  uint32_t idle = 0; /* waits in a row */
  while (d->batch_seq == seq) {
    if (work(x)) {
      idle = 0;
      continue;
    }
    if (phase_over(d)) {
      if (advance(d)) batch_end(job, d);
      continue;
    }
    /* Others are still tracing rays of this phase (or testing the last rays
     * of this core's pass): their rays may make work for this one. */
    CHECK_GT(d->wait_cycles, 0);
    mem_wait(&x->tr->mem, d->wait_cycles << idle);
    if (idle < DYN_WAIT_DOUBLINGS) idle++;
  }
  return true;
}

/* Every queue empty, every chunk free; the queue arena at its largest: the
 * rays in flight. */
static void dyn_finish(struct policy_job *job, struct render_stats *st) {
  const struct dyn *d = job->shared;
  CHECK(!d->active);
  CHECK_EQ(d->heap_n, 0);
  CHECK_EQ(d->pending, 0);
  for (uint32_t i = 0; i < d->qs.count; i++) {
    CHECK_EQ(d->q[i].count, 0);
    CHECK_EQ(d->qsh[i].count, 0);
    CHECK_EQ(d->qn[i].count, 0);
    CHECK(!d->q[i].held);
  }
  for (uint32_t c = 0; c < d->cores; c++) CHECK_EQ(d->drain[c].qi, DYN_NONE);
  uint32_t free_chunks = 0;
  for (uint32_t c = d->free_head; c != DYN_NONE; c = d->chunk_next[c]) {
    CHECK_EQ(d->chunk_refs[c], 0);
    free_chunks++;
  }
  CHECK_EQ(free_chunks, d->chunks);
  st->ray_slots_max += (uint64_t)d->chunks * DYN_CHUNK_RAYS;
}

const struct policy_module policy_dynamic_module = {
    .region_bytes = 0, /* its rays wait in the queues, at queue_base */
    .max_workers = 0,  /* any: a core's workers share its queue point */
    .create = dyn_create,
    .destroy = dyn_destroy,
    .step = dyn_step,
    .scratch_free = dyn_scratch_free,
    .finish = dyn_finish,
};
