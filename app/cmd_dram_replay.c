/* rtsim dram-replay: the DRAM of a machine config alone (no cores, no L2),
 * driven open loop by a trace of requests, as DRAMsim3's trace CPU drives
 * it: each request is offered at its arrival cycle, in trace order; one the
 * DRAM refuses holds back every later one until the DRAM signals space. The
 * trace is read as the engine reaches it, one bounded line at a time, so its
 * length costs no memory; requests in flight wait in a ring indexed by their
 * place in the trace, which puts the per-request file in trace order. */
#include "app/app.h"

#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "app/opts.h"
#include "sim/derived.h"
#include "sim/dram.h"
#include "sim/dram_trace_read.h"
#include "sim/engine.h"
#include "sim/err.h"
#include "sim/hist.h"
#include "sim/line.h"
#include "sim/machine.h"
#include "sim/machine_cfg.h"
#include "sim/outfile.h"
#include "sim/ring.h"
#include "sim/stats.h"

static const char HELP[] =
    "usage: rtsim dram-replay MACHINE.yaml TRACE [options]\n"
    "\n"
    "Replay a trace of DRAM requests on the DRAM of MACHINE.yaml alone (fidelity:\n"
    "fixed, channel or banked, and its dram keys; no cores, no L2), open loop as\n"
    "DRAMsim3's trace CPU: requests are offered in trace order at their arrival\n"
    "cycle; one the DRAM refuses (its queue is full) waits, with every later one,\n"
    "until the DRAM has space. TRACE is rtsim run's --dram-trace, DRAMsim3's or\n"
    "Ramulator's format (--help-full). Prints one tidy CSV row with its header on\n"
    "stdout: requests, the span, read and write latencies (mean, percentiles),\n"
    "bandwidth, then the level's own numbers; cycles are core cycles unless named\n"
    "_dram_cycles.\n"
    "\n"
    "example (a run's DRAM requests replayed on the channel rung):\n"
    "  rtsim run configs/tiny.yaml scenes/small/room.yaml --width 32 --height 32 \\\n"
    "      -o build/replay-run --dram-trace build/room.trace\n"
    "  rtsim dram-replay configs/tiny.yaml build/room.trace --set fidelity=channel\n"
    "\n"
    "options:\n"
    "  --set KEY=VALUE       override a machine config key (repeatable), e.g.\n"
    "                        --set fidelity=banked --set clock_ghz=1.2\n"
    "  --per-request FILE    also write 'index arrival_cycle taken_cycle done_cycle'\n"
    "                        (core cycles) for every request, in trace order\n"
    "  --help-stats          list the replay's own numbers: name, unit, what it is\n"
    "                        (the level's are rtsim run --help-stats' dram rows)\n"
    "  -h, --help            this text; --help-full: also the trace formats\n"
    "\f"
    "\n"
    "TRACE: one request a line, fields separated by blanks; '#' lines and blank\n"
    "lines are skipped; every request line has the same number of fields:\n"
    "  5  0xADDR READ|WRITE DRAM_CYCLE ARRIVAL_CYCLE DONE_CYCLE   (rtsim run\n"
    "     --dram-trace): the arrival is ARRIVAL_CYCLE, in core cycles; the DRAM\n"
    "     cycle and the done cycle are not read\n"
    "  3  0xADDR READ|WRITE DRAM_CYCLE   (DRAMsim3): the arrival is the core cycle\n"
    "     in which that DRAM cycle begins (dram.clock_mhz against clock_ghz)\n"
    "  2  0xADDR R|W   (Ramulator): request i (from 0) arrives in DRAM cycle i, as\n"
    "     Ramulator's trace mode offers one a memory clock\n"
    "The operation is READ, WRITE, R or W (case matters) in every format. The\n"
    "address is hexadecimal after 0x, or decimal, and is aligned down to its\n"
    "64-byte line (every request is one line). Arrivals must not decrease. A line\n"
    "is at most 4096 bytes. On a banked DRAM with refresh, a trace may span at\n"
    "most 2^20 refreshes (channels x the last arrival / (tREFI / ranks)): the\n"
    "replay steps through each.\n"
    "\n"
    "The CSV: requests, reads, writes, the span from the first arrival to the last\n"
    "request served, read latencies from arrival to done (so waiting for a refusing\n"
    "DRAM counts; mean, p50, p95, p99, max) and from taken to done (mean, max), the\n"
    "write latency and the wait to be taken (means), bytes a cycle and GB/s, the\n"
    "read latencies again in DRAM clock cycles, then the level's own numbers (row\n"
    "hits, queues, ...; the banked level's energy by part, dram_energy_*_j, and\n"
    "dram_power_w). Latencies and spans are in core cycles unless named\n"
    "_dram_cycles.\n";

/* A request taken by the DRAM, at its index in the trace. */
struct slot {
  uint64_t arrival, taken, done;
  bool write, served;
};

struct replay {
  struct engine *eng;
  struct dram *dram;
  struct dram_trace_reader rd;
  struct dram_trace_request next; /* the next request to offer, when have_next */
  bool have_next, blocked, failed;
  uint64_t feed_at; /* the pending feed event's cycle, or UINT64_MAX */
  struct ring fl;   /* struct slot: requests taken, by index; head: the oldest not retired */
  FILE *per;        /* the per-request file, or NULL */
  struct hist read_latency; /* arrival to done, core cycles */
  uint64_t reads, writes, write_latency_sum, wait_sum;
  uint64_t first_arrival, last_done;
};

static void feed(struct replay *p);

static void ev_feed(void *ctx, uint64_t at) {
  struct replay *p = ctx;
  if (at == p->feed_at) p->feed_at = UINT64_MAX;
  feed(p);
}

/* Hand the next request to the DRAM now and read the one after it. */
static void take(struct replay *p) {
  const uint64_t now = engine_now(p->eng), idx = p->fl.tail;
  struct slot *s = RING_PUSH(&p->fl, struct slot);
  *s = (struct slot){p->next.arrival, now, 0, p->next.write, false};
  p->wait_sum += now - p->next.arrival;
  dram_take(p->dram, p->next.addr, p->next.write, idx);
  int rc = dram_trace_next(&p->rd, &p->next);
  p->have_next = rc > 0;
  /* A bad line stops the feed; what is in flight drains, then main reports. */
  if (rc < 0) p->failed = true;
}

/* Offer every request that has arrived, in order, until the DRAM refuses
 * one; then wait for its space callback, or for the next arrival. */
static void feed(struct replay *p) {
  const uint64_t now = engine_now(p->eng);
  while (p->have_next && p->next.arrival <= now) {
    if (!dram_can_take(p->dram, p->next.addr, p->next.write)) {
      p->blocked = true;
      return;
    }
    take(p);
  }
  p->blocked = false;
  if (p->have_next && p->feed_at != p->next.arrival) {
    p->feed_at = p->next.arrival;
    engine_at(p->eng, p->next.arrival, ev_feed, p, p->next.arrival);
  }
}

static void on_space(void *ctx) {
  struct replay *p = ctx;
  if (p->blocked) feed(p);
}

static void on_done(void *ctx, uint64_t idx) {
  struct replay *p = ctx;
  CHECK(idx >= p->fl.head && idx < p->fl.tail);
  struct slot *s = RING_AT(&p->fl, struct slot, idx);
  CHECK(!s->served);
  const uint64_t now = engine_now(p->eng);
  s->served = true;
  s->done = now;
  if (s->write) {
    p->writes++;
    p->write_latency_sum += now - s->arrival;
  } else {
    p->reads++;
    hist_add(&p->read_latency, now - s->arrival);
  }
  if (now > p->last_done) p->last_done = now;
  /* Retire, in trace order, every request served from the head on. */
  while (ring_len(&p->fl)) {
    struct slot *h = RING_HEAD(&p->fl, struct slot);
    if (!h->served) break;
    if (p->per)
      fprintf(p->per, "%llu %llu %llu %llu\n", (unsigned long long)p->fl.head,
              (unsigned long long)h->arrival, (unsigned long long)h->taken,
              (unsigned long long)h->done);
    ring_pop(&p->fl);
  }
}

/* ---- the replay's numbers, declared once (st: the struct replay; env->ctx:
 * the machine params; env->cycles: first arrival to last done) ---- */

static const struct replay *rp(const void *st) { return st; }
static const struct machine_params *rmp(const struct stats_env *env) { return env->ctx; }
static uint64_t r_requests(const void *st, const struct stats_env *env) {
  (void)env;
  return rp(st)->reads + rp(st)->writes;
}
/* DRAM clock cycles per core cycle. */
static double r_to_dram(const struct stats_env *env) {
  return (double)rmp(env)->dram_clock_mhz * 1000.0 / (double)machine_core_khz(rmp(env));
}
static double r_bpc(const void *st, const struct stats_env *env) {
  return stats_ratio((double)SIM_LINE_BYTES * (double)r_requests(st, env), (double)env->cycles);
}
static double r_clock_ghz(const void *st, const struct stats_env *env) {
  (void)st;
  return rmp(env)->clock_ghz;
}
static uint64_t r_clock_mhz(const void *st, const struct stats_env *env) {
  (void)st;
  return rmp(env)->dram_clock_mhz;
}
static uint64_t r_cycles(const void *st, const struct stats_env *env) {
  (void)st;
  return env->cycles;
}
static double r_taken_mean(const void *st, const struct stats_env *env) {
  (void)env;
  return hist_mean(&dram_get_stats(rp(st)->dram)->read_latency);
}
static uint64_t r_taken_max(const void *st, const struct stats_env *env) {
  (void)env;
  return dram_get_stats(rp(st)->dram)->read_latency.max;
}
static double r_write_mean(const void *st, const struct stats_env *env) {
  (void)env;
  return stats_ratio((double)rp(st)->write_latency_sum, (double)rp(st)->writes);
}
static double r_wait_mean(const void *st, const struct stats_env *env) {
  return stats_ratio((double)rp(st)->wait_sum, (double)r_requests(st, env));
}
static double r_gbps(const void *st, const struct stats_env *env) {
  return r_bpc(st, env) * rmp(env)->clock_ghz;
}
static double r_mean_dram(const void *st, const struct stats_env *env) {
  return hist_mean(&rp(st)->read_latency) * r_to_dram(env);
}
#define R_QUANTILE_DRAM(pc)                                                                        \
  static double r_p##pc##_dram(const void *st, const struct stats_env *env) {                      \
    return (double)hist_quantile(&rp(st)->read_latency, pc / 100.0) * r_to_dram(env);              \
  }
R_QUANTILE_DRAM(50)
R_QUANTILE_DRAM(95)
R_QUANTILE_DRAM(99)
#undef R_QUANTILE_DRAM

static const struct stats_desc replay_desc[] = {
    STATS_FN_F64(r_clock_ghz, "clock_ghz", "GHz", "the core clock (the config's)"),
    STATS_FN_U64(r_clock_mhz, "dram.clock_mhz", "MHz", "the DRAM's clock (the config's)"),
    STATS_FN_U64(r_requests, "requests", "count", "requests replayed"),
    STATS_FIELD(struct replay, reads, "reads", "count", "reads served"),
    STATS_FIELD(struct replay, writes, "writes", "count", "writes served"),
    STATS_FIELD(struct replay, first_arrival, "first_arrival_cycle", "cycles",
                "the first request's arrival"),
    STATS_FIELD(struct replay, last_done, "last_done_cycle", "cycles", "the last request served"),
    STATS_FN_U64(r_cycles, "cycles", "cycles", "from the first arrival to the last served"),
    STATS_HIST_MEAN(struct replay, read_latency, "read_latency_mean", "cycles",
                    "a read's latency from its arrival, mean"),
    STATS_HIST_Q(struct replay, read_latency, 0.50, "read_latency_p50", "cycles", "its median"),
    STATS_HIST_Q(struct replay, read_latency, 0.95, "read_latency_p95", "cycles",
                 "its 95th percentile"),
    STATS_HIST_Q(struct replay, read_latency, 0.99, "read_latency_p99", "cycles",
                 "its 99th percentile"),
    STATS_FIELD(struct replay, read_latency.max, "read_latency_max", "cycles", "its largest"),
    STATS_FN_F64(r_taken_mean, "read_latency_taken_mean", "cycles",
                 "a read's latency from the DRAM taking it, mean"),
    STATS_FN_U64(r_taken_max, "read_latency_taken_max", "cycles", "its largest"),
    STATS_FN_F64(r_write_mean, "write_latency_mean", "cycles",
                 "a write's latency from its arrival, mean"),
    STATS_FN_F64(r_wait_mean, "refused_wait_mean", "cycles",
                 "cycles a request waited past its arrival for the DRAM to take it, mean"),
    STATS_FN_F64(r_bpc, "bytes_per_cycle", "bytes/cycle", "64-byte lines moved / cycles"),
    STATS_FN_F64(r_gbps, "gb_per_s", "GB/s", "bytes_per_cycle at clock_ghz"),
    STATS_FN_F64(r_mean_dram, "read_latency_mean_dram_cycles", "DRAM cycles",
                 "read_latency_mean in DRAM clock cycles"),
    STATS_FN_F64(r_p50_dram, "read_latency_p50_dram_cycles", "DRAM cycles",
                 "read_latency_p50 likewise"),
    STATS_FN_F64(r_p95_dram, "read_latency_p95_dram_cycles", "DRAM cycles",
                 "read_latency_p95 likewise"),
    STATS_FN_F64(r_p99_dram, "read_latency_p99_dram_cycles", "DRAM cycles",
                 "read_latency_p99 likewise"),
};
static const struct stats_descs replay_stats_descs = {
    "dram-replay", replay_desc, STATS_COUNT(replay_desc), 0, NULL, 0};

/* The CSV row: what was replayed, the replay's own numbers, then the level's. */
static void report(const struct replay *p, const char *path, const char *format,
                   const struct machine_cfg *mc, struct stats_table *t) {
  const struct machine_params *mp = &mc->p;
  stats_str(t, "trace", path);
  stats_str(t, "trace_format", format);
  stats_str(t, "fidelity", dram_model_names[machine_fidelity_dram(mp->fidelity)]);
  const uint64_t cycles = p->last_done - p->first_arrival;
  const struct stats_env env = {.cycles = cycles, .ctx = mp};
  stats_emit(t, &replay_stats_descs, p, &env);
  dram_report(p->dram, t, cycles);
}

int cmd_dram_replay(int argc, char **argv) {
  const char *per_path = NULL;
  struct outfile per = {0};
  struct app_sets sets = {xcalloc((size_t)argc + 1, sizeof *sets.v),
                          0}; /* at most one an argument */
  struct replay *p = NULL;
  FILE *in = NULL;
  bool help_stats = false;
  const struct opts_spec spec[] = {OPTS_PARSE("set", 0, &sets, app_sets_add, "KEY=VALUE"),
                                   OPTS_STR("per-request", 0, &per_path),
                                   OPTS_FLAG("help-stats", 0, &help_stats), OPTS_END};
  struct opts_args args;
  int rc = opts_parse("dram-replay", HELP, spec, argc, argv, &args);
  if (rc != OPTS_GO) goto done;
  if (help_stats) {
    stats_write_help(&replay_stats_descs, stdout);
    rc = fflush(stdout) == 0 ? 0 : 1;
    goto done;
  }
  rc = APP_EXIT_USAGE;
  if (args.n != 2) {
    app_usage_error("dram-replay", "expected MACHINE.yaml TRACE, got %d file%s", args.n,
                    args.n == 1 ? "" : "s");
    goto done;
  }
  const char *machine_path = args.v[0], *trace_path = args.v[1];
  struct machine_cfg mc;
  struct err e;
  memset(&e, 0, sizeof e);
  if (!app_machine_load(&mc, machine_path, &sets, &e)) {
    rc = app_report(&e);
    goto done;
  }
  if (mc.p.fidelity == MACHINE_FIDELITY_ANALYTIC) {
    const struct machine_cfg_origin *o = &mc.at[machine_cfg_find("fidelity")];
    err_set(&e, o->file, o->line, o->col,
            "fidelity: analytic has no DRAM to replay a trace on (got analytic, expected "
            "fixed, channel or banked)");
    rc = app_report(&e);
    goto done;
  }
  const struct dram_params dp = machine_dram_params(&mc.p);
  const uint64_t core_khz = machine_core_khz(&mc.p);

  const char *why;
  in = err_fopen_regular(trace_path, &why);
  if (!in) {
    err_set(&e, trace_path, 0, 0, "cannot open: %s", why);
    rc = app_report(&e);
    goto done;
  }
  p = xcalloc(1, sizeof *p);
  dram_trace_reader_init(&p->rd, in, trace_path,
                         dram_clock_make(core_khz, (uint64_t)dp.clock_mhz * 1000), &e);
  if (dp.model == DRAM_MODEL_BANKED && dp.banked.tREFI > 0)
    dram_trace_reader_refresh(&p->rd, dp.banked.tREFI / dp.banked.ranks, dp.banked.channels);
  int got = dram_trace_next(&p->rd, &p->next);
  if (got == 0)
    err_set(&e, trace_path, 0, 0,
            "no request in the trace (expected at least one line '0xADDR READ|WRITE ...')");
  if (got <= 0) {
    rc = app_report(&e);
    goto done;
  }
  if (per_path) {
    if (!outfile_open(&per, per_path, "the per-request file", &e)) {
      rc = app_report(&e);
      goto done;
    }
    p->per = per.f;
    fputs("# index arrival_cycle taken_cycle done_cycle (core cycles; trace order)\n", p->per);
  }

  p->have_next = true;
  p->first_arrival = p->next.arrival;
  p->eng = engine_create();
  const struct dram_client client = {p, on_done, on_space, NULL};
  p->dram = dram_create(&dp, core_khz, p->eng, &client);
  p->feed_at = p->next.arrival;
  engine_at(p->eng, p->next.arrival, ev_feed, p, p->next.arrival);
  engine_run(p->eng);
  /* Every request offered was taken and served, unless a bad line stopped the feed. */
  CHECK(p->failed || !p->have_next);
  CHECK_EQ(ring_len(&p->fl), 0);
  dram_finish(p->dram, engine_now(p->eng));
  if (p->failed) {
    rc = app_report(&e);
    goto done;
  }
  if (per_path && !outfile_commit(&per, &e)) {
    rc = app_report(&e);
    goto done;
  }
  struct stats_table t = {0};
  report(p, trace_path, dram_trace_format(&p->rd), &mc, &t);
  stats_write_csv_header(&t, stdout);
  stats_write_csv_row(&t, stdout);
  stats_fini(&t);
  rc = 0;
done:
  outfile_abort(&per);
  if (p) {
    dram_destroy(p->dram);
    engine_destroy(p->eng);
    ring_free(&p->fl);
    free(p);
  }
  if (in) fclose(in);
  free(sets.v);
  return rc;
}
