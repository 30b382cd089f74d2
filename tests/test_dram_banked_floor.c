/* The banked level's column floor alone (dram_banked_col_floor in
 * sim/dram_banked_bank.c): a cycle under every column command of one rank
 * and direction, kept until the next column command. Hand-computed with
 * DDR4-2400's figures (tCL 17, tCWL 12, BL/2 4, tCCD_S 4, tCCD_L 6, tRTW 10),
 * then against every request's earliest time on random command streams. */
#include "sim/dram_banked_state.h"
#include "sim/engine.h"
#include "testing.h"

static void no_done(void *ctx, uint64_t tag) {
  (void)ctx;
  (void)tag;
}

static struct dram_banked *level(struct engine *e) {
  struct dram_banked_params p = testing_ddr4_params();
  p.ranks = 2;
  p.queue_structure = DRAM_BANKED_PER_BANK;
  p.command_queue = 8;
  p.controller_cycles = 1;
  p.tCL = 17, p.tCWL = 12, p.tRTW = 10;
  struct dram_client cl = {NULL, no_done, NULL, NULL};
  return dram_banked_create(&p, 1200 * 1000, e, &cl);
}

/* A request to bank `bank` (within the channel) ready at `ready`. */
static struct dram_banked_req req(const struct dram_banked *d, uint32_t bank, int64_t ready) {
  struct dram_banked_req r = {0};
  r.bank = bank;
  r.rank = bank / d->banks_per_rank;
  r.group = bank % d->banks_per_rank / d->p.banks_per_group;
  r.ready = ready;
  return r;
}

static void test_hand(void) {
  struct engine *e = engine_create();
  struct dram_banked *d = level(e);
  struct dram_banked_channel *c = &d->ch[0];
  const int64_t f = DRAM_BANKED_NEVER;
  /* An idle channel: nothing but the cycle asked. */
  EXPECT(dram_banked_col_floor(d, c, 0, false, 50) == 50);
  EXPECT(dram_banked_col_floor(d, c, 1, true, 50) == 50);
  /* A RD of rank 0, group 0 at 100: its burst on [117, 121). */
  struct dram_banked_req r = req(d, 0, f);
  dram_banked_column_state(d, c, &r, false, 100);
  EXPECT(dram_banked_col_floor(d, c, 0, false, 101) == 104); /* tCCD_S; back to back */
  EXPECT(dram_banked_col_floor(d, c, 1, false, 101) == 105); /* the bus: one idle cycle */
  EXPECT(dram_banked_col_floor(d, c, 0, true, 101) == 110);  /* tRTW */
  EXPECT(dram_banked_col_floor(d, c, 1, true, 101) == 110);
  /* The group's tCCD_L is not in the floor: a RD of group 0 waits to 106,
   * one of group 1 exactly to the floor. */
  struct dram_banked_req g0 = req(d, 1, f), g1 = req(d, 4, f);
  EXPECT(dram_banked_col_earliest(d, c, &g0, false, 101) == 106);
  EXPECT(dram_banked_col_earliest(d, c, &g1, false, 101) == 104);
  /* Kept: asked later, the same floor; past it, fitted again. */
  EXPECT(dram_banked_col_floor(d, c, 0, false, 103) == 104);
  EXPECT(dram_banked_col_floor(d, c, 0, false, 107) == 107);
  /* A WR of rank 1 at 110 (data [122, 126)) moves them. */
  struct dram_banked_req w = req(d, 16, f);
  dram_banked_column_state(d, c, &w, true, 110);
  EXPECT(dram_banked_col_floor(d, c, 1, true, 111) == 114);  /* tCCD_S */
  EXPECT(dram_banked_col_floor(d, c, 0, true, 111) == 114);  /* the bus: write after write */
  EXPECT(dram_banked_col_floor(d, c, 1, false, 111) == 129); /* tCWL + BL/2 + tWTR_S */
  EXPECT(dram_banked_col_floor(d, c, 0, false, 111) == 111); /* data at 128: after the gap */
  dram_banked_destroy(d);
  engine_destroy(e);
}

static uint64_t next_rand(uint64_t *x) {
  *x ^= *x << 13, *x ^= *x >> 7, *x ^= *x << 17;
  return *x;
}

/* Random streams of column commands, each issued at its request's earliest
 * time (so the bus and the spacing stay legal), on banks of groups 0-2 only.
 * After each, at rising cycles: the kept floor and one fitted from scratch
 * are under every request's earliest time, the kept one under the fresh;
 * and a request of the unused group 3, ready and with its row open, issues
 * exactly at the fresh floor (so a floor is never lower than it must be). */
static void test_random(void) {
  struct engine *e = engine_create();
  int bad = 0, checked = 0, tight = 0;
  for (uint64_t seed = 1; seed <= 20; seed++) {
    struct dram_banked *d = level(e);
    struct dram_banked_channel *c = &d->ch[0];
    uint64_t x = seed * 0x9E3779B97F4A7C15ull;
    int64_t now = 100;
    for (int step = 0; step < 400; step++) {
      const uint32_t bank = (uint32_t)(next_rand(&x) % d->banks_per_channel);
      if (bank % d->banks_per_rank / d->p.banks_per_group == 3) continue;
      const bool write = next_rand(&x) % 3 == 0;
      /* Now and then a bank's tRCD reaches past the bus. */
      if (next_rand(&x) % 8 == 0) c->banks[bank].col_ok = now + (int64_t)(next_rand(&x) % 30);
      struct dram_banked_req r = req(d, bank, now - (int64_t)(next_rand(&x) % 4));
      now = dram_banked_col_earliest(d, c, &r, write, now);
      dram_banked_column_state(d, c, &r, write, now);
      for (int64_t at = now + 1; at < now + 20; at += 1 + (int64_t)(next_rand(&x) % 5)) {
        for (uint32_t k = 0; k < 2; k++)
          for (int wr = 0; wr < 2; wr++) {
            const int64_t kept = dram_banked_col_floor(d, c, k, wr, at);
            const int64_t fresh = dram_banked_col_floor_fit(d, c, k, wr, at);
            bad += kept > fresh;
            for (uint32_t b = k * d->banks_per_rank; b < (k + 1) * d->banks_per_rank; b++) {
              struct dram_banked_req q = req(d, b, at - 3 + (int64_t)(next_rand(&x) % 8));
              bad += fresh > dram_banked_col_earliest(d, c, &q, wr, at);
              checked++;
            }
            struct dram_banked_req g3 =
                req(d, k * d->banks_per_rank + 3 * d->p.banks_per_group, at);
            const bool exact = fresh == dram_banked_col_earliest(d, c, &g3, wr, at);
            bad += !exact;
            tight += exact;
          }
      }
    }
    dram_banked_destroy(d);
  }
  EXPECTF(bad == 0, "%d floors above a command's earliest time or not tight", bad);
  EXPECT(checked > 10000 && tight > 1000);
  engine_destroy(e);
}

int main(void) {
  test_hand();
  test_random();
  return testing_done("dram_banked_floor");
}
