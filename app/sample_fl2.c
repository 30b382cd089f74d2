/* Sampling's functional model of the shared L2: record items, replay them
 * interleaved (sample_fl2.h says the model). */
#include "app/sample_fl2.h"

#include <stdlib.h>
#include <string.h>

#include "sim/cache.h"
#include "sim/err.h"
#include "sim/line.h"
#include "sim/machine.h"

/* A recorded access: line << 2 | kind. */
enum { K_LOAD, K_STORE, K_STORE_LINE };
#define NO_ITEM UINT64_MAX

struct item {
  uint64_t begin, end; /* its accesses [begin, end), absolute indices */
  double *out;
};

struct sfl2 {
  uint32_t nctx, per_core, cores;
  struct cache_params l1p, l2p;
  bool have_l1;
  struct cache **l1; /* [cores], made per batch */
  struct cache *l2;
  uint64_t *acc; /* accesses [abase, abase + nacc) */
  uint64_t abase, nacc, acap;
  struct item *it; /* items [ibase, ibase + nit) */
  uint64_t ibase, nit, icap;
  uint64_t next;      /* the next item a context takes */
  uint64_t *ctx_item; /* [nctx]: the item each context runs, or NO_ITEM */
  uint64_t *ctx_pos;  /* [nctx]: its next access */
  bool *ctx_fill;     /* [nctx]: its item is a filler (counted nowhere) */
  uint32_t rr;        /* the context whose turn it is */
  uint32_t counting;  /* contexts holding an item that counts */
  uint64_t replayed;
  uint64_t refill;              /* the next recorded item a filler repeats (SFL2_REFILL) */
  uint64_t sets_every, residue; /* the sets modelled: lines with line % sets_every == residue */
};

static void caches_make(struct sfl2 *x) {
  for (uint32_t c = 0; x->have_l1 && c < x->cores; c++) x->l1[c] = cache_create(&x->l1p);
  x->l2 = cache_create(&x->l2p);
}

static void caches_drop(struct sfl2 *x) {
  for (uint32_t c = 0; x->have_l1 && c < x->cores; c++) cache_destroy(x->l1[c]);
  cache_destroy(x->l2);
}

struct sfl2 *sfl2_create(const struct machine_params *p, uint32_t sets_every, uint32_t residue) {
  CHECK(sets_every >= 1 && (sets_every & (sets_every - 1)) == 0);
  CHECK_LT(residue, sets_every);
  struct sfl2 *x = xcalloc(1, sizeof *x);
  x->cores = p->cores;
  x->per_core = p->threads_per_core * p->rays_per_thread;
  x->nctx = x->cores * x->per_core;
  x->have_l1 = p->l1_size_bytes > 0;
  x->l1p = (struct cache_params){p->l1_size_bytes, p->l1_ways, SIM_LINE_LG2, false};
  x->l2p = (struct cache_params){p->l2_size_bytes, p->l2_ways, SIM_LINE_LG2, true};
  x->l1 = xcalloc(x->cores, sizeof *x->l1);
  x->sets_every = sets_every;
  x->residue = residue;
  caches_make(x);
  x->acap = 1u << 16;
  x->acc = xcalloc(x->acap, sizeof *x->acc);
  x->icap = 1024;
  x->it = xcalloc(x->icap, sizeof *x->it);
  x->ctx_item = xcalloc(x->nctx, sizeof *x->ctx_item);
  x->ctx_pos = xcalloc(x->nctx, sizeof *x->ctx_pos);
  x->ctx_fill = xcalloc(x->nctx, sizeof *x->ctx_fill);
  for (uint32_t c = 0; c < x->nctx; c++) x->ctx_item[c] = NO_ITEM;
  return x;
}

void sfl2_destroy(struct sfl2 *x) {
  if (!x) return;
  caches_drop(x);
  free(x->l1);
  free(x->acc);
  free(x->it);
  free(x->ctx_item);
  free(x->ctx_pos);
  free(x->ctx_fill);
  free(x);
}

void sfl2_item(struct sfl2 *x, double *out) {
  if (x->nit == x->icap) {
    x->icap *= 2;
    x->it = xrealloc(x->it, x->icap * sizeof *x->it);
  }
  const uint64_t at = x->abase + x->nacc;
  x->it[x->nit++] = (struct item){at, at, out};
}

static void push(struct sfl2 *x, uint64_t e) {
  struct item *cur = &x->it[x->nit - 1];
  /* The same line again, at once: a hit in its core's L1 or the L2 that
   * changes nothing the model counts. */
  if (cur->end > cur->begin && x->acc[x->nacc - 1] == e) return;
  if (x->nacc == x->acap) {
    x->acap *= 2;
    x->acc = xrealloc(x->acc, x->acap * sizeof *x->acc);
  }
  x->acc[x->nacc++] = e;
  cur->end++;
}

void sfl2_access(struct sfl2 *x, uint64_t addr, uint32_t size, bool store) {
  CHECK_GT(x->nit, 0);
  const uint64_t last = addr + size - 1, lmask = SIM_LINE_BYTES - 1;
  const uint64_t first = addr >> SIM_LINE_LG2, end = last >> SIM_LINE_LG2;
  const uint64_t first_whole = (addr & lmask) ? first + 1 : first;
  const bool last_whole = (last & lmask) == lmask;
  for (uint64_t line = first; line <= end; line++) {
    unsigned k = K_LOAD;
    if ((line & (x->sets_every - 1)) != x->residue) continue;
    if (store) k = line >= first_whole && (line < end || last_whole) ? K_STORE_LINE : K_STORE;
    push(x, line << 2 | k);
  }
}

/* One access at the L2: the DRAM bytes it causes. */
static unsigned model_access(struct sfl2 *x, uint64_t line, unsigned k) {
  const uint32_t s = cache_use(x->l2, line);
  if (s != CACHE_NONE) {
    if (k != K_LOAD) cache_set_dirty(x->l2, s);
    return 0;
  }
  const uint32_t v = cache_victim(x->l2, line);
  CHECK_NE(v, CACHE_NONE); /* nothing is pending here */
  unsigned bytes = cache_valid(x->l2, v) && cache_dirty(x->l2, v) ? SIM_LINE_BYTES : 0;
  cache_install(x->l2, v, line, k != K_LOAD, false);
  return bytes + (k == K_STORE_LINE ? 0 : SIM_LINE_BYTES);
}

/* Context c's turn: its accesses up to and including the first load the
 * L1 does not hold (there the machine's ray waits and another runs), or to
 * its item's end; true when the item has ended. */
static bool turn(struct sfl2 *x, uint32_t c) {
  const struct item *it = &x->it[x->ctx_item[c] - x->ibase];
  double *out = x->ctx_fill[c] ? NULL : it->out;
  struct cache *l1 = x->have_l1 ? x->l1[c / x->per_core] : NULL;
  uint64_t pos = x->ctx_pos[c];
  bool wait = false;
  while (!wait && pos < it->end) {
    const uint64_t e = x->acc[pos++ - x->abase];
    const uint64_t line = e >> 2;
    const unsigned k = e & 3;
    x->replayed++;
    if (l1) {
      const bool hit = cache_use(l1, line) != CACHE_NONE;
      if (k == K_LOAD && hit) continue;
      if (k == K_LOAD) cache_install(l1, cache_victim(l1, line), line, false, false);
    }
    wait = k == K_LOAD;
    const unsigned bytes = model_access(x, line, k);
    if (bytes && out) *out += (double)bytes * (double)x->sets_every;
  }
  x->ctx_pos[c] = pos;
  return pos == it->end;
}

/* Give context c item i (a filler: counted nowhere). */
static void give(struct sfl2 *x, uint32_t c, uint64_t i, bool filler) {
  const struct item *it = &x->it[i - x->ibase];
  x->ctx_item[c] = i;
  x->ctx_pos[c] = it->begin;
  x->ctx_fill[c] = filler;
  x->counting += !filler && it->out;
}

/* Give context c the next item; false when none is recorded. An item of no
 * access ends at once. */
static bool take(struct sfl2 *x, uint32_t c) {
  while (x->next < x->ibase + x->nit) {
    const uint64_t i = x->next++;
    if (x->it[i - x->ibase].end == x->it[i - x->ibase].begin) continue;
    give(x, c, i, false);
    return true;
  }
  return false;
}

/* Give context c a filler: the recorded items again, in turn (the batch's
 * own accesses stand for the items the full run would take next). */
static bool refill(struct sfl2 *x, uint32_t c) {
  for (uint64_t tries = 0; tries < x->nit; tries++) {
    if (x->refill < x->ibase || x->refill >= x->ibase + x->nit) x->refill = x->ibase;
    const uint64_t i = x->refill++;
    if (x->it[i - x->ibase].end == x->it[i - x->ibase].begin) continue;
    give(x, c, i, true);
    return true;
  }
  return false;
}

/* Drop the items every context is done with, and their accesses. */
static void compact(struct sfl2 *x) {
  uint64_t lo = x->next;
  for (uint32_t c = 0; c < x->nctx; c++)
    if (x->ctx_item[c] != NO_ITEM && x->ctx_item[c] < lo) lo = x->ctx_item[c];
  const uint64_t drop = lo - x->ibase;
  if (drop == 0) return;
  const uint64_t abase = drop < x->nit ? x->it[drop].begin : x->abase + x->nacc;
  uint64_t alo = abase;
  for (uint32_t c = 0; c < x->nctx; c++)
    if (x->ctx_item[c] != NO_ITEM && x->ctx_pos[c] < alo) alo = x->ctx_pos[c];
  memmove(x->it, x->it + drop, (x->nit - drop) * sizeof *x->it);
  x->nit -= drop;
  x->ibase = lo;
  const uint64_t adrop = alo - x->abase;
  memmove(x->acc, x->acc + adrop, (x->nacc - adrop) * sizeof *x->acc);
  x->nacc -= adrop;
  x->abase = alo;
}

/* Context c's turn is over: its item has ended. */
static void ended(struct sfl2 *x, uint32_t c) {
  const struct item *it = &x->it[x->ctx_item[c] - x->ibase];
  x->counting -= !x->ctx_fill[c] && it->out;
  x->ctx_item[c] = NO_ITEM;
}

/* Empty the batch: every context idle, the items dropped, the caches kept
 * (sample_fl2.h says why). */
static void batch_end(struct sfl2 *x) {
  for (uint32_t c = 0; c < x->nctx; c++) x->ctx_item[c] = NO_ITEM;
  x->counting = 0;
  x->rr = 0;
  x->next = x->ibase + x->nit;
  x->ibase = x->next;
  x->nit = 0;
  x->abase += x->nacc;
  x->nacc = 0;
}

void sfl2_pump(struct sfl2 *x, enum sfl2_end end) {
  const bool final = end != SFL2_MORE;
  for (;;) {
    const uint32_t c = x->rr;
    if (x->ctx_item[c] == NO_ITEM && !take(x, c)) {
      if (!final) break;
      /* The recorded items are all taken: the batch runs on until no
       * counted item runs, its contexts kept busy by fillers (SFL2_REFILL)
       * or left idle (SFL2_DRAIN). */
      if (x->counting == 0) break;
      if (end == SFL2_REFILL) refill(x, c);
    }
    if (x->ctx_item[c] != NO_ITEM && turn(x, c)) ended(x, c);
    x->rr = c + 1 == x->nctx ? 0 : c + 1;
  }
  if (final) batch_end(x);
  else compact(x);
}

uint64_t sfl2_replayed(const struct sfl2 *x) { return x->replayed; }
