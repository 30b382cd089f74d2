/* sim/lru_stack: the one-pass analyser equals an independent per-size LRU
 * simulation exactly (misses, writebacks, dirty lines at the end, per class) on
 * random, looping, adversarial and hand-computed traces; plus the functional
 * backend's line splitting. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "sim/lru_stack.h"
#include "sim/mem_functional.h"
#include "testing.h"

/* ---- The oracle: one true LRU cache per size, simulated separately. -------
 * Lines are dense ids in [0, universe); each cache keeps its own recency list
 * (most recent first) and evicts its tail. No stack distances, no sharing. */
struct naive_cache {
  uint32_t cap, count;
  int32_t head, tail;
  int32_t *prev, *next;
  uint8_t *in, *dirty, *cls;
  uint64_t misses[MEM_CLASS_MAX], wb[MEM_CLASS_MAX], dirty_end[MEM_CLASS_MAX];
};

struct naive {
  unsigned n;
  struct naive_cache c[LRU_STACK_MAX_SIZES];
};

static void naive_init(struct naive *nv, const struct lru_stack_params *p, uint32_t universe) {
  memset(nv, 0, sizeof *nv);
  nv->n = p->lg2_max - p->lg2_min + 1;
  for (unsigned i = 0; i < nv->n; i++) {
    struct naive_cache *c = &nv->c[i];
    c->cap = UINT32_C(1) << (p->lg2_min + i - p->lg2_line);
    c->head = c->tail = -1;
    c->prev = calloc(universe, sizeof *c->prev);
    c->next = calloc(universe, sizeof *c->next);
    c->in = calloc(universe, 1);
    c->dirty = calloc(universe, 1);
    c->cls = calloc(universe, 1);
  }
}

static void naive_free(struct naive *nv) {
  for (unsigned i = 0; i < nv->n; i++) {
    free(nv->c[i].prev);
    free(nv->c[i].next);
    free(nv->c[i].in);
    free(nv->c[i].dirty);
    free(nv->c[i].cls);
  }
}

static void nc_unlink(struct naive_cache *c, int32_t x) {
  if (c->prev[x] >= 0) c->next[c->prev[x]] = c->next[x];
  else c->head = c->next[x];
  if (c->next[x] >= 0) c->prev[c->next[x]] = c->prev[x];
  else c->tail = c->prev[x];
}

static void nc_push_front(struct naive_cache *c, int32_t x) {
  c->prev[x] = -1;
  c->next[x] = c->head;
  if (c->head >= 0) c->prev[c->head] = x;
  else c->tail = x;
  c->head = x;
}

/* op as enum lru_stack_op: 0 load, 1 store (fetch on miss), 2 whole-line store
 * (allocate on miss without fetching: not a miss). */
static void naive_access(struct naive *nv, uint32_t id, int op, unsigned cls) {
  const uint8_t store = op != LRU_STACK_READ;
  for (unsigned i = 0; i < nv->n; i++) {
    struct naive_cache *c = &nv->c[i];
    int32_t x = (int32_t)id;
    if (c->in[id]) {
      nc_unlink(c, x);
      c->dirty[id] |= store;
    } else {
      if (op != LRU_STACK_WRITE_LINE) c->misses[cls]++;
      if (c->count == c->cap) {
        int32_t v = c->tail;
        nc_unlink(c, v);
        c->in[v] = 0;
        if (c->dirty[v]) c->wb[c->cls[v]]++;
        c->count--;
      }
      c->in[id] = 1;
      c->dirty[id] = store;
      c->count++;
    }
    c->cls[id] = (uint8_t)cls;
    nc_push_front(c, x);
  }
}

static void naive_finish(struct naive *nv) {
  for (unsigned i = 0; i < nv->n; i++) {
    struct naive_cache *c = &nv->c[i];
    for (int32_t x = c->head; x >= 0; x = c->next[x])
      if (c->dirty[x]) c->dirty_end[c->cls[x]]++;
  }
}

/* ---- Traces over dense ids, mapped to line numbers in several ways. ------- */
struct acc {
  uint32_t id;
  uint8_t store, cls;
};

struct trace {
  struct acc *a;
  size_t n, cap;
  uint32_t universe;
};

static void tr_add(struct trace *t, uint32_t id, int store, unsigned cls) {
  if (t->n == t->cap) {
    t->cap = t->cap ? 2 * t->cap : 1024;
    t->a = realloc(t->a, t->cap * sizeof *t->a);
  }
  t->a[t->n].id = id;
  t->a[t->n].store = (uint8_t)store;
  t->a[t->n].cls = (uint8_t)cls;
  t->n++;
  if (id >= t->universe) t->universe = id + 1;
}

static uint64_t rng_next(uint64_t *s) {
  uint64_t z = (*s += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

/* A bijection on 64-bit values (splitmix's finalizer is invertible). */
static uint64_t mix64(uint64_t z) {
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

enum map_kind { MAP_IDENTITY, MAP_STRIDE_HIGH, MAP_NEAR_TOP, MAP_SPARSE, MAP_HIGH_ONLY, MAP_COUNT };
static const char *const map_names[MAP_COUNT] = {"identity", "stride 2^32", "near 2^64",
                                                 "sparse random", "high bits only"};

static uint64_t map_line(enum map_kind m, uint32_t id) {
  switch (m) {
  case MAP_IDENTITY: return id;
  case MAP_STRIDE_HIGH: return (uint64_t)id << 32 | 7;
  case MAP_NEAR_TOP: return UINT64_MAX - id;
  case MAP_SPARSE: return mix64(id + 0x1234567ull);
  case MAP_HIGH_ONLY: return ((uint64_t)id << 40) | (UINT64_C(1) << 63); /* ids < 2^23 */
  default: return 0;
  }
}

/* Run trace t through both models with geometry p and line map m; compare every
 * counter. Returns the number of mismatching counters. */
static int compare_run(const char *name, const struct trace *t, const struct lru_stack_params *p,
                       enum map_kind m, size_t check_every) {
  struct naive nv;
  naive_init(&nv, p, t->universe);
  struct lru_stack *ls = lru_stack_create(p);
  for (size_t k = 0; k < t->n; k++) {
    naive_access(&nv, t->a[k].id, t->a[k].store, t->a[k].cls);
    lru_stack_access(ls, map_line(m, t->a[k].id), (enum lru_stack_op)t->a[k].store, t->a[k].cls);
    if (check_every && k % check_every == 0) lru_stack_check_invariants(ls);
  }
  lru_stack_check_invariants(ls);
  naive_finish(&nv);
  lru_stack_finish(ls);
  struct lru_stack_results r;
  lru_stack_get_results(ls, &r);
  int bad = 0;
  EXPECT(r.size_count == nv.n);
  uint64_t total = 0;
  for (unsigned c = 0; c < MEM_CLASS_MAX; c++) total += r.accesses[c];
  EXPECTF(total == t->n, "%s: %llu accesses counted, %zu fed", name, (unsigned long long)total,
          t->n);
  for (unsigned i = 0; i < nv.n; i++) {
    for (unsigned c = 0; c < MEM_CLASS_MAX; c++) {
      const struct lru_stack_size_stats *z = &r.size[i];
      const struct naive_cache *o = &nv.c[i];
      if (z->misses[c] != o->misses[c] || z->writebacks[c] != o->wb[c] ||
          z->dirty_at_end[c] != o->dirty_end[c]) {
        bad++;
        if (bad <= 4)
          fprintf(stderr,
                  "%s [%s] size %llu B class %u: misses %llu/%llu wb %llu/%llu dirty_end "
                  "%llu/%llu (stack/naive)\n",
                  name, map_names[m], (unsigned long long)z->capacity_bytes, c,
                  (unsigned long long)z->misses[c], (unsigned long long)o->misses[c],
                  (unsigned long long)z->writebacks[c], (unsigned long long)o->wb[c],
                  (unsigned long long)z->dirty_at_end[c], (unsigned long long)o->dirty_end[c]);
      }
    }
  }
  EXPECTF(bad == 0, "%s [%s]: %d counters differ from the naive LRU", name, map_names[m], bad);
  lru_stack_destroy(ls);
  naive_free(&nv);
  return bad;
}

/* Every map for small traces; check invariants often. */
static void compare_all_maps(const char *name, const struct trace *t,
                             const struct lru_stack_params *p) {
  for (int m = 0; m < MAP_COUNT; m++) compare_run(name, t, p, (enum map_kind)m, 257);
}

static void test_hand_computed(void) {
  /* Sizes 1, 2, 4 lines. A=0 B=1 C=2 D=3. Worked out on paper:
   *  step  1 A ld c0 | 2 B st c2 | 3 A ld c0 | 4 C ld c1 | 5 B ld c3 | 6 D st c2 |
   *        7 A ld c0 | 8 B ld c4
   *  1 line : all 8 miss; B (dirty, step 2) evicted at 3, D (dirty) at 7: wb c2 = 2.
   *  2 lines: only step 3 hits; B evicted dirty at 4, D evicted dirty at 8: wb c2 = 2.
   *  4 lines: misses at 1,2,4,6; no eviction; dirty at end: B (last access c4), D (c2). */
  struct lru_stack_params p = {6, 6, 8};
  struct lru_stack *ls = lru_stack_create(&p);
  static const struct {
    uint64_t line;
    int store;
    unsigned cls;
  } tr[] = {{0, 0, 0}, {1, 1, 2}, {0, 0, 0}, {2, 0, 1}, {1, 0, 3}, {3, 1, 2}, {0, 0, 0}, {1, 0, 4}};
  for (size_t k = 0; k < sizeof tr / sizeof tr[0]; k++) {
    lru_stack_access(ls, tr[k].line, tr[k].store ? LRU_STACK_WRITE : LRU_STACK_READ, tr[k].cls);
    lru_stack_check_invariants(ls);
  }
  lru_stack_finish(ls);
  struct lru_stack_results r;
  lru_stack_get_results(ls, &r);
  static const uint64_t want_miss[3][5] = {{3, 1, 2, 1, 1}, {2, 1, 2, 1, 1}, {1, 1, 2, 0, 0}};
  static const uint64_t want_wb[3][5] = {{0, 0, 2, 0, 0}, {0, 0, 2, 0, 0}, {0, 0, 0, 0, 0}};
  static const uint64_t want_end[3][5] = {{0, 0, 0, 0, 0}, {0, 0, 0, 0, 0}, {0, 0, 1, 0, 1}};
  EXPECT(r.size_count == 3);
  for (unsigned i = 0; i < 3; i++) {
    EXPECT(r.size[i].capacity_bytes == (UINT64_C(64) << i));
    for (unsigned c = 0; c < 5; c++) {
      EXPECTF(r.size[i].misses[c] == want_miss[i][c], "size %u class %u misses %llu want %llu", i,
              c, (unsigned long long)r.size[i].misses[c], (unsigned long long)want_miss[i][c]);
      EXPECTF(r.size[i].writebacks[c] == want_wb[i][c], "size %u class %u wb %llu", i, c,
              (unsigned long long)r.size[i].writebacks[c]);
      EXPECTF(r.size[i].dirty_at_end[c] == want_end[i][c], "size %u class %u end %llu", i, c,
              (unsigned long long)r.size[i].dirty_at_end[c]);
      EXPECT(lru_stack_misses(ls, i, c) == want_miss[i][c]);
      EXPECT(lru_stack_writebacks(ls, i, c) == want_wb[i][c]);
    }
  }
  EXPECT(r.accesses[0] == 3 && r.accesses[2] == 2 && r.stores[2] == 2 && r.stores[0] == 0);
  EXPECT(r.size[1].accesses[0] == 3);
  EXPECT(lru_stack_lines_held(ls) == 4);
  lru_stack_destroy(ls);
}

static void test_random(void) {
  struct lru_stack_params p = {6, 6, 12}; /* 1 .. 64 lines */
  static const uint32_t universes[] = {1, 2, 3, 17, 63, 64, 65, 100, 1000, 100000};
  uint64_t rng = 42;
  for (size_t u = 0; u < sizeof universes / sizeof universes[0]; u++) {
    struct trace t = {0};
    for (int k = 0; k < 60000; k++) {
      uint64_t r = rng_next(&rng);
      unsigned roll = (unsigned)((r >> 32) % 10); /* 70% loads, 20% stores, 10% whole-line stores */
      enum lru_stack_op op = roll < 7   ? LRU_STACK_READ
                             : roll < 9 ? LRU_STACK_WRITE
                                        : LRU_STACK_WRITE_LINE;
      tr_add(&t, (uint32_t)(r % universes[u]), op, (unsigned)((r >> 40) % MEM_CLASS_MAX));
    }
    char name[64];
    snprintf(name, sizeof name, "random N=%u", universes[u]);
    compare_all_maps(name, &t, &p);
    free(t.a);
  }
  /* Other geometries: 128-byte lines; smallest cache of several lines. */
  struct lru_stack_params q[] = {{7, 7, 11}, {6, 8, 12}, {6, 6, 6}, {2, 2, 9}};
  for (size_t g = 0; g < sizeof q / sizeof q[0]; g++) {
    struct trace t = {0};
    for (int k = 0; k < 40000; k++) {
      uint64_t r = rng_next(&rng);
      tr_add(&t, (uint32_t)(r % 150), (int)((r >> 32) % 3), (unsigned)((r >> 40) % MEM_CLASS_MAX));
    }
    compare_all_maps("random, other geometry", &t, &q[g]);
    free(t.a);
  }
}

static void test_loops(void) {
  struct lru_stack_params p = {6, 6, 12};
  for (uint32_t cap = 1; cap <= 64; cap *= 2) {
    for (int d = -1; d <= 1; d++) {
      uint32_t len = (uint32_t)((int)cap + d);
      if (len == 0) continue;
      struct trace t = {0};
      for (int round = 0; round < 40; round++)
        for (uint32_t i = 0; i < len; i++)
          tr_add(&t, i, (int)((i + (uint32_t)round) % 3), i % MEM_CLASS_MAX);
      char name[64];
      snprintf(name, sizeof name, "loop L=%u (size %u lines)", len, cap);
      compare_all_maps(name, &t, &p);
      /* The LRU pathology, exactly: a sweep of cap+1 lines misses every time in
       * the cache of cap lines; a sweep of cap lines misses only the first round. */
      struct lru_stack *ls = lru_stack_create(&p);
      for (size_t k = 0; k < t.n; k++) lru_stack_access(ls, t.a[k].id, LRU_STACK_READ, 0);
      unsigned idx = (unsigned)__builtin_ctz(cap);
      uint64_t want = len > cap ? t.n : len;
      EXPECTF(lru_stack_misses(ls, idx, 0) == want, "loop %u in %u lines: %llu misses, want %llu",
              len, cap, (unsigned long long)lru_stack_misses(ls, idx, 0), (unsigned long long)want);
      lru_stack_destroy(ls);
      free(t.a);
    }
  }
}

static void test_adversarial(void) {
  struct lru_stack_params p = {6, 6, 12};
  uint64_t rng = 7;
  {
    struct trace t = {0}; /* the same line, over and over, stores and loads */
    for (int k = 0; k < 5000; k++) tr_add(&t, 0, k % 7 == 3, (unsigned)k % MEM_CLASS_MAX);
    compare_all_maps("same line", &t, &p);
    free(t.a);
  }
  {
    struct trace t = {0}; /* two interleaved sweeps of different lengths and strides */
    for (int k = 0; k < 30000; k++) {
      uint32_t a = (uint32_t)(k % 37) * 3, b = 1000 + (uint32_t)(k % 70) * 17;
      tr_add(&t, (k & 1) ? a : b, k % 11 == 0, (k & 1) ? 1u : 2u);
    }
    compare_all_maps("alternating strides", &t, &p);
    free(t.a);
  }
  {
    struct trace t = {0}; /* a hot set of 3 lines against a stream of fresh lines */
    for (uint32_t k = 0; k < 30000; k++) {
      if (k % 3) tr_add(&t, k % 2 + (k % 5 == 0), (k % 4) == 0, 3);
      else tr_add(&t, 10 + k, k % 9 == 0, 4);
    }
    compare_all_maps("hot set vs stream", &t, &p);
    free(t.a);
  }
  {
    struct trace t = {0}; /* stores only, then loads only */
    for (int k = 0; k < 20000; k++) {
      uint64_t r = rng_next(&rng);
      tr_add(&t, (uint32_t)(r % 90), k < 10000, (unsigned)(r >> 50) % MEM_CLASS_MAX);
    }
    compare_all_maps("stores then loads", &t, &p);
    free(t.a);
  }
  {
    struct trace t = {0}; /* lines fall off the bottom of the largest cache and come back */
    for (uint32_t i = 0; i < 200; i++) tr_add(&t, i, i % 2, i % MEM_CLASS_MAX);
    for (uint32_t i = 0; i < 200; i++) tr_add(&t, i, 0, 1);
    for (int k = 0; k < 3000; k++) tr_add(&t, (uint32_t)(rng_next(&rng) % 31), k % 5 == 0, 2);
    for (uint32_t i = 150; i < 200; i++) tr_add(&t, i, 1, 4);
    for (uint32_t i = 0; i < 64; i++) tr_add(&t, 199 - i, 0, 0);
    compare_all_maps("fall off and come back", &t, &p);
    free(t.a);
  }
  {
    struct trace t = {0}; /* working set that grows and shrinks across the boundaries */
    for (int k = 0; k < 40000; k++) {
      uint32_t span = 1 + (uint32_t)(k / 500 % 20) * 7;
      uint64_t r = rng_next(&rng);
      tr_add(&t, (uint32_t)(r % span), (int)((r >> 33) % 3), (unsigned)(r >> 50) % MEM_CLASS_MAX);
    }
    compare_all_maps("breathing working set", &t, &p);
    free(t.a);
  }
}

/* The paper's 13 sizes on a shorter mixed trace. */
static void test_default_sizes(void) {
  struct lru_stack_params p = lru_stack_params_default();
  EXPECT(p.lg2_line == 6 && p.lg2_min == 10 && p.lg2_max == 22);
  EXPECT(lru_stack_params_problem(&p) == NULL);
  struct trace t = {0};
  uint64_t rng = 99;
  uint32_t hot = 0, stream = 30000;
  for (int k = 0; k < 400000; k++) {
    uint64_t r = rng_next(&rng);
    if (r % 10 < 7) {
      hot = (r >> 8) % 8 ? (hot + 20000 + (uint32_t)((r >> 16) % 33) - 16) % 20000
                         : (uint32_t)((r >> 16) % 20000);
      tr_add(&t, hot, (r >> 40) % 4 == 0, (unsigned)(r >> 44) % MEM_CLASS_MAX);
    } else {
      tr_add(&t, stream++, (r >> 40) % 4 == 0 ? LRU_STACK_WRITE_LINE : LRU_STACK_READ, 2);
      if (stream == 130000) stream = 30000; /* stream revisits: deep reuse */
    }
  }
  compare_run("default 13 sizes", &t, &p, MAP_SPARSE, 0);
  compare_run("default 13 sizes", &t, &p, MAP_IDENTITY, 0);
  free(t.a);
}

/* lru_stack_access_batch against one call an access (checked against the naive
 * LRU above): the same results with every size alone (the dynamic runs of
 * rtsim traffic analyse one; from 8,192 lines the batch fetches ahead) and all
 * 13 at once, in batches of uneven lengths. */
static void test_batch(void) {
  struct trace t = {0};
  uint64_t rng = 7;
  uint32_t hot = 0, stream = 30000;
  for (int k = 0; k < 300000; k++) {
    uint64_t r = rng_next(&rng);
    if (r % 10 < 7) {
      hot = (hot + 20000 + (uint32_t)((r >> 16) % 33) - 16) % 20000;
      tr_add(&t, hot, (int)((r >> 40) % 3), (unsigned)(r >> 44) % MEM_CLASS_MAX);
    } else {
      tr_add(&t, stream++, (r >> 40) % 4 == 0 ? LRU_STACK_WRITE_LINE : LRU_STACK_READ, 2);
      if (stream == 130000) stream = 30000;
    }
  }
  uint64_t *rec = malloc(t.n * sizeof *rec);
  for (size_t k = 0; k < t.n; k++)
    rec[k] = LRU_STACK_REC(map_line(MAP_SPARSE, t.a[k].id) & ((UINT64_C(1) << 59) - 1),
                           t.a[k].store, t.a[k].cls);
  const struct lru_stack_params all = lru_stack_params_default();
  for (unsigned lg2 = all.lg2_min; lg2 <= all.lg2_max + 1; lg2++) {
    struct lru_stack_params p = all;
    if (lg2 <= all.lg2_max) p.lg2_min = p.lg2_max = lg2; /* else all 13 sizes */
    struct lru_stack *one = lru_stack_create(&p), *bat = lru_stack_create(&p);
    for (size_t k = 0; k < t.n; k++)
      lru_stack_access(one, rec[k] >> 5, (enum lru_stack_op)(rec[k] & 3u),
                       (unsigned)(rec[k] >> 2) & 7u);
    for (size_t k = 0, len = 1; k < t.n; k += len, len = len * 3 % 4099 + 1) {
      if (len > t.n - k) len = t.n - k;
      lru_stack_access_batch(bat, rec + k, (uint32_t)len);
    }
    lru_stack_check_invariants(bat);
    struct lru_stack_results a, b;
    lru_stack_get_results(one, &a);
    lru_stack_get_results(bat, &b);
    EXPECTF(memcmp(&a, &b, sizeof a) == 0, "batch, sizes 2^%u..2^%u: results differ", p.lg2_min,
            p.lg2_max);
    lru_stack_destroy(one);
    lru_stack_destroy(bat);
  }
  free(rec);
  free(t.a);
}

static void test_params(void) {
  struct lru_stack_params bad[] = {{6, 5, 10}, {6, 12, 10}, {6, 6, 40}, {25, 26, 30}, {0, 0, 31}};
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++)
    EXPECTF(lru_stack_params_problem(&bad[i]) != NULL, "params %zu accepted", i);
  struct lru_stack_params ok[] = {{6, 6, 6}, {0, 0, 24}, {6, 10, 22}, {6, 0 + 6, 30}};
  for (size_t i = 0; i < sizeof ok / sizeof ok[0]; i++)
    EXPECTF(lru_stack_params_problem(&ok[i]) == NULL, "params %zu rejected: %s", i,
            lru_stack_params_problem(&ok[i]));
}

/* Functional backend: line splitting and request counters. Classes are plain
 * integers to sim (the renderer names them); C_LAST shows the whole range works. */
enum { C0 = 0, C1 = 1, C2 = 2, C3 = 3, C_LAST = MEM_CLASS_MAX - 1 };

static void test_backend(void) {
  struct lru_stack_params p = {6, 6, 9}; /* 1 .. 8 lines */
  struct mem_functional *b = mem_functional_create(&p, NULL, false);
  struct mem_port port = mem_functional_port(b);
  mem_load(&port, 60, 8, C2);                    /* lines 0 and 1 */
  mem_store(&port, 64, 64, C2);                  /* line 1 */
  mem_load(&port, 128, 1, C0);                   /* line 2 */
  mem_load(&port, 130, 200, C1);                 /* lines 2..5 */
  mem_compute(&port, 1000);                      /* ignored */
  mem_store(&port, UINT64_MAX - 63, 64, C_LAST); /* the very last line */
  mem_load(&port, UINT64_MAX, 1, C_LAST);
  const struct mem_functional_stats *st = mem_functional_get_stats(b);
  EXPECT(st->loads[C2] == 1 && st->stores[C2] == 1);
  EXPECT(st->bytes_loaded[C2] == 8 && st->bytes_stored[C2] == 64);
  EXPECT(st->line_accesses[C2] == 3);
  EXPECT(st->line_accesses[C0] == 1 && st->line_accesses[C1] == 4);
  EXPECT(st->bytes_loaded[C1] == 200);
  EXPECT(st->line_accesses[C_LAST] == 2 && st->bytes_stored[C_LAST] == 64);
  struct lru_stack *ls = mem_functional_stack(b);
  lru_stack_check_invariants(ls);
  lru_stack_finish(ls);
  struct lru_stack_results r;
  lru_stack_get_results(ls, &r);
  for (unsigned c = 0; c < MEM_CLASS_MAX; c++) EXPECT(r.accesses[c] == st->line_accesses[c]);
  /* 8-line cache: distinct lines 0..5 miss (6); the repeat of line 1 (class 2) and
   * line 2 (class 1) hit; the last line is stored whole first, so it is allocated
   * without a fetch, and the load after it hits. */
  uint64_t m = 0;
  for (unsigned c = 0; c < MEM_CLASS_MAX; c++) m += r.size[3].misses[c];
  EXPECTF(m == 6, "8-line cache misses %llu", (unsigned long long)m);
  EXPECT(r.size[3].misses[C2] == 2 && r.size[3].misses[C1] == 3);
  EXPECT(r.size[3].misses[C_LAST] == 0);
  EXPECT(r.size[3].dirty_at_end[C2] == 1 && r.size[3].dirty_at_end[C_LAST] == 1);
  mem_functional_destroy(b);

  /* Whole-line stores are found line by line: [1000, 1128) covers line 16 whole
   * and lines 15 and 17 in part, so 2 fetches; a 64-byte store across a line
   * boundary covers neither line whole (2 more); a 128-byte aligned store none. */
  b = mem_functional_create(&p, NULL, false);
  port = mem_functional_port(b);
  mem_store(&port, 1000, 128, C3);
  mem_store(&port, 32, 64, C2);
  mem_store(&port, 4096, 128, C0);
  ls = mem_functional_stack(b);
  lru_stack_get_results(ls, &r);
  for (unsigned i = 0; i < r.size_count; i++) {
    EXPECTF(r.size[i].misses[C3] == 2, "size %u: %llu class-3 fetches", i,
            (unsigned long long)r.size[i].misses[C3]);
    EXPECT(r.size[i].misses[C2] == 2 && r.size[i].misses[C0] == 0);
  }
  EXPECT(r.size[3].dirty_at_end[C3] == 3 && r.size[3].dirty_at_end[C0] == 2);
  mem_functional_destroy(b);
  mem_functional_destroy(NULL);
  lru_stack_destroy(NULL);
}

/* The backend keeps repeats of the last line from the analyser (and hands their
 * counts over in mem_functional_stack): its results must equal the analyser fed
 * every line directly, on a trace dense in repeats, class changes and stores of
 * both kinds to the repeated line. With the analyser on its own thread too:
 * the lines cross the ring in batches (a dozen here, the handover mid-run
 * falling inside one), and the counts must not change. */
static void test_backend_repeats(bool thread) {
  struct lru_stack_params p = {6, 6, 9}; /* 1 .. 8 lines */
  struct mem_functional *b = mem_functional_create(&p, NULL, thread);
  EXPECT(mem_functional_threaded(b) == thread);
  struct mem_port port = mem_functional_port(b);
  struct lru_stack *direct = lru_stack_create(&p);
  uint64_t rng = 7, line = 0;
  unsigned cls = 0;
  for (int k = 0; k < 200000; k++) {
    uint64_t r = rng_next(&rng);
    if (r % 10 >= 5) line = (r >> 8) % 24; /* else the last line again */
    if ((r >> 16) % 10 >= 7) cls = (unsigned)((r >> 20) % MEM_CLASS_MAX);
    unsigned kind = (unsigned)((r >> 24) % 4); /* 0, 1 load; 2 part store; 3 whole */
    uint64_t a = line << p.lg2_line;
    if (kind < 2) {
      mem_load(&port, a + (r >> 32) % 32, 1 + (uint32_t)((r >> 40) % 32), cls);
      lru_stack_access(direct, line, LRU_STACK_READ, cls);
    } else if (kind == 2) {
      mem_store(&port, a + 8, 8, cls);
      lru_stack_access(direct, line, LRU_STACK_WRITE, cls);
    } else {
      mem_store(&port, a, 64, cls);
      lru_stack_access(direct, line, LRU_STACK_WRITE_LINE, cls);
    }
    if (k == 100000) lru_stack_check_invariants(mem_functional_stack(b)); /* a mid-run handover */
  }
  struct lru_stack *ls = mem_functional_stack(b);
  lru_stack_check_invariants(ls);
  struct lru_stack_results got, want;
  lru_stack_get_results(ls, &got);
  lru_stack_get_results(direct, &want);
  EXPECT(memcmp(&got, &want, sizeof got) == 0);
  for (unsigned i = 0; i < want.size_count; i++)
    for (unsigned c = 0; c < MEM_CLASS_MAX; c++)
      EXPECTF(got.size[i].misses[c] == want.size[i].misses[c] &&
                  got.size[i].writebacks[c] == want.size[i].writebacks[c] &&
                  got.size[i].dirty_at_end[c] == want.size[i].dirty_at_end[c] &&
                  got.size[i].accesses[c] == want.size[i].accesses[c] &&
                  got.size[i].stores[c] == want.size[i].stores[c],
              "size %u class %u: misses %llu/%llu, writebacks %llu/%llu", i, c,
              (unsigned long long)got.size[i].misses[c], (unsigned long long)want.size[i].misses[c],
              (unsigned long long)got.size[i].writebacks[c],
              (unsigned long long)want.size[i].writebacks[c]);
  lru_stack_destroy(direct);
  mem_functional_destroy(b);
}

/* A threaded backend destroyed mid-run (lines published, lines still in the
 * batch being filled, nobody reading): its thread ends and nothing leaks (ASan). */
static void test_backend_thread_teardown(void) {
  struct lru_stack_params p = lru_stack_params_default();
  for (int n = 0; n < 3; n++) {
    struct mem_functional *b = mem_functional_create(&p, NULL, true);
    struct mem_port port = mem_functional_port(b);
    for (uint64_t k = 0; k < (uint64_t)n * 50000; k++) mem_load(&port, k * 64, 8, 0);
    mem_functional_destroy(b);
  }
  EXPECT(mem_functional_host_cpus() >= 1);
}

static void test_bench(void) {
  double rate = lru_stack_bench(300000, 1);
  EXPECT(rate > 0);
  fprintf(stderr, "lru_stack_bench: %.1f M line accesses/s (300K accesses; indicative only)\n",
          rate / 1e6);
}

int main(void) {
  test_hand_computed();
  test_params();
  test_random();
  test_loops();
  test_adversarial();
  test_default_sizes();
  test_batch();
  test_backend();
  test_backend_repeats(false);
  test_backend_repeats(true);
  test_backend_thread_teardown();
  test_bench();
  return testing_done("test_lru_stack");
}
