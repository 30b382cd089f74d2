/* Slots are grouped by set. A scanned set (few ways) orders its slots by a
 * use stamp; a hashed one keeps an LRU list (indices, most recent at the
 * head). A hash table of line -> slot (linear probing, backward-shift
 * deletion) finds a line in O(1) whatever the associativity, so a fully
 * associative L2 of 64K lines costs what a 4-way L1 does. */
#include "sim/cache.h"

#include <stdbool.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "sim/cache_packed.h"
#include "sim/err.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#define F_VALID 1u
#define F_DIRTY 2u
#define F_PENDING 4u

struct slot {
  uint64_t line;
  /* A scanned cache stamps each use from one counter: the least recently
   * used slot of a set has the smallest stamp, so a use is one store, where
   * moving a slot to the head of a list took three dependent ones (an L1 hit
   * on the timed machine makes one). A hashed cache, whose set may be the
   * whole cache, keeps the list: its victim is the list's tail, no scan. */
  union {
    struct {
      uint32_t prev, next; /* hashed: the set's used slots, a circular LRU list */
    };
    uint64_t stamp; /* scanned: the cache's use count at the last use */
  };
  uint8_t flags, byte; /* byte, word: the owner's (cache_byte, cache_word) */
  uint32_t word;
};

/* A set's used slots form its LRU list (head most recent); the rest of its
 * slots have never held a line. A fresh set is a list of all its slots in
 * index order whose tail is taken first, and a slot taken moves to the head:
 * so the never-used slots are always the lowest `ways - used` of the set, in
 * order, at the list's tail, and need no state of their own. The used ones
 * are kept in a vector that grows with them: way w at vec[ways - 1 - w]; its
 * capacity is a function of `used` (vec_cap). A hashed set's list is circular
 * (the head's prev is the tail), so a set is 16 bytes: in a very large cache
 * nearly every touched set holds one line, and the set is a third of it. */
struct set {
  struct slot *vec;
  uint32_t used;
  uint32_t head; /* hashed caches only: the most recently used slot */
};

/* Sets live in pages allocated when a set is first written, and a set's
 * slots in its vector: a cache's host memory follows the lines it has held,
 * not its configured size. */
#define SET_PAGE 1024u

struct cache {
  /* What a find, a use, a victim and an install read, first and in one host
   * line (the struct is line-aligned): on 1024 cores the L1s' headers are
   * as far from the host's near caches as their sets. */
  bool scan;    /* few ways: find a line by scanning its set */
  bool flat_ok; /* small and scanned: flat, made at the first install */
  /* Flat, 4 or 16 ways (the configured L1s and L2), and a power-of-two
   * count of sets: the ways, whose use and fill take a path with the
   * geometry as constants (FAST_USE); else 0. */
  uint8_t fast_ways;
  /* Flat, 16 ways and a power-of-two count of sets (the configured L2):
   * the sets packed (pk, sim/cache_packed.h) while every line held has a
   * tag of 32 bits; fast_ways is 0 meanwhile. */
  bool packed;
  unsigned lg2_ways; /* ways a power of two: its log2, else 64 (divide) */
  uint64_t set_mask; /* sets - 1 when a power of two, else 0 (use %) */
  uint64_t uses;     /* scanned: the last stamp given */
  /* Then each set's tags (line + 1; 0: never held one, so invalid) and
   * after them its stamps (with FLAT_PENDING and FLAT_DIRTY), slot i's at
   * index k of its set s (k: ways - 1 - way): a 4-way set is one host line,
   * which a find, a use, a victim and an install all stay in. */
  uint64_t *ftag; /* host-line aligned */
  struct cache_packed pk;
  /* The rest. */
  uint64_t ways;
  struct fmeta *fmeta; /* the owner's word and byte, made at the first set */
  uint64_t sets;
  struct set **set_pages;
  uint64_t set_page_count;
  uint64_t lines;
  uint32_t *table; /* otherwise: slot index + 1; 0 empty */
  uint64_t table_mask, table_used;
  unsigned table_shift;
  uint64_t vec_bytes; /* slots allocated: in vectors, or a flat cache's blocks */
};

_Static_assert(offsetof(struct cache, pk) + sizeof(struct cache_packed) <= 64,
               "a find's fields fit the header's first host line");

/* A flat slot's word and byte (cache_word, cache_byte): only an owner that
 * keeps them (the L2) pays for them. */
struct fmeta {
  uint32_t word;
  uint8_t byte;
};
#define FLAT_PENDING (1ull << 63)
#define FLAT_DIRTY (1ull << 62)
#define FLAT_STATE (FLAT_PENDING | FLAT_DIRTY)

/* A scanned cache of at most this many lines (an L1: 8 KiB is 128), or a
 * shared one of at most FLAT_LINES_SHARED (the default L2, 4 MiB of 16 ways,
 * 65,536; per-core caches stay below 1024 lines so that many cores with large,
 * sparsely used L1s cost what their lines do) is flat: one block of each
 * set's tags (line + 1) followed by its stamps, 16 bytes a line, allocated
 * when the first line arrives (a core that never runs costs nothing; the
 * pages of a large block only as they are written), and the owner's word and
 * byte in another block made when first set (the L2's; an L1 has none). A
 * never-used slot is zeros: invalid, and the oldest stamp of its set, so no
 * set needs a count or a list. A find reads the set's tags only, and a use,
 * a victim choice and an install the stamps beside them: a 4-way L1's set is
 * one host line. (The set pages and per-set vectors took two or three
 * dependent misses a find; a block of 24-byte slots beside the tags took two
 * more host lines for a victim: on 1024 cores, whose L1s do not stay in the
 * host's caches, these were a third of the run.) */
#define FLAT_LINES 1024u
#define FLAT_LINES_SHARED (1u << 17)

static const struct slot ZERO_SLOT;
static const struct set ZERO_SET;

/* Up to this many ways a set is scanned (its tags sit in a few host lines);
 * beyond, the hash table finds the line. */
#define SCAN_WAYS 16

/* Slot i's set and its way in the set. A power-of-two way count (every
 * configured cache so far) shifts and masks: the division they replace was
 * a tenth of a timed run's host time on the L1 hit path. */
static inline uint64_t set_of_slot(const struct cache *c, uint64_t i) {
  return c->lg2_ways < 64 ? i >> c->lg2_ways : i / c->ways;
}

static inline uint64_t way_of_slot(const struct cache *c, uint64_t i) {
  return c->lg2_ways < 64 ? i & (c->ways - 1) : i % c->ways;
}

static inline uint64_t set_of_line(const struct cache *c, uint64_t line) {
  return c->set_mask ? (line & c->set_mask) : line % c->sets;
}

static inline const struct set *set_peek(const struct cache *c, uint64_t s) {
  const struct set *p = c->set_pages[s / SET_PAGE];
  return p ? &p[s % SET_PAGE] : &ZERO_SET;
}

static void flat_make(struct cache *c) {
  const uint64_t bytes = 2 * c->lines * sizeof *c->ftag;
  c->ftag = xcalloc_aligned(64, bytes);
  c->vec_bytes += bytes;
}

/* Set s's tags, then its stamps. */
static inline uint64_t *ftags(const struct cache *c, uint64_t s) {
  return c->ftag + 2 * s * c->ways;
}
static inline uint64_t *fstamps(const struct cache *c, uint64_t s) {
  return c->ftag + (2 * s + 1) * c->ways;
}

/* The slot at index k of set s's vector (k: ways - 1 - way), CACHE_NONE for k < 0. */
static inline uint32_t slot_no(const struct cache *c, uint64_t s, int64_t k) {
  return k < 0 ? CACHE_NONE : (uint32_t)(s * c->ways + c->ways - 1 - (uint64_t)k);
}

/* Slot i's index within its set's vector or block (ways - 1 - way). */
static inline uint64_t in_set(const struct cache *c, uint64_t i) {
  return c->ways - 1 - way_of_slot(c, i);
}

/* Slot i's tag and stamp in a flat cache whose block is made. */
static inline uint64_t *ftag_of(const struct cache *c, uint64_t i) {
  return ftags(c, set_of_slot(c, i)) + in_set(c, i);
}
static inline uint64_t *fstamp_of(const struct cache *c, uint64_t i) {
  return ftag_of(c, i) + c->ways;
}
/* Slot i's tag and stamp to write (the block made at the first write). */
static inline uint64_t *fstamp_get(struct cache *c, uint64_t i) {
  if (!c->ftag) flat_make(c);
  return fstamp_of(c, i);
}
/* Slot i's stamp to read: 0 (oldest, not pending, clean) if never written. */
static inline uint64_t fstamp_peek(const struct cache *c, uint64_t i) {
  return c->ftag ? *fstamp_of(c, i) : 0;
}
/* Slot i's word and byte (made at the first set; index as in a set's tags). */
static inline uint64_t flat_index(const struct cache *c, uint64_t i) {
  return set_of_slot(c, i) * c->ways + in_set(c, i);
}
static inline struct fmeta *fmeta_get(struct cache *c, uint64_t i) {
  if (!c->fmeta) {
    c->fmeta = xcalloc(c->lines, sizeof *c->fmeta);
    c->vec_bytes += c->lines * sizeof *c->fmeta;
  }
  return &c->fmeta[flat_index(c, i)];
}
static const struct fmeta ZERO_FMETA;
static inline const struct fmeta *fmeta_peek(const struct cache *c, uint64_t i) {
  return c->fmeta ? &c->fmeta[flat_index(c, i)] : &ZERO_FMETA;
}

/* A packed cache's slots: slot numbers as the wide layout's (s * 16 + 15 -
 * k for way index k of set s), so that a cache that widens keeps them. */
static inline uint64_t pk_set(uint32_t slot) { return slot / CPK_WAYS; }
static inline unsigned pk_k(uint32_t slot) { return CPK_WAYS - 1 - slot % CPK_WAYS; }
static inline uint32_t pk_slot(uint64_t s, int k) {
  return k < 0 ? CACHE_NONE : (uint32_t)(s * CPK_WAYS + CPK_WAYS - 1 - (unsigned)k);
}
/* A packed cache's blocks, made at the first write. */
static inline void pk_ready(struct cache *c) {
  if (!c->pk.tag) c->vec_bytes += cpk_make(&c->pk);
}
/* The way index holding line in its set, or -1. */
static inline int pk_find(const struct cache *c, uint64_t line) {
  if (!c->pk.tag || !cpk_fits(&c->pk, line)) return -1;
  return cpk_find(&c->pk, line & c->pk.set_mask, cpk_key(&c->pk, line));
}
/* A packed slot's state bit (dirty or pending word of its set) as read:
 * clear before the blocks are made. */
static inline bool pk_bit(const struct cache *c, uint32_t slot, bool pending) {
  if (!c->pk.tag) return false;
  const struct cpk_set *st = &c->pk.set[pk_set(slot)];
  return ((pending ? st->pending : st->dirty) >> pk_k(slot)) & 1;
}
static inline void pk_set_bit(struct cache *c, uint32_t slot, bool pending, bool on) {
  pk_ready(c);
  struct cpk_set *st = &c->pk.set[pk_set(slot)];
  uint16_t *w = pending ? &st->pending : &st->dirty;
  const uint16_t bit = (uint16_t)(1u << pk_k(slot));
  *w = (uint16_t)(on ? *w | bit : *w & ~bit);
}

/* A line whose tag does not fit 32 bits is to arrive: move a packed cache
 * to the wide flat layout. Each set's order becomes the stamps 1..16 from
 * its least recently used up (the tags and states as they were), and the
 * next use stamps 17: the stamps order the ways as the order did, so every
 * victim and use answers as before. */
static void pk_widen(struct cache *c) {
  c->packed = false;
  c->fast_ways = CPK_WAYS;
  if (c->pk.tag) {
    flat_make(c);
    for (uint64_t s = 0; s < c->sets; s++) {
      const struct cpk_set *st = &c->pk.set[s];
      uint64_t *tg = ftags(c, s), *sp = fstamps(c, s);
      for (unsigned i = 0; i < CPK_WAYS; i++) {
        const unsigned k = (unsigned)(st->order >> (4 * i)) & 15;
        tg[k] = c->pk.tag[CPK_WAYS * s + k] ? cpk_line(&c->pk, s, k) + 1 : 0;
        sp[k] = (i + 1) | ((st->dirty >> k & 1) ? FLAT_DIRTY : 0) |
                ((st->pending >> k & 1) ? FLAT_PENDING : 0);
      }
    }
    c->uses = CPK_WAYS;
    c->vec_bytes -= c->sets * (CPK_WAYS * sizeof *c->pk.tag + sizeof *c->pk.set);
  }
  cpk_fini(&c->pk);
}

/* Sets in page i: SET_PAGE, fewer in a small cache's only page. */
static inline uint64_t page_sets(const struct cache *c, uint64_t i) {
  uint64_t left = c->sets - i * SET_PAGE;
  return left < SET_PAGE ? left : SET_PAGE;
}

static inline struct set *set_get(struct cache *c, uint64_t s) {
  struct set **p = &c->set_pages[s / SET_PAGE];
  if (!*p) *p = xcalloc(page_sets(c, s / SET_PAGE), sizeof **p);
  return &(*p)[s % SET_PAGE];
}

/* Slot i to read: a never-used slot reads as zeros (no line, no flags). */
static inline const struct slot *slot_peek(const struct cache *c, uint64_t i) {
  const uint64_t s = set_of_slot(c, i), w = way_of_slot(c, i);
  const struct set *st = set_peek(c, s);
  return w + st->used >= c->ways ? &st->vec[c->ways - 1 - w] : &ZERO_SLOT;
}

/* The slots a set's vector holds when `used` are used: 0, then powers of two
 * up to the ways. */
static inline uint64_t vec_cap(const struct cache *c, uint64_t used) {
  if (used <= 1) return used;
  const uint64_t p = 1ull << (64 - __builtin_clzll(used - 1));
  return p < c->ways ? p : c->ways;
}

/* Slot i of set st, used. */
static inline struct slot *slot_at(const struct cache *c, struct set *st, uint64_t i) {
  const uint64_t w = way_of_slot(c, i);
  CHECK_GE(w + st->used, c->ways);
  return &st->vec[c->ways - 1 - w];
}

static inline struct slot *slot_get(struct cache *c, uint64_t i) {
  return slot_at(c, set_get(c, set_of_slot(c, i)), i);
}

enum cache_geometry cache_geometry(const struct cache_params *p) {
  if (p->lg2_line < 2 || p->lg2_line > 16) return CACHE_GEOMETRY_LINE;
  uint64_t line = 1ull << p->lg2_line;
  if (p->size_bytes < line) return CACHE_GEOMETRY_SMALL;
  if (p->size_bytes % line) return CACHE_GEOMETRY_PARTIAL;
  uint64_t lines = p->size_bytes >> p->lg2_line;
  if (lines > CACHE_MAX_LINES) return CACHE_GEOMETRY_LINES;
  if (p->ways > lines) return CACHE_GEOMETRY_WAYS_OVER;
  if (p->ways && lines % p->ways) return CACHE_GEOMETRY_WAYS_SPLIT;
  return CACHE_GEOMETRY_OK;
}

const char *cache_params_problem(const struct cache_params *p) {
  static const char *const WHY[] = {NULL,
                                    "the line size must be 4 bytes to 64 KiB",
                                    "the size is smaller than one line",
                                    "the size is not a whole number of lines",
                                    "more than 2^28 lines",
                                    "more ways than lines",
                                    "the ways do not divide the number of lines"};
  return WHY[cache_geometry(p)];
}

static inline uint64_t hash_of(const struct cache *c, uint64_t line) {
  return (line * 0x9E3779B97F4A7C15ull) >> c->table_shift;
}

static void table_insert(struct cache *c, uint64_t line, uint32_t slot) {
  uint64_t i = hash_of(c, line);
  while (c->table[i]) i = (i + 1) & c->table_mask;
  c->table[i] = slot + 1;
}

/* The table holds the valid lines at most half full: it starts small and
 * doubles as lines arrive (lookups answer the same at any size). */
static void table_resize(struct cache *c, unsigned bits) {
  uint32_t *old = c->table;
  uint64_t old_size = old ? c->table_mask + 1 : 0;
  c->table = xcalloc(1ull << bits, sizeof *c->table);
  c->table_mask = (1ull << bits) - 1;
  c->table_shift = 64 - bits;
  for (uint64_t i = 0; i < old_size; i++)
    if (old[i]) table_insert(c, slot_peek(c, old[i] - 1)->line, old[i] - 1);
  free(old);
}

static void table_put(struct cache *c, uint64_t line, uint32_t slot) {
  if (2 * (c->table_used + 1) > c->table_mask + 1) table_resize(c, 64 - c->table_shift + 1);
  c->table_used++;
  table_insert(c, line, slot);
}

static void table_del(struct cache *c, uint64_t line) {
  uint64_t i = hash_of(c, line);
  while (slot_peek(c, c->table[i] - 1)->line != line) i = (i + 1) & c->table_mask;
  c->table_used--;
  /* Backward shift: move later entries of the cluster into the hole when their
   * home position allows it. */
  uint64_t j = i;
  for (;;) {
    c->table[i] = 0;
    for (;;) {
      j = (j + 1) & c->table_mask;
      if (!c->table[j]) return;
      uint64_t home = hash_of(c, slot_peek(c, c->table[j] - 1)->line);
      /* Entry j may fill hole i unless its home lies cyclically in (i, j]. */
      bool stays = i <= j ? (i < home && home <= j) : (i < home || home <= j);
      if (!stays) break;
    }
    c->table[i] = c->table[j];
    i = j;
  }
}

struct cache *cache_create(const struct cache_params *p) {
  CHECK(cache_params_problem(p) == NULL);
  struct cache *c = xcalloc_aligned(64, sizeof *c);
  c->lines = p->size_bytes >> p->lg2_line;
  c->ways = p->ways ? p->ways : c->lines;
  c->sets = c->lines / c->ways;
  c->lg2_ways = 64;
  if ((c->ways & (c->ways - 1)) == 0) c->lg2_ways = (unsigned)__builtin_ctzll(c->ways);
  c->set_mask = (c->sets & (c->sets - 1)) == 0 ? c->sets - 1 : 0;
  if (c->sets == 1) c->set_mask = 0;
  c->scan = c->ways <= SCAN_WAYS;
  c->flat_ok = c->scan && c->lines <= (p->shared ? FLAT_LINES_SHARED : FLAT_LINES);
  const bool sets_pow2 = (c->sets & (c->sets - 1)) == 0; /* set_of_line masks */
  if (c->flat_ok && sets_pow2 && (c->ways == 4 || c->ways == 16)) c->fast_ways = (uint8_t)c->ways;
  if (c->fast_ways == CPK_WAYS) {
    c->packed = true;
    c->fast_ways = 0;
    cpk_init(&c->pk, c->sets);
  }
  c->set_page_count = c->flat_ok ? 0 : (c->sets + SET_PAGE - 1) / SET_PAGE;
  c->set_pages = xcalloc(c->set_page_count ? c->set_page_count : 1, sizeof *c->set_pages);
  if (!c->scan) table_resize(c, 4);
  return c;
}

void cache_destroy(struct cache *c) {
  if (!c) return;
  free(c->ftag);
  cpk_fini(&c->pk);
  free(c->fmeta);
  for (uint64_t i = 0; i < c->set_page_count; i++) {
    if (!c->set_pages[i]) continue;
    for (uint64_t k = 0; k < page_sets(c, i); k++) free(c->set_pages[i][k].vec);
    free(c->set_pages[i]);
  }
  free(c->set_pages);
  free(c->table);
  free(c);
}

uint64_t cache_lines(const struct cache *c) { return c->lines; }

uint64_t cache_host_bytes(const struct cache *c) {
  uint64_t b = sizeof *c + 8 * c->set_page_count + c->vec_bytes;
  for (uint64_t i = 0; i < c->set_page_count; i++)
    b += c->set_pages[i] ? page_sets(c, i) * sizeof(struct set) : 0;
  return b + (c->table ? (c->table_mask + 1) * sizeof *c->table : 0);
}

/* The index in st->vec of line's valid slot, or -1: only the used slots can
 * hold a line (a line is in one slot at most). */
static inline int64_t scan_used(const struct set *st, uint64_t line) {
  for (uint32_t k = 0; k < st->used; k++)
    if (st->vec[k].line == line && (st->vec[k].flags & F_VALID)) return k;
  return -1;
}

#if defined(__SSE2__)
/* Bit k set when tag k of the n (even) at t is key: two tags a compare. */
static inline uint32_t flat_match(const uint64_t *t, uint64_t key, uint64_t n) {
  const __m128i kk = _mm_set1_epi64x((long long)key);
  uint32_t mask = 0;
  for (uint32_t k = 0; k < n; k += 2) {
    __m128i e = _mm_cmpeq_epi32(_mm_loadu_si128((const __m128i *)(t + k)), kk);
    e = _mm_and_si128(e, _mm_shuffle_epi32(e, _MM_SHUFFLE(2, 3, 0, 1)));
    mask |= (uint32_t)_mm_movemask_pd(_mm_castsi128_pd(e)) << k;
  }
  return mask;
}
#endif

/* The index of key among the n (4 or 16) tags at t, or -1 (a line is in one
 * slot at most). SSE2 compares 32-bit halves and packs the results narrower
 * before one movemask, so a tag matches where all the bits of its halves
 * are set: half the instructions of flat_match's two tags a compare. Four
 * tags: words to 16 bits, four bits a tag; eight: on to bytes, two a tag. */
static inline int64_t flat_find_n(const uint64_t *t, uint64_t key, uint64_t n) {
#if defined(__SSE2__)
  const __m128i kk = _mm_set1_epi64x((long long)key);
#define FIND_EQ(i) _mm_cmpeq_epi32(_mm_loadu_si128((const __m128i *)(t + (i))), kk)
  if (n == 4) {
    uint32_t m = (uint32_t)_mm_movemask_epi8(_mm_packs_epi32(FIND_EQ(0), FIND_EQ(2)));
    m &= (m >> 2) & 0x1111u;
    return m ? (int64_t)(__builtin_ctz(m) >> 2) : -1;
  }
  uint64_t m = 0;
  for (uint64_t k = 0; k < n; k += 8) {
    const __m128i lo = _mm_packs_epi32(FIND_EQ(k), FIND_EQ(k + 2));
    const __m128i hi = _mm_packs_epi32(FIND_EQ(k + 4), FIND_EQ(k + 6));
    m |= (uint64_t)(uint32_t)_mm_movemask_epi8(_mm_packs_epi16(lo, hi)) << (2 * k);
  }
#undef FIND_EQ
  m &= (m >> 1) & 0x5555555555555555ull;
  return m ? (int64_t)(__builtin_ctzll(m) >> 1) : -1;
#else
  for (uint64_t k = 0; k < n; k++)
    if (t[k] == key) return (int64_t)k;
  return -1;
#endif
}

/* A flat cache's scan: set s's tags only (one host line for 8 ways), no
 * set or slot read; the index in the set's vector of line's slot, or -1. */
static inline int64_t flat_scan(const struct cache *c, uint64_t s, uint64_t line) {
  const uint64_t *t = ftags(c, s), key = line + 1;
#if defined(__SSE2__)
  /* Two tags a compare, all of the set's, then one branch: a loop that
   * stopped at the matching way mispredicted its exit on nearly every hit. */
  if (!(c->ways & 1)) {
    /* The configured L1s' 4 ways and the L2's 16 unrolled (a loop over a
     * count read at run time cost as many instructions as the compares). */
    const uint32_t mask = c->ways == 4    ? flat_match(t, key, 4)
                          : c->ways == 16 ? flat_match(t, key, 16)
                                          : flat_match(t, key, c->ways);
    return mask ? __builtin_ctz(mask) : -1;
  }
#endif
  for (uint32_t k = 0; k < c->ways; k++)
    if (t[k] == key) return k;
  return -1;
}

uint32_t cache_find(const struct cache *c, uint64_t line) {
  if (c->packed) return pk_slot(line & c->pk.set_mask, pk_find(c, line));
  if (c->flat_ok) {
    if (!c->ftag) return CACHE_NONE;
    const uint64_t s = set_of_line(c, line);
    const int64_t k = flat_scan(c, s, line);
    return slot_no(c, s, k);
  }
  if (c->scan) {
    const uint64_t s = set_of_line(c, line);
    const int64_t k = scan_used(set_peek(c, s), line);
    return slot_no(c, s, k);
  }
  uint64_t i = hash_of(c, line);
  for (;;) {
    uint32_t v = c->table[i];
    if (!v) return CACHE_NONE;
    if (slot_peek(c, v - 1)->line == line) return v - 1;
    i = (i + 1) & c->table_mask;
  }
}

/* Slot x (not in the list) into a hashed set's circular list, not empty,
 * as its head: between the tail and the old head. */
static void list_push(struct cache *c, struct set *st, uint32_t slot, struct slot *x) {
  struct slot *h = slot_at(c, st, st->head);
  const uint32_t tail = h->prev;
  x->prev = tail;
  x->next = st->head;
  slot_at(c, st, tail)->next = slot;
  h->prev = slot;
  st->head = slot;
}

/* Slot (used) to the head of its set's list. */
static void to_head(struct cache *c, struct set *st, uint32_t slot) {
  if (c->scan) {
    slot_at(c, st, slot)->stamp = ++c->uses;
    return;
  }
  if (st->head == slot) return;
  struct slot *x = slot_at(c, st, slot);
  /* The tail becomes the head by turning the circle; another slot is
   * unlinked (its neighbours exist: the list is circular) and pushed. */
  if (slot_at(c, st, st->head)->prev == slot) {
    st->head = slot;
    return;
  }
  slot_at(c, st, x->prev)->next = x->next;
  slot_at(c, st, x->next)->prev = x->prev;
  list_push(c, st, slot, x);
}

/* A flat slot's stamp st made the newest of its set (its state kept), and
 * a line put in a flat slot (its tag tg, its stamp st) as the newest. */
static inline void flat_touch(struct cache *c, uint64_t *st) {
  *st = (*st & FLAT_STATE) | ++c->uses;
}
static inline void flat_put(struct cache *c, uint64_t *tg, uint64_t *st, uint64_t line, bool dirty,
                            bool pending) {
  *st = ++c->uses | (pending ? FLAT_PENDING : 0) | (dirty ? FLAT_DIRTY : 0);
  *tg = line + 1;
}

void cache_touch(struct cache *c, uint32_t slot) {
  if (c->packed) {
    pk_ready(c);
    cpk_touch(&c->pk, pk_set(slot), pk_k(slot));
    return;
  }
  if (c->flat_ok) {
    flat_touch(c, fstamp_get(c, slot));
    return;
  }
  to_head(c, set_get(c, set_of_slot(c, slot)), slot);
}

/* cache_use of a fast_ways cache of W ways (a constant at each call). */
static inline uint32_t fast_use(struct cache *c, uint64_t line, const uint64_t W) {
  if (!c->ftag) return CACHE_NONE;
  const uint64_t s = line & c->set_mask;
  uint64_t *t = c->ftag + 2 * W * s;
  const int64_t k = flat_find_n(t, line + 1, W);
  if (k < 0) return CACHE_NONE;
  flat_touch(c, t + W + k);
  return (uint32_t)(s * W + W - 1 - (uint64_t)k);
}

/* cache_use of a packed cache. */
static inline uint32_t packed_use(struct cache *c, uint64_t line) {
  const int k = pk_find(c, line);
  if (k < 0) return CACHE_NONE;
  const uint64_t s = line & c->pk.set_mask;
  cpk_touch(&c->pk, s, (unsigned)k);
  return pk_slot(s, k);
}

uint32_t cache_use(struct cache *c, uint64_t line) {
  if (c->fast_ways == 4) return fast_use(c, line, 4);
  if (c->packed) return packed_use(c, line);
  if (c->fast_ways == 16) return fast_use(c, line, 16);
  if (!c->scan) {
    const uint32_t slot = cache_find(c, line);
    if (slot != CACHE_NONE) cache_touch(c, slot);
    return slot;
  }
  const uint64_t s = set_of_line(c, line);
  if (c->flat_ok) {
    if (!c->ftag) return CACHE_NONE;
    const int64_t k = flat_scan(c, s, line);
    if (k < 0) return CACHE_NONE;
    flat_touch(c, fstamps(c, s) + k);
    return slot_no(c, s, k);
  }
  /* A paged scanned set: only its used slots can hold the line. */
  struct set *page = c->set_pages[s / SET_PAGE];
  if (!page) return CACHE_NONE;
  struct set *st = &page[s % SET_PAGE];
  const int64_t k = scan_used(st, line);
  if (k < 0) return CACHE_NONE;
  st->vec[k].stamp = ++c->uses;
  return slot_no(c, s, k);
}

void cache_prefetch(const struct cache *c, uint64_t line) {
  if (c->packed && c->pk.tag) __builtin_prefetch(c->pk.tag + CPK_WAYS * (line & c->pk.set_mask));
}

/* The oldest stamp not pending among n slots from v (stamps are distinct
 * but for the never-used slots' zeros, the first of which is the set's
 * lowest-ranked never-used one): its index in v, or -1. */
static inline int64_t oldest_free(const struct slot *v, uint64_t n) {
  int64_t best = -1;
  uint64_t oldest = UINT64_MAX;
  for (uint64_t k = 0; k < n; k++)
    if (!(v[k].flags & F_PENDING) && v[k].stamp < oldest) {
      oldest = v[k].stamp;
      best = (int64_t)k;
    }
  return best;
}

/* The index of the least of n stamps, dirtiness aside, or -1 when it is
 * pending: a pending one's top bit puts it after every other, so the least
 * is pending only when all are. Called with the configured caches' way
 * counts as constants (unrolled). */
static inline int64_t flat_oldest(const uint64_t *v, uint64_t n) {
  uint64_t least = v[0] & ~FLAT_DIRTY;
  int64_t k = 0;
  for (uint64_t j = 1; j < n; j++)
    if ((v[j] & ~FLAT_DIRTY) < least) {
      least = v[j] & ~FLAT_DIRTY;
      k = (int64_t)j;
    }
  return least & FLAT_PENDING ? -1 : k;
}

/* flat_oldest of a set's stamps v. */
static inline int64_t flat_victim(const struct cache *c, const uint64_t *v) {
  return c->ways == 4    ? flat_oldest(v, 4)
         : c->ways == 16 ? flat_oldest(v, 16)
                         : flat_oldest(v, c->ways);
}

uint32_t cache_victim(const struct cache *c, uint64_t line) {
  uint64_t s = set_of_line(c, line);
  if (c->packed) return pk_slot(s, c->pk.tag ? cpk_victim(&c->pk, s) : 0);
  if (c->flat_ok) {
    /* Never-used slots are zeros: the first of them is the paged path's
     * choice too (a never-used slot first, the highest-ranked way). */
    if (!c->ftag) return (uint32_t)(s * c->ways + c->ways - 1);
    return slot_no(c, s, flat_victim(c, fstamps(c, s)));
  }
  const struct set *st = set_peek(c, s);
  /* A never-used slot first: the highest of them is the list's tail. */
  if (st->used < c->ways) return (uint32_t)(s * c->ways + (c->ways - st->used) - 1);
  if (c->scan) {
    /* The oldest stamp not pending (stamps are distinct: one answer). */
    const int64_t k = oldest_free(st->vec, c->ways);
    return slot_no(c, s, k);
  }
  /* From the tail (the head's prev) towards the head. */
  const uint32_t head = st->head;
  for (uint32_t i = st->vec[in_set(c, head)].prev;;) {
    const struct slot *x = &st->vec[in_set(c, i)];
    if (!(x->flags & F_PENDING)) return i;
    if (i == head) return CACHE_NONE;
    i = x->prev;
  }
}

/* A flat slot is valid when it holds a tag (nothing invalidates a line). */
bool cache_valid(const struct cache *c, uint32_t slot) {
  if (c->packed) return c->pk.tag && c->pk.tag[CPK_WAYS * pk_set(slot) + pk_k(slot)];
  if (c->flat_ok) return c->ftag && *ftag_of(c, slot);
  return slot_peek(c, slot)->flags & F_VALID;
}
uint64_t cache_line(const struct cache *c, uint32_t slot) {
  if (c->packed) return cache_valid(c, slot) ? cpk_line(&c->pk, pk_set(slot), pk_k(slot)) : 0;
  if (c->flat_ok) {
    const uint64_t t = c->ftag ? *ftag_of(c, slot) : 0;
    return t ? t - 1 : 0;
  }
  return slot_peek(c, slot)->line;
}
bool cache_dirty(const struct cache *c, uint32_t slot) {
  if (c->packed) return pk_bit(c, slot, false);
  if (c->flat_ok) return fstamp_peek(c, slot) & FLAT_DIRTY;
  return slot_peek(c, slot)->flags & F_DIRTY;
}
bool cache_pending(const struct cache *c, uint32_t slot) {
  if (c->packed) return pk_bit(c, slot, true);
  if (c->flat_ok) return fstamp_peek(c, slot) & FLAT_PENDING;
  return slot_peek(c, slot)->flags & F_PENDING;
}
void cache_set_dirty(struct cache *c, uint32_t slot) {
  if (c->packed) pk_set_bit(c, slot, false, true);
  else if (c->flat_ok) *fstamp_get(c, slot) |= FLAT_DIRTY;
  else slot_get(c, slot)->flags |= F_DIRTY;
}

void cache_set_pending(struct cache *c, uint32_t slot, bool pending) {
  if (c->packed) {
    pk_set_bit(c, slot, true, pending);
    return;
  }
  if (c->flat_ok) {
    uint64_t *st = fstamp_get(c, slot);
    *st = pending ? *st | FLAT_PENDING : *st & ~FLAT_PENDING;
    return;
  }
  struct slot *x = slot_get(c, slot);
  if (pending) x->flags |= F_PENDING;
  else x->flags &= (uint8_t)~F_PENDING;
}

uint32_t cache_word(const struct cache *c, uint32_t slot) {
  return c->flat_ok ? fmeta_peek(c, slot)->word : slot_peek(c, slot)->word;
}
void cache_set_word(struct cache *c, uint32_t slot, uint32_t v) {
  if (c->flat_ok) fmeta_get(c, slot)->word = v;
  else slot_get(c, slot)->word = v;
}
uint8_t cache_byte(const struct cache *c, uint32_t slot) {
  return c->flat_ok ? fmeta_peek(c, slot)->byte : slot_peek(c, slot)->byte;
}
void cache_set_byte(struct cache *c, uint32_t slot, uint8_t v) {
  if (c->flat_ok) fmeta_get(c, slot)->byte = v;
  else slot_get(c, slot)->byte = v;
}

/* cache_fill of a fast_ways cache of W ways (a constant at each call). */
static inline bool fast_fill(struct cache *c, uint64_t line, bool dirty, const uint64_t W) {
  if (!c->ftag) flat_make(c);
  uint64_t *t = c->ftag + 2 * W * (line & c->set_mask);
  int64_t k = flat_find_n(t, line + 1, W);
  if (k >= 0) {
    flat_touch(c, t + W + k);
    return true;
  }
  k = flat_oldest(t + W, W);
  if (k >= 0) flat_put(c, t + k, t + W + k, line, dirty, false);
  return false;
}

/* cache_fill of a packed cache that can hold line. */
static inline bool packed_fill(struct cache *c, uint64_t line, bool dirty) {
  pk_ready(c);
  const uint64_t s = line & c->pk.set_mask;
  int k = cpk_find(&c->pk, s, cpk_key(&c->pk, line));
  if (k >= 0) {
    cpk_touch(&c->pk, s, (unsigned)k);
    return true;
  }
  k = cpk_victim(&c->pk, s);
  if (k >= 0) cpk_put(&c->pk, s, (unsigned)k, line, dirty, false);
  return false;
}

bool cache_fill(struct cache *c, uint64_t line, bool dirty) {
  if (c->fast_ways == 4) return fast_fill(c, line, dirty, 4);
  if (c->packed) {
    if (cpk_fits(&c->pk, line)) return packed_fill(c, line, dirty);
    pk_widen(c);
  }
  if (c->fast_ways == 16) return fast_fill(c, line, dirty, 16);
  if (c->flat_ok) {
    /* cache_use, cache_victim and cache_install in one look at the set. */
    if (!c->ftag) flat_make(c);
    const uint64_t s = set_of_line(c, line);
    uint64_t *st = fstamps(c, s);
    int64_t k = flat_scan(c, s, line);
    if (k >= 0) {
      flat_touch(c, st + k);
      return true;
    }
    k = flat_victim(c, st);
    if (k >= 0) flat_put(c, ftags(c, s) + k, st + k, line, dirty, false);
    return false;
  }
  if (cache_use(c, line) != CACHE_NONE) return true;
  const uint32_t v = cache_victim(c, line);
  if (v != CACHE_NONE) cache_install(c, v, line, dirty, false);
  return false;
}

void cache_install(struct cache *c, uint32_t slot, uint64_t line, bool dirty, bool pending) {
  const uint64_t s = set_of_slot(c, slot);
  CHECK_EQ(s, set_of_line(c, line));
  if (c->packed && !cpk_fits(&c->pk, line)) pk_widen(c);
  if (c->packed) {
    pk_ready(c);
    CHECK(!(c->pk.set[s].pending >> pk_k(slot) & 1));
    cpk_put(&c->pk, s, pk_k(slot), line, dirty, pending);
    return;
  }
  if (c->flat_ok) {
    /* A slot keeps its word and byte. */
    uint64_t *st = fstamp_get(c, slot);
    CHECK(!(*st & FLAT_PENDING));
    flat_put(c, ftag_of(c, slot), st, line, dirty, pending);
    return;
  }
  struct set *st = set_get(c, s);
  const uint64_t in_set = slot - s * c->ways;
  struct slot *x;
  if (in_set < c->ways - st->used) {
    /* A never-used slot: only the lowest-ranked one (cache_victim's) may be
     * taken; it joins the list at the head. */
    CHECK_EQ(in_set, c->ways - st->used - 1);
    const uint64_t cap = vec_cap(c, st->used);
    if (st->used == cap) {
      const uint64_t grown = vec_cap(c, st->used + 1);
      st->vec = xrealloc(st->vec, grown * sizeof *st->vec);
      c->vec_bytes += (grown - cap) * sizeof *st->vec;
    }
    x = &st->vec[st->used];
    memset(x, 0, sizeof *x);
    if (c->scan) {
      x->stamp = ++c->uses;
    } else if (st->used) {
      list_push(c, st, slot, x);
    } else {
      x->prev = x->next = slot;
      st->head = slot;
    }
    st->used++;
  } else {
    x = slot_at(c, st, slot);
    CHECK(!(x->flags & F_PENDING));
    if (!c->scan && (x->flags & F_VALID)) table_del(c, x->line);
    to_head(c, st, slot);
  }
  x->line = line;
  x->flags = (uint8_t)(F_VALID | (dirty ? F_DIRTY : 0) | (pending ? F_PENDING : 0));
  if (!c->scan) table_put(c, line, slot);
}
