/* One-pass LRU stack analyser: misses and dirty writebacks of every fully
 * associative LRU cache of 2^k bytes (k = lg2_min..lg2_max) with 2^lg2_line-byte
 * lines, from a single pass over a stream of line accesses, per data class.
 * Works because LRU has the inclusion property (Mattson et al. 1970): a cache of
 * C lines holds exactly the C most recently used lines, so one recency stack
 * with a boundary marker at each capacity answers for all sizes at once.
 * Write-back, write-allocate caches. A store that writes part of a line fetches
 * it on a miss (a miss); a store that writes the whole line allocates it without
 * fetching (nothing of the old line survives, so nothing is read): it is not a
 * miss, though the line now takes its place in every cache, dirty. Allocation
 * still happens in every size, so the stack (inclusion) property holds. */
#ifndef RTSIM_SIM_LRU_STACK_H
#define RTSIM_SIM_LRU_STACK_H

#include <stdbool.h>
#include <stdint.h>

#include "sim/mem.h"

/* At most this many cache sizes (one dirty bit per size in a 32-bit mask). */
#define LRU_STACK_MAX_SIZES 32
/* The largest cache holds at most 2^LRU_STACK_MAX_LG2_LINES lines. */
#define LRU_STACK_MAX_LG2_LINES 24

/* Cache geometry: line 2^lg2_line bytes, sizes 2^lg2_min .. 2^lg2_max bytes. */
struct lru_stack_params {
  unsigned lg2_line; /* default 6: 64-byte lines */
  unsigned lg2_min;  /* default 10: 1 KB */
  unsigned lg2_max;  /* default 22: 4 MB (13 sizes, as in the paper) */
};

/* The paper's geometry: 64-byte lines, 1 KB .. 4 MB. */
struct lru_stack_params lru_stack_params_default(void);

/* NULL if p is usable, else a constant one-line description of what is wrong
 * (for the config reader to wrap in a struct err with the value's position). */
const char *lru_stack_params_problem(const struct lru_stack_params *p);

/* What an access does to its line. */
enum lru_stack_op {
  LRU_STACK_READ = 0,      /* load: a miss fetches the line */
  LRU_STACK_WRITE = 1,     /* store to part of the line: a miss fetches it first */
  LRU_STACK_WRITE_LINE = 2 /* store of the whole line: a miss allocates, no fetch */
};

struct lru_stack;

/* Create an empty analyser (all caches cold). p must pass
 * lru_stack_params_problem (CHECKed). Caller destroys. */
struct lru_stack *lru_stack_create(const struct lru_stack_params *p);
void lru_stack_destroy(struct lru_stack *ls); /* NULL ok */

/* One access to one line. line is a LINE NUMBER (byte address >> lg2_line), any
 * 64-bit value; the caller splits multi-line requests (mem_functional does).
 * cls < MEM_CLASS_MAX (CHECKed). Cost: O(1) for a repeat of the most recent
 * line; else one hash probe, a list move and one step per size that misses. */
void lru_stack_access(struct lru_stack *ls, uint64_t line, enum lru_stack_op op, unsigned cls);

/* A packed access for lru_stack_access_batch: line << 5 | cls << 2 | op. The
 * line must be below 2^59 (a byte address over lines of 32 bytes or more) and
 * cls below 8. */
#define LRU_STACK_REC(line, op, cls) ((uint64_t)(line) << 5 | (uint64_t)(cls) << 2 | (uint64_t)(op))

/* The n accesses rec[0..n) (LRU_STACK_REC), in order: exactly n calls of
 * lru_stack_access, faster because the hash slots and nodes of the accesses a
 * few places ahead are fetched into the host cache while earlier ones run. */
void lru_stack_access_batch(struct lru_stack *ls, const uint64_t *rec, uint32_t n);

/* Count, without passing them one by one, `loads` + `stores` accesses of class
 * cls that the caller filtered out because each repeated the most recent line
 * with that line's last class, and each store found it dirty already (a store
 * to the top line makes it dirty in every size). Such an access is a hit in
 * every size and changes no recency order, dirty state or class: only access
 * counters move, so the results are exactly those of lru_stack_access. Call it
 * before reading results; the caller is trusted on the condition. */
void lru_stack_count_repeats(struct lru_stack *ls, unsigned cls, uint64_t loads, uint64_t stores);

/* End of trace: walk the lines held (O(lines)) to count the lines still dirty
 * in each cache (dirty_at_end) and the writebacks not yet counted (evictions are
 * counted lazily, when a line is next seen). Results call it themselves when
 * accesses came after the last call, so it is optional; accesses may go on. */
void lru_stack_finish(struct lru_stack *ls);

/* Counters of one cache size. Every size sees every access, so accesses and
 * stores equal the analyser totals; they are repeated here for tidy output. */
struct lru_stack_size_stats {
  uint64_t capacity_bytes;
  uint64_t accesses[MEM_CLASS_MAX]; /* line accesses, by class of the access */
  uint64_t stores[MEM_CLASS_MAX];   /* of which stores */
  /* Lines fetched from DRAM, by class of the access that missed (LRU_STACK_READ or
   * LRU_STACK_WRITE; an LRU_STACK_WRITE_LINE miss fetches nothing and is not counted). */
  uint64_t misses[MEM_CLASS_MAX];
  /* Dirty lines evicted (written back), by class of the line's last access. */
  uint64_t writebacks[MEM_CLASS_MAX];
  /* Lines still dirty in this cache at the results snapshot, same attribution. */
  uint64_t dirty_at_end[MEM_CLASS_MAX];
};

struct lru_stack_results {
  struct lru_stack_params params;
  unsigned size_count;              /* lg2_max - lg2_min + 1 */
  uint64_t accesses[MEM_CLASS_MAX]; /* line accesses by class */
  uint64_t stores[MEM_CLASS_MAX];
  struct lru_stack_size_stats size[LRU_STACK_MAX_SIZES]; /* [k - lg2_min] */
};

/* Fill out with every counter, exact for the accesses so far (dirty_at_end:
 * lines dirty now). Cost O(sizes^2 * classes), plus lru_stack_finish if stale. */
void lru_stack_get_results(struct lru_stack *ls, struct lru_stack_results *out);

/* Single counters; size_index = k - lg2_min, in [0, size_count). writebacks may
 * run lru_stack_finish (hence not const). */
unsigned lru_stack_size_count(const struct lru_stack *ls);
uint64_t lru_stack_misses(const struct lru_stack *ls, unsigned size_index, unsigned cls);
uint64_t lru_stack_writebacks(struct lru_stack *ls, unsigned size_index, unsigned cls);

/* Lines currently held (those of the largest cache). */
uint64_t lru_stack_lines_held(const struct lru_stack *ls);

/* Verify every internal invariant (list, segments, boundaries, dirty state,
 * hash table) with CHECK. O(lines + table slots): for tests, not for runs. */
void lru_stack_check_invariants(const struct lru_stack *ls);

/* Host micro-benchmark for `rtsim bench`: feed `accesses` line accesses of a
 * mixed trace (70% a 20K-line hot set walked with locality, 30% a stream of
 * fresh lines, 25% stores, all classes) through a default 13-size stack.
 * Returns line accesses per second of wall time spent inside the analyser
 * (trace generation excluded). A host measurement: never part of a result. */
double lru_stack_bench(uint64_t accesses, uint64_t seed);

#endif
