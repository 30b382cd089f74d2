/* The banked DRAM level's refresh due times alone (sim/dram_banked_refresh.c):
 * rank r's k-th refresh falls due at (k * ranks + r + 1) * floor(tREFI /
 * ranks), hand-computed, and a channel's ranks fall due at those times, each
 * due refresh counted once and blocking its rank's command queues. */
#include "sim/dram_banked_state.h"
#include "sim/engine.h"
#include "testing.h"

static void no_done(void *ctx, uint64_t tag) {
  (void)ctx;
  (void)tag;
}

static struct dram_banked *level(struct engine *e, uint32_t ranks, uint32_t tREFI,
                                 enum dram_banked_queues qs) {
  struct dram_banked_params p = testing_ddr4_params();
  p.ranks = ranks;
  p.tREFI = tREFI;
  p.queue_structure = qs;
  p.command_queue = 8;
  p.controller_cycles = 1;
  struct dram_client cl = {NULL, no_done, NULL, NULL};
  return dram_banked_create(&p, 1200 * 1000, e, &cl);
}

static void test_due_times(void) {
  struct engine *e = engine_create();
  /* DDR4-2400's tREFI 9364 over 4 ranks: a refresh every floor(9364 / 4) =
   * 2341 cycles, ranks in turn. */
  struct dram_banked *d = level(e, 4, 9364, DRAM_BANKED_SHARED);
  EXPECT(dram_banked_refresh_due(d, 0, 0) == 2341);
  EXPECT(dram_banked_refresh_due(d, 1, 0) == 4682);
  EXPECT(dram_banked_refresh_due(d, 3, 0) == 9364);
  EXPECT(dram_banked_refresh_due(d, 0, 1) == 11705); /* (4 + 1) x 2341 */
  EXPECT(dram_banked_refresh_due(d, 2, 2) == 25751); /* (8 + 3) x 2341 */
  EXPECT(dram_banked_refresh_due(d, 3, 9) == 93640); /* (36 + 4) x 2341 */
  dram_banked_destroy(d);
  /* An odd tREFI over 2 ranks: floor(9363 / 2) = 4681, the half cycle dropped. */
  d = level(e, 2, 9363, DRAM_BANKED_SHARED);
  EXPECT(dram_banked_refresh_due(d, 0, 0) == 4681);
  EXPECT(dram_banked_refresh_due(d, 1, 0) == 9362);
  EXPECT(dram_banked_refresh_due(d, 0, 1) == 14043);
  dram_banked_destroy(d);
  /* One rank: every tREFI. tREFI 0: never. */
  d = level(e, 1, 9364, DRAM_BANKED_SHARED);
  EXPECT(dram_banked_refresh_due(d, 0, 0) == 9364 && dram_banked_refresh_due(d, 0, 2) == 28092);
  dram_banked_destroy(d);
  d = level(e, 2, 0, DRAM_BANKED_SHARED);
  EXPECT(dram_banked_refresh_due(d, 1, 5) == DRAM_BANKED_FAR);
  EXPECT(d->ch[0].ranks[0].next_due == DRAM_BANKED_FAR && d->ch[0].next == DRAM_BANKED_FAR);
  dram_banked_destroy(d);
  engine_destroy(e);
}

/* Two ranks of tREFI 9364, per_bank: step 4682; rank 0 due at 4682, 14046,
 * 23410; rank 1 at 9364, 18728, 28092. 16 banks a rank: rank 0's command
 * queues are 0..15, rank 1's 16..31. */
static void test_falling_due(void) {
  struct engine *e = engine_create();
  struct dram_banked *d = level(e, 2, 9364, DRAM_BANKED_PER_BANK);
  struct dram_banked_channel *c = &d->ch[0];
  EXPECT(c->ranks[0].next_due == 4682 && c->ranks[1].next_due == 9364 && c->next == 4682);
  dram_banked_refresh_fall_due(d, c, 4681);
  EXPECT(c->ranks[0].pending == 0 && c->ranks[1].pending == 0 && c->blocked[0] == 0);
  EXPECT(c->due_min == 4682 && c->ref_ranks == 0);
  dram_banked_refresh_fall_due(d, c, 4682);
  EXPECT(c->ranks[0].pending == 1 && c->ranks[0].next_due == 14046);
  EXPECT(c->ranks[1].pending == 0 && c->ranks[1].next_due == 9364);
  EXPECT(c->blocked[0] == 0xFFFFull); /* rank 0's queues */
  EXPECT(c->due_min == 9364 && c->ref_ranks == 1);
  /* A late look counts each refresh that fell due meanwhile. */
  dram_banked_refresh_fall_due(d, c, 20000);
  EXPECT(c->ranks[0].pending == 2 && c->ranks[0].next_due == 23410);
  EXPECT(c->ranks[1].pending == 2 && c->ranks[1].next_due == 28092);
  EXPECT(c->blocked[0] == 0xFFFFFFFFull);
  EXPECT(c->due_min == 23410 && c->ref_ranks == 2);
  /* A scan: refresh work first (rank 0's REF: its banks are closed), and
   * once none is pending, next is the next refresh to fall due. */
  struct dram_banked_pick pk = {
      .cmd.type = DRAM_BANKED_CMD_NONE, .next = DRAM_BANKED_FAR, .first_t = DRAM_BANKED_FAR};
  dram_banked_scan_refresh(d, c, 20000, &pk);
  EXPECT(pk.first.type == DRAM_BANKED_CMD_REF && pk.first.rank == 0 && pk.first_t == 20000);
  EXPECT(pk.next == 20000);
  dram_banked_refresh_issue(d, c, 0, 20000);
  dram_banked_refresh_issue(d, c, 0, 20001);
  EXPECT(c->ref_ranks == 1 && c->blocked[0] == 0xFFFF0000ull);
  dram_banked_refresh_issue(d, c, 1, 20002);
  dram_banked_refresh_issue(d, c, 1, 20003);
  EXPECT(c->ref_ranks == 0 && c->blocked[0] == 0);
  pk = (struct dram_banked_pick){
      .cmd.type = DRAM_BANKED_CMD_NONE, .next = DRAM_BANKED_FAR, .first_t = DRAM_BANKED_FAR};
  dram_banked_scan_refresh(d, c, 20004, &pk);
  EXPECT(pk.first_t == DRAM_BANKED_FAR && pk.next == 23410);
  for (uint32_t r = 0; r < 2; r++) EXPECT(c->ranks[r].next_due == dram_banked_refresh_due(d, r, 2));
  dram_banked_destroy(d);
  engine_destroy(e);
}

int main(void) {
  test_due_times();
  test_falling_due();
  return testing_done("dram_banked_refresh");
}
