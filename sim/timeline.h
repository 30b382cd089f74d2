/* A timeline: counts per window of simulated time, a fixed number of columns a
 * row. Windows start at timeline.window cycles and double (pairs of rows merge)
 * whenever a run would need more than TIMELINE_MAX_ROWS rows, so a run of any
 * length costs a bounded array. Pure data: the machine and the L2 add to it,
 * run_output writes it. */
#ifndef RTSIM_SIM_TIMELINE_H
#define RTSIM_SIM_TIMELINE_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#define TIMELINE_MAX_ROWS 4096u

struct timeline {
  double *v; /* rows x cols, row-major */
  uint64_t rows, cap, window;
  unsigned cols;
  /* The row last reached and the cycles [lo, hi) it counts: most adds fall
   * there, and find it without a division. */
  double *hot;
  uint64_t lo, hi;
};

/* window_cycles >= 1; cols >= 1. Nothing is allocated until the first add. */
void timeline_init(struct timeline *tl, unsigned cols, uint64_t window_cycles);
void timeline_fini(struct timeline *tl);

/* Add amount to column col at cycle t. */
void timeline_point_any(struct timeline *tl, unsigned col, uint64_t t, double amount);
/* Add per_cycle for every cycle of [a, b), split between windows in proportion. */
void timeline_span_any(struct timeline *tl, unsigned col, uint64_t a, uint64_t b, double per_cycle);

/* Add amount over the cycles [a, b) (a >= 0, with fractions), split between
 * windows in proportion to the time each holds; b == a adds it whole at
 * cycle a. The pieces sum to amount. */
void timeline_spread_any(struct timeline *tl, unsigned col, double a, double b, double amount);

/* Cycle t lies in the row last reached (tl->hot). */
static inline bool timeline_in_hot(const struct timeline *tl, uint64_t t) {
  return t >= tl->lo && t < tl->hi;
}

/* The same, inline when it falls in the row last reached (most adds: one per
 * access and issue of a timed run); the same sums either way. */
static inline void timeline_point(struct timeline *tl, unsigned col, uint64_t t, double amount) {
  if (timeline_in_hot(tl, t) && col < tl->cols) tl->hot[col] += amount;
  else timeline_point_any(tl, col, t, amount);
}
/* timeline_spread_any, inline when [a, b) lies in the row last reached (a
 * DRAM transfer: two adds a line moved), where it adds amount whole. */
static inline void timeline_spread(struct timeline *tl, unsigned col, double a, double b,
                                   double amount) {
  if (b >= a && a >= (double)tl->lo && a < (double)tl->hi && b <= (double)tl->hi && col < tl->cols)
    tl->hot[col] += amount;
  else timeline_spread_any(tl, col, a, b, amount);
}
static inline void timeline_span(struct timeline *tl, unsigned col, uint64_t a, uint64_t b,
                                 double per_cycle) {
  if (b > a && a >= tl->lo && b <= tl->hi && col < tl->cols)
    tl->hot[col] += per_cycle * (double)(b - a);
  else timeline_span_any(tl, col, a, b, per_cycle);
}

/* Make sure the rows reach cycle end - 1 (a run's last window exists). */
void timeline_cover(struct timeline *tl, uint64_t end);

/* Row i (i < rows): cols values. */
const double *timeline_row(const struct timeline *tl, uint64_t i);

/* A column of timeline.csv, declared once by whoever adds to it: its name
 * (with per_class, a format with one %s: one column per data class, values
 * in col + class), unit, one-line description, the decimals it is written
 * with (negative: that many significant digits, %g), and whether it is
 * written per cycle of its window (a mean) rather than as the window's sum.
 * span: the timeline columns it covers. */
struct timeline_col {
  const char *name, *unit, *desc;
  unsigned col, span;
  int decimals;
  bool per_class, mean;
};

/* timeline.csv: `cycle,cycles,<names>` then a row per window up to the run's
 * end (the last window cut at end): its start, its length, then each
 * column's value. Per-class columns for `classes` classes named class_names. */
void timeline_write_csv(const struct timeline *tl, const struct timeline_col *c, unsigned n,
                        const char *const *class_names, unsigned classes, uint64_t end, FILE *f);
/* The header timeline_write_csv gives the timeline's column col (of c[0..n),
 * per-class columns named from class_names), into buf: for readers that pick
 * columns by name, so a column added cannot shift them. */
void timeline_col_header(const struct timeline_col *c, unsigned n, unsigned col,
                         const char *const *class_names, char *buf, size_t len);
/* One line per column: name, unit, description (Markdown rows if markdown). */
void timeline_write_help(const struct timeline_col *c, unsigned n, bool markdown, FILE *f);

#endif
