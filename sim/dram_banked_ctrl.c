/* The banked level's controller with queue_structure per_bank / per_rank
 * (DRAMsim3's): per channel a read queue and a write buffer of transactions
 * feeding command queues, one per bank or per rank (sim/dram_banked.h,
 * "Structure per_bank / per_rank"). Holds: at the end of each DRAM cycle at
 * most one transaction moves to its command queue, and at most one command
 * issues per cycle, the first candidate of the round-robin scan
 * (dram_banked_cmdq_scan); writes are posted, served controller_cycles after
 * they arrive. */
#include "sim/dram_banked_state.h"

#include <string.h>

#include "sim/engine.h"
#include "sim/err.h"

uint32_t dram_banked_cq_of(const struct dram_banked *d, const struct dram_banked_req *r) {
  return d->p.queue_structure == DRAM_BANKED_PER_RANK ? r->rank : r->bank;
}

static void cq_mark(struct dram_banked_channel *c, uint32_t qi, bool busy) {
  const uint64_t bit = 1ull << (qi % 64);
  if (busy) c->cq_busy[qi / 64] |= bit;
  else c->cq_busy[qi / 64] &= ~bit;
}

/* Does a read transaction wait for a command queue that is not full? (If
 * not, none of the read queue can move.) */
static bool reads_movable(const struct dram_banked_channel *c) {
  for (uint32_t w = 0; w * 64 < c->ncq; w++)
    if (c->rd_any[w] & ~c->full[w]) return true;
  return false;
}

/* Test only (check_summaries): rd_for and rd_any against the read queue
 * counted from scratch. */
static void check_rd_for(const struct dram_banked_channel *c) {
  for (uint32_t qi = 0; qi < c->ncq; qi++) {
    uint32_t n = 0;
    for (uint32_t i = 0; i < c->q[DRAM_BANKED_RD_Q].n; i++)
      n += c->q[DRAM_BANKED_RD_Q].r[i].cq == qi;
    CHECK_EQ(n, c->rd_for[qi]);
    CHECK_EQ(n > 0, c->rd_any[qi / 64] >> (qi % 64) & 1);
  }
}

/* Count a read transaction bound for command queue qi in (delta 1) or out
 * (-1) of the read queue. */
static void rd_count(struct dram_banked_channel *c, uint32_t qi, int delta) {
  c->rd_for[qi] += (uint32_t)delta;
  const uint64_t bit = 1ull << (qi % 64);
  c->rd_any[qi / 64] = c->rd_for[qi] ? c->rd_any[qi / 64] | bit : c->rd_any[qi / 64] & ~bit;
}

/* Entries of transaction queue q that may take part in cycle t (a prefix:
 * ready grows with arrival). */
static uint32_t visible(const struct dram_banked_queue *q, int64_t t) {
  uint32_t n = q->n;
  while (n > 0 && q->r[n - 1].ready - 1 > t) n--;
  return n;
}

/* Does a request of line `line` wait, as a write (write) or a read, in the
 * transaction queue or in command queue cq (the one its line maps to)? */
static bool line_waits(const struct dram_banked_channel *c, const struct dram_banked_queue *cq,
                       bool write, uint64_t line) {
  const struct dram_banked_queue *q = &c->q[write ? DRAM_BANKED_WR_Q : DRAM_BANKED_RD_Q];
  for (uint32_t i = 0; i < q->n; i++)
    if (q->r[i].line == line) return true;
  for (uint32_t i = 0; i < cq->n; i++)
    if (cq->r[i].write == write && cq->r[i].line == line) return true;
  return false;
}

/* The first cycle after t at which schedule_cq's answer may change with no
 * command issued and no transaction come or moved: a transaction's becoming
 * visible, or the idle drain's time coming. */
static int64_t idle_until(const struct dram_banked *d, const struct dram_banked_channel *c,
                          int64_t t) {
  /* (idle_drain_cycles 0: no idle drain ever comes) */
  int64_t to =
      d->p.idle_drain_cycles ? c->last_busy + (int64_t)d->p.idle_drain_cycles : DRAM_BANKED_FAR;
  if (to <= t) to = DRAM_BANKED_FAR;
  for (int k = 0; k < 2; k++) {
    const struct dram_banked_queue *q = &c->q[k];
    const uint32_t v = visible(q, t);
    if (v < q->n && q->r[v].ready - 1 < to) to = q->r[v].ready - 1;
  }
  return to;
}

/* The end of cycle t: maybe start a write drain, then move at most one
 * transaction to its command queue. apply false: change nothing, only say
 * whether anything would change. What it reads (the transaction queues and
 * which of them are visible at t, the command queues, draining, cq_n,
 * last_busy) changes only by a column command, a transaction taken or moved,
 * or t reaching idle_until: so an answer of no change holds until one of
 * those (idle_ok). An ACT or PRE moves last_busy, read only while cq_n is 0,
 * when no request's ACT or PRE can issue; a later last_busy only delays the
 * idle drain, so idle_to stays a safe bound. */
static bool schedule_cq(struct dram_banked *d, struct dram_banked_channel *c, int64_t t,
                        bool apply) {
  if (c->idle_ok && t >= c->idle_from && t < c->idle_to) {
    if (!d->p.check_summaries) return false;
    c->idle_ok = false; /* test only: asked again, it must agree */
    CHECK(!schedule_cq(d, c, t, false));
    return false;
  }
  const uint32_t nw = visible(&c->q[DRAM_BANKED_WR_Q], t), nr = visible(&c->q[DRAM_BANKED_RD_Q], t);
  uint32_t draining = c->draining;
  if (!draining && nw > 0 &&
      (nw >= d->p.write_high || (nw > d->p.write_low && c->cq_n == 0) ||
       (nr == 0 && c->cq_n == 0 && d->p.idle_drain_cycles &&
        t >= c->last_busy + (int64_t)d->p.idle_drain_cycles)))
    draining = nw;
  int k = draining ? DRAM_BANKED_WR_Q : DRAM_BANKED_RD_Q;
  uint32_t mi = UINT32_MAX; /* the transaction to move */
  if (d->p.check_summaries) check_rd_for(c);
  /* (Reads bound only for full command queues: none moves, none asked.) */
  const uint32_t nr_asked = reads_movable(c) ? nr : 0;
  for (uint32_t i = 0; i < (k == DRAM_BANKED_WR_Q ? nw : nr_asked); i++) {
    const uint32_t qi = c->q[k].r[i].cq;
    if (c->full[qi / 64] >> (qi % 64) & 1) continue;
    const struct dram_banked_queue *cq = &c->cq[qi];
    if (k == DRAM_BANKED_WR_Q && line_waits(c, cq, false, c->q[k].r[i].line)) {
      /* A read of the line still waits: writing first would lose its data;
       * the drain ends (and may start again next cycle). With every command
       * queue empty and that read still in the read queue nothing would
       * ever change: the read queue is served this cycle instead ([ours];
       * DRAMsim3 deadlocks there). */
      draining = 0;
      if (c->cq_n) break; /* (else the read is in the read queue) */
      k = DRAM_BANKED_RD_Q;
      i = UINT32_MAX; /* the loop's increment makes it 0 */
      continue;
    }
    mi = i;
    break;
  }
  struct dram_banked_queue *q = &c->q[k];
  const bool changed = mi != UINT32_MAX || draining != c->draining;
  if (!changed) {
    c->idle_ok = true;
    c->idle_from = t;
    c->idle_to = idle_until(d, c, t);
  }
  if (!apply) return changed;
  if (changed) c->memo_ok = c->idle_ok = false;
  if (mi != UINT32_MAX) {
    struct dram_banked_req m = q->r[mi];
    struct dram_banked_queue *cq = &c->cq[dram_banked_cq_of(d, &m)];
    memmove(&q->r[mi], &q->r[mi + 1], (q->n - mi - 1) * sizeof *q->r);
    q->n--;
    if (k == DRAM_BANKED_RD_Q) rd_count(c, m.cq, -1);
    m.ready = t + 1;
    cq->r[cq->n++] = m;
    if (cq->n == cq->cap) c->full[m.cq / 64] |= 1ull << (m.cq % 64);
    dram_banked_stale_bank(d, c, m.bank);
    c->cq_n++;
    cq_mark(c, dram_banked_cq_of(d, &m), true);
    d->space_due = true;
    if (k == DRAM_BANKED_WR_Q) draining--;
  }
  if (!c->draining && k == DRAM_BANKED_WR_Q && (mi != UINT32_MAX || draining)) d->st.write_drains++;
  c->draining = draining;
  return changed;
}

void dram_banked_ctrl_issue_column(struct dram_banked *d, struct dram_banked_channel *c,
                                   uint32_t qi, uint32_t j, int64_t now) {
  struct dram_banked_queue *q = &c->cq[qi];
  struct dram_banked_req r = q->r[j];
  memmove(&q->r[j], &q->r[j + 1], (q->n - j - 1) * sizeof *q->r);
  q->n--;
  c->idle_ok = false;
  c->full[qi / 64] &= ~(1ull << (qi % 64));
  dram_banked_stale_bank(d, c, r.bank);
  c->cq_n--;
  if (!q->n) cq_mark(c, qi, false);
  d->queued--;
  /* DRAMsim3's row hit: the row has served a column command since its ACT. */
  dram_banked_count_kind(d, c->banks[r.bank].hits                 ? DRAM_BANKED_KIND_HIT
                            : r.kind == DRAM_BANKED_KIND_CONFLICT ? DRAM_BANKED_KIND_CONFLICT
                                                                  : DRAM_BANKED_KIND_MISS);
  int64_t end = dram_banked_column_state(d, c, &r, r.write, now);
  dram_banked_queue_leave(d, r.write ? DRAM_BANKED_WR_Q : DRAM_BANKED_RD_Q, &r, now);
  if (r.write) return; /* posted: served when it arrived */
  uint64_t done = dram_clock_to_core(d->clk, (uint64_t)end);
  CHECK_GE(done, engine_now(d->e));
  dram_banked_serve(d, done, r.tag);
  /* Reads of the same line that arrived while it waited. */
  uint32_t k = 0;
  for (uint32_t i = 0; i < c->nfol; i++) {
    if (c->fol[i].line != r.line) {
      c->fol[k++] = c->fol[i];
      continue;
    }
    dram_banked_serve(d, done, c->fol[i].tag);
  }
  c->nfol = k;
}

/* The earliest cycle >= t at which channel c's state may change. */
static int64_t next_cq(struct dram_banked *d, struct dram_banked_channel *c, int64_t t) {
  struct dram_banked_pick pk;
  dram_banked_cmdq_scan(d, c, t, &pk);
  int64_t nx = pk.next;
  if (schedule_cq(d, c, t, false)) return t;
  for (int k = 0; k < 2; k++) {
    const struct dram_banked_queue *q = &c->q[k];
    uint32_t v = visible(q, t);
    if (v < q->n && q->r[v].ready - 1 < nx) nx = q->r[v].ready - 1;
  }
  if (d->p.idle_drain_cycles && !c->draining && c->q[DRAM_BANKED_WR_Q].n && !c->cq_n &&
      !visible(&c->q[DRAM_BANKED_RD_Q], t)) {
    int64_t idle = c->last_busy + (int64_t)d->p.idle_drain_cycles;
    if (idle < nx) nx = idle;
  }
  return nx < t ? t : nx;
}

bool dram_banked_ctrl_parked(struct dram_banked *d, struct dram_banked_channel *c, int64_t t) {
  const struct dram_banked_queue *w = &c->q[DRAM_BANKED_WR_Q];
  return !d->p.idle_drain_cycles && w->n && !c->draining && !c->cq_n && !c->q[DRAM_BANKED_RD_Q].n &&
         visible(w, t) == w->n && !schedule_cq(d, c, t, false);
}

/* Handle DRAM cycle `now` on channel c (refreshes fallen due): at most one
 * command, then at most one transaction moved; then c->next. */
void dram_banked_ctrl_cycle(struct dram_banked *d, struct dram_banked_channel *c, int64_t now) {
  struct dram_banked_pick pk;
  /* The last scan's answer stands while nothing changed since: every
   * queue's summary holds from memo_at to its own least time, so none can
   * issue before memo_t, and at memo_t the memo's queue comes first. */
  if (c->memo_ok && now >= c->memo_at && now <= c->memo_t) {
    pk.cmd.type = DRAM_BANKED_CMD_NONE;
    if (now == c->memo_t) pk.cmd = c->memo;
  } else {
    dram_banked_cmdq_scan(d, c, now, &pk);
  }
  if (pk.cmd.type != DRAM_BANKED_CMD_NONE) {
    dram_banked_issue(d, c, &pk.cmd, now);
    if (pk.cmd.for_req) {
      c->rr = pk.cmd.cq;
      c->last_busy = now;
    }
  }
  schedule_cq(d, c, now, true);
  c->next = next_cq(d, c, now + 1);
}

/* Serve tag at DRAM cycle at, with no command. */
static void serve_at(struct dram_banked *d, int64_t at, uint64_t tag) {
  dram_banked_serve(d, dram_clock_to_core(d->clk, (uint64_t)at), tag);
}

/* The request arrives after DRAM cycle cursor - 1. */
void dram_banked_ctrl_take(struct dram_banked *d, struct dram_banked_channel *c,
                           const struct dram_banked_coord *co, uint64_t addr, bool write,
                           uint64_t tag) {
  const int64_t arr = d->cursor - 1, ready = arr + (int64_t)d->p.controller_cycles;
  const uint64_t line = addr >> SIM_LINE_LG2;
  c->idle_ok = false;
  CHECK_LT(c->took_at, arr);
  c->took_at = arr;
  struct dram_banked_req probe;
  probe.rank = co->rank;
  probe.bank = co->rank * d->banks_per_rank + co->bank_group * d->p.banks_per_group + co->bank;
  const struct dram_banked_queue *cq = &c->cq[dram_banked_cq_of(d, &probe)];
  if (line_waits(c, cq, true, line)) {
    /* Its line's write has not issued: a read is answered from it, a write
     * replaces it. */
    if (write) d->st.write_merges++;
    else d->st.write_forwards++;
    serve_at(d, ready, tag);
    return;
  }
  if (!write && line_waits(c, cq, false, line)) {
    if (c->nfol == c->cap_fol) {
      c->cap_fol = c->cap_fol ? 2 * c->cap_fol : 8;
      c->fol = xrealloc(c->fol, c->cap_fol * sizeof *c->fol);
    }
    c->fol[c->nfol].line = line;
    c->fol[c->nfol].tag = tag;
    c->nfol++;
    d->st.read_merges++;
    return;
  }
  const struct dram_banked_req *r =
      dram_banked_enqueue(d, c, write ? DRAM_BANKED_WR_Q : DRAM_BANKED_RD_Q, co, addr, tag, ready);
  if (!write) rd_count(c, r->cq, 1);
  if (write) serve_at(d, ready, tag); /* posted */
  if (arr > c->last_busy) c->last_busy = arr;
  /* It may move at the end of cycle ready - 1 (never before the cursor). */
  int64_t nx = max64(d->cursor, ready - 1);
  if (nx < c->next) c->next = nx;
  dram_banked_schedule_wake(d);
}
