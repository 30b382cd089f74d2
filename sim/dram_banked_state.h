/* The banked DRAM level's inside: the state its files share and the calls
 * between them. Private to the level: only sim/dram_banked*.c include it (and
 * the tests of its pieces, tests/test_dram_*.c); the contract is
 * sim/dram_banked.h. Times are signed DRAM cycles; DRAM_BANKED_NEVER sits far
 * enough below zero that adding any timing to it still constrains nothing.
 *
 * One idea a file:
 *   dram_banked.c          the level: clock and events, a request's life
 *                          (taken, queued, served), creation
 *   dram_banked_bank.c     bank, group and rank state: each command's
 *                          earliest time and the state it leaves
 *   dram_banked_bus.c      the data bus: bursts and where the next one fits
 *   dram_banked_cmdq.c     per_bank / per_rank: a command queue's candidates,
 *                          its kept summary, the round-robin scan
 *   dram_banked_ctrl.c     per_bank / per_rank: DRAMsim3's controller,
 *                          transaction queues feeding command queues
 *   dram_banked_frfcfs.c   queue_structure shared: FR-FCFS over a read and a
 *                          write queue
 *   dram_banked_map.c      the address mapping
 *   dram_banked_params.c   the rules between parameters
 *   dram_banked_power.c    energy: joules from each rank's commands and states
 *   dram_banked_refresh.c  refresh: due times and the work they bring
 *   dram_banked_stats.c    the level's numbers
 *
 * NOTE: the hot calls between these files (the scan, the earliest times, the
 * bus) cost the same as calls within one file only while gcc's link-time
 * optimisation keeps them in one partition, and it partitions in link order
 * (these names sort the hot files together). A call across a partition loses
 * interprocedural register allocation: with the bank state's file sorted after
 * the cold ones a DRAM-bound run took 0.6% more instructions. After moving
 * code between these files, compare callgrind totals; -flto-partition=one
 * removes the dependence on file order at about twice the link time. */
#ifndef RTSIM_SIM_DRAM_BANKED_STATE_H
#define RTSIM_SIM_DRAM_BANKED_STATE_H

#include <stdbool.h>
#include <stdint.h>

#include "sim/dram_banked.h"
#include "sim/dram_level.h"
#include "sim/line.h"

struct engine;
struct stats_part;

#define DRAM_BANKED_NEVER (-((int64_t)1 << 40))
#define DRAM_BANKED_FAR INT64_MAX

enum { DRAM_BANKED_RD_Q = 0, DRAM_BANKED_WR_Q = 1 };
enum { DRAM_BANKED_KIND_HIT = 0, DRAM_BANKED_KIND_MISS = 1, DRAM_BANKED_KIND_CONFLICT = 2 };
enum dram_banked_cmd_type {
  DRAM_BANKED_CMD_NONE,
  DRAM_BANKED_CMD_ACT,
  DRAM_BANKED_CMD_PRE,
  DRAM_BANKED_CMD_RD,
  DRAM_BANKED_CMD_WR,
  DRAM_BANKED_CMD_REF
};

struct dram_banked_bank {
  int64_t act_ok;           /* earliest ACT: PRE + tRP, ACT + tRC, REF + tRFC */
  int64_t col_ok;           /* ACT + tRCD */
  int64_t pre_ok;           /* ACT + tRAS, RD + tRTP, WR + tCWL + BL/2 + tWR */
  int64_t ref_ok;           /* its last precharge + tRP */
  int64_t act_at, close_at; /* the current or last open interval (act_at < 0: none) */
  uint64_t row;
  uint32_t hits; /* column commands since ACT */
  bool open;
  /* Scan scratch, valid when stamp == the channel's scan number. */
  uint64_t stamp;
  bool conflict_seen, hit_held;
};

struct dram_banked_group {
  int64_t act, rd, wr; /* last ACT, RD, WR in the bank group */
};

struct dram_banked_rank {
  int64_t act, rd, wr; /* last ACT, RD, WR in the rank */
  int64_t faw[4];      /* the last four ACTs, a ring from faw_i (oldest) */
  unsigned faw_i;
  int64_t ref_end;  /* REF + tRFC */
  int64_t next_due; /* the next refresh falls due (DRAM_BANKED_FAR: refresh off) */
  uint32_t pending; /* refreshes due and not yet issued */
  uint32_t open;    /* banks with a row open */
  /* Energy's counts (dram_banked_power.c): its ACT, RD, WR and REF commands,
   * and the DRAM cycles it had a bank open (DRAMsim3's rank state: active from
   * the cycle of the ACT that opens its first bank to that of the precharge
   * that closes its last; active_since: that ACT's, while open). */
  uint64_t acts, reads, writes, refs, active_cycles;
  int64_t active_since;
};

struct dram_banked_req {
  uint64_t tag, take_core, seq, row, line, column;
  /* The first DRAM cycle its commands may issue (controller_cycles after
   * taken). per_bank: a transaction may move at the end of cycle ready - 1;
   * moved at the end of m, its command may issue from m + 1. */
  int64_t ready;
  uint32_t rank, group, bank; /* bank: index within the channel */
  uint32_t cq;                /* per_bank / per_rank: its command queue */
  uint8_t kind;
  bool write;
};

/* A read served by another queued read of its line (per_bank). */
struct dram_banked_follower {
  uint64_t line, tag;
};

struct dram_banked_queue {
  struct dram_banked_req *r; /* in age order */
  uint32_t n, cap;
};

struct dram_banked_burst {
  int64_t start;
  uint32_t rank;
  bool write;
};

/* A floor under the earliest time of every column command of one rank and
 * direction, as of cycle `at` and the channel's column generation gen
 * (dram_banked_col_floor). */
struct dram_banked_floor {
  int64_t at, t;
  uint64_t gen;
};

/* A command: its type, where it goes, and for which request. */
struct dram_banked_cmd {
  enum dram_banked_cmd_type type;
  uint32_t rank, bank; /* bank within the channel */
  uint32_t qi;         /* request index in the served queue (per_bank: in command queue cq) */
  uint32_t cq;
  bool for_req; /* a request's command (else refresh work) */
};

/* A scan's answer: the command to issue now (type DRAM_BANKED_CMD_NONE: none), the
 * earliest cycle anything could, and the first candidate in scan order whose
 * earliest time is the least of all candidates' (first_t; DRAM_BANKED_FAR: none). */
struct dram_banked_pick {
  struct dram_banked_cmd cmd;
  int64_t next; /* earliest cycle >= now any candidate could issue (DRAM_BANKED_FAR: none) */
  struct dram_banked_cmd first;
  int64_t first_t;
};

/* A command queue's summary: of its candidates as of cycle `at`, the least
 * earliest time t (DRAM_BANKED_FAR: none) and the first candidate with it. */
struct dram_banked_qsum {
  int64_t at, t;
  struct dram_banked_cmd k;
  int64_t act_t, rd_t,
      wr_t; /* the least of its ACT, RD and WR candidates (DRAM_BANKED_FAR: none) */
  /* per_bank: the one ACT or PRE candidate (o_t DRAM_BANKED_FAR: none), and the entries
   * of the RD and WR candidates (see col_refresh in dram_banked_cmdq.c). */
  int64_t o_t;
  struct dram_banked_cmd o;
  uint32_t rd_j, wr_j;
};

struct dram_banked_channel {
  struct dram_banked_queue q[2];
  bool writing;
  int64_t rd;                       /* last RD on the channel (tRTW) */
  struct dram_banked_burst *bursts; /* data bursts that may still matter, by start */
  uint32_t nb, cap_b;
  struct dram_banked_bank *banks;   /* ranks x groups x banks_per_group */
  struct dram_banked_group *groups; /* ranks x groups */
  struct dram_banked_rank *ranks;
  int64_t next; /* earliest cycle a command may issue or a refresh fall due */
  /* Refresh at a glance (dram_banked_refresh.c): the least of the ranks'
   * next_due, and how many ranks have a refresh pending. */
  int64_t due_min;
  uint32_t ref_ranks;
  uint64_t scan_no;
  /* Floors under column commands' times by rank x 2 + write
   * (dram_banked_col_floor); col_gen counts column commands, from 1. */
  struct dram_banked_floor *floors;
  uint64_t col_gen;
  /* per_bank / per_rank: */
  struct dram_banked_queue *cq; /* command queues, by bank within the channel or by rank */
  uint32_t ncq, cq_n;           /* command queues; commands in them all */
  uint64_t *cq_busy;            /* bit i of word i / 64: command queue i holds a command */
  uint32_t rr;                  /* the command queue probed last (round robin) */
  uint32_t draining;            /* writes still to move in the current drain */
  int64_t last_busy;            /* the last cycle a request arrived or a request command issued */
  int64_t took_at;              /* the arrival cycle of the last request taken */
  struct dram_banked_follower *fol; /* reads waiting for another read's RD */
  uint32_t nfol, cap_fol;
  /* per_bank / per_rank: each command queue's least candidate (dram_banked_cmdq.c),
   * and bitmaps by command queue: its summary is fresh; it has an ACT
   * candidate; it has a column candidate (what a command elsewhere can
   * invalidate: see cq_sum). */
  struct dram_banked_qsum *sum;
  uint64_t *fresh, *has_act, *has_col;
  uint64_t *col_stale; /* per_bank: only its column candidates' times may have moved */
  uint64_t *blocked;   /* bitmap: the command queue's rank has a refresh due */
  uint64_t *full;      /* bitmap: the command queue is full */
  uint32_t *rd_for;    /* by command queue: read transactions in the read queue bound for it */
  uint64_t *rd_any;    /* bitmap: rd_for is not 0 */
  /* The last scan's first least candidate (memo, at cycle memo_t), made at
   * cycle memo_at, kept while no command issued and no entry or refresh came
   * since (memo_ok; see dram_banked_ctrl_cycle). */
  bool memo_ok;
  int64_t memo_at, memo_t;
  struct dram_banked_cmd memo;
  /* The end-of-cycle move (schedule_cq in dram_banked_ctrl.c) changes
   * nothing at any cycle of [idle_from, idle_to), kept while no command
   * issued and no transaction came or moved since (idle_ok). */
  bool idle_ok;
  int64_t idle_from, idle_to;
};

/* The address mapping: shift and mask of each field above the line offset. */
struct dram_banked_map {
  unsigned sh_ch, sh_ra, sh_bg, sh_ba, sh_ro, sh_co;
  uint64_t mk_ch, mk_ra, mk_bg, mk_ba, mk_ro, mk_co;
  uint32_t burst_length; /* a line's first device column: its co field times this */
};

struct dram_banked {
  struct dram_banked_params p;
  struct dram_clock clk;
  struct engine *e;
  struct dram_client client;
  struct dram_banked_channel *ch;
  uint32_t banks_per_rank, banks_per_channel;
  int64_t burst_cycles; /* BL / 2 */
  int64_t refresh_step; /* tREFI / ranks */
  bool cq_mode;         /* queue_structure per_bank or per_rank */
  struct dram_banked_map map;
  int64_t cursor;   /* the first DRAM cycle not yet handled */
  uint64_t wake_at; /* earliest wake pending (UINT64_MAX: none) */
  uint64_t
      space_at; /* per_bank: the latest space callback scheduled for a refused second request */
  uint64_t seq, inflight, queued;
  /* Occupancy integrals by time, per queue kind. */
  uint64_t q_len[2], q_last[2];
  bool space_due;
  uint64_t finished_dram_cycles; /* the cursor when finished */
  bool finished;
  struct dram_banked_stats st;
};

static inline int64_t max64(int64_t a, int64_t b) { return a > b ? a : b; }

/* A candidate that may issue from cycle t, into a scan's answer pk. qi: the
 * request's index in the served queue (per_bank / per_rank: in command queue
 * cq), or -1 for refresh work. */
static inline void dram_banked_consider_in(struct dram_banked_pick *pk, int64_t t, int64_t now,
                                           enum dram_banked_cmd_type type, uint32_t rank,
                                           uint32_t bank, uint32_t cq, int64_t qi) {
  const struct dram_banked_cmd k = {type, rank, bank, qi >= 0 ? (uint32_t)qi : 0, cq, qi >= 0};
  if (t < pk->next) pk->next = t;
  if (t < pk->first_t) {
    pk->first_t = t;
    pk->first = k;
  }
  if (t == now && pk->cmd.type == DRAM_BANKED_CMD_NONE) pk->cmd = k;
}

static inline void dram_banked_consider(struct dram_banked_pick *pk, int64_t t, int64_t now,
                                        enum dram_banked_cmd_type type, uint32_t rank,
                                        uint32_t bank, int64_t qi) {
  dram_banked_consider_in(pk, t, now, type, rank, bank, 0, qi);
}

/* ---- dram_banked.c: the level ---- */

/* Issue command k on channel c at DRAM cycle now: its state, its request's
 * bookkeeping. */
void dram_banked_issue(struct dram_banked *d, struct dram_banked_channel *c,
                       const struct dram_banked_cmd *k, int64_t now);
/* Queue a request in its channel's queue qk (the request's fields but tag,
 * line and ready from co); the level's counters follow. */
struct dram_banked_req *dram_banked_enqueue(struct dram_banked *d, struct dram_banked_channel *c,
                                            int qk, const struct dram_banked_coord *co,
                                            uint64_t addr, uint64_t tag, int64_t ready);
/* r, of queue kind qk, leaves its queue at its column command at now. */
void dram_banked_queue_leave(struct dram_banked *d, int qk, const struct dram_banked_req *r,
                             int64_t now);
/* Count a column command's row hit, miss or conflict. */
void dram_banked_count_kind(struct dram_banked *d, uint8_t kind);
/* Answer tag at core cycle t (>= engine_now), from an event. */
void dram_banked_serve(struct dram_banked *d, uint64_t t, uint64_t tag);
/* Raise a space callback if one is due, and schedule the next wake. */
void dram_banked_schedule_wake(struct dram_banked *d);

/* ---- dram_banked_frfcfs.c: queue_structure shared ---- */

/* Handle DRAM cycle now on channel c (refreshes fallen due); set c->next. */
void dram_banked_frfcfs_cycle(struct dram_banked *d, struct dram_banked_channel *c, int64_t now);
/* Take a request of line addr (coordinates co) into channel c. */
void dram_banked_frfcfs_take(struct dram_banked *d, struct dram_banked_channel *c,
                             const struct dram_banked_coord *co, uint64_t addr, bool write,
                             uint64_t tag);
/* Issue the column command of entry qi of queue kind qk at now. */
void dram_banked_frfcfs_issue_column(struct dram_banked *d, struct dram_banked_channel *c, int qk,
                                     uint32_t qi, int64_t now);

/* ---- dram_banked_ctrl.c: per_bank / per_rank ---- */

/* Handle DRAM cycle now on channel c (refreshes fallen due): at most one
 * command, at most one transaction moved; set c->next. */
void dram_banked_ctrl_cycle(struct dram_banked *d, struct dram_banked_channel *c, int64_t now);
/* Take a request of line addr (coordinates co) into channel c; it arrives
 * after DRAM cycle cursor - 1. */
void dram_banked_ctrl_take(struct dram_banked *d, struct dram_banked_channel *c,
                           const struct dram_banked_coord *co, uint64_t addr, bool write,
                           uint64_t tag);
/* Issue the column command of entry j of command queue qi at now. */
void dram_banked_ctrl_issue_column(struct dram_banked *d, struct dram_banked_channel *c,
                                   uint32_t qi, uint32_t j, int64_t now);
/* Is channel c parked at cycle t: idle_drain_cycles 0 and its only work
 * writes in its write buffer, all arrived, that no drain will move before the
 * next request arrives? (Such a channel needs no wake.) */
bool dram_banked_ctrl_parked(struct dram_banked *d, struct dram_banked_channel *c, int64_t t);
/* The command queue request r goes to. */
uint32_t dram_banked_cq_of(const struct dram_banked *d, const struct dram_banked_req *r);

/* ---- dram_banked_cmdq.c: per_bank / per_rank command queues ---- */

/* Refresh work, then the command queues round robin; see the file. */
void dram_banked_cmdq_scan(struct dram_banked *d, struct dram_banked_channel *c, int64_t now,
                           struct dram_banked_pick *pk);
/* What a change makes stale (each does nothing with queue_structure shared):
 * bank `bank`'s state or its command queue's entries; all of rank k's state
 * (a refresh); rank k's ACT spacing (an ACT at now); the column spacing and
 * the bus (a column command at now). */
void dram_banked_stale_bank(const struct dram_banked *d, struct dram_banked_channel *c,
                            uint32_t bank);
void dram_banked_stale_rank(const struct dram_banked *d, struct dram_banked_channel *c, uint32_t k);
void dram_banked_stale_acts(const struct dram_banked *d, struct dram_banked_channel *c, uint32_t k,
                            int64_t now);
void dram_banked_stale_columns(const struct dram_banked *d, struct dram_banked_channel *c,
                               bool write, int64_t now);
/* Rank k's command queues take no command while it has a refresh due. */
void dram_banked_block_rank(const struct dram_banked *d, struct dram_banked_channel *c, uint32_t k,
                            bool due);

/* ---- dram_banked_bank.c: bank, group and rank state ---- */

/* The earliest cycle >= now request r's ACT, or its column command (a write's
 * or a read's), could issue. */
int64_t dram_banked_act_earliest(const struct dram_banked *d, const struct dram_banked_channel *c,
                                 const struct dram_banked_req *r, int64_t now);
int64_t dram_banked_col_earliest(const struct dram_banked *d, const struct dram_banked_channel *c,
                                 const struct dram_banked_req *r, bool write, int64_t now);
/* The same for a command of the given type (ACT, PRE, RD or WR). */
int64_t dram_banked_req_earliest(const struct dram_banked *d, const struct dram_banked_channel *c,
                                 const struct dram_banked_req *r, enum dram_banked_cmd_type type,
                                 int64_t now);
/* A cycle no column command of `rank` (a WR: write) asked at any cycle from
 * now on comes before, until the next column command: the data bus's first
 * fit from the rank's and the channel's spacing (its groups' spacing
 * ignored). Kept in c->floors. */
int64_t dram_banked_col_floor_fit(const struct dram_banked *d, struct dram_banked_channel *c,
                                  uint32_t rank, bool write, int64_t now);
static inline int64_t dram_banked_col_floor(const struct dram_banked *d,
                                            struct dram_banked_channel *c, uint32_t rank,
                                            bool write, int64_t now) {
  const struct dram_banked_floor *f = &c->floors[rank * 2 + write];
  if (f->gen == c->col_gen && now >= f->at && now <= f->t) return f->t;
  return dram_banked_col_floor_fit(d, c, rank, write, now);
}
/* The state an ACT of r's row in bank k->bank leaves at now. */
void dram_banked_activate(struct dram_banked *d, struct dram_banked_channel *c,
                          const struct dram_banked_cmd *k, const struct dram_banked_req *r,
                          int64_t now);
/* Bank bk of rank `rank` precharges at `at`, by a command issued at now (a PRE at
 * now, or a column command's auto-precharge). */
void dram_banked_bank_close(struct dram_banked *d, struct dram_banked_channel *c,
                            struct dram_banked_bank *bk, uint32_t rank, int64_t now, int64_t at);
/* The bank, rank, group and bus state of r's column command at now; returns
 * the cycle its data transfer ends. */
int64_t dram_banked_column_state(struct dram_banked *d, struct dram_banked_channel *c,
                                 const struct dram_banked_req *rq, bool write, int64_t now);

/* ---- dram_banked_bus.c: the data bus ---- */

/* Channel c's burst list, empty (freed with the channel). */
void dram_banked_bus_init(const struct dram_banked *d, struct dram_banked_channel *c);

/* The earliest start >= s0 of a burst of `rank` (a write or a read) that
 * overlaps no burst on channel c, with the idle cycle between ranks. */
int64_t dram_banked_bus_fit(const struct dram_banked *d, const struct dram_banked_channel *c,
                            int64_t s0, uint32_t rank, bool write);
/* Record a burst at `start` by a command at `now` (forgetting those no later
 * command can meet). */
void dram_banked_bus_add(struct dram_banked *d, struct dram_banked_channel *c, int64_t now,
                         int64_t start, uint32_t rank, bool write);

/* ---- dram_banked_refresh.c: refresh ---- */

/* The cycle rank `rank`'s k-th refresh (k >= 0) falls due
 * (DRAM_BANKED_FAR: refresh off). */
int64_t dram_banked_refresh_due(const struct dram_banked *d, uint32_t rank, uint64_t k);
/* Channel c's refresh state at creation: each rank's first due time. */
void dram_banked_refresh_init(const struct dram_banked *d, struct dram_banked_channel *c);
/* Refreshes falling due by cycle now on channel c. */
void dram_banked_refresh_fall_due(struct dram_banked *d, struct dram_banked_channel *c,
                                  int64_t now);
/* Refresh work's candidates at now into pk (the scan's first). */
void dram_banked_scan_refresh(struct dram_banked *d, struct dram_banked_channel *c, int64_t now,
                              struct dram_banked_pick *pk);
/* A REF of rank `rank` at now. */
void dram_banked_refresh_issue(struct dram_banked *d, struct dram_banked_channel *c, uint32_t rank,
                               int64_t now);

/* ---- dram_banked_map.c: the address mapping ---- */

/* m for p's mapping and sizes (p passed dram_banked_params_problem). */
void dram_banked_map_init(struct dram_banked_map *m, const struct dram_banked_params *p);
/* addr's coordinates under m (the line offset ignored; bits above the fields
 * alias). */
void dram_banked_map_decode(const struct dram_banked_map *m, uint64_t addr,
                            struct dram_banked_coord *out);
/* Address bits the six fields of p take above the line offset. */
unsigned dram_banked_map_bits(const struct dram_banked_params *p);

/* ---- dram_banked_params.c ---- */

/* Are p's timings and clock within what the level's arithmetic holds? */
bool dram_banked_params_within_model(const struct dram_banked_params *p);

/* ---- dram_banked_power.c: energy ---- */

/* Close the ranks' active intervals at the level's last cycle, end (at finish). */
void dram_banked_power_finish(struct dram_banked *d, int64_t end);
/* The level's energy so far at core cycle t, J (struct dram_level_ops's
 * energy_j; self: the level). */
double dram_banked_energy_so_far(const void *self, uint64_t t);
/* The level's energy from its stats struct s (the stats table's figures). */
void dram_banked_energy_total(const struct dram_banked *d, const struct dram_banked_stats *s,
                              struct dram_banked_energy *out);

/* ---- dram_banked_stats.c ---- */

/* The level's table, stats and ctx (the level's stats operation). */
void dram_banked_stats_part(const void *self, struct stats_part *out);

#endif
