/* The queue store (qstore.h): queues as lists of chunks in one arena, a free
 * list of chunks, and the heap that orders set 0's free queues. */
#include "renderer/policy/qstore.h"

#include <stdlib.h>

#include "renderer/trace.h"
#include "sim/err.h"

void qstore_init(struct qstore *st, uint32_t queues, uint32_t sets, uint64_t qtable_base,
                 uint64_t queue_base) {
  CHECK_GE(sets, 1);
  *st = (struct qstore){0};
  st->queues = queues;
  st->sets = sets;
  st->qtable_base = qtable_base;
  st->queue_base = queue_base;
  st->free_head = QSTORE_NONE;
  st->set = xmalloc((uint64_t)sets * sizeof *st->set);
  for (uint32_t s = 0; s < sets; s++) {
    st->set[s] = xmalloc((uint64_t)queues * sizeof *st->set[s] + 1);
    for (uint32_t i = 0; i < queues; i++)
      st->set[s][i] = (struct qstore_queue){QSTORE_NONE, QSTORE_NONE, 0, 0, -1, false};
  }
  st->heap = xmalloc((uint64_t)queues * sizeof *st->heap + 1);
}

void qstore_fini(struct qstore *st) {
  for (uint32_t s = 0; st->set && s < st->sets; s++) free(st->set[s]);
  free(st->set);
  free(st->heap);
  free(st->pool);
  free(st->stored);
  free(st->entry);
  free(st->chunk_next);
  free(st->chunk_refs);
  *st = (struct qstore){0};
}

/* ---- the heap of set 0's free queues ---- */

static bool heap_above(const struct qstore *st, uint32_t a, uint32_t b) {
  uint32_t ca = st->set[0][a].count, cb = st->set[0][b].count;
  return ca > cb || (ca == cb && a < b);
}

static void heap_set(struct qstore *st, uint32_t pos, uint32_t qi) {
  st->heap[pos] = qi;
  st->set[0][qi].heap_pos = pos;
}

static void heap_up(struct qstore *st, uint32_t pos) {
  uint32_t qi = st->heap[pos];
  while (pos > 0) {
    uint32_t parent = (pos - 1) / 2;
    if (!heap_above(st, qi, st->heap[parent])) break;
    heap_set(st, pos, st->heap[parent]);
    pos = parent;
  }
  heap_set(st, pos, qi);
}

static uint32_t heap_pop(struct qstore *st) {
  uint32_t top = st->heap[0];
  st->set[0][top].heap_pos = -1;
  uint32_t last = st->heap[--st->heap_n];
  if (st->heap_n > 0) {
    uint32_t pos = 0;
    for (;;) {
      uint32_t c = 2 * pos + 1;
      if (c >= st->heap_n) break;
      if (c + 1 < st->heap_n && heap_above(st, st->heap[c + 1], st->heap[c])) c++;
      if (!heap_above(st, st->heap[c], last)) break;
      heap_set(st, pos, st->heap[c]);
      pos = c;
    }
    heap_set(st, pos, last);
  }
  return top;
}

/* Put queue qi of set 0 (not held, not empty) into the heap, or move it up
 * after its count grew. */
static void heap_offer(struct qstore *st, uint32_t qi) {
  struct qstore_queue *q = &st->set[0][qi];
  if (q->heap_pos < 0) {
    st->heap[st->heap_n] = qi;
    q->heap_pos = st->heap_n++;
  }
  heap_up(st, (uint32_t)q->heap_pos);
}

/* ---- chunks ---- */

static uint32_t chunk_alloc(struct qstore *st) {
  uint32_t c;
  if (st->free_head != QSTORE_NONE) {
    c = st->free_head;
    st->free_head = st->chunk_next[c];
  } else {
    if (st->chunks == st->chunk_cap) {
      st->chunk_cap = st->chunk_cap ? 2 * st->chunk_cap : 256;
      const uint64_t slots = (uint64_t)st->chunk_cap * QSTORE_CHUNK_RAYS;
      st->pool = xrealloc(st->pool, slots * sizeof *st->pool);
      st->stored = xrealloc(st->stored, slots);
      st->entry = xrealloc(st->entry, slots * sizeof *st->entry);
      st->chunk_next = xrealloc(st->chunk_next, (uint64_t)st->chunk_cap * sizeof *st->chunk_next);
      st->chunk_refs = xrealloc(st->chunk_refs, (uint64_t)st->chunk_cap * sizeof *st->chunk_refs);
    }
    c = st->chunks++;
  }
  st->chunk_next[c] = QSTORE_NONE;
  st->chunk_refs[c] = 0;
  return c;
}

void qstore_chunk_drop(struct qstore *st, uint32_t c) {
  CHECK_GT(st->chunk_refs[c], 0);
  if (--st->chunk_refs[c] > 0) return;
  st->chunk_next[c] = st->free_head;
  st->free_head = c;
}

/* ---- queues ---- */

uint64_t qstore_push(struct qstore *st, uint32_t set, uint32_t qi, const struct ray *r) {
  CHECK_LT(set, st->sets);
  CHECK_LT(qi, st->queues);
  struct qstore_queue *q = &st->set[set][qi];
  if (q->tail == QSTORE_NONE || q->tail_fill == QSTORE_CHUNK_RAYS) {
    uint32_t c = chunk_alloc(st);
    if (q->tail == QSTORE_NONE) q->head = c;
    else st->chunk_next[q->tail] = c;
    q->tail = c;
    q->tail_fill = 0;
  }
  const uint64_t slot = (uint64_t)q->tail * QSTORE_CHUNK_RAYS + q->tail_fill;
  st->pool[slot] = *r;
  st->stored[slot] = 0;
  st->entry[slot] = 0;
  q->tail_fill++;
  q->count++;
  if (set == 0 && !q->held) heap_offer(st, qi);
  return slot;
}

static uint64_t table_addr(const struct qstore *st, uint32_t qi) {
  return st->qtable_base + 8ull * qi;
}

void qstore_write(struct qstore *st, const struct mem_port *mem, uint32_t qi, uint64_t slot) {
  mem_load(mem, table_addr(st, qi), 8, TRACE_CLASS_QUEUE);
  mem_store(mem, qstore_slot_addr(st, slot), sizeof(struct ray), TRACE_CLASS_RAY);
  st->stored[slot] = 1;
  mem_store(mem, table_addr(st, qi), 8, TRACE_CLASS_QUEUE);
}

void qstore_touch(const struct qstore *st, const struct mem_port *mem, uint32_t qi) {
  mem_load(mem, table_addr(st, qi), 8, TRACE_CLASS_QUEUE);
  mem_store(mem, table_addr(st, qi), 8, TRACE_CLASS_QUEUE);
}

/* Reverse a detached queue's chunk list (host bookkeeping only) and return a
 * cursor at its newest ray. */
static struct qstore_cur cur_newest(struct qstore *st, uint32_t head, uint32_t tail_fill,
                                    uint64_t count) {
  uint32_t prev = QSTORE_NONE;
  for (uint32_t c = head; c != QSTORE_NONE;) {
    uint32_t nc = st->chunk_next[c];
    st->chunk_next[c] = prev;
    prev = c;
    c = nc;
  }
  struct qstore_cur k = {prev, tail_fill - 1, count};
  return k;
}

uint32_t qstore_take(struct qstore *st, struct qstore_cur *first) {
  CHECK_GT(st->heap_n, 0);
  const uint32_t qi = heap_pop(st);
  struct qstore_queue *q = &st->set[0][qi];
  q->held = true;
  *first = cur_newest(st, q->head, q->tail_fill, q->count);
  q->head = q->tail = QSTORE_NONE;
  q->tail_fill = q->count = 0;
  return qi;
}

void qstore_release(struct qstore *st, uint32_t qi) {
  struct qstore_queue *q = &st->set[0][qi];
  CHECK(q->held);
  q->held = false;
  if (q->count > 0) heap_offer(st, qi);
}

uint64_t qstore_activate(struct qstore *st, uint32_t set) {
  CHECK_LT(set, st->sets);
  CHECK_EQ(st->heap_n, 0);
  struct qstore_queue *t = st->set[0];
  st->set[0] = st->set[set];
  st->set[set] = t;
  uint64_t rays = 0;
  for (uint32_t i = 0; i < st->queues; i++) {
    CHECK(!st->set[set][i].held);
    if (st->set[0][i].count > 0) {
      heap_offer(st, i);
      rays += st->set[0][i].count;
    }
  }
  return rays;
}

void qstore_cur_next(struct qstore *st, struct qstore_cur *k, bool release) {
  k->left--;
  if (k->i == 0 || k->left == 0) {
    const uint32_t c = k->c;
    k->c = st->chunk_next[c];
    k->i = QSTORE_CHUNK_RAYS - 1;
    if (release) {
      if (k->left > 0) qstore_chunk_hold(st, k->c);
      qstore_chunk_drop(st, c);
    }
  } else {
    k->i--;
  }
}

void qstore_check_empty(const struct qstore *st) {
  CHECK_EQ(st->heap_n, 0);
  for (uint32_t s = 0; s < st->sets; s++)
    for (uint32_t i = 0; i < st->queues; i++) {
      CHECK_EQ(st->set[s][i].count, 0);
      CHECK(!st->set[s][i].held);
    }
  uint32_t free_chunks = 0;
  for (uint32_t c = st->free_head; c != QSTORE_NONE; c = st->chunk_next[c]) {
    CHECK_EQ(st->chunk_refs[c], 0);
    free_chunks++;
  }
  CHECK_EQ(free_chunks, st->chunks);
}
