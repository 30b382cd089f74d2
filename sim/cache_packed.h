/* A shared 16-way cache's sets packed for the host's caches (sim/cache.c's
 * layout for the L2): each set's 16 tags, 32 bits each, fill one aligned
 * 64-byte host line, and its LRU order, dirty and pending bits take 16 bytes
 * of a second block (four sets a host line), so a find reads one host line
 * and a use writes 16 bytes beside three other sets' (the wide layout's 16
 * bytes a way took four lines a set, three of them on every use). A tag is
 * the line's bits above the set index, plus one (0: never held a line); a
 * line whose tag does not fit is never held here (cpk_fits): the cache
 * moves to its wide layout before such a line arrives (cache.c). Way index
 * k within a set as the wide layout's (ways - 1 - way). */
#ifndef RTSIM_SIM_CACHE_PACKED_H
#define RTSIM_SIM_CACHE_PACKED_H

#include <stdbool.h>
#include <stdint.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#define CPK_WAYS 16

/* A set's state. order: its 16 way indices as nibbles, least recently used
 * in the lowest, most recently used in the top one: the order the wide
 * layout's use stamps give, never-used slots (all stamps 0) at the bottom
 * by index. dirty, pending: a bit a way index. */
struct cpk_set {
  uint64_t order;
  uint16_t dirty, pending;
};

struct cache_packed {
  uint32_t *tag;       /* sets x 16, host-line aligned; NULL until the first write */
  struct cpk_set *set; /* made with tag */
  uint64_t set_mask;   /* sets - 1 (sets a power of two) */
  unsigned lg2_sets;
};

/* A fresh set's order: index k the k-th least recently used. */
#define CPK_ORDER0 0xFEDCBA9876543210ull
#define CPK_NIBBLES 0x1111111111111111ull

/* An empty store of sets (a power of two) of 16 ways; nothing allocated. */
void cpk_init(struct cache_packed *p, uint64_t sets);
void cpk_fini(struct cache_packed *p);
/* Make the blocks (all sets fresh); the host bytes they take. */
uint64_t cpk_make(struct cache_packed *p);

/* Whether line's tag fits the 32 bits a tag holds. */
static inline bool cpk_fits(const struct cache_packed *p, uint64_t line) {
  return (line >> p->lg2_sets) < UINT32_MAX;
}
static inline uint32_t cpk_key(const struct cache_packed *p, uint64_t line) {
  return (uint32_t)(line >> p->lg2_sets) + 1;
}

/* The index of key among set s's tags, or -1 (a line is in one slot at
 * most). The blocks are made. SSE2: four compares of four tags, packed to
 * one bit a tag. */
static inline int cpk_find(const struct cache_packed *p, uint64_t s, uint32_t key) {
  const uint32_t *t = p->tag + CPK_WAYS * s;
#if defined(__SSE2__)
  const __m128i kk = _mm_set1_epi32((int)key);
#define CPK_EQ(i) _mm_cmpeq_epi32(_mm_load_si128((const __m128i *)(t + (i))), kk)
  const __m128i lo = _mm_packs_epi32(CPK_EQ(0), CPK_EQ(4));
  const __m128i hi = _mm_packs_epi32(CPK_EQ(8), CPK_EQ(12));
#undef CPK_EQ
  const unsigned m = (unsigned)_mm_movemask_epi8(_mm_packs_epi16(lo, hi));
  return m ? __builtin_ctz(m) : -1;
#else
  for (int k = 0; k < CPK_WAYS; k++)
    if (t[k] == key) return k;
  return -1;
#endif
}

/* Where way index k stands in order (0: least recently used). */
static inline unsigned cpk_rank(uint64_t order, unsigned k) {
  const uint64_t x = order ^ (CPK_NIBBLES * k);
  /* Bit 4i set when nibble i is not k; k stands in exactly one nibble. */
  const uint64_t other = (x | x >> 1 | x >> 2 | x >> 3) & CPK_NIBBLES;
  return (unsigned)__builtin_ctzll(~other & CPK_NIBBLES) >> 2;
}

/* order with way index k moved to the top (the most recently used), the
 * nibbles above its place each one down. */
static inline uint64_t cpk_to_top(uint64_t order, unsigned k) {
  const uint64_t below = (1ull << (4 * cpk_rank(order, k))) - 1;
  return (order & below) | ((order >> 4) & ~below) | ((uint64_t)k << 60);
}

/* Make way index k of set s the most recently used. */
static inline void cpk_touch(struct cache_packed *p, uint64_t s, unsigned k) {
  struct cpk_set *st = &p->set[s];
  st->order = cpk_to_top(st->order, k);
}

/* The least recently used way index of set s not pending, or -1 when all
 * are. The blocks are made. */
static inline int cpk_victim(const struct cache_packed *p, uint64_t s) {
  const struct cpk_set *st = &p->set[s];
  if (!st->pending) return (int)(st->order & 15);
  for (unsigned i = 0; i < CPK_WAYS; i++) {
    const unsigned k = (unsigned)(st->order >> (4 * i)) & 15;
    if (!(st->pending >> k & 1)) return (int)k;
  }
  return -1;
}

/* Put line (its tag fits) in way index k of set s as the most recently
 * used, with the given state. The blocks are made. */
void cpk_put(struct cache_packed *p, uint64_t s, unsigned k, uint64_t line, bool dirty,
             bool pending);
/* The line way index k of set s holds (its tag not 0). */
static inline uint64_t cpk_line(const struct cache_packed *p, uint64_t s, unsigned k) {
  return ((uint64_t)(p->tag[CPK_WAYS * s + k] - 1) << p->lg2_sets) | s;
}

#endif
