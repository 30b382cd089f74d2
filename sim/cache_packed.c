/* The packed sets' blocks and installs (the finds and uses are inline in
 * the header). */
#include "sim/cache_packed.h"

#include <stdlib.h>

#include "sim/err.h"

void cpk_init(struct cache_packed *p, uint64_t sets) {
  CHECK(sets && (sets & (sets - 1)) == 0);
  p->tag = NULL;
  p->set = NULL;
  p->set_mask = sets - 1;
  p->lg2_sets = (unsigned)__builtin_ctzll(sets);
}

void cpk_fini(struct cache_packed *p) {
  free(p->tag);
  free(p->set);
  p->tag = NULL;
  p->set = NULL;
}

uint64_t cpk_make(struct cache_packed *p) {
  const uint64_t sets = p->set_mask + 1;
  p->tag = xcalloc_aligned(64, sets * CPK_WAYS * sizeof *p->tag);
  p->set = xcalloc_aligned(64, sets * sizeof *p->set);
  for (uint64_t s = 0; s < sets; s++) p->set[s].order = CPK_ORDER0;
  return sets * (CPK_WAYS * sizeof *p->tag + sizeof *p->set);
}

void cpk_put(struct cache_packed *p, uint64_t s, unsigned k, uint64_t line, bool dirty,
             bool pending) {
  struct cpk_set *st = &p->set[s];
  const uint16_t bit = (uint16_t)(1u << k);
  p->tag[CPK_WAYS * s + k] = cpk_key(p, line);
  st->order = cpk_to_top(st->order, k);
  st->dirty = (uint16_t)(dirty ? st->dirty | bit : st->dirty & ~bit);
  st->pending = (uint16_t)(pending ? st->pending | bit : st->pending & ~bit);
}
