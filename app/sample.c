/* Sampling a timed run: the plan, the claim hook, the probes and the
 * estimates (sample.h says the design; docs/fidelity-and-sampling.md says why). */
#include "app/sample.h"

#include "app/sample_aux.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "renderer/rng.h"
#include "sim/derived.h"
#include "sim/err.h"
#include "sim/stats.h"

/* Femtojoules a joule: the probes count energy in whole fJ. */
#define FJ_PER_J 1e15

/* Units when sample.units is 0: as many as the detailed items allow, each
 * at least three pipelines long (3 x the ray contexts), at most this many. */
#define SAMPLE_AUTO_UNITS_MAX 40

uint32_t sample_units(const struct machine_cfg_sample *c, uint64_t total, uint32_t contexts) {
  if (c->units) return c->units;
  double n = c->fraction * (double)total / (3.0 * contexts);
  return n >= SAMPLE_AUTO_UNITS_MAX ? SAMPLE_AUTO_UNITS_MAX : (uint32_t)n;
}

const char *sample_problem(const struct machine_cfg_sample *c, uint32_t fidelity,
                           enum policy_kind k, uint64_t total, uint32_t contexts, char *buf,
                           size_t cap) {
  if (c->fraction >= 1) return NULL;
  if (fidelity == MACHINE_FIDELITY_ANALYTIC)
    return "sample.fraction: sampling simulates units in time: a timed fidelity (fixed, channel "
           "or banked), not analytic";
  if (policy_queues(k))
    return "sample.fraction: sampling needs a policy that takes its work item by item "
           "(recursive or packet); the dynamic and treelet policies trace every primary ray "
           "as one batch, and sampling them in time (fast-forwarding the whole machine "
           "between windows) was measured 2-18% off in cycles at 128x128 with intervals "
           "that missed (docs/fidelity-and-sampling.md): run them whole";
  /* A unit warms the pipeline with two items a ray context, then measures
   * at least one a context: the measured window then holds the unit's own
   * items, started at spread times. */
  uint32_t n = sample_units(c, total, contexts);
  if (n < SAMPLE_MIN_UNITS || c->fraction * (double)total / n < 3.0 * contexts) {
    /* The fraction that gives SAMPLE_MIN_UNITS units of 3 x contexts items. */
    const double need = SAMPLE_MIN_UNITS * 3.0 * contexts / (double)total;
    char hint[160];
    if (c->units && c->units < SAMPLE_MIN_UNITS)
      snprintf(hint, sizeof hint, "sample.units 0 or at least %u", SAMPLE_MIN_UNITS);
    else if (need <= 1)
      snprintf(hint, sizeof hint,
               "sample.fraction %.3g or more, a larger image, or fewer ray contexts", need);
    else
      snprintf(hint, sizeof hint,
               "this image is too small to sample on %u ray contexts: a larger image, fewer "
               "contexts, or the whole run",
               contexts);
    snprintf(buf, cap,
             "sample.fraction: too few detailed items: %.0f of %llu work items in %u unit%s, and "
             "a unit needs 3 x %u (the ray contexts: two pipelines to warm, one to measure) and "
             "there must be at least %u units (fewer leave a 95%% interval that means nothing); "
             "%s",
             c->fraction * (double)total, (unsigned long long)total, n, n == 1 ? "" : "s", contexts,
             SAMPLE_MIN_UNITS, hint);
    return buf;
  }
  return NULL;
}

void sample_init(struct sampler *s, const struct machine_cfg_sample *c, uint32_t cores,
                 double clock_ghz, uint64_t total, uint32_t contexts) {
  memset(s, 0, sizeof *s);
  s->total = total;
  s->n = sample_units(c, total, contexts);
  CHECK_GE(s->n, SAMPLE_MIN_UNITS);
  s->cores = cores;
  s->hz = derived_hz(clock_ghz);
  s->whole = c->whole_image != 0;
  s->u = xcalloc(s->n, sizeof *s->u);
  s->drained = xcalloc(s->n, sizeof *s->drained);
  uint64_t prev_end = 0;
  for (uint32_t h = 0; h < s->n; h++) {
    struct sample_unit *u = &s->u[h];
    u->stratum_lo = total * h / s->n;
    u->stratum_hi = total * (h + 1) / s->n;
    const uint64_t size = u->stratum_hi - u->stratum_lo;
    uint64_t d = (uint64_t)llround(c->fraction * (double)size);
    if (d > size) d = size;
    /* Two items a ray context warm the pipeline: after the drain every
     * context starts at once, and by the second round their items' starts
     * have spread as in the full run's steady state. The first unit starts
     * the run as the full run starts it (cold, at cycle 0) and is measured
     * from there; the last ends the run. */
    uint64_t wc = 2 * (uint64_t)contexts;
    uint64_t warm = h == 0 ? 0 : wc < d - contexts ? wc : d - contexts;
    uint64_t off = h == 0 ? 0 : size - d;
    if (h > 0 && h + 1 < s->n) off = rng_hash2(c->seed, h) % (size - d + 1);
    u->start = u->stratum_lo + off;
    u->measure = u->start + warm;
    u->end = u->start + d;
    CHECK_GT(u->end, u->measure);
    uint64_t w = (uint64_t)llround(c->warming * (double)d);
    u->warm_from = u->start - (w < u->start - prev_end ? w : u->start - prev_end);
    prev_end = u->end;
    s->detailed += d;
    s->measured += d - warm;
    s->warmed += u->start - u->warm_from;
  }
  CHECK_EQ(s->u[s->n - 1].end, total);
}

void sample_fini(struct sampler *s) {
  free(s->u);
  free(s->drained);
  sample_aux_free(s->aux);
  s->u = NULL;
  s->drained = NULL;
  s->aux = NULL;
}

/* The run's energy at cycle t with `slots` issue slots used, in whole
 * femtojoules (a probe's integers; a run's joules are far below 2^64 fJ). */
static uint64_t energy_fj(const struct machine *m, uint64_t t, uint64_t slots) {
  return (uint64_t)llround(machine_energy_j(m, t, slots) * FJ_PER_J);
}

static void probe(struct sampler *s, uint64_t *at) {
  struct machine_probe p;
  machine_probe(s->m, &p);
  at[SQ_CYCLES] = p.cycle;
  at[SQ_SLOTS] = p.issue_slots;
  at[SQ_DRAM_BYTES] = p.dram_bytes;
  at[SQ_LAT_SUM] = p.load_latency_sum;
  at[SQ_LAT_N] = p.loads_timed;
  at[SQ_RAYS] = s->rays_now ? s->rays_now(s->rays_ctx) : 0;
  at[SQ_ENERGY_FJ] = energy_fj(s->m, p.cycle, p.issue_slots);
}

enum policy_item sample_item(void *ctx, uint64_t k, uint32_t core, struct mem_port *port) {
  struct sampler *s = ctx;
  if (s->cur < s->n && k == s->u[s->cur].end) {
    /* (asked again while the worker holds: the unit is closed already) */
    probe(s, s->u[s->cur].at1);
    s->u[s->cur].have1 = true;
    s->cur++;
  }
  CHECK_LT(s->cur, s->n); /* (the last unit ends at the last item) */
  struct sample_unit *u = &s->u[s->cur];
  CHECK_LT(k, u->end);
  if (k >= u->start) {
    if (k == u->start) probe(s, u->at_start);
    if (k == u->measure) {
      probe(s, u->at0);
      u->have0 = true;
    }
    s->in_flight++;
    s->traced++;
    return POLICY_ITEM_DETAIL;
  }
  /* An item before the warming window: skipped (a sampled image), or only
   * counted; neither touches a cache, so neither waits for the drain. */
  if (k < u->warm_from && !s->whole) return POLICY_ITEM_SKIP;
  /* Between units the pipeline drains before the fast-forward: the unit's
   * last items must not run on caches warmed for the next one. */
  if (s->in_flight > 0 && !s->drained[s->cur]) return POLICY_ITEM_HOLD;
  s->drained[s->cur] = true;
  s->traced++;
  *port = k >= u->warm_from ? machine_warm_port(s->m, core) : machine_count_port(s->m);
  return POLICY_ITEM_PORT;
}

void sample_item_done(void *ctx, uint64_t k) {
  struct sampler *s = ctx;
  (void)k;
  CHECK_GT(s->in_flight, 0);
  s->in_flight--;
}

static void choose_cyc_aux(struct sampler *s);

void sample_finish(struct sampler *s, uint64_t rays_total) {
  CHECK_EQ(s->cur, s->n - 1);
  struct sample_unit *u = &s->u[s->n - 1];
  const struct machine_stats *st = machine_get_stats(s->m);
  u->at1[SQ_CYCLES] = st->cycles;
  u->at1[SQ_SLOTS] = st->issue_slots;
  u->at1[SQ_DRAM_BYTES] = st->l2.fetch_bytes + st->l2.writeback_bytes;
  u->at1[SQ_LAT_SUM] = st->load_latency.sum;
  u->at1[SQ_LAT_N] = st->load_latency.count;
  u->at1[SQ_RAYS] = rays_total;
  u->at1[SQ_ENERGY_FJ] = energy_fj(s->m, st->cycles, st->issue_slots);
  u->have1 = true;
  s->rays_total = rays_total;
  s->slots_detailed = st->issue_slots;
  s->slots_total = st->issue_slots + machine_warm_slots(s->m) + machine_count_slots(s->m);
  for (uint32_t h = 0; h < s->n; h++) CHECK(s->u[h].have0 && s->u[h].have1);
  sample_settle(s);
}

void sample_settle(struct sampler *s) {
  const struct sample_unit *u = &s->u[s->n - 1];
  /* With a sampled image the middle units stand for every item outside the
   * first and last units' measured ones: their strata scaled up to that. */
  s->mid_scale = 1;
  if (!s->whole) {
    double w = 0;
    for (uint32_t h = 1; h + 1 < s->n; h++) w += (double)(s->u[h].stratum_hi - s->u[h].stratum_lo);
    s->mid_scale = ((double)s->total - (double)(s->u[0].end - s->u[0].measure) -
                    (double)(u->end - u->measure)) /
                   w;
  }
  if (s->aux) choose_cyc_aux(s);
}

double sample_t975(unsigned dof) {
  /* Exact for the smallest; the Cornish-Fisher expansion (error < 1e-4 from 8 on). */
  static const double small[] = {0, 12.7062, 4.3027, 3.1824, 2.7764, 2.5706, 2.4469, 2.3646};
  CHECK_GE(dof, 1);
  if (dof < sizeof small / sizeof small[0]) return small[dof];
  const double z = 1.959963985, v = dof, z3 = z * z * z, z5 = z3 * z * z, z7 = z5 * z * z;
  return z + (z3 + z) / (4 * v) + (5 * z5 + 16 * z3 + 3 * z) / (96 * v * v) +
         (3 * z7 + 19 * z5 + 17 * z3 - 15 * z) / (384 * v * v * v);
}

/* A unit's measured value of q, and its measured items. */
static double delta(const struct sample_unit *u, enum sample_q q) {
  return (double)(u->at1[q] - u->at0[q]);
}
static double items(const struct sample_unit *u) { return (double)(u->end - u->measure); }

/* What the estimates are made of: the first and last units' own values
 * (certain), the middle units' per-item values weighted by their strata's
 * sizes (S, random), and the work the middle stands for: every issue slot of
 * the run (counted exactly: every item is traced) less the first and last
 * windows'; with a pre-pass, the middle units' auxiliary figures weighted
 * the same way (A) and the middle's auxiliary totals (X, estimated). */
struct parts {
  double edge[SQ_COUNT]; /* first + last units' deltas */
  double S[SQ_COUNT];    /* sum over middle units of W_h x q_h / M_h */
  double slots_mid;      /* issue slots the middle stands for (the whole image) */
  double A[SA_COUNT];    /* sum over middle units of W_h x a_h / M_h (pre-pass) */
  double X[SA_COUNT];    /* the middle's auxiliary totals (pre-pass) */
  double D; /* sum over middle units of W_h x (DRAM bytes of its detailed items) / d_h */
};

enum sample_fig {
  SF_SLOTS,
  SF_RAYS,
  SF_CYCLES,
  SF_DRAM_BYTES,
  SF_BYTES_PER_CYCLE,
  SF_UTIL,
  SF_RAYS_PER_S,
  SF_LOAD_LAT,
  SF_ENERGY,
  SF_POWER,
  SF_COUNT
};

/* The auxiliary figure quantity q is taken in ratio to: the work for issue
 * slots, rays and the count of loads, the footprint for DRAM bytes and the
 * loads' latencies (misses), the one chosen for cycles and energy. */
static unsigned aux_of(const struct sampler *s, enum sample_q q) {
  switch (q) {
  case SQ_SLOTS:
  case SQ_LAT_N: return SA_SLOTS;
  case SQ_RAYS: return SA_RAYS;
  case SQ_DRAM_BYTES:
  case SQ_LAT_SUM: return SA_DRAM;
  default: return s->cyc_aux;
  }
}

/* A middle quantity's total. With a pre-pass: its ratio to its auxiliary
 * figure over the middle units, times the middle's auxiliary total. With the whole image traced:
 * its ratio to issue slots over the middle units, times the issue slots the middle stands for
 * (known); with a sampled image, the middle units' values per item times the
 * items they stand for (S: parts_of weighs each stratum so that the weights
 * sum to the items outside the first and last units). */
static double mid(const struct sampler *s, const struct parts *p, enum sample_q q) {
  if (s->aux) {
    const unsigned a = aux_of(s, q);
    /* In ratio to the model's DRAM bytes: the units' measured bytes per
     * modelled byte over their detailed items (the same items in both: the
     * model's calibration) times the middle's modelled bytes, then q per
     * DRAM byte over the units' windows. */
    if (a == SA_DRAM)
      return p->A[a] > 0 && p->S[SQ_DRAM_BYTES] > 0
                 ? p->S[q] / p->S[SQ_DRAM_BYTES] * p->D / p->A[a] * p->X[a]
                 : 0;
    return p->A[a] > 0 ? p->S[q] / p->A[a] * p->X[a] : 0;
  }
  if (!s->whole) return p->S[q];
  return p->S[SQ_SLOTS] > 0 ? p->S[q] / p->S[SQ_SLOTS] * p->slots_mid : 0;
}

static double figure(const struct sampler *s, const struct parts *p, enum sample_fig f) {
  double cycles = p->edge[SQ_CYCLES] + mid(s, p, SQ_CYCLES);
  double bytes = p->edge[SQ_DRAM_BYTES] + mid(s, p, SQ_DRAM_BYTES);
  const double slots = s->whole ? (double)s->slots_total : p->edge[SQ_SLOTS] + mid(s, p, SQ_SLOTS);
  const double rays = s->whole ? (double)s->rays_total : p->edge[SQ_RAYS] + mid(s, p, SQ_RAYS);
  switch (f) {
  case SF_SLOTS: return slots;
  case SF_RAYS: return rays;
  case SF_CYCLES: return cycles;
  case SF_DRAM_BYTES: return bytes;
  case SF_BYTES_PER_CYCLE: return stats_ratio(bytes, cycles);
  case SF_UTIL: return derived_core_utilization(slots, s->cores, cycles);
  case SF_RAYS_PER_S: return derived_rays_per_second(rays, cycles / s->hz);
  case SF_ENERGY: return p->edge[SQ_ENERGY_FJ] + mid(s, p, SQ_ENERGY_FJ);
  case SF_POWER:
    return stats_ratio(p->edge[SQ_ENERGY_FJ] + mid(s, p, SQ_ENERGY_FJ), cycles / s->hz);
  default: {
    double n = p->edge[SQ_LAT_N] + mid(s, p, SQ_LAT_N);
    return n > 0 ? (p->edge[SQ_LAT_SUM] + mid(s, p, SQ_LAT_SUM)) / n : 0;
  }
  }
}

/* The items middle unit h stands for: its stratum's, scaled by mid_scale. */
static double weight(const struct sampler *s, uint32_t h) {
  return (double)(s->u[h].stratum_hi - s->u[h].stratum_lo) * s->mid_scale;
}

/* Middle unit h's auxiliary figure a over its measured window. The window
 * (from the claim of its first measured item to the claim of the first
 * after it) holds the tails of the warm-up's items and not those of its own
 * last ones: on a machine of many contexts and a short unit its work is not
 * its items' (measured: up to 2x). The issue slots it did are measured,
 * so the window's figure a is those slots at the unit's detailed items'
 * share of a per slot (the pre-pass's, over warm-up and measured items). */
static double aux_unit(const struct sampler *s, uint32_t h, unsigned a) {
  const double *x = &s->aux->unit[h * SA_COUNT];
  const double slots = delta(&s->u[h], SQ_SLOTS);
  return x[SA_SLOTS] > 0 ? slots * x[a] / x[SA_SLOTS] : 0;
}

/* Middle unit h's detailed items: their count, the DRAM bytes the machine
 * moved for them (from the claim of its first to that of the next unit's
 * first: the drain between lets every item of h finish, and the warming and
 * skipped items move none), and the model's bytes for them. */
static double detailed(const struct sample_unit *u) { return (double)(u->end - u->start); }
static double unit_dram(const struct sampler *s, uint32_t h) {
  return (double)(s->u[h + 1].at_start[SQ_DRAM_BYTES] - s->u[h].at_start[SQ_DRAM_BYTES]);
}

/* Middle unit h's value of auxiliary a per item: the DRAM model's over its
 * detailed items, the others' over its window (aux_unit). */
static double aux_val(const struct sampler *s, uint32_t h, unsigned a) {
  if (a == SA_DRAM) return s->aux->unit[h * SA_COUNT + a] / detailed(&s->u[h]);
  return aux_unit(s, h, a) / items(&s->u[h]);
}

static void parts_of(const struct sampler *s, struct parts *p) {
  memset(p, 0, sizeof *p);
  const struct sample_unit *f = &s->u[0], *l = &s->u[s->n - 1];
  for (unsigned q = 0; q < SQ_COUNT; q++) {
    p->edge[q] = delta(f, q) + delta(l, q);
    for (uint32_t h = 1; h + 1 < s->n; h++)
      p->S[q] += weight(s, h) * delta(&s->u[h], q) / items(&s->u[h]);
  }
  p->slots_mid = (double)s->slots_total - p->edge[SQ_SLOTS];
  if (!s->aux) return;
  for (unsigned a = 0; a < SA_COUNT; a++) {
    for (uint32_t h = 1; h + 1 < s->n; h++) p->A[a] += weight(s, h) * aux_val(s, h, a);
    p->X[a] = sample_aux_total(s->aux, a);
  }
  for (uint32_t h = 1; h + 1 < s->n; h++)
    p->D += weight(s, h) * unit_dram(s, h) / detailed(&s->u[h]);
}

struct est {
  double v, lo, hi;
};

/* The relative systematic uncertainty of figures made of cycles (estimate). */
#define SAMPLE_SYSTEMATIC 0.005

/* f's gradient in the middle units' auxiliary sums (ga) and in the middle's
 * auxiliary totals (gx), numerically, at the estimate v. */
static void aux_grad(const struct sampler *s, const struct parts *p, enum sample_fig f, double v,
                     double ga[SA_COUNT], double gx[SA_COUNT], double *gd) {
  struct parts dd = *p;
  const double eps_d = fabs(p->D) * 1e-7 + 1e-9;
  dd.D += eps_d;
  *gd = (figure(s, &dd, f) - v) / eps_d;
  for (unsigned a = 0; a < SA_COUNT; a++) {
    struct parts d = *p;
    double eps = fabs(p->A[a]) * 1e-7 + 1e-9;
    d.A[a] += eps;
    ga[a] = (figure(s, &d, f) - v) / eps;
    d = *p;
    eps = fabs(p->X[a]) * 1e-7 + 1e-9;
    d.X[a] += eps;
    gx[a] = (figure(s, &d, f) - v) / eps;
  }
}

/* Figure f with its 95% interval. Linearization: f's gradient in the middle
 * sums S (numerically) turns each middle unit into one value l_h, and the
 * variance of sum W_h l_h comes from successive differences of l_h: the
 * units are a systematic sample along the work list, one a stratum, so
 * neighbours differ by less than any two at random, and this keeps what the
 * strata gain (it is the simple variance when the values are in random
 * order). */
static struct est estimate(const struct sampler *s, enum sample_fig f) {
  struct parts p;
  parts_of(s, &p);
  const double v = figure(s, &p, f);
  double grad[SQ_COUNT];
  for (unsigned q = 0; q < SQ_COUNT; q++) {
    struct parts d = p;
    double eps = fabs(p.S[q]) * 1e-7 + 1e-9;
    d.S[q] += eps;
    grad[q] = (figure(s, &d, f) - v) / eps;
  }
  double ga[SA_COUNT] = {0}, gx[SA_COUNT] = {0}, gd = 0;
  if (s->aux) aux_grad(s, &p, f, v, ga, gx, &gd);
  const uint32_t r = s->n - 2; /* middle units */
  double prev = 0, ss = 0, w2 = 0;
  for (uint32_t h = 1; h + 1 < s->n; h++) {
    double l = 0;
    for (unsigned q = 0; q < SQ_COUNT; q++) l += grad[q] * delta(&s->u[h], q) / items(&s->u[h]);
    if (s->aux) {
      for (unsigned a = 0; a < SA_COUNT; a++) l += ga[a] * aux_val(s, h, a);
      l += gd * unit_dram(s, h) / detailed(&s->u[h]);
    }
    if (h > 1) ss += (l - prev) * (l - prev);
    prev = l;
    w2 += weight(s, h) * weight(s, h);
  }
  double var = r > 1 ? ss / (2.0 * (r - 1)) * w2 : 0;
  /* The pre-pass's own error: its sample of the rest stands for the middle's
   * auxiliary totals (double sampling: the two stages' variances add). */
  if (s->aux) var += sample_aux_var(s->aux, gx);
  double half = sample_t975(r > 1 ? r - 1 : 1) * sqrt(var);
  /* What the units' spread cannot show: a bias common to every window (the
   * restart after each drain, the edges). Measured against full runs
   * (results/speed-accuracy) it stays within a few tenths of a percent, so
   * figures made of cycles carry a systematic +-SAMPLE_SYSTEMATIC, added in
   * quadrature; without it an issue-bound run's interval is narrower than
   * that bias. */
  if (f == SF_CYCLES || f == SF_BYTES_PER_CYCLE || f == SF_UTIL || f == SF_RAYS_PER_S ||
      f == SF_ENERGY || f == SF_POWER) /* (leakage and DRAM background follow cycles) */
    half = hypot(half, SAMPLE_SYSTEMATIC * v);
  struct est e = {v, v - half, v + half};
  return e;
}

/* The cycles' auxiliary figure: the work (issue slots) where the cores
 * bound the run, the footprint where the memory does; which one tracks the
 * units' cycles better shows in the interval each gives, and the narrower
 * is taken (the energy follows, its leakage and background being cycles). */
static void choose_cyc_aux(struct sampler *s) {
  double best = INFINITY;
  unsigned pick = SA_SLOTS;
  const unsigned cand[] = {SA_SLOTS, SA_DRAM};
  for (unsigned i = 0; i < 2; i++) {
    s->cyc_aux = cand[i];
    const struct est e = estimate(s, SF_CYCLES);
    if (e.hi - e.lo < best) {
      best = e.hi - e.lo;
      pick = cand[i];
    }
  }
  s->cyc_aux = pick;
}

/* e with each of its three numbers moved into [lo, hi]. */
static struct est clamp_est(struct est e, double lo, double hi) {
  const double x[3] = {e.v, e.lo, e.hi};
  double c[3];
  for (int i = 0; i < 3; i++) c[i] = x[i] < lo ? lo : x[i] > hi ? hi : x[i];
  struct est r = {c[0], c[1], c[2]};
  return r;
}

/* The fewest cycles the run can have taken: its issue slots over the cores
 * (a core issues one slot a cycle), and the cycles the units took (they are
 * part of the run: each unit's measured cycles, which do not overlap). */
static double min_cycles(const struct sampler *s) {
  double units = 0;
  for (uint32_t h = 0; h < s->n; h++) units += delta(&s->u[h], SQ_CYCLES);
  const double issue = (double)s->slots_total / s->cores;
  return issue > units ? issue : units;
}

double sample_dram_bytes(const struct sampler *s, double *lo, double *hi) {
  double own = 0;
  for (uint32_t h = 0; h < s->n; h++) own += delta(&s->u[h], SQ_DRAM_BYTES);
  struct est e = clamp_est(estimate(s, SF_DRAM_BYTES), own, INFINITY);
  *lo = e.lo;
  *hi = e.hi;
  return e.v;
}

/* The run's energy, J: at least what the units spent themselves. */
static struct est energy_est(const struct sampler *s) {
  double own = 0;
  for (uint32_t h = 0; h < s->n; h++) own += delta(&s->u[h], SQ_ENERGY_FJ);
  const struct est e = clamp_est(estimate(s, SF_ENERGY), own, INFINITY);
  const struct est j = {e.v / FJ_PER_J, e.lo / FJ_PER_J, e.hi / FJ_PER_J};
  return j;
}

double sample_cycles(const struct sampler *s, double *lo, double *hi) {
  struct est e = clamp_est(estimate(s, SF_CYCLES), min_cycles(s), INFINITY);
  *lo = e.lo;
  *hi = e.hi;
  return e.v;
}

/* ---- the sampled run's numbers (docs/stats.md, component sampled) ----
 * st: the struct sampler; env->ctx: the struct sample_env below. Each
 * estimate is three numbers: NAME, NAME_ci95_low and NAME_ci95_high. */

struct sample_env {
  double clock_ghz;
  double peak; /* the DRAM's peak bytes a cycle (0: none) */
  uint64_t contexts, threads;
};

/* The estimates written: sample_fig's and two made of them. */
enum sample_out {
  SO_SLOTS,
  SO_RAYS,
  SO_CYCLES,
  SO_SECONDS,
  SO_RAYS_PER_S,
  SO_UTIL,
  SO_DRAM_BYTES,
  SO_BYTES_PER_CYCLE,
  SO_DRAM_UTIL,
  SO_LOAD_LAT,
  SO_ENERGY,
  SO_POWER
};

/* Output o's estimate and interval, each number within the range its figure
 * can take (a linearized interval is symmetric and knows no range; from a
 * wide spread it reached below zero): cycles and seconds at least
 * min_cycles, utilizations in [0, 1] and at most what min_cycles allows,
 * DRAM bytes at least the units' own, the rest at least 0. */
static struct est est_of(const void *st, const struct stats_env *env, enum sample_out o) {
  const struct sampler *s = st;
  const struct sample_env *x = env->ctx;
  const double hz = derived_hz(x->clock_ghz), c0 = min_cycles(s);
  struct est e;
  switch (o) {
  case SO_CYCLES: return clamp_est(estimate(s, SF_CYCLES), c0, INFINITY);
  case SO_SECONDS: {
    e = clamp_est(estimate(s, SF_CYCLES), c0, INFINITY);
    struct est sec = {e.v / hz, e.lo / hz, e.hi / hz};
    return sec;
  }
  /* What was traced is at least what the image holds. */
  case SO_SLOTS: return clamp_est(estimate(s, SF_SLOTS), (double)s->slots_total, INFINITY);
  case SO_RAYS: return clamp_est(estimate(s, SF_RAYS), (double)s->rays_total, INFINITY);
  case SO_RAYS_PER_S:
    return clamp_est(estimate(s, SF_RAYS_PER_S), 0,
                     s->whole ? (double)s->rays_total / (c0 / hz) : INFINITY);
  case SO_UTIL: {
    const double top = s->whole ? (double)s->slots_total / (c0 * s->cores) : 1;
    return clamp_est(estimate(s, SF_UTIL), 0, top < 1 ? top : 1);
  }
  case SO_DRAM_BYTES: {
    struct est d;
    d.v = sample_dram_bytes(s, &d.lo, &d.hi);
    return d;
  }
  case SO_BYTES_PER_CYCLE: return clamp_est(estimate(s, SF_BYTES_PER_CYCLE), 0, INFINITY);
  case SO_DRAM_UTIL: {
    e = estimate(s, SF_BYTES_PER_CYCLE);
    struct est u = {e.v / x->peak, e.lo / x->peak, e.hi / x->peak};
    return clamp_est(u, 0, 1);
  }
  case SO_ENERGY: return energy_est(s);
  case SO_POWER: { /* (the femtojoules' watts) */
    e = clamp_est(estimate(s, SF_POWER), 0, INFINITY);
    struct est w = {e.v / FJ_PER_J, e.lo / FJ_PER_J, e.hi / FJ_PER_J};
    return w;
  }
  default: return clamp_est(estimate(s, SF_LOAD_LAT), 0, INFINITY);
  }
}

#define SAMPLE_EST(o)                                                                              \
  static double o##_v(const void *st, const struct stats_env *env) {                               \
    return est_of(st, env, o).v;                                                                   \
  }                                                                                                \
  static double o##_lo(const void *st, const struct stats_env *env) {                              \
    return est_of(st, env, o).lo;                                                                  \
  }                                                                                                \
  static double o##_hi(const void *st, const struct stats_env *env) {                              \
    return est_of(st, env, o).hi;                                                                  \
  }
SAMPLE_EST(SO_SLOTS)
SAMPLE_EST(SO_RAYS)
SAMPLE_EST(SO_CYCLES)
SAMPLE_EST(SO_SECONDS)
SAMPLE_EST(SO_RAYS_PER_S)
SAMPLE_EST(SO_UTIL)
SAMPLE_EST(SO_DRAM_BYTES)
SAMPLE_EST(SO_BYTES_PER_CYCLE)
SAMPLE_EST(SO_DRAM_UTIL)
SAMPLE_EST(SO_LOAD_LAT)
SAMPLE_EST(SO_ENERGY)
SAMPLE_EST(SO_POWER)
#undef SAMPLE_EST

static bool has_peak(const void *st, const struct stats_env *env) {
  (void)st;
  return ((const struct sample_env *)env->ctx)->peak > 0;
}
static uint64_t s_contexts(const void *st, const struct stats_env *env) {
  (void)st;
  return ((const struct sample_env *)env->ctx)->contexts;
}
static uint64_t s_threads(const void *st, const struct stats_env *env) {
  (void)st;
  return ((const struct sample_env *)env->ctx)->threads;
}
static double items_fraction(const void *st, uint64_t n) {
  return (double)n / (double)((const struct sampler *)st)->total;
}
static double s_detailed(const void *st, const struct stats_env *env) {
  (void)env;
  return items_fraction(st, ((const struct sampler *)st)->detailed);
}
static double s_measured(const void *st, const struct stats_env *env) {
  (void)env;
  return items_fraction(st, ((const struct sampler *)st)->measured);
}
static double s_traced(const void *st, const struct stats_env *env) {
  (void)env;
  return items_fraction(st, ((const struct sampler *)st)->traced);
}
static double s_warmed(const void *st, const struct stats_env *env) {
  (void)env;
  return items_fraction(st, ((const struct sampler *)st)->warmed);
}
static double s_prepass(const void *st, const struct stats_env *env) {
  (void)env;
  const struct sampler *s = st;
  return items_fraction(st, s->aux ? s->aux->traced : 0);
}
static double s_detailed_slots(const void *st, const struct stats_env *env) {
  (void)env;
  const struct sampler *s = st;
  return (double)s->slots_detailed / (double)(s->slots_total ? s->slots_total : 1);
}
static uint64_t s_units(const void *st, const struct stats_env *env) {
  (void)env;
  return ((const struct sampler *)st)->n;
}

/* An estimate and its interval's two ends. */
#define EST(o, nm, un, ds, pres)                                                                   \
  {.name = nm, .unit = un, .desc = ds, .how = STATS_HOW_F64, .f64 = o##_v, .present = pres},       \
      {.name = nm "_ci95_low",                                                                     \
       .unit = un,                                                                                 \
       .desc = "the low end of the 95% interval of " nm,                                           \
       .how = STATS_HOW_F64,                                                                       \
       .f64 = o##_lo,                                                                              \
       .present = pres},                                                                           \
  {                                                                                                \
    .name = nm "_ci95_high", .unit = un, .desc = "the high end of the 95% interval of " nm,        \
    .how = STATS_HOW_F64, .f64 = o##_hi, .present = pres                                           \
  }
static const struct stats_desc sample_desc[] = {
    STATS_FN_U64(s_contexts, "ray_contexts", "count", "ray contexts: cores x threads x rays"),
    STATS_FN_U64(s_threads, "threads", "count", "hardware threads: cores x threads_per_core"),
    EST(SO_CYCLES, "cycles", "cycles", "the run's cycles, estimated", NULL),
    EST(SO_SECONDS, "seconds", "seconds", "the run at clock_ghz, estimated", NULL),
    EST(SO_RAYS, "rays_traced", "count",
        "rays of the whole image, every kind (with sample.image whole, traced and exact: the "
        "interval is the value)",
        NULL),
    EST(SO_RAYS_PER_S, "rays_per_second", "per second", "rays traced / seconds, estimated", NULL),
    EST(SO_SLOTS, "issue_slots", "cycles",
        "issue slots the whole image takes (with sample.image whole, counted and exact: the "
        "interval is the value)",
        NULL),
    EST(SO_UTIL, "core_utilization", "fraction", "issue slots / cores x cycles, estimated", NULL),
    EST(SO_DRAM_BYTES, "dram_bytes", "bytes", "bytes read from and written to the DRAM, estimated",
        NULL),
    EST(SO_BYTES_PER_CYCLE, "dram_bytes_per_cycle", "bytes/cycle", "DRAM bytes / cycles, estimated",
        NULL),
    EST(SO_DRAM_UTIL, "dram_utilization", "fraction",
        "dram_bytes_per_cycle / the DRAM's peak, estimated (a DRAM with a peak)", has_peak),
    EST(SO_LOAD_LAT, "load_latency_mean", "cycles", "a load's latency, mean, estimated", NULL),
    EST(SO_ENERGY, "energy_j", "J",
        "the chip's and the DRAM's energy, estimated (at least the units' own)", NULL),
    EST(SO_POWER, "power_w", "W", "energy_j / seconds, estimated", NULL),
    STATS_FIELD(struct sampler, total, "sample_work_items", "count",
                "work items (pixels or tiles) of the run"),
    STATS_FN_U64(s_units, "sample_units_measured", "count", "units simulated in detail"),
    STATS_FN_F64(s_detailed, "sample_detailed_fraction", "fraction",
                 "work items simulated in detail (warm-up included) / work items"),
    STATS_FN_F64(s_measured, "sample_measured_fraction", "fraction",
                 "work items measured / work items"),
    STATS_FN_F64(s_warmed, "sample_warmed_fraction", "fraction",
                 "work items warmed without time / work items"),
    STATS_FN_F64(s_traced, "sample_traced_fraction", "fraction",
                 "work items traced (detailed, warmed or counted) / work items"),
    STATS_FN_F64(s_prepass, "sample_prepass_fraction", "fraction",
                 "work items traced by the pre-pass (no time, auxiliary figures) / work items"),
    STATS_FN_F64(s_detailed_slots, "sample_detailed_slots_fraction", "fraction",
                 "issue slots simulated in detail / issue slots traced"),
};
#undef EST
const struct stats_descs sample_stats_descs = {"sampled", sample_desc, STATS_COUNT(sample_desc),
                                               0,         NULL,        0};

void sample_stats(const struct sampler *s, double clock_ghz, double peak_bytes_per_cycle,
                  uint64_t contexts, uint64_t threads, struct stats_table *t) {
  const struct sample_env x = {clock_ghz, peak_bytes_per_cycle, contexts, threads};
  const struct stats_env env = {.ctx = &x};
  stats_emit(t, &sample_stats_descs, s, &env);
}
