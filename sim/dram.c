/* Every request passes through here on its way to the level: it gets a
 * sequence number (the tag the level sees), its arrival and the client's tag
 * wait in a ring indexed by that number, and when the level serves it the
 * latency is counted and the client told. The ring's head is the oldest
 * request not yet traced, so trace lines come out in arrival order however
 * the level reorders. */
#include "sim/dram.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sim/dram_energy_estimate.h"
#include "sim/dram_fixed.h"
#include "sim/engine.h"
#include "sim/line.h"
#include "sim/ring.h"
#include "sim/stats.h"

const char *const dram_model_names[DRAM_MODEL_COUNT] = {"fixed", "channel", "banked"};

struct flight {
  uint64_t addr, tag, at, done_at;
  double xfer_start, xfer_end; /* the level's transfer, when has_xfer */
  bool write, done, has_xfer;
};

struct dram {
  struct dram_params p;
  struct engine *eng;
  struct dram_client client;
  const struct dram_level_ops *ops;
  void *level;
  struct dram_clock clock;
  struct dram_energy_estimate_in est; /* filled by dram_finish */
  uint64_t core_khz;
  struct ring fl;    /* requests taken, by sequence; head: the oldest not yet traced */
  uint64_t inflight; /* taken, not yet served */
  /* The request being reported served (inside client.done): its transfer. */
  bool served_has_xfer;
  double served_start, served_end;
  FILE *trace;
  struct dram_stats st;
};

const char *dram_params_problem(const struct dram_params *p) {
  if (p->model >= DRAM_MODEL_COUNT) return "fidelity: expected fixed, channel or banked";
  /* Every level's figures are checked, used or not: a bad value is refused
   * rather than silently ignored (a sweep over dram.tRC on the channel).
   * Each key's range is the key table's; the banked level adds its rules. */
  struct dram_banked_params b = p->banked;
  b.clock_mhz = p->clock_mhz;
  return dram_banked_params_problem(&b);
}

static void trace_flush(struct dram *d) {
  while (ring_len(&d->fl)) {
    struct flight *f = RING_HEAD(&d->fl, struct flight);
    if (!f->done) break;
    if (d->trace)
      fprintf(d->trace, "0x%llx %s %llu %llu %llu\n", (unsigned long long)f->addr,
              f->write ? "WRITE" : "READ",
              (unsigned long long)dram_clock_from_core(d->clock, f->at), (unsigned long long)f->at,
              (unsigned long long)f->done_at);
    ring_pop(&d->fl);
  }
}

static void level_done(void *ctx, uint64_t seq) {
  struct dram *d = ctx;
  CHECK(seq >= d->fl.head && seq < d->fl.tail);
  struct flight *f = RING_AT(&d->fl, struct flight, seq);
  CHECK(!f->done);
  f->done = true;
  f->done_at = engine_now(d->eng);
  hist_add(f->write ? &d->st.write_latency : &d->st.read_latency, f->done_at - f->at);
  d->inflight--;
  uint64_t tag = f->tag;
  d->served_has_xfer = f->has_xfer;
  d->served_start = f->xfer_start;
  d->served_end = f->xfer_end;
  if (seq == d->fl.head) trace_flush(d);
  d->client.done(d->client.ctx, tag);
  d->served_has_xfer = false;
}

static void level_transfer(void *ctx, uint64_t seq, double start, double end) {
  struct dram *d = ctx;
  CHECK(seq >= d->fl.head && seq < d->fl.tail);
  struct flight *f = RING_AT(&d->fl, struct flight, seq);
  f->has_xfer = true;
  f->xfer_start = start;
  f->xfer_end = end;
}

static void level_space(void *ctx) {
  struct dram *d = ctx;
  d->client.space(d->client.ctx);
}

struct dram *dram_create(const struct dram_params *p, uint64_t core_khz, struct engine *e,
                         const struct dram_client *client) {
  CHECK(dram_params_problem(p) == NULL);
  struct dram *d = xcalloc(1, sizeof *d);
  d->p = *p;
  d->eng = e;
  d->client = *client;
  d->clock = dram_clock_make(core_khz, (uint64_t)p->clock_mhz * 1000);
  d->core_khz = core_khz;
  struct dram_client mine = {d, level_done, level_space, level_transfer};
  switch (p->model) {
  case DRAM_MODEL_FIXED:
    d->ops = &dram_fixed_ops;
    d->level = dram_fixed_create(p->latency_cycles, e, &mine);
    break;
  case DRAM_MODEL_CHANNEL: {
    struct dram_channel_params c = {p->latency_cycles, p->bytes_per_cycle, p->queue_depth};
    d->ops = &dram_channel_ops;
    d->level = dram_channel_create(&c, e, &mine);
    break;
  }
  case DRAM_MODEL_BANKED: {
    struct dram_banked_params b = p->banked;
    b.clock_mhz = p->clock_mhz;
    d->ops = &dram_banked_ops;
    d->level = dram_banked_create(&b, core_khz, e, &mine);
    break;
  }
  default: CHECK(false);
  }
  return d;
}

void dram_destroy(struct dram *d) {
  if (!d) return;
  d->ops->destroy(d->level);
  ring_free(&d->fl);
  free(d);
}

bool dram_can_take(struct dram *d, uint64_t addr, bool write) {
  return d->ops->can_take(d->level, addr, write);
}

void dram_take(struct dram *d, uint64_t addr, bool write, uint64_t tag) {
  const uint64_t seq = d->fl.tail;
  struct flight *f = RING_PUSH(&d->fl, struct flight);
  f->addr = addr;
  f->tag = tag;
  f->at = engine_now(d->eng);
  f->write = write;
  f->done = false;
  f->has_xfer = false;
  d->inflight++;
  if (write) {
    d->st.writes++;
    d->st.write_bytes += SIM_LINE_BYTES;
  } else {
    d->st.reads++;
    d->st.read_bytes += SIM_LINE_BYTES;
  }
  d->ops->take(d->level, addr, write, seq);
}

void dram_finish(struct dram *d, uint64_t end) {
  CHECK_EQ(d->inflight, 0);
  CHECK_EQ(ring_len(&d->fl), 0);
  d->ops->finish(d->level, end);
  /* What a cheaper level's energy estimate is made of (dram_level_stats). */
  d->est.p = d->p.banked;
  d->est.p.clock_mhz = d->p.clock_mhz;
  d->est.reads = d->st.reads;
  d->est.writes = d->st.writes;
  d->est.dram_per = (double)d->clock.den;
  d->est.core_per = (double)d->clock.num;
}

const struct dram_stats *dram_get_stats(const struct dram *d) { return &d->st; }

double dram_energy_so_far(const struct dram *d, uint64_t t) {
  if (d->ops->energy_j) return d->ops->energy_j(d->level, t);
  struct dram_banked_params p = d->p.banked;
  p.clock_mhz = d->p.clock_mhz;
  /* est_dram_cycles' arithmetic, so the last figure is the stats' own. */
  const double dram_cycles = (double)t * (double)d->clock.den / (double)d->clock.num;
  struct dram_banked_energy e;
  dram_energy_estimate(&p, d->st.reads, d->st.writes, dram_cycles, &e);
  return e.total_j;
}
uint64_t dram_in_flight(const struct dram *d) { return d->inflight; }

bool dram_served_transfer(const struct dram *d, double *start, double *end) {
  *start = d->served_start;
  *end = d->served_end;
  return d->served_has_xfer;
}

unsigned dram_level_stats(const struct dram *d, struct stats_part *out) {
  unsigned n = 0;
  out[n] = (struct stats_part){.at = DRAM_STATS_AT_LEVEL};
  d->ops->stats(d->level, &out[n]);
  if (out[n].g) n++;
  /* The banked level counts its own energy; the cheaper ones estimate it. */
  if (d->p.model != DRAM_MODEL_BANKED)
    out[n++] = (struct stats_part){DRAM_STATS_AT_ESTIMATE, &dram_energy_estimate_stats_descs,
                                   &d->est, NULL};
  return n;
}

void dram_level_report(const struct dram_level_ops *ops, const void *level, struct stats_table *t,
                       uint64_t cycles) {
  struct stats_part p = {.at = DRAM_STATS_AT_LEVEL};
  ops->stats(level, &p);
  if (!p.g) return;
  const struct stats_env env = {.cycles = cycles, .ctx = p.ctx};
  stats_emit(t, p.g, p.st, &env);
}

void dram_report(const struct dram *d, struct stats_table *t, uint64_t cycles) {
  dram_level_report(d->ops, d->level, t, cycles);
}

void dram_trace_to(struct dram *d, FILE *f) {
  d->trace = f;
  fprintf(f,
          "# rtsim dram trace v1: address op arrival_dram_cycle arrival_cycle done_cycle "
          "(fidelity %s, DRAM clock %u MHz, core clock %llu kHz; one line a 64-byte request, "
          "in arrival order)\n",
          dram_model_names[d->p.model], d->p.clock_mhz, (unsigned long long)d->core_khz);
}

/* ---- the numbers every level shares (docs/stats.md) ---- */

static uint64_t dram_bytes(const void *st, const struct stats_env *env) {
  (void)env;
  const struct dram_stats *s = st;
  return s->read_bytes + s->write_bytes;
}
static double dram_bytes_per_cycle(const void *st, const struct stats_env *env) {
  return stats_ratio((double)dram_bytes(st, env), (double)env->cycles);
}
/* A latency histogram's mean, median, 95th and 99th percentiles and most. */
#define DRAM_LATENCY(rw, ds)                                                                       \
  STATS_HIST_MEAN(struct dram_stats, rw##_latency, "dram_" #rw "_latency_mean", "cycles", ds),     \
      STATS_HIST_Q(struct dram_stats, rw##_latency, 0.50, "dram_" #rw "_latency_p50", "cycles",    \
                   "the same, median"),                                                            \
      STATS_HIST_Q(struct dram_stats, rw##_latency, 0.95, "dram_" #rw "_latency_p95", "cycles",    \
                   "the same, 95th percentile"),                                                   \
      STATS_HIST_Q(struct dram_stats, rw##_latency, 0.99, "dram_" #rw "_latency_p99", "cycles",    \
                   "the same, 99th percentile"),                                                   \
      STATS_FIELD(struct dram_stats, rw##_latency.max, "dram_" #rw "_latency_max", "cycles",       \
                  "the same, most")
static const struct stats_desc dram_desc[] = {
    STATS_FIELD(struct dram_stats, reads, "dram_reads", "count", "64-byte reads served"),
    STATS_FIELD(struct dram_stats, writes, "dram_writes", "count", "64-byte writes served"),
    STATS_FIELD(struct dram_stats, read_bytes, "dram_read_bytes", "bytes", "bytes read"),
    STATS_FIELD(struct dram_stats, write_bytes, "dram_write_bytes", "bytes", "bytes written"),
    STATS_U64(struct dram_stats, read_bytes, dram_bytes, "dram_bytes", "bytes",
              "bytes read and written"),
    STATS_F64(struct dram_stats, write_bytes, dram_bytes_per_cycle, "dram_bytes_per_cycle",
              "bytes/cycle", "bytes read and written per core cycle of the run"),
    STATS_AT(DRAM_STATS_AT_UTILIZATION),
    DRAM_LATENCY(read, "reads, taken to data delivered: mean"),
    DRAM_LATENCY(write, "writes, taken to written: mean"),
    STATS_AT(DRAM_STATS_AT_LEVEL),
    STATS_AT(DRAM_STATS_AT_ESTIMATE),
};
#undef DRAM_LATENCY
const struct stats_descs dram_stats_descs = {
    "dram", dram_desc, STATS_COUNT(dram_desc), sizeof(struct dram_stats), NULL, 0};
