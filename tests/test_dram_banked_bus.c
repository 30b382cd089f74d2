/* The banked DRAM level's data bus alone (sim/dram_banked_bus.c): where a
 * burst fits among those on the channel, hand-computed. DDR4-2400's figures,
 * 2 ranks: a burst takes BL/2 = 4 cycles; bursts of two ranks are one idle
 * cycle apart, except (per_bank / per_rank) a write after another rank's
 * write; and the bus forgets bursts no later command can meet. */
#include "sim/dram_banked_state.h"
#include "sim/engine.h"
#include "testing.h"

static void no_done(void *ctx, uint64_t tag) {
  (void)ctx;
  (void)tag;
}

static struct dram_banked *level(struct engine *e, enum dram_banked_queues qs) {
  struct dram_banked_params p = testing_ddr4_params();
  p.ranks = 2;
  p.queue_structure = qs;
  p.command_queue = 8;
  p.controller_cycles = 1;
  struct dram_client cl = {NULL, no_done, NULL, NULL};
  return dram_banked_create(&p, 1200 * 1000, e, &cl);
}

static int64_t fit(const struct dram_banked *d, int64_t s0, uint32_t rank, bool write) {
  return dram_banked_bus_fit(d, &d->ch[0], s0, rank, write);
}

static void test_fit(void) {
  struct engine *e = engine_create();
  struct dram_banked *d = level(e, DRAM_BANKED_SHARED);
  struct dram_banked_channel *c = &d->ch[0];
  EXPECT(fit(d, 16, 1, false) == 16); /* an empty bus */
  /* Rank 0 reads: a RD at 0 puts its burst on [16, 20). */
  dram_banked_bus_add(d, c, 0, 16, 0, false);
  EXPECT(fit(d, 16, 0, false) == 20); /* same rank: back to back */
  EXPECT(fit(d, 12, 0, false) == 12); /* ends as the other starts */
  EXPECT(fit(d, 13, 0, false) == 20);
  EXPECT(fit(d, 16, 1, false) == 21); /* other rank: one idle cycle, [20, 21) */
  EXPECT(fit(d, 11, 1, false) == 11); /* [11, 15), idle 15, then rank 0 at 16 */
  EXPECT(fit(d, 12, 1, false) == 21);
  EXPECT(fit(d, 21, 1, false) == 21);
  /* A second burst of rank 0 on [24, 28) leaves [20, 24): four cycles, room
   * for rank 0 but not for rank 1 with an idle cycle either side. */
  dram_banked_bus_add(d, c, 1, 24, 0, false);
  EXPECT(c->nb == 2 && c->bursts[0].start == 16 && c->bursts[1].start == 24);
  EXPECT(fit(d, 18, 0, false) == 20);
  EXPECT(fit(d, 18, 1, false) == 29);
  EXPECT(fit(d, 28, 1, false) == 29);
  EXPECT(fit(d, 29, 1, false) == 29);
  /* Writes keep the idle cycle between ranks with queue_structure shared. */
  dram_banked_destroy(d);
  d = level(e, DRAM_BANKED_SHARED);
  dram_banked_bus_add(d, &d->ch[0], 0, 16, 0, true);
  EXPECT(fit(d, 16, 1, true) == 21 && fit(d, 16, 1, false) == 21);
  dram_banked_destroy(d);
  /* per_bank (DRAMsim3's write-to-write across ranks is BL/2): a write may
   * follow another rank's write with no idle cycle; a read may not, nor a
   * write another rank's read. */
  d = level(e, DRAM_BANKED_PER_BANK);
  dram_banked_bus_add(d, &d->ch[0], 0, 16, 0, true);
  EXPECT(fit(d, 16, 1, true) == 20);
  EXPECT(fit(d, 12, 1, true) == 12);
  EXPECT(fit(d, 16, 1, false) == 21);
  dram_banked_bus_add(d, &d->ch[0], 1, 24, 0, false);
  EXPECT(fit(d, 21, 1, true) == 29);
  dram_banked_destroy(d);
  engine_destroy(e);
}

/* A command at `now` puts data no sooner than now + min(tCL, tCWL) = now +
 * 16, so a burst that ends, idle cycle included, by then is forgotten; each
 * burst adds BL/2 cycles to the bus's busy count. */
static void test_forget(void) {
  struct engine *e = engine_create();
  struct dram_banked *d = level(e, DRAM_BANKED_SHARED);
  struct dram_banked_channel *c = &d->ch[0];
  dram_banked_bus_add(d, c, 0, 16, 0, false); /* [16, 20) */
  dram_banked_bus_add(d, c, 4, 20, 1, false); /* [20, 24) (add records; fit decides) */
  EXPECT(c->nb == 2);
  dram_banked_bus_add(d, c, 5, 30, 0, false); /* horizon 21: [16, 20) + idle 20 gone */
  EXPECT(c->nb == 2 && c->bursts[0].start == 20 && c->bursts[1].start == 30);
  dram_banked_bus_add(d, c, 100, 116, 1, true); /* horizon 116: both go */
  EXPECT(c->nb == 1 && c->bursts[0].start == 116 && c->bursts[0].rank == 1 && c->bursts[0].write);
  EXPECT(d->st.bus_busy_cycles == 4 * 4);
  dram_banked_destroy(d);
  engine_destroy(e);
}

int main(void) {
  test_fit();
  test_forget();
  return testing_done("dram_banked_bus");
}
