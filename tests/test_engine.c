/* The event engine against a sort: events come out in (cycle, insertion)
 * order, whether they were near (calendar) or far (heap) when scheduled, and
 * events scheduled by a handler for its own cycle run after those already
 * queued for it. */
#include <stdlib.h>
#include <string.h>

#include "sim/engine.h"
#include "testing.h"

struct rec {
  uint64_t at, id;
};

struct state {
  struct engine *e;
  struct rec *log;
  uint64_t n, next_id, rng, spawn_left;
  struct rec *sched; /* every scheduled event, in insertion order */
  uint64_t ns;
};

static uint64_t rnd(struct state *s) {
  s->rng = s->rng * 6364136223846793005ull + 1442695040888963407ull;
  return s->rng >> 17;
}

static void handler(void *ctx, uint64_t id);

static void schedule(struct state *s, uint64_t at) {
  uint64_t id = s->next_id++;
  s->sched[s->ns].at = at;
  s->sched[s->ns++].id = id;
  engine_at(s->e, at, handler, s, id);
}

static void handler(void *ctx, uint64_t id) {
  struct state *s = ctx;
  s->log[s->n].at = engine_now(s->e);
  s->log[s->n++].id = id;
  if (s->spawn_left) {
    s->spawn_left--;
    /* Same cycle, near, at the calendar's edge, or far. */
    uint64_t k = rnd(s) % 4, now = engine_now(s->e);
    uint64_t d = k == 0   ? 0
                 : k == 1 ? rnd(s) % 100
                 : k == 2 ? ENGINE_WINDOW - 1 + rnd(s) % 3
                          : rnd(s) % 100000;
    schedule(s, now + d);
  }
}

static int cmp(const void *a, const void *b) {
  const struct rec *x = a, *y = b;
  if (x->at != y->at) return x->at < y->at ? -1 : 1;
  return x->id < y->id ? -1 : (x->id > y->id);
}

int main(void) {
  const uint64_t first = 2000, spawned = 200000, total = first + spawned;
  struct state s = {engine_create(), calloc(total, sizeof(struct rec)), 0, 0, 42,
                    spawned,         calloc(total, sizeof(struct rec)), 0};
  for (uint64_t i = 0; i < first; i++) schedule(&s, rnd(&s) % (i & 1 ? 50 : 300000));
  EXPECT(engine_run(s.e) == total);
  EXPECT(s.n == total && engine_pending(s.e) == 0);
  qsort(s.sched, s.ns, sizeof *s.sched, cmp);
  uint64_t bad = 0;
  for (uint64_t i = 0; i < total; i++)
    bad += s.log[i].at != s.sched[i].at || s.log[i].id != s.sched[i].id;
  EXPECTF(bad == 0, "%llu events out of (cycle, insertion) order", (unsigned long long)bad);
  engine_destroy(s.e);
  free(s.log);
  free(s.sched);
  return testing_done("test_engine");
}
