/* The banked level's energy (dram_banked_power.c) against hand-computed
 * cases: DRAMsim3's increments worked out from the DDR4 test preset's
 * currents (testing_ddr4_params: DRAMsim3's DDR4_8Gb_x8_2400.ini figures, 8
 * x8 devices a rank, 1200 MHz, tRC 55, tRAS 39, tRP 16, tRFC 420, BL/2 4),
 * clocks 1:1. One mA for one DRAM cycle on a rank costs VDD x devices x tCK =
 * 1.2 V x 8 x 0.8333 ns = 8 pJ, so (in pJ):
 *   ACT   8 (48 x 55 - 43 x 39 - 34 x 16) = 8 x 419 = 3352
 *   RD    8 (135 - 43) 4 = 2944        WR  8 (123 - 43) 4 = 2560
 *   REF   8 (250 - 43) 420 = 695520
 *   a cycle active 8 x 43 = 344, precharged 8 x 34 = 272. */
#include <math.h>
#include <string.h>

#include "sim/dram_banked.h"
#include "sim/engine.h"
#include "sim/stats.h"
#include "testing.h"

static const double PJ = 1e-12;
enum { ACT = 3352, RD = 2944, WR = 2560, REF = 695520, ACT_STB = 344, PRE_STB = 272 };

struct rq {
  uint64_t at, addr;
  bool write;
};

struct harness {
  struct dram_banked *d;
  const struct rq *reqs;
  uint64_t served;
};

static void h_done(void *ctx, uint64_t tag) {
  (void)tag;
  ((struct harness *)ctx)->served++;
}

static void h_inject(void *ctx, uint64_t i) {
  struct harness *h = ctx;
  const struct rq *r = &h->reqs[i];
  CHECK(dram_banked_ops.can_take(h->d, r->addr, r->write));
  dram_banked_ops.take(h->d, r->addr, r->write, i);
}

/* The run's end at core cycle arg. */
static void h_finish(void *ctx, uint64_t arg) {
  dram_banked_ops.finish(((struct harness *)ctx)->d, arg);
}

/* Requests reqs (each taken at its core cycle) on a fresh level, finished
 * at core cycle end. Caller destroys the level. */
static struct dram_banked *run(const struct dram_banked_params *p, const struct rq *reqs,
                               uint64_t n, uint64_t end) {
  struct harness h = {NULL, reqs, 0};
  struct engine *e = engine_create();
  const struct dram_client cl = {&h, h_done, NULL, NULL};
  h.d = dram_banked_create(p, 1200000, e, &cl);
  for (uint64_t i = 0; i < n; i++) engine_at(e, reqs[i].at, h_inject, &h, i);
  engine_at(e, end, h_finish, &h, end);
  engine_run(e);
  EXPECT(h.served == n);
  engine_destroy(e);
  return h.d;
}

/* A line of rank ra, bank group bg, row row under "rochrababgco" (one channel). */
static uint64_t line(const struct dram_banked_params *p, uint32_t ra, uint32_t bg, uint64_t row) {
  const uint64_t co = p->columns / p->burst_length;
  return ((((row * p->ranks + ra) * p->banks_per_group + 0) * p->bank_groups + bg) * co) << 6;
}

static bool near(double have, double want) { return fabs(have - want) <= 1e-12 * fabs(want); }

/* Each component of e against the hand-computed pJ figures. */
static void expect_energy(const char *what, const struct dram_banked_energy *e, double act,
                          double rd, double wr, double ref, double act_stb, double pre_stb) {
  const double want[6] = {act, rd, wr, ref, act_stb, pre_stb};
  const double have[6] = {e->activate_j, e->read_j,           e->write_j,
                          e->refresh_j,  e->active_standby_j, e->precharge_standby_j};
  static const char *const names[6] = {"activate", "read",   "write",
                                       "refresh",  "active", "precharged"};
  double sum = 0;
  for (int i = 0; i < 6; i++) {
    EXPECTF(near(have[i], want[i] * PJ), "%s: %s %.15g J, expected %.15g", what, names[i], have[i],
            want[i] * PJ);
    sum += want[i] * PJ;
  }
  EXPECTF(near(e->total_j, sum), "%s: total %.15g J, expected %.15g", what, e->total_j, sum);
}

/* The stats table's figure `name` (a double). */
static double table_f64(const struct stats_table *t, const char *name) {
  const double v = testing_stat(t, name);
  EXPECTF(!isnan(v), "no %s in the table", name);
  return v;
}

/* One read to a closed row, open page, finished at 1000: ACT at 100, RD at
 * 116, the row open from 100 to the end: 900 cycles active, 100 precharged.
 * The stats table says the same, its six parts add to its total, and the
 * power is that over 1000 cycles of 0.8333 ns. */
static void test_read_open_page(void) {
  struct dram_banked_params p = testing_ddr4_params();
  const struct rq a[] = {{100, line(&p, 0, 0, 7), false}};
  struct dram_banked *d = run(&p, a, 1, 1000);
  struct dram_banked_energy e;
  dram_banked_energy_of(d, -1, -1, &e);
  expect_energy("a read, open page", &e, ACT, RD, 0, 0, 900.0 * ACT_STB, 100.0 * PRE_STB);
  struct stats_table t = {0};
  dram_level_report(&dram_banked_ops, d, &t, 1000);
  static const char *const parts[] = {
      "dram_energy_activate_j", "dram_energy_read_j",           "dram_energy_write_j",
      "dram_energy_refresh_j",  "dram_energy_active_standby_j", "dram_energy_precharge_standby_j"};
  double sum = 0;
  for (int i = 0; i < 6; i++) sum += table_f64(&t, parts[i]);
  EXPECT(table_f64(&t, "dram_energy_j") == sum && sum == e.total_j);
  const double watts = e.total_j / (1000 / 1.2e9);
  EXPECTF(near(table_f64(&t, "dram_power_w"), watts), "power %.15g W, expected %.15g",
          table_f64(&t, "dram_power_w"), watts);
  stats_fini(&t);
  dram_banked_destroy(d);
}

/* Close page: the read's RDA at 116 closes the bank at once (DRAMsim3's bank
 * state), though its precharge happens at tRAS: 16 cycles active. Two reads to
 * two bank groups: ACTs at 100 and 104 (tRRD_S), RDAs at 116 and 120: the
 * rank is active from its first ACT to its last RDA, 20 cycles. */
static void test_close_page(void) {
  struct dram_banked_params p = testing_ddr4_params();
  p.page = DRAM_BANKED_CLOSE_PAGE;
  const struct rq a[] = {{100, line(&p, 0, 0, 7), false}};
  struct dram_banked *d = run(&p, a, 1, 1000);
  struct dram_banked_energy e;
  dram_banked_energy_of(d, 0, 0, &e);
  expect_energy("a read, close page", &e, ACT, RD, 0, 0, 16.0 * ACT_STB, 984.0 * PRE_STB);
  dram_banked_destroy(d);
  const struct rq b[] = {{100, line(&p, 0, 0, 7), false}, {100, line(&p, 0, 1, 7), false}};
  d = run(&p, b, 2, 1000);
  dram_banked_energy_of(d, 0, 0, &e);
  expect_energy("two reads, close page", &e, 2.0 * ACT, 2.0 * RD, 0, 0, 20.0 * ACT_STB,
                980.0 * PRE_STB);
  dram_banked_destroy(d);
}

/* Refresh on, no request: the one rank's first refresh falls due at tREFI
 * (9360) and issues then (all banks closed); by 10000 one REF, and every
 * cycle precharged standby, tRFC's included. */
static void test_refresh(void) {
  struct dram_banked_params p = testing_ddr4_params();
  p.tREFI = 9360;
  struct dram_banked *d = run(&p, NULL, 0, 10000);
  EXPECT(dram_banked_get_stats(d)->refreshes == 1);
  struct dram_banked_energy e;
  dram_banked_energy_of(d, -1, -1, &e);
  expect_energy("a refresh", &e, 0, 0, 0, REF, 0, 10000.0 * PRE_STB);
  dram_banked_destroy(d);
}

/* Two ranks, per rank: rank 1 takes a write at 100 (ACT 100, WR 116) and keeps
 * its row open to the end (2000); rank 0 idles. The ranks' figures add up to
 * the level's. */
static void test_per_rank(void) {
  struct dram_banked_params p = testing_ddr4_params();
  p.ranks = 2;
  const struct rq a[] = {{100, line(&p, 1, 0, 3), true}};
  struct dram_banked *d = run(&p, a, 1, 2000);
  struct dram_banked_energy r0, r1, all;
  dram_banked_energy_of(d, 0, 0, &r0);
  dram_banked_energy_of(d, 0, 1, &r1);
  dram_banked_energy_of(d, 0, -1, &all);
  expect_energy("rank 0, idle", &r0, 0, 0, 0, 0, 0, 2000.0 * PRE_STB);
  expect_energy("rank 1, a write", &r1, ACT, 0, WR, 0, 1900.0 * ACT_STB, 100.0 * PRE_STB);
  expect_energy("both ranks", &all, ACT, 0, WR, 0, 1900.0 * ACT_STB, 2100.0 * PRE_STB);
  dram_banked_destroy(d);
}

/* The idle write drain moves energy between the background parts (per_bank,
 * two writes to one row taken at 100 and 101, finished at core cycle 3000:
 * per_bank decides that cycle too, so the level runs 3001). Draining
 * after 1000 idle cycles (the presets'): the second write arrived after cycle
 * 101, so the drain starts at the end of 1101 and moves one write a cycle;
 * ACT 1102, WR 1118 (tRCD) and 1124 (tCCD_L), the row open from 1102 to the
 * end: 1899 cycles active, 1102 precharged. Never draining (0, DRAMsim3's):
 * no command, 3001 cycles precharged, the two writes left in the buffer. So
 * the drain costs 1899 precharged cycles turned active, ACT and two WR. */
static void test_idle_drain(void) {
  struct dram_banked_params p = testing_ddr4_params();
  p.queue_structure = DRAM_BANKED_PER_BANK;
  p.command_queue = 8;
  p.controller_cycles = 2;
  const struct rq a[] = {{100, line(&p, 0, 0, 7), true}, {101, line(&p, 0, 0, 7) + 64, true}};
  struct dram_banked_energy drained, kept;
  p.idle_drain_cycles = 1000;
  struct dram_banked *d = run(&p, a, 2, 3000);
  dram_banked_energy_of(d, -1, -1, &drained);
  expect_energy("idle drain after 1000", &drained, ACT, 0, 2.0 * WR, 0, 1899.0 * ACT_STB,
                1102.0 * PRE_STB);
  EXPECT(dram_banked_get_stats(d)->writes == 2 && dram_banked_get_stats(d)->writes_left == 0);
  dram_banked_destroy(d);
  p.idle_drain_cycles = 0;
  d = run(&p, a, 2, 3000);
  dram_banked_energy_of(d, -1, -1, &kept);
  expect_energy("no idle drain", &kept, 0, 0, 0, 0, 0, 3001.0 * PRE_STB);
  struct stats_table t = {0};
  dram_level_report(&dram_banked_ops, d, &t, 3000);
  EXPECT(table_f64(&t, "dram_writes_left") == 2 && dram_banked_get_stats(d)->writes == 0);
  stats_fini(&t);
  dram_banked_destroy(d);
  EXPECTF(near(kept.precharge_standby_j - drained.precharge_standby_j, 1899.0 * PRE_STB * PJ),
          "the drain's precharged standby: %.15g J less, expected %.15g",
          kept.precharge_standby_j - drained.precharge_standby_j, 1899.0 * PRE_STB * PJ);
}

int main(void) {
  test_read_open_page();
  test_idle_drain();
  test_close_page();
  test_refresh();
  test_per_rank();
  return testing_done("dram_banked_power");
}
