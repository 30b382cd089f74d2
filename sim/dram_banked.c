/* The banked DRAM level (sim/dram_banked.h): its clock and events, a
 * request's life from take to its answer, the dispatch of each handled cycle
 * to the controller structure (dram_banked_frfcfs.c, dram_banked_ctrl.c), and
 * the level's creation. Holds: DRAM cycles before the cursor are decided; a
 * cycle is handled only once every request that may take part in it has
 * arrived (core_deciding), and after each handled cycle one wake is scheduled
 * at the earliest cycle any channel's state may change, so skipping ahead
 * equals ticking every cycle (tick_every_cycle, the tests' oracle). The files
 * of the level and what they share: sim/dram_banked_state.h. */
#include "sim/dram_banked.h"

#include <stdlib.h>

#include "sim/dram_banked_state.h"
#include "sim/engine.h"
#include "sim/err.h"

/* ---- Time and events ---- */

/* The first core cycle by which every request that may take part in DRAM
 * cycle w has arrived, so w can be decided: floor(w num / den) + 1. */
static uint64_t core_deciding(const struct dram_banked *d, int64_t w) {
  /* per_bank: a request arriving in cycle w takes no part in it (it arrives
   * after w's tick), so w is decided once the core reaches cycle w's arrivals:
   * the first core cycle with from_core >= w. */
  if (d->cq_mode) {
    if (w <= 0) return 0;
    w--;
  }
  if (w < ((int64_t)1 << 31) && d->clk.num < (1ull << 32))
    return (uint64_t)w * d->clk.num / d->clk.den + 1;
  return (uint64_t)(((unsigned __int128)(uint64_t)w * d->clk.num) / d->clk.den) + 1;
}

static void on_done(void *ctx, uint64_t tag) {
  struct dram_banked *d = ctx;
  CHECK_GT(d->inflight, 0);
  d->inflight--;
  d->client.done(d->client.ctx, tag);
}

static void on_space(void *ctx, uint64_t arg) {
  (void)arg;
  struct dram_banked *d = ctx;
  if (d->client.space) d->client.space(d->client.ctx);
}

static void advance(struct dram_banked *d);

static void on_wake(void *ctx, uint64_t at) {
  struct dram_banked *d = ctx;
  if (at == d->wake_at) d->wake_at = UINT64_MAX;
  advance(d);
}

/* ---- A request's life ---- */

/* The occupancy integral of queue kind k up to core cycle t. */
static void area_to(struct dram_banked *d, int k, uint64_t t) {
  CHECK_GE(t, d->q_last[k]);
  d->st.queue_area[k] += d->q_len[k] * (t - d->q_last[k]);
  d->q_last[k] = t;
}

void dram_banked_serve(struct dram_banked *d, uint64_t t, uint64_t tag) {
  d->inflight++;
  engine_at(d->e, t, on_done, d, tag);
}

/* Queue a request in its channel's queue qk (the request's fields but tag,
 * line and ready from co); the level's counters follow. */
struct dram_banked_req *dram_banked_enqueue(struct dram_banked *d, struct dram_banked_channel *c,
                                            int qk, const struct dram_banked_coord *co,
                                            uint64_t addr, uint64_t tag, int64_t ready) {
  struct dram_banked_queue *q = &c->q[qk];
  CHECK_LT(q->n, q->cap);
  struct dram_banked_req *r = &q->r[q->n++];
  r->tag = tag;
  r->take_core = engine_now(d->e);
  r->line = addr >> SIM_LINE_LG2;
  r->ready = ready;
  r->seq = d->seq++;
  r->row = co->row;
  r->column = co->column;
  r->rank = co->rank;
  r->group = co->bank_group;
  r->bank = co->rank * d->banks_per_rank + co->bank_group * d->p.banks_per_group + co->bank;
  r->kind = DRAM_BANKED_KIND_HIT;
  r->write = qk == DRAM_BANKED_WR_Q;
  if (d->cq_mode) r->cq = dram_banked_cq_of(d, r);
  d->queued++;
  area_to(d, qk, r->take_core);
  d->q_len[qk]++;
  if (d->q_len[qk] > d->st.queue_max[qk]) d->st.queue_max[qk] = d->q_len[qk];
  return r;
}

void dram_banked_count_kind(struct dram_banked *d, uint8_t kind) {
  if (kind == DRAM_BANKED_KIND_HIT) d->st.row_hits++;
  else if (kind == DRAM_BANKED_KIND_MISS) d->st.row_misses++;
  else d->st.row_conflicts++;
}

/* Queue time of r, of queue kind qk, ends at its column command at now: in
 * the core cycle DRAM cycle now begins (per_bank: the first core cycle whose
 * arrivals come after cycle now, which is when now may be handled, so that
 * the occupancy integral runs forward). */
void dram_banked_queue_leave(struct dram_banked *d, int qk, const struct dram_banked_req *r,
                             int64_t now) {
  uint64_t left = d->cq_mode ? core_deciding(d, now) : dram_clock_to_core(d->clk, (uint64_t)now);
  area_to(d, qk, left);
  d->q_len[qk]--;
  uint64_t wait = left - r->take_core;
  d->st.queue_wait_sum_cycles[qk] += wait;
  if (wait > d->st.queue_wait_max_cycles[qk]) d->st.queue_wait_max_cycles[qk] = wait;
}

/* ---- Cycles ---- */

void dram_banked_issue(struct dram_banked *d, struct dram_banked_channel *c,
                       const struct dram_banked_cmd *k, int64_t now) {
  c->memo_ok = false;
  const int qk = c->writing ? DRAM_BANKED_WR_Q : DRAM_BANKED_RD_Q;
  struct dram_banked_req *r = !k->for_req  ? NULL
                              : d->cq_mode ? &c->cq[k->cq].r[k->qi]
                                           : &c->q[qk].r[k->qi];
  switch (k->type) {
  case DRAM_BANKED_CMD_PRE: {
    struct dram_banked_bank *bk = &c->banks[k->bank];
    dram_banked_bank_close(d, c, bk, k->rank, now, now);
    if (r) r->kind = DRAM_BANKED_KIND_CONFLICT;
    break;
  }
  case DRAM_BANKED_CMD_ACT:
    dram_banked_activate(d, c, k, r, now);
    if (r->kind == DRAM_BANKED_KIND_HIT) r->kind = DRAM_BANKED_KIND_MISS;
    break;
  case DRAM_BANKED_CMD_RD:
  case DRAM_BANKED_CMD_WR:
    if (d->cq_mode) dram_banked_ctrl_issue_column(d, c, k->cq, k->qi, now);
    else dram_banked_frfcfs_issue_column(d, c, qk, k->qi, now);
    break;
  case DRAM_BANKED_CMD_REF: dram_banked_refresh_issue(d, c, k->rank, now); break;
  case DRAM_BANKED_CMD_NONE: break;
  }
}

/* Handle DRAM cycle `now` on channel c: refreshes falling due, then the
 * controller structure's cycle (at most one command); then c->next. */
static void channel_cycle(struct dram_banked *d, struct dram_banked_channel *c, int64_t now) {
  dram_banked_refresh_fall_due(d, c, now);
  if (d->cq_mode) dram_banked_ctrl_cycle(d, c, now);
  else dram_banked_frfcfs_cycle(d, c, now);
}

static bool channel_busy(const struct dram_banked *d, const struct dram_banked_channel *c) {
  if (c->q[DRAM_BANKED_RD_Q].n || c->q[DRAM_BANKED_WR_Q].n || c->cq_n) return true;
  for (uint32_t k = 0; k < d->p.ranks; k++)
    if (c->ranks[k].pending) return true;
  return false;
}

/* The next DRAM cycle to handle (DRAM_BANKED_FAR: none). The oracle mode handles every
 * cycle while any channel has work, and otherwise jumps to the next refresh. */
static int64_t next_cycle(const struct dram_banked *d) {
  int64_t w = DRAM_BANKED_FAR;
  for (uint32_t i = 0; i < d->p.channels; i++) {
    const struct dram_banked_channel *c = &d->ch[i];
    if (d->p.tick_every_cycle) {
      if (channel_busy(d, c)) return d->cursor;
      for (uint32_t k = 0; k < d->p.ranks; k++)
        if (c->ranks[k].next_due < w) w = c->ranks[k].next_due;
    } else if (c->next < w) {
      w = c->next;
    }
  }
  return w < d->cursor ? d->cursor : w;
}

/* Has the level queued work that needs a wake: a request queued in a
 * channel that is not parked (dram_banked_ctrl_parked)? */
static bool has_work(struct dram_banked *d) {
  if (!d->queued) return false;
  if (!d->cq_mode || d->p.idle_drain_cycles) return true;
  for (uint32_t i = 0; i < d->p.channels; i++) {
    struct dram_banked_channel *c = &d->ch[i];
    const bool queued = c->q[DRAM_BANKED_RD_Q].n || c->q[DRAM_BANKED_WR_Q].n || c->cq_n;
    if (queued && !dram_banked_ctrl_parked(d, c, d->cursor)) return true;
  }
  return false;
}

void dram_banked_schedule_wake(struct dram_banked *d) {
  if (d->space_due) {
    d->space_due = false;
    engine_at(d->e, engine_now(d->e), on_space, d, 0);
  }
  /* Idle (nothing queued, or only parked writes): no wake; refreshes are
   * caught up at the next call. */
  if (!has_work(d)) return;
  int64_t w = next_cycle(d);
  CHECK_LT(w, DRAM_BANKED_FAR);
  uint64_t t = core_deciding(d, w);
  if (t >= d->wake_at) return;
  d->wake_at = t;
  engine_at(d->e, t, on_wake, d, t);
}

/* Handle every DRAM cycle that can be decided by now: those before the first
 * one that begins at or after engine_now (per_bank: that one too, since what
 * arrives in it arrives after its tick). */
/* Run the channels' cycles up to core cycle t's. */
static void advance_to(struct dram_banked *d, uint64_t t) {
  const int64_t limit = (int64_t)dram_clock_from_core(d->clk, t) + d->cq_mode;
  for (;;) {
    int64_t w = next_cycle(d);
    if (w >= limit) break;
    for (uint32_t i = 0; i < d->p.channels; i++) {
      struct dram_banked_channel *c = &d->ch[i];
      if (d->p.tick_every_cycle || c->next <= w) channel_cycle(d, c, w);
    }
    d->cursor = w + 1;
  }
  if (d->cursor < limit) d->cursor = limit;
}

static void advance(struct dram_banked *d) {
  advance_to(d, engine_now(d->e));
  dram_banked_schedule_wake(d);
}

/* ---- The level ---- */

static bool banked_can_take(void *self, uint64_t addr, bool write) {
  /* Answering needs the state as of now: the cycles before it first. */
  struct dram_banked *d = self;
  advance(d);
  struct dram_banked_coord co;
  dram_banked_decode(d, addr, &co);
  struct dram_banked_channel *c = &d->ch[co.channel];
  const struct dram_banked_queue *q = &c->q[write ? DRAM_BANKED_WR_Q : DRAM_BANKED_RD_Q];
  if (d->cq_mode && c->took_at == d->cursor - 1) {
    /* One request a channel a DRAM cycle: ask again in the next. */
    uint64_t t = core_deciding(d, d->cursor);
    if (d->space_at != t) {
      d->space_at = t;
      engine_at(d->e, t, on_space, d, 0);
    }
    return false;
  }
  return q->n < q->cap;
}

static void banked_take(void *self, uint64_t addr, bool write, uint64_t tag) {
  struct dram_banked *d = self;
  CHECK_EQ(addr & (SIM_LINE_BYTES - 1), 0);
  advance(d);
  struct dram_banked_coord co;
  dram_banked_decode(d, addr, &co);
  struct dram_banked_channel *c = &d->ch[co.channel];
  if (d->cq_mode) dram_banked_ctrl_take(d, c, &co, addr, write, tag);
  else dram_banked_frfcfs_take(d, c, &co, addr, write, tag);
}

static void banked_finish(void *self, uint64_t end) {
  struct dram_banked *d = self;
  /* The run may end after its last event (a thread's last compute): the
   * DRAM idles (and refreshes) to the end, so its time is the run's. */
  CHECK_GE(end, engine_now(d->e));
  advance_to(d, end);
  /* Nothing left but parked writes (idle_drain_cycles 0), never written. */
  CHECK(!has_work(d));
  for (uint32_t i = 0; i < d->p.channels; i++) d->st.writes_left += d->ch[i].q[DRAM_BANKED_WR_Q].n;
  CHECK_EQ(d->queued, d->st.writes_left);
  CHECK_EQ(d->inflight, 0);
  area_to(d, DRAM_BANKED_RD_Q, end);
  area_to(d, DRAM_BANKED_WR_Q, end);
  for (uint32_t i = 0; i < d->p.channels; i++)
    for (uint32_t j = 0; j < d->banks_per_channel; j++) {
      struct dram_banked_bank *bk = &d->ch[i].banks[j];
      if (bk->act_at < 0) continue;
      int64_t shut = bk->close_at < d->cursor ? bk->close_at : d->cursor;
      if (shut > bk->act_at) d->st.bank_open_cycles += (uint64_t)(shut - bk->act_at);
      bk->act_at = -1;
    }
  dram_banked_power_finish(d, d->cursor);
  d->finished_dram_cycles = (uint64_t)d->cursor;
  d->finished = true;
}

static void banked_destroy(void *self) { dram_banked_destroy(self); }

const struct dram_level_ops dram_banked_ops = {banked_can_take, banked_take,
                                               banked_finish,   dram_banked_stats_part,
                                               banked_destroy,  dram_banked_energy_so_far};

struct dram_banked *dram_banked_create(const struct dram_banked_params *p, uint64_t core_khz,
                                       struct engine *e, const struct dram_client *client) {
  CHECK(dram_banked_params_problem(p) == NULL);
  CHECK(dram_banked_params_within_model(p));
  CHECK(client && client->done);
  struct dram_banked *d = xcalloc(1, sizeof *d);
  d->p = *p;
  d->clk = dram_clock_make(core_khz, (uint64_t)p->clock_mhz * 1000);
  d->e = e;
  d->client = *client;
  d->banks_per_rank = p->bank_groups * p->banks_per_group;
  d->banks_per_channel = p->ranks * d->banks_per_rank;
  d->burst_cycles = p->burst_length / 2;
  d->refresh_step = p->tREFI / p->ranks;
  d->cq_mode = p->queue_structure != DRAM_BANKED_SHARED;
  d->wake_at = UINT64_MAX;
  dram_banked_map_init(&d->map, p);
  d->ch = xcalloc(p->channels, sizeof *d->ch);
  for (uint32_t i = 0; i < p->channels; i++) {
    struct dram_banked_channel *c = &d->ch[i];
    c->q[DRAM_BANKED_RD_Q].cap = p->read_queue;
    c->q[DRAM_BANKED_RD_Q].r = xcalloc(p->read_queue, sizeof(struct dram_banked_req));
    c->q[DRAM_BANKED_WR_Q].cap = p->write_queue;
    c->q[DRAM_BANKED_WR_Q].r = xcalloc(p->write_queue, sizeof(struct dram_banked_req));
    c->rd = DRAM_BANKED_NEVER;
    dram_banked_bus_init(d, c);
    c->banks = xcalloc(d->banks_per_channel, sizeof *c->banks);
    for (uint32_t j = 0; j < d->banks_per_channel; j++) {
      struct dram_banked_bank *bk = &c->banks[j];
      bk->act_ok = bk->col_ok = bk->pre_ok = bk->ref_ok = DRAM_BANKED_NEVER;
      bk->act_at = -1;
      bk->close_at = DRAM_BANKED_FAR;
    }
    c->groups = xcalloc(p->ranks * p->bank_groups, sizeof *c->groups);
    for (uint32_t j = 0; j < p->ranks * p->bank_groups; j++)
      c->groups[j].act = c->groups[j].rd = c->groups[j].wr = DRAM_BANKED_NEVER;
    c->ranks = xcalloc(p->ranks, sizeof *c->ranks);
    c->floors = xcalloc((size_t)p->ranks * 2, sizeof *c->floors);
    c->col_gen = 1; /* (a floor of generation 0 was never fitted) */
    if (d->cq_mode) {
      c->ncq = p->queue_structure == DRAM_BANKED_PER_RANK ? p->ranks : d->banks_per_channel;
      c->cq = xcalloc(c->ncq, sizeof *c->cq);
      c->cq_busy = xcalloc((c->ncq + 63) / 64, sizeof *c->cq_busy);
      c->sum = xcalloc(c->ncq, sizeof *c->sum);
      c->fresh = xcalloc((c->ncq + 63) / 64, sizeof *c->fresh);
      c->has_act = xcalloc((c->ncq + 63) / 64, sizeof *c->has_act);
      c->has_col = xcalloc((c->ncq + 63) / 64, sizeof *c->has_col);
      c->blocked = xcalloc((c->ncq + 63) / 64, sizeof *c->blocked);
      c->full = xcalloc((c->ncq + 63) / 64, sizeof *c->full);
      c->rd_for = xcalloc(c->ncq, sizeof *c->rd_for);
      c->rd_any = xcalloc((c->ncq + 63) / 64, sizeof *c->rd_any);
      if (p->queue_structure == DRAM_BANKED_PER_BANK)
        c->col_stale = xcalloc((c->ncq + 63) / 64, sizeof *c->col_stale);
      for (uint32_t j = 0; j < c->ncq; j++) {
        c->cq[j].cap = p->command_queue;
        c->cq[j].r = xcalloc(p->command_queue, sizeof(struct dram_banked_req));
      }
      c->last_busy = c->took_at = DRAM_BANKED_NEVER;
    }
    for (uint32_t k = 0; k < p->ranks; k++) {
      struct dram_banked_rank *rk = &c->ranks[k];
      rk->act = rk->rd = rk->wr = rk->ref_end = DRAM_BANKED_NEVER;
      for (int j = 0; j < 4; j++) rk->faw[j] = DRAM_BANKED_NEVER;
    }
    dram_banked_refresh_init(d, c);
    c->next = c->due_min;
  }
  return d;
}

void dram_banked_destroy(struct dram_banked *d) {
  if (!d) return;
  for (uint32_t i = 0; i < d->p.channels; i++) {
    struct dram_banked_channel *c = &d->ch[i];
    free(c->q[DRAM_BANKED_RD_Q].r);
    free(c->q[DRAM_BANKED_WR_Q].r);
    free(c->bursts);
    free(c->banks);
    free(c->groups);
    free(c->ranks);
    free(c->floors);
    for (uint32_t j = 0; j < c->ncq; j++) free(c->cq[j].r);
    free(c->cq);
    free(c->cq_busy);
    free(c->sum);
    free(c->fresh);
    free(c->has_act);
    free(c->has_col);
    free(c->blocked);
    free(c->full);
    free(c->rd_for);
    free(c->rd_any);
    free(c->col_stale);
    free(c->fol);
  }
  free(d->ch);
  free(d);
}
