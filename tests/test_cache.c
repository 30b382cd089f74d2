/* The cache module against a brute-force LRU (a timestamp per way, the oldest
 * replaced), for set-associative and fully associative geometries, including
 * pending lines that may not be evicted. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sim/cache.h"
#include "testing.h"

struct ref {
  uint64_t sets, ways, clock;
  uint64_t *line, *stamp;
  unsigned char *valid;
};

static void ref_init(struct ref *r, uint64_t lines, uint64_t ways) {
  r->ways = ways;
  r->sets = lines / ways;
  r->clock = 0;
  r->line = calloc(lines, sizeof *r->line);
  r->stamp = calloc(lines, sizeof *r->stamp);
  r->valid = calloc(lines, 1);
}

/* Access line: true on a hit. A miss replaces the invalid or oldest way. */
static int ref_access(struct ref *r, uint64_t line) {
  uint64_t s = line % r->sets, *L = r->line + s * r->ways, *S = r->stamp + s * r->ways;
  unsigned char *V = r->valid + s * r->ways;
  r->clock++;
  for (uint64_t w = 0; w < r->ways; w++)
    if (V[w] && L[w] == line) {
      S[w] = r->clock;
      return 1;
    }
  uint64_t victim = 0;
  for (uint64_t w = 0; w < r->ways; w++) {
    if (!V[w]) {
      victim = w;
      break;
    }
    if (S[w] < S[victim]) victim = w;
  }
  V[victim] = 1;
  L[victim] = line;
  S[victim] = r->clock;
  return 0;
}

static void run_geometry(uint64_t size, uint32_t ways, uint64_t span, uint64_t n) {
  struct cache_params p = {size, ways, 6, false};
  EXPECT(cache_params_problem(&p) == NULL);
  struct cache *c = cache_create(&p);
  struct ref r;
  ref_init(&r, size / 64, ways ? ways : size / 64);
  uint64_t x = 7, hits = 0, mism = 0;
  for (uint64_t i = 0; i < n; i++) {
    x = x * 6364136223846793005ull + 1442695040888963407ull;
    uint64_t line = (x >> 33) % span;
    int want = ref_access(&r, line);
    uint32_t s = cache_find(c, line);
    int got = s != CACHE_NONE;
    if (got) {
      cache_touch(c, s);
    } else {
      uint32_t v = cache_victim(c, line);
      cache_install(c, v, line, false, false);
    }
    hits += (uint64_t)got;
    mism += (uint64_t)(got != want);
  }
  EXPECTF(mism == 0, "size %llu ways %u: %llu disagreements", (unsigned long long)size, ways,
          (unsigned long long)mism);
  EXPECT(hits > 0 && hits < n);
  cache_destroy(c);
  free(r.line);
  free(r.stamp);
  free(r.valid);
}

static void test_pending(void) {
  /* Two lines, fully associative: a pending line is never the victim, and
   * with every way pending there is none. */
  struct cache_params p = {128, 0, 6, false};
  struct cache *c = cache_create(&p);
  cache_install(c, cache_victim(c, 10), 10, false, true);
  cache_install(c, cache_victim(c, 11), 11, true, false);
  uint32_t v = cache_victim(c, 12);
  EXPECT(v != CACHE_NONE && cache_line(c, v) == 11 && cache_dirty(c, v));
  cache_set_pending(c, cache_find(c, 11), true);
  EXPECT(cache_victim(c, 12) == CACHE_NONE);
  cache_set_pending(c, cache_find(c, 10), false);
  v = cache_victim(c, 12);
  EXPECT(v != CACHE_NONE && cache_line(c, v) == 10);
  cache_destroy(c);
}

/* Tags are allocated as lines arrive: a 16 GiB cache (set-associative and
 * fully associative) that sees the same 20,000 lines as a 4 MiB one answers
 * the same (neither evicts: 20,000 lines fit both) and holds well under 100
 * bytes a line touched beyond its page table; the set-associative one, whose
 * 20,000 lines fall in as many sets, under 44 (a 16-byte set and a 24-byte
 * slot: 40; sets of 24 bytes made it 48). The fully associative 16 GiB one
 * holds about what the 4 MiB one does; the 4 MiB 16-way one is packed: 5
 * bytes a line of the cache (a 4-byte tag, a 16-byte state a set), made
 * whole at the first line. */
static void test_lazy(void) {
  const uint32_t ways[] = {16, 0};
  for (int k = 0; k < 2; k++) {
    struct cache_params small = {4u << 20, ways[k], 6, true}, big = {1ull << 34, ways[k], 6, true};
    struct cache *a = cache_create(&small), *b = cache_create(&big);
    const uint64_t b0 = cache_host_bytes(b);
    uint64_t x = 11, mism = 0, hits = 0, distinct = 0;
    static unsigned char seen[20000];
    memset(seen, 0, sizeof seen);
    for (int i = 0; i < 200000; i++) {
      x = x * 6364136223846793005ull + 1442695040888963407ull;
      uint64_t line = (x >> 33) % 20000;
      distinct += !seen[line];
      seen[line] = 1;
      struct cache *cs[2] = {a, b};
      int hit[2];
      for (int j = 0; j < 2; j++) {
        uint32_t s = cache_find(cs[j], line);
        hit[j] = s != CACHE_NONE;
        if (hit[j]) cache_touch(cs[j], s);
        else cache_install(cs[j], cache_victim(cs[j], line), line, false, false);
      }
      mism += hit[0] != hit[1];
      hits += hit[0];
    }
    EXPECTF(mism == 0 && hits == 200000 - distinct, "ways %u: %llu disagreements, %llu hits",
            ways[k], (unsigned long long)mism, (unsigned long long)hits);
    const uint64_t ha = cache_host_bytes(a), hb = cache_host_bytes(b);
    printf("ways %u: 4 MiB holds %llu host bytes, 16 GiB %llu (%llu before any line)\n", ways[k],
           (unsigned long long)ha, (unsigned long long)hb, (unsigned long long)b0);
    EXPECTF(hb - b0 < 100ull * 20000 && (ways[k] || hb <= ha + ha / 2),
            "ways %u: %llu host bytes against %llu", ways[k], (unsigned long long)hb,
            (unsigned long long)ha);
    if (ways[k])
      EXPECTF(ha >= 5ull * 65536 && ha < 5ull * 65536 + 4096, "packed: %llu host bytes",
              (unsigned long long)ha);
    EXPECT(b0 < (1u << 20)); /* the page table of a 16 GiB cache */
    if (ways[k])
      EXPECTF(hb - b0 < 44ull * 20000, "%llu host bytes a touched line",
              (unsigned long long)((hb - b0) / 20000));
    cache_destroy(a);
    cache_destroy(b);
  }
}

/* cache_use, and cache_fill on a miss, against the reference LRU (the
 * timed machine's L1 and L2 calls). Lines 2^32 apart share a set and the
 * low half of their tag, so a find must compare both halves. */
static void run_use_fill(uint64_t size, uint32_t ways, bool shared, uint64_t span) {
  struct cache_params p = {size, ways, 6, shared};
  struct cache *c = cache_create(&p);
  struct ref r;
  ref_init(&r, size / 64, ways);
  uint64_t x = 11, hits = 0, mism = 0;
  for (uint64_t i = 0; i < 200000; i++) {
    x = x * 6364136223846793005ull + 1442695040888963407ull;
    const uint64_t line = (x >> 33) % span + ((x >> 20) & 3) * (1ull << 32);
    int want = ref_access(&r, line);
    int got = (i & 1) ? cache_fill(c, line, false) : cache_use(c, line) != CACHE_NONE;
    if (!got && !(i & 1)) mism += cache_fill(c, line, false); /* a miss, then installed */
    const uint32_t s = cache_find(c, line);                   /* held now, under its own line */
    mism += s == CACHE_NONE || cache_line(c, s) != line;
    hits += (uint64_t)got;
    mism += (uint64_t)(got != want);
  }
  EXPECTF(mism == 0, "use/fill size %llu ways %u: %llu disagreements", (unsigned long long)size,
          ways, (unsigned long long)mism);
  EXPECT(hits > 0 && hits < 200000);
  cache_destroy(c);
  free(r.line);
  free(r.stamp);
  free(r.valid);
}

static void test_params(void) {
  struct cache_params bad[] = {{32, 0, 6, false}, {100, 0, 6, false}, {64 * 12, 5, 6, false}};
  for (unsigned i = 0; i < 3; i++) EXPECT(cache_params_problem(&bad[i]) != NULL);
}

int main(void) {
  run_geometry(64, 0, 4, 20000);
  run_geometry(4096, 0, 200, 200000);
  run_geometry(4096, 4, 300, 200000);
  run_geometry(64 * 96, 3, 500, 200000);
  run_geometry(32768, 8, 1 << 12, 300000);
  run_geometry(1 << 16, 0, 2048, 200000);
  run_geometry(1u << 30, 16, 1 << 18, 300000); /* 16M lines, sparsely touched */
  run_geometry(3u << 20, 12, 1 << 17, 300000); /* ways not a power of two */
  run_use_fill(8192, 4, false, 300);           /* the default L1 */
  run_use_fill(4u << 20, 16, true, 1 << 17);   /* the default L2 */
  run_use_fill(64 * 4, 4, false, 16);          /* one set */
  run_use_fill(64 * 96, 4, false, 200);        /* sets not a power of two */
  run_use_fill(32768, 8, false, 1 << 10);      /* neither 4 nor 16 ways */
  test_pending();
  test_lazy();
  test_params();
  return testing_done("test_cache");
}
