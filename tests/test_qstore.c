/* The queue store (renderer/policy/qstore.h) alone, against a brute-force model: a
 * plain list of ray ids per queue and set. Random sequences of pushes, takes,
 * passes over taken queues (several at once, with rays handed out and done
 * out of order), releases and set swaps; at every step the store must agree
 * with the lists: counts, which queue is taken (the fullest free one of the
 * active set, ties to the lower index), the rays a cursor yields (newest
 * first, the host records intact), and no slot handed out twice while its ray
 * is still queued or being traced. At the end every chunk is free, and the
 * arena never grew while a freed chunk was waiting. The accesses of a push
 * and a take are checked against their simulated addresses. */
#include <stdlib.h>
#include <string.h>

#include "renderer/policy/qstore.h"
#include "renderer/trace.h"
#include "sim/err.h"
#include "testing.h"

#define SETS 3
#define QUEUES 6
#define MAXR 4096 /* ray ids per run: bounds the lists */
#define DRAINS 3

/* ---- the model ---- */

struct list {
  uint32_t id[MAXR];
  uint32_t n;
};

/* A taken queue being passed over: its rays newest first (exp), the pass
 * (the last one releases), the cursor, the slots handed out in the releasing
 * pass and not yet done. */
struct tdrain {
  bool on;
  uint32_t qi, passes, pass;
  struct qstore_cur first, k;
  uint32_t exp[MAXR];
  uint32_t n, pos;
  uint64_t out[MAXR];
  uint32_t nout;
};

struct model {
  struct list q[SETS][QUEUES];
  bool held[QUEUES];
  struct tdrain dr[DRAINS];
  uint8_t *live; /* per slot: holds a ray queued or not yet done */
  uint64_t live_cap, live_rays;
  uint32_t next_id;
  uint64_t rng;
  uint32_t max_chunks_needed; /* bound on the arena, as the lists need it */
};

static uint32_t rnd(struct model *m, uint32_t n) {
  m->rng ^= m->rng << 13;
  m->rng ^= m->rng >> 7;
  m->rng ^= m->rng << 17;
  return (uint32_t)(m->rng % n);
}

static void live_set(struct model *m, uint64_t slot, uint8_t v) {
  if (slot >= m->live_cap) {
    uint64_t cap = m->live_cap ? m->live_cap : 256;
    while (cap <= slot) cap *= 2;
    m->live = realloc(m->live, cap);
    memset(m->live + m->live_cap, 0, cap - m->live_cap);
    m->live_cap = cap;
  }
  m->live[slot] = v;
}

/* The chunks the model's state needs at most: every queue list in whole
 * chunks plus a partial tail, every drain's rays likewise. A store that
 * reuses freed chunks first never holds more than the most this ever was. */
static uint32_t chunks_needed(const struct model *m) {
  uint32_t c = 0;
  for (int s = 0; s < SETS; s++)
    for (int q = 0; q < QUEUES; q++)
      c += (m->q[s][q].n + QSTORE_CHUNK_RAYS - 1) / QSTORE_CHUNK_RAYS;
  for (int d = 0; d < DRAINS; d++)
    if (m->dr[d].on || m->dr[d].nout) c += (m->dr[d].n + QSTORE_CHUNK_RAYS - 1) / QSTORE_CHUNK_RAYS;
  return c;
}

/* ---- a recording port ---- */

struct rec {
  uint64_t addr[4];
  uint32_t size[4];
  unsigned cls[4];
  int store[4];
  int n;
  const struct qstore *st;
  uint64_t watch;   /* a slot whose stored mark is read at each access */
  int stored_at[4]; /* its mark as each access was made */
};

static void rec_access(void *ctx, uint64_t addr, uint32_t size, unsigned cls, int store) {
  struct rec *r = ctx;
  if (r->n < 4) {
    r->addr[r->n] = addr;
    r->size[r->n] = size;
    r->cls[r->n] = cls;
    r->store[r->n] = store;
    r->stored_at[r->n] = qstore_stored(r->st, r->watch);
  }
  r->n++;
}
static void rec_load(void *c, uint64_t a, uint32_t s, unsigned k) { rec_access(c, a, s, k, 0); }
static void rec_store(void *c, uint64_t a, uint32_t s, unsigned k) { rec_access(c, a, s, k, 1); }
static const struct mem_ops REC_OPS = {rec_load, rec_store, NULL, NULL, NULL, NULL};

#define TABLE 0x1000000ull
#define BUFS 0x8000000ull

/* ---- operations ---- */

static void op_push(struct model *m, struct qstore *st, bool with_port) {
  if (m->next_id >= MAXR) return;
  const uint32_t set = rnd(m, SETS), qi = rnd(m, QUEUES);
  struct list *l = &m->q[set][qi];
  struct ray r;
  memset(&r, 0, sizeof r);
  r.pixel = m->next_id;
  r.o.x = (float)m->next_id;
  r.hit_prim = -1;
  const uint64_t slot = qstore_push(st, set, qi, &r);
  EXPECTF(slot >= m->live_cap || !m->live[slot], "slot %llu handed out while it holds a ray",
          (unsigned long long)slot);
  EXPECT(!qstore_stored(st, slot));
  EXPECT(qstore_ray(st, slot)->pixel == m->next_id);
  live_set(m, slot, 1);
  m->live_rays++;
  l->id[l->n++] = m->next_id++;
  if (with_port) {
    struct rec rc = {.st = st, .watch = slot};
    struct mem_port p = {&REC_OPS, &rc};
    qstore_write(st, &p, qi, slot);
    /* Table load, ray store (then marked stored), table store. */
    EXPECT(rc.n == 3);
    EXPECT(rc.addr[0] == TABLE + 8ull * qi && !rc.store[0] && rc.size[0] == 8 &&
           rc.cls[0] == TRACE_CLASS_QUEUE);
    EXPECT(rc.addr[1] == BUFS + 64 * slot && rc.store[1] && rc.size[1] == 64 &&
           rc.cls[1] == TRACE_CLASS_RAY);
    EXPECT(rc.addr[2] == TABLE + 8ull * qi && rc.store[2] && rc.size[2] == 8);
    EXPECT(!rc.stored_at[0] && !rc.stored_at[1] && rc.stored_at[2]);
  } else {
    st->stored[slot] = 1; /* as qstore_write would, without accesses */
  }
  EXPECT(qstore_stored(st, slot));
  EXPECT(qstore_count(st, set, qi) == l->n);
}

/* The queue the store must take: set 0's fullest free one, ties to the lower
 * index; QUEUES when none. */
static uint32_t expected_take(const struct model *m) {
  uint32_t best = QUEUES;
  for (uint32_t q = 0; q < QUEUES; q++)
    if (!m->held[q] && m->q[0][q].n > 0 && (best == QUEUES || m->q[0][q].n > m->q[0][best].n))
      best = q;
  return best;
}

static void op_take(struct model *m, struct qstore *st) {
  int d = -1;
  for (int i = 0; i < DRAINS; i++)
    if (!m->dr[i].on && m->dr[i].nout == 0) d = i;
  const uint32_t want = expected_take(m);
  EXPECT(qstore_any_free(st) == (want != QUEUES));
  if (d < 0 || want == QUEUES) return;
  struct tdrain *t = &m->dr[d];
  const uint32_t qi = qstore_take(st, &t->first);
  EXPECTF(qi == want, "took queue %u, expected %u", qi, want);
  if (qi != want) return;
  if (rnd(m, 2) == 0) { /* the table accesses of a take */
    struct rec rc = {.st = st};
    struct mem_port p = {&REC_OPS, &rc};
    qstore_touch(st, &p, qi);
    EXPECT(rc.n == 2 && rc.addr[0] == TABLE + 8ull * qi && !rc.store[0] &&
           rc.addr[1] == rc.addr[0] && rc.store[1]);
  }
  struct list *l = &m->q[0][qi];
  t->on = true;
  t->qi = qi;
  t->n = l->n;
  for (uint32_t i = 0; i < l->n; i++) t->exp[i] = l->id[l->n - 1 - i]; /* newest first */
  l->n = 0;
  m->held[qi] = true;
  EXPECT(qstore_held(st, qi) && qstore_count(st, 0, qi) == 0);
  EXPECT(t->first.left == t->n);
  t->passes = 1 + rnd(m, 3);
  t->pass = 0;
  t->pos = 0;
  t->k = t->first;
  if (t->passes == 1) qstore_chunk_hold(st, t->k.c);
}

/* Hand out the next ray of drain t's pass (checking it), and move on to the
 * next pass, or release the queue, when the pass is over. */
static void op_step(struct model *m, struct qstore *st, struct tdrain *t) {
  const bool last = t->pass + 1 == t->passes;
  const uint64_t slot = qstore_cur_slot(&t->k);
  const struct ray *r = qstore_ray(st, slot);
  EXPECTF(r->pixel == t->exp[t->pos] && r->o.x == (float)t->exp[t->pos],
          "pass %u of %u, ray %u: id %u, expected %u", t->pass, t->passes, t->pos, r->pixel,
          t->exp[t->pos]);
  EXPECT(slot < m->live_cap && m->live[slot]);
  if (last) {
    qstore_chunk_hold(st, qstore_slot_chunk(slot));
    t->out[t->nout++] = slot;
  }
  qstore_cur_next(st, &t->k, last);
  t->pos++;
  EXPECT(t->k.left == t->n - t->pos);
  if (t->pos < t->n) return;
  if (!last) {
    t->pass++;
    t->pos = 0;
    t->k = t->first;
    if (t->pass + 1 == t->passes) qstore_chunk_hold(st, t->k.c);
    return;
  }
  /* All handed out: the queue goes back, with the rays that arrived since. */
  qstore_release(st, t->qi);
  m->held[t->qi] = false;
  EXPECT(!qstore_held(st, t->qi));
  t->on = false;
}

/* One ray handed out in a releasing pass is done (any of them). */
static void op_done(struct model *m, struct qstore *st, struct tdrain *t) {
  uint32_t i = rnd(m, t->nout);
  uint64_t slot = t->out[i];
  t->out[i] = t->out[--t->nout];
  live_set(m, slot, 0);
  m->live_rays--;
  qstore_chunk_drop(st, qstore_slot_chunk(slot));
}

/* Swap set 0 with another, as a phase change does: nothing of set 0 may be
 * queued, held or in flight. */
static void op_activate(struct model *m, struct qstore *st, uint32_t set) {
  for (int d = 0; d < DRAINS; d++)
    if (m->dr[d].on) return;
  for (int q = 0; q < QUEUES; q++)
    if (m->q[0][q].n) return;
  if (set == 0) set = 1 + rnd(m, SETS - 1);
  uint64_t rays = 0;
  for (int q = 0; q < QUEUES; q++) {
    struct list t = m->q[0][q];
    m->q[0][q] = m->q[set][q];
    m->q[set][q] = t;
    rays += m->q[0][q].n;
  }
  EXPECT(qstore_activate(st, set) == rays);
  for (uint32_t q = 0; q < QUEUES; q++)
    for (uint32_t s = 0; s < SETS; s++) EXPECT(qstore_count(st, s, q) == m->q[s][q].n);
}

static void run(uint64_t seed, uint32_t ops) {
  struct model *m = calloc(1, sizeof *m);
  m->rng = seed * 0x9E3779B97F4A7C15ull + 1;
  struct qstore st;
  qstore_init(&st, QUEUES, SETS, TABLE, BUFS);
  uint32_t grew_with_free = 0;
  for (uint32_t i = 0; i < ops; i++) {
    const uint32_t chunks0 = qstore_chunks(&st), free0 = st.free_head;
    const uint32_t k = rnd(m, 100);
    if (k < 40) {
      op_push(m, &st, k < 4);
    } else if (k < 50) {
      op_take(m, &st);
    } else if (k < 85) {
      struct tdrain *t = &m->dr[rnd(m, DRAINS)];
      if (t->on) op_step(m, &st, t);
    } else if (k < 98) {
      struct tdrain *t = &m->dr[rnd(m, DRAINS)];
      if (t->nout) op_done(m, &st, t);
    } else {
      op_activate(m, &st, 0);
    }
    grew_with_free += qstore_chunks(&st) > chunks0 && free0 != QSTORE_NONE;
    uint32_t need = chunks_needed(m);
    if (need > m->max_chunks_needed) m->max_chunks_needed = need;
  }
  /* Drain everything: take and pass over every queue of every set. */
  for (int round = 0; round < 4 * SETS; round++) {
    for (;;) {
      for (int d = 0; d < DRAINS; d++) {
        struct tdrain *t = &m->dr[d];
        while (t->on) op_step(m, &st, t);
        while (t->nout) op_done(m, &st, t);
      }
      if (expected_take(m) == QUEUES) break;
      op_take(m, &st);
    }
    op_activate(m, &st, 1 + (uint32_t)round % (SETS - 1));
  }
  for (int s = 0; s < SETS; s++)
    for (int q = 0; q < QUEUES; q++) EXPECTF(m->q[s][q].n == 0, "set %d queue %d left", s, q);
  EXPECT(m->live_rays == 0);
  EXPECTF(grew_with_free == 0, "seed %llu: the arena grew %u times with a chunk free",
          (unsigned long long)seed, grew_with_free);
  EXPECTF(qstore_chunks(&st) <= m->max_chunks_needed,
          "seed %llu: %u chunks, the lists needed at most %u", (unsigned long long)seed,
          qstore_chunks(&st), m->max_chunks_needed);
  qstore_check_empty(&st); /* CHECKs: every chunk back on the free list */
  qstore_fini(&st);
  free(m->live);
  free(m);
}

/* A hand-computed case: 130 rays into one queue make three chunks (64, 64,
 * 2); a take yields them newest first: ids 129, 128, then 127 down to 64 in
 * the middle chunk, then 63 down to 0. */
static void hand_case(void) {
  struct qstore st;
  qstore_init(&st, 2, 1, TABLE, BUFS);
  struct ray r;
  memset(&r, 0, sizeof r);
  for (uint32_t i = 0; i < 130; i++) {
    r.pixel = i;
    uint64_t slot = qstore_push(&st, 0, 1, &r);
    EXPECT(slot == i); /* chunks 0, 1, 2 in order, slots in order */
    st.stored[slot] = 1;
  }
  r.pixel = 1000;
  qstore_push(&st, 0, 0, &r); /* queue 0: one ray, chunk 3 */
  st.stored[3 * 64] = 1;
  EXPECT(qstore_chunks(&st) == 4);
  struct qstore_cur k;
  EXPECT(qstore_take(&st, &k) == 1); /* 130 rays beat 1 */
  EXPECT(k.left == 130 && k.c == 2 && k.i == 1);
  qstore_chunk_hold(&st, k.c);
  for (uint32_t i = 0; i < 130; i++) {
    EXPECT(qstore_ray(&st, qstore_cur_slot(&k))->pixel == 129 - i);
    qstore_cur_next(&st, &k, true);
  }
  EXPECT(k.left == 0);
  /* Chunks 2, 1, 0 freed in that order: the free list is 0, 1, 2. */
  EXPECT(st.free_head == 0);
  qstore_release(&st, 1);
  EXPECT(qstore_take(&st, &k) == 0 && k.left == 1);
  qstore_chunk_hold(&st, k.c);
  EXPECT(qstore_ray(&st, qstore_cur_slot(&k))->pixel == 1000);
  qstore_cur_next(&st, &k, true);
  qstore_release(&st, 0);
  /* The next push reuses the last chunk freed (3), not a new one. */
  EXPECT(qstore_push(&st, 0, 0, &r) == 3 * 64 && qstore_chunks(&st) == 4);
  qstore_fini(&st);
}

int main(void) {
  hand_case();
  for (uint64_t seed = 1; seed <= 40; seed++) run(seed, 20000);
  return testing_done("test_qstore");
}
