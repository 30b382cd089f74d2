/* The trace layer's record (machine_trace_enable), private to
 * sim/machine_trace.c, which fills it, and sim/machine_trace_json.c, which
 * writes it. Holds: each traced thread's slices are kept in time order, tile
 * [window start, its `from`) and never overlap; at most max_events events. */
#ifndef RTSIM_SIM_MACHINE_TRACE_H
#define RTSIM_SIM_MACHINE_TRACE_H

#include <stdbool.h>
#include <stdint.h>

#include "sim/machine.h"

/* The counters, each a track of the "memory" process. */
enum {
  MTRACE_DRAM_READ,   /* bytes served a cycle since the previous sample */
  MTRACE_DRAM_WRITE,  /* likewise */
  MTRACE_DRAM_FLIGHT, /* requests the DRAM took and has not served */
  MTRACE_L2_MSHRS,    /* MSHRs in use */
  MTRACE_L2_STALLED,  /* accesses queued at the L2's input */
  MTRACE_L2_HELD,     /* misses the DRAM refused so far */
  MTRACE_L2_WBUF,     /* write-buffer places taken */
  MTRACE_POWER,       /* watts, chip and DRAM, since the previous sample */
  MTRACE_COUNTERS
};
/* A counter's name and its one argument's: Perfetto names the track by both
 * ("L2 MSHRs in use"); chrome://tracing shows the name. */
extern const char *const mtrace_counter_names[MTRACE_COUNTERS][2];

/* One event: a slice of thread `track` (kind < MACHINE_TRACE_KINDS) lasting
 * dur cycles, or a sample of counter `track` (kind MTRACE_COUNTER). */
#define MTRACE_COUNTER 255
struct mtrace_ev {
  uint64_t ts;
  union {
    uint64_t dur;
    double value;
  } u;
  uint32_t track;
  uint8_t kind;
};

/* A traced thread: its current slice, from cycle `from` (a switch ends at
 * sw_end, then the thread is ready), and its rays with a load's line queued
 * at the L2's input. */
struct mtrack {
  uint64_t from, sw_end;
  uint32_t stalled_rays;
  uint8_t kind;
};

struct mtrace {
  struct machine_trace_params p;
  uint32_t nth, nctx; /* traced threads and ray contexts: a prefix of each */
  struct mtrack *th;  /* nth */
  uint32_t *stalled;  /* nctx: a ray's load lines queued at the L2's input */
  int l2_reason;      /* the L2's stall reason now (enum l2_stall), -1: none */
  uint64_t end;       /* the window's end in effect: to_cycle, the cap's cut or the run's end */
  bool capped;        /* max_events cut the window at `end` */
  struct mtrace_ev *ev;
  uint64_t n, cap, limit; /* events kept, room, the count that cuts (a reserve after) */
  /* Counters: the next sample's cycle; the previous sample's cycle, the DRAM
   * bytes served and the run's energy (J) by then, and each counter's last
   * value written. */
  uint64_t next_sample, last_t, last_read, last_write;
  double last_energy_j;
  bool sampled;
  double last_value[MTRACE_COUNTERS];
};

#endif
