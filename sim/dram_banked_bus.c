/* The banked level's data bus, one per channel: the bursts that may still
 * matter, and where the next burst fits. Holds: the bursts kept are disjoint
 * and sorted by start; bursts of two ranks are at least one idle cycle apart,
 * but with queue_structure per_bank / per_rank a write may follow another
 * rank's write with none (DRAMsim3's write-to-write across ranks is BL/2). */
#include "sim/dram_banked_state.h"

#include "sim/err.h"

void dram_banked_bus_init(const struct dram_banked *d, struct dram_banked_channel *c) {
  /* Bursts that can still matter lie within the spread of the two latencies
   * plus a burst either side. */
  const struct dram_banked_params *p = &d->p;
  uint32_t spread = p->tCL > p->tCWL ? p->tCL - p->tCWL : p->tCWL - p->tCL;
  c->cap_b = spread / (uint32_t)d->burst_cycles + 6;
  c->bursts = xcalloc(c->cap_b, sizeof *c->bursts);
}

/* Bursts are disjoint and sorted by start, so moving past one can only meet
 * later ones. */
int64_t dram_banked_bus_fit(const struct dram_banked *d, const struct dram_banked_channel *c,
                            int64_t s0, uint32_t rank, bool write) {
  const int64_t b = d->burst_cycles;
  int64_t s = s0;
  /* Past the last burst's end and its turnaround gap (at most a cycle; the
   * bursts are in order of start): nothing to fit around. */
  if (!c->nb || s >= c->bursts[c->nb - 1].start + b + 1) return s;
  for (uint32_t i = 0; i < c->nb; i++) {
    int64_t gap = c->bursts[i].rank != rank && !(d->cq_mode && write && c->bursts[i].write);
    int64_t a = c->bursts[i].start;
    if (s < a + b + gap && s + b + gap > a) s = a + b + gap;
  }
  return s;
}

/* Forget the bursts that end before any future burst could begin (a command
 * at `now` or later puts data at now + min latency). */
void dram_banked_bus_add(struct dram_banked *d, struct dram_banked_channel *c, int64_t now,
                         int64_t start, uint32_t rank, bool write) {
  const int64_t b = d->burst_cycles;
  int64_t horizon = now + (d->p.tCL < d->p.tCWL ? d->p.tCL : d->p.tCWL);
  uint32_t k = 0;
  for (uint32_t i = 0; i < c->nb; i++)
    if (c->bursts[i].start + b + 1 > horizon) c->bursts[k++] = c->bursts[i];
  c->nb = k;
  CHECK_LT(c->nb, c->cap_b);
  uint32_t i = c->nb;
  while (i > 0 && c->bursts[i - 1].start > start) {
    c->bursts[i] = c->bursts[i - 1];
    i--;
  }
  c->bursts[i].start = start;
  c->bursts[i].rank = rank;
  c->bursts[i].write = write;
  c->nb++;
  d->st.bus_busy_cycles += (uint64_t)b;
}
