/* The banked DRAM level against hand-computed command timelines (DDR4-2400
 * figures, 1:1 clocks unless said), bandwidth bounds, the per-cycle oracle on
 * random traffic and Little's law; both controller structures (shared
 * FR-FCFS, per-bank command queues). Its pieces alone: address decoding
 * (test_dram_banked_map.c), parameter rules (test_dram_banked_params.c),
 * refresh due times (test_dram_banked_refresh.c), the data bus
 * (test_dram_banked_bus.c). */
#include <stdlib.h>
#include <string.h>

#include "sim/dram_banked.h"
#include "sim/engine.h"
#include "sim/stats.h"
#include "testing.h"

/* DDR4-2400 (DRAMsim3's DDR4_8Gb_x8_2400.ini, tRTP 9), one channel and rank,
 * refresh off unless a test turns it on. B = BL/2 = 4. */
static struct dram_banked_params ddr4(void) { return testing_ddr4_params(); }

/* The same with DRAMsim3's structure: command queues per bank of 8. */
static struct dram_banked_params ddr4_per_bank(void) {
  struct dram_banked_params p = ddr4();
  p.queue_structure = DRAM_BANKED_PER_BANK;
  p.command_queue = 8;
  p.controller_cycles = 2;
  return p;
}

/* ---- Harness: requests injected by events at given core cycles; a refused
 * one waits in a list retried at every space callback. ---- */

struct rq {
  uint64_t at, addr;
  bool write;
};

struct harness {
  struct engine *e;
  struct dram_banked *d;
  const struct rq *reqs;
  uint64_t n;
  uint64_t *done;
  uint64_t *waiting, nwait;
  uint64_t served;
};

static void h_done(void *ctx, uint64_t tag) {
  struct harness *h = ctx;
  EXPECT(h->done[tag] == UINT64_MAX);
  h->done[tag] = engine_now(h->e);
  h->served++;
}

static bool h_try(struct harness *h, uint64_t i) {
  const struct rq *r = &h->reqs[i];
  if (!dram_banked_ops.can_take(h->d, r->addr, r->write)) return false;
  dram_banked_ops.take(h->d, r->addr, r->write, i);
  return true;
}

static void h_space(void *ctx) {
  struct harness *h = ctx;
  uint64_t k = 0;
  for (uint64_t i = 0; i < h->nwait; i++)
    if (!h_try(h, h->waiting[i])) h->waiting[k++] = h->waiting[i];
  h->nwait = k;
}

static void h_inject(void *ctx, uint64_t i) {
  struct harness *h = ctx;
  if (!h_try(h, i)) h->waiting[h->nwait++] = i;
}

static void h_finish(void *ctx, uint64_t arg) {
  (void)arg;
  struct harness *h = ctx;
  dram_banked_ops.finish(h->d, engine_now(h->e));
}

/* Run reqs to completion on a fresh level (core_khz: the core clock);
 * finish_at: the core cycle of finish (0: when the engine runs dry). done[i]:
 * request i's done cycle. Returns the level (caller destroys). */
static struct dram_banked *run(const struct dram_banked_params *p, uint64_t core_khz,
                               const struct rq *reqs, uint64_t n, uint64_t *done,
                               uint64_t finish_at) {
  struct harness h;
  memset(&h, 0, sizeof h);
  h.e = engine_create();
  h.reqs = reqs;
  h.n = n;
  h.done = done;
  h.waiting = xcalloc(n + 1, sizeof *h.waiting);
  struct dram_client cl = {&h, h_done, h_space, NULL};
  h.d = dram_banked_create(p, core_khz, h.e, &cl);
  for (uint64_t i = 0; i < n; i++) {
    done[i] = UINT64_MAX;
    engine_at(h.e, reqs[i].at, h_inject, &h, i);
  }
  if (finish_at) engine_at(h.e, finish_at, h_finish, &h, 0);
  engine_run(h.e);
  if (!finish_at) dram_banked_ops.finish(h.d, engine_now(h.e));
  EXPECTF(h.served == n, "served %llu of %llu", (unsigned long long)h.served,
          (unsigned long long)n);
  EXPECT(h.nwait == 0);
  free(h.waiting);
  engine_destroy(h.e);
  return h.d;
}

/* The byte address of a line, built from the mapping string field by field
 * (col: the burst index within the row). */
static uint64_t addr_of(const struct dram_banked_params *p, uint32_t ch, uint32_t ra, uint32_t bg,
                        uint32_t ba, uint64_t row, uint64_t col) {
  uint64_t a = 0;
  for (int i = 0; i < 6; i++) {
    const char *f = p->mapping + 2 * i;
    uint64_t n, v;
    if (!strncmp(f, "ro", 2)) n = p->rows, v = row;
    else if (!strncmp(f, "ch", 2)) n = p->channels, v = ch;
    else if (!strncmp(f, "ra", 2)) n = p->ranks, v = ra;
    else if (!strncmp(f, "bg", 2)) n = p->bank_groups, v = bg;
    else if (!strncmp(f, "ba", 2)) n = p->banks_per_group, v = ba;
    else n = p->columns / p->burst_length, v = col;
    a = a * n + v;
  }
  return a << 6;
}

static const uint64_t MHZ = 1000; /* kHz per MHz */

/* 1-3: closed bank, row hit, row conflict (with and without a tRAS wait). */
static void test_latencies(void) {
  struct dram_banked_params p = ddr4();
  uint64_t done[4];
  /* Read at 100, bank closed: ACT 100, RD 116 (tRCD 16), last beat 116 + 16
   * + 4 = 136. Same row at 300: RD 300, done 320 (tCL + B = 20). Other row at
   * 500: PRE 500, ACT 516 (tRP), RD 532, done 552 (16 + 16 + 16 + 4 = 52). */
  struct rq a[] = {{100, addr_of(&p, 0, 0, 0, 0, 7, 0), false},
                   {300, addr_of(&p, 0, 0, 0, 0, 7, 1), false},
                   {500, addr_of(&p, 0, 0, 0, 0, 9, 0), false}};
  struct dram_banked *d = run(&p, 1200 * MHZ, a, 3, done, 0);
  EXPECTF(done[0] == 136, "closed bank: done %llu, expected 136", (unsigned long long)done[0]);
  EXPECTF(done[1] == 320, "row hit: done %llu, expected 320", (unsigned long long)done[1]);
  EXPECTF(done[2] == 552, "row conflict: done %llu, expected 552", (unsigned long long)done[2]);
  const struct dram_banked_stats *s = dram_banked_get_stats(d);
  EXPECT(s->row_misses == 1 && s->row_hits == 1 && s->row_conflicts == 1);
  EXPECT(s->activates == 2 && s->precharges == 1 && s->reads == 3);
  dram_banked_destroy(d);

  /* Conflict arriving at 20, soon after the ACT at 0 (RD 16, done 36): PRE
   * waits for tRAS, max(20, 0 + 39, 16 + tRTP 9) = 39; ACT 55 (= tRP after,
   * and tRC 55 after the first ACT); RD 71; done 91. */
  struct rq b[] = {{0, addr_of(&p, 0, 0, 0, 0, 7, 0), false},
                   {20, addr_of(&p, 0, 0, 0, 0, 9, 0), false}};
  d = run(&p, 1200 * MHZ, b, 2, done, 0);
  EXPECTF(done[0] == 36 && done[1] == 91, "tRAS case: %llu %llu, expected 36 91",
          (unsigned long long)done[0], (unsigned long long)done[1]);
  dram_banked_destroy(d);

  /* Core 1400 MHz, DRAM 1200 MHz: 7 core cycles per 6 DRAM cycles. A read at
   * core 100 may start at DRAM cycle ceil(100 * 6 / 7) = 86: ACT 86, RD 102,
   * last beat 122 = core ceil(122 * 7 / 6) = ceil(142.33) = 143. */
  struct rq c[] = {{100, addr_of(&p, 0, 0, 0, 0, 7, 0), false}};
  d = run(&p, 1400 * MHZ, c, 1, done, 0);
  EXPECTF(done[0] == 143, "1400:1200 clocks: done %llu, expected 143", (unsigned long long)done[0]);
  dram_banked_destroy(d);
}

/* 4: a read after a write to the same rank waits tWTR. */
static void test_wtr(void) {
  struct dram_banked_params p = ddr4();
  p.write_low = 0; /* a lone write keeps the channel until its column command */
  uint64_t done[2];
  /* Write at 0 alone: the channel serves writes; ACT 0, WR 16, data [32, 36),
   * done 36. A read at 1 to the same bank and row waits for the write's column
   * command (the channel turns back to reads after it) and then for
   * WR + tCWL + B + tWTR_L = 16 + 16 + 4 + 9 = 45: data [61, 65), done 65. */
  struct rq a[] = {{0, addr_of(&p, 0, 0, 0, 0, 3, 0), true},
                   {1, addr_of(&p, 0, 0, 0, 0, 3, 1), false}};
  struct dram_banked *d = run(&p, 1200 * MHZ, a, 2, done, 0);
  EXPECTF(done[0] == 36 && done[1] == 65, "tWTR_L: %llu %llu, expected 36 65",
          (unsigned long long)done[0], (unsigned long long)done[1]);
  dram_banked_destroy(d);
  /* The read to another bank group instead: its ACT at 17 (after the WR at
   * 16; tRRD_S from the ACT at 0 long past), RD at max(17 + 16, 16 + 16 + 4 +
   * tWTR_S 3 = 39) = 39, done 39 + 20 = 59. */
  struct rq b[] = {{0, addr_of(&p, 0, 0, 0, 0, 3, 0), true},
                   {1, addr_of(&p, 0, 0, 1, 0, 3, 0), false}};
  d = run(&p, 1200 * MHZ, b, 2, done, 0);
  EXPECTF(done[0] == 36 && done[1] == 59, "tWTR_S: %llu %llu, expected 36 59",
          (unsigned long long)done[0], (unsigned long long)done[1]);
  dram_banked_destroy(d);
}

/* 5: tFAW, tRRD_S, tRRD_L. */
static void test_act_spacing(void) {
  struct dram_banked_params p = ddr4();
  uint64_t done[5];
  /* Five reads at 0 to bank 0 of groups 0, 1, 2, 3, then bank 1 of group 0.
   * ACTs 0, 4, 8, 12 (tRRD_S 4); the fifth waits for tFAW: 0 + 26 = 26. RDs
   * 16, 20, 24, 28 (tRCD after each ACT, tCCD_S apart), done 36, 40, 44, 48;
   * the fifth RD at 26 + 16 = 42, done 62. */
  struct rq a[5];
  const uint32_t grp[5] = {0, 1, 2, 3, 0}, bnk[5] = {0, 0, 0, 0, 1};
  for (int i = 0; i < 5; i++) a[i] = (struct rq){0, addr_of(&p, 0, 0, grp[i], bnk[i], 5, 0), false};
  struct dram_banked *d = run(&p, 1200 * MHZ, a, 5, done, 0);
  const uint64_t want[5] = {36, 40, 44, 48, 62};
  for (int i = 0; i < 5; i++)
    EXPECTF(done[i] == want[i], "tFAW read %d: done %llu, expected %llu", i,
            (unsigned long long)done[i], (unsigned long long)want[i]);
  dram_banked_destroy(d);
  /* Same group, two banks: ACT 0 and 6 (tRRD_L), RD 16 and 22, done 36, 42. */
  struct rq b[] = {{0, addr_of(&p, 0, 0, 0, 0, 5, 0), false},
                   {0, addr_of(&p, 0, 0, 0, 1, 5, 0), false}};
  d = run(&p, 1200 * MHZ, b, 2, done, 0);
  EXPECTF(done[0] == 36 && done[1] == 42, "tRRD_L: %llu %llu, expected 36 42",
          (unsigned long long)done[0], (unsigned long long)done[1]);
  dram_banked_destroy(d);
  /* Other group: ACT 0 and 4, RD 16 and 20, done 36, 40. */
  struct rq c[] = {{0, addr_of(&p, 0, 0, 0, 0, 5, 0), false},
                   {0, addr_of(&p, 0, 0, 1, 0, 5, 0), false}};
  d = run(&p, 1200 * MHZ, c, 2, done, 0);
  EXPECTF(done[0] == 36 && done[1] == 40, "tRRD_S: %llu %llu, expected 36 40",
          (unsigned long long)done[0], (unsigned long long)done[1]);
  dram_banked_destroy(d);
}

/* 6: refresh. */
static void test_refresh(void) {
  struct dram_banked_params p = ddr4();
  p.tREFI = 9364;
  uint64_t done[2];
  /* Idle rank: REF at 9364 (due, all banks long precharged), rank busy to
   * 9364 + 420 = 9784. A read at 9374: ACT 9784, RD 9800, done 9820. */
  struct rq a[] = {{9374, addr_of(&p, 0, 0, 0, 0, 1, 0), false}};
  struct dram_banked *d = run(&p, 1200 * MHZ, a, 1, done, 0);
  EXPECTF(done[0] == 9820, "read during refresh: done %llu, expected 9820",
          (unsigned long long)done[0]);
  EXPECT(dram_banked_get_stats(d)->refreshes == 1);
  dram_banked_destroy(d);
  /* An open bank (read at 9000: ACT 9000, RD 9016, done 9036): at 9364 PRE
   * (tRAS and tRTP long met), REF at 9380 (tRP), rank busy to 9800; a read at
   * 9370 to the open row: ACT 9800, RD 9816, done 9836. */
  struct rq b[] = {{9000, addr_of(&p, 0, 0, 0, 0, 1, 0), false},
                   {9370, addr_of(&p, 0, 0, 0, 0, 1, 1), false}};
  d = run(&p, 1200 * MHZ, b, 2, done, 0);
  EXPECTF(done[0] == 9036 && done[1] == 9836,
          "refresh of an open bank: %llu %llu, expected 9036 9836", (unsigned long long)done[0],
          (unsigned long long)done[1]);
  dram_banked_destroy(d);

  /* Long run, 2 channels x 4 ranks, reads every 97 cycles for 400000 cycles:
   * each rank refreshes floor(T / tREFI) times +-1 (staggered by tREFI / 4). */
  p.channels = 2;
  p.ranks = 4;
  p.tREFI = 9364; /* divisible by 4: 2341 */
  const uint64_t n = 4000;
  struct rq *r = xcalloc(n, sizeof *r);
  uint64_t *dn = xcalloc(n, sizeof *dn);
  uint64_t x = 12345;
  for (uint64_t i = 0; i < n; i++) {
    x = x * 6364136223846793005ull + 1442695040888963407ull;
    r[i] = (struct rq){i * 97,
                       addr_of(&p, (x >> 20) & 1, (x >> 22) & 3, (x >> 24) & 3, (x >> 26) & 3,
                               (x >> 28) & 7, (x >> 32) & 127),
                       false};
  }
  d = run(&p, 1200 * MHZ, r, n, dn, 400000);
  const struct dram_banked_stats *s = dram_banked_get_stats(d);
  uint64_t per_rank = 400000 / 9364; /* 42 */
  uint64_t ranks = 2 * 4;
  EXPECTF(s->refreshes + ranks >= ranks * per_rank && s->refreshes <= ranks * (per_rank + 1),
          "refreshes %llu, expected %llu +- %llu", (unsigned long long)s->refreshes,
          (unsigned long long)(ranks * per_rank), (unsigned long long)ranks);
  EXPECT(s->refresh_cycles == s->refreshes * 420);
  EXPECT(dram_banked_finished_cycles(d) == 400000);
  dram_banked_destroy(d);
  free(r);
  free(dn);
}

/* 7: streaming a row reaches the burst-limited peak. */
static void test_streaming(void) {
  struct dram_banked_params p = ddr4();
  uint64_t done[512];
  struct rq r[512];
  /* "rochrababgco": co lowest, so 128 consecutive lines are one row of one
   * bank. RD every tCCD_L = 6 (same group; > B = 4): 64 bytes per 6 cycles.
   * ACT 0, RDs 16 + 6 i, the last (i = 127) done 16 + 762 + 20 = 798. */
  for (int i = 0; i < 128; i++) r[i] = (struct rq){0, (uint64_t)i * 64, false};
  struct dram_banked *d = run(&p, 1200 * MHZ, r, 128, done, 0);
  for (int i = 0; i < 128; i++)
    EXPECTF(done[i] == 36 + 6 * (uint64_t)i, "stream line %d: done %llu, expected %llu", i,
            (unsigned long long)done[i], 36 + 6 * (unsigned long long)i);
  dram_banked_destroy(d);
  /* "rochrabacobg": bank group lowest, lines rotate over the 4 groups: RD every
   * max(B, tCCD_S) = 4 cycles, 64 bytes per 4 cycles (16 B/cycle, 19.2 GB/s).
   * ACTs 0, 4, 8, 12; RDs 16 + 4 i; line i done 36 + 4 i, the last 2080. */
  strcpy(p.mapping, "rochrabacobg");
  for (int i = 0; i < 512; i++) r[i] = (struct rq){0, (uint64_t)i * 64, false};
  d = run(&p, 1200 * MHZ, r, 512, done, 0);
  int bad = 0;
  for (int i = 0; i < 512; i++) bad += done[i] != 36 + 4 * (uint64_t)i;
  EXPECTF(bad == 0 && done[511] == 2080, "bank-group stream: %d off, last %llu, expected 2080", bad,
          (unsigned long long)done[511]);
  dram_banked_destroy(d);
}

/* 8: a new row every access over all 16 banks (close page): tFAW binds
 * (4 ACTs / 26 cycles < 16 banks / tRC 55, < 1 / tRRD_S 4); two banks only:
 * tRC binds (each bank once per 55 cycles). */
static void test_act_bound(void) {
  struct dram_banked_params p = ddr4();
  p.page = DRAM_BANKED_CLOSE_PAGE;
  enum { N = 640 };
  struct rq r[N];
  uint64_t done[N];
  for (int i = 0; i < N; i++)
    r[i] = (struct rq){0, addr_of(&p, 0, 0, i % 4, (i / 4) % 4, (uint64_t)i / 16 + 1, 0), false};
  struct dram_banked *d = run(&p, 1200 * MHZ, r, N, done, 0);
  /* Each done is its ACT + 36 (RD at tRCD, tCCD and the bus never bind here),
   * so the dones show the ACTs: any 5 in a row span >= tFAW. */
  int bad = 0;
  for (int i = 0; i + 4 < N; i++) bad += done[i + 4] - done[i] < 26;
  EXPECTF(bad == 0, "%d windows of 5 ACTs within tFAW", bad);
  double rate = (double)(N - 1) / (double)(done[N - 1] - done[0]);
  double bound = 4.0 / 26.0;
  EXPECTF(rate <= bound * (double)N / (N - 4) && rate >= 0.98 * bound,
          "ACT rate %.5f, tFAW bound %.5f", rate, bound);
  EXPECT(dram_banked_get_stats(d)->activates == N && dram_banked_get_stats(d)->precharges == N);
  dram_banked_destroy(d);
  /* Two banks (groups 0 and 1): ACT to ACT of a bank = RD (ACT + 16) ->
   * auto-precharge at max(ACT + tRAS 39, RD + tRTP 9) = ACT + 39 -> ACT + 39 +
   * tRP 16 = ACT + 55 = tRC: a bank's dones exactly 55 apart. */
  for (int i = 0; i < 64; i++)
    r[i] = (struct rq){0, addr_of(&p, 0, 0, i % 2, 0, (uint64_t)i + 1, 0), false};
  d = run(&p, 1200 * MHZ, r, 64, done, 0);
  bad = 0;
  for (int i = 0; i + 2 < 64; i++) bad += done[i + 2] - done[i] != 55;
  EXPECTF(bad == 0 && done[0] == 36 && done[1] == 40, "tRC bound: %d gaps off, first %llu %llu",
          bad, (unsigned long long)done[0], (unsigned long long)done[1]);
  dram_banked_destroy(d);
}

/* 9: close page against open page on a row-hit stream. */
static void test_page_policy(void) {
  struct dram_banked_params p = ddr4();
  enum { N = 64 };
  struct rq r[N];
  uint64_t done[N];
  /* Spaced 100 apart: open page, first 36 then tCL + B = 20 each; close page,
   * tRCD + tCL + B = 36 each. */
  for (int i = 0; i < N; i++)
    r[i] = (struct rq){100 * (uint64_t)i, addr_of(&p, 0, 0, 0, 0, 4, (uint64_t)i), false};
  for (int cp = 0; cp < 2; cp++) {
    p.page = cp ? DRAM_BANKED_CLOSE_PAGE : DRAM_BANKED_OPEN_PAGE;
    struct dram_banked *d = run(&p, 1200 * MHZ, r, N, done, 0);
    int bad = 0;
    for (int i = 0; i < N; i++) bad += done[i] - r[i].at != (cp || i == 0 ? 36u : 20u);
    EXPECTF(bad == 0, "%s page, spaced hits: %d latencies off", cp ? "close" : "open", bad);
    const struct dram_banked_stats *s = dram_banked_get_stats(d);
    EXPECT(s->row_hits == (cp ? 0u : N - 1u) && s->activates == (cp ? N : 1u));
    dram_banked_destroy(d);
  }
  /* All at 0: open page, RD every tCCD_L, last done 36 + 6 x 63 = 414; close
   * page, one ACT per tRC (see test_act_bound), last done 55 x 63 + 36 = 3501. */
  for (int i = 0; i < N; i++) r[i].at = 0;
  p.page = DRAM_BANKED_OPEN_PAGE;
  struct dram_banked *d = run(&p, 1200 * MHZ, r, N, done, 0);
  EXPECTF(done[N - 1] == 414, "open page stream: last %llu, expected 414",
          (unsigned long long)done[N - 1]);
  dram_banked_destroy(d);
  p.page = DRAM_BANKED_CLOSE_PAGE;
  d = run(&p, 1200 * MHZ, r, N, done, 0);
  EXPECTF(done[N - 1] == 3501, "close page stream: last %llu, expected 3501",
          (unsigned long long)done[N - 1]);
  dram_banked_destroy(d);
}

/* 10: FR-FCFS: a younger hit passes an older conflict. */
static void test_frfcfs(void) {
  struct dram_banked_params p = ddr4();
  uint64_t done[3];
  /* A at 0 (row 1): ACT 0, RD 16, done 36. B at 1 (row 2): its PRE waits while
   * C at 2 (row 1) hits: C's RD at 16 + tCCD_L = 22, done 42. B: PRE at
   * max(ACT + tRAS = 39, 22 + tRTP = 31) = 39, ACT 55, RD 71, done 91. */
  struct rq a[] = {{0, addr_of(&p, 0, 0, 0, 0, 1, 0), false},
                   {1, addr_of(&p, 0, 0, 0, 0, 2, 0), false},
                   {2, addr_of(&p, 0, 0, 0, 0, 1, 1), false}};
  struct dram_banked *d = run(&p, 1200 * MHZ, a, 3, done, 0);
  EXPECTF(done[0] == 36 && done[1] == 91 && done[2] == 42,
          "FR-FCFS: %llu %llu %llu, expected 36 91 42", (unsigned long long)done[0],
          (unsigned long long)done[1], (unsigned long long)done[2]);
  dram_banked_destroy(d);
  /* The starvation bound: 20 hits to row 1 queued behind one conflict (row 2)
   * at 0; the row serves A plus DRAM_BANKED_ROW_HIT_CAP - 1 more hits, then the
   * conflict goes before the younger hits: B is not last. */
  struct rq b[22];
  uint64_t dn[22];
  b[0] = (struct rq){0, addr_of(&p, 0, 0, 0, 0, 1, 0), false};
  b[1] = (struct rq){0, addr_of(&p, 0, 0, 0, 0, 2, 0), false};
  for (int i = 2; i < 22; i++)
    b[i] = (struct rq){0, addr_of(&p, 0, 0, 0, 0, 1, (uint64_t)i), false};
  d = run(&p, 1200 * MHZ, b, 22, dn, 0);
  int before = 0;
  for (int i = 2; i < 22; i++) before += dn[i] < dn[1];
  EXPECTF(before == DRAM_BANKED_ROW_HIT_CAP - 1,
          "%d younger hits went before the conflict, expected %u", before,
          DRAM_BANKED_ROW_HIT_CAP - 1);
  dram_banked_destroy(d);
}

/* 11: writes held until write_high, drained to write_low. */
static void test_write_drain(void) {
  struct dram_banked_params p = ddr4();
  p.read_queue = 8;
  p.write_queue = 16;
  p.write_high = 8;
  p.write_low = 2;
  enum { NR = 300, NW = 8 };
  struct rq r[NR + NW];
  uint64_t done[NR + NW];
  /* 300 reads at 0 (one row, a hit stream: one per 6 cycles, ~1800 cycles)
   * keep reads queued; writes at 100, 110, ..., 170 to another group. */
  for (int i = 0; i < NR; i++)
    r[i] = (struct rq){0, addr_of(&p, 0, 0, 0, 0, 1, (uint64_t)i % 128), false};
  for (int i = 0; i < NW; i++)
    r[NR + i] = (struct rq){100 + 10 * (uint64_t)i, addr_of(&p, 0, 0, 1, 0, 1, (uint64_t)i), true};
  struct dram_banked *d = run(&p, 1200 * MHZ, r, NR + NW, done, 0);
  uint64_t last_read = 0;
  for (int i = 0; i < NR; i++)
    if (done[i] > last_read) last_read = done[i];
  int early = 0, drained = 0;
  for (int i = 0; i < NW; i++) {
    early += done[NR + i] <= 170;
    drained += done[NR + i] < last_read;
  }
  EXPECTF(early == 0, "%d writes served before write_high was reached", early);
  EXPECTF(drained == NW - 2,
          "%d writes drained while reads waited, expected %d (8 down to write_low 2)", drained,
          NW - 2);
  EXPECT(dram_banked_get_stats(d)->write_drains == 2);
  dram_banked_destroy(d);
}

/* A read does not starve behind a write stream that never lets the write
 * queue fall to write_low: once it has waited DRAM_BANKED_READ_AGE_CAP x tRC
 * (4 x 55 = 220 cycles) the channel turns to reads; then it needs at most a
 * write's recovery before the precharge (tCWL + BL/2 + tWR = 39), tRP, tRCD,
 * tCL and a burst (16 + 16 + 16 + 4): served by 100 + 220 + 91 + a few
 * cycles for the command bus. Without the bound it waits for the stream's end
 * (2000 writes, at least 4 cycles each). */
static void test_starvation(void) {
  struct dram_banked_params p = ddr4();
  p.write_queue = 16;
  p.write_high = 16;
  p.write_low = 8;
  enum { NW = 2000 };
  struct rq r[NW + 1];
  uint64_t done[NW + 1];
  for (int i = 0; i < NW; i++) /* every write a new row of one bank: slow to serve */
    r[i] = (struct rq){(uint64_t)i, addr_of(&p, 0, 0, 0, 0, 2 + (uint64_t)i % 64, 0), true};
  r[NW] = (struct rq){100, addr_of(&p, 0, 0, 0, 0, 1, 0), false};
  struct dram_banked *d = run(&p, 1200 * MHZ, r, NW + 1, done, 0);
  uint64_t last_write = 0;
  for (int i = 0; i < NW; i++)
    if (done[i] > last_write) last_write = done[i];
  EXPECTF(done[NW] <= 100 + 220 + 91 + 20 && last_write > 8000,
          "the read was served at %llu, the last write at %llu", (unsigned long long)done[NW],
          (unsigned long long)last_write);
  dram_banked_destroy(d);
}

/* 16: per_bank, one request alone: it arrives after DRAM cycle 100, moves
 * to its bank's command queue at the end of 101, ACT 102, RD 102 + tRCD 16 =
 * 118, last beat 118 + tCL 16 + B 4 = 138: 2 + tRCD + tCL + B after arrival.
 * A row hit at 300: RD 302, done 322 (2 + tCL + B). Another row of the bank
 * at 500: PRE 502, ACT 518 (tRP), RD 534, done 554. Row hits counted as
 * DRAMsim3 does (the first column command after an ACT is not one). */
static void test_cq_latencies(void) {
  struct dram_banked_params p = ddr4_per_bank();
  uint64_t done[3];
  struct rq a[] = {{100, addr_of(&p, 0, 0, 0, 0, 7, 0), false},
                   {300, addr_of(&p, 0, 0, 0, 0, 7, 1), false},
                   {500, addr_of(&p, 0, 0, 0, 0, 9, 0), false}};
  struct dram_banked *d = run(&p, 1200 * MHZ, a, 3, done, 0);
  EXPECTF(done[0] == 138 && done[1] == 322 && done[2] == 554,
          "per_bank idle read, row hit, conflict: %llu %llu %llu, expected 138 322 554",
          (unsigned long long)done[0], (unsigned long long)done[1], (unsigned long long)done[2]);
  const struct dram_banked_stats *s = dram_banked_get_stats(d);
  EXPECT(s->row_hits == 1 && s->row_misses == 1 && s->row_conflicts == 1 && s->activates == 2);
  dram_banked_destroy(d);
  /* Two requests in one DRAM cycle: the channel takes one a cycle, the second
   * in the next (refused, then asked again): done 138 and 138 + 6 (its RD
   * tCCD_L after the first, its line the next column of the open row). */
  struct rq b[] = {{100, addr_of(&p, 0, 0, 0, 0, 7, 0), false},
                   {100, addr_of(&p, 0, 0, 0, 0, 7, 1), false}};
  d = run(&p, 1200 * MHZ, b, 2, done, 0);
  EXPECTF(done[0] == 138 && done[1] == 144, "one a cycle: %llu %llu, expected 138 144",
          (unsigned long long)done[0], (unsigned long long)done[1]);
  dram_banked_destroy(d);
}

/* 17: per_bank, the command queues are served round robin from the one after
 * the last that issued, not oldest first. Reads R0-R3 arriving at 0, 1, 2, 3
 * to bank 1 of groups 0-3 (queues 1, 5, 9, 13), A at 4 to bank 0 of group 0
 * (queue 0), B at 5 to bank 0 of group 3 (queue 12); each may issue 2 cycles
 * after it arrives. ACTs: R0 at 2, R1 at 6 (tRRD_S), R2 at 10 (the probe from
 * queue 6 reaches 9 first), and at 14 the probe from 10 reaches B (queue 12)
 * before R3 (13) and A (0, the probe's last), though B is the youngest. Then
 * tFAW holds ACTs to 2 + 26 = 28. RDs R0 18, R1 22, R2 26 (tRCD). At 28 the
 * probe from 10 finds R3's ACT (B's RD waits for tRCD to 30); B's RD 30 (from
 * 13 the probe wraps to 12); A's ACT at 32 (tFAW from 6, tRRD_S from 28); R3's
 * RD 44, A's 48. Done: RD + tCL 16 + B 4. */
static void test_cq_round_robin(void) {
  struct dram_banked_params p = ddr4_per_bank();
  struct rq r[6];
  uint64_t done[6];
  for (uint32_t g = 0; g < 4; g++) r[g] = (struct rq){g, addr_of(&p, 0, 0, g, 1, 3, 0), false};
  r[4] = (struct rq){4, addr_of(&p, 0, 0, 0, 0, 3, 0), false}; /* A */
  r[5] = (struct rq){5, addr_of(&p, 0, 0, 3, 0, 3, 0), false}; /* B */
  struct dram_banked *d = run(&p, 1200 * MHZ, r, 6, done, 0);
  const uint64_t want[6] = {38, 42, 46, 64, 68, 50};
  for (int i = 0; i < 6; i++)
    EXPECTF(done[i] == want[i], "round robin, read %d: done %llu, expected %llu", i,
            (unsigned long long)done[i], (unsigned long long)want[i]);
  dram_banked_destroy(d);
  /* The shared FR-FCFS structure serves the older A first. */
  p = ddr4();
  d = run(&p, 1200 * MHZ, r, 6, done, 0);
  EXPECTF(done[4] < done[5], "shared: A done %llu, B %llu, expected A first",
          (unsigned long long)done[4], (unsigned long long)done[5]);
  dram_banked_destroy(d);
}

/* 18: per_bank write drain and posted writes. write_queue 4, write_high 4,
 * write_low 2. Writes W0-W2 at 0, 1, 2 to bank 0 of group 0, row 1: each is
 * served 2 cycles after it arrives (posted). At the end of cycle 3 the buffer
 * holds 3 > write_low with every command queue empty: a drain of 3 moves them
 * at the ends of 3, 4 and 5. A read R at 3 to the same row waits in the read
 * queue meanwhile (moves at the end of 6, behind the writes in the bank's
 * queue). ACT 4; WR 20, 26, 32 (tCCD_L); R's RD after the last write's burst
 * and tWTR_L: 32 + tCWL 16 + B 4 + 9 = 61, done 81. A read at 4 of W1's line
 * is answered from the write buffer: done 6. */
static void test_cq_write_drain(void) {
  struct dram_banked_params p = ddr4_per_bank();
  p.write_queue = 4;
  p.write_high = 4;
  p.write_low = 2;
  struct rq r[5];
  uint64_t done[5];
  for (int i = 0; i < 3; i++)
    r[i] = (struct rq){(uint64_t)i, addr_of(&p, 0, 0, 0, 0, 1, (uint64_t)i), true};
  r[3] = (struct rq){3, addr_of(&p, 0, 0, 0, 0, 1, 5), false};
  r[4] = (struct rq){4, addr_of(&p, 0, 0, 0, 0, 1, 1), false};
  struct dram_banked *d = run(&p, 1200 * MHZ, r, 5, done, 0);
  const uint64_t want[5] = {2, 3, 4, 81, 6};
  for (int i = 0; i < 5; i++)
    EXPECTF(done[i] == want[i], "write drain, request %d: done %llu, expected %llu", i,
            (unsigned long long)done[i], (unsigned long long)want[i]);
  const struct dram_banked_stats *s = dram_banked_get_stats(d);
  EXPECT(s->write_drains == 1 && s->writes == 3 && s->reads == 1 && s->write_forwards == 1);
  dram_banked_destroy(d);
  /* Two writes (not more than write_low) and no other traffic stay buffered
   * until the channel has been idle idle_drain_cycles: a read of another row
   * of their bank at 500 finds it closed (ACT 502, done 538); they are
   * written by the end (finish checks nothing is left queued), the second
   * arrived after cycle 1, so drained from the end of 1001 on. With
   * idle_drain_cycles 0 (DRAMsim3's) the read is the same, the writes are
   * never written and the run ends with the read. */
  struct rq b[] = {{0, addr_of(&p, 0, 0, 0, 0, 1, 0), true},
                   {1, addr_of(&p, 0, 0, 0, 0, 1, 1), true},
                   {500, addr_of(&p, 0, 0, 0, 0, 2, 0), false}};
  for (uint32_t idle = 1000; idle != UINT32_MAX; idle = idle ? 0 : UINT32_MAX) {
    p.idle_drain_cycles = idle;
    d = run(&p, 1200 * MHZ, b, 3, done, 0);
    EXPECTF(done[0] == 2 && done[1] == 3 && done[2] == 538,
            "idle writes (%u): %llu %llu %llu, expected 2 3 538", idle, (unsigned long long)done[0],
            (unsigned long long)done[1], (unsigned long long)done[2]);
    s = dram_banked_get_stats(d);
    const uint64_t end = dram_banked_finished_cycles(d);
    if (idle) {
      EXPECT(s->writes == 2 && s->writes_left == 0 && s->write_drains == 1 &&
             s->row_conflicts == 1);
      EXPECTF(end > 1001 + 2 + 16,
              "idle writes: finished at %llu, expected past the drain's ACT "
              "(1002) and first WR (1018)",
              (unsigned long long)end);
    } else {
      EXPECT(s->writes == 0 && s->writes_left == 2 && s->write_drains == 0 && s->row_misses == 1 &&
             s->activates == 1);
      EXPECTF(end == 539, "no idle drain: finished at %llu, expected 539 (the read's data at 538)",
              (unsigned long long)end);
    }
    dram_banked_destroy(d);
  }
}

/* 19: per_bank, a row hit does not pass an older request's ready ACT or PRE
 * in its own queue unless the PRE would close a row the queue still hits:
 * A (row 1) at 0, B (row 2) at 1, C (row 1) at 2, one bank. ACT (A) 2, RD A
 * 18; B's PRE waits while C hits: C's RD at 24 (tCCD_L), done 44; PRE at
 * max(2 + tRAS 39, 24 + tRTP 9) = 41, ACT 57, RD 73, done 93. A read D at 3
 * of A's line is served with A (one RD): done 38. */
static void test_cq_in_order(void) {
  struct dram_banked_params p = ddr4_per_bank();
  struct rq a[] = {{0, addr_of(&p, 0, 0, 0, 0, 1, 0), false},
                   {1, addr_of(&p, 0, 0, 0, 0, 2, 0), false},
                   {2, addr_of(&p, 0, 0, 0, 0, 1, 1), false},
                   {3, addr_of(&p, 0, 0, 0, 0, 1, 0), false}};
  uint64_t done[4];
  struct dram_banked *d = run(&p, 1200 * MHZ, a, 4, done, 0);
  EXPECTF(done[0] == 38 && done[1] == 93 && done[2] == 44 && done[3] == 38,
          "per_bank order: %llu %llu %llu %llu, expected 38 93 44 38", (unsigned long long)done[0],
          (unsigned long long)done[1], (unsigned long long)done[2], (unsigned long long)done[3]);
  const struct dram_banked_stats *s = dram_banked_get_stats(d);
  EXPECT(s->reads == 3 && s->read_merges == 1 && s->row_hits == 1);
  dram_banked_destroy(d);
}

/* dram_row_hit_rate is row hits over column commands (RD and WR issued), as
 * DRAMsim3 reports it, and its description says so: a read served with
 * another's RD and a read answered from the write buffer issue none. By
 * hand, the two cases above: per_bank order (A finds its bank closed, C
 * hits, B conflicts, D is served with A): 1 hit of 3 commands, not of 4
 * requests; the write drain (W0 opens row 1, W1, W2 and R3 hit it, R4 is
 * answered from the buffer): 3 hits of 4 commands, not of 5 requests. */
static double row_hit_rate(const struct dram_banked *d) {
  struct stats_table t = {0};
  dram_level_report(&dram_banked_ops, d, &t, 1000);
  double v = -1;
  for (unsigned i = 0; i < t.n; i++)
    if (!strcmp(t.e[i].name, "dram_row_hit_rate")) v = t.e[i].f;
  stats_fini(&t);
  return v;
}

static void test_row_hit_rate(void) {
  struct dram_banked_params p = ddr4_per_bank();
  struct rq a[] = {{0, addr_of(&p, 0, 0, 0, 0, 1, 0), false},
                   {1, addr_of(&p, 0, 0, 0, 0, 2, 0), false},
                   {2, addr_of(&p, 0, 0, 0, 0, 1, 1), false},
                   {3, addr_of(&p, 0, 0, 0, 0, 1, 0), false}};
  uint64_t done[5];
  struct dram_banked *d = run(&p, 1200 * MHZ, a, 4, done, 0);
  const struct dram_banked_stats *s = dram_banked_get_stats(d);
  EXPECT(s->row_hits + s->row_misses + s->row_conflicts == s->reads + s->writes);
  EXPECTF(s->row_hits == 1 && s->reads == 3 && row_hit_rate(d) == 1.0 / 3,
          "merged read: rate %.6f, %llu hits of %llu commands", row_hit_rate(d),
          (unsigned long long)s->row_hits, (unsigned long long)(s->reads + s->writes));
  dram_banked_destroy(d);

  p.write_queue = 4;
  p.write_high = 4;
  p.write_low = 2;
  struct rq r[5];
  for (int i = 0; i < 3; i++)
    r[i] = (struct rq){(uint64_t)i, addr_of(&p, 0, 0, 0, 0, 1, (uint64_t)i), true};
  r[3] = (struct rq){3, addr_of(&p, 0, 0, 0, 0, 1, 5), false};
  r[4] = (struct rq){4, addr_of(&p, 0, 0, 0, 0, 1, 1), false};
  d = run(&p, 1200 * MHZ, r, 5, done, 0);
  s = dram_banked_get_stats(d);
  EXPECT(s->row_hits + s->row_misses + s->row_conflicts == s->reads + s->writes);
  EXPECTF(s->write_forwards == 1 && s->reads + s->writes == 4 && s->row_hits == 3 &&
              row_hit_rate(d) == 3.0 / 4,
          "forwarded read: rate %.6f, %llu hits of %llu commands", row_hit_rate(d),
          (unsigned long long)s->row_hits, (unsigned long long)(s->reads + s->writes));
  dram_banked_destroy(d);

  /* The description says what is computed. */
  const char *desc = NULL;
  for (unsigned i = 0; i < dram_banked_stats_descs.n; i++)
    if (!strcmp(dram_banked_stats_descs.d[i].name, "dram_row_hit_rate"))
      desc = dram_banked_stats_descs.d[i].desc;
  EXPECTF(desc && strstr(desc, "column commands") && !strstr(desc, "requests ("),
          "dram_row_hit_rate: %s", desc ? desc : "(none)");
}

/* Random traffic: bursts of arrivals, 30% writes, a small footprint of rows
 * so hits, misses and conflicts all occur. */
static void random_traffic(const struct dram_banked_params *p, uint64_t seed, struct rq *r,
                           uint64_t n) {
  uint64_t x = seed * 0x9E3779B97F4A7C15ull + 1, t = 0;
  for (uint64_t i = 0; i < n; i++) {
    x ^= x << 13, x ^= x >> 7, x ^= x << 17;
    uint64_t g = x % 100;
    t += g < 50 ? 0 : g < 85 ? x % 7 : x % 400;
    x ^= x << 13, x ^= x >> 7, x ^= x << 17;
    r[i].at = t;
    r[i].write = x % 10 < 3;
    r[i].addr =
        addr_of(p, (uint32_t)((x >> 8) % p->channels), (uint32_t)((x >> 12) % p->ranks),
                (uint32_t)((x >> 16) % p->bank_groups), (uint32_t)((x >> 20) % p->banks_per_group),
                (x >> 24) % 3, (x >> 30) % (p->columns / p->burst_length));
  }
}

/* 13 and 14: skip-ahead against the per-cycle oracle, and Little's law. */
static void test_oracle_and_little(void) {
  struct cfg {
    const char *mapping;
    uint32_t channels, ranks, groups, banks, rq, wq, hi, lo;
    enum dram_banked_page page;
    uint64_t core_mhz;
    enum dram_banked_queues qs;
    uint32_t cmdq, cc;
    bool never_drain; /* idle_drain_cycles 0 (else the presets' 1000) */
  } cfgs[] = {
      {"rochrababgco", 1, 1, 4, 4, 32, 32, 24, 8, DRAM_BANKED_OPEN_PAGE, 1200, DRAM_BANKED_SHARED,
       0, 0, false},
      {"chrobabgraco", 2, 2, 4, 4, 16, 16, 12, 4, DRAM_BANKED_CLOSE_PAGE, 1400, DRAM_BANKED_SHARED,
       0, 0, false},
      {"rorabgbachco", 4, 4, 2, 2, 4, 4, 3, 1, DRAM_BANKED_OPEN_PAGE, 1000, DRAM_BANKED_SHARED, 0,
       0, false},
      {"robgbarachco", 2, 2, 4, 2, 8, 8, 6, 0, DRAM_BANKED_OPEN_PAGE, 2000, DRAM_BANKED_SHARED, 0,
       0, false},
      {"rochrababgco", 1, 2, 4, 4, 16, 16, 16, 8, DRAM_BANKED_OPEN_PAGE, 1400, DRAM_BANKED_PER_BANK,
       8, 2, false},
      {"chrobabgraco", 2, 2, 4, 4, 8, 8, 6, 2, DRAM_BANKED_CLOSE_PAGE, 1000, DRAM_BANKED_PER_BANK,
       2, 1, false},
      {"rorabgbachco", 2, 1, 4, 4, 16, 16, 12, 4, DRAM_BANKED_OPEN_PAGE, 2000, DRAM_BANKED_PER_RANK,
       32, 3, false},
      {"robgbarachco", 2, 4, 2, 2, 4, 4, 4, 0, DRAM_BANKED_OPEN_PAGE, 1200, DRAM_BANKED_PER_RANK, 3,
       2, false},
      {"rochrababgco", 1, 2, 4, 4, 16, 16, 16, 8, DRAM_BANKED_OPEN_PAGE, 1400, DRAM_BANKED_PER_BANK,
       8, 2, true},
      {"rorabgbachco", 2, 1, 4, 4, 16, 16, 12, 4, DRAM_BANKED_OPEN_PAGE, 2000, DRAM_BANKED_PER_RANK,
       32, 3, true},
  };
  enum { N = 1500, SEEDS = 6 };
  struct rq *r = xcalloc(N, sizeof *r);
  uint64_t *d1 = xcalloc(N, sizeof *d1), *d2 = xcalloc(N, sizeof *d2);
  int mismatched = 0, little_bad = 0;
  for (unsigned ci = 0; ci < sizeof cfgs / sizeof cfgs[0]; ci++) {
    struct dram_banked_params p = ddr4();
    strcpy(p.mapping, cfgs[ci].mapping);
    p.channels = cfgs[ci].channels;
    p.ranks = cfgs[ci].ranks;
    p.bank_groups = cfgs[ci].groups;
    p.banks_per_group = cfgs[ci].banks;
    p.rows = 256;
    p.read_queue = cfgs[ci].rq;
    p.write_queue = cfgs[ci].wq;
    p.write_high = cfgs[ci].hi;
    p.write_low = cfgs[ci].lo;
    p.page = cfgs[ci].page;
    p.queue_structure = cfgs[ci].qs;
    p.command_queue = cfgs[ci].cmdq;
    if (cfgs[ci].cc) p.controller_cycles = cfgs[ci].cc;
    if (cfgs[ci].never_drain) p.idle_drain_cycles = 0;
    p.tREFI = 2400; /* frequent, to exercise refresh */
    p.tRFC = 120;
    for (uint64_t seed = 1; seed <= SEEDS; seed++) {
      random_traffic(&p, seed * 31 + ci, r, N);
      uint64_t fin = r[N - 1].at + 200000;
      uint64_t khz = cfgs[ci].core_mhz * MHZ;
      p.tick_every_cycle = false;
      p.check_summaries = true;
      struct dram_banked *a = run(&p, khz, r, N, d1, fin);
      p.tick_every_cycle = true;
      struct dram_banked *b = run(&p, khz, r, N, d2, fin);
      const struct dram_banked_stats *sa = dram_banked_get_stats(a), *sb = dram_banked_get_stats(b);
      bool same = !memcmp(d1, d2, N * sizeof *d1) && !memcmp(sa, sb, sizeof *sa);
      if (!same) {
        mismatched++;
        fprintf(stderr, "config %u seed %llu: skip-ahead differs from the per-cycle oracle\n", ci,
                (unsigned long long)seed);
      }
      /* Every request is served by a column command, or from the write queue,
       * or is a write left buffered (never draining only, at most write_low a
       * channel). */
      EXPECT(sa->reads + sa->writes + sa->write_forwards + sa->write_merges + sa->read_merges +
                 sa->writes_left ==
             N);
      EXPECT(cfgs[ci].never_drain ? sa->writes_left <= p.write_low * p.channels
                                  : sa->writes_left == 0);
      EXPECT(sa->row_hits + sa->row_misses + sa->row_conflicts == sa->reads + sa->writes);
      /* Little: the occupancy integral by time equals the waits by request
       * (writes left buffered occupy the queue with no wait counted). */
      for (int k = 0; k < 2; k++)
        little_bad +=
            (k == 0 || !sa->writes_left) && sa->queue_area[k] != sa->queue_wait_sum_cycles[k];
      if (seed == 1) {
        struct stats_table t = {0};
        dram_level_report(&dram_banked_ops, a, &t, fin);
        double len[2] = {-1, -1}, wmean[2] = {-1, -1};
        for (unsigned i = 0; i < t.n; i++) {
          if (!strcmp(t.e[i].name, "dram_read_queue_length_mean")) len[0] = t.e[i].f;
          if (!strcmp(t.e[i].name, "dram_write_queue_length_mean")) len[1] = t.e[i].f;
          if (!strcmp(t.e[i].name, "dram_read_queue_wait_mean_cycles")) wmean[0] = t.e[i].f;
          if (!strcmp(t.e[i].name, "dram_write_queue_wait_mean_cycles")) wmean[1] = t.e[i].f;
        }
        double nk[2] = {(double)sa->reads, (double)sa->writes};
        for (int k = 0; k < 2; k++) {
          if (k == 1 && sa->writes_left) continue; /* (as above) */
          double lhs = len[k] * (double)fin, rhs = wmean[k] * nk[k];
          EXPECTF(lhs > 0 && rhs > 0 && lhs <= rhs * (1 + 1e-9) && rhs <= lhs * (1 + 1e-9),
                  "Little, queue %d: length mean x cycles %.3f, waits %.3f", k, lhs, rhs);
        }
        stats_fini(&t);
      }
      dram_banked_destroy(a);
      dram_banked_destroy(b);
    }
  }
  EXPECTF(mismatched == 0, "%d runs differ between skip-ahead and per-cycle", mismatched);
  EXPECTF(little_bad == 0, "%d queues break Little's law", little_bad);
  free(r);
  free(d1);
  free(d2);
}

int main(void) {
  test_latencies();
  test_wtr();
  test_act_spacing();
  test_refresh();
  test_streaming();
  test_act_bound();
  test_page_policy();
  test_frfcfs();
  test_write_drain();
  test_starvation();
  test_cq_latencies();
  test_cq_round_robin();
  test_cq_write_drain();
  test_cq_in_order();
  test_row_hit_rate();
  test_oracle_and_little();
  return testing_done("dram_banked");
}
