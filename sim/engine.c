/* A calendar of ENGINE_WINDOW one-cycle buckets for near events and a binary
 * heap keyed by (cycle, sequence) for far ones. */
#include "sim/engine.h"

#include <stdlib.h>
#include <time.h>

#include "sim/err.h"

#define MASK (ENGINE_WINDOW - 1u)
#define NIL UINT32_MAX

struct node {
  uint64_t at;
  engine_fn fn;
  void *ctx;
  uint64_t arg;
  uint32_t next;
};

struct far {
  uint64_t at, seq;
  uint32_t node;
};

struct engine {
  struct node *nodes;
  uint32_t free, cap;
  uint32_t head[ENGINE_WINDOW], tail[ENGINE_WINDOW];
  uint64_t bits[ENGINE_WINDOW / 64]; /* non-empty buckets */
  uint64_t near;                     /* events in the calendar */
  struct far *heap;
  uint64_t far_n, far_cap, seq;
  uint64_t now, handled;
  uint64_t tick_at; /* UINT64_MAX: no tick */
  engine_tick_fn tick;
  void *tick_ctx;
};

struct engine *engine_create(void) {
  struct engine *e = xcalloc(1, sizeof *e);
  for (uint32_t i = 0; i < ENGINE_WINDOW; i++) e->head[i] = e->tail[i] = NIL;
  e->free = NIL;
  e->tick_at = UINT64_MAX;
  return e;
}

void engine_destroy(struct engine *e) {
  if (!e) return;
  free(e->nodes);
  free(e->heap);
  free(e);
}

uint64_t engine_now(const struct engine *e) { return e->now; }
uint64_t engine_events(const struct engine *e) { return e->handled; }
uint64_t engine_pending(const struct engine *e) { return e->near + e->far_n; }

void engine_tick(struct engine *e, uint64_t at, engine_tick_fn fn, void *ctx) {
  e->tick_at = fn ? at : UINT64_MAX;
  e->tick = fn;
  e->tick_ctx = ctx;
}

/* Time moved to e->now: the tick, when due. Checked only where time moves, so
 * the events of one cycle pay nothing for it. */
static inline void time_moved(struct engine *e) {
  if (e->now < e->tick_at) return;
  e->tick_at = UINT64_MAX;
  e->tick(e->tick_ctx, e->now);
}

/* The slow paths of engine_at, kept out of it: inlined, their registers
 * made every call save six (17 of its 50-odd instructions an event). */
static __attribute__((noinline, cold)) void nodes_grow(struct engine *e) {
  uint32_t old = e->cap;
  e->cap = old ? 2 * old : 4096;
  e->nodes = xrealloc(e->nodes, (uint64_t)e->cap * sizeof *e->nodes);
  for (uint32_t i = old; i < e->cap; i++) e->nodes[i].next = i + 1 < e->cap ? i + 1 : NIL;
  e->free = old;
}

static inline uint32_t node_new(struct engine *e) {
  if (e->free == NIL) nodes_grow(e);
  uint32_t n = e->free;
  e->free = e->nodes[n].next;
  return n;
}

/* Append node n (time within the window) to its bucket. */
static void bucket_push(struct engine *e, uint32_t n) {
  uint32_t b = (uint32_t)(e->nodes[n].at & MASK);
  e->nodes[n].next = NIL;
  if (e->tail[b] == NIL) {
    e->head[b] = n;
    e->bits[b >> 6] |= 1ull << (b & 63);
  } else {
    e->nodes[e->tail[b]].next = n;
  }
  e->tail[b] = n;
  e->near++;
}

static inline int far_before(const struct far *a, const struct far *b) {
  return a->at < b->at || (a->at == b->at && a->seq < b->seq);
}

static __attribute__((noinline)) void far_push(struct engine *e, uint32_t n) {
  if (e->far_n == e->far_cap) {
    e->far_cap = e->far_cap ? 2 * e->far_cap : 256;
    e->heap = xrealloc(e->heap, e->far_cap * sizeof *e->heap);
  }
  struct far f = {e->nodes[n].at, e->seq++, n};
  uint64_t i = e->far_n++;
  while (i > 0) {
    uint64_t p = (i - 1) / 2;
    if (!far_before(&f, &e->heap[p])) break;
    e->heap[i] = e->heap[p];
    i = p;
  }
  e->heap[i] = f;
}

static uint32_t far_pop(struct engine *e) {
  struct far *h = e->heap;
  uint32_t n = h[0].node;
  struct far last = h[--e->far_n];
  uint64_t i = 0, cnt = e->far_n;
  for (;;) {
    uint64_t c = 2 * i + 1;
    if (c >= cnt) break;
    if (c + 1 < cnt && far_before(&h[c + 1], &h[c])) c++;
    if (!far_before(&h[c], &last)) break;
    h[i] = h[c];
    i = c;
  }
  h[i] = last;
  return n;
}

/* Move far events that came within the window into the calendar. */
static void migrate(struct engine *e) {
  while (e->far_n && e->heap[0].at - e->now < ENGINE_WINDOW) bucket_push(e, far_pop(e));
}

void engine_at(struct engine *e, uint64_t at, engine_fn fn, void *ctx, uint64_t arg) {
  CHECK_GE(at, e->now);
  uint32_t n = node_new(e);
  struct node *x = &e->nodes[n];
  x->at = at;
  x->fn = fn;
  x->ctx = ctx;
  x->arg = arg;
  if (at - e->now < ENGINE_WINDOW) bucket_push(e, n);
  else far_push(e, n);
}

/* The first non-empty bucket at or after now's, circularly. */
static uint32_t first_bucket(const struct engine *e) {
  uint32_t b = (uint32_t)(e->now & MASK), w = b >> 6;
  uint64_t word = e->bits[w] & (~0ull << (b & 63));
  for (uint32_t k = 0; k <= ENGINE_WINDOW / 64; k++) {
    if (word) return (w << 6) | (uint32_t)__builtin_ctzll(word);
    w = (w + 1) & (ENGINE_WINDOW / 64 - 1);
    word = e->bits[w];
  }
  CHECK(!"calendar bits out of step");
}

uint64_t engine_run(struct engine *e) {
  uint64_t start = e->handled;
  for (;;) {
    if (!e->near) {
      if (!e->far_n) break;
      e->now = e->heap[0].at;
      migrate(e);
      time_moved(e);
    }
    uint32_t b = first_bucket(e);
    uint32_t n = e->head[b];
    struct node x = e->nodes[n];
    e->head[b] = x.next;
    if (x.next == NIL) {
      e->tail[b] = NIL;
      e->bits[b >> 6] &= ~(1ull << (b & 63));
    }
    e->near--;
    e->nodes[n].next = e->free;
    e->free = n;
    if (x.at != e->now) {
      e->now = x.at;
      migrate(e);
      time_moved(e);
    }
    e->handled++;
    /* The next event's context (its first two host lines), which its
     * handler reads first, is fetched into the host cache while this one
     * runs: on a large machine the contexts of consecutive events (rays,
     * cores) are far apart. */
    if (x.next != NIL) {
      const char *nc = e->nodes[x.next].ctx;
      __builtin_prefetch(nc);
      __builtin_prefetch(nc + 64);
    }
    x.fn(x.ctx, x.arg);
  }
  return e->handled - start;
}

struct bench_state {
  struct engine *e;
  uint64_t left, rng, max_delay;
};

static void bench_event(void *ctx, uint64_t arg) {
  struct bench_state *b = ctx;
  (void)arg;
  if (b->left == 0) return;
  b->left--;
  b->rng = b->rng * 6364136223846793005ull + 1442695040888963407ull;
  engine_at(b->e, b->e->now + 1 + (b->rng >> 24) % b->max_delay, bench_event, b, 0);
}

double engine_bench(uint64_t events, uint32_t depth, uint64_t max_delay) {
  struct bench_state b = {engine_create(), events, 1, max_delay ? max_delay : 1};
  for (uint32_t i = 0; i < depth; i++) engine_at(b.e, i, bench_event, &b, 0);
  struct timespec t0, t1;
  clock_gettime(CLOCK_MONOTONIC, &t0);
  uint64_t n = engine_run(b.e);
  clock_gettime(CLOCK_MONOTONIC, &t1);
  engine_destroy(b.e);
  double s = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
  return s > 0 ? (double)n / s : 0.0;
}
