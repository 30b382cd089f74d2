/* Binary heap of events keyed by (cycle, sequence). */
#include "sim/engine.h"

#include <stdlib.h>
#include <time.h>

#include "sim/err.h"

struct event {
  uint64_t at, seq;
  engine_fn fn;
  void *ctx;
  uint64_t arg;
};

struct engine {
  struct event *heap;
  uint64_t n, cap;
  uint64_t now, seq, handled;
};

struct engine *engine_create(void) {
  struct engine *e = xcalloc(1, sizeof *e);
  e->cap = 1024;
  e->heap = xmalloc(e->cap * sizeof *e->heap);
  return e;
}

void engine_destroy(struct engine *e) {
  if (!e) return;
  free(e->heap);
  free(e);
}

uint64_t engine_now(const struct engine *e) { return e->now; }
uint64_t engine_events(const struct engine *e) { return e->handled; }
uint64_t engine_pending(const struct engine *e) { return e->n; }

static inline int before(const struct event *a, const struct event *b) {
  return a->at < b->at || (a->at == b->at && a->seq < b->seq);
}

void engine_at(struct engine *e, uint64_t at, engine_fn fn, void *ctx, uint64_t arg) {
  CHECK(at >= e->now);
  if (e->n == e->cap) {
    e->cap *= 2;
    e->heap = xrealloc(e->heap, e->cap * sizeof *e->heap);
  }
  struct event ev = {at, e->seq++, fn, ctx, arg};
  uint64_t i = e->n++;
  while (i > 0) {
    uint64_t p = (i - 1) / 2;
    if (!before(&ev, &e->heap[p])) break;
    e->heap[i] = e->heap[p];
    i = p;
  }
  e->heap[i] = ev;
}

/* Remove the first event into *out. */
static void pop(struct engine *e, struct event *out) {
  struct event *h = e->heap;
  *out = h[0];
  struct event last = h[--e->n];
  uint64_t i = 0, n = e->n;
  for (;;) {
    uint64_t c = 2 * i + 1;
    if (c >= n) break;
    if (c + 1 < n && before(&h[c + 1], &h[c])) c++;
    if (!before(&h[c], &last)) break;
    h[i] = h[c];
    i = c;
  }
  h[i] = last;
}

uint64_t engine_run(struct engine *e) {
  uint64_t start = e->handled;
  struct event ev;
  while (e->n) {
    pop(e, &ev);
    e->now = ev.at;
    e->handled++;
    ev.fn(ev.ctx, ev.arg);
  }
  return e->handled - start;
}

struct bench_state {
  struct engine *e;
  uint64_t left, rng;
};

static void bench_event(void *ctx, uint64_t arg) {
  struct bench_state *b = ctx;
  (void)arg;
  if (b->left == 0) return;
  b->left--;
  b->rng = b->rng * 6364136223846793005ull + 1442695040888963407ull;
  engine_at(b->e, b->e->now + 1 + ((b->rng >> 33) & 1023), bench_event, b, 0);
}

double engine_bench(uint64_t events, uint32_t depth) {
  struct bench_state b = {engine_create(), events, 1};
  for (uint32_t i = 0; i < depth; i++) engine_at(b.e, i, bench_event, &b, 0);
  struct timespec t0, t1;
  clock_gettime(CLOCK_MONOTONIC, &t0);
  uint64_t n = engine_run(b.e);
  clock_gettime(CLOCK_MONOTONIC, &t1);
  engine_destroy(b.e);
  double s = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
  return s > 0 ? (double)n / s : 0.0;
}
