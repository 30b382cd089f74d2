/* The banked level's bank, group and rank state: the earliest cycle each
 * command of a request could issue, and the state each command leaves. Holds:
 * each bank, group and rank field records the last command that bounds a
 * later one (struct dram_banked_bank says which), so a command's earliest time
 * is a max over those fields plus its timings, then the data bus's first fit
 * for a column command. The constraints, as modelled: sim/dram_banked.h. */
#include "sim/dram_banked_state.h"

int64_t dram_banked_act_earliest(const struct dram_banked *d, const struct dram_banked_channel *c,
                                 const struct dram_banked_req *r, int64_t now) {
  const struct dram_banked_bank *bk = &c->banks[r->bank];
  const struct dram_banked_rank *rk = &c->ranks[r->rank];
  const struct dram_banked_group *g = &c->groups[r->rank * d->p.bank_groups + r->group];
  int64_t t = max64(max64(now, r->ready), bk->act_ok);
  t = max64(t, rk->ref_end);
  t = max64(t, rk->act + d->p.tRRD_S);
  t = max64(t, g->act + d->p.tRRD_L);
  t = max64(t, rk->faw[rk->faw_i] + d->p.tFAW);
  return t;
}

int64_t dram_banked_col_earliest(const struct dram_banked *d, const struct dram_banked_channel *c,
                                 const struct dram_banked_req *r, bool write, int64_t now) {
  const struct dram_banked_bank *bk = &c->banks[r->bank];
  const struct dram_banked_rank *rk = &c->ranks[r->rank];
  const struct dram_banked_group *g = &c->groups[r->rank * d->p.bank_groups + r->group];
  const int64_t b = d->burst_cycles;
  int64_t t = max64(max64(now, r->ready), bk->col_ok);
  int64_t lat;
  if (write) {
    t = max64(t, rk->wr + d->p.tCCD_S);
    t = max64(t, g->wr + d->p.tCCD_L);
    t = max64(t, c->rd + d->p.tRTW);
    lat = d->p.tCWL;
  } else {
    t = max64(t, rk->rd + d->p.tCCD_S);
    t = max64(t, g->rd + d->p.tCCD_L);
    t = max64(t, rk->wr + d->p.tCWL + b + d->p.tWTR_S);
    t = max64(t, g->wr + d->p.tCWL + b + d->p.tWTR_L);
    lat = d->p.tCL;
  }
  return dram_banked_bus_fit(d, c, t + lat, r->rank, write) - lat;
}

/* A floor kept from cycle `at` holds at any later cycle of its generation:
 * the fit is monotone, and the spacing and the bus change only with a
 * column command (dram_banked_column_state bumps col_gen). Asked past its
 * floor, it is fitted again (a higher floor). */
int64_t dram_banked_col_floor_fit(const struct dram_banked *d, struct dram_banked_channel *c,
                                  uint32_t rank, bool write, int64_t now) {
  struct dram_banked_floor *f = &c->floors[rank * 2 + write];
  const struct dram_banked_rank *rk = &c->ranks[rank];
  int64_t t;
  if (write) {
    t = max64(rk->wr + d->p.tCCD_S, c->rd + d->p.tRTW);
  } else {
    t = max64(rk->rd + d->p.tCCD_S, rk->wr + d->p.tCWL + d->burst_cycles + d->p.tWTR_S);
  }
  const int64_t lat = write ? d->p.tCWL : d->p.tCL;
  f->at = now;
  f->t = dram_banked_bus_fit(d, c, max64(now, t) + lat, rank, write) - lat;
  f->gen = c->col_gen;
  return f->t;
}

int64_t dram_banked_req_earliest(const struct dram_banked *d, const struct dram_banked_channel *c,
                                 const struct dram_banked_req *r, enum dram_banked_cmd_type type,
                                 int64_t now) {
  if (type == DRAM_BANKED_CMD_ACT) return dram_banked_act_earliest(d, c, r, now);
  if (type == DRAM_BANKED_CMD_PRE) return max64(max64(now, r->ready), c->banks[r->bank].pre_ok);
  return dram_banked_col_earliest(d, c, r, r->write, now);
}

void dram_banked_activate(struct dram_banked *d, struct dram_banked_channel *c,
                          const struct dram_banked_cmd *k, const struct dram_banked_req *r,
                          int64_t now) {
  struct dram_banked_bank *bk = &c->banks[k->bank];
  struct dram_banked_rank *rk = &c->ranks[k->rank];
  struct dram_banked_group *g = &c->groups[r->rank * d->p.bank_groups + r->group];
  if (bk->act_at >= 0) d->st.bank_open_cycles += (uint64_t)(bk->close_at - bk->act_at);
  bk->open = true;
  bk->row = r->row;
  bk->hits = 0;
  bk->act_at = now;
  bk->close_at = DRAM_BANKED_FAR;
  bk->col_ok = now + d->p.tRCD;
  bk->pre_ok = now + d->p.tRAS;
  bk->act_ok = now + d->p.tRC;
  rk->act = g->act = now;
  rk->faw[rk->faw_i] = now;
  rk->faw_i = (rk->faw_i + 1) & 3;
  if (!rk->open++) rk->active_since = now;
  rk->acts++;
  dram_banked_stale_bank(d, c, k->bank);
  dram_banked_stale_acts(d, c, k->rank, now);
  d->st.activates++;
}

void dram_banked_bank_close(struct dram_banked *d, struct dram_banked_channel *c,
                            struct dram_banked_bank *bk, uint32_t rank, int64_t now, int64_t at) {
  struct dram_banked_rank *rk = &c->ranks[rank];
  bk->open = false;
  bk->close_at = at;
  bk->act_ok = max64(bk->act_ok, at + d->p.tRP);
  bk->ref_ok = at + d->p.tRP;
  dram_banked_stale_bank(d, c, (uint32_t)(bk - c->banks));
  /* The rank's state follows the command, as DRAMsim3's bank state does (an
   * auto-precharge closes the bank at its RDA / WRA). */
  if (!--rk->open) rk->active_cycles += (uint64_t)(now - rk->active_since);
  d->st.precharges++;
}

int64_t dram_banked_column_state(struct dram_banked *d, struct dram_banked_channel *c,
                                 const struct dram_banked_req *rq, bool write, int64_t now) {
  const struct dram_banked_req r = *rq;
  struct dram_banked_bank *bk = &c->banks[r.bank];
  struct dram_banked_rank *rk = &c->ranks[r.rank];
  struct dram_banked_group *g = &c->groups[r.rank * d->p.bank_groups + r.group];
  const int64_t b = d->burst_cycles;
  int64_t end, pre;
  bk->hits++;
  c->col_gen++; /* (the spacing and the bus change below) */
  dram_banked_stale_bank(d, c, r.bank);
  dram_banked_stale_columns(d, c, write, now);
  if (write) {
    rk->wr = g->wr = now;
    dram_banked_bus_add(d, c, now, now + d->p.tCWL, r.rank, true);
    end = now + d->p.tCWL + b;
    pre = end + d->p.tWR;
    d->st.writes++;
    rk->writes++;
  } else {
    rk->rd = g->rd = c->rd = now;
    dram_banked_bus_add(d, c, now, now + d->p.tCL, r.rank, false);
    end = now + d->p.tCL + b;
    pre = now + d->p.tRTP;
    d->st.reads++;
    rk->reads++;
  }
  bk->pre_ok = max64(bk->pre_ok, pre);
  if (d->p.page == DRAM_BANKED_CLOSE_PAGE)
    dram_banked_bank_close(d, c, bk, r.rank, now, bk->pre_ok);
  return end;
}
