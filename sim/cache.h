/* One cache: set-associative or fully associative, LRU within a set, lines of
 * 2^lg2_line bytes. Tags and state only (values live on the host), allocated
 * as lines arrive: host memory follows the lines a run touches (about 48
 * bytes each, the allocator's share included), not the configured size, so a
 * 16 GiB cache costs what a small one does on the same work (a cache of at
 * most 1024 lines, or a shared one of at most 2^17, and at most 16 ways is
 * one block of 16 bytes a line from its first line on, its pages taken by the
 * host as they are written, 2 MiB at most, plus 8 bytes a line once the owner
 * keeps a word or a byte; of exactly 16 ways and a power-of-two count of
 * sets, 5 bytes a line, sim/cache_packed.h). A line may be pending
 * (allocated, its fill not yet back): it is never chosen as a victim. The
 * caller decides what a hit, a miss or an eviction costs; this module only
 * keeps the contents. Used for the L1s and the L2. */
#ifndef RTSIM_SIM_CACHE_H
#define RTSIM_SIM_CACHE_H

#include <stdbool.h>
#include <stdint.h>

struct cache_params {
  uint64_t size_bytes; /* a multiple of the line; >= one line */
  uint32_t ways;       /* 0: fully associative; else divides the line count */
  unsigned lg2_line;
  /* One shared cache (an L2): kept flat up to 2^17 lines (2 MiB of host
   * memory, 3 MiB with the owner's words and bytes) for a faster find.
   * false (per-core caches): flat up to 1024 lines only, so many cores with
   * large, sparsely used caches stay cheap. */
  bool shared;
};

/* What is wrong with a cache's shape, checked in this order (the one rule for
 * every cache: cache_create's check and the machine config's). */
enum cache_geometry {
  CACHE_GEOMETRY_OK,
  CACHE_GEOMETRY_LINE,       /* lg2_line outside 2..16 */
  CACHE_GEOMETRY_SMALL,      /* smaller than one line */
  CACHE_GEOMETRY_PARTIAL,    /* not a whole number of lines */
  CACHE_GEOMETRY_LINES,      /* more than CACHE_MAX_LINES lines */
  CACHE_GEOMETRY_WAYS_OVER,  /* more ways than lines */
  CACHE_GEOMETRY_WAYS_SPLIT, /* the ways do not divide the lines */
};
#define CACHE_MAX_LINES (1ull << 28)
enum cache_geometry cache_geometry(const struct cache_params *p);
/* NULL if p is usable, else a one-line description of what is wrong. */
const char *cache_params_problem(const struct cache_params *p);

struct cache;

/* p must pass cache_params_problem (CHECKed). Caller destroys. */
struct cache *cache_create(const struct cache_params *p);
void cache_destroy(struct cache *c); /* NULL ok */

#define CACHE_NONE UINT32_MAX

/* The slot holding line (valid or pending), or CACHE_NONE. Changes nothing. */
uint32_t cache_find(const struct cache *c, uint64_t line);
/* Make slot the most recently used of its set. */
void cache_touch(struct cache *c, uint32_t slot);
/* cache_find then, on a hit, cache_touch, in one look at the set: the slot
 * (now the most recently used), or CACHE_NONE (nothing changed). */
uint32_t cache_use(struct cache *c, uint64_t line);

/* Ask the host to bring line's set into its caches, for a find or a use
 * soon after (the L2's, when a load misses the L1): a packed cache's
 * tags; other layouts ignore it. Changes nothing. */
void cache_prefetch(const struct cache *c, uint64_t line);

/* The slot line would replace: the least recently used slot of its set that is
 * not pending (an invalid slot first), or CACHE_NONE if every slot is pending. */
uint32_t cache_victim(const struct cache *c, uint64_t line);
/* What a slot holds: valid (a line), its number, dirty, pending. */
bool cache_valid(const struct cache *c, uint32_t slot);
uint64_t cache_line(const struct cache *c, uint32_t slot);
bool cache_dirty(const struct cache *c, uint32_t slot);
bool cache_pending(const struct cache *c, uint32_t slot);
/* Put line into slot (from cache_victim; its old line is dropped: write it back
 * first if dirty) as the most recently used, with the given state. */
void cache_install(struct cache *c, uint32_t slot, uint64_t line, bool dirty, bool pending);
void cache_set_dirty(struct cache *c, uint32_t slot);
/* cache_use; on a miss, cache_install of line (not pending, dirty as given)
 * into cache_victim's slot, when the set has one. True on a hit. */
bool cache_fill(struct cache *c, uint64_t line, bool dirty);
void cache_set_pending(struct cache *c, uint32_t slot, bool pending);
/* A word and a byte the owner keeps with each slot (the L2: the head of a
 * pending line's waiter list, the class of the access that missed); 0 until
 * set, and kept across installs. */
uint32_t cache_word(const struct cache *c, uint32_t slot);
void cache_set_word(struct cache *c, uint32_t slot, uint32_t v);
uint8_t cache_byte(const struct cache *c, uint32_t slot);
void cache_set_byte(struct cache *c, uint32_t slot, uint8_t v);

/* Lines the cache holds at most. */
uint64_t cache_lines(const struct cache *c);
/* Host bytes it holds now: page tables, the pages written so far, the table. */
uint64_t cache_host_bytes(const struct cache *c);

#endif
