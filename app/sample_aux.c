/* Sampling's pre-pass: the auxiliary figures of the middle units' windows
 * and of a systematic sample of the rest (sample_aux.h says the design). */
#include "app/sample_aux.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "app/app.h"
#include "app/sample_fl2.h"
#include "renderer/rng.h"
#include "sim/err.h"
#include "sim/line.h"
#include "sim/machine_cfg.h"

/* The L2 model follows one set in this many (sample_fl2.h): against all
 * sets on grove 256x256 at the memory-bound point (512 ray contexts, a
 * 512 KiB L2) the whole image's modelled DRAM bytes came out 3% higher, and
 * the units' the same (the ratio estimator takes their quotient), at a
 * ninth of the replay's cost. */
#define SAMPLE_AUX_SETS_EVERY 8u

/* The dense sample: one item in this many of the rest, traced alone for its
 * issue slots and rays (no L2 model: a twentieth of a native render's cost
 * at 1 in 16). The stretches' modelled DRAM bytes per issue slot vary half
 * as much from stretch to stretch as their bytes per item (grove 256x256 at
 * the memory-bound point, stretches of 64: 20% and 35% between neighbours),
 * so the middle's modelled bytes are taken as that ratio times the dense
 * sample's issue slots. */
#define SAMPLE_AUX_DENSE_EVERY 16u

/* The pre-pass's state: the current item's counts and where they go. */
struct prepass {
  const struct sampler *s;
  struct sample_aux *x;
  struct policy_worker *wk;
  struct sfl2 *l2;
  double cur[SA_COUNT]; /* the item being traced */
  double *dst;          /* where its counts go (NULL: a warming item, or none yet) */
  double *dense;        /* and where else (NULL: not in the dense sample) */
  uint64_t rays0;       /* the worker's rays when it began */
  uint64_t last;        /* the last item traced + 1 (0: none) */
  uint32_t since_pump;  /* items recorded since the L2 model last ran */
  uint32_t contexts;
};

static void close_item(struct prepass *pp) {
  pp->cur[SA_RAYS] = (double)(render_stats_total(&pp->wk->st) - pp->rays0);
  for (unsigned a = 0; a < SA_COUNT; a++) {
    if (a == SA_DRAM) continue;
    if (pp->dst) pp->dst[a] += pp->cur[a];
    if (pp->dense) pp->dense[a] += pp->cur[a];
  }
  pp->dst = pp->dense = NULL;
}

static void pp_load(void *ctx, uint64_t addr, uint32_t size, unsigned cls) {
  struct prepass *pp = ctx;
  (void)cls;
  pp->cur[SA_SLOTS]++;
  sfl2_access(pp->l2, addr, size, false);
}

static void pp_store(void *ctx, uint64_t addr, uint32_t size, unsigned cls) {
  struct prepass *pp = ctx;
  (void)cls;
  pp->cur[SA_SLOTS]++;
  sfl2_access(pp->l2, addr, size, true);
}

static void pp_compute(void *ctx, uint64_t cycles) {
  ((struct prepass *)ctx)->cur[SA_SLOTS] += (double)cycles;
}

static const struct mem_ops pp_ops = {pp_load, pp_store, pp_compute, NULL, NULL, NULL};

/* An item of the dense sample only: its issue slots counted, nothing
 * recorded for the L2 model. */
static void pp_count(void *ctx, uint64_t addr, uint32_t size, unsigned cls) {
  (void)addr;
  (void)size;
  (void)cls;
  ((struct prepass *)ctx)->cur[SA_SLOTS]++;
}

static const struct mem_ops pp_count_ops = {pp_count, pp_count, pp_compute, NULL, NULL, NULL};

/* The middle unit whose detailed items hold k, or 0 (none). */
static uint32_t window_of(const struct sampler *s, uint64_t k) {
  uint32_t lo = 1, hi = s->n - 1; /* middle units: [1, n - 1), in order */
  while (lo < hi) {
    const uint32_t mid = lo + (hi - lo) / 2;
    if (s->u[mid].end <= k) lo = mid + 1;
    else hi = mid;
  }
  return lo < s->n - 1 && k >= s->u[lo].start && k < s->u[lo].end ? lo : 0;
}

/* The first middle unit whose window starts after k (n - 1: none). */
static uint32_t unit_after(const struct sampler *s, uint64_t k) {
  uint32_t lo = 1, hi = s->n - 1;
  while (lo < hi) {
    const uint32_t mid = lo + (hi - lo) / 2;
    if (s->u[mid].start <= k) lo = mid + 1;
    else hi = mid;
  }
  return lo;
}

/* Where item k of the middle stands in the stretches: the stretch whose
 * counted items hold it (its index), else SIZE_MAX. */
static uint64_t stretch_of(const struct sample_aux *x, uint64_t k) {
  const uint64_t off = k - x->lo + x->period - x->phase;
  return off % x->period < x->len ? off / x->period : UINT64_MAX;
}

/* True when item k warms: within `warm` items before a stretch or a middle
 * unit's window. No item after a stretch warms: the L2 model keeps every
 * context busy with fillers until the stretch's last counted item ends
 * (SFL2_REFILL), however long it runs, at no tracing cost. */
static bool warms(const struct sampler *s, const struct sample_aux *x, uint64_t k) {
  const uint64_t off = k - x->lo + x->period - x->phase;
  if (x->period - off % x->period <= x->warm) return true;
  const uint32_t h = unit_after(s, k);
  return h + 1 < s->n && s->u[h].start - k <= x->warm;
}

static enum policy_item pp_item(void *ctx, uint64_t k, uint32_t core, struct mem_port *port) {
  struct prepass *pp = ctx;
  struct sample_aux *x = pp->x;
  (void)core;
  close_item(pp);
  if (k < x->lo || k >= x->hi) return POLICY_ITEM_SKIP;
  const uint32_t h = window_of(pp->s, k);
  const uint64_t i = h ? UINT64_MAX : stretch_of(x, k);
  double *dense = NULL;
  if (!h && x->dense_every && (k + x->dense_phase) % x->dense_every == 0)
    dense = &x->dense[x->n_dense++ * SA_COUNT];
  double *dst = NULL;
  if (h) dst = &x->unit[h * SA_COUNT];
  else if (i != UINT64_MAX) dst = &x->sparse[i * SA_COUNT];
  else if (!warms(pp->s, x, k)) {
    if (!dense) return POLICY_ITEM_SKIP;
    pp->dense = dense;
    x->traced++;
    memset(pp->cur, 0, sizeof pp->cur);
    pp->rays0 = render_stats_total(&pp->wk->st);
    *port = (struct mem_port){&pp_count_ops, pp};
    return POLICY_ITEM_PORT;
  }
  if (!h && i != UINT64_MAX) x->sparse_n[i]++;
  pp->dense = dense;
  /* A gap ends the L2 model's batch (the next starts from the caches it
   * left, then warms),
   * and so does a unit's end. A unit's batch drains (its last items run
   * with ever fewer others, as in the timed unit, whose bytes calibrate the
   * model over the same items); a stretch's is refilled (its last items
   * share the L2 as in the full run). */
  const uint32_t before = pp->last ? window_of(pp->s, pp->last - 1) : 0;
  if (pp->last != k || (before && before != h))
    sfl2_pump(pp->l2, before ? SFL2_DRAIN : SFL2_REFILL);
  else if (++pp->since_pump >= pp->contexts) {
    sfl2_pump(pp->l2, SFL2_MORE);
    pp->since_pump = 0;
  }
  pp->last = k + 1;
  sfl2_item(pp->l2, dst ? &dst[SA_DRAM] : NULL);
  pp->dst = dst;
  x->traced++;
  memset(pp->cur, 0, sizeof pp->cur);
  pp->rays0 = render_stats_total(&pp->wk->st);
  return POLICY_ITEM_DETAIL;
}

/* The items of the rest and the room its stretches need. */
static void plan(struct sample_aux *x, const struct sampler *s) {
  x->lo = s->u[0].end;
  x->hi = s->u[s->n - 1].measure;
  uint64_t windows = 0;
  for (uint32_t h = 1; h + 1 < s->n; h++) windows += s->u[h].end - s->u[h].start;
  x->pop = x->hi - x->lo - windows;
  x->unit = xcalloc((size_t)s->n * SA_COUNT, sizeof *x->unit);
  x->n_sparse = (x->hi - x->lo + x->period - x->phase) / x->period + 1;
  x->sparse = xcalloc((size_t)x->n_sparse * SA_COUNT, sizeof *x->sparse);
  x->sparse_n = xcalloc((size_t)x->n_sparse, sizeof *x->sparse_n);
  if (x->dense_every)
    x->dense = xcalloc((size_t)((x->hi - x->lo) / x->dense_every + 1) * SA_COUNT, sizeof *x->dense);
}

/* The stretches that counted no item (cut by a unit's window, or past the
 * middle's end) are dropped: the rest keep their order. */
static void squeeze(struct sample_aux *x) {
  uint64_t w = 0;
  for (uint64_t i = 0; i < x->n_sparse; i++) {
    if (!x->sparse_n[i]) continue;
    memmove(&x->sparse[w * SA_COUNT], &x->sparse[i * SA_COUNT], SA_COUNT * sizeof *x->sparse);
    x->sparse_n[w++] = x->sparse_n[i];
  }
  x->n_sparse = w;
}

struct sample_aux_plan sample_aux_plan_of(const struct machine_cfg_sample *c, uint32_t contexts) {
  struct sample_aux_plan p;
  p.every = c->prepass ? c->prepass : 1;
  p.len = c->stretch ? c->stretch : contexts;
  p.warm = (uint64_t)llround(c->stretch_warming * contexts);
  return p;
}

void sample_aux_run(struct sampler *s, const struct sample_aux_plan *sp, uint64_t seed_units,
                    const struct machine_params *mp, const struct app_world *w, uint32_t mask,
                    uint64_t seed, uint32_t width, uint32_t height, enum policy_kind k,
                    const struct policy_params *p, const struct machine_cfg_work *work) {
  CHECK_GE(sp->every, 1);
  CHECK_GE(sp->len, 1);
  const double t0 = app_now();
  struct sample_aux *x = xcalloc(1, sizeof *x);
  x->every = sp->every;
  x->len = sp->len;
  x->period = sp->len * sp->every;
  x->warm = sp->warm;
  x->phase = rng_hash2(seed_units, 0x5A4D) % x->period;
  x->dense_every = SAMPLE_AUX_DENSE_EVERY;
  x->dense_phase = rng_hash2(seed_units, 0xDE5E) % x->dense_every;
  plan(x, s);
  struct app_render ar; /* its own framebuffer: the pre-pass leaves no pixel */
  app_render_init(&ar, w, mask, seed, width, height);
  ar.setup.layout.node_cycles = work->cost_node_cycles;
  ar.setup.layout.tri_cycles = work->cost_triangle_cycles;
  ar.sc.shade_cycles = work->cost_shade_cycles;
  struct policy_worker wk;
  struct prepass pp = {.s = s, .x = x, .wk = &wk, .l2 = NULL};
  pp.l2 = sfl2_create(mp, SAMPLE_AUX_SETS_EVERY,
                      (uint32_t)(rng_hash2(seed_units, 0x5E75) % SAMPLE_AUX_SETS_EVERY));
  pp.contexts = mp->cores * mp->threads_per_core * mp->rays_per_thread;
  ar.setup.item = pp_item;
  ar.setup.item_ctx = &pp;
  struct policy_job *job = policy_job_create(k, &ar.setup, p, 1, 1);
  const struct mem_port port = {&pp_ops, &pp};
  policy_worker_init(&wk, job, 0, 0, 0, port);
  CHECK(!policy_job_work(job, &wk)); /* one worker never parks */
  close_item(&pp);
  sfl2_pump(pp.l2, pp.last && window_of(s, pp.last - 1) ? SFL2_DRAIN : SFL2_REFILL);
  x->replayed = sfl2_replayed(pp.l2);
  sfl2_destroy(pp.l2);
  squeeze(x);
  policy_worker_fini(job, &wk);
  struct render_stats st;
  struct trace_stats ts;
  policy_job_finish(job, &st, &ts);
  policy_job_destroy(job);
  app_render_fini(&ar);
  for (uint32_t h = 1; h + 1 < s->n; h++)
    for (unsigned a = 0; a < SA_COUNT; a++) x->exact[a] += x->unit[h * SA_COUNT + a];
  x->wall_s = app_now() - t0;
  s->aux = x;
}

/* Stretch i's counted items. */
static double items_of(const struct sample_aux *x, uint64_t i) {
  return x->sparse_n ? (double)x->sparse_n[i] : 1;
}

/* sum_a g[a] x value_a of row r of a table of SA_COUNT columns. */
static double dot(const double *r, const double g[SA_COUNT]) {
  double v = 0;
  for (unsigned a = 0; a < SA_COUNT; a++) v += g[a] * r[a];
  return v;
}

/* The stretches' ratio of sum_a g[a] x a to `per` (an auxiliary: the
 * stretches' issue slots; or, per < 0, their counted items). */
static double stretch_ratio(const struct sample_aux *x, const double g[SA_COUNT], int per) {
  double v = 0, m = 0;
  for (uint64_t i = 0; i < x->n_sparse; i++) {
    v += dot(&x->sparse[i * SA_COUNT], g);
    m += per < 0 ? items_of(x, i) : x->sparse[i * SA_COUNT + per];
  }
  return m > 0 ? v / m : 0;
}

/* The dense sample's mean of sum_a g[a] x a over its items. */
static double dense_mean(const struct sample_aux *x, const double g[SA_COUNT]) {
  double v = 0;
  for (uint64_t i = 0; i < x->n_dense; i++) v += dot(&x->dense[i * SA_COUNT], g);
  return x->n_dense ? v / (double)x->n_dense : 0;
}

/* With a dense sample: g's modelled-bytes part taken through the stretches'
 * bytes per issue slot (R), the rest per item from the dense sample; g' =
 * g with its DRAM weight moved onto the slots (x R). */
static void through_slots(const struct sample_aux *x, const double g[SA_COUNT], double gs[SA_COUNT],
                          double *r) {
  double gd[SA_COUNT] = {0};
  gd[SA_DRAM] = 1;
  *r = stretch_ratio(x, gd, SA_SLOTS);
  for (unsigned a = 0; a < SA_COUNT; a++) gs[a] = g[a];
  gs[SA_DRAM] = 0;
  gs[SA_SLOTS] += g[SA_DRAM] * *r;
}

double sample_aux_total(const struct sample_aux *x, unsigned a) {
  double g[SA_COUNT] = {0};
  g[a] = 1;
  if (x->n_dense) {
    double gs[SA_COUNT], r;
    through_slots(x, g, gs, &r);
    return x->exact[a] + dense_mean(x, gs) * (double)x->pop;
  }
  return x->exact[a] + stretch_ratio(x, g, -1) * (double)x->pop;
}

/* The variance of a systematic sample's estimate of a total of N units from
 * n values e_i in order (successive differences, finite population
 * correction). */
static double sys_var(double N, const double *e, uint64_t n) {
  if (n < 2) return 0;
  double ss = 0;
  for (uint64_t i = 1; i < n; i++) ss += (e[i] - e[i - 1]) * (e[i] - e[i - 1]);
  const double s2 = ss / (2.0 * (double)(n - 1)), fpc = 1 - (double)n / N;
  return N * N * (fpc > 0 ? fpc : 0) * s2 / (double)n;
}

/* The stretches' residuals against the ratio r to `per` (as stretch_ratio),
 * scaled to what they say of the rest's total: the variance of r x (the
 * rest's `per`), clusters of mean size standing for pop / that size. */
static double stretch_var(const struct sample_aux *x, const double g[SA_COUNT], int per,
                          double scale) {
  const uint64_t n = x->n_sparse;
  if (n < 2) return 0;
  const double r = stretch_ratio(x, g, per);
  double *e = xcalloc(n, sizeof *e), m = 0;
  for (uint64_t i = 0; i < n; i++) {
    const double size = per < 0 ? items_of(x, i) : x->sparse[i * SA_COUNT + per];
    e[i] = dot(&x->sparse[i * SA_COUNT], g) - r * size;
    m += items_of(x, i);
  }
  const double v = sys_var((double)x->pop * (double)n / m, e, n);
  free(e);
  return v * scale * scale;
}

double sample_aux_var(const struct sample_aux *x, const double g[SA_COUNT]) {
  if (!x->n_dense) return stretch_var(x, g, -1, 1);
  /* Two independent parts: the dense sample's items (of g with its DRAM
   * weight on the slots) and the stretches' ratio R, whose error spreads
   * over the rest's issue slots: d total / d R = g_DRAM x (the rest's slots);
   * the stretches' residuals against R sum to their slots x (R's error). */
  double gs[SA_COUNT], r;
  through_slots(x, g, gs, &r);
  double *v = xcalloc(x->n_dense ? x->n_dense : 1, sizeof *v);
  for (uint64_t i = 0; i < x->n_dense; i++) v[i] = dot(&x->dense[i * SA_COUNT], gs);
  const double dense = sys_var((double)x->pop, v, x->n_dense);
  free(v);
  double gd[SA_COUNT] = {0}, gsl[SA_COUNT] = {0}, sl = 0;
  gd[SA_DRAM] = g[SA_DRAM];
  gsl[SA_SLOTS] = 1;
  for (uint64_t i = 0; i < x->n_sparse; i++) sl += x->sparse[i * SA_COUNT + SA_SLOTS];
  /* The stretches' residual sum stands for (pop / their items) x their
   * slots x R's error; the rest's slots over the stretches' puts it on the
   * rest: scale = rest slots / (stretches' slots x pop / their items). */
  double items = 0;
  for (uint64_t i = 0; i < x->n_sparse; i++) items += items_of(x, i);
  const double rest_slots = dense_mean(x, gsl) * (double)x->pop;
  const double scale = sl > 0 && items > 0 ? rest_slots / (sl * (double)x->pop / items) : 0;
  return dense + stretch_var(x, gd, SA_SLOTS, scale);
}

void sample_aux_free(struct sample_aux *x) {
  if (!x) return;
  free(x->unit);
  free(x->sparse);
  free(x->sparse_n);
  free(x->dense);
  free(x);
}
