/* The cheaper rungs' DRAM energy estimate (sim/dram_energy_estimate.c)
 * against hand-computed cases on the DDR4 test preset's currents
 * (testing_ddr4_params: 8 x8 devices a rank, 1200 MHz, tRC 55, tRAS 39, tRP
 * 16, tRFC 420, BL/2 4). One mA for one DRAM cycle on a rank costs VDD x
 * devices x tCK = 1.2 V x 8 x 0.8333 ns = 8 pJ, so (in pJ) an ACT 8 (48 x 55 -
 * 43 x 39 - 34 x 16) = 3352, a RD 8 (135 - 43) 4 = 2944, a WR 8 (123 - 43) 4
 * = 2560, a REF 8 (250 - 43) 420 = 695520, a rank-cycle active 8 x 43 = 344.
 * Then the wrapper's stats: the estimate at fixed and channel under the
 * banked level's names, and none at banked. */
#include <math.h>
#include <string.h>

#include "sim/dram.h"
#include "sim/dram_energy_estimate.h"
#include "sim/engine.h"
#include "sim/stats.h"
#include "testing.h"

static const double PJ = 1e-12;

static bool near(double have, double want) { return fabs(have - want) <= 1e-12 * fabs(want); }

static void expect_parts(const char *what, const struct dram_banked_energy *e, double act,
                         double rd, double wr, double ref, double act_stb) {
  const double want[6] = {act, rd, wr, ref, act_stb, 0};
  const double have[6] = {e->activate_j, e->read_j,           e->write_j,
                          e->refresh_j,  e->active_standby_j, e->precharge_standby_j};
  double sum = 0;
  for (int i = 0; i < 6; i++) {
    EXPECTF(near(have[i], want[i] * PJ), "%s: part %d %.15g J, expected %.15g", what, i, have[i],
            want[i] * PJ);
    sum += want[i] * PJ;
  }
  EXPECTF(near(e->total_j, sum), "%s: total %.15g J, expected %.15g", what, e->total_j, sum);
}

/* 2 channels of 2 ranks, tREFI 9364 (a REF every 4682 DRAM cycles a
 * channel); 7 reads and 3 writes over 10000.5 DRAM cycles: 5 ACTs (half the
 * 10 requests), 2 REFs a channel (4), 40002 rank-cycles active. */
static void test_hand(void) {
  struct dram_banked_params p = testing_ddr4_params();
  p.channels = 2;
  p.ranks = 2;
  p.tREFI = 9364;
  struct dram_banked_energy e;
  dram_energy_estimate(&p, 7, 3, 10000.5, &e);
  expect_parts("7 reads, 3 writes", &e, 5 * 3352.0, 7 * 2944.0, 3 * 2560.0, 4 * 695520.0,
               40002 * 344.0);
  /* 16587816 pJ over 10000.5 cycles of 1/1.2 GHz. */
  const double w = 16587816 * PJ / (10000.5 / 1.2e9);
  EXPECTF(near(dram_energy_estimate_power_w(&p, e.total_j, 10000.5), w), "power, expected %.15g",
          w);
  /* Just short of the second REF's cycle (9364): one a channel. */
  dram_energy_estimate(&p, 7, 3, 9363.5, &e);
  EXPECT(near(e.refresh_j, 2 * 695520.0 * PJ));
  /* One read, refresh off (the preset's tREFI 0): half an ACT, no REF. */
  p = testing_ddr4_params();
  dram_energy_estimate(&p, 1, 0, 100, &e);
  expect_parts("one read, no refresh", &e, 1676, 2944, 0, 0, 100 * 344.0);
  EXPECT(dram_energy_estimate_power_w(&p, 1, 0) == 0);
}

/* The figure `name` of t, NAN when absent. */
static double find(const struct stats_table *t, const char *name) {
  for (unsigned i = 0; i < t->n; i++)
    if (!strcmp(t->e[i].name, name))
      return t->e[i].kind == STATS_U64 ? (double)t->e[i].u : t->e[i].f;
  return NAN;
}

static void on_done(void *ctx, uint64_t tag) {
  (void)tag;
  (*(unsigned *)ctx)++;
}
static void on_space(void *ctx) { (void)ctx; }
static void ev_send(void *ctx, uint64_t k) {
  struct dram *d = ctx;
  const uint64_t addr = k * 64 * 37;
  CHECK(dram_can_take(d, addr, k % 3 == 0));
  dram_take(d, addr, k % 3 == 0, k);
}

/* Six requests (two writes) a few hundred cycles apart on each level behind
 * the wrapper, a 1.4 GHz core, the DRAM at 1200 MHz: a run of 7000 core
 * cycles is 6000 DRAM cycles. */
static void wrapper_case(enum dram_model model) {
  struct dram_params p = testing_dram_params(model, 8);
  struct engine *e = engine_create();
  unsigned served = 0;
  const struct dram_client dc = {&served, on_done, on_space, NULL};
  struct dram *d = dram_create(&p, 1400000, e, &dc);
  for (uint64_t k = 0; k < 6; k++) engine_at(e, 100 + 300 * k, ev_send, d, k);
  engine_run(e);
  dram_finish(d, engine_now(e));
  EXPECT(served == 6);
  struct stats_part parts[2];
  const unsigned n = dram_level_stats(d, parts);
  struct stats_table t = {0};
  const struct stats_env env = {.cycles = 7000, .parts = parts, .nparts = n};
  stats_emit(&t, &dram_stats_descs, dram_get_stats(d), &env);
  struct dram_banked_energy want;
  dram_energy_estimate(&p.banked, 4, 2, 6000, &want);
  const char *name = dram_model_names[model];
  if (model == DRAM_MODEL_BANKED) {
    EXPECTF(isnan(find(&t, "dram_energy_estimated")), "%s: no estimate", name);
    EXPECTF(find(&t, "dram_energy_j") != want.total_j, "%s: its own energy", name);
  } else {
    EXPECTF(find(&t, "dram_energy_estimated") == 1, "%s: the flag", name);
    EXPECTF(find(&t, "dram_energy_j") == want.total_j &&
                find(&t, "dram_energy_activate_j") == want.activate_j,
            "%s: %.15g J, expected %.15g", name, find(&t, "dram_energy_j"), want.total_j);
    EXPECT(near(find(&t, "dram_power_w"), want.total_j / (6000 / 1.2e9)));
  }
  stats_fini(&t);
  dram_destroy(d);
  engine_destroy(e);
}

int main(void) {
  test_hand();
  wrapper_case(DRAM_MODEL_FIXED);
  wrapper_case(DRAM_MODEL_CHANNEL);
  wrapper_case(DRAM_MODEL_BANKED);
  return testing_done("test_dram_energy_estimate");
}
