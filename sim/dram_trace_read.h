/* A reader of DRAM request traces, one request a line, in three formats told
 * apart by their number of fields (blanks between them; '#' lines and blank
 * lines skipped; one format a trace):
 *   5  0xADDR READ|WRITE DRAM_CYCLE ARRIVAL_CYCLE DONE_CYCLE  (rtsim run
 *      --dram-trace): the arrival is ARRIVAL_CYCLE, in core cycles
 *   3  0xADDR READ|WRITE DRAM_CYCLE  (DRAMsim3): the arrival is the core cycle
 *      in which that DRAM cycle begins
 *   2  0xADDR R|W  (Ramulator): request i (from 0) arrives in DRAM cycle i
 * The operation is READ, WRITE, R or W in every format; the address is hex
 * after 0x, or decimal, aligned down to its 64-byte line. Arrivals must not
 * decrease. A bad line is a user error at its line and column. */
#ifndef RTSIM_SIM_DRAM_TRACE_READ_H
#define RTSIM_SIM_DRAM_TRACE_READ_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "sim/dram_level.h"

struct err;

#define DRAM_TRACE_LINE_MAX 4096          /* bytes a line, its newline not counted */
#define DRAM_TRACE_CYCLE_MAX (1ull << 40) /* latest arrival, in core cycles */
/* Refreshes a trace may span, over the banked level's channels: the level
 * steps through each one (an idle stretch too), some 40 ns apiece. */
#define DRAM_TRACE_REFRESHES_MAX (1ull << 20)

/* One request: its line's address, the operation, the arrival in core cycles. */
struct dram_trace_request {
  uint64_t addr, arrival;
  bool write;
};

/* A trace being read (caller-provided storage; dram_trace_reader_init). */
struct dram_trace_reader {
  FILE *f;
  const char *path;
  char buf[DRAM_TRACE_LINE_MAX];
  unsigned long line;
  unsigned fields;           /* the trace's fields a line; 0 until its first request */
  unsigned long format_line; /* the line that set it */
  struct dram_clock clock;
  uint64_t dram_cycle_max; /* latest arrival in DRAM cycles (DRAM_TRACE_REFRESHES_MAX) */
  uint64_t refresh_every;  /* the banked level's refresh interval, DRAM cycles (0: none) */
  uint64_t requests;       /* read so far */
  uint64_t last_at;        /* the last request's arrival as written (its field's unit) */
  struct err *e;
};

/* Read f (borrowed, named path in messages; both must outlive r) with clock
 * converting DRAM cycles to core cycles; errors go to *e. */
void dram_trace_reader_init(struct dram_trace_reader *r, FILE *f, const char *path,
                            struct dram_clock clock, struct err *e);
/* A banked level refreshing every refresh_every DRAM cycles on each of its
 * channels steps through every refresh up to the last arrival: bound that
 * to DRAM_TRACE_REFRESHES_MAX refreshes in all. */
void dram_trace_reader_refresh(struct dram_trace_reader *r, uint64_t refresh_every,
                               unsigned channels);

/* The next request: 1 (in *q), 0 at the end of the trace, -1 on a bad line
 * or a read error (*e set, at the line and the offending field's column). */
int dram_trace_next(struct dram_trace_reader *r, struct dram_trace_request *q);

/* The trace's format once a request is read: "rtsim", "dramsim3" or
 * "ramulator"; NULL before. */
const char *dram_trace_format(const struct dram_trace_reader *r);

#endif
