/* The ring's growth (sim/ring.h). */
#include "sim/ring.h"

#include <stdlib.h>
#include <string.h>

#include "sim/err.h"

void ring_grow(struct ring *r, size_t size) {
  const uint64_t cap = r->cap ? 2 * r->cap : 4;
  char *v = xcalloc(cap, size);
  for (uint64_t s = r->head; s < r->tail; s++)
    memcpy(v + (s & (cap - 1)) * size, ring_at(r, size, s), size);
  free(r->v);
  r->v = v;
  r->cap = cap;
}

void ring_free(struct ring *r) {
  free(r->v);
  *r = (struct ring){0};
}
