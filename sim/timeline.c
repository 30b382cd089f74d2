/* Rows grow by doubling up to TIMELINE_MAX_ROWS; past it, the window doubles
 * and pairs of rows merge, so the counts stay exact sums whatever the length. */
#include "sim/timeline.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sim/err.h"

void timeline_init(struct timeline *tl, unsigned cols, uint64_t window_cycles) {
  CHECK(cols >= 1 && window_cycles >= 1);
  memset(tl, 0, sizeof *tl);
  tl->cols = cols;
  tl->window = window_cycles;
}

void timeline_fini(struct timeline *tl) {
  free(tl->v);
  tl->v = NULL;
}

/* The row of window w, growing or coarsening the array as needed. */
static double *row(struct timeline *tl, uint64_t w) {
  const unsigned C = tl->cols;
  while (w >= TIMELINE_MAX_ROWS) {
    /* Coarsen: windows double, pairs of rows merge. */
    uint64_t half = (tl->rows + 1) / 2;
    for (uint64_t i = 0; i < half; i++)
      for (unsigned c = 0; c < C; c++) {
        double b = 2 * i + 1 < tl->rows ? tl->v[(2 * i + 1) * C + c] : 0.0;
        tl->v[i * C + c] = tl->v[2 * i * C + c] + b;
      }
    if (tl->rows > half) /* (an empty timeline has no array yet) */
      memset(tl->v + half * C, 0, (tl->rows - half) * C * sizeof *tl->v);
    tl->rows = half;
    tl->window *= 2;
    w /= 2;
  }
  if (w >= tl->cap) {
    uint64_t cap = tl->cap ? tl->cap : 256;
    while (cap <= w) cap *= 2;
    if (cap > TIMELINE_MAX_ROWS) cap = TIMELINE_MAX_ROWS;
    tl->v = xrealloc(tl->v, cap * C * sizeof *tl->v);
    memset(tl->v + tl->cap * C, 0, (cap - tl->cap) * C * sizeof *tl->v);
    tl->cap = cap;
  }
  if (w >= tl->rows) tl->rows = w + 1;
  tl->hot = tl->v + w * C;
  tl->lo = w * tl->window;
  tl->hi = tl->lo + tl->window;
  return tl->hot;
}

/* The row of cycle t. */
static inline double *row_at(struct timeline *tl, uint64_t t) {
  return timeline_in_hot(tl, t) ? tl->hot : row(tl, t / tl->window);
}

void timeline_point_any(struct timeline *tl, unsigned col, uint64_t t, double amount) {
  CHECK_LT(col, tl->cols);
  row_at(tl, t)[col] += amount;
}

void timeline_span_any(struct timeline *tl, unsigned col, uint64_t a, uint64_t b,
                       double per_cycle) {
  CHECK_LT(col, tl->cols);
  if (b <= a) return;
  /* The row of the span's last window first: any coarsening happens now. */
  if (!timeline_in_hot(tl, b - 1)) row(tl, (b - 1) / tl->window);
  for (uint64_t x = a; x < b;) {
    double *r = row_at(tl, x);
    uint64_t end = tl->hi; /* row_at leaves x's window hot */
    if (end > b) end = b;
    r[col] += per_cycle * (double)(end - x);
    x = end;
  }
}

void timeline_spread_any(struct timeline *tl, unsigned col, double a, double b, double amount) {
  CHECK_LT(col, tl->cols);
  CHECK(a >= 0 && b >= a);
  const uint64_t first = (uint64_t)a;
  /* The cycle that holds the end (b itself belongs to the next one). */
  uint64_t last = b > a ? (uint64_t)ceil(b) - 1 : first;
  if (last < first) last = first;
  /* The row of the last window first: any coarsening happens now. */
  if (!timeline_in_hot(tl, last)) row(tl, last / tl->window);
  double from = a, left = amount;
  for (uint64_t x = first;;) {
    double *r = row_at(tl, x);
    const uint64_t hi = tl->hi; /* row_at leaves x's window hot */
    if (!(b > a) || (double)hi >= b) {
      r[col] += left; /* the rest, so the pieces sum to amount */
      return;
    }
    const double part = amount * (((double)hi - from) / (b - a));
    r[col] += part;
    left -= part;
    from = (double)hi;
    x = hi;
  }
}

void timeline_cover(struct timeline *tl, uint64_t end) {
  if (end > 0) row(tl, (end - 1) / tl->window);
}

const double *timeline_row(const struct timeline *tl, uint64_t i) {
  CHECK_LT(i, tl->rows);
  return tl->v + i * tl->cols;
}

static void col_name(const struct timeline_col *c, const char *cls, char *buf, size_t len) {
  if (c->per_class) snprintf(buf, len, c->name, cls);
  else snprintf(buf, len, "%s", c->name);
}

void timeline_col_header(const struct timeline_col *c, unsigned n, unsigned col,
                         const char *const *class_names, char *buf, size_t len) {
  for (unsigned j = 0; j < n; j++)
    if (col >= c[j].col && col < c[j].col + c[j].span) {
      col_name(&c[j], c[j].per_class ? class_names[col - c[j].col] : "", buf, len);
      return;
    }
  CHECK(!"a timeline column without a descriptor");
}

void timeline_write_csv(const struct timeline *tl, const struct timeline_col *c, unsigned n,
                        const char *const *class_names, unsigned classes, uint64_t end, FILE *f) {
  char name[64];
  fputs("cycle,cycles", f);
  for (unsigned j = 0; j < n; j++) {
    CHECK(!c[j].per_class || classes <= c[j].span);
    for (unsigned k = 0; k < (c[j].per_class ? classes : 1); k++) {
      col_name(&c[j], c[j].per_class ? class_names[k] : "", name, sizeof name);
      fprintf(f, ",%s", name);
    }
  }
  fputc('\n', f);
  const uint64_t win = tl->window;
  for (uint64_t i = 0; i < tl->rows; i++) {
    const double *v = timeline_row(tl, i);
    uint64_t start = i * win, len = start + win <= end ? win : (end > start ? end - start : 0);
    if (len == 0) break;
    fprintf(f, "%llu,%llu", (unsigned long long)start, (unsigned long long)len);
    for (unsigned j = 0; j < n; j++)
      for (unsigned k = 0; k < (c[j].per_class ? classes : 1); k++) {
        CHECK_LT(c[j].col + k, tl->cols);
        double x = v[c[j].col + k];
        x = c[j].mean ? x / (double)len : x;
        if (c[j].decimals < 0) fprintf(f, ",%.*g", -c[j].decimals, x);
        else fprintf(f, ",%.*f", c[j].decimals, x);
      }
    fputc('\n', f);
  }
}

void timeline_write_help(const struct timeline_col *c, unsigned n, bool markdown, FILE *f) {
  char name[64];
  for (unsigned j = 0; j < n; j++) {
    col_name(&c[j], "<class>", name, sizeof name);
    if (markdown) fprintf(f, "| `%s` | %s | timeline.csv | %s |\n", name, c[j].unit, c[j].desc);
    else fprintf(f, "%-36s %-16s timeline.csv: %s\n", name, c[j].unit, c[j].desc);
  }
}
