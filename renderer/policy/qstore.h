/* The queue store: rays waiting at queue points, in simulated memory and on
 * the host. A store holds `sets` sets of `queues` queues each (the dynamic
 * policy's: the phase being drained, this generation's shadow rays, the next
 * generation); set 0, the active one, keeps its non-empty queues that no drain
 * holds in a max-heap on (rays, -index), so the fullest is taken first.
 *
 * Simulated memory (trace_layout):
 * - queue table at qtable_base: entry q (8 bytes: its buffer's tail) is loaded
 *   and stored on each enqueue, and when a queue is taken (qstore_touch);
 * - queue buffers at queue_base: chunks of QSTORE_CHUNK_RAYS 64-byte rays,
 *   slot k at queue_base + 64 k (chunk c at queue_base + 4096 c). A queue is a
 *   list of chunks; drained chunks go to a last-in-first-out free list and new
 *   chunks come from it first, so the arena stays as small as the most rays
 *   ever queued at once. An enqueue writes a whole line, which the cache
 *   allocates without a fetch.
 *
 * A taken queue is detached whole (qstore_take): its rays are read through a
 * cursor, newest first (the likeliest to be still cached, read before the
 * queue's own work evicts them), and rays that arrive meanwhile start a new
 * list, offered again when the queue is let go (qstore_release).
 *
 * Two hazards of interleaved workers, and how the store settles them:
 * - An enqueue claims its slot (qstore_push: counts, the host record, the
 *   heap) before its accesses (qstore_write), as any of them may suspend the
 *   worker and the next enqueue must find the slot taken. A worker may reach
 *   the slot before the enqueuer's store: the slot is marked stored only once
 *   its store is issued (qstore_stored), and whoever reads it waits for that.
 * - A chunk is freed (and may be reused by any enqueue) only when nothing
 *   refers to it any more: a cursor in it, or a ray handed out from it and not
 *   done (qstore_chunk_hold / qstore_chunk_drop; only a releasing pass over a
 *   detached queue counts, and frees the chunks behind it). So writes made to
 *   a handed-out ray's slot always land in that ray's own record.
 * Private to renderer/. */
#ifndef RTSIM_RENDERER_POLICY_QSTORE_H
#define RTSIM_RENDERER_POLICY_QSTORE_H

#include <stdbool.h>
#include <stdint.h>

#include "renderer/ray.h"
#include "sim/mem.h"

#define QSTORE_CHUNK_RAYS 64u
#define QSTORE_NONE UINT32_MAX

struct qstore_queue {
  uint32_t head, tail; /* chunks, QSTORE_NONE when empty */
  uint32_t tail_fill;  /* rays in the tail chunk */
  uint32_t count;      /* rays queued */
  int64_t heap_pos;    /* position in the heap (set 0), -1 when not in it */
  bool held;           /* taken: its rays are detached (not in the heap) */
};

/* Caller-provided storage: qstore_init, qstore_fini. Fields are the module's. */
struct qstore {
  uint32_t queues, sets;
  uint64_t qtable_base, queue_base; /* simulated addresses */
  struct qstore_queue **set;        /* set[s][q]; set[0] is the active set */
  struct ray *pool;                 /* slot k: pool[k], chunk k / QSTORE_CHUNK_RAYS */
  uint8_t *stored;                  /* per slot: its enqueue has issued its store */
  uint32_t *entry;                  /* per slot: the node the ray resumes at (qstore_entry) */
  uint32_t *chunk_next;             /* next chunk of the same queue, or of the free list */
  uint32_t *chunk_refs;             /* cursors in it + rays handed out from it, not done */
  uint32_t chunks, chunk_cap, free_head;
  uint32_t *heap; /* set 0's free non-empty queues: a max-heap on (count, -index) */
  uint32_t heap_n;
};

/* A position in a detached queue's slots, newest first: the tail chunk from
 * its last ray down, then each earlier chunk from its last slot down. */
struct qstore_cur {
  uint32_t c, i;
  uint64_t left; /* slots from here to the end of the queue */
};

/* `sets` (>= 1) sets of `queues` empty queues; table and buffers at the given
 * simulated addresses. */
void qstore_init(struct qstore *st, uint32_t queues, uint32_t sets, uint64_t qtable_base,
                 uint64_t queue_base);
void qstore_fini(struct qstore *st);

/* Claim a slot at the tail of queue qi of set `set` and copy r into its host
 * record, unstored (host only: no access). A queue of set 0 not held goes into
 * the heap (or up in it). Returns the slot. */
uint64_t qstore_push(struct qstore *st, uint32_t set, uint32_t qi, const struct ray *r);

/* The accesses of pushing slot into queue qi: the table entry is loaded, the
 * ray stored in its slot (then marked stored), the entry stored. Any of them
 * may suspend the caller. */
void qstore_write(struct qstore *st, const struct mem_port *mem, uint32_t qi, uint64_t slot);

/* Whether slot's enqueue has issued its store (see the hazards above). */
static inline bool qstore_stored(const struct qstore *st, uint64_t slot) {
  return st->stored[slot] != 0;
}

/* The host record of slot (valid while the slot holds its ray). */
static inline struct ray *qstore_ray(const struct qstore *st, uint64_t slot) {
  return &st->pool[slot];
}

/* The node a queued ray resumes at, where its queue does not tell it (the
 * treelet policy: a ray enters a treelet at its root or at a node its stack
 * holds). 0 at the push. Host only: the 64-byte record has no room for it,
 * where a real one would carry 4 more bytes (as it would carry its hit's t). */
static inline uint32_t qstore_entry(const struct qstore *st, uint64_t slot) {
  return st->entry[slot];
}
static inline void qstore_set_entry(struct qstore *st, uint64_t slot, uint32_t node) {
  st->entry[slot] = node;
}

static inline uint64_t qstore_slot_addr(const struct qstore *st, uint64_t slot) {
  return st->queue_base + slot * sizeof(struct ray);
}

static inline uint32_t qstore_slot_chunk(uint64_t slot) {
  return (uint32_t)(slot / QSTORE_CHUNK_RAYS);
}

/* Rays queued in queue qi of set `set` (a held queue: those that arrived
 * since it was taken). */
static inline uint32_t qstore_count(const struct qstore *st, uint32_t set, uint32_t qi) {
  return st->set[set][qi].count;
}

static inline bool qstore_held(const struct qstore *st, uint32_t qi) { return st->set[0][qi].held; }

/* Set 0 has a non-empty queue that nobody holds (how many). */
static inline bool qstore_any_free(const struct qstore *st) { return st->heap_n > 0; }
static inline uint32_t qstore_free_queues(const struct qstore *st) { return st->heap_n; }

/* Take set 0's fullest free queue (ties: the lower index): it is held, its
 * rays detached, and *first is a cursor at its newest ray. Returns its index.
 * Host only (qstore_touch makes its accesses). CHECKs one exists. */
uint32_t qstore_take(struct qstore *st, struct qstore_cur *first);

/* The table accesses of taking queue qi: its entry is loaded and stored. */
void qstore_touch(const struct qstore *st, const struct mem_port *mem, uint32_t qi);

/* Let held queue qi of set 0 go: back into the heap if rays arrived since. */
void qstore_release(struct qstore *st, uint32_t qi);

/* Make set `set` the active one (set 0 takes its place): no queue of set 0 may
 * be held or in the heap. The new set's non-empty queues enter the heap.
 * Returns the rays they hold. */
uint64_t qstore_activate(struct qstore *st, uint32_t set);

static inline uint64_t qstore_cur_slot(const struct qstore_cur *k) {
  return (uint64_t)k->c * QSTORE_CHUNK_RAYS + k->i;
}

/* Advance k (k->left > 0). release: k is a releasing pass, which holds the
 * chunk it is in and drops it when it leaves. */
void qstore_cur_next(struct qstore *st, struct qstore_cur *k, bool release);

/* Chunk c is wanted by one more (a cursor in it, a ray handed out from it), or
 * one less: freed at none. */
static inline void qstore_chunk_hold(struct qstore *st, uint32_t c) { st->chunk_refs[c]++; }
void qstore_chunk_drop(struct qstore *st, uint32_t c);

/* Chunks the arena ever had (its size: the most rays queued at once, in
 * chunks). */
static inline uint32_t qstore_chunks(const struct qstore *st) { return st->chunks; }

/* CHECK that the store is empty: every queue of every set, none held, the
 * heap empty, every chunk free and unreferenced. */
void qstore_check_empty(const struct qstore *st);

#endif
