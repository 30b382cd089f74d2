/* The fixed and channel DRAM levels alone, and the wrapper every level sits
 * behind (sim/dram.h), against a closed-form reference written here:
 *   fixed:   request k is served at taken_k + latency, never refused;
 *   channel: a FIFO of depth D crossed at T = 64 / bytes_per_cycle cycles a
 *            line: taken_k = max(want_k, taken_{k-1}, ceil(start_{k-D})),
 *            start_k = max(taken_k, end_{k-1}), end_k = start_k + T,
 *            served at ceil(end_k) (+ latency for a read).
 * T is chosen exact in the level's ticks (8, 12.5, 0.5, 128 cycles), so the
 * reference needs no rounding rule of its own. The client sends in order,
 * when a request arrives and when the level says a place freed, as the L2
 * does; the level must never hold more than D requests that have not started.
 * The wrapper's counts, latency histograms and trace (arrival order, each
 * line once every earlier request is served) are checked on the same runs. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sim/dram.h"
#include "sim/dram_channel.h"
#include "sim/dram_fixed.h"
#include "sim/engine.h"
#include "sim/stats.h"
#include "testing.h"

#define NREQ 400

struct req {
  uint64_t want; /* cycle the client wants to send it */
  bool write;
  uint64_t taken; /* cycle it was sent (filled by the run) */
  uint64_t done;  /* cycle it was served (filled by the run), UINT64_MAX before */
};

/* The client: requests in order, sent as soon as the level takes them. */
struct client {
  struct engine *eng;
  struct req *r;
  unsigned n, next, arrived;
  /* Either a level through its ops, or the wrapper. */
  const struct dram_level_ops *ops;
  void *level;
  struct dram *dram;
  unsigned spaces;
};

static bool can_take(struct client *c, uint64_t addr, bool w) {
  return c->dram ? dram_can_take(c->dram, addr, w) : c->ops->can_take(c->level, addr, w);
}

static void take(struct client *c, uint64_t addr, bool w, uint64_t tag) {
  if (c->dram) dram_take(c->dram, addr, w, tag);
  else c->ops->take(c->level, addr, w, tag);
}

static uint64_t addr_of(unsigned k) { return (uint64_t)k * 64 * 37; }

static void send(struct client *c) {
  while (c->next < c->arrived && can_take(c, addr_of(c->next), c->r[c->next].write)) {
    c->r[c->next].taken = engine_now(c->eng);
    take(c, addr_of(c->next), c->r[c->next].write, c->next);
    c->next++;
  }
}

static void ev_arrive(void *ctx, uint64_t k) {
  struct client *c = ctx;
  CHECK_EQ(k, c->arrived);
  c->arrived++;
  send(c);
}

static void on_done(void *ctx, uint64_t tag) {
  struct client *c = ctx;
  CHECK_LT(tag, c->next);
  CHECK_EQ(c->r[tag].done, UINT64_MAX);
  c->r[tag].done = engine_now(c->eng);
}

static void on_space(void *ctx) {
  struct client *c = ctx;
  c->spaces++;
  send(c);
}

/* Requests: bursts and gaps, a quarter of them writes (a fixed LCG). */
static void make_requests(struct req *r, unsigned n, uint64_t seed, unsigned mean_gap) {
  uint64_t s = seed, t = 0;
  for (unsigned k = 0; k < n; k++) {
    s = s * 6364136223846793005ull + 1442695040888963407ull;
    unsigned x = (unsigned)(s >> 33);
    if (x % 8 == 0) t += (x >> 3) % (40u * mean_gap + 1); /* a gap */
    else if (x % 3 == 0) t += (x >> 5) % (2u * mean_gap + 1);
    r[k].want = t;
    r[k].write = (x >> 11) % 4 == 0;
    r[k].taken = 0;
    r[k].done = UINT64_MAX;
  }
}

/* Arrivals are scheduled in order (ev_arrive checks), the run drains. */
static void drive(struct client *c) {
  for (unsigned k = 0; k < c->n; k++) engine_at(c->eng, c->r[k].want, ev_arrive, c, k);
  engine_run(c->eng);
}

/* The channel's reference: served cycles and taken cycles for depth D. */
static void channel_reference(const struct req *r, unsigned n, double T, uint64_t latency,
                              unsigned D, uint64_t *taken, uint64_t *done) {
  double *start = malloc(n * sizeof *start);
  double end_prev = 0;
  for (unsigned k = 0; k < n; k++) {
    uint64_t t = r[k].want;
    if (k > 0 && taken[k - 1] > t) t = taken[k - 1];
    if (k >= D && (uint64_t)ceil(start[k - D]) > t) t = (uint64_t)ceil(start[k - D]);
    taken[k] = t;
    start[k] = (double)t > end_prev ? (double)t : end_prev;
    end_prev = start[k] + T;
    done[k] = (uint64_t)ceil(end_prev) + (r[k].write ? 0 : latency);
  }
  free(start);
}

static void test_fixed(void) {
  static struct req r[NREQ];
  const uint64_t lats[] = {0, 1, 37, 300};
  for (unsigned i = 0; i < 4; i++) {
    make_requests(r, NREQ, 11 + i, 3);
    struct client c = {.eng = engine_create(), .r = r, .n = NREQ, .ops = &dram_fixed_ops};
    struct dram_client dc = {&c, on_done, on_space, NULL};
    c.level = dram_fixed_create(lats[i], c.eng, &dc);
    drive(&c);
    unsigned bad = 0;
    for (unsigned k = 0; k < NREQ; k++)
      bad += r[k].taken != r[k].want || r[k].done != r[k].want + lats[i];
    EXPECTF(bad == 0 && c.next == NREQ, "fixed latency %llu: %u requests off",
            (unsigned long long)lats[i], bad);
    EXPECT(c.spaces == 0); /* it never refuses, so never frees a place */
    c.ops->finish(c.level, engine_now(c.eng));
    c.ops->destroy(c.level);
    engine_destroy(c.eng);
  }
}

/* One channel run against the reference; also counts FIFO overfills. */
static void channel_case(double bytes_per_cycle, uint64_t latency, unsigned depth, unsigned gap,
                         uint64_t seed) {
  static struct req r[NREQ];
  static uint64_t taken[NREQ], done[NREQ];
  make_requests(r, NREQ, seed, gap);
  const double T = 64.0 / bytes_per_cycle;
  channel_reference(r, NREQ, T, latency, depth, taken, done);
  struct client c = {.eng = engine_create(), .r = r, .n = NREQ, .ops = &dram_channel_ops};
  struct dram_client dc = {&c, on_done, on_space, NULL};
  struct dram_channel_params p = {latency, bytes_per_cycle, depth};
  c.level = dram_channel_create(&p, c.eng, &dc);
  drive(&c);
  unsigned bad_taken = 0, bad_done = 0, first = NREQ;
  for (unsigned k = 0; k < NREQ; k++) {
    if (r[k].taken != taken[k]) bad_taken++;
    if (r[k].done != done[k]) bad_done++;
    if ((r[k].taken != taken[k] || r[k].done != done[k]) && first == NREQ) first = k;
  }
  EXPECTF(c.next == NREQ && bad_taken == 0 && bad_done == 0,
          "channel %.3g B/cycle, latency %llu, depth %u: %u taken and %u served off the "
          "reference (first: request %u, taken %llu/%llu, served %llu/%llu)",
          bytes_per_cycle, (unsigned long long)latency, depth, bad_taken, bad_done, first,
          first < NREQ ? (unsigned long long)r[first].taken : 0ull,
          first < NREQ ? (unsigned long long)taken[first] : 0ull,
          first < NREQ ? (unsigned long long)r[first].done : 0ull,
          first < NREQ ? (unsigned long long)done[first] : 0ull);
  c.ops->finish(c.level, engine_now(c.eng));
  /* Its own report: utilization is the transfer time over the run. */
  struct stats_table t = {0};
  uint64_t cycles = 0;
  for (unsigned k = 0; k < NREQ; k++)
    if (r[k].done > cycles) cycles = r[k].done;
  dram_level_report(c.ops, c.level, &t, cycles);
  bool found = false;
  for (unsigned i = 0; i < t.n; i++)
    if (!strcmp(t.e[i].name, "dram_utilization")) {
      found = true;
      EXPECTF(fabs(t.e[i].f - NREQ * T / (double)cycles) < 1e-9, "utilization %.9f, want %.9f",
              t.e[i].f, NREQ * T / (double)cycles);
    }
  EXPECT(found);
  stats_fini(&t);
  c.ops->destroy(c.level);
  engine_destroy(c.eng);
}

static void test_channel(void) {
  /* Bandwidth above, near and below the offered load; deep and shallow FIFOs
   * (depth 1: every request waits for the one before it to start). */
  const double bpc[] = {8.0, 5.12, 128.0, 0.5};
  const unsigned depth[] = {1, 2, 16, 64};
  const uint64_t lat[] = {0, 25, 100};
  unsigned n = 0;
  for (unsigned b = 0; b < 4; b++)
    for (unsigned d = 0; d < 4; d++) channel_case(bpc[b], lat[(b + d) % 3], depth[d], 4, 100 + n++);
  /* Saturated: requests come faster than the channel crosses them. */
  channel_case(0.5, 50, 8, 1, 7);
}

/* The wrapper around each cheap level: counts, latencies and the trace. */
static void wrapper_case(enum dram_model model) {
  static struct req r[NREQ];
  make_requests(r, NREQ, 77 + model, 6);
  struct dram_params p = testing_dram_params(model, 4);
  EXPECT(dram_params_problem(&p) == NULL);
  struct client c = {.eng = engine_create(), .r = r, .n = NREQ};
  struct dram_client dc = {&c, on_done, on_space, NULL};
  c.dram = dram_create(&p, 1400000, c.eng, &dc); /* 1.4 GHz core */
  char *buf = NULL;
  size_t len = 0;
  FILE *f = open_memstream(&buf, &len);
  dram_trace_to(c.dram, f);
  drive(&c);
  dram_finish(c.dram, engine_now(c.eng));
  fclose(f);
  const struct dram_stats *s = dram_get_stats(c.dram);
  uint64_t reads = 0, writes = 0, rsum = 0, wsum = 0, rmax = 0;
  for (unsigned k = 0; k < NREQ; k++) {
    uint64_t l = r[k].done - r[k].taken;
    if (r[k].write) {
      writes++;
      wsum += l;
    } else {
      reads++;
      rsum += l;
      if (l > rmax) rmax = l;
    }
  }
  EXPECT(s->reads == reads && s->writes == writes);
  EXPECT(s->read_bytes == 64 * reads && s->write_bytes == 64 * writes);
  EXPECT(s->read_latency.count == reads && s->read_latency.sum == rsum);
  EXPECT(s->read_latency.max == rmax);
  EXPECT(s->write_latency.count == writes && s->write_latency.sum == wsum);
  /* The trace: a header, then one line a request in arrival order (the
   * client sends in order, so line k is request k). */
  char *line = strtok(buf, "\n");
  EXPECT(line && line[0] == '#' && strstr(line, dram_model_names[model]));
  unsigned k = 0, bad = 0;
  while ((line = strtok(NULL, "\n"))) {
    unsigned long long a, dc_, at, done;
    char op[8];
    if (k >= NREQ || sscanf(line, "0x%llx %7s %llu %llu %llu", &a, op, &dc_, &at, &done) != 5) {
      bad++;
      break;
    }
    /* 1400 MHz core, 1200 MHz DRAM: DRAM cycle of core cycle t is ceil(t * 6 / 7). */
    bad += a != addr_of(k) || strcmp(op, r[k].write ? "WRITE" : "READ") != 0 || at != r[k].taken ||
           done != r[k].done || dc_ != (at * 6 + 6) / 7;
    k++;
  }
  EXPECTF(bad == 0 && k == NREQ, "%s trace: %u of %u lines off", dram_model_names[model], bad, k);
  free(buf);
  dram_destroy(c.dram);
  engine_destroy(c.eng);
}

int main(void) {
  test_fixed();
  test_channel();
  wrapper_case(DRAM_MODEL_FIXED);
  wrapper_case(DRAM_MODEL_CHANNEL);
  wrapper_case(DRAM_MODEL_BANKED);
  return testing_done("test_dram");
}
