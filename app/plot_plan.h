/* rtsim plot's plan: its command line read into a plain struct, every check
 * that needs no table done (a usage error is exit code 2 and one message).
 * Nothing is read or written here, so a test can check a plan alone. The
 * plan points into argv: argv must outlive it. */
#ifndef RTSIM_APP_PLOT_PLAN_H
#define RTSIM_APP_PLOT_PLAN_H

#include <stdbool.h>

/* Most --where filters, and most --mark-x values. */
#define PLOT_WHERE_MAX 32
/* Most --y columns: stacked data classes are five (geometry, node, ray, queue,
 * other). */
#define PLOT_Y_MAX 8

/* The picture's format, chosen by -o's extension: gnuplot's pngcairo,
 * pdfcairo or svg terminal. */
enum plot_format { PLOT_PNG, PLOT_PDF, PLOT_SVG };

struct plot_plan {
  const char *table; /* TABLE.csv */
  /* --x, --y (as typed), --lines, --panels, --dash; NULL when not given. */
  const char *x, *y, *lines, *panels, *dash;
  const char *out, *script, *order; /* -o, --script, --order */
  /* --title, --xlabel, --ylabel; NULL: made from the columns' names and units. */
  const char *title, *xlabel, *ylabel;
  enum plot_format format;           /* by -o's extension */
  const char *where[PLOT_WHERE_MAX]; /* --where KEY=VALUE, each holding a '=' */
  unsigned nwhere;
  double mark[PLOT_WHERE_MAX]; /* --mark-x values */
  unsigned nmark;
  bool yrange; /* --yrange given: ylo < yhi */
  double ylo, yhi;
  bool logx, logy, own_y, points;
  bool y_from_data; /* --y-from-data: the y range around the values, not from 0 */
  bool peak_given;  /* --peak Y: a line at y = peak */
  double peak;
  bool no_peak; /* --no-peak: no DRAM peak line even where the table gives one */
  bool bars;    /* --bars or --stack asked for bars (a text --x draws them too) */
  bool stack;   /* --stack */
  int argc;     /* the command line, echoed in --script's file */
  char **argv;
};

/* Read argv[0..argc) (argv[0] is "plot") into *p. Returns OPTS_GO (app/opts.h)
 * to go on; else the exit code, after printing the help (0) or one usage
 * error (2). */
int plot_plan_parse(struct plot_plan *p, int argc, char **argv);

#endif
