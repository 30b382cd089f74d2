/* rtsim plot's figure: the rows of a table that a plan draws, each as numbers
 * (x, one y per --y column) with its panel and line, sorted by panel, line, x;
 * the distinct values that make the lines, panels and bar groups, in the
 * plan's order; and the caption of the parameters every drawn row shares.
 * Every check of the table against the plan happens here, before anything is
 * drawn; nothing is written. */
#ifndef RTSIM_APP_PLOT_FIGURE_H
#define RTSIM_APP_PLOT_FIGURE_H

#include <stdbool.h>

#include "app/plot_plan.h"

struct csv_table;
struct err;

/* Most panels a plot may have: the picture grows with them (a square grid of
 * 520x380-pixel panels: 100 make 5200x3800 pixels, about 100 MB for gnuplot;
 * 2,500 took gnuplot a minute and 2.5 GB), and past a hundred no panel can
 * be read anyway. */
#define PLOT_PANELS_MAX 100
/* Most lines a panel may have, and most bar groups: a legend of more cannot
 * be read, and the colours repeat long before. */
#define PLOT_LINES_MAX 100
/* Most --dash values: past four, dash patterns are hard to tell apart. */
#define PLOT_DASHES_MAX 4

/* Distinct values of a column over the kept rows (the table's strings). */
struct plot_values {
  const char **v;
  unsigned n;
};

struct plot_row {
  unsigned r; /* the table's row (the first of its seeds) */
  double x;   /* the value, or for bars the group's index */
  double y[PLOT_Y_MAX];
  /* Rows that differ only in their seed are one row: y their mean, ylo and
   * yhi the smallest and largest, nseeds how many (1: y = ylo = yhi). */
  double ylo[PLOT_Y_MAX], yhi[PLOT_Y_MAX];
  unsigned nseeds;
  unsigned panel, line, dash; /* indices into the figure's panels, lines and dashes */
};

/* The --y columns: the names, and the part of each that differs from the
 * others (fetch_geometry_bytes, fetch_ray_bytes: geometry, ray) for legends,
 * with the shared rest as a pattern for the axis (fetch_*_bytes). */
struct plot_ycols {
  char buf[1024], toks[1024];
  const char *name[PLOT_Y_MAX];
  int col[PLOT_Y_MAX];
  char title[PLOT_Y_MAX][256];
  char pattern[1024];
  unsigned n;
};

struct plot_figure {
  const struct plot_plan *plan;
  const struct csv_table *t;
  struct plot_ycols *ys;
  const char *yunit;  /* the --y columns' one unit (plot_unit_of) */
  int xc, lc, pc, dc; /* the --x, --lines, --panels, --dash columns; -1 when not given */
  int wcol[PLOT_WHERE_MAX];
  unsigned *kept; /* the rows every --where keeps and with x and y cells, in table order */
  unsigned nkept;
  struct plot_row *rows;         /* nrows, sorted by panel, line, x, row */
  unsigned nrows;                /* nkept less the rows merged into another's seeds */
  unsigned seeds_min, seeds_max; /* over rows of several seeds; 0 when none */
  /* The peak line's y in each panel (--peak, or the DRAM's peak bytes per
   * cycle), or 0 for none. */
  double *peak;
  bool dram_peak; /* peak is the DRAM's */
  /* One "" when not given; groups: the bars' x values (bars only). */
  struct plot_values lines, panels, groups, dashes;
  bool bars;    /* the plan's, or --x holds text */
  bool stacked; /* --stack with several --y columns */
  char caption[4096];
};

/* Build f from table t (which must outlive f) as plan p says. False on a
 * table that does not fit the plan: with e set, or with the message already
 * printed (a column the table lacks: the list of columns outgrows an error
 * record); exit code 2 either way. plot_figure_fini frees f in both cases. */
bool plot_figure_build(struct plot_figure *f, const struct plot_plan *p, const struct csv_table *t,
                       struct err *e);
void plot_figure_fini(struct plot_figure *f);

#endif
