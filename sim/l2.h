/* The shared L2: line-interleaved banks (one access a bank a cycle), LRU sets
 * or fully associative, 64-byte lines, write-back and write-allocate (a store
 * covering a whole line allocates it without a fetch), MSHRs that merge
 * misses to a pending line, a bounded write buffer for dirty victims, and the
 * DRAM below it (sim/dram.h), which it fills from and writes back to.
 *
 * The rules (docs/machine.md):
 * - An access is taken by its bank at max(arrival, bank free) and answered
 *   l2.latency cycles later on a hit; a load merging into a pending line is
 *   answered at the fill, never before that same l2.latency.
 * - A miss allocates its line at once (pending until the fill) and an MSHR;
 *   it is offered to the DRAM l2.latency cycles after its bank took it, and
 *   waits at the L2, in order, while the DRAM refuses it (back-pressure).
 * - A dirty victim enters the write buffer (l2.write_buffer entries); the
 *   buffer drains to the DRAM, oldest first. A miss to a line still in the
 *   buffer takes it back when it would leave for the DRAM (no DRAM access). Reads go to the DRAM
 * first; a write goes when no read is waiting, or first when the buffer is full.
 * - The input stalls in order (every later access queues behind) while the
 *   oldest access cannot proceed: MSHRs full, every way of its set pending,
 *   a dirty victim with the write buffer full, or a miss held at the L2
 *   because the DRAM refused it. */
#ifndef RTSIM_SIM_L2_H
#define RTSIM_SIM_L2_H

#include <stdbool.h>
#include <stdint.h>

#include "sim/engine.h"
#include "sim/mem.h"
#include "sim/qmeter.h"

struct dram;
struct timeline;

struct l2_params {
  uint64_t size_bytes;
  uint32_t ways; /* 0: fully associative */
  uint32_t latency_cycles, banks, mshrs, write_buffer;
};

/* Timeline columns the L2 adds to (per window). */
struct l2_timeline_cols {
  unsigned accesses, misses, read_bytes, read_class0, write_bytes;
};

enum l2_op { L2_LOAD = 0, L2_STORE = 1, L2_STORE_LINE = 2 };

/* Why the input stalled (the oldest access's reason, cycle by cycle). */
enum l2_stall { L2_STALL_MSHR, L2_STALL_SET, L2_STALL_WRITE_BUFFER, L2_STALL_DRAM, L2_STALL_COUNT };

struct l2_stats {
  uint64_t accesses, hits, misses, mshr_merges, whole_line_allocs;
  uint64_t merges_held;       /* merged loads answered after the fill, to honour l2.latency */
  uint64_t write_buffer_hits; /* misses served from the write buffer (no DRAM read or write) */
  uint64_t bank_wait_cycles;  /* accesses waiting for their bank */
  uint64_t stalls;            /* accesses that queued behind a stall */
  uint64_t stall_cycles[L2_STALL_COUNT];
  uint64_t accesses_by_class[MEM_CLASS_MAX];
  uint64_t fetch_bytes, writeback_bytes;
  uint64_t fetch_bytes_by_class[MEM_CLASS_MAX];
  struct qmeter stall_queue;  /* accesses stalled at the input */
  struct qmeter miss_queue;   /* misses waiting for the DRAM to take them: back-pressure */
  struct qmeter write_buffer; /* write-backs from eviction to the DRAM taking them */
};

/* What the L2 tells its client: ready(waiter, line) is scheduled (or called)
 * at the cycle a load's line is answered; waiter is what l2_access was given.
 * cost (NULL: not wanted) hears every DRAM transfer with the access it is
 * charged to: a line read for a miss when the DRAM delivers it (write false:
 * waiter and tag of the access that missed, its class), a write-back when the
 * DRAM takes it (write true: waiter NULL, the tag of the access whose miss
 * evicted the dirty line, class 0). Misses served from the write buffer move
 * nothing and are not told. */
struct l2_client {
  engine_fn ready;
  void *cost_ctx;
  void (*cost)(void *cost_ctx, void *waiter, uint32_t tag, unsigned cls, bool write);
  /* stall (NULL: not wanted) hears the input's stalls as they change:
   * (waiter, +1) when a load's access queues behind a stall and (waiter, -1)
   * when it leaves that queue; (NULL, reason) when the oldest stalled
   * access's reason becomes `reason` (enum l2_stall; -1: no stall). */
  void *stall_ctx;
  void (*stall)(void *stall_ctx, void *waiter, int what);
};

/* NULL if usable, else what is wrong (naming the l2.* key): the geometry.
 * banks, mshrs and write_buffer (at least 1) are held to their ranges by the
 * key table (machine_params_problem), the one way to an L2. */
const char *l2_params_problem(const struct l2_params *p);

struct l2;

/* p must pass l2_params_problem (CHECKed). tl: the timeline it adds to (not
 * owned). Attach the DRAM before the first access. Caller destroys. */
struct l2 *l2_create(const struct l2_params *p, struct engine *e, struct timeline *tl,
                     const struct l2_timeline_cols *cols, const struct l2_client *client);
void l2_destroy(struct l2 *l2); /* NULL ok; the DRAM is not the L2's */

/* The client the DRAM must be created with, and the DRAM to use (not owned). */
struct dram_client l2_dram_client(struct l2 *l2);
void l2_attach(struct l2 *l2, struct dram *d);
/* Replace the client (struct l2_client) before the first access. */
void l2_set_client(struct l2 *l2, const struct l2_client *client);

/* An access of one line at engine_now. waiter: a load's, handed back to
 * client->ready; NULL for a store (posted: nobody waits). tag: the client's
 * word for whom the access is for, handed back to client->cost. */
void l2_access(struct l2 *l2, uint64_t line, enum l2_op op, unsigned cls, void *waiter,
               uint32_t tag);

/* Ask the host to fetch the tags an access of line will read (a load that
 * missed the L1 reaches the L2 an event later). Changes nothing. */
void l2_prefetch(const struct l2 *l2, uint64_t line);

/* Warm the L2 with one access of a line, no time (sampling's fast-forward):
 * a line it holds (or is fetching) becomes the most recently used, dirty on a
 * write; else it is installed in its set's victim slot, valid and not pending
 * (dirty on a write). A dirty victim is dropped, not written back, and nothing
 * is counted: warming only keeps the tags as the skipped work would have left
 * them. With every way of the set pending it does nothing. */
void l2_warm(struct l2 *l2, uint64_t line, bool write);

/* Nothing in flight, stalled or buffered (CHECKed at the end of a run). */
bool l2_quiet(const struct l2 *l2);
/* Close the meters at cycle end. */
void l2_finish(struct l2 *l2, uint64_t end);

const struct l2_stats *l2_get_stats(const struct l2 *l2);

/* What the L2 holds at this cycle (for a trace's counters; changes nothing). */
struct l2_occupancy {
  uint32_t mshrs;        /* MSHRs in use: misses whose line is not yet back */
  uint32_t stalled;      /* accesses queued at the input behind a stall */
  uint32_t misses_held;  /* misses the DRAM has refused so far: back-pressure */
  uint32_t write_buffer; /* places of the write buffer taken */
};
void l2_occupancy(const struct l2 *l2, struct l2_occupancy *out);
/* The L2's numbers, over a struct l2_stats (sim/stats.h; cycles: the run's). */
struct stats_descs;
extern const struct stats_descs l2_stats_descs;

#endif
