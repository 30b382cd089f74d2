/* A FIFO channel solved in closed form when a request is taken: request k
 * starts its transfer at max(taken, end of request k - 1). It is taken only
 * while the FIFO has a free place: the request queue_depth places ahead of it
 * has started. A ring of the last queue_depth start times is all the state
 * that rule needs. */
#include "sim/dram_channel.h"

#include <math.h>
#include <stdlib.h>

#include "sim/engine.h"
#include "sim/line.h"
#include "sim/ring.h"
#include "sim/stats.h"

struct dram_channel {
  struct dram_channel_params p;
  struct engine *eng;
  struct dram_client client;
  uint64_t line_ticks;  /* one line's transfer: at least one tick, so it takes time */
  dram_tick *starts;    /* ring: start ticks of the last queue_depth requests */
  uint64_t k;           /* requests so far */
  dram_tick free_ticks; /* when the channel is next free: the last transfer's end */
  uint64_t space_at;    /* cycle of the pending space event, or UINT64_MAX */
  /* Occupancy sweep: entry and start ticks (struct span) of requests not yet
   * started at sweep_t; sw_e: how many of them have entered by sweep_t. */
  struct ring sw;
  uint64_t sw_e;
  dram_tick sweep_t;
  double occ;
  struct dram_channel_stats st;
};

/* A request's entry into the FIFO and the start of its transfer, in ticks. */
struct span {
  dram_tick entry, start;
};

#define TICK_FOREVER (~(dram_tick)0)

/* Advance the occupancy integral to tick x: entries and starts are each
 * non-decreasing, so two pointers merge them in time order. */
static void sweep_to(struct dram_channel *d, dram_tick x) {
  const double tick = 1.0 / (double)(1ull << DRAM_TICK_BITS);
  while (ring_len(&d->sw)) {
    const uint64_t n = ring_len(&d->sw);
    dram_tick next_entry =
        d->sw_e < n ? RING_AT(&d->sw, struct span, d->sw.head + d->sw_e)->entry : TICK_FOREVER;
    dram_tick next_start = RING_HEAD(&d->sw, struct span)->start;
    dram_tick ev = next_entry < next_start ? next_entry : next_start;
    if (ev > x) break;
    d->st.fifo_area += d->occ * (double)(ev - d->sweep_t) * tick;
    d->sweep_t = ev;
    /* At equal ticks a start goes first (its place frees for the entry), unless
     * the head has not entered yet. */
    if (d->sw_e == 0 || next_entry < next_start) {
      d->sw_e++;
      d->occ += 1.0;
      if (d->occ > d->st.fifo_max) d->st.fifo_max = (uint32_t)d->occ;
    } else {
      /* The head starts: it entered no later than it started. */
      CHECK_GT(d->sw_e, 0);
      ring_pop(&d->sw);
      d->sw_e--;
      d->occ -= 1.0;
    }
  }
  if (x != TICK_FOREVER && x > d->sweep_t) {
    d->st.fifo_area += d->occ * (double)(x - d->sweep_t) * tick;
    d->sweep_t = x;
  }
}

static void sweep_add(struct dram_channel *d, dram_tick entry, dram_tick start) {
  *RING_PUSH(&d->sw, struct span) = (struct span){entry, start};
}

static void ev_done(void *ctx, uint64_t tag) {
  struct dram_channel *d = ctx;
  d->client.done(d->client.ctx, tag);
}

static void ev_space(void *ctx, uint64_t arg) {
  struct dram_channel *d = ctx;
  (void)arg;
  d->space_at = UINT64_MAX;
  d->client.space(d->client.ctx);
}

/* Is a FIFO place free at tick now? The request queue_depth ahead has started. */
static bool place_free(const struct dram_channel *d, dram_tick now_ticks) {
  return d->k < d->p.queue_depth || d->starts[d->k % d->p.queue_depth] <= now_ticks;
}

static bool ch_can_take(void *self, uint64_t addr, bool write) {
  const struct dram_channel *d = self;
  (void)addr;
  (void)write;
  return place_free(d, (dram_tick)engine_now(d->eng) << DRAM_TICK_BITS);
}

static void ch_take(void *self, uint64_t addr, bool write, uint64_t tag) {
  struct dram_channel *d = self;
  (void)addr;
  const uint64_t now = engine_now(d->eng);
  const dram_tick arrive = (dram_tick)now << DRAM_TICK_BITS;
  CHECK(place_free(d, arrive));
  sweep_to(d, arrive);
  uint32_t slot = (uint32_t)(d->k % d->p.queue_depth);
  dram_tick start = arrive > d->free_ticks ? arrive : d->free_ticks;
  const uint64_t dur = d->line_ticks;
  dram_tick end = start + dur;
  d->starts[slot] = start;
  d->k++;
  d->st.requests++;
  d->free_ticks = end;
  d->st.busy_ticks += dur;
  d->st.wait_ticks_sum += start - arrive;
  sweep_add(d, arrive, start);
  if (d->client.transfer) {
    const double per_cycle = (double)(1ull << DRAM_TICK_BITS);
    d->client.transfer(d->client.ctx, tag, (double)start / per_cycle, (double)end / per_cycle);
  }
  uint64_t done = dram_ticks_to_cycles_ceil(end) + (write ? 0 : d->p.latency_cycles);
  engine_at(d->eng, done, ev_done, d, tag);
  /* Full now: tell the client when the next place frees (the request
   * queue_depth ahead of the next one starts). */
  if (!place_free(d, arrive)) {
    uint64_t at = dram_ticks_to_cycles_ceil(d->starts[d->k % d->p.queue_depth]);
    if (d->space_at != at) {
      d->space_at = at;
      engine_at(d->eng, at, ev_space, d, 0);
    }
  }
}

static void ch_finish(void *self, uint64_t end) {
  (void)end;
  sweep_to(self, TICK_FOREVER);
}

/* The channel level's numbers (docs/stats.md). */
static double ch_utilization(const void *st, const struct stats_env *env) {
  const struct dram_channel_stats *s = st;
  const double tick = (double)(1ull << DRAM_TICK_BITS), cyc = (double)env->cycles;
  return stats_ratio((double)s->busy_ticks / tick, cyc);
}
static double ch_fifo_wait_mean(const void *st, const struct stats_env *env) {
  (void)env;
  const struct dram_channel_stats *s = st;
  const double tick = (double)(1ull << DRAM_TICK_BITS), n = (double)s->requests;
  return stats_ratio((double)s->wait_ticks_sum / tick, n);
}
static double ch_fifo_length_mean(const void *st, const struct stats_env *env) {
  const struct dram_channel_stats *s = st;
  const double cyc = (double)env->cycles;
  return cyc > 0 ? s->fifo_area / cyc : 0.0;
}
static uint64_t ch_fifo_length_max(const void *st, const struct stats_env *env) {
  (void)env;
  return ((const struct dram_channel_stats *)st)->fifo_max;
}

#define CH_AFTER(f)                                                                                \
  (offsetof(struct dram_channel_stats, f) + STATS_FIELD_SIZE(struct dram_channel_stats, f))
static const struct stats_desc channel_desc[] = {
    STATS_F64(struct dram_channel_stats, busy_ticks, ch_utilization, "dram_utilization", "fraction",
              "cycles the channel was transferring / cycles of the run"),
    {.name = "dram_fifo_wait_mean",
     .unit = "cycles",
     .desc = "requests, taken to the start of their transfer: mean",
     .how = STATS_HOW_F64,
     .off = offsetof(struct dram_channel_stats, wait_ticks_sum), /* and requests, after it */
     .size = CH_AFTER(requests) - offsetof(struct dram_channel_stats, wait_ticks_sum),
     .f64 = ch_fifo_wait_mean},
    STATS_F64(struct dram_channel_stats, fifo_area, ch_fifo_length_mean, "dram_fifo_length_mean",
              "requests", "requests in the FIFO: mean over the run"),
    STATS_U64(struct dram_channel_stats, fifo_max, ch_fifo_length_max, "dram_fifo_length_max",
              "requests", "requests in the FIFO: most at once"),
};
static const struct stats_skip channel_skip[] = {
    {CH_AFTER(fifo_max), sizeof(struct dram_channel_stats) - CH_AFTER(fifo_max), "padding", NULL},
};
const struct stats_descs dram_channel_stats_descs = {"dram channel",
                                                     channel_desc,
                                                     STATS_COUNT(channel_desc),
                                                     sizeof(struct dram_channel_stats),
                                                     channel_skip,
                                                     STATS_COUNT(channel_skip)};

static void ch_stats(const void *self, struct stats_part *out) {
  const struct dram_channel *d = self;
  out->g = &dram_channel_stats_descs;
  out->st = &d->st;
  out->ctx = d;
}

static void ch_destroy(void *self) {
  struct dram_channel *d = self;
  if (!d) return;
  ring_free(&d->sw);
  free(d->starts);
  free(d);
}

const struct dram_level_ops dram_channel_ops = {ch_can_take, ch_take,    ch_finish,
                                                ch_stats,    ch_destroy, NULL};

struct dram_channel *dram_channel_create(const struct dram_channel_params *p, struct engine *e,
                                         const struct dram_client *client) {
  /* The FIFO divides by both (the key table keeps them positive). */
  CHECK(p->bytes_per_cycle > 0 && p->queue_depth >= 1);
  struct dram_channel *d = xcalloc(1, sizeof *d);
  d->p = *p;
  d->eng = e;
  d->client = *client;
  d->space_at = UINT64_MAX;
  const double ticks_per_byte = (double)(1ull << DRAM_TICK_BITS) / p->bytes_per_cycle;
  d->line_ticks = (uint64_t)llround((double)SIM_LINE_BYTES * ticks_per_byte);
  if (d->line_ticks == 0) d->line_ticks = 1;
  d->starts = xcalloc(p->queue_depth, sizeof *d->starts);
  return d;
}
