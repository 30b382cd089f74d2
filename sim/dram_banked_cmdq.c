/* The banked level's command queues (queue_structure per_bank / per_rank):
 * which commands a queue offers (its candidates), the summary each queue keeps
 * of them, and the round-robin scan over the summaries. Holds: a fresh summary
 * equals its candidates asked again at any cycle from its `at` to its least
 * time (check_summaries CHECKs it), because every change that could move a
 * candidate's time clears the queue's fresh bit (the dram_banked_stale_
 * calls; see cq_sum for why that suffices). */
#include "sim/dram_banked_state.h"

#include "sim/err.h"

/* Clear, in bitmap `fresh`, the bits of [lo, hi) set in `mask` (NULL: all). */
static void stale_range(uint64_t *fresh, const uint64_t *mask, uint32_t lo, uint32_t hi) {
  for (uint32_t i = lo; i < hi;) {
    const uint32_t w = i / 64, b = i % 64, n = hi - i < 64 - b ? hi - i : 64 - b;
    const uint64_t bits = (n == 64 ? ~0ull : ((1ull << n) - 1)) << b;
    fresh[w] &= ~(bits & (mask ? mask[w] : ~0ull));
    i += n;
  }
}

/* The command queues holding rank k's requests: [*lo, *hi). */
static void rank_queues(const struct dram_banked *d, uint32_t k, uint32_t *lo, uint32_t *hi) {
  const bool per_rank = d->p.queue_structure == DRAM_BANKED_PER_RANK;
  *lo = per_rank ? k : k * d->banks_per_rank;
  *hi = per_rank ? k + 1 : (k + 1) * d->banks_per_rank;
}

/* Bank `bank`'s state or its command queue's entries changed. */
void dram_banked_stale_bank(const struct dram_banked *d, struct dram_banked_channel *c,
                            uint32_t bank) {
  if (!d->cq_mode) return;
  const uint32_t qi =
      d->p.queue_structure == DRAM_BANKED_PER_RANK ? bank / d->banks_per_rank : bank;
  c->fresh[qi / 64] &= ~(1ull << (qi % 64));
}

/* A refresh changed all of rank k's state. */
void dram_banked_stale_rank(const struct dram_banked *d, struct dram_banked_channel *c,
                            uint32_t k) {
  if (!d->cq_mode) return;
  uint32_t lo, hi;
  rank_queues(d, k, &lo, &hi);
  stale_range(c->fresh, NULL, lo, hi);
}

/* Clear the fresh bit of each queue of [lo, hi) set in `mask` whose summary
 * has an ACT candidate before h_act, a RD before h_rd or a WR before h_wr. */
static void stale_before(struct dram_banked_channel *c, const uint64_t *mask, uint32_t lo,
                         uint32_t hi, int64_t h_act, int64_t h_rd, int64_t h_wr) {
  for (uint32_t w = lo / 64; w * 64 < hi; w++) {
    uint64_t bits = mask[w] & c->fresh[w];
    if (w == lo / 64) bits &= ~0ull << (lo % 64);
    if (hi - w * 64 < 64) bits &= (1ull << (hi - w * 64)) - 1;
    while (bits) {
      const uint32_t b = (uint32_t)__builtin_ctzll(bits);
      const struct dram_banked_qsum *s = &c->sum[w * 64 + b];
      bits &= bits - 1;
      if (s->act_t < h_act || s->rd_t < h_rd || s->wr_t < h_wr) {
        /* per_bank: a column command moves only the column candidates. */
        if (h_act == DRAM_BANKED_FAR && c->col_stale) c->col_stale[w] |= 1ull << b;
        else c->fresh[w] &= ~(1ull << b);
      }
    }
  }
}

/* An ACT in rank k at `now` moved its ACT spacing (tRRD, tFAW): nothing
 * before now + tRRD_L or the new oldest of the last four ACTs + tFAW changes
 * (tRRD_L >= tRRD_S), so only its queues with an ACT candidate earlier than
 * that can be stale. */
void dram_banked_stale_acts(const struct dram_banked *d, struct dram_banked_channel *c, uint32_t k,
                            int64_t now) {
  if (!d->cq_mode) return;
  const struct dram_banked_rank *rk = &c->ranks[k];
  const int64_t h = max64(now + d->p.tRRD_L, rk->faw[rk->faw_i] + d->p.tFAW);
  uint32_t lo, hi;
  rank_queues(d, k, &lo, &hi);
  stale_before(c, c->has_act, lo, hi, h, DRAM_BANKED_FAR, DRAM_BANKED_FAR);
}

/* A column command at `now` moved the column spacing (tCCD, tWTR, tRTW) and
 * put a burst on the data bus. Each constraint it adds ends by the bounds
 * below (one idle cycle between bursts, whichever ranks; tCCD_L >= tCCD_S,
 * tWTR_L >= tWTR_S), and a column candidate no earlier than its bound keeps
 * its time: the new burst ends, gap included, before that candidate's data
 * would start. So only queues with a column candidate earlier can be stale. */
void dram_banked_stale_columns(const struct dram_banked *d, struct dram_banked_channel *c,
                               bool write, int64_t now) {
  if (!d->cq_mode) return;
  const struct dram_banked_params *p = &d->p;
  const int64_t b = d->burst_cycles;
  int64_t h_rd, h_wr;
  if (write) {
    h_rd = now + max64(p->tCWL + b + p->tWTR_L, (int64_t)p->tCWL + b + 1 - p->tCL);
    h_wr = now + max64(p->tCCD_L, b + 1);
  } else {
    h_rd = now + max64(p->tCCD_L, b + 1);
    h_wr = now + max64(p->tRTW, (int64_t)p->tCL + b + 1 - p->tCWL);
  }
  stale_before(c, c->has_col, 0, c->ncq, DRAM_BANKED_FAR, h_rd, h_wr);
}

/* Rank k's command queues take no command while it has a refresh due. */
void dram_banked_block_rank(const struct dram_banked *d, struct dram_banked_channel *c, uint32_t k,
                            bool due) {
  if (!d->cq_mode) return;
  uint32_t lo, hi;
  rank_queues(d, k, &lo, &hi);
  for (uint32_t i = lo; i < hi; i++) {
    const uint64_t bit = 1ull << (i % 64);
    c->blocked[i / 64] = due ? c->blocked[i / 64] | bit : c->blocked[i / 64] & ~bit;
  }
}

/* May the PRE at entry j of command queue q (for a conflict in bank bk) issue?
 * Not before an older request of its queue for the same bank, nor while one
 * of its queue still hits the open row, unless the row has served the cap. */
static bool pre_allowed(const struct dram_banked_queue *q, uint32_t j,
                        const struct dram_banked_bank *bk) {
  const struct dram_banked_req *r = &q->r[j];
  for (uint32_t i = 0; i < j; i++)
    if (q->r[i].bank == r->bank) return false;
  if (bk->hits >= DRAM_BANKED_ROW_HIT_CAP) return true;
  for (uint32_t i = j + 1; i < q->n; i++)
    if (q->r[i].bank == r->bank && q->r[i].row == bk->row) return false;
  return true;
}

/* Does the write at entry j of q wait behind an older read of its place in
 * the DRAM? NOTE: its place (bank, row, column), not its address: addresses
 * above the DRAM's capacity alias, and DRAMsim3 compares places here though
 * it forwards and merges by address. */
static bool write_behind_read(const struct dram_banked_queue *q, uint32_t j) {
  const struct dram_banked_req *w = &q->r[j];
  for (uint32_t i = 0; i < j; i++) {
    const struct dram_banked_req *r = &q->r[i];
    if (!r->write && r->bank == w->bank && r->row == w->row && r->column == w->column) return true;
  }
  return false;
}

/* Command queue qi's candidates as of cycle now: the least earliest time and
 * the first candidate with it, into s; has_act and has_col say which kinds
 * of command it holds. */
static void cq_candidates(const struct dram_banked *d, const struct dram_banked_channel *c,
                          uint32_t qi, int64_t now, struct dram_banked_qsum *s, bool *has_act,
                          bool *has_col) {
  const struct dram_banked_queue *q = &c->cq[qi];
  struct dram_banked_pick pk = {
      .cmd.type = DRAM_BANKED_CMD_NONE, .next = DRAM_BANKED_FAR, .first_t = DRAM_BANKED_FAR};
  *has_act = *has_col = false;
  s->act_t = s->rd_t = s->wr_t = s->o_t = DRAM_BANKED_FAR;
  /* An ACT, RD or WR's earliest time depends on its request only through
   * the bank and `ready`, and never falls as `ready` grows: a later entry of
   * the same command and bank as the last one considered here, ready no
   * sooner, can neither come first nor lower the least (ties keep the
   * older), so it is not asked (in per_bank every entry shares the bank: of
   * the ACTs of a closed bank only the oldest is asked). */
  uint32_t seen_bank[3] = {UINT32_MAX, UINT32_MAX, UINT32_MAX}; /* ACT, RD, WR */
  int64_t seen_ready[3] = {0, 0, 0};
  for (uint32_t j = 0; j < q->n; j++) {
    const struct dram_banked_req *r = &q->r[j];
    const struct dram_banked_bank *bk = &c->banks[r->bank];
    enum dram_banked_cmd_type type;
    if (!bk->open || bk->row == r->row) {
      const int w = !bk->open ? 0 : r->write ? 2 : 1;
      if (seen_bank[w] == r->bank && r->ready >= seen_ready[w]) continue;
      if (w == 2 && write_behind_read(q, j)) continue;
      seen_bank[w] = r->bank;
      seen_ready[w] = r->ready;
      type = !w ? DRAM_BANKED_CMD_ACT : r->write ? DRAM_BANKED_CMD_WR : DRAM_BANKED_CMD_RD;
      if (!w) *has_act = true;
      else *has_col = true;
    } else {
      if (!pre_allowed(q, j, bk)) continue;
      type = DRAM_BANKED_CMD_PRE;
    }
    const int64_t t = dram_banked_req_earliest(d, c, r, type, now);
    if (type == DRAM_BANKED_CMD_RD || type == DRAM_BANKED_CMD_WR) {
      int64_t *least = type == DRAM_BANKED_CMD_RD ? &s->rd_t : &s->wr_t;
      if (t < *least) {
        *least = t;
        *(type == DRAM_BANKED_CMD_RD ? &s->rd_j : &s->wr_j) = j;
      }
    } else {
      if (type == DRAM_BANKED_CMD_ACT && t < s->act_t) s->act_t = t;
      if (t < s->o_t) {
        s->o_t = t;
        s->o = (struct dram_banked_cmd){type, r->rank, r->bank, j, qi, true};
      }
    }
    dram_banked_consider_in(&pk, t, now, type, r->rank, r->bank, qi, j);
  }
  s->at = now;
  s->t = pk.first_t;
  s->k = pk.first;
}

/* Command queue qi's summary as of cycle now, computed again only when
 * stale. NOTE: why a summary stays true. A candidate's earliest time asked at
 * n is h(max(n, T)), T from its request and the timing state, h the identity
 * (ACT, PRE) or the data bus's first fit (RD, WR), which is monotone and
 * maps every cycle between t0 and h(t0) to h(t0). So while the state it read
 * is unchanged, each candidate's time asked at any n in [at, t] is the time
 * asked at `at`, and the summary holds there. What it read, and the call that
 * marks it stale when that changes: the queue's entries and their bank
 * (dram_banked_stale_bank), the rank's ACT spacing for ACT candidates
 * (dram_banked_stale_acts), the rank, group and channel column spacing and the
 * bus for RD and WR candidates (dram_banked_stale_columns), a refresh
 * (dram_banked_stale_rank, all). */
/* per_bank: a summary whose column candidates alone may have moved, asked
 * again at now (within [at, t]). A per_bank queue holds one bank, so it has
 * at most one ACT or PRE candidate (its oldest entry: an ACT for a closed
 * bank, a PRE for a conflict, pre_allowed), one RD and one WR (each the
 * oldest of its kind asked, as `ready` grows along the queue): the first
 * least of those three is the queue's. */
static void col_refresh(const struct dram_banked *d, const struct dram_banked_channel *c,
                        uint32_t qi, int64_t now, struct dram_banked_qsum *s) {
  const struct dram_banked_queue *q = &c->cq[qi];
  int64_t t = s->o_t;
  struct dram_banked_cmd k = s->o;
  uint32_t kj = t < DRAM_BANKED_FAR ? s->o.qi : UINT32_MAX;
  for (int i = 0; i < 2; i++) {
    int64_t *ct = i ? &s->wr_t : &s->rd_t;
    if (*ct == DRAM_BANKED_FAR) continue;
    const uint32_t j = i ? s->wr_j : s->rd_j;
    const struct dram_banked_req *r = &q->r[j];
    *ct = dram_banked_col_earliest(d, c, r, r->write, now);
    if (*ct < t || (*ct == t && j < kj)) {
      t = *ct;
      kj = j;
      k = (struct dram_banked_cmd){
          r->write ? DRAM_BANKED_CMD_WR : DRAM_BANKED_CMD_RD, r->rank, r->bank, j, qi, true};
    }
  }
  s->at = now;
  s->t = t;
  s->k = k;
}

/* per_bank: command queue qi's candidates as cq_candidates finds them, from
 * what a queue of one bank can offer (see col_refresh): a closed bank, its
 * oldest entry's ACT; an open one, the oldest read and the oldest write of
 * the open row (a write behind an older read of its place skipped), and a
 * PRE for the oldest entry when it conflicts and no entry hits the row (or
 * the row has served the cap). Holds because `ready` never falls along a
 * command queue (entries move to it in cycle order). */
static void bank_candidates(const struct dram_banked *d, const struct dram_banked_channel *c,
                            uint32_t qi, int64_t now, struct dram_banked_qsum *s, bool *has_act,
                            bool *has_col) {
  const struct dram_banked_queue *q = &c->cq[qi];
  const struct dram_banked_bank *bk = &c->banks[qi];
  const struct dram_banked_req *r0 = &q->r[0];
  s->act_t = s->rd_t = s->wr_t = s->o_t = DRAM_BANKED_FAR;
  s->o = (struct dram_banked_cmd){DRAM_BANKED_CMD_NONE, 0, 0, 0, 0, false};
  *has_act = !bk->open;
  if (!bk->open) {
    s->act_t = s->o_t = dram_banked_act_earliest(d, c, r0, now);
    s->o = (struct dram_banked_cmd){DRAM_BANKED_CMD_ACT, r0->rank, r0->bank, 0, qi, true};
  } else {
    bool hit = false;
    for (uint32_t j = 0; j < q->n && (s->rd_t == DRAM_BANKED_FAR || s->wr_t == DRAM_BANKED_FAR);
         j++) {
      const struct dram_banked_req *r = &q->r[j];
      if (r->row != bk->row) continue;
      hit = true;
      if (!r->write) {
        if (s->rd_t == DRAM_BANKED_FAR) s->rd_t = now, s->rd_j = j;
      } else if (s->wr_t == DRAM_BANKED_FAR && !write_behind_read(q, j)) {
        s->wr_t = now, s->wr_j = j;
      }
    }
    if (r0->row != bk->row && (bk->hits >= DRAM_BANKED_ROW_HIT_CAP || !hit)) {
      s->o_t = max64(max64(now, r0->ready), bk->pre_ok);
      s->o = (struct dram_banked_cmd){DRAM_BANKED_CMD_PRE, r0->rank, r0->bank, 0, qi, true};
    }
  }
  *has_col = s->rd_t < DRAM_BANKED_FAR || s->wr_t < DRAM_BANKED_FAR;
  col_refresh(d, c, qi, now, s); /* (the column times, and the first least) */
}

/* Test only (check_summaries): bank_candidates' summary s of command queue
 * qi at now, and its kinds, against cq_candidates' from scratch. */
static void check_bank_candidates(const struct dram_banked *d, const struct dram_banked_channel *c,
                                  uint32_t qi, int64_t now, const struct dram_banked_qsum *s,
                                  bool act, bool col) {
  struct dram_banked_qsum full;
  bool full_act, full_col;
  cq_candidates(d, c, qi, now, &full, &full_act, &full_col);
  CHECK_EQ(full_act, act);
  CHECK_EQ(full_col, col);
  CHECK_EQ(full.t, s->t);
  CHECK_EQ(full.act_t, s->act_t);
  CHECK_EQ(full.rd_t, s->rd_t);
  CHECK_EQ(full.wr_t, s->wr_t);
  CHECK_EQ(full.o_t, s->o_t);
  CHECK(full.rd_t == DRAM_BANKED_FAR || full.rd_j == s->rd_j);
  CHECK(full.wr_t == DRAM_BANKED_FAR || full.wr_j == s->wr_j);
  CHECK(full.o_t == DRAM_BANKED_FAR || (full.o.type == s->o.type && full.o.qi == s->o.qi));
  CHECK(full.t == DRAM_BANKED_FAR ||
        (full.k.type == s->k.type && full.k.qi == s->k.qi && full.k.bank == s->k.bank));
}

static const struct dram_banked_qsum *
cq_sum(const struct dram_banked *d, struct dram_banked_channel *c, uint32_t qi, int64_t now) {
  struct dram_banked_qsum *s = &c->sum[qi];
  const uint32_t w = qi / 64;
  const uint64_t bit = 1ull << (qi % 64);
  if ((c->fresh[w] & bit) && now >= s->at && now <= s->t) {
    if (!c->col_stale || !(c->col_stale[w] & bit)) return s;
    c->col_stale[w] &= ~bit;
    col_refresh(d, c, qi, now, s);
    return s;
  }
  if ((c->fresh[w] & bit) && now > s->t && c->col_stale) {
    /* per_bank, past its least time with nothing it read changed: its
     * candidates are the same entries (which entries offer a command does
     * not depend on the cycle asked), the ACT or PRE one now at max(now, its
     * time) (the identity h), the column ones asked again. */
    c->col_stale[w] &= ~bit;
    if (s->o_t < now) s->o_t = now;
    if (s->act_t < now) s->act_t = now;
    col_refresh(d, c, qi, now, s);
    return s;
  }
  bool act, col;
  if (c->col_stale) {
    bank_candidates(d, c, qi, now, s, &act, &col);
    if (d->p.check_summaries) check_bank_candidates(d, c, qi, now, s, act, col);
  } else {
    cq_candidates(d, c, qi, now, s, &act, &col);
  }
  if (c->col_stale) c->col_stale[w] &= ~bit;
  c->fresh[w] |= bit;
  c->has_act[w] = act ? c->has_act[w] | bit : c->has_act[w] & ~bit;
  c->has_col[w] = col ? c->has_col[w] | bit : c->has_col[w] & ~bit;
  return s;
}

/* per_bank: a floor at now under the least time of command queue qi, whose
 * column candidates' times alone may have grown since its summary: its ACT
 * or PRE candidate's time holds (their state is unchanged, and both are at
 * least now), and a column candidate's time only grows with the spacing and
 * the bus, and is at or past its rank's floor (dram_banked_col_floor). */
static int64_t least_floor(const struct dram_banked *d, struct dram_banked_channel *c, uint32_t qi,
                           int64_t now) {
  const struct dram_banked_qsum *s = &c->sum[qi];
  const uint32_t rank = qi / d->banks_per_rank;
  int64_t t = s->o_t;
  if (s->rd_t < t) {
    const int64_t rd = max64(s->rd_t, dram_banked_col_floor(d, c, rank, false, now));
    if (rd < t) t = rd;
  }
  if (s->wr_t < t) {
    const int64_t wr = max64(s->wr_t, dram_banked_col_floor(d, c, rank, true, now));
    if (wr < t) t = wr;
  }
  return max64(t, now);
}

/* Test only (check_summaries): command queue qi's summary s at now against
 * its candidates asked from scratch; s->t exact, or with floor above
 * DRAM_BANKED_NEVER, only a floor under the least time. */
static void check_summary(const struct dram_banked *d, const struct dram_banked_channel *c,
                          uint32_t qi, int64_t now, const struct dram_banked_qsum *s,
                          int64_t floor) {
  struct dram_banked_qsum full;
  bool act, col;
  CHECK_GE(now, s->at);
  cq_candidates(d, c, qi, now, &full, &act, &col);
  if (floor > DRAM_BANKED_NEVER) {
    CHECK_GE(full.t, floor);
    return;
  }
  CHECK_EQ(full.t, s->t);
  CHECK(full.t == DRAM_BANKED_FAR || (full.k.type == s->k.type && full.k.bank == s->k.bank &&
                                      full.k.qi == s->k.qi && full.k.for_req == s->k.for_req));
}

/* Test only (check_summaries): the scan's answer pk at now against every
 * queue's candidates asked from scratch, in round-robin order, none skipped. */
static void check_scan(const struct dram_banked *d, const struct dram_banked_channel *c,
                       int64_t now, const struct dram_banked_pick *pk, int64_t refresh_t) {
  int64_t best_t = refresh_t;
  struct dram_banked_qsum full, best = {.t = DRAM_BANKED_FAR};
  for (uint32_t n = 1; n <= c->ncq; n++) {
    const uint32_t qi = (c->rr + n) % c->ncq;
    const uint64_t bit = 1ull << (qi % 64);
    if (!(c->cq_busy[qi / 64] & bit) || (c->blocked[qi / 64] & bit)) continue;
    bool act, col;
    cq_candidates(d, c, qi, now, &full, &act, &col);
    if (full.t < best_t) {
      best_t = full.t;
      best = full;
    }
  }
  CHECK_EQ(best_t < refresh_t ? best_t : refresh_t, pk->first_t);
  CHECK(best_t >= refresh_t || (best.k.type == pk->first.type && best.k.cq == pk->first.cq &&
                                best.k.qi == pk->first.qi && best.k.for_req == pk->first.for_req));
  CHECK(pk->next <= pk->first_t);
}

/* Refresh work, then the command queues round robin from the one after the
 * last that issued; in each, the oldest command that can issue now. next:
 * the earliest any candidate could. */
void dram_banked_cmdq_scan(struct dram_banked *d, struct dram_banked_channel *c, int64_t now,
                           struct dram_banked_pick *pk) {
  pk->cmd.type = DRAM_BANKED_CMD_NONE;
  pk->next = pk->first_t = DRAM_BANKED_FAR;
  dram_banked_scan_refresh(d, c, now, pk);
  const int64_t refresh_t = pk->first_t;
  /* The queues holding commands (but those of a rank with a refresh due: a
   * queue's commands share a rank), round robin from the one after rr: those
   * from there on, then those before it (rr last). A queue's candidates in
   * scan order are its own in entry order, so its summary (the first least)
   * stands for them all; and since every candidate is asked at now, one can
   * issue now only if it is a least: the first least of the whole scan.
   * No time is below now, so the scan ends at the first candidate that can
   * issue now (refresh work's included): nothing after it can come first,
   * and a summary left unasked is asked when next scanned (a summary past its
   * least time is asked again; the times it keeps are at or below its own,
   * so the stale marks stay on the safe side). */
  const uint32_t start = (c->rr + 1) % c->ncq, nw = (c->ncq + 63) / 64;
  uint32_t best = UINT32_MAX;
  int64_t best_t = pk->first_t > now ? DRAM_BANKED_FAR : now;
  /* Words from start's on, the first of them from start's bit; then from the
   * first word up to start's, that one below start's bit. */
  for (uint32_t step = 0; step <= nw && best_t > now; step++) {
    const uint32_t w = (start / 64 + step) % nw;
    uint64_t bits = c->cq_busy[w] & ~c->blocked[w];
    const uint64_t from_start = ~0ull << (start % 64);
    if (step == 0) bits &= from_start;
    else if (step == nw) bits &= ~from_start;
    const uint64_t fresh = c->fresh[w], cols = c->col_stale ? c->col_stale[w] : 0;
    while (bits && best_t > now) {
      const uint32_t b = (uint32_t)__builtin_ctzll(bits);
      const uint32_t qi = w * 64 + b;
      bits &= bits - 1;
      const struct dram_banked_qsum *s = &c->sum[qi];
      if (!(fresh >> b & 1)) {
        s = cq_sum(d, c, qi, now);
      } else if (cols >> b & 1) {
        /* At or past the best so far the queue cannot come first (ties
         * go to the earlier queue): it is left to be asked when it can. */
        if (s->t >= best_t || least_floor(d, c, qi, now) >= best_t) {
          if (d->p.check_summaries) check_summary(d, c, qi, now, s, best_t);
          continue;
        }
        s = cq_sum(d, c, qi, now);
      } else if (s->t < now) {
        s = cq_sum(d, c, qi, now);
      }
      if (d->p.check_summaries) check_summary(d, c, qi, now, s, DRAM_BANKED_NEVER);
      if (s->t < best_t) {
        best_t = s->t;
        best = qi;
      }
    }
  }
  if (best_t < pk->next) pk->next = best_t;
  if (best_t < pk->first_t) {
    pk->first_t = best_t;
    pk->first = c->sum[best].k;
  }
  if (pk->first_t == now) pk->cmd = pk->first;
  if (d->p.check_summaries) check_scan(d, c, now, pk, refresh_t);
  c->memo = pk->first;
  c->memo_t = pk->first_t;
  c->memo_at = now;
  c->memo_ok = true;
}
