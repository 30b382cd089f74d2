/* Sampling's pre-pass: the auxiliary figures of the middle units' windows
 * and of a systematic sample of the rest (sample_aux.h says the design). */
#include "app/sample_aux.h"

#include <stdlib.h>
#include <string.h>

#include "app/app.h"
#include "renderer/rng.h"
#include "sim/err.h"
#include "sim/line.h"
#include "sim/machine_cfg.h"

/* The distinct lines one item touches: an open-addressed set whose entries
 * belong to the item whose generation they carry (a new item empties it by
 * taking the next generation); it doubles when half full. */
struct lineset {
  uint64_t *key;
  uint32_t *gen;
  uint32_t cap, n, cur;
};

static void lineset_init(struct lineset *l, uint32_t cap) {
  l->key = xcalloc(cap, sizeof *l->key);
  l->gen = xcalloc(cap, sizeof *l->gen);
  l->cap = cap;
  l->n = 0;
  l->cur = 1;
}

static void lineset_fini(struct lineset *l) {
  free(l->key);
  free(l->gen);
}

static uint32_t slot_of(const struct lineset *l, uint64_t line) {
  uint32_t i = (uint32_t)(rng_hash2(line, 0) & (l->cap - 1));
  while (l->gen[i] == l->cur && l->key[i] != line) i = (i + 1) & (l->cap - 1);
  return i;
}

static void lineset_grow(struct lineset *l) {
  struct lineset g;
  lineset_init(&g, 2 * l->cap);
  for (uint32_t i = 0; i < l->cap; i++)
    if (l->gen[i] == l->cur) {
      const uint32_t j = slot_of(&g, l->key[i]);
      g.key[j] = l->key[i];
      g.gen[j] = g.cur;
    }
  g.n = l->n;
  lineset_fini(l);
  *l = g;
}

/* True when line is new to the current item. */
static int lineset_add(struct lineset *l, uint64_t line) {
  const uint32_t i = slot_of(l, line);
  if (l->gen[i] == l->cur) return 0;
  l->gen[i] = l->cur;
  l->key[i] = line;
  if (2 * ++l->n > l->cap) lineset_grow(l);
  return 1;
}

static void lineset_next(struct lineset *l) {
  l->n = 0;
  if (++l->cur == 0) { /* (the generations wrapped: start the stamps over) */
    memset(l->gen, 0, l->cap * sizeof *l->gen);
    l->cur = 1;
  }
}

/* The pre-pass's state: the current item's counts and where they go. */
struct prepass {
  const struct sampler *s;
  struct sample_aux *x;
  struct policy_worker *wk;
  struct lineset lines;
  double cur[SA_COUNT]; /* the item being traced */
  double *dst;          /* where its counts go (NULL: none traced yet) */
  uint64_t rays0;       /* the worker's rays when it began */
};

static void close_item(struct prepass *pp) {
  if (!pp->dst) return;
  pp->cur[SA_RAYS] = (double)(render_stats_total(&pp->wk->st) - pp->rays0);
  pp->cur[SA_LINES] = pp->lines.n;
  for (unsigned a = 0; a < SA_COUNT; a++) pp->dst[a] += pp->cur[a];
  pp->dst = NULL;
}

static void pp_access(void *ctx, uint64_t addr, uint32_t size, unsigned cls) {
  struct prepass *pp = ctx;
  (void)cls;
  pp->cur[SA_SLOTS]++;
  for (uint64_t line = addr >> SIM_LINE_LG2, end = (addr + size - 1) >> SIM_LINE_LG2; line <= end;
       line++)
    lineset_add(&pp->lines, line);
}

static void pp_compute(void *ctx, uint64_t cycles) {
  ((struct prepass *)ctx)->cur[SA_SLOTS] += (double)cycles;
}

static const struct mem_ops pp_ops = {pp_access, pp_access, pp_compute, NULL, NULL, NULL};

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

static enum policy_item pp_item(void *ctx, uint64_t k, uint32_t core, struct mem_port *port) {
  struct prepass *pp = ctx;
  struct sample_aux *x = pp->x;
  (void)core;
  (void)port;
  close_item(pp);
  if (k < x->lo || k >= x->hi) return POLICY_ITEM_SKIP;
  const uint32_t h = window_of(pp->s, k);
  if (h) pp->dst = &x->unit[h * SA_COUNT];
  else if ((k + x->phase) % x->every == 0) pp->dst = &x->sparse[x->n_sparse++ * SA_COUNT];
  else return POLICY_ITEM_SKIP;
  x->traced++;
  memset(pp->cur, 0, sizeof pp->cur);
  lineset_next(&pp->lines);
  pp->rays0 = render_stats_total(&pp->wk->st);
  return POLICY_ITEM_DETAIL;
}

/* The items of the rest and the room its sample needs. */
static void plan(struct sample_aux *x, const struct sampler *s) {
  x->lo = s->u[0].end;
  x->hi = s->u[s->n - 1].measure;
  uint64_t windows = 0;
  for (uint32_t h = 1; h + 1 < s->n; h++) windows += s->u[h].end - s->u[h].start;
  x->pop = x->hi - x->lo - windows;
  x->unit = xcalloc((size_t)s->n * SA_COUNT, sizeof *x->unit);
  x->sparse = xcalloc((size_t)((x->hi - x->lo) / x->every + 1) * SA_COUNT, sizeof *x->sparse);
}

void sample_aux_run(struct sampler *s, uint32_t every, uint64_t seed_units,
                    const struct app_world *w, uint32_t mask, uint64_t seed, uint32_t width,
                    uint32_t height, enum policy_kind k, const struct policy_params *p,
                    const struct machine_cfg_work *work) {
  CHECK_GE(every, 1);
  const double t0 = app_now();
  struct sample_aux *x = xcalloc(1, sizeof *x);
  x->every = every;
  x->phase = (uint32_t)(rng_hash2(seed_units, 0x5A4D) % every);
  plan(x, s);
  struct app_render ar; /* its own framebuffer: the pre-pass leaves no pixel */
  app_render_init(&ar, w, mask, seed, width, height);
  ar.setup.layout.node_cycles = work->cost_node_cycles;
  ar.setup.layout.tri_cycles = work->cost_triangle_cycles;
  ar.sc.shade_cycles = work->cost_shade_cycles;
  struct policy_worker wk;
  struct prepass pp = {.s = s, .x = x, .wk = &wk};
  lineset_init(&pp.lines, 1u << 14);
  ar.setup.item = pp_item;
  ar.setup.item_ctx = &pp;
  struct policy_job *job = policy_job_create(k, &ar.setup, p, 1, 1);
  const struct mem_port port = {&pp_ops, &pp};
  policy_worker_init(&wk, job, 0, 0, 0, port);
  CHECK(!policy_job_work(job, &wk)); /* one worker never parks */
  close_item(&pp);
  policy_worker_fini(job, &wk);
  struct render_stats st;
  struct trace_stats ts;
  policy_job_finish(job, &st, &ts);
  policy_job_destroy(job);
  app_render_fini(&ar);
  lineset_fini(&pp.lines);
  for (uint32_t h = 1; h + 1 < s->n; h++)
    for (unsigned a = 0; a < SA_COUNT; a++) x->exact[a] += x->unit[h * SA_COUNT + a];
  x->wall_s = app_now() - t0;
  s->aux = x;
}

double sample_aux_total(const struct sample_aux *x, unsigned a) {
  double sum = 0;
  for (uint64_t i = 0; i < x->n_sparse; i++) sum += x->sparse[i * SA_COUNT + a];
  return x->exact[a] + (x->n_sparse ? sum * (double)x->pop / (double)x->n_sparse : 0);
}

double sample_aux_var(const struct sample_aux *x, const double g[SA_COUNT]) {
  const uint64_t n = x->n_sparse;
  if (n < 2) return 0;
  double prev = 0, ss = 0;
  for (uint64_t i = 0; i < n; i++) {
    double v = 0;
    for (unsigned a = 0; a < SA_COUNT; a++) v += g[a] * x->sparse[i * SA_COUNT + a];
    if (i) ss += (v - prev) * (v - prev);
    prev = v;
  }
  const double N = (double)x->pop, s2 = ss / (2.0 * (double)(n - 1));
  const double fpc = 1 - (double)n / N;
  return N * N * (fpc > 0 ? fpc : 0) * s2 / (double)n;
}

void sample_aux_free(struct sample_aux *x) {
  if (!x) return;
  free(x->unit);
  free(x->sparse);
  free(x);
}
