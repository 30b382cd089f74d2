/* One-pass LRU stack analyser for all fully associative cache sizes.
 * One recency list (most recent first) holds the lines of the largest cache.
 * Size i holds cap[i] lines; bound[i] is the node at depth cap[i] (the last line
 * size i holds), 0 while fewer lines exist. A node's segment is the smallest
 * size holding it. Misses and writebacks are counted lazily (see the struct),
 * so a boundary sliding past a node only rewrites that node's segment. */
#include "sim/lru_stack.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "sim/err.h"

/* 24 bytes, the line key included, so the hash table holds 4-byte node
 * indices only (a smaller table misses the host cache less; the node is read
 * anyway). Node 0 is the list sentinel: node[0].next is the top, node[0].prev
 * the bottom.
 * Dirty state: a line is dirty in size i iff it was stored to after it last
 * entered size i. Loads at segment s re-fetch it clean into sizes < s, so the
 * dirty sizes are always a suffix [dfrom, n): one byte holds the whole mask. */
struct lru_node {
  uint64_t line;
  uint32_t prev, next;
  uint32_t slot; /* index of this line's hash slot */
  uint8_t seg;   /* smallest size index holding the line */
  uint8_t dfrom; /* dirty in sizes >= dfrom as of its last access; n = clean */
  uint8_t cls;   /* class of the line's last access */
  uint8_t unused;
};

struct lru_stack {
  struct lru_stack_params p;
  unsigned nsz;                        /* number of sizes, n */
  uint32_t cap[LRU_STACK_MAX_SIZES];   /* lines held by size i */
  uint32_t bound[LRU_STACK_MAX_SIZES]; /* node at depth cap[i], 0 if none yet */
  uint32_t count, max_lines;           /* lines held; cap[n - 1] */
  uint64_t top_line;                   /* line of node[0].next when count > 0 */
  struct lru_node *node;               /* [max_lines + 1] */
  uint32_t *slot;                      /* [mask + 1]: node index, 0 = empty (open addressing) */
  uint64_t mask;
  unsigned shift; /* 64 - log2(slots) */
  /* hist[s][c]: fetching accesses of class c whose line was in segment s
   * (s == n: not held at all). Size i misses exactly when s > i, so misses are suffix sums:
   * one increment per access instead of one per missing size. */
  uint64_t hist[LRU_STACK_MAX_SIZES + 1][MEM_CLASS_MAX];
  /* Writebacks, counted when the line is next seen (its next access, its fall
   * off the bottom, or the results walk): a line dirty in sizes >= d that is
   * found in segment s was evicted dirty from sizes d..s-1 meanwhile. Ranges go
   * into a difference array: wbdiff[d]++, wbdiff[s]--; prefix sums at the end. */
  int64_t wbdiff[LRU_STACK_MAX_SIZES + 1][MEM_CLASS_MAX];
  uint64_t accesses[MEM_CLASS_MAX], stores[MEM_CLASS_MAX];
  uint64_t total; /* accesses, for the snapshot below */
  /* Snapshot of the lines held, taken by lru_stack_finish at total == snap_at. */
  bool snap_valid;
  uint64_t snap_at;
  uint64_t pending_wb[LRU_STACK_MAX_SIZES][MEM_CLASS_MAX];
  uint64_t dirty_end[LRU_STACK_MAX_SIZES][MEM_CLASS_MAX];
};

struct lru_stack_params lru_stack_params_default(void) {
  struct lru_stack_params p = {6, 10, 22};
  return p;
}

const char *lru_stack_params_problem(const struct lru_stack_params *p) {
  if (p->lg2_line > 20) return "lg2_line must be at most 20 (1 MB lines)";
  if (p->lg2_min < p->lg2_line) return "the smallest cache must hold at least one line";
  if (p->lg2_max < p->lg2_min) return "the largest cache size is below the smallest";
  if (p->lg2_max - p->lg2_min + 1 > LRU_STACK_MAX_SIZES) return "at most 32 cache sizes";
  if (p->lg2_max - p->lg2_line > LRU_STACK_MAX_LG2_LINES)
    return "the largest cache may hold at most 2^24 lines";
  return NULL;
}

/* Home slot of a line: fold high bits into low ones (sparse 64-bit addresses
 * differing only in high bits must still spread), multiply, keep the top bits.
 * NOTE: mapping groups of consecutive lines to one host cache line of slots was
 * tried: it lengthened linear-probe runs and lost ~10% on lru_stack_bench. */
static inline uint64_t slot_of(const struct lru_stack *ls, uint64_t line) {
  uint64_t g = line ^ (line >> 29);
  g *= 0x9E3779B97F4A7C15ull;
  return g >> ls->shift;
}

struct lru_stack *lru_stack_create(const struct lru_stack_params *p) {
  CHECK(lru_stack_params_problem(p) == NULL);
  struct lru_stack *ls = xcalloc(1, sizeof *ls);
  ls->p = *p;
  ls->nsz = p->lg2_max - p->lg2_min + 1;
  for (unsigned i = 0; i < ls->nsz; i++) ls->cap[i] = UINT32_C(1) << (p->lg2_min + i - p->lg2_line);
  ls->max_lines = ls->cap[ls->nsz - 1];
  ls->node = xcalloc((unsigned long long)ls->max_lines + 1, sizeof *ls->node);
  /* Load factor at most 1/4 (the table never holds more than max_lines keys:
   * the bottom line leaves before a new one enters): short probe runs, and at
   * 4 bytes a slot the table is still only 1 MB for 4 MB of cache. */
  unsigned bits = 1;
  while ((UINT64_C(1) << bits) < 4 * (uint64_t)ls->max_lines) bits++;
  ls->mask = (UINT64_C(1) << bits) - 1;
  ls->shift = 64 - bits;
  ls->slot = xcalloc(ls->mask + 1, sizeof *ls->slot);
  return ls;
}

void lru_stack_destroy(struct lru_stack *ls) {
  if (!ls) return;
  free(ls->node);
  free(ls->slot);
  free(ls);
}

/* Empty slot i; backward-shift deletion keeps every probe chain unbroken
 * without tombstones (linear probing). Moved keys tell their nodes. */
static void table_delete(struct lru_stack *ls, uint64_t i) {
  uint32_t *t = ls->slot;
  uint64_t j = i;
  for (;;) {
    j = (j + 1) & ls->mask;
    if (t[j] == 0) break;
    uint64_t home = slot_of(ls, ls->node[t[j]].line);
    /* Move j back into the hole at i unless its home lies cyclically in (i, j]. */
    if (((j - home) & ls->mask) >= ((j - i) & ls->mask)) {
      t[i] = t[j];
      ls->node[t[i]].slot = (uint32_t)i;
      i = j;
    }
  }
  t[i] = 0;
}

static inline void list_unlink(struct lru_node *nd, uint32_t p) {
  nd[nd[p].prev].next = nd[p].next;
  nd[nd[p].next].prev = nd[p].prev;
}

static inline void list_push_top(struct lru_node *nd, uint32_t p) {
  uint32_t top = nd[0].next;
  nd[p].prev = 0;
  nd[p].next = top;
  nd[top].prev = p;
  nd[0].next = p;
}

/* The line at each boundary i < n moves one deeper: it leaves size i. */
static inline void slide_bounds(struct lru_stack *ls, unsigned n) {
  struct lru_node *nd = ls->node;
  for (unsigned i = 0; i < n; i++) {
    struct lru_node *v = &nd[ls->bound[i]];
    v->seg = (uint8_t)(i + 1);
    ls->bound[i] = v->prev;
    /* The next access will likely slide the new boundary: fetch it now. */
    __builtin_prefetch(&nd[v->prev]);
  }
}

/* A line last seen dirty in sizes >= d is now found in segment s (s == n: it
 * left every cache): it was evicted dirty from sizes d..s-1 in between. */
static inline void count_evictions(struct lru_stack *ls, unsigned d, unsigned s, unsigned cls) {
  if (d < s) {
    ls->wbdiff[d][cls]++;
    ls->wbdiff[s][cls]--;
  }
}

/* One access; home is slot_of(line), computed by the caller. */
static inline __attribute__((always_inline)) void
access_one(struct lru_stack *ls, uint64_t line, enum lru_stack_op op, unsigned cls, uint64_t home) {
  CHECK_LT(cls, MEM_CLASS_MAX);
  CHECK_LE(op, LRU_STACK_WRITE_LINE);
  const bool is_store = op != LRU_STACK_READ;
  /* Misses are counted in hist: a whole-line store never fetches. */
  const unsigned fetch = op != LRU_STACK_WRITE_LINE;
  ls->accesses[cls]++;
  ls->stores[cls] += is_store;
  ls->total++;
  struct lru_node *nd = ls->node;
  /* Fast path: the most recent line again (consecutive accesses to a line are
   * common in real traces). A hit everywhere; nothing moves. */
  if (line == ls->top_line && ls->count) {
    struct lru_node *v = &nd[nd[0].next];
    ls->hist[0][cls]++;
    if (is_store) v->dfrom = 0;
    v->cls = (uint8_t)cls;
    return;
  }
  ls->top_line = line;
  uint32_t *t = ls->slot;
  uint64_t h = home;
  while (t[h] != 0) {
    uint32_t p = t[h];
    struct lru_node *v = &nd[p];
    if (v->line == line) {
      /* Hit in every size from its segment s up; miss in sizes below s. */
      unsigned s = v->seg;
      ls->hist[s][cls] += fetch;
      count_evictions(ls, v->dfrom, s, v->cls);
      v->dfrom = is_store ? 0 : (uint8_t)(v->dfrom > s ? v->dfrom : s);
      v->cls = (uint8_t)cls;
      /* The line above p takes its place at depth cap[s] if p was boundary s. */
      if (ls->bound[s] == p) ls->bound[s] = v->prev;
      list_unlink(nd, p);
      list_push_top(nd, p);
      v->seg = 0;
      slide_bounds(ls, s);
      return;
    }
    h = (h + 1) & ls->mask;
  }

  /* Miss in every size. */
  unsigned n = ls->nsz;
  ls->hist[n][cls] += fetch;
  uint32_t p;
  if (ls->count == ls->max_lines) {
    /* The bottom line leaves every cache. Reuse its node. */
    p = nd[0].prev;
    count_evictions(ls, nd[p].dfrom, n, nd[p].cls);
    list_unlink(nd, p);
    table_delete(ls, nd[p].slot);
    ls->count--;
    ls->bound[n - 1] = 0;
    /* Deletion may have shifted slots: find the insertion point again. */
    h = slot_of(ls, line);
    while (t[h] != 0) h = (h + 1) & ls->mask;
    __builtin_prefetch(&nd[nd[0].prev]); /* the next bottom */
  } else {
    p = ls->count + 1;
  }
  t[h] = p;
  nd[p].line = line;
  nd[p].slot = (uint32_t)h;
  nd[p].dfrom = is_store ? 0 : (uint8_t)n;
  nd[p].seg = 0;
  nd[p].cls = (uint8_t)cls;
  list_push_top(nd, p);
  /* Established boundaries (cap <= lines before this one) slide one deeper; the
   * first size that just filled up gets its boundary at the bottom. */
  unsigned k = 0;
  if (n > 1 && ls->count >= ls->cap[n - 2])
    k = n - 1; /* the usual case once warm: all but the largest (count < max here) */
  else
    while (k < n && ls->cap[k] <= ls->count) k++;
  slide_bounds(ls, k);
  if (k < n && ls->cap[k] == ls->count + 1) ls->bound[k] = nd[0].prev;
  ls->count++;
}

void lru_stack_access(struct lru_stack *ls, uint64_t line, enum lru_stack_op op, unsigned cls) {
  access_one(ls, line, op, cls, slot_of(ls, line));
}

/* How far ahead the batch fetches an access's home slot, and its node (the one
 * the home slot names, usually the line's own). Every lookup misses the host
 * cache once the stack outgrows it (a few hundred KB): this overlaps those
 * misses. The fetches are hints only: a slot or node that changes before its
 * access is merely fetched for nothing. */
#define LRU_PF_SLOT 16u
#define LRU_PF_NODE 8u

/* Below this many lines (a footprint of about 200 KiB: nodes and slots) the
 * stack stays in the host's L2 and the fetches ahead would only cost
 * instructions (a fifth more an access): the batch then runs plain. */
#define LRU_PF_MIN_LINES 8192u

void lru_stack_access_batch(struct lru_stack *ls, const uint64_t *rec, uint32_t n) {
  if (ls->max_lines < LRU_PF_MIN_LINES) {
    for (uint32_t i = 0; i < n; i++) {
      const uint64_t r = rec[i], line = r >> 5;
      access_one(ls, line, (enum lru_stack_op)(r & 3u), (unsigned)(r >> 2) & 7u, slot_of(ls, line));
    }
    return;
  }
  /* home[i % LRU_PF_SLOT]: the home slot of access i, from i - LRU_PF_SLOT on. */
  uint64_t home[LRU_PF_SLOT];
  for (uint32_t i = 0; i < n && i < LRU_PF_SLOT; i++) {
    home[i] = slot_of(ls, rec[i] >> 5);
    __builtin_prefetch(&ls->slot[home[i]]);
  }
  for (uint32_t i = 0; i < n; i++) {
    const uint64_t h = home[i % LRU_PF_SLOT];
    if (i + LRU_PF_SLOT < n) {
      const uint64_t a = slot_of(ls, rec[i + LRU_PF_SLOT] >> 5);
      home[i % LRU_PF_SLOT] = a;
      __builtin_prefetch(&ls->slot[a]);
    }
    if (i + LRU_PF_NODE < n)
      __builtin_prefetch(&ls->node[ls->slot[home[(i + LRU_PF_NODE) % LRU_PF_SLOT]]]);
    const uint64_t r = rec[i];
    access_one(ls, r >> 5, (enum lru_stack_op)(r & 3u), (unsigned)(r >> 2) & 7u, h);
  }
}

void lru_stack_count_repeats(struct lru_stack *ls, unsigned cls, uint64_t loads, uint64_t stores) {
  CHECK_LT(cls, MEM_CLASS_MAX);
  /* NOTE: hist[0] (hits in every size) is left alone: no result reads it. */
  ls->accesses[cls] += loads + stores;
  ls->stores[cls] += stores;
  ls->total += loads + stores;
}

void lru_stack_finish(struct lru_stack *ls) {
  memset(ls->pending_wb, 0, sizeof ls->pending_wb);
  memset(ls->dirty_end, 0, sizeof ls->dirty_end);
  const struct lru_node *nd = ls->node;
  unsigned n = ls->nsz;
  for (uint32_t p = nd[0].next; p != 0; p = nd[p].next) {
    unsigned s = nd[p].seg, d = nd[p].dfrom, c = nd[p].cls;
    for (unsigned i = d; i < s; i++) ls->pending_wb[i][c]++;
    for (unsigned i = d > s ? d : s; i < n; i++) ls->dirty_end[i][c]++;
  }
  ls->snap_valid = true;
  ls->snap_at = ls->total;
}

/* Results must include the writebacks not yet counted lazily: retake the
 * snapshot of the lines held if accesses came after the last one. */
static void refresh_snapshot(struct lru_stack *ls) {
  if (!ls->snap_valid || ls->snap_at != ls->total) lru_stack_finish(ls);
}

unsigned lru_stack_size_count(const struct lru_stack *ls) { return ls->nsz; }

uint64_t lru_stack_misses(const struct lru_stack *ls, unsigned size_index, unsigned cls) {
  CHECK_LT(size_index, ls->nsz);
  CHECK_LT(cls, MEM_CLASS_MAX);
  uint64_t m = 0;
  for (unsigned s = size_index + 1; s <= ls->nsz; s++) m += ls->hist[s][cls];
  return m;
}

uint64_t lru_stack_writebacks(struct lru_stack *ls, unsigned size_index, unsigned cls) {
  CHECK_LT(size_index, ls->nsz);
  CHECK_LT(cls, MEM_CLASS_MAX);
  refresh_snapshot(ls);
  int64_t w = 0;
  for (unsigned i = 0; i <= size_index; i++) w += ls->wbdiff[i][cls];
  CHECK_GE(w, 0);
  return (uint64_t)w + ls->pending_wb[size_index][cls];
}

uint64_t lru_stack_lines_held(const struct lru_stack *ls) { return ls->count; }

void lru_stack_get_results(struct lru_stack *ls, struct lru_stack_results *out) {
  refresh_snapshot(ls);
  memset(out, 0, sizeof *out);
  out->params = ls->p;
  out->size_count = ls->nsz;
  memcpy(out->accesses, ls->accesses, sizeof out->accesses);
  memcpy(out->stores, ls->stores, sizeof out->stores);
  for (unsigned i = 0; i < ls->nsz; i++) {
    struct lru_stack_size_stats *z = &out->size[i];
    z->capacity_bytes = UINT64_C(1) << (ls->p.lg2_min + i);
    for (unsigned c = 0; c < MEM_CLASS_MAX; c++) {
      z->accesses[c] = ls->accesses[c];
      z->stores[c] = ls->stores[c];
      z->misses[c] = lru_stack_misses(ls, i, c);
      z->writebacks[c] = lru_stack_writebacks(ls, i, c);
      z->dirty_at_end[c] = ls->dirty_end[i][c];
    }
  }
}

void lru_stack_check_invariants(const struct lru_stack *ls) {
  const struct lru_node *nd = ls->node;
  uint32_t depth = 0, prev = 0;
  for (uint32_t p = nd[0].next; p != 0; p = nd[p].next) {
    depth++;
    CHECK_LE(depth, ls->count);
    CHECK_EQ(nd[p].prev, prev);
    unsigned s = 0;
    while (ls->cap[s] < depth) s++;
    CHECK_EQ(nd[p].seg, s);
    CHECK_LE(nd[p].dfrom, ls->nsz);
    CHECK_LT(nd[p].cls, MEM_CLASS_MAX);
    if (depth == ls->cap[s]) CHECK_EQ(ls->bound[s], p);
    /* The slot names this node and is reachable from the line's home slot. */
    CHECK_LE(nd[p].slot, ls->mask);
    CHECK_EQ(ls->slot[nd[p].slot], p);
    uint64_t line = nd[p].line;
    if (depth == 1) CHECK_EQ(line, ls->top_line);
    for (uint64_t h = slot_of(ls, line); h != nd[p].slot; h = (h + 1) & ls->mask) {
      CHECK_NE(ls->slot[h], 0);
      CHECK_NE(nd[ls->slot[h]].line, line);
    }
    prev = p;
  }
  CHECK_EQ(depth, ls->count);
  CHECK_EQ(nd[0].prev, prev);
  for (unsigned i = 0; i < ls->nsz; i++)
    if (ls->cap[i] > ls->count) CHECK_EQ(ls->bound[i], 0);
  uint64_t used = 0;
  for (uint64_t h = 0; h <= ls->mask; h++) used += ls->slot[h] != 0;
  CHECK_EQ(used, ls->count);
}

/* splitmix64: the benchmark's own RNG state, passed explicitly. */
static uint64_t bench_next(uint64_t *s) {
  uint64_t z = (*s += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

_Static_assert(MEM_CLASS_MAX <= 8, "the bench packs a class in 3 bits");

double lru_stack_bench(uint64_t accesses, uint64_t seed) {
  enum { CHUNK = 1 << 16, HOT_LINES = 20000 };
  struct lru_stack_params p = lru_stack_params_default();
  struct lru_stack *ls = lru_stack_create(&p);
  uint64_t *buf = xmalloc(CHUNK * sizeof *buf); /* line << 4 | store << 3 | cls */
  uint64_t rng = seed, hot = 0, stream = UINT64_C(1) << 30;
  const uint64_t hot_base = UINT64_C(1) << 20;
  double seconds = 0;
  for (uint64_t done = 0; done < accesses;) {
    uint64_t n = accesses - done < CHUNK ? accesses - done : CHUNK;
    for (uint64_t k = 0; k < n; k++) {
      uint64_t r = bench_next(&rng);
      uint64_t line;
      if (r % 100 < 70) {
        /* Hot set: mostly small steps from the last hot line, sometimes a jump. */
        uint64_t step = (r >> 8) % 100;
        if (step < 85) hot = (hot + HOT_LINES + (r >> 16) % 33 - 16) % HOT_LINES;
        else hot = (r >> 16) % HOT_LINES;
        line = hot_base + hot;
      } else {
        line = stream++;
      }
      uint64_t store = (r >> 40) % 4 == 0;
      uint64_t cls = (r >> 44) % MEM_CLASS_MAX;
      buf[k] = line << 4 | store << 3 | cls;
    }
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    for (uint64_t k = 0; k < n; k++)
      lru_stack_access(ls, buf[k] >> 4, (enum lru_stack_op)((buf[k] >> 3) & 1),
                       (unsigned)(buf[k] & 7));
    clock_gettime(CLOCK_MONOTONIC, &t1);
    seconds += (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
    done += n;
  }
  free(buf);
  lru_stack_destroy(ls);
  return seconds > 0 ? (double)accesses / seconds : 0.0;
}
