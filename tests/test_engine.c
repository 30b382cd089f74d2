/* The event engine against a sort: events come out in (cycle, insertion)
 * order, whether they were near (calendar) or far (heap) when scheduled, and
 * events scheduled by a handler for its own cycle run after those already
 * queued for it. Reserved events (engine_reserve) handed over later run at
 * the place of their reservation, before events scheduled after it for their
 * cycle. */
#include <stdlib.h>
#include <string.h>

#include "sim/engine.h"
#include "testing.h"

struct rec {
  uint64_t at, id;
};

/* A reserved event not yet handed over. */
struct held {
  uint64_t at, seq, id;
  bool given;
};

struct state {
  struct engine *e;
  struct rec *log;
  uint64_t n, next_id, rng, spawn_left;
  struct rec *sched; /* every scheduled event, in insertion order */
  uint64_t ns;
  bool reserve;    /* spawn reserved events too */
  struct held *hs; /* reserved events, in reservation order */
  uint64_t nh, guards;
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

static void give(struct state *s, uint64_t h) {
  if (s->hs[h].given) return;
  s->hs[h].given = true;
  engine_at_reserved(s->e, s->hs[h].at, s->hs[h].seq, handler, s, s->hs[h].id);
}

/* A guard: the last event before its reserved one's key, which hands it over. */
static void guard(void *ctx, uint64_t h) { give(ctx, h); }

/* Reserve an event at cycle at (> now), hand over by a guard at the cycle
 * before if nothing else does. */
static void reserve(struct state *s, uint64_t at) {
  uint64_t id = s->next_id++;
  s->sched[s->ns].at = at;
  s->sched[s->ns++].id = id;
  s->hs[s->nh] = (struct held){at, engine_reserve(s->e), id, false};
  engine_at(s->e, at - 1, guard, s, s->nh++);
  s->guards++;
}

static void handler(void *ctx, uint64_t id) {
  struct state *s = ctx;
  s->log[s->n].at = engine_now(s->e);
  s->log[s->n++].id = id;
  /* Hand over some reserved events early (none is due yet: their guards
   * come first). */
  for (uint64_t h = s->nh > 8 ? s->nh - 8 : 0; h < s->nh; h++)
    if (rnd(s) % 4 == 0) give(s, h);
  if (s->spawn_left) {
    s->spawn_left--;
    /* Same cycle, near, at the calendar's edge, or far. */
    uint64_t k = rnd(s) % 4, now = engine_now(s->e);
    uint64_t d = k == 0   ? 0
                 : k == 1 ? rnd(s) % 100
                 : k == 2 ? ENGINE_WINDOW - 1 + rnd(s) % 3
                          : rnd(s) % 100000;
    if (s->reserve && d > 0 && rnd(s) % 2) {
      /* Reserved, then events for its cycle scheduled after it. */
      reserve(s, now + d);
      schedule(s, now + d);
    } else {
      schedule(s, now + d);
    }
  }
}

static int cmp(const void *a, const void *b) {
  const struct rec *x = a, *y = b;
  if (x->at != y->at) return x->at < y->at ? -1 : 1;
  return x->id < y->id ? -1 : (x->id > y->id);
}

/* Spawn events (reserved ones too, with `reserve`) and compare the order
 * they ran in with a sort of every logged event by (cycle, insertion). */
static void run(bool reserve) {
  const uint64_t first = 2000, spawned = 200000, total = first + 2 * spawned;
  struct state s = {engine_create(),
                    calloc(total, sizeof(struct rec)),
                    0,
                    0,
                    42,
                    spawned,
                    calloc(total, sizeof(struct rec)),
                    0,
                    reserve,
                    calloc(spawned, sizeof(struct held)),
                    0,
                    0};
  for (uint64_t i = 0; i < first; i++) schedule(&s, rnd(&s) % (i & 1 ? 50 : 300000));
  const uint64_t handled = engine_run(s.e);
  EXPECT(handled == s.ns + s.guards);
  EXPECT(s.n == s.ns && engine_pending(s.e) == 0);
  EXPECT(!reserve || s.nh > spawned / 4); /* the case is exercised */
  qsort(s.sched, s.ns, sizeof *s.sched, cmp);
  uint64_t bad = 0;
  for (uint64_t i = 0; i < s.ns; i++)
    bad += s.log[i].at != s.sched[i].at || s.log[i].id != s.sched[i].id;
  EXPECTF(bad == 0, "%llu events out of (cycle, insertion) order (reserved: %d)",
          (unsigned long long)bad, reserve);
  engine_destroy(s.e);
  free(s.log);
  free(s.sched);
  free(s.hs);
}

int main(void) {
  run(false);
  run(true);
  return testing_done("test_engine");
}
