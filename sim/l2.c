/* The L2's state: the tag array (sim/cache.h), which keeps per slot the head
 * of its waiter list and the class of the miss; a pool of request records (stalled
 * accesses and waiters on pending lines); the miss queue (slots whose fetch
 * the DRAM has not yet taken) and the write buffer (lines to write back), both
 * FIFO rings. Events: a miss leaving for the DRAM, a write-back entering the
 * write buffer, a held merge answered; the DRAM calls back when a fetch or a
 * write is served and when it has room again. */
#include "sim/l2.h"

#include <stdlib.h>

#include "sim/cache.h"
#include "sim/dram.h"
#include "sim/err.h"
#include "sim/line.h"
#include "sim/ring.h"
#include "sim/stats.h"
#include "sim/timeline.h"

#define NONE UINT32_MAX

struct req {
  uint64_t line;
  void *waiter;      /* NULL: a posted store */
  uint64_t ready_at; /* a merged load: not before this cycle */
  uint32_t tag;      /* the client's (l2_access) */
  uint8_t op, cls;
  bool owner; /* in a pending line's waiters: the access that missed (client.cost) */
  uint32_t next;
};

/* An entry of the miss queue (value: the slot) or the write buffer (value:
 * the line, WB_TAKEN_BACK once taken back; tag: the line's cost tag). */
struct qentry {
  uint64_t value, at, tag;
};

struct l2 {
  struct l2_params p;
  struct engine *eng;
  struct timeline *tl;
  struct l2_timeline_cols col;
  struct l2_client client;
  struct dram *dram;
  struct cache *tags;
  uint64_t *bank_free;
  bool banks_pow2; /* banks a power of two: mask, not divide, the line */
  uint32_t mshr_used;
  uint32_t wb_used; /* write-buffer places taken (reserved at eviction) */
  struct req *reqs;
  uint32_t req_free, req_cap;
  uint32_t stall_head, stall_tail;
  int stall_reason;     /* the oldest stalled access's reason, or -1 */
  uint64_t stall_since; /* when that reason began */
  int last_refusal;     /* why l2_try last said no */
  struct ring miss_q, wb;
  struct {
    struct qmeter_clock stall_queue, miss_queue, write_buffer;
  } qc; /* the meters' clocks, beside their numbers in st */
  struct l2_stats st;
};

const char *l2_params_problem(const struct l2_params *p) {
  struct cache_params c = {p->size_bytes, p->ways, SIM_LINE_LG2, true};
  if (cache_params_problem(&c)) return "l2: size and ways do not make a cache of 64-byte lines";
  return NULL;
}

static uint32_t req_new(struct l2 *l2) {
  if (l2->req_free == NONE) {
    uint32_t old = l2->req_cap;
    l2->req_cap = old ? 2 * old : 1024;
    l2->reqs = xrealloc(l2->reqs, (uint64_t)l2->req_cap * sizeof *l2->reqs);
    for (uint32_t i = old; i < l2->req_cap; i++)
      l2->reqs[i].next = i + 1 < l2->req_cap ? i + 1 : NONE;
    l2->req_free = old;
  }
  uint32_t r = l2->req_free;
  l2->req_free = l2->reqs[r].next;
  l2->reqs[r].next = NONE;
  return r;
}

static void req_release(struct l2 *l2, uint32_t r) {
  l2->reqs[r].next = l2->req_free;
  l2->req_free = r;
}

/* DRAM tags: a fetch carries its slot, a write-back nothing but its kind. */
static uint64_t tag_read(uint32_t slot) { return (uint64_t)slot << 1; }
#define TAG_WRITE 1u

static void ev_to_dram(void *ctx, uint64_t slot);
static void ev_to_write_buffer(void *ctx, uint64_t r);
static void ev_held_merge(void *ctx, uint64_t r);
static void pump(struct l2 *l2);

/* Try one access at cycle t; false (and last_refusal) if it must wait. */
static bool l2_try(struct l2 *l2, const struct req *r, uint64_t t) {
  if (ring_len(&l2->miss_q)) {
    l2->last_refusal = L2_STALL_DRAM;
    return false;
  }
  const uint64_t line = r->line;
  /* A hit is made the most recently used now: nothing below refuses a hit. */
  uint32_t slot = cache_use(l2->tags, line);
  bool hit = slot != CACHE_NONE;
  uint32_t victim = CACHE_NONE;
  bool victim_dirty = false; /* a line to write back */
  if (!hit) {
    if (r->op != L2_STORE_LINE && l2->mshr_used >= l2->p.mshrs) {
      l2->last_refusal = L2_STALL_MSHR;
      return false;
    }
    victim = cache_victim(l2->tags, line);
    if (victim == CACHE_NONE) {
      l2->last_refusal = L2_STALL_SET;
      return false;
    }
    victim_dirty = cache_valid(l2->tags, victim) && cache_dirty(l2->tags, victim);
    if (victim_dirty && l2->wb_used >= l2->p.write_buffer) {
      l2->last_refusal = L2_STALL_WRITE_BUFFER;
      return false;
    }
  }
  const uint64_t bank = l2->banks_pow2 ? line & (l2->p.banks - 1) : line % l2->p.banks;
  uint64_t *bf = &l2->bank_free[bank];
  uint64_t start = t > *bf ? t : *bf;
  l2->st.bank_wait_cycles += start - t;
  *bf = start + 1;
  uint64_t ready = start + l2->p.latency_cycles;
  l2->st.accesses++;
  l2->st.accesses_by_class[r->cls]++;
  timeline_point(l2->tl, l2->col.accesses, start, 1.0);
  if (hit) {
    if (r->op != L2_LOAD) cache_set_dirty(l2->tags, slot);
    if (cache_pending(l2->tags, slot)) {
      l2->st.mshr_merges++;
      if (r->waiter) {
        uint32_t w = req_new(l2);
        l2->reqs[w] = *r;
        l2->reqs[w].ready_at = ready;
        l2->reqs[w].owner = false;
        l2->reqs[w].next = cache_word(l2->tags, slot);
        cache_set_word(l2->tags, slot, w);
      }
    } else {
      l2->st.hits++;
      if (r->waiter) engine_at(l2->eng, ready, l2->client.ready, r->waiter, line);
    }
    return true;
  }
  if (victim_dirty) {
    l2->wb_used++;
    l2->st.writeback_bytes += SIM_LINE_BYTES;
    /* The victim's line and the evicting access's tag travel in a request. */
    uint32_t w = req_new(l2);
    l2->reqs[w].line = cache_line(l2->tags, victim);
    l2->reqs[w].tag = r->tag;
    engine_at(l2->eng, ready, ev_to_write_buffer, l2, w);
  }
  if (r->op == L2_STORE_LINE) {
    /* Nothing of the old line survives: allocate without a fetch. */
    l2->st.whole_line_allocs++;
    cache_install(l2->tags, victim, line, true, false);
    return true;
  }
  cache_install(l2->tags, victim, line, r->op != L2_LOAD, true);
  l2->mshr_used++;
  l2->st.misses++;
  l2->st.fetch_bytes += SIM_LINE_BYTES;
  l2->st.fetch_bytes_by_class[r->cls] += SIM_LINE_BYTES;
  timeline_point(l2->tl, l2->col.misses, start, 1.0);
  cache_set_byte(l2->tags, victim, (uint8_t)r->cls);
  /* The access that missed heads the waiters (the oldest): a load's own
   * request, or for a store, when its DRAM read is to be charged, a record
   * that waits for nothing. */
  uint32_t head = NONE;
  if (r->waiter || l2->client.cost) {
    head = req_new(l2);
    l2->reqs[head] = *r;
    l2->reqs[head].ready_at = ready;
    l2->reqs[head].owner = true;
    l2->reqs[head].next = NONE;
  }
  cache_set_word(l2->tags, victim, head);
  engine_at(l2->eng, ready, ev_to_dram, l2, victim);
  return true;
}

void l2_prefetch(const struct l2 *l2, uint64_t line) { cache_prefetch(l2->tags, line); }

void l2_warm(struct l2 *l2, uint64_t line, bool write) {
  uint32_t slot = cache_use(l2->tags, line);
  if (slot != CACHE_NONE) {
    if (write) cache_set_dirty(l2->tags, slot);
    return;
  }
  uint32_t victim = cache_victim(l2->tags, line);
  if (victim != CACHE_NONE) cache_install(l2->tags, victim, line, write, false);
}

/* Attribute the stall time so far to the current reason; then take `reason`
 * (-1: not stalled) from cycle t. */
static void stall_reason_set(struct l2 *l2, int reason, uint64_t t) {
  if (l2->stall_reason >= 0) l2->st.stall_cycles[l2->stall_reason] += t - l2->stall_since;
  l2->stall_reason = reason;
  l2->stall_since = t;
  if (l2->client.stall) l2->client.stall(l2->client.stall_ctx, NULL, reason);
}

static void stall_push(struct l2 *l2, const struct req *r, uint64_t t) {
  uint32_t i = req_new(l2);
  l2->reqs[i] = *r;
  l2->reqs[i].ready_at = t; /* (the cycle it entered the stall queue) */
  l2->reqs[i].next = NONE;
  if (l2->stall_tail == NONE) l2->stall_head = i;
  else l2->reqs[l2->stall_tail].next = i;
  l2->stall_tail = i;
  l2->st.stalls++;
  qmeter_enter(&l2->st.stall_queue, &l2->qc.stall_queue, t);
  if (r->waiter && l2->client.stall) l2->client.stall(l2->client.stall_ctx, r->waiter, 1);
}

/* Retry stalled accesses, oldest first, until one must still wait. */
static void stall_retry(struct l2 *l2, uint64_t t) {
  while (l2->stall_head != NONE) {
    if (ring_len(&l2->miss_q)) { /* l2_try's first refusal, without a copy of the access */
      l2->last_refusal = L2_STALL_DRAM;
      if (l2->stall_reason != L2_STALL_DRAM) stall_reason_set(l2, L2_STALL_DRAM, t);
      return;
    }
    uint32_t i = l2->stall_head;
    struct req r = l2->reqs[i];
    if (!l2_try(l2, &r, t)) {
      if (l2->last_refusal != l2->stall_reason) stall_reason_set(l2, l2->last_refusal, t);
      return;
    }
    qmeter_leave(&l2->st.stall_queue, &l2->qc.stall_queue, t, r.ready_at);
    if (r.waiter && l2->client.stall) l2->client.stall(l2->client.stall_ctx, r.waiter, -1);
    l2->stall_head = r.next;
    if (l2->stall_head == NONE) l2->stall_tail = NONE;
    req_release(l2, i);
  }
  if (l2->stall_reason >= 0) stall_reason_set(l2, -1, t);
}

void l2_access(struct l2 *l2, uint64_t line, enum l2_op op, unsigned cls, void *waiter,
               uint32_t tag) {
  const uint64_t t = engine_now(l2->eng);
  struct req r = {line, waiter, 0, tag, (uint8_t)op, (uint8_t)cls, false, NONE};
  /* In order: while anything is stalled, later accesses queue behind it. */
  if (l2->stall_head != NONE) {
    stall_push(l2, &r, t);
  } else if (!l2_try(l2, &r, t)) {
    stall_push(l2, &r, t);
    stall_reason_set(l2, l2->last_refusal, t);
  }
}

/* ---- towards the DRAM ---- */

static bool try_read(struct l2 *l2, uint64_t t) {
  if (!ring_len(&l2->miss_q)) return false;
  const struct qentry *h = RING_HEAD(&l2->miss_q, struct qentry);
  uint32_t slot = (uint32_t)h->value;
  uint64_t addr = cache_line(l2->tags, slot) << SIM_LINE_LG2;
  if (!dram_can_take(l2->dram, addr, false)) return false;
  qmeter_leave(&l2->st.miss_queue, &l2->qc.miss_queue, t, h->at);
  ring_pop(&l2->miss_q);
  dram_take(l2->dram, addr, false, tag_read(slot));
  return true;
}

/* A write-buffer entry whose line a miss took back (ev_to_dram). */
#define WB_TAKEN_BACK UINT64_MAX

static bool try_write(struct l2 *l2, uint64_t t) {
  while (ring_len(&l2->wb) && RING_HEAD(&l2->wb, struct qentry)->value == WB_TAKEN_BACK)
    ring_pop(&l2->wb);
  if (!ring_len(&l2->wb)) return false;
  const struct qentry *h = RING_HEAD(&l2->wb, struct qentry);
  uint64_t addr = h->value << SIM_LINE_LG2;
  if (!dram_can_take(l2->dram, addr, true)) return false;
  qmeter_leave(&l2->st.write_buffer, &l2->qc.write_buffer, t, h->at);
  const uint32_t tag = (uint32_t)h->tag;
  ring_pop(&l2->wb);
  l2->wb_used--;
  dram_take(l2->dram, addr, true, TAG_WRITE);
  if (l2->client.cost) l2->client.cost(l2->client.cost_ctx, NULL, tag, 0, true);
  return true;
}

/* Hand the DRAM what it will take: reads first, writes when no read waits,
 * or first when the write buffer is full. Then let stalled accesses retry. */
static void pump(struct l2 *l2) {
  const uint64_t t = engine_now(l2->eng);
  bool moved = false;
  for (;;) {
    bool writes_first = l2->wb_used >= l2->p.write_buffer;
    if (writes_first && try_write(l2, t)) {
      moved = true;
      continue;
    }
    if (try_read(l2, t)) {
      moved = true;
      continue;
    }
    if (!writes_first && !ring_len(&l2->miss_q) && try_write(l2, t)) {
      moved = true;
      continue;
    }
    break;
  }
  if (moved && l2->stall_head != NONE) stall_retry(l2, t);
}

static void fill(struct l2 *l2, uint32_t s, uint64_t t, bool from_dram);

/* A miss whose line still waits in the write buffer (evicted dirty, not yet
 * taken by the DRAM) takes it back from there: no read, no write reaches the
 * DRAM, and the line is dirty again. (Without this the DRAM would see a read
 * of a line and then its older data written over it.) */
static bool take_back(struct l2 *l2, uint32_t slot, uint64_t t) {
  const uint64_t line = cache_line(l2->tags, slot);
  for (uint64_t s = l2->wb.head; s < l2->wb.tail; s++) {
    struct qentry *e = RING_AT(&l2->wb, struct qentry, s);
    if (e->value != line) continue;
    qmeter_leave(&l2->st.write_buffer, &l2->qc.write_buffer, t, e->at);
    e->value = WB_TAKEN_BACK;
    l2->wb_used--;
    l2->st.writeback_bytes -= SIM_LINE_BYTES;
    l2->st.fetch_bytes -= SIM_LINE_BYTES;
    l2->st.fetch_bytes_by_class[cache_byte(l2->tags, slot)] -= SIM_LINE_BYTES;
    l2->st.write_buffer_hits++;
    cache_set_dirty(l2->tags, slot);
    fill(l2, slot, t, false);
    return true;
  }
  return false;
}

static void ev_to_dram(void *ctx, uint64_t slot) {
  struct l2 *l2 = ctx;
  const uint64_t t = engine_now(l2->eng);
  if (take_back(l2, (uint32_t)slot, t)) {
    pump(l2); /* (a place in the write buffer is free) */
    return;
  }
  *RING_PUSH(&l2->miss_q, struct qentry) = (struct qentry){slot, t, 0};
  qmeter_enter(&l2->st.miss_queue, &l2->qc.miss_queue, t);
  pump(l2);
}

static void ev_to_write_buffer(void *ctx, uint64_t r) {
  struct l2 *l2 = ctx;
  const uint64_t t = engine_now(l2->eng);
  *RING_PUSH(&l2->wb, struct qentry) = (struct qentry){l2->reqs[r].line, t, l2->reqs[r].tag};
  req_release(l2, (uint32_t)r);
  qmeter_enter(&l2->st.write_buffer, &l2->qc.write_buffer, t);
  pump(l2);
}

static void ev_held_merge(void *ctx, uint64_t r) {
  struct l2 *l2 = ctx;
  const struct req *q = &l2->reqs[r];
  l2->client.ready(q->waiter, q->line);
  req_release(l2, (uint32_t)r);
}

/* ---- from the DRAM ---- */

/* A line the DRAM moved, into timeline column col: over the cycles its data
 * held the channel when the DRAM says (so no window shows more than the
 * channel can move in it), else whole at cycle t, when it was served. */
static void count_line(struct l2 *l2, unsigned col, uint64_t t) {
  double a, b;
  if (dram_served_transfer(l2->dram, &a, &b)) timeline_spread(l2->tl, col, a, b, SIM_LINE_BYTES);
  else timeline_point(l2->tl, col, t, SIM_LINE_BYTES);
}

static void fill(struct l2 *l2, uint32_t s, uint64_t t, bool from_dram) {
  cache_set_pending(l2->tags, s, false);
  l2->mshr_used--;
  unsigned cls = cache_byte(l2->tags, s);
  if (from_dram) {
    count_line(l2, l2->col.read_bytes, t);
    count_line(l2, l2->col.read_class0 + cls, t);
  }
  uint32_t w = cache_word(l2->tags, s);
  cache_set_word(l2->tags, s, NONE);
  /* Waiters were pushed newest first: answer them oldest first. */
  uint32_t prev = NONE;
  while (w != NONE) {
    uint32_t n = l2->reqs[w].next;
    l2->reqs[w].next = prev;
    prev = w;
    w = n;
  }
  for (w = prev; w != NONE;) {
    uint32_t n = l2->reqs[w].next;
    const struct req *q = &l2->reqs[w];
    if (q->owner && from_dram && l2->client.cost)
      l2->client.cost(l2->client.cost_ctx, q->waiter, q->tag, cls, false);
    if (!q->waiter) { /* a store's record: nobody to answer */
      req_release(l2, w);
      w = n;
      continue;
    }
    if (l2->reqs[w].ready_at > t) {
      /* A merged load is never answered sooner than an L2 hit would be. */
      l2->st.merges_held++;
      engine_at(l2->eng, l2->reqs[w].ready_at, ev_held_merge, l2, w);
    } else {
      l2->client.ready(l2->reqs[w].waiter, l2->reqs[w].line);
      req_release(l2, w);
    }
    w = n;
  }
  stall_retry(l2, t);
}

static void dram_done(void *ctx, uint64_t tag) {
  struct l2 *l2 = ctx;
  const uint64_t t = engine_now(l2->eng);
  if (tag == TAG_WRITE) {
    count_line(l2, l2->col.write_bytes, t);
    return;
  }
  fill(l2, (uint32_t)(tag >> 1), t, true);
}

static void dram_space(void *ctx) { pump(ctx); }

struct dram_client l2_dram_client(struct l2 *l2) {
  struct dram_client c = {l2, dram_done, dram_space, NULL};
  return c;
}

void l2_attach(struct l2 *l2, struct dram *d) { l2->dram = d; }

void l2_set_client(struct l2 *l2, const struct l2_client *client) {
  CHECK_EQ(l2->st.accesses + l2->st.stalls, 0);
  CHECK(client->ready);
  l2->client = *client;
}

/* ---- life ---- */

struct l2 *l2_create(const struct l2_params *p, struct engine *e, struct timeline *tl,
                     const struct l2_timeline_cols *cols, const struct l2_client *client) {
  CHECK(l2_params_problem(p) == NULL);
  struct l2 *l2 = xcalloc(1, sizeof *l2);
  l2->p = *p;
  l2->eng = e;
  l2->tl = tl;
  l2->col = *cols;
  l2->client = *client;
  struct cache_params cp = {p->size_bytes, p->ways, SIM_LINE_LG2, true};
  l2->tags = cache_create(&cp);
  l2->bank_free = xcalloc(p->banks, sizeof *l2->bank_free);
  l2->banks_pow2 = (p->banks & (p->banks - 1)) == 0;
  l2->req_free = NONE;
  l2->stall_head = l2->stall_tail = NONE;
  l2->stall_reason = -1;
  return l2;
}

void l2_destroy(struct l2 *l2) {
  if (!l2) return;
  ring_free(&l2->miss_q);
  ring_free(&l2->wb);
  free(l2->reqs);
  free(l2->bank_free);
  cache_destroy(l2->tags);
  free(l2);
}

bool l2_quiet(const struct l2 *l2) {
  return l2->mshr_used == 0 && l2->stall_head == NONE && ring_len(&l2->miss_q) == 0 &&
         ring_len(&l2->wb) == 0 && l2->wb_used == 0;
}

void l2_finish(struct l2 *l2, uint64_t end) {
  qmeter_advance(&l2->st.stall_queue, &l2->qc.stall_queue, end);
  qmeter_advance(&l2->st.miss_queue, &l2->qc.miss_queue, end);
  qmeter_advance(&l2->st.write_buffer, &l2->qc.write_buffer, end);
  /* Conservation: a quiet L2 holds nothing, so whatever entered a queue left it. */
  const struct qmeter *q[] = {&l2->st.stall_queue, &l2->st.miss_queue, &l2->st.write_buffer};
  for (unsigned i = 0; i < 3; i++) CHECK_EQ(q[i]->entered, q[i]->left);
}

void l2_occupancy(const struct l2 *l2, struct l2_occupancy *out) {
  out->mshrs = l2->mshr_used;
  out->stalled = (uint32_t)l2->qc.stall_queue.len;
  out->misses_held = (uint32_t)ring_len(&l2->miss_q);
  out->write_buffer = l2->wb_used;
}

const struct l2_stats *l2_get_stats(const struct l2 *l2) { return &l2->st; }

/* ---- the L2's numbers (docs/stats.md) ---- */

static double l2_miss_rate(const void *st, const struct stats_env *env) {
  (void)env;
  const struct l2_stats *s = st;
  return stats_ratio(s->misses, s->accesses);
}
/* A queue's numbers for Little's law: requests that left it, their mean wait,
 * and the mean and most requests inside (length_mean x cycles = wait_mean x
 * requests, measured apart). */
#define L2_QUEUE_FNS(q)                                                                            \
  static double q##_wait_mean(const void *st, const struct stats_env *env) {                       \
    (void)env;                                                                                     \
    const struct l2_stats *s = st;                                                                 \
    return stats_ratio(s->q.wait_sum, s->q.left);                                                  \
  }                                                                                                \
  static double q##_length_mean(const void *st, const struct stats_env *env) {                     \
    const struct l2_stats *s = st;                                                                 \
    return stats_ratio(s->q.area, env->cycles);                                                    \
  }
L2_QUEUE_FNS(stall_queue)
L2_QUEUE_FNS(miss_queue)
L2_QUEUE_FNS(write_buffer)
#define L2_QUEUE(q, pre, what)                                                                     \
  STATS_FIELD(struct l2_stats, q.left, pre "_requests", "requests", what " that left it"),         \
      STATS_F64(struct l2_stats, q.wait_sum, q##_wait_mean, pre "_wait_mean", "cycles",            \
                what ": mean cycles inside"),                                                      \
      STATS_F64(struct l2_stats, q.area, q##_length_mean, pre "_length_mean", "requests",          \
                what ": mean requests inside over the run"),                                       \
      STATS_FIELD(struct l2_stats, q.max, pre "_length_max", "requests",                           \
                  what ": most inside at once")
#define L2_QUEUE_SKIPS(q)                                                                          \
  STATS_SKIP(struct l2_stats, q.entered,                                                           \
             "equals requests at the end of every run: a conservation CHECK (l2_finish)")

_Static_assert(L2_STALL_COUNT == 4, "a descriptor for each stall reason");
static const struct stats_desc l2_desc[] = {
    STATS_FIELD(struct l2_stats, accesses, "l2_accesses", "count",
                "loads and stores that reached the L2"),
    {.name = "l2_%s_accesses",
     .unit = "count",
     .desc = "of the accesses, those of each data class",
     .how = STATS_HOW_FIELD,
     .off = offsetof(struct l2_stats, accesses_by_class),
     .size = STATS_FIELD_SIZE(struct l2_stats, accesses_by_class),
     .per_class = true},
    STATS_FIELD(struct l2_stats, hits, "l2_hits", "count", "accesses that found their line"),
    STATS_FIELD(struct l2_stats, misses, "l2_misses", "count", "accesses that did not"),
    STATS_F64(struct l2_stats, misses, l2_miss_rate, "l2_miss_rate", "fraction",
              "misses / accesses"),
    STATS_FIELD(struct l2_stats, mshr_merges, "l2_mshr_merges", "count",
                "misses that joined a fetch already in flight (an MSHR)"),
    STATS_FIELD(struct l2_stats, merges_held, "l2_merges_held", "count",
                "merged loads answered after the fill, to honour l2.latency"),
    STATS_FIELD(struct l2_stats, write_buffer_hits, "l2_write_buffer_hits", "count",
                "misses served from the write buffer (no DRAM read or write)"),
    STATS_FIELD(struct l2_stats, whole_line_allocs, "l2_whole_line_allocs", "count",
                "whole-line stores allocated without a fetch"),
    STATS_FIELD(struct l2_stats, stalls, "l2_stalls", "count",
                "accesses that queued behind a stall"),
    STATS_FIELD(struct l2_stats, stall_cycles[L2_STALL_MSHR], "l2_stall_mshr_cycles", "cycles",
                "stalled: no MSHR free"),
    STATS_FIELD(struct l2_stats, stall_cycles[L2_STALL_SET], "l2_stall_set_cycles", "cycles",
                "stalled: every way of the set busy"),
    STATS_FIELD(struct l2_stats, stall_cycles[L2_STALL_WRITE_BUFFER],
                "l2_stall_write_buffer_cycles", "cycles", "stalled: write buffer full"),
    STATS_FIELD(struct l2_stats, stall_cycles[L2_STALL_DRAM], "l2_stall_dram_cycles", "cycles",
                "stalled: the DRAM would not take a request"),
    STATS_FIELD(struct l2_stats, bank_wait_cycles, "l2_bank_wait_cycles", "cycles",
                "accesses waiting for their bank"),
    STATS_FIELD(struct l2_stats, fetch_bytes, "l2_fetch_bytes", "bytes",
                "lines read from the DRAM"),
    STATS_FIELD(struct l2_stats, writeback_bytes, "l2_writeback_bytes", "bytes",
                "dirty lines written back to the DRAM"),
    {.name = "fetch_%s_bytes",
     .unit = "bytes",
     .desc = "lines read from the DRAM, by data class",
     .how = STATS_HOW_FIELD,
     .off = offsetof(struct l2_stats, fetch_bytes_by_class),
     .size = STATS_FIELD_SIZE(struct l2_stats, fetch_bytes_by_class),
     .per_class = true},
    L2_QUEUE(stall_queue, "l2_stall_queue", "accesses stalled at the input"),
    L2_QUEUE(miss_queue, "l2_miss_queue", "misses waiting for the DRAM to take them"),
    STATS_FIELD(struct l2_stats, miss_queue.wait_sum, "backpressure_cycles", "cycles",
                "cycles misses waited for the DRAM to take them, summed"),
    L2_QUEUE(write_buffer, "l2_write_buffer", "write-backs from eviction to the DRAM taking them"),
};
static const struct stats_skip l2_skip[] = {
    L2_QUEUE_SKIPS(stall_queue),
    L2_QUEUE_SKIPS(miss_queue),
    L2_QUEUE_SKIPS(write_buffer),
};
const struct stats_descs l2_stats_descs = {
    "l2", l2_desc, STATS_COUNT(l2_desc), sizeof(struct l2_stats), l2_skip, STATS_COUNT(l2_skip)};
