/* The packed layout (sim/cache_packed.h) against the layouts it stands in
 * for: its LRU order against a brute-force list, and a packed cache against
 * a paged one of the same geometry (a per-core cache of over 1024 lines is
 * paged: per-set vectors, their own stamps and code) on random streams of
 * every call the L2 and the analytic rung make, pending and dirty lines,
 * words and bytes included, every answer compared. Lines whose tags need
 * more than 32 bits arrive midway in some streams: the packed cache widens
 * and must go on answering as the paged one. */
#include <stdlib.h>
#include <string.h>

#include "sim/cache.h"
#include "sim/cache_packed.h"
#include "testing.h"

static uint64_t rnd(uint64_t *x) {
  *x = *x * 6364136223846793005ull + 1442695040888963407ull;
  return *x >> 33;
}

/* cpk_rank and cpk_to_top against a list moved by hand: the way indices
 * from least to most recently used; a use takes one out and appends it. */
static void test_order(void) {
  uint64_t x = 3, order = CPK_ORDER0, bad = 0;
  unsigned list[CPK_WAYS];
  for (unsigned i = 0; i < CPK_WAYS; i++) list[i] = i;
  for (int n = 0; n < 100000; n++) {
    const unsigned k = (unsigned)(rnd(&x) % CPK_WAYS);
    unsigned at = 0;
    while (list[at] != k) at++;
    bad += cpk_rank(order, k) != at;
    memmove(list + at, list + at + 1, (CPK_WAYS - 1 - at) * sizeof *list);
    list[CPK_WAYS - 1] = k;
    order = cpk_to_top(order, k);
    for (unsigned i = 0; i < CPK_WAYS; i++) bad += ((order >> (4 * i)) & 15) != list[i];
  }
  EXPECTF(bad == 0, "%llu nibbles differ from the list", (unsigned long long)bad);
}

/* Everything the owner can read of slot s, the same in both caches. */
static uint64_t slot_differs(struct cache *a, struct cache *b, uint32_t s) {
  uint64_t d = cache_valid(a, s) != cache_valid(b, s);
  d += cache_line(a, s) != cache_line(b, s);
  d += cache_dirty(a, s) != cache_dirty(b, s);
  d += cache_pending(a, s) != cache_pending(b, s);
  d += cache_word(a, s) != cache_word(b, s);
  return d + (cache_byte(a, s) != cache_byte(b, s));
}

/* One random call on both caches (line in line's set); the answers that differ. */
static uint64_t step(struct cache *a, struct cache *b, uint64_t line, uint64_t *x) {
  const uint64_t r = rnd(x) % 100;
  uint64_t d = 0;
  if (r < 30) return cache_use(a, line) != cache_use(b, line);
  if (r < 40) {
    const bool dirty = rnd(x) & 1;
    return cache_fill(a, line, dirty) != cache_fill(b, line, dirty);
  }
  const uint32_t fa = cache_find(a, line);
  d += fa != cache_find(b, line);
  if (fa == CACHE_NONE && r < 70) {
    /* A miss: the victim, what it held, then the install (as l2_try). */
    const uint32_t v = cache_victim(a, line);
    d += v != cache_victim(b, line);
    if (v == CACHE_NONE) return d;
    d += slot_differs(a, b, v);
    const bool dirty = rnd(x) & 1, pending = rnd(x) % 4 == 0;
    cache_install(a, v, line, dirty, pending);
    cache_install(b, v, line, dirty, pending);
    const uint32_t w = (uint32_t)rnd(x), byte = w & 0xff;
    cache_set_word(a, v, w);
    cache_set_word(b, v, w);
    cache_set_byte(a, v, (uint8_t)byte);
    cache_set_byte(b, v, (uint8_t)byte);
    return d;
  }
  if (fa == CACHE_NONE) return d;
  if (r < 80) {
    cache_touch(a, fa);
    cache_touch(b, fa);
  } else if (r < 90) {
    cache_set_pending(a, fa, false); /* its fill is back */
    cache_set_pending(b, fa, false);
  } else {
    cache_set_dirty(a, fa);
    cache_set_dirty(b, fa);
  }
  return d + slot_differs(a, b, fa);
}

/* n calls on lines of `sets_used` sets of a 16-way cache of `size` bytes,
 * `tags` tags a set (over 16: evictions); from call `wide_from` on, one
 * line in 50 has a tag of over 32 bits. */
static void run_stream(uint64_t size, uint64_t sets_used, uint64_t tags, uint64_t n,
                       uint64_t wide_from) {
  const struct cache_params packed = {size, 16, 6, true}, paged = {size, 16, 6, false};
  struct cache *a = cache_create(&packed), *b = cache_create(&paged);
  const uint64_t sets = size / 64 / 16;
  uint64_t x = 5 + size + wide_from, differ = 0, hits = 0;
  for (uint64_t i = 0; i < n; i++) {
    const uint64_t set = (rnd(&x) % sets_used) * (sets / sets_used);
    uint64_t tag = rnd(&x) % tags;
    if (i >= wide_from && rnd(&x) % 50 == 0) tag |= 1ull << 33;
    const uint64_t line = tag * sets + set;
    hits += cache_find(b, line) != CACHE_NONE;
    differ += step(a, b, line, &x);
    if (i % 64 == 0) {
      const uint32_t s = (uint32_t)(set * 16 + rnd(&x) % 16);
      differ += slot_differs(a, b, s);
    }
  }
  EXPECTF(differ == 0, "size %llu, %llu sets used, wide from %llu: %llu answers differ",
          (unsigned long long)size, (unsigned long long)sets_used, (unsigned long long)wide_from,
          (unsigned long long)differ);
  EXPECT(hits > n / 10 && hits < n - n / 10);
  cache_destroy(a);
  cache_destroy(b);
}

int main(void) {
  test_order();
  run_stream(4u << 20, 8, 40, 400000, UINT64_MAX);    /* the default L2, evictions and pending */
  run_stream(4u << 20, 4096, 24, 400000, UINT64_MAX); /* every set */
  run_stream(512u << 10, 16, 20, 200000, UINT64_MAX); /* 512 KiB */
  run_stream(4u << 20, 8, 40, 200000, 100000);        /* widened midway */
  run_stream(1u << 20, 2, 30, 100000, 0);             /* widened at once */
  return testing_done("test_cache_packed");
}
