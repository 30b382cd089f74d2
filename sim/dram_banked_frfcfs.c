/* The banked level's controller with queue_structure shared: one FR-FCFS
 * scheduler per channel over a read queue and a write queue, turning between
 * them at the write watermarks (sim/dram_banked.h, "Structure shared"). Holds:
 * one scan of the served queue per handled cycle gives both the command to
 * issue and the earliest cycle any could, so the channel sleeps exactly until
 * then; a request keeps its queue place until its column command. */
#include "sim/dram_banked_state.h"

#include <string.h>

#include "sim/engine.h"
#include "sim/err.h"

/* Candidates in priority order: refresh work (dram_banked_scan_refresh), then
 * the oldest row hit of the served queue, then the oldest PRE or ACT. The
 * first that can issue at `now` is picked; next is the least earliest time of
 * all of them. */
static void scan(struct dram_banked *d, struct dram_banked_channel *c, int64_t now,
                 struct dram_banked_pick *pk) {
  pk->cmd.type = DRAM_BANKED_CMD_NONE;
  pk->next = pk->first_t = DRAM_BANKED_FAR;
  dram_banked_scan_refresh(d, c, now, pk);
  const int qk = c->writing ? DRAM_BANKED_WR_Q : DRAM_BANKED_RD_Q;
  const struct dram_banked_queue *q = &c->q[qk];
  uint64_t no = ++c->scan_no;
  /* Pass 1: row hits, oldest first; note per bank whether a hit that may
   * still issue holds back a conflict's PRE. */
  for (uint32_t i = 0; i < q->n; i++) {
    const struct dram_banked_req *r = &q->r[i];
    if (c->ranks[r->rank].pending) continue;
    struct dram_banked_bank *bk = &c->banks[r->bank];
    if (bk->stamp != no) {
      bk->stamp = no;
      bk->conflict_seen = false;
      bk->hit_held = false;
    }
    if (!bk->open) continue;
    if (bk->row != r->row) {
      bk->conflict_seen = true;
      continue;
    }
    if (bk->conflict_seen && bk->hits >= DRAM_BANKED_ROW_HIT_CAP) continue;
    bk->hit_held = true;
    dram_banked_consider(pk, dram_banked_col_earliest(d, c, r, qk == DRAM_BANKED_WR_Q, now), now,
                         qk == DRAM_BANKED_WR_Q ? DRAM_BANKED_CMD_WR : DRAM_BANKED_CMD_RD, r->rank,
                         r->bank, i);
  }
  /* Pass 2: PRE for a conflict no hit holds back, ACT for a closed bank. */
  for (uint32_t i = 0; i < q->n; i++) {
    const struct dram_banked_req *r = &q->r[i];
    if (c->ranks[r->rank].pending) continue;
    const struct dram_banked_bank *bk = &c->banks[r->bank];
    if (!bk->open)
      dram_banked_consider(pk, dram_banked_act_earliest(d, c, r, now), now, DRAM_BANKED_CMD_ACT,
                           r->rank, r->bank, i);
    else if (bk->row != r->row && !bk->hit_held)
      dram_banked_consider(pk, max64(max64(now, r->ready), bk->pre_ok), now, DRAM_BANKED_CMD_PRE,
                           r->rank, r->bank, i);
  }
}

/* The cycle from which channel c's oldest read has waited too long
 * (DRAM_BANKED_READ_AGE_CAP x tRC), or DRAM_BANKED_FAR with no read queued. */
static int64_t starve_at(const struct dram_banked *d, const struct dram_banked_channel *c) {
  if (!c->q[DRAM_BANKED_RD_Q].n) return DRAM_BANKED_FAR;
  return c->q[DRAM_BANKED_RD_Q].r[0].ready + (int64_t)DRAM_BANKED_READ_AGE_CAP * (int64_t)d->p.tRC;
}

/* Turn the channel to writes or back to reads at DRAM cycle now. NOTE: a
 * read that has waited too long (starve_at) turns the channel back to reads
 * and keeps it there until it is served: under a heavy write stream the
 * write queue never falls to write_low, or refills to write_high before a
 * conflicting read's precharge, activate and read fit between drains, and
 * such a read starved for 30,000 cycles. The moment a read starts starving is
 * a wake of its own (next_of), so skipping ahead still equals ticking. */
static void update_mode(struct dram_banked *d, struct dram_banked_channel *c, int64_t now) {
  uint32_t nr = c->q[DRAM_BANKED_RD_Q].n, nw = c->q[DRAM_BANKED_WR_Q].n;
  bool starving = now >= starve_at(d, c);
  if (!c->writing) {
    if ((nw >= d->p.write_high && !starving) || (nr == 0 && nw > 0)) {
      c->writing = true;
      d->st.write_drains++;
    }
  } else if (nw == 0 || (nw <= d->p.write_low && nr > 0) || starving) {
    c->writing = false;
  }
}

/* The channel's next wake: its next command, or a read starting to starve
 * while the channel serves writes. */
static int64_t next_of(const struct dram_banked *d, const struct dram_banked_channel *c,
                       int64_t next) {
  int64_t s = c->writing ? starve_at(d, c) : DRAM_BANKED_FAR;
  return s < next ? s : next;
}

void dram_banked_frfcfs_issue_column(struct dram_banked *d, struct dram_banked_channel *c, int qk,
                                     uint32_t qi, int64_t now) {
  struct dram_banked_queue *q = &c->q[qk];
  struct dram_banked_req r = q->r[qi];
  memmove(&q->r[qi], &q->r[qi + 1], (q->n - qi - 1) * sizeof *q->r);
  q->n--;
  d->queued--;
  int64_t end = dram_banked_column_state(d, c, &r, qk == DRAM_BANKED_WR_Q, now);
  dram_banked_count_kind(d, r.kind);
  /* The place frees at the column command: queue time ends there. */
  dram_banked_queue_leave(d, qk, &r, now);
  d->space_due = true;
  uint64_t done = dram_clock_to_core(d->clk, (uint64_t)end);
  CHECK_GE(done, engine_now(d->e));
  dram_banked_serve(d, done, r.tag);
}

/* The drain mode, at most one command; then c->next. */
void dram_banked_frfcfs_cycle(struct dram_banked *d, struct dram_banked_channel *c, int64_t now) {
  update_mode(d, c, now);
  struct dram_banked_pick pk;
  scan(d, c, now, &pk);
  if (pk.cmd.type == DRAM_BANKED_CMD_NONE) {
    CHECK_GT(pk.next, now);
    c->next = next_of(d, c, pk.next);
    if (c->next <= now) c->next = now + 1;
    return;
  }
  dram_banked_issue(d, c, &pk.cmd, now);
  update_mode(d, c, now + 1);
  scan(d, c, now + 1, &pk);
  c->next = next_of(d, c, pk.next);
  if (c->next <= now) c->next = now + 1;
}

void dram_banked_frfcfs_take(struct dram_banked *d, struct dram_banked_channel *c,
                             const struct dram_banked_coord *co, uint64_t addr, bool write,
                             uint64_t tag) {
  const int qk = write ? DRAM_BANKED_WR_Q : DRAM_BANKED_RD_Q;
  /* A line waiting in the write queue answers a read of it, and takes a later
   * write of it in its place (a controller's write queue is searched by
   * address, as DRAMsim3's is): served the next DRAM cycle, no command. */
  const struct dram_banked_queue *wq = &c->q[DRAM_BANKED_WR_Q];
  for (uint32_t i = 0; i < wq->n; i++)
    if (wq->r[i].line == addr >> SIM_LINE_LG2) {
      if (write) d->st.write_merges++;
      else d->st.write_forwards++;
      dram_banked_serve(d, dram_clock_to_core(d->clk, (uint64_t)d->cursor + 1), tag);
      return;
    }
  dram_banked_enqueue(d, c, qk, co, addr, tag, d->cursor + (int64_t)d->p.controller_cycles);
  /* Cycles before the cursor are decided; the new request joins at it. */
  update_mode(d, c, d->cursor);
  struct dram_banked_pick pk;
  scan(d, c, d->cursor, &pk);
  int64_t nx = next_of(d, c, pk.next);
  if (nx < d->cursor) nx = d->cursor;
  if (nx < c->next) c->next = nx;
  dram_banked_schedule_wake(d);
}
