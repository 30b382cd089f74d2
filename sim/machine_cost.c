/* Per-item cost attribution (machine_costs_enable): each ray context counts
 * what it costs (issue slots, load waits, lines read by class, lines written
 * back) and charges it, split evenly, to the work items it was told it works
 * for (machine_attribute) when told anew; the L2 reports lines read and
 * written through its cost hook. Holds: the items' sums are the run's
 * totals (machine_cost_finish CHECKs it). Off (no counters) unless enabled. */
#include "sim/machine_state.h"

#include <stdlib.h>

#include "sim/l2.h"

/* Add v of counter ch to item. NOTE: line counts are 32-bit (half the host
 * memory): 2^32 lines, 256 GiB of DRAM traffic for one item, is far past any
 * run that ends. */
static void cost_put(struct machine *m, uint32_t item, unsigned ch, uint64_t v) {
  struct machine_costs *k = &m->costs;
  CHECK_LT(item, k->items);
  if (ch == COST_SLOTS) {
    k->issue_slots[item] += v;
  } else if (ch == COST_WAIT) {
    k->load_wait_cycles[item] += v;
  } else {
    uint32_t *p = ch == COST_WRITE ? &k->write_lines[item] : &k->read_lines[ch - COST_READ0][item];
    CHECK_LE(v, UINT32_MAX - *p);
    *p += (uint32_t)v;
  }
}

/* Charge what c has cost since it was told whom it works for: each counter
 * split evenly among its items, the remainder one each to the first. */
void machine_cost_flush(struct mctx *c) {
  struct machine *m = c->m;
  for (unsigned ch = 0; ch < m->cost_stride; ch++) {
    const uint64_t v = c->acc[ch];
    if (!v) continue;
    c->acc[ch] = 0;
    CHECK_GT(c->nitems, 0);
    const uint64_t q = v / c->nitems, r = v % c->nitems;
    for (uint32_t j = 0; j < c->nitems; j++)
      if (q + (j < r)) cost_put(m, c->items[j], ch, q + (j < r));
  }
}

/* The L2's cost hook (struct l2_client): a line read for a miss or written
 * back. A load's read waits with its context, which still works for the
 * items it loaded for. */
static void l2_cost(void *ctx, void *waiter, uint32_t tag, unsigned cls, bool write) {
  struct machine *m = ctx;
  if (write) {
    cost_put(m, tag, COST_WRITE, 1);
    return;
  }
  CHECK_LT(cls, m->costs.classes);
  if (waiter) cost_charge(waiter, COST_READ0 + cls, 1);
  else cost_put(m, tag, COST_READ0 + cls, 1);
}

void machine_costs_enable(struct machine *m, uint64_t items, unsigned classes) {
  CHECK(!m->ran);
  CHECK(!m->cost_acc);
  CHECK_LT(classes, MEM_CLASS_MAX + 1);
  CHECK_LE(items, (uint64_t)UINT32_MAX + 1);
  struct machine_costs *k = &m->costs;
  k->items = items;
  k->classes = classes;
  k->issue_slots = xcalloc(items + 1, sizeof *k->issue_slots);
  k->load_wait_cycles = xcalloc(items + 1, sizeof *k->load_wait_cycles);
  for (unsigned c = 0; c < classes; c++)
    k->read_lines[c] = xcalloc(items + 1, sizeof *k->read_lines[c]);
  k->write_lines = xcalloc(items + 1, sizeof *k->write_lines);
  m->cost_stride = COST_READ0 + classes;
  m->cost_acc = xcalloc((uint64_t)m->nctx * m->cost_stride, sizeof *m->cost_acc);
  for (uint32_t i = 0; i < m->nctx; i++) m->ctx[i].acc = m->cost_acc + (uint64_t)i * m->cost_stride;
  machine_door_costed(m, m, l2_cost);
}

void machine_attribute(struct machine *m, uint32_t ctx, const uint32_t *items, uint32_t n) {
  if (!m->cost_acc) return;
  CHECK_LT(ctx, m->nctx);
  struct mctx *c = &m->ctx[ctx];
  CHECK(m->running == c);
  machine_cost_flush(c);
  for (uint32_t j = 0; j < n; j++) CHECK_LT(items[j], m->costs.items);
  c->item1 = n ? items[0] : 0;
  c->items = n == 1 ? &c->item1 : items;
  c->nitems = n;
}

const struct machine_costs *machine_get_costs(const struct machine *m) {
  return m->cost_acc ? &m->costs : NULL;
}

/* The end of a run that counted costs: every context's charged, and the
 * items' sums are the run's totals (conservation). */
void machine_cost_finish(struct machine *m) {
  for (uint32_t i = 0; i < m->nctx; i++) {
    CHECK_EQ(m->ctx[i].nitems, 0);
    CHECK_EQ(ring_len(&m->ctx[i].runs), 0);
  }
  const struct machine_costs *k = &m->costs;
  uint64_t slots = 0, wait = 0, wr = 0, rd[MEM_CLASS_MAX] = {0};
  for (uint64_t i = 0; i < k->items; i++) {
    slots += k->issue_slots[i];
    wait += k->load_wait_cycles[i];
    wr += k->write_lines[i];
    for (unsigned c = 0; c < k->classes; c++) rd[c] += k->read_lines[c][i];
  }
  CHECK_EQ(slots, m->st.issue_slots);
  CHECK_EQ(wait, m->st.load_latency.sum);
  CHECK_EQ(wr * SIM_LINE_BYTES, m->st.l2.writeback_bytes);
  for (unsigned c = 0; c < MEM_CLASS_MAX; c++)
    CHECK_EQ(c < k->classes ? rd[c] * SIM_LINE_BYTES : 0, m->st.l2.fetch_bytes_by_class[c]);
}
