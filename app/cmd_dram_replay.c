/* rtsim dram-replay: the DRAM of a machine config alone (no cores, no L2),
 * driven open loop by a trace of requests, as DRAMsim3's trace CPU drives
 * it: each request is offered at its arrival cycle, in trace order; one the
 * DRAM refuses holds back every later one until the DRAM signals space. The
 * trace is read as the engine reaches it, one bounded line at a time, so its
 * length costs no memory; requests in flight wait in a ring indexed by their
 * place in the trace, which puts the per-request file in trace order. */
#include "app/app.h"

#include <errno.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "app/opts.h"
#include "sim/dram.h"
#include "sim/engine.h"
#include "sim/err.h"
#include "sim/hist.h"
#include "sim/machine.h"
#include "sim/machine_cfg.h"
#include "sim/outfile.h"
#include "sim/stats.h"

static const char HELP[] =
    "usage: rtsim dram-replay MACHINE.yaml TRACE [options]\n"
    "\n"
    "Replay a trace of DRAM requests on the DRAM of MACHINE.yaml alone (fidelity:\n"
    "fixed, channel or banked, and its dram keys; no cores, no L2), open loop as\n"
    "DRAMsim3's trace CPU: requests are offered in trace order at their arrival\n"
    "cycle; one the DRAM refuses (its queue is full) waits, with every later one,\n"
    "until the DRAM has space.\n"
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
    "Prints one tidy CSV row with its header on stdout: requests, reads, writes,\n"
    "the span from the first arrival to the last request served, read latencies\n"
    "from arrival to done (so waiting for a refusing DRAM counts; mean, p50, p95,\n"
    "p99, max) and from taken to done (mean, max), the write latency and the wait\n"
    "to be taken (means), bytes a cycle and GB/s, the read latencies again in\n"
    "DRAM clock cycles, then the level's own numbers (row hits, queues, ...).\n"
    "Latencies and spans are in core cycles unless named _dram_cycles.\n"
    "\n"
    "options:\n"
    "  --set KEY=VALUE       override a machine config key (repeatable), e.g.\n"
    "                        --set fidelity=banked --set clock_ghz=1.2\n"
    "  --per-request FILE    also write 'index arrival_cycle taken_cycle done_cycle'\n"
    "                        (core cycles) for every request, in trace order\n"
    "  --help-stats          list the replay's own numbers: name, unit, what it is\n"
    "                        (the level's are rtsim run --help-stats' dram rows)\n"
    "  -h, --help            this text\n";

#define REPLAY_LINE_MAX 4096          /* bytes a line, its newline not counted */
#define REPLAY_CYCLE_MAX (1ull << 40) /* latest arrival, in core cycles */
/* Refreshes a trace may span, over the banked level's channels: the level
 * steps through each one (an idle stretch too), some 40 ns apiece. */
#define REPLAY_REFRESHES_MAX (1ull << 20)
#define REPLAY_LINE_BYTES 64u
#define REPLAY_FIELDS_MAX 6 /* fields kept of a line (one past the most allowed) */
#define REPLAY_ECHO_MAX 40  /* bytes of a bad field quoted in a message */

/* ---- the trace reader ---- */

struct field {
  const char *s;
  size_t len;
  int col; /* 1-based */
};

struct request {
  uint64_t addr, arrival;
  bool write;
};

struct reader {
  FILE *f;
  const char *path;
  char buf[REPLAY_LINE_MAX];
  unsigned long line;
  unsigned fields;           /* the trace's fields a line; 0 until its first request */
  unsigned long format_line; /* the line that set it */
  struct dram_clock clock;
  uint64_t dram_cycle_max; /* latest arrival in DRAM cycles (REPLAY_REFRESHES_MAX) */
  uint64_t refresh_every;  /* the banked level's refresh interval, DRAM cycles (0: none) */
  uint64_t requests;       /* read so far */
  uint64_t last_at;        /* the last request's arrival as written (its field's unit) */
  struct err *e;
};

static int line_no(const struct reader *r) {
  return r->line > 2147483647ul ? 2147483647 : (int)r->line;
}

/* Quote at most REPLAY_ECHO_MAX bytes of a field for a message. */
static const char *echo(const struct field *f, char *buf, size_t cap) {
  size_t n = f->len < REPLAY_ECHO_MAX ? f->len : REPLAY_ECHO_MAX;
  snprintf(buf, cap, "'%.*s%s'", (int)n, f->s, n < f->len ? "..." : "");
  return buf;
}

static bool is_blank(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

/* A whole decimal number below 2^64. */
static bool parse_dec(const struct field *f, uint64_t *out) {
  uint64_t v = 0;
  if (f->len == 0) return false;
  for (size_t i = 0; i < f->len; i++) {
    char c = f->s[i];
    if (c < '0' || c > '9') return false;
    uint64_t d = (uint64_t)(c - '0');
    if (v > (UINT64_MAX - d) / 10) return false;
    v = v * 10 + d;
  }
  *out = v;
  return true;
}

/* 0x (or 0X) and hexadecimal digits, or decimal; below 2^64 either way. */
static bool parse_addr(const struct field *f, uint64_t *out) {
  if (f->len > 2 && f->s[0] == '0' && (f->s[1] == 'x' || f->s[1] == 'X')) {
    uint64_t v = 0;
    for (size_t i = 2; i < f->len; i++) {
      char c = f->s[i];
      unsigned d;
      if (c >= '0' && c <= '9') d = (unsigned)(c - '0');
      else if (c >= 'a' && c <= 'f') d = (unsigned)(c - 'a' + 10);
      else if (c >= 'A' && c <= 'F') d = (unsigned)(c - 'A' + 10);
      else return false;
      if (v >> 60) return false;
      v = v << 4 | d;
    }
    *out = v;
    return true;
  }
  return parse_dec(f, out);
}

static bool parse_op(const struct field *f, bool *write) {
  static const struct {
    const char *name;
    bool write;
  } ops[] = {{"READ", false}, {"WRITE", true}, {"R", false}, {"W", true}};
  for (size_t i = 0; i < sizeof ops / sizeof ops[0]; i++)
    if (f->len == strlen(ops[i].name) && !memcmp(f->s, ops[i].name, f->len)) {
      *write = ops[i].write;
      return true;
    }
  return false;
}

/* Read one line into r->buf: 1 and its length, 0 at the end of the file, -1
 * on a line too long or a read error (e set). */
static int read_line(struct reader *r, size_t *len) {
  size_t n = 0;
  int c;
  while ((c = getc(r->f)) != EOF && c != '\n') {
    if (n == 0) r->line++;
    if (n == REPLAY_LINE_MAX)
      return err_set(r->e, r->path, line_no(r), REPLAY_LINE_MAX + 1,
                     "line too long (got more than %d bytes, expected at most %d)", REPLAY_LINE_MAX,
                     REPLAY_LINE_MAX),
             -1;
    r->buf[n++] = (char)c;
  }
  if (c == EOF && ferror(r->f))
    return err_set(r->e, r->path, 0, 0, "cannot read: %s", strerror(errno)), -1;
  if (c == EOF && n == 0) return 0;
  if (n == 0) r->line++; /* an empty line */
  *len = n;
  return 1;
}

/* The next request: 1 (in *q), 0 at the end of the trace, -1 on a bad line
 * (e set at its line and the offending field's column). */
static int reader_next(struct reader *r, struct request *q) {
  char got[REPLAY_ECHO_MAX + 8];
  for (;;) {
    size_t len;
    int rc = read_line(r, &len);
    if (rc <= 0) return rc;
    struct field f[REPLAY_FIELDS_MAX];
    unsigned n = 0;
    size_t i = 0;
    while (i < len) {
      while (i < len && is_blank(r->buf[i])) i++;
      if (i == len) break;
      size_t start = i;
      while (i < len && !is_blank(r->buf[i])) i++;
      if (n < REPLAY_FIELDS_MAX) f[n] = (struct field){r->buf + start, i - start, (int)start + 1};
      n++;
    }
    if (n == 0 || f[0].s[0] == '#') continue;
    const int line = line_no(r);
    /* Where a missing field would begin: one past the line's end. */
    const int end_col = (int)len + 1;
    if (r->fields && n != r->fields)
      return err_set(r->e, r->path, line, n < r->fields ? end_col : f[r->fields].col,
                     "wrong number of fields (got %u, expected %u as on line %lu: one format a "
                     "trace)",
                     n, r->fields, r->format_line),
             -1;
    if (n < 2)
      return err_set(r->e, r->path, line, end_col,
                     "too few fields (got %u, expected 2 (0xADDR R|W), 3 (0xADDR READ|WRITE "
                     "DRAM_CYCLE) or 5 (rtsim's trace))",
                     n),
             -1;
    if (n == 4 || n > 5)
      return err_set(r->e, r->path, line, f[n == 4 ? 3 : 5].col,
                     "wrong number of fields (got %u, expected 2 (0xADDR R|W), 3 (0xADDR "
                     "READ|WRITE DRAM_CYCLE) or 5 (rtsim's trace))",
                     n),
             -1;
    if (!r->fields) {
      r->fields = n;
      r->format_line = r->line;
    }
    uint64_t addr;
    if (!parse_addr(&f[0], &addr))
      return err_set(r->e, r->path, line, f[0].col,
                     "address: not a number (got %s, expected 0x and hexadecimal digits, or "
                     "decimal digits, below 2^64)",
                     echo(&f[0], got, sizeof got)),
             -1;
    if (!parse_op(&f[1], &q->write))
      return err_set(r->e, r->path, line, f[1].col,
                     "operation: unknown (got %s, expected READ, WRITE, R or W)",
                     echo(&f[1], got, sizeof got)),
             -1;
    q->addr = addr & ~(uint64_t)(REPLAY_LINE_BYTES - 1);
    /* The arrival as written: Ramulator's is the request's index, in DRAM cycles. */
    uint64_t v = r->requests;
    if (n > 2) {
      const struct field *at = &f[n == 3 ? 2 : 3];
      const char *what = n == 3 ? "arrival DRAM cycle" : "arrival cycle";
      if (!parse_dec(at, &v) || v > REPLAY_CYCLE_MAX)
        return err_set(r->e, r->path, line, at->col,
                       "%s: not a cycle (got %s, expected a whole number from 0 to %llu)", what,
                       echo(at, got, sizeof got), REPLAY_CYCLE_MAX),
               -1;
      if (r->requests && v < r->last_at)
        return err_set(r->e, r->path, line, at->col,
                       "%s: earlier than the request before (got %llu, expected at least %llu)",
                       what, (unsigned long long)v, (unsigned long long)r->last_at),
               -1;
    }
    q->arrival = n == 5 ? v : dram_clock_to_core(r->clock, v);
    /* A fast core against a slow DRAM clock multiplies DRAM cycles. */
    if (q->arrival > REPLAY_CYCLE_MAX)
      return err_set(r->e, r->path, line, n == 3 ? f[2].col : f[0].col,
                     "arrival DRAM cycle: too late (got %llu, core cycle %llu; expected at most "
                     "core cycle %llu)",
                     (unsigned long long)v, (unsigned long long)q->arrival, REPLAY_CYCLE_MAX),
             -1;
    /* A banked DRAM with refresh steps through every refresh until then. */
    const uint64_t dram_at = n == 5 ? dram_clock_from_core(r->clock, v) : v;
    if (dram_at > r->dram_cycle_max)
      return err_set(r->e, r->path, line, n == 2 ? f[0].col : f[n == 3 ? 2 : 3].col,
                     "%s: too late for the replay (got DRAM cycle %llu, expected at most %llu: "
                     "the DRAM refreshes every tREFI / ranks = %llu DRAM cycles on each channel "
                     "and the replay steps through every refresh, at most %llu in all; "
                     "--set dram.tREFI=0 turns refresh off)",
                     n == 2   ? "request"
                     : n == 3 ? "arrival DRAM cycle"
                              : "arrival cycle",
                     (unsigned long long)dram_at, (unsigned long long)r->dram_cycle_max,
                     (unsigned long long)r->refresh_every, REPLAY_REFRESHES_MAX),
             -1;
    r->last_at = v;
    r->requests++;
    return 1;
  }
}

/* ---- the replay ---- */

/* A request taken by the DRAM, at its index in the trace. */
struct slot {
  uint64_t arrival, taken, done;
  bool write, served;
};

struct replay {
  struct engine *eng;
  struct dram *dram;
  struct reader rd;
  struct request next; /* the next request to offer, when have_next */
  bool have_next, blocked, failed;
  uint64_t feed_at;  /* the pending feed event's cycle, or UINT64_MAX */
  struct slot *ring; /* capacity a power of two; requests [head, taken) by index */
  uint64_t cap, head, taken;
  FILE *per;                /* the per-request file, or NULL */
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
  if (p->taken - p->head == p->cap) {
    /* Grow the ring, keeping each request at its index modulo the new size. */
    uint64_t cap = 2 * p->cap;
    struct slot *n = xcalloc(cap, sizeof *n);
    for (uint64_t i = p->head; i < p->taken; i++) n[i & (cap - 1)] = p->ring[i & (p->cap - 1)];
    free(p->ring);
    p->ring = n;
    p->cap = cap;
  }
  const uint64_t now = engine_now(p->eng), idx = p->taken++;
  struct slot *s = &p->ring[idx & (p->cap - 1)];
  *s = (struct slot){p->next.arrival, now, 0, p->next.write, false};
  p->wait_sum += now - p->next.arrival;
  dram_take(p->dram, p->next.addr, p->next.write, idx);
  int rc = reader_next(&p->rd, &p->next);
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
  CHECK(idx >= p->head && idx < p->taken);
  struct slot *s = &p->ring[idx & (p->cap - 1)];
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
  while (p->head < p->taken) {
    struct slot *h = &p->ring[p->head & (p->cap - 1)];
    if (!h->served) break;
    if (p->per)
      fprintf(p->per, "%llu %llu %llu %llu\n", (unsigned long long)p->head,
              (unsigned long long)h->arrival, (unsigned long long)h->taken,
              (unsigned long long)h->done);
    p->head++;
  }
}

static double ratio(double a, double b) { return b > 0 ? a / b : 0.0; }

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
  return ratio((double)REPLAY_LINE_BYTES * (double)r_requests(st, env), (double)env->cycles);
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
static double r_lat_mean(const void *st, const struct stats_env *env) {
  (void)env;
  return hist_mean(&rp(st)->read_latency);
}
static uint64_t r_p50(const void *st, const struct stats_env *env) {
  (void)env;
  return hist_quantile(&rp(st)->read_latency, 0.50);
}
static uint64_t r_p95(const void *st, const struct stats_env *env) {
  (void)env;
  return hist_quantile(&rp(st)->read_latency, 0.95);
}
static uint64_t r_p99(const void *st, const struct stats_env *env) {
  (void)env;
  return hist_quantile(&rp(st)->read_latency, 0.99);
}
static uint64_t r_lat_max(const void *st, const struct stats_env *env) {
  (void)env;
  return rp(st)->read_latency.max;
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
  return ratio((double)rp(st)->write_latency_sum, (double)rp(st)->writes);
}
static double r_wait_mean(const void *st, const struct stats_env *env) {
  return ratio((double)rp(st)->wait_sum, (double)r_requests(st, env));
}
static double r_gbps(const void *st, const struct stats_env *env) {
  return r_bpc(st, env) * rmp(env)->clock_ghz;
}
static double r_mean_dram(const void *st, const struct stats_env *env) {
  return r_lat_mean(st, env) * r_to_dram(env);
}
static double r_p50_dram(const void *st, const struct stats_env *env) {
  return (double)r_p50(st, env) * r_to_dram(env);
}
static double r_p95_dram(const void *st, const struct stats_env *env) {
  return (double)r_p95(st, env) * r_to_dram(env);
}
static double r_p99_dram(const void *st, const struct stats_env *env) {
  return (double)r_p99(st, env) * r_to_dram(env);
}

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
    STATS_FN_F64(r_lat_mean, "read_latency_mean", "cycles",
                 "a read's latency from its arrival, mean"),
    STATS_FN_U64(r_p50, "read_latency_p50", "cycles", "its median"),
    STATS_FN_U64(r_p95, "read_latency_p95", "cycles", "its 95th percentile"),
    STATS_FN_U64(r_p99, "read_latency_p99", "cycles", "its 99th percentile"),
    STATS_FN_U64(r_lat_max, "read_latency_max", "cycles", "its largest"),
    STATS_FN_F64(r_taken_mean, "read_latency_taken_mean", "cycles",
                 "a read's latency from the DRAM taking it, mean"),
    STATS_FN_U64(r_taken_max, "read_latency_taken_max", "cycles", "its largest"),
    STATS_FN_F64(r_write_mean, "write_latency_mean", "cycles",
                 "a write's latency from its arrival, mean"),
    STATS_FN_F64(r_wait_mean, "refused_wait_mean", "cycles",
                 "cycles a request waited past its arrival for the DRAM to take it, mean"),
    STATS_FN_F64(r_bpc, "bytes_per_cycle", "bytes a cycle", "64-byte lines moved / cycles"),
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
  p->rd.f = in;
  p->rd.path = trace_path;
  p->rd.e = &e;
  p->rd.clock = dram_clock_make(core_khz, (uint64_t)dp.clock_mhz * 1000);
  p->rd.dram_cycle_max = UINT64_MAX;
  if (dp.model == DRAM_MODEL_BANKED && dp.banked.tREFI > 0) {
    p->rd.refresh_every = dp.banked.tREFI / dp.banked.ranks;
    p->rd.dram_cycle_max = REPLAY_REFRESHES_MAX / dp.banked.channels * p->rd.refresh_every;
  }
  int got = reader_next(&p->rd, &p->next);
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
  p->cap = 64;
  p->ring = xcalloc(p->cap, sizeof *p->ring);
  p->eng = engine_create();
  const struct dram_client client = {p, on_done, on_space, NULL};
  p->dram = dram_create(&dp, core_khz, p->eng, &client);
  p->feed_at = p->next.arrival;
  engine_at(p->eng, p->next.arrival, ev_feed, p, p->next.arrival);
  engine_run(p->eng);
  /* Every request offered was taken and served, unless a bad line stopped the feed. */
  CHECK(p->failed || !p->have_next);
  CHECK_EQ(p->head, p->taken);
  dram_finish(p->dram);
  if (p->failed) {
    rc = app_report(&e);
    goto done;
  }
  if (per_path && !outfile_commit(&per, &e)) {
    rc = app_report(&e);
    goto done;
  }
  static const char *const formats[6] = {NULL, NULL, "ramulator", "dramsim3", NULL, "rtsim"};
  struct stats_table t = {0};
  report(p, trace_path, formats[p->rd.fields], &mc, &t);
  stats_write_csv_header(&t, stdout);
  stats_write_csv_row(&t, stdout);
  stats_fini(&t);
  rc = 0;
done:
  outfile_abort(&per);
  if (p) {
    dram_destroy(p->dram);
    engine_destroy(p->eng);
    free(p->ring);
    free(p);
  }
  if (in) fclose(in);
  free(sets.v);
  return rc;
}
