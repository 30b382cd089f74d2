/* A FIFO channel solved in closed form at submission: request k enters the FIFO
 * at max(arrival, start of request k - depth) and starts its transfer at
 * max(entry, end of request k - 1). A ring of the last `depth` start times is
 * all the state the bound needs. */
#include "sim/dram.h"

#include <math.h>
#include <stdlib.h>

#include "sim/err.h"

struct dram {
  struct dram_params p;
  double ticks_per_byte;
  uint64_t *starts; /* ring: start ticks of the last queue_depth requests */
  uint64_t k;       /* requests so far */
  uint64_t last_arrival;
  /* Occupancy sweep: entry and start ticks of requests not yet started at
   * sweep_t (a ring of capacity sw_cap from sw_lo, sw_n long); sw_e: how many
   * of them have entered by sweep_t. */
  uint64_t (*sw)[2];
  uint64_t sw_cap, sw_lo, sw_n, sw_e;
  uint64_t sweep_t;
  double occ;
  struct dram_stats st;
};

/* Advance the occupancy integral to tick x: entries and starts are each
 * non-decreasing, so two pointers merge them in time order. */
static void sweep_to(struct dram *d, uint64_t x) {
  const double tick = 1.0 / (double)(1ull << DRAM_TICK_BITS);
  while (d->sw_n) {
    uint64_t *head = d->sw[d->sw_lo % d->sw_cap];
    uint64_t next_entry = d->sw_e < d->sw_n ? d->sw[(d->sw_lo + d->sw_e) % d->sw_cap][0] : UINT64_MAX;
    uint64_t next_start = head[1];
    uint64_t ev = next_entry < next_start ? next_entry : next_start;
    if (ev > x) break;
    d->st.fifo_area += d->occ * (double)(ev - d->sweep_t) * tick;
    d->sweep_t = ev;
    /* At equal ticks a start goes first (its place frees for the entry), unless
     * the head has not entered yet. */
    if (d->sw_e == 0 || next_entry < next_start) {
      d->sw_e++;
      d->occ += 1.0;
      if (d->occ > d->st.fifo_max) d->st.fifo_max = (uint32_t)d->occ;
    } else {
      /* The head starts: it entered no later than it started. */
      CHECK_GT(d->sw_e, 0);
      d->sw_lo++;
      d->sw_n--;
      d->sw_e--;
      d->occ -= 1.0;
    }
  }
  if (x != UINT64_MAX && x > d->sweep_t) {
    d->st.fifo_area += d->occ * (double)(x - d->sweep_t) * tick;
    d->sweep_t = x;
  }
}

static void sweep_add(struct dram *d, uint64_t entry, uint64_t start) {
  if (d->sw_n == d->sw_cap) {
    uint64_t cap = d->sw_cap ? 2 * d->sw_cap : 64;
    uint64_t(*n)[2] = xmalloc(cap * sizeof *n);
    for (uint64_t i = 0; i < d->sw_n; i++) {
      n[i][0] = d->sw[(d->sw_lo + i) % d->sw_cap][0];
      n[i][1] = d->sw[(d->sw_lo + i) % d->sw_cap][1];
    }
    free(d->sw);
    d->sw = n;
    d->sw_cap = cap;
    d->sw_lo = 0;
  }
  uint64_t *r = d->sw[(d->sw_lo + d->sw_n) % d->sw_cap];
  r[0] = entry;
  r[1] = start;
  d->sw_n++;
}

void dram_finish(struct dram *d) { sweep_to(d, UINT64_MAX); }

const char *dram_params_problem(const struct dram_params *p) {
  if (!(p->bytes_per_cycle > 0) || !isfinite(p->bytes_per_cycle) || p->bytes_per_cycle > 1e6)
    return "the bandwidth must be above 0 and at most 10^6 bytes per cycle";
  if (p->queue_depth < 1 || p->queue_depth > (1u << 20)) return "the queue depth must be 1 to 2^20";
  if (p->latency_cycles > (1ull << 40)) return "the latency must be at most 2^40 cycles";
  return NULL;
}

struct dram *dram_create(const struct dram_params *p) {
  CHECK(dram_params_problem(p) == NULL);
  struct dram *d = xcalloc(1, sizeof *d);
  d->p = *p;
  d->ticks_per_byte = (double)(1ull << DRAM_TICK_BITS) / p->bytes_per_cycle;
  d->starts = xcalloc(p->queue_depth, sizeof *d->starts);
  return d;
}

void dram_destroy(struct dram *d) {
  if (!d) return;
  free(d->sw);
  free(d->starts);
  free(d);
}

void dram_submit(struct dram *d, uint64_t at, uint64_t addr, uint32_t bytes, bool write,
                 struct dram_timing *out) {
  (void)addr;
  CHECK_GE(at, d->last_arrival);
  CHECK_LT(at, (1ull << (64 - DRAM_TICK_BITS - 1)));
  d->last_arrival = at;
  uint64_t arrive = at << DRAM_TICK_BITS;
  sweep_to(d, arrive);
  uint64_t entry = arrive;
  uint32_t slot = (uint32_t)(d->k % d->p.queue_depth);
  if (d->k >= d->p.queue_depth && d->starts[slot] > entry) entry = d->starts[slot];
  uint64_t start = entry > d->st.last_end_ticks ? entry : d->st.last_end_ticks;
  /* At least one tick, so a transfer always takes time. */
  uint64_t dur = (uint64_t)llround((double)bytes * d->ticks_per_byte);
  if (dur == 0) dur = 1;
  uint64_t end = start + dur;
  d->starts[slot] = start;
  d->k++;
  d->st.last_end_ticks = end;
  d->st.busy_ticks += dur;
  out->start_ticks = start;
  out->end_ticks = end;
  out->wait_cycles = dram_ticks_to_cycles_ceil(start - arrive);
  out->done_cycle = dram_ticks_to_cycles_ceil(end) + d->p.latency_cycles;
  d->st.wait_ticks_sum += start - arrive;
  d->st.fifo_wait_cycles_sum += (double)(start - entry) / (double)(1ull << DRAM_TICK_BITS);
  sweep_add(d, entry, start);
  d->st.backpressure_cycles += dram_ticks_to_cycles_ceil(entry - arrive);
  if (write) {
    d->st.writes++;
    d->st.write_bytes += bytes;
  } else {
    d->st.reads++;
    d->st.read_bytes += bytes;
  }
}

const struct dram_stats *dram_get_stats(const struct dram *d) { return &d->st; }
