/* The banked level's refresh (DRAMsim3's RANK_LEVEL_STAGGERED): when each
 * rank's refreshes fall due, and the work one brings. Holds: rank r's k-th
 * refresh (k >= 0) falls due at (k * ranks + r + 1) * floor(tREFI / ranks);
 * once due, the rank takes no request command; its open banks are precharged,
 * REF issues once all have been precharged for tRP, and the rank takes no ACT
 * for tRFC after it. tREFI 0: no refresh. */
#include "sim/dram_banked_state.h"

int64_t dram_banked_refresh_due(const struct dram_banked *d, uint32_t rank, uint64_t k) {
  if (!d->p.tREFI) return DRAM_BANKED_FAR;
  return ((int64_t)k * (int64_t)d->p.ranks + rank + 1) * d->refresh_step;
}

/* c->due_min after a rank's next_due moved. */
static void due_min_update(const struct dram_banked *d, struct dram_banked_channel *c) {
  c->due_min = DRAM_BANKED_FAR;
  for (uint32_t k = 0; k < d->p.ranks; k++)
    if (c->ranks[k].next_due < c->due_min) c->due_min = c->ranks[k].next_due;
}

void dram_banked_refresh_init(const struct dram_banked *d, struct dram_banked_channel *c) {
  for (uint32_t k = 0; k < d->p.ranks; k++) c->ranks[k].next_due = dram_banked_refresh_due(d, k, 0);
  due_min_update(d, c);
  c->ref_ranks = 0;
}

void dram_banked_refresh_fall_due(struct dram_banked *d, struct dram_banked_channel *c,
                                  int64_t now) {
  if (now < c->due_min) return;
  const int64_t period = d->refresh_step * (int64_t)d->p.ranks;
  for (uint32_t k = 0; k < d->p.ranks; k++) {
    struct dram_banked_rank *rk = &c->ranks[k];
    while (rk->next_due <= now) {
      if (!rk->pending++) {
        dram_banked_block_rank(d, c, k, true);
        c->ref_ranks++;
      }
      rk->next_due += period;
      c->memo_ok = false;
    }
  }
  due_min_update(d, c);
}

/* The earliest cycle >= now rank `rank`'s REF could issue (its banks all
 * closed). */
static int64_t ref_earliest(const struct dram_banked *d, const struct dram_banked_channel *c,
                            uint32_t rank, int64_t now) {
  const uint32_t bpr = d->banks_per_rank;
  int64_t t = max64(now, c->ranks[rank].ref_end);
  for (uint32_t i = 0; i < bpr; i++) t = max64(t, c->banks[rank * bpr + i].ref_ok);
  return t;
}

/* Refresh work comes first in a scan: ranks in order, a PRE for each open
 * bank (lowest bank first), or REF once all are closed. The next refresh to
 * fall due bounds the scan's next. */
void dram_banked_scan_refresh(struct dram_banked *d, struct dram_banked_channel *c, int64_t now,
                              struct dram_banked_pick *pk) {
  /* (No refresh pending: only the next to fall due bounds next.) */
  if (c->due_min < pk->next) pk->next = max64(c->due_min, now);
  if (!c->ref_ranks) return;
  const uint32_t bpr = d->banks_per_rank;
  for (uint32_t k = 0; k < d->p.ranks; k++) {
    struct dram_banked_rank *rk = &c->ranks[k];
    if (!rk->pending) continue;
    if (rk->open) {
      for (uint32_t i = 0; i < bpr; i++) {
        const struct dram_banked_bank *bk = &c->banks[k * bpr + i];
        if (bk->open)
          dram_banked_consider(pk, max64(now, bk->pre_ok), now, DRAM_BANKED_CMD_PRE, k, k * bpr + i,
                               -1);
      }
    } else {
      dram_banked_consider(pk, ref_earliest(d, c, k, now), now, DRAM_BANKED_CMD_REF, k, 0, -1);
    }
  }
}

void dram_banked_refresh_issue(struct dram_banked *d, struct dram_banked_channel *c, uint32_t rank,
                               int64_t now) {
  struct dram_banked_rank *rk = &c->ranks[rank];
  if (!--rk->pending) {
    dram_banked_block_rank(d, c, rank, false);
    c->ref_ranks--;
  }
  rk->ref_end = now + d->p.tRFC;
  for (uint32_t i = 0; i < d->banks_per_rank; i++) {
    struct dram_banked_bank *bk = &c->banks[rank * d->banks_per_rank + i];
    bk->act_ok = max64(bk->act_ok, rk->ref_end);
  }
  dram_banked_stale_rank(d, c, rank);
  d->st.refreshes++;
  rk->refs++;
  d->st.refresh_cycles += d->p.tRFC;
}
