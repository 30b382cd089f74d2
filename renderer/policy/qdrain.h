/* The multi-core drain: how the workers of a machine's cores share the queues
 * of a queue store's active set (qstore.h). A core takes one queue point at a
 * time, the fullest free queue, into its drain, and its workers hand out the
 * drain's rays among themselves: a ray at a time at an interior queue point, a
 * group of rays at a leaf (loaded, tested against a block of its geometry and
 * stored back together). A leaf whose geometry exceeds the block (the paper's
 * "separate scheduling problem") takes one pass over all its rays per block;
 * any other queue point one pass. When a drain's rays are all handed out its
 * core takes the next queue. A core that finds no free queue joins the drain
 * with the most rays left in its pass (its geometry is resident already), so a
 * scene with fewer queue points than cores (at the extreme, the root alone:
 * Whitted) still keeps every core busy. Drain c is the one core c took: at
 * most one a core, so at most `cores` queue points are drained at once. With
 * chip-wide sharing (qdrain_share_chip) a core joins the fullest drain first
 * and takes a queue of its own only when the drains cannot feed the contexts.
 *
 * Whoever traces a claim's rays (the policy) tells the drain when each ray and
 * the claim are done: a pass moves on once all its claims are, and a releasing
 * (last) pass frees chunks behind the rays (qstore_chunk_drop). With one
 * worker this is one loop: take the fullest queue, pass over its rays in
 * order, take the next. Private to renderer/. */
#ifndef RTSIM_RENDERER_POLICY_QDRAIN_H
#define RTSIM_RENDERER_POLICY_QDRAIN_H

#include <stdbool.h>
#include <stdint.h>

#include "renderer/policy/qstore.h"

struct qpoint_set;
struct trace_ctx;

/* A queue point being drained: the rays detached from its queue, handed out
 * pass by pass to the workers of the core that took it and of the cores that
 * joined it. */
struct qdrain {
  uint32_t qi;             /* queue held, QSTORE_NONE when none */
  uint32_t node;           /* its node */
  uint32_t block, blocks;  /* the pass (geometry block) and how many */
  struct qstore_cur first; /* the held rays' newest: each pass starts there */
  struct qstore_cur k;     /* the next slot to hand out in this pass */
  uint32_t busy;           /* claims of this pass not yet done */
  uint32_t seq;            /* bumped by each pass: tells a claim of an earlier one */
  uint32_t take_seq;       /* bumped by each take: tells a core that joined an earlier one */
};

/* Where a core's workers take rays from: drain `drain` as of its take
 * take_seq (QSTORE_NONE: none). */
struct qdrain_core {
  uint32_t drain, take_seq;
};

/* Caller-provided storage: qdrain_init, qdrain_fini. */
struct qdrain_set {
  struct qstore *st;           /* borrowed */
  const struct qpoint_set *qs; /* borrowed: queue i is at node qs->qnode[i] */
  uint32_t block_tris;         /* triangles of an oversized leaf processed at once */
  uint32_t group;              /* rays a worker takes at once at a leaf */
  uint32_t cores;
  struct qdrain *drain; /* one a core */
  struct qdrain_core *core;
  /* Chip-wide sharing (qdrain_share_chip): a core takes a free queue only
   * while the drains have fewer than feed rays left to hand out (handout). */
  bool chip;
  uint64_t feed, handout;
  /* Drains with rays to hand out or passes left (qdrain_idle: none), kept
   * as they change so that a worker about to park does not scan the cores. */
  uint32_t open;
  /* The drains with rays to hand out in their pass (qi held, k.left > 0),
   * in no order, and each drain's place there + 1 (0: not there): a core
   * looking for a drain to join reads these, not every core's. */
  uint32_t *hand, *hand_at, nhand;
};

/* The rays a worker took at once from a drain (slot indices: qstore_ray). */
struct qdrain_claim {
  uint32_t drain, seq, node, j0, j1; /* at a leaf: entries [j0, j1) of its geometry */
  bool leaf, last;                   /* last: the last pass, which lets the rays go on */
  uint32_t n;
  uint64_t *slot; /* group entries (qdrain_claim_init) */
  /* The pixels of the rays of a queue point its worker took or started a
   * pass of (trace_attribute: their shared work), grown as needed. */
  uint32_t *pixels;
  uint64_t pixels_cap;
};

void qdrain_init(struct qdrain_set *ds, struct qstore *st, const struct qpoint_set *qs,
                 uint32_t cores, uint32_t block_tris, uint32_t group);
void qdrain_fini(struct qdrain_set *ds);

/* Share the queues chip-wide instead of a queue point a core: a core with
 * nothing to do joins the fullest drain, and takes a free queue only while
 * all drains together have fewer than feed rays left to hand out in their
 * passes (feed: what the contexts take at once). */
void qdrain_share_chip(struct qdrain_set *ds, uint64_t feed);

void qdrain_claim_init(const struct qdrain_set *ds, struct qdrain_claim *cl);
void qdrain_claim_fini(struct qdrain_claim *cl);

/* What qdrain_work did. */
enum qdrain_did {
  QDRAIN_NOTHING,   /* nothing to do now for this core */
  QDRAIN_PASS_WAIT, /* nothing until the core's own pass is done (its last
                       claims are being traced: qdrain_claim_done says) */
  QDRAIN_STARTED,   /* took a queue or started a pass (accesses made, no rays
                       handed out yet: qdrain_claims_left) */
  QDRAIN_CLAIMED    /* *cl holds rays to trace, then qdrain_claim_done */
};

/* One scheduling step for a worker of `core` whose accesses go through tr:
 * start its drain's next pass once the last is done; else take the fullest
 * free queue for the core (its table entry is read and written, and at a leaf
 * the first block of geometry is loaded: it will all be tested); else join the
 * fullest drain; then claim rays from the core's drain. */
enum qdrain_did qdrain_work(struct qdrain_set *ds, uint32_t core, struct trace_ctx *tr,
                            struct qdrain_claim *cl);

/* The claim's ray t is done (a releasing pass frees behind it). */
void qdrain_slot_done(struct qdrain_set *ds, const struct qdrain_claim *cl, uint32_t t);
/* The claim is done: its pass may move on once all of its claims are. True
 * when that is now: the pass is handed out and done, and another follows
 * (its drain's core, cl->drain, may start it). */
bool qdrain_claim_done(struct qdrain_set *ds, const struct qdrain_claim *cl);

/* Claims the drain core's workers take from could still hand out: its rays
 * left in this pass, in groups at a leaf. 0 when the core has none. */
uint64_t qdrain_claims_left(struct qdrain_set *ds, uint32_t core);

/* No drain has rays to hand out or passes left (a pass goes on over its rays
 * even when they have all ended). */
bool qdrain_idle(const struct qdrain_set *ds);

/* Before the store's active set changes: every core lets its queue point go
 * (their queues must have had no rays since they were taken). */
void qdrain_release_all(struct qdrain_set *ds);

/* CHECK that no core holds a queue point. */
void qdrain_check_done(const struct qdrain_set *ds);

#endif
