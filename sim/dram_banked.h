/* The banked DRAM level: DDR-style channels x ranks x bank groups x banks, each
 * bank with one open row (or none), commands timed in the DRAM's own clock and
 * scheduled by one of two controller structures per channel (queue_structure),
 * behind sim/dram_level.h.
 *
 * Structure `shared`: one FR-FCFS scheduler over a read queue and a write
 * queue. Structure `per_bank` (or `per_rank`): DRAMsim3's controller, a
 * transaction queue feeding command queues served round robin. The timing of
 * commands (below, "One command per channel...") and refresh are the same for
 * both.
 *
 * Structure per_bank / per_rank, as modelled:
 * - Queues. Per channel a read queue (read_queue entries) and a write buffer
 *   (write_queue entries) of transactions, and command queues of
 *   command_queue entries: one per bank (per_bank) or per rank (per_rank).
 *   A full transaction queue refuses, and so does a channel that has taken
 *   a request in the same DRAM cycle (one a cycle, as DRAMsim3's controller
 *   is fed); client->space is raised when a transaction leaves its queue for
 *   its command queue, and in the next cycle after a second request.
 * - Time. A request taken in core cycle c arrives after DRAM cycle
 *   a = from_core(c) has been decided (as DRAMsim3's trace driver adds a
 *   request after that cycle's tick); it may move to its command queue at the
 *   end of cycle a + controller_cycles - 1 and issue from the cycle after.
 * - Moving. At the end of each DRAM cycle at most one transaction moves: the
 *   oldest of the served transaction queue whose command queue has room. The
 *   read queue is served, except during a write drain, which starts when the
 *   write buffer holds write_high writes, or more than write_low with every
 *   command queue empty, and moves as many writes as the buffer held then
 *   (reads already in command queues keep issuing meanwhile). A write whose
 *   line a queued read still waits for ends the drain.
 * - Issue. Refresh work first; else the command queues are probed round
 *   robin from the one after the last that issued, and the first command
 *   queue with a command that can issue now issues the oldest such command
 *   (in order with readiness skipping: row hits are not promoted past an
 *   older ready ACT or PRE of the same queue). A PRE for a queued request
 *   needs no older request of its queue for the same bank, and no request of
 *   its queue left to hit the open row unless the row has served
 *   DRAM_BANKED_ROW_HIT_CAP column commands. A write waits behind an older
 *   read of its line in its queue. The queues of a rank with a refresh due
 *   are skipped.
 * - Writes are posted: a write is served controller_cycles after it arrives
 *   (it waits in the write buffer). A read of a line whose write has not
 *   issued is answered from it, and a write of such a line replaces it, both
 *   served controller_cycles after arrival; a read of a line another queued
 *   read waits for is served with it (one RD).
 * - Leftover writes (idle_drain_cycles, [ours]; DRAMsim3 leaves up to
 *   write_low writes buffered for ever): once no request has arrived and no
 *   request command issued for idle_drain_cycles DRAM cycles, with no read
 *   queued and every command queue empty, the buffered writes drain, so a run
 *   ends with them written. idle_drain_cycles 0: never, as DRAMsim3; a level
 *   whose only work is such writes is idle (it schedules no wake), and the
 *   writes still buffered when the run ends are never written (counted as
 *   writes_left; their bursts are in no energy figure).
 * - Row hits (DRAMsim3's count): a column command is a hit when its row has
 *   served one since its ACT.
 * - A write burst may follow another rank's write burst with no idle cycle
 *   (DRAMsim3's write-to-write across ranks is BL/2); every other pair of
 *   bursts of two ranks keeps the idle cycle.
 *
 * Structure shared, as modelled:
 * - Time. A request taken at core cycle c may issue its first command in DRAM
 *   cycle from_core(c) + controller_cycles (the controller's front end:
 *   queueing the request at its bank), from_core(c) being the first that
 *   begins at or after c (struct
 *   dram_clock, exact). The decision for DRAM cycle d waits until every request
 *   that could take part in it has arrived, i.e. until the first core cycle
 *   with from_core > d; state is advanced lazily to the present at every call
 *   and wake, so when a call lands within a core cycle never matters.
 * - Queues. Per channel a read queue and a write queue, bounded (read_queue,
 *   write_queue entries). A request holds its place from take until its column
 *   command issues; then client->space is raised from an event.
 * - The write queue is searched by address: a read of a line waiting there is
 *   answered from it, and a write of such a line takes its place, both served
 *   the next DRAM cycle with no command (as DRAMsim3's controller does).
 * - Write draining. Reads are served; the channel turns to writes when the write
 *   queue reaches write_high, or when no read is queued and writes are; it turns
 *   back when the write queue empties, or falls to write_low with a read
 *   waiting; it does not turn to writes while the oldest read has waited
 *   DRAM_BANKED_READ_AGE_CAP x tRC (a bound on starvation). Only the queue
 *   being served issues request commands.
 * - FR-FCFS. Among the served queue: the oldest request whose column command
 *   (a row hit) can issue this cycle; else the oldest whose PRE or ACT can.
 *   Refresh commands go before both.
 * - Open page: a row stays open after its column command. A PRE for a conflict
 *   waits while a queued request of the served queue still hits the open row.
 *   Starvation bound (DRAMsim3's cap of 4): once a row has served
 *   DRAM_BANKED_ROW_HIT_CAP column commands since its ACT, hits younger than
 *   the oldest conflicting request to that bank stop counting (and stop
 *   issuing), so the conflict waits at most for the hits older than itself.
 * - Close page: every column command auto-precharges (RDA/WRA): the bank
 *   precharges at the earliest legal time, max(ACT + tRAS, RD + tRTP) or
 *   max(ACT + tRAS, WR + tCWL + BL/2 + tWR), and may be activated tRP later.
 * - One command per channel per DRAM cycle. Constraints: ACT->RD/WR tRCD,
 *   ACT->ACT tRC, ACT->PRE tRAS, PRE->ACT tRP (same bank); RD->PRE tRTP,
 *   WR->PRE tCWL + BL/2 + tWR; RD->RD, WR->WR tCCD_L same group, tCCD_S other
 *   group (same rank); WR->RD tCWL + BL/2 + tWTR_L / tWTR_S (same rank);
 *   RD->WR tRTW (channel); ACT->ACT tRRD_L / tRRD_S (same rank); at most 4
 *   ACTs per rank in any tFAW window; data bursts (read [RD + tCL, + BL/2),
 *   write [WR + tCWL, + BL/2)) never overlap on a channel, and bursts of two
 *   different ranks are at least one idle cycle apart.
 * - Service. A read is done when its last beat arrives (RD + tCL + BL/2), a
 *   write at WR + tCWL + BL/2, each at the core cycle at or after that DRAM
 *   cycle, from an engine event.
 * - Refresh (DRAMsim3's RANK_LEVEL_STAGGERED). A refresh falls due every
 *   floor(tREFI / ranks) DRAM cycles, ranks in turn: rank r's k-th (k >= 0) at
 *   (k * ranks + r + 1) * floor(tREFI / ranks). Once due, the rank takes no
 *   request command; its open banks are precharged (tRAS, tRTP, write recovery
 *   respected), REF issues once all have been precharged for tRP, and the rank
 *   takes no ACT for tRFC. tREFI = 0 turns refresh off.
 * - Event-driven: after each handled DRAM cycle one wake is scheduled at the
 *   earliest cycle any command could issue, computed from the timing state; an
 *   idle level schedules nothing and catches up on refreshes at its next call.
 *   tick_every_cycle (a test oracle) wakes every DRAM cycle instead; both give
 *   the same results.
 *
 * Address mapping (DRAMsim3's): above the 6 line-offset bits, six fields from
 * most to least significant, "ro" "ch" "ra" "bg" "ba" "co", each log2 of its
 * count wide; co is log2(columns / burst_length) (one line per burst).
 *
 * Presets (DRAM clock cycles), from DRAMsim3's configs/:
 * - DDR4_8Gb_x8_2400.ini (Micron MT40A1G8PM-083E, DDR4-2400, tCK 0.833 ns):
 *   clock_mhz 1200; bank_groups 4, banks_per_group 4, rows 65536, columns 1024,
 *   x8 devices on a 64-bit bus (bus_bytes 8), burst_length 8, 8 GB per channel
 *   = 1 rank, channels 1, mapping "chrobabgraco". tCL 16, tCWL 16, tRCD 16,
 *   tRP 16, tRAS 39, tRC 55 (= tRAS + tRP, as DRAMsim3 derives it), tCCD_S 4,
 *   tCCD_L 6, tRRD_S 4, tRRD_L 6, tFAW 26, tWR 19, tWTR_S 3, tWTR_L 9,
 *   tREFI 9364, tRFC 420. tRTP: absent from the ini, so DRAMsim3 runs with its
 *   default 5; JEDEC's max(4 nCK, 7.5 ns) is 9, which a preset should use.
 *   tRTW: DRAMsim3 derives read-to-write as RL + BL/2 - WL + tRTRS
 *   (RL = AL + CL, WL = AL + CWL, AL 0, tRTRS 2) = 16 + 4 - 16 + 2 = 6.
 * - HBM2_8Gb_x128.ini (1000 MHz): channels 8, 1 rank, bank_groups 4,
 *   banks_per_group 4, rows 32768, columns 128 (the ini's 64, doubled by
 *   DRAMsim3 for HBM's prefetch), bus_bytes 16, burst_length 4 (BL/2 = 2),
 *   mapping "rorabgbachco"; tCL 14, tCWL 4, tRCD 14 (tRCDRD = tRCDWR), tRP 14,
 *   tRAS 34, tRC 48, tCCD_S 1, tCCD_L 2, tRRD_S 4, tRRD_L 6, tFAW 30, tWR 16,
 *   tWTR_S 6, tWTR_L 8, tREFI 3900, tRFC 260; tRTW = 14 + 2 - 4 + 2 = 14;
 *   tRTP: the ini's tRTP_L 6 / tRTP_S 4 are not read by DRAMsim3 (default 5);
 *   use 6. HBM's separate row and column command buses are not modelled here
 *   (one command per channel per cycle). */
#ifndef RTSIM_SIM_DRAM_BANKED_H
#define RTSIM_SIM_DRAM_BANKED_H

#include <stdbool.h>
#include <stdint.h>

#include "sim/dram_level.h"

struct engine;

/* Column commands a row may serve since its ACT before younger hits stop
 * holding back an older conflict (DRAMsim3's row-hit cap). */
#define DRAM_BANKED_ROW_HIT_CAP 4u
/* A read waiting longer than this many tRC holds the channel on reads (no
 * turn to writes at write_high) until it is served: a bound on starvation. */
#define DRAM_BANKED_READ_AGE_CAP 4u

enum dram_banked_page { DRAM_BANKED_OPEN_PAGE, DRAM_BANKED_CLOSE_PAGE };
/* The controller's structure (see above): shared FR-FCFS queues, or
 * DRAMsim3's transaction queue feeding command queues per bank or per rank. */
enum dram_banked_queues { DRAM_BANKED_SHARED, DRAM_BANKED_PER_BANK, DRAM_BANKED_PER_RANK };

struct dram_banked_params {
  uint32_t clock_mhz; /* DRAM command clock (DDR4-2400: 1200) */
  uint32_t channels, ranks, bank_groups, banks_per_group;
  uint32_t rows, columns; /* per bank; columns in device columns, a burst covers
                             burst_length of them */
  uint32_t bus_bytes;     /* data bus width per channel; bus_bytes * burst_length = 64 */
  uint32_t burst_length;  /* beats per burst (even); a burst takes burst_length / 2 cycles */
  char mapping[16];       /* e.g. "rochrababgco" */
  enum dram_banked_page page;
  uint32_t read_queue, write_queue; /* entries per channel */
  uint32_t write_high, write_low;   /* write drain watermarks (entries) */
  uint32_t controller_cycles;       /* DRAM cycles from taking a request to its first command */
  enum dram_banked_queues queue_structure;
  uint32_t command_queue; /* per_bank / per_rank: entries a command queue */
  /* per_bank / per_rank: DRAM cycles without an arrival or a request command,
   * with no read queued, after which buffered writes drain (see above; 0:
   * never). */
  uint32_t idle_drain_cycles;
  /* Timing in DRAM clock cycles. */
  uint32_t tCL, tCWL, tRCD, tRP, tRAS, tRC, tCCD_S, tCCD_L, tRRD_S, tRRD_L, tFAW, tWR, tWTR_S,
      tWTR_L, tRTW, tRTP, tREFI, tRFC;
  /* Energy (sim/dram_banked_stats.c): a device's data width in bits (a rank is
   * bus_bytes x 8 / device_width devices), its supply in volts and its
   * datasheet currents in mA: IDD0 (one bank activated and precharged every
   * tRC), IDD2N (all banks precharged, standby), IDD3N (a bank active,
   * standby), IDD4R / IDD4W (burst reads / writes), IDD5AB (all-bank refresh). */
  uint32_t device_width;
  double VDD, IDD0, IDD2N, IDD3N, IDD4R, IDD4W, IDD5AB;
  bool tick_every_cycle; /* test only: wake every DRAM cycle while work is queued */
  bool check_summaries;  /* test only: check each command queue's kept summary against its
                            candidates asked again (per_bank / per_rank) */
};

/* NULL if p is usable, else "dram.KEY: what is wrong" (a constant string):
 * powers of two and the rules between keys. Each key's range is the key
 * table's (machine_cfg_range_problem), checked before a machine is built. */
const char *dram_banked_params_problem(const struct dram_banked_params *p);

/* Is s a usable mapping: six two-letter fields, each of ro ch ra bg ba co once? */
bool dram_banked_mapping_ok(const char *s);

struct dram_banked;

/* A level on engine e calling back client (copied); core_khz: the core clock.
 * p is CHECKed with dram_banked_params_problem. Caller destroys. */
struct dram_banked *dram_banked_create(const struct dram_banked_params *p, uint64_t core_khz,
                                       struct engine *e, const struct dram_client *client);
void dram_banked_destroy(struct dram_banked *d); /* NULL ok */

/* The level's operations; self is a struct dram_banked *. */
extern const struct dram_level_ops dram_banked_ops;

/* Counters over the run (complete after finish). Queue figures sum over
 * channels; "queue time" runs from take to the request's column command. */
struct dram_banked_stats {
  uint64_t reads, writes;
  uint64_t row_hits, row_misses, row_conflicts; /* per request, at its column command: found
                                                   its row open / its bank closed / another
                                                   row open */
  uint64_t activates, precharges;               /* precharges include auto-precharges */
  uint64_t refreshes, refresh_cycles;           /* refresh_cycles: rank-cycles (DRAM) in tRFC */
  uint64_t write_drains;                        /* turns from reads to writes */
  uint64_t write_forwards; /* reads answered from the write queue (no command) */
  uint64_t write_merges;   /* writes that found their line in the write queue */
  uint64_t read_merges;    /* per_bank / per_rank: reads served by another queued read's RD */
  uint64_t writes_left;    /* writes still buffered at the end, never written (none unless
                              idle_drain_cycles is 0) */
  /* Per queue kind [0] reads, [1] writes: */
  uint64_t queue_area[2]; /* time integral of the entries queued, core cycles x entries */
  uint64_t queue_wait_sum_cycles[2]; /* sum over requests of their queue time (core cycles) */
  uint64_t queue_wait_max_cycles[2];
  uint64_t queue_max[2];     /* most entries queued at once, all channels together */
  uint64_t bus_busy_cycles;  /* data bus cycles carrying a burst, summed over channels */
  uint64_t bank_open_cycles; /* DRAM cycles with a row open, summed over banks */
  /* Energy's (dram_banked_energy): rank-cycles (DRAM) with a bank open, and
   * all rank-cycles the level ran (its DRAM cycles x ranks x channels). */
  uint64_t rank_active_cycles, rank_cycles;
};
const struct dram_banked_stats *dram_banked_get_stats(const struct dram_banked *d);
/* The DRAM cycles the level had simulated when it finished (its clock, not
 * one of its numbers: the figures use the run's length). */
uint64_t dram_banked_finished_cycles(const struct dram_banked *d);
/* The DRAM's energy in joules, DRAMsim3's model (its configuration.cc and
 * controller.cc, commit 29817593): each command adds a fixed energy from the
 * datasheet currents, devices = bus_bytes x 8 / device_width, tCK = 1 /
 * clock_mhz:
 *   ACT (with its PRE)  VDD (IDD0 tRC - IDD3N tRAS - IDD2N tRP) tCK devices
 *   RD / WR             VDD (IDD4R / IDD4W - IDD3N) BL/2 tCK devices
 *   REF                 VDD (IDD5AB - IDD3N) tRFC tCK devices
 * and each rank each DRAM cycle VDD IDD3N tCK devices with a bank open
 * (active standby), VDD IDD2N tCK devices with all banks precharged
 * (precharge standby), whether or not it is refreshing. Power-down and self
 * refresh (IDD2P, IDD3P, IDD6) are not modelled: a rank never leaves standby.
 * DRAMsim3 prints these sums in V x mA x DRAM cycles ("pJ" in its output);
 * here they are multiplied by tCK, so joules. */
struct dram_banked_energy {
  double activate_j, read_j, write_j, refresh_j;
  double active_standby_j, precharge_standby_j; /* background, by rank state */
  double total_j;                               /* the six summed, in that order */
};
/* Joules one of each costs, the increments above times tCK: an ACT with its
 * PRE, a RD burst, a WR burst, a REF, a rank-cycle in active standby and one
 * in precharge standby (p's clock_mhz set; the cheaper rungs' estimate,
 * sim/dram_energy_estimate.h, prices its counts with these too). */
struct dram_banked_costs {
  double act, read, write, ref, act_stb, pre_stb;
};
void dram_banked_costs_of(const struct dram_banked_params *p, struct dram_banked_costs *out);
/* Rank `rank` of channel `channel`'s energy over the run, or with channel -1
 * every channel's, with rank -1 every rank's (complete after finish). */
void dram_banked_energy_of(const struct dram_banked *d, int channel, int rank,
                           struct dram_banked_energy *out);

/* The level's numbers, over its struct dram_banked_stats (sim/stats.h). */
struct stats_descs;
extern const struct stats_descs dram_banked_stats_descs;

/* A line address's coordinates. column: the first device column of the
 * line's burst (the co field times burst_length). */
struct dram_banked_coord {
  uint32_t channel, rank, bank_group, bank;
  uint64_t row, column;
};
void dram_banked_decode(const struct dram_banked *d, uint64_t addr, struct dram_banked_coord *out);

#endif
