/* The multi-core drain (qdrain.h): drains, passes, claims, and cores joining
 * one another's drains. */
#include "renderer/policy/qdrain.h"

#include <stdlib.h>

#include "renderer/bvh.h"
#include "renderer/kdtree.h"
#include "renderer/policy/qpoint.h"
#include "renderer/trace.h"
#include "renderer/trav.h"
#include "sim/err.h"

void qdrain_init(struct qdrain_set *ds, struct qstore *st, const struct qpoint_set *qs,
                 uint32_t cores, uint32_t block_tris, uint32_t group) {
  CHECK_GE(cores, 1);
  CHECK_GE(block_tris, 1);
  CHECK_GE(group, 1);
  ds->st = st;
  ds->qs = qs;
  ds->block_tris = block_tris;
  ds->group = group;
  ds->cores = cores;
  ds->drain = xcalloc(cores, sizeof *ds->drain);
  ds->core = xcalloc(cores, sizeof *ds->core);
  ds->hand = xcalloc(cores, sizeof *ds->hand);
  ds->hand_at = xcalloc(cores, sizeof *ds->hand_at);
  ds->nhand = 0;
  for (uint32_t c = 0; c < cores; c++) ds->drain[c].qi = ds->core[c].drain = QSTORE_NONE;
}

void qdrain_share_chip(struct qdrain_set *ds, uint64_t feed) {
  ds->chip = true;
  ds->feed = feed ? feed : 1;
}

void qdrain_fini(struct qdrain_set *ds) {
  free(ds->drain);
  free(ds->core);
  free(ds->hand);
  free(ds->hand_at);
  ds->drain = NULL;
  ds->core = NULL;
  ds->hand = ds->hand_at = NULL;
}

void qdrain_claim_init(const struct qdrain_set *ds, struct qdrain_claim *cl) {
  *cl = (struct qdrain_claim){0};
  cl->slot = xmalloc((uint64_t)ds->group * sizeof *cl->slot);
}

void qdrain_claim_fini(struct qdrain_claim *cl) {
  free(cl->slot);
  free(cl->pixels);
  cl->slot = NULL;
  cl->pixels = NULL;
}

/* What tr does next (drain dr's table entry, a block of its geometry) is
 * shared by all the queue's rays: tell it their pixels, kept in cl until the
 * work is done (qdrain_attribute_end). */
static void attribute_begin(const struct qdrain_set *ds, const struct qdrain *dr,
                            struct trace_ctx *tr, struct qdrain_claim *cl) {
  if (!tr->attribute) return;
  struct qstore_cur k = dr->first;
  const uint64_t n = k.left;
  CHECK_GT(n, 0);
  CHECK_LE(n, UINT32_MAX);
  if (n > cl->pixels_cap) {
    cl->pixels_cap = n;
    cl->pixels = xrealloc(cl->pixels, n * sizeof *cl->pixels);
  }
  for (uint64_t i = 0; i < n; i++) {
    cl->pixels[i] = qstore_ray(ds->st, qstore_cur_slot(&k))->pixel;
    if (i + 1 < n) qstore_cur_next(ds->st, &k, false);
  }
  trace_attribute(tr, cl->pixels, (uint32_t)n);
}

/* The shared work is done: its cost is split now (the worker may park next). */
static void attribute_end(struct trace_ctx *tr) { trace_attribute(tr, NULL, 0); }

/* Load (announce) entries [j0, j1) of a leaf's geometry (its entries from
 * off), as the paper does on opening a queue at a leaf: it will all be
 * tested. */
static void preload_leaf(struct trace_ctx *tr, uint32_t off, uint32_t j0, uint32_t j1) {
  const uint32_t *prims = tr->bvh ? tr->bvh->prims : tr->kd->prims;
  for (uint32_t j = j0; j < j1; j++) {
    mem_load(&tr->mem, tr->layout.prim_idx_base + 4ull * (off + j), 4, TRACE_CLASS_NODE);
    const uint32_t p = prims[off + j];
    mem_load(&tr->mem, tr->layout.tri_base + (uint64_t)tr->layout.tri_bytes * p,
             tr->layout.tri_bytes, TRACE_CLASS_GEOMETRY);
  }
}

/* Entries [*j0, *j1) of a leaf of cnt triangles that pass `block` tests. */
static void block_range(const struct qdrain_set *ds, uint32_t cnt, uint32_t block, uint32_t *j0,
                        uint32_t *j1) {
  const uint32_t bt = ds->block_tris;
  *j0 = block * bt;
  *j1 = cnt - *j0 > bt ? *j0 + bt : cnt;
}

static bool pass_last(const struct qdrain *dr) { return dr->block + 1 == dr->blocks; }

/* Keep drain c's place in ds->hand true after its queue or its pass's rays
 * left changed. */
static void hand_update(struct qdrain_set *ds, uint32_t c) {
  const struct qdrain *dr = &ds->drain[c];
  const bool in = dr->qi != QSTORE_NONE && dr->k.left > 0;
  if (in == (ds->hand_at[c] != 0)) return;
  if (in) {
    ds->hand[ds->nhand++] = c;
    ds->hand_at[c] = ds->nhand;
  } else {
    const uint32_t i = ds->hand_at[c] - 1, last = ds->hand[--ds->nhand];
    ds->hand[i] = last;
    ds->hand_at[last] = i + 1;
    ds->hand_at[c] = 0;
  }
}

/* Start pass `block` over the rays of drain dr: from the newest again. */
static void pass_begin(struct qdrain_set *ds, struct qdrain *dr, uint32_t block) {
  dr->block = block;
  dr->k = dr->first;
  dr->busy = 0;
  dr->seq++;
  ds->handout += dr->k.left;
  if (pass_last(dr)) qstore_chunk_hold(ds->st, dr->k.c); /* the last pass frees behind it */
  hand_update(ds, (uint32_t)(dr - ds->drain));
}

/* The drain core's workers take rays from, or NULL: a drain it joined is left
 * once it is over (let go, or taken again by its core). */
static struct qdrain *core_drain(struct qdrain_set *ds, uint32_t core) {
  struct qdrain_core *co = &ds->core[core];
  if (co->drain == QSTORE_NONE) return NULL;
  struct qdrain *dr = &ds->drain[co->drain];
  if (dr->qi != QSTORE_NONE && dr->take_seq == co->take_seq) return dr;
  co->drain = QSTORE_NONE;
  return NULL;
}

static void core_join(struct qdrain_set *ds, uint32_t core, uint32_t drain) {
  ds->core[core].drain = drain;
  ds->core[core].take_seq = ds->drain[drain].take_seq;
}

/* A drain with rays to hand out in its current pass, the most of them (ties:
 * the lower core), or QSTORE_NONE: one that a core, having nothing of its own
 * and no free queue to take, may join. Its queue point's geometry is resident
 * already, so joining asks nothing more of the L2. */
static uint32_t fullest_drain(const struct qdrain_set *ds) {
  uint32_t best = QSTORE_NONE;
  for (uint32_t i = 0; i < ds->nhand; i++) {
    const uint32_t c = ds->hand[i];
    const uint64_t left = ds->drain[c].k.left;
    if (best == QSTORE_NONE || left > ds->drain[best].k.left ||
        (left == ds->drain[best].k.left && c < best))
      best = c;
  }
  return best;
}

/* core takes the fullest queue no core holds into its drain: its rays are
 * detached (rays that arrive meanwhile start a new list, which goes back to
 * the heap when the drain lets go; no ray comes back to a queue point it has
 * left, since a traversal visits a node once), then its table entry is read
 * and written, and at a leaf the first block of geometry is loaded. The
 * core's workers hand out the rays meanwhile. */
static void take(struct qdrain_set *ds, uint32_t core, struct trace_ctx *tr,
                 struct qdrain_claim *cl) {
  struct qdrain *dr = &ds->drain[core];
  CHECK_EQ(dr->qi, QSTORE_NONE);
  const uint32_t qi = qstore_take(ds->st, &dr->first);
  dr->qi = qi;
  dr->node = ds->qs->qnode[qi];
  dr->take_seq++;
  uint32_t off = 0, cnt = 0;
  const bool leaf = qpoint_leaf(ds->qs, dr->node, &off, &cnt);
  dr->blocks = cnt == 0 ? 1 : (cnt + ds->block_tris - 1) / ds->block_tris;
  pass_begin(ds, dr, 0);
  ds->open++;
  core_join(ds, core, core);
  attribute_begin(ds, dr, tr, cl);
  qstore_touch(ds->st, &tr->mem, qi);
  if (leaf) {
    uint32_t j0, j1;
    block_range(ds, cnt, 0, &j0, &j1);
    preload_leaf(tr, off, j0, j1);
  }
  attribute_end(tr);
}

/* Every ray of the pass is handed out and done: start the next pass (the next
 * block of an oversized leaf's geometry, loaded at once). */
static void next_pass(struct qdrain_set *ds, struct qdrain *dr, struct trace_ctx *tr,
                      struct qdrain_claim *cl) {
  pass_begin(ds, dr, dr->block + 1);
  uint32_t off, cnt, j0, j1;
  CHECK(qpoint_leaf(ds->qs, dr->node, &off, &cnt));
  block_range(ds, cnt, dr->block, &j0, &j1);
  attribute_begin(ds, dr, tr, cl);
  preload_leaf(tr, off, j0, j1);
  attribute_end(tr);
}

/* Drain dr's rays are all handed out (their last pass): let the queue point
 * go, back into the heap if rays arrived meanwhile. The cores that take part
 * in it notice (core_drain). */
static void release(struct qdrain_set *ds, struct qdrain *dr) {
  qstore_release(ds->st, dr->qi);
  dr->qi = QSTORE_NONE;
  hand_update(ds, (uint32_t)(dr - ds->drain));
}

/* Hand the next rays of drain dr's pass to cl: a group at a leaf (loaded,
 * tested and stored back together), one ray at an interior queue point. */
static void claim(struct qdrain_set *ds, struct qdrain *dr, struct qdrain_claim *cl) {
  uint32_t off, cnt;
  cl->drain = (uint32_t)(dr - ds->drain);
  cl->seq = dr->seq;
  cl->node = dr->node;
  cl->leaf = qpoint_leaf(ds->qs, dr->node, &off, &cnt);
  cl->last = pass_last(dr);
  cl->j0 = cl->j1 = 0;
  if (cl->leaf) block_range(ds, cnt, dr->block, &cl->j0, &cl->j1);
  const uint32_t n = cl->leaf ? ds->group : 1;
  for (cl->n = 0; cl->n < n && dr->k.left > 0; qstore_cur_next(ds->st, &dr->k, cl->last)) {
    if (cl->last) qstore_chunk_hold(ds->st, dr->k.c);
    cl->slot[cl->n++] = qstore_cur_slot(&dr->k);
  }
  ds->handout -= cl->n;
  if (dr->k.left == 0 && cl->last) ds->open--; /* all handed out, no pass after */
  dr->busy++;
  hand_update(ds, cl->drain);
}

enum qdrain_did qdrain_work(struct qdrain_set *ds, uint32_t core, struct trace_ctx *tr,
                            struct qdrain_claim *cl) {
  struct qdrain *dr = core_drain(ds, core);
  if (dr && dr->k.left == 0) { /* this pass is all handed out */
    if (!pass_last(dr)) {
      if (dr->busy == 0) {
        next_pass(ds, dr, tr, cl);
        return QDRAIN_STARTED;
      }
      /* Its last rays are still being tested: the core that took it waits for
       * them (and starts the next pass); a core that joined looks elsewhere. */
      if (dr == &ds->drain[core]) return QDRAIN_PASS_WAIT;
    } else {
      release(ds, dr); /* whichever core sees it first lets it go */
    }
    ds->core[core].drain = QSTORE_NONE;
    dr = NULL;
  }
  if (!dr) {
    if (qstore_any_free(ds->st) && ds->drain[core].qi == QSTORE_NONE &&
        (!ds->chip || ds->handout < ds->feed)) {
      take(ds, core, tr, cl);
      return QDRAIN_STARTED;
    }
    const uint32_t j = fullest_drain(ds);
    if (j == QSTORE_NONE) return QDRAIN_NOTHING;
    core_join(ds, core, j);
    dr = &ds->drain[j];
  }
  claim(ds, dr, cl);
  return QDRAIN_CLAIMED;
}

void qdrain_slot_done(struct qdrain_set *ds, const struct qdrain_claim *cl, uint32_t t) {
  if (cl->last) qstore_chunk_drop(ds->st, qstore_slot_chunk(cl->slot[t]));
}

bool qdrain_claim_done(struct qdrain_set *ds, const struct qdrain_claim *cl) {
  struct qdrain *dr = &ds->drain[cl->drain];
  if (dr->seq != cl->seq) return false;
  CHECK_GT(dr->busy, 0);
  dr->busy--;
  return dr->busy == 0 && dr->k.left == 0 && !pass_last(dr);
}

uint64_t qdrain_claims_left(struct qdrain_set *ds, uint32_t core) {
  const struct qdrain *dr = core_drain(ds, core);
  if (!dr) return 0;
  uint32_t off, cnt;
  if (!qpoint_leaf(ds->qs, dr->node, &off, &cnt)) return dr->k.left;
  return (dr->k.left + ds->group - 1) / ds->group;
}

/* Drains with rays to hand out or passes left, counted the slow way. */
static uint32_t count_open(const struct qdrain_set *ds) {
  uint32_t n = 0;
  for (uint32_t c = 0; c < ds->cores; c++) {
    const struct qdrain *dr = &ds->drain[c];
    n += dr->qi != QSTORE_NONE && (dr->k.left > 0 || !pass_last(dr));
  }
  return n;
}

bool qdrain_idle(const struct qdrain_set *ds) { return ds->open == 0; }

void qdrain_release_all(struct qdrain_set *ds) {
  CHECK_EQ(ds->open, count_open(ds)); /* once a phase: the count kept is the count */
  for (uint32_t c = 0; c < ds->cores; c++) {
    struct qdrain *dr = &ds->drain[c];
    ds->core[c].drain = QSTORE_NONE;
    if (dr->qi == QSTORE_NONE) continue;
    CHECK_EQ(qstore_count(ds->st, 0, dr->qi), 0);
    release(ds, dr);
  }
}

void qdrain_check_done(const struct qdrain_set *ds) {
  CHECK_EQ(ds->open, 0);
  CHECK_EQ(ds->nhand, 0);
  for (uint32_t c = 0; c < ds->cores; c++) CHECK_EQ(ds->drain[c].qi, QSTORE_NONE);
}
