/* Slots are grouped by set; each set keeps an LRU list (indices, most recent
 * at the head). A hash table of line -> slot (linear probing, backward-shift
 * deletion) finds a line in O(1) whatever the associativity, so a fully
 * associative L2 of 64K lines costs what a 4-way L1 does. */
#include "sim/cache.h"

#include <stdbool.h>
#include <stdlib.h>

#include "sim/err.h"

#define F_VALID 1u
#define F_DIRTY 2u
#define F_PENDING 4u

struct slot {
  uint64_t line;
  uint32_t prev, next; /* LRU list of the set; CACHE_NONE ends it */
  uint32_t flags;
};

struct cache {
  struct slot *slots;
  uint32_t *head, *tail; /* per set: most / least recently used slot */
  uint64_t lines, sets, ways;
  uint64_t set_mask;     /* sets - 1 when a power of two, else 0 (use %) */
  bool scan;             /* few ways: find a line by scanning its set */
  uint32_t *table;       /* otherwise: slot index + 1; 0 empty */
  uint64_t table_mask;
  unsigned table_shift;
};

/* Up to this many ways a set is scanned (its tags sit in a few host lines);
 * beyond, the hash table finds the line. */
#define SCAN_WAYS 16

static inline uint64_t set_of_line(const struct cache *c, uint64_t line) {
  return c->set_mask ? (line & c->set_mask) : line % c->sets;
}

const char *cache_params_problem(const struct cache_params *p) {
  if (p->lg2_line < 2 || p->lg2_line > 16) return "the line size must be 4 bytes to 64 KiB";
  uint64_t line = 1ull << p->lg2_line;
  if (p->size_bytes < line) return "the size is smaller than one line";
  if (p->size_bytes % line) return "the size is not a whole number of lines";
  uint64_t lines = p->size_bytes >> p->lg2_line;
  if (lines > (1ull << 28)) return "more than 2^28 lines";
  if (p->ways && lines % p->ways) return "the ways do not divide the number of lines";
  return NULL;
}

static inline uint64_t hash_of(const struct cache *c, uint64_t line) {
  return (line * 0x9E3779B97F4A7C15ull) >> c->table_shift;
}

static void table_put(struct cache *c, uint64_t line, uint32_t slot) {
  uint64_t i = hash_of(c, line);
  while (c->table[i]) i = (i + 1) & c->table_mask;
  c->table[i] = slot + 1;
}

static void table_del(struct cache *c, uint64_t line) {
  uint64_t i = hash_of(c, line);
  while (c->slots[c->table[i] - 1].line != line) i = (i + 1) & c->table_mask;
  /* Backward shift: move later entries of the cluster into the hole when their
   * home position allows it. */
  uint64_t j = i;
  for (;;) {
    c->table[i] = 0;
    for (;;) {
      j = (j + 1) & c->table_mask;
      if (!c->table[j]) return;
      uint64_t home = hash_of(c, c->slots[c->table[j] - 1].line);
      /* Entry j may fill hole i unless its home lies cyclically in (i, j]. */
      bool stays = i <= j ? (i < home && home <= j) : (i < home || home <= j);
      if (!stays) break;
    }
    c->table[i] = c->table[j];
    i = j;
  }
}

uint64_t cache_host_bytes(const struct cache_params *p) {
  const uint64_t lines = p->size_bytes >> p->lg2_line, ways = p->ways ? p->ways : lines;
  const uint64_t sets = lines / ways;
  uint64_t b = sizeof(struct cache) + lines * sizeof(struct slot) + 2 * sets * sizeof(uint32_t);
  if (ways <= SCAN_WAYS) return b;
  uint64_t tsize = 16;
  while (tsize < 2 * lines) tsize *= 2;
  return b + tsize * sizeof(uint32_t); /* the table */
}

struct cache *cache_create(const struct cache_params *p) {
  CHECK(cache_params_problem(p) == NULL);
  struct cache *c = xcalloc(1, sizeof *c);
  c->lines = p->size_bytes >> p->lg2_line;
  c->ways = p->ways ? p->ways : c->lines;
  c->sets = c->lines / c->ways;
  c->set_mask = (c->sets & (c->sets - 1)) == 0 ? c->sets - 1 : 0;
  if (c->sets == 1) c->set_mask = 0;
  c->scan = c->ways <= SCAN_WAYS;
  c->slots = xmalloc(c->lines * sizeof *c->slots);
  c->head = xmalloc(c->sets * sizeof *c->head);
  c->tail = xmalloc(c->sets * sizeof *c->tail);
  for (uint64_t s = 0; s < c->sets; s++) {
    uint64_t first = s * c->ways, last = first + c->ways - 1;
    c->head[s] = (uint32_t)first;
    c->tail[s] = (uint32_t)last;
    for (uint64_t i = first; i <= last; i++) {
      c->slots[i].line = 0;
      c->slots[i].flags = 0;
      c->slots[i].prev = i == first ? CACHE_NONE : (uint32_t)(i - 1);
      c->slots[i].next = i == last ? CACHE_NONE : (uint32_t)(i + 1);
    }
  }
  if (c->scan) return c;
  uint64_t tsize = 16;
  unsigned bits = 4;
  while (tsize < 2 * c->lines) {
    tsize *= 2;
    bits++;
  }
  c->table = xcalloc(tsize, sizeof *c->table);
  c->table_mask = tsize - 1;
  c->table_shift = 64 - bits;
  return c;
}

void cache_destroy(struct cache *c) {
  if (!c) return;
  free(c->slots);
  free(c->head);
  free(c->tail);
  free(c->table);
  free(c);
}

uint64_t cache_lines(const struct cache *c) { return c->lines; }

uint32_t cache_find(const struct cache *c, uint64_t line) {
  if (c->scan) {
    const uint64_t first = set_of_line(c, line) * c->ways;
    for (uint64_t i = first; i < first + c->ways; i++)
      if (c->slots[i].line == line && (c->slots[i].flags & F_VALID)) return (uint32_t)i;
    return CACHE_NONE;
  }
  uint64_t i = hash_of(c, line);
  for (;;) {
    uint32_t v = c->table[i];
    if (!v) return CACHE_NONE;
    if (c->slots[v - 1].line == line) return v - 1;
    i = (i + 1) & c->table_mask;
  }
}

static inline uint64_t set_of_slot(const struct cache *c, uint32_t slot) { return slot / c->ways; }

void cache_touch(struct cache *c, uint32_t slot) {
  uint64_t s = set_of_slot(c, slot);
  if (c->head[s] == slot) return;
  struct slot *x = &c->slots[slot];
  /* Unlink (x is not the head, so it has a prev). */
  c->slots[x->prev].next = x->next;
  if (x->next != CACHE_NONE) c->slots[x->next].prev = x->prev;
  else c->tail[s] = x->prev;
  x->prev = CACHE_NONE;
  x->next = c->head[s];
  c->slots[c->head[s]].prev = slot;
  c->head[s] = slot;
}

uint32_t cache_victim(const struct cache *c, uint64_t line) {
  uint64_t s = set_of_line(c, line);
  for (uint32_t i = c->tail[s]; i != CACHE_NONE; i = c->slots[i].prev)
    if (!(c->slots[i].flags & F_PENDING)) return i;
  return CACHE_NONE;
}

bool cache_valid(const struct cache *c, uint32_t slot) { return c->slots[slot].flags & F_VALID; }
uint64_t cache_line(const struct cache *c, uint32_t slot) { return c->slots[slot].line; }
bool cache_dirty(const struct cache *c, uint32_t slot) { return c->slots[slot].flags & F_DIRTY; }
bool cache_pending(const struct cache *c, uint32_t slot) { return c->slots[slot].flags & F_PENDING; }
void cache_set_dirty(struct cache *c, uint32_t slot) { c->slots[slot].flags |= F_DIRTY; }

void cache_set_pending(struct cache *c, uint32_t slot, bool pending) {
  if (pending) c->slots[slot].flags |= F_PENDING;
  else c->slots[slot].flags &= ~F_PENDING;
}

void cache_install(struct cache *c, uint32_t slot, uint64_t line, bool dirty, bool pending) {
  struct slot *x = &c->slots[slot];
  CHECK_EQ(set_of_slot(c, slot), set_of_line(c, line));
  CHECK(!(x->flags & F_PENDING));
  if (!c->scan && (x->flags & F_VALID)) table_del(c, x->line);
  x->line = line;
  x->flags = F_VALID | (dirty ? F_DIRTY : 0) | (pending ? F_PENDING : 0);
  if (!c->scan) table_put(c, line, slot);
  cache_touch(c, slot);
}
