/* rtsim plot's command line into a plan (app/plot_plan.h): the options'
 * table, its help text and the checks that need no table. */
#include "app/plot_plan.h"

#include <stdio.h>
#include <string.h>

#include "app/app.h"
#include "app/opts.h"
#include "sim/scalar.h"

static const char HELP[] =
    "usage: rtsim plot TABLE.csv --x KEY --y METRIC -o FILE.png|FILE.svg [options]\n"
    "\n"
    "Plot column METRIC against column KEY of a tidy table (rtsim merge's)\n"
    "through gnuplot: lines with points when KEY holds numbers, bars when it\n"
    "holds text (a policy) or with --bars. Axis labels carry the unit the\n"
    "column name gives: _bytes, l1.size, l2.size: bytes; cycles, _cycles,\n"
    ".latency, costs., timeline.window, _wait_mean, _latency_mean/_p50/_p95/\n"
    "_p99/_max: cycles; dram.tCL and the other timings: DRAM cycles; _fraction,\n"
    "utilization, _rate: fraction (drawn on 0..1); _per_second: per second;\n"
    "_bytes_per_cycle: bytes per cycle; seconds, _s: seconds; clock_ghz: GHz;\n"
    "dram.clock_mhz: MHz; _mb: MiB; l2.write_buffer: lines; the DRAM queues:\n"
    "entries; width, height: pixels; anything else is a count or a label.\n"
    "Panels share one y range, the figure one legend, and a caption names the\n"
    "parameters every plotted row has in common. Rows with an empty KEY or\n"
    "METRIC cell are left out.\n"
    "\n"
    "options:\n"
    "  --x KEY            the x axis: a numeric column (lines), or any column\n"
    "                     (bars, one group per value)\n"
    "  --y METRIC[,...]   the y axis: a numeric column; several (of one unit),\n"
    "                     comma-separated, draw a line or bar each\n"
    "  --lines KEY        one line (or bar in each group) per value of this\n"
    "                     column, with a legend (at most 100)\n"
    "  --panels KEY       one panel per value of this column (at most 100)\n"
    "  --where KEY=VALUE  keep only rows where KEY is VALUE (numbers compare as\n"
    "                     numbers); repeatable. Every other column that varies\n"
    "                     must be fixed so, or be --lines or --panels: two rows\n"
    "                     at the same x on one line are refused\n"
    "  --bars             bars even when KEY holds numbers (one group a value)\n"
    "  --stack            bars with the --y columns stacked (bytes by data\n"
    "                     class); with --lines, one stacked bar per value\n"
    "  --points           markers only, no lines (a scatter: a series may hold\n"
    "                     several rows at one x); not with bars\n"
    "  --own-y            each panel its own y range (default: one for all)\n"
    "  --yrange LO:HI     the y range (default: from the data; 0..1 for a\n"
    "                     fraction)\n"
    "  --logx, --logy     logarithmic axis (base 2 when every value is a power of\n"
    "                     2); lines only\n"
    "  --mark-x X         a dashed vertical line at x = X in every panel (e.g. a\n"
    "                     value a paper names); repeatable; lines only\n"
    "  --order A,B,...    these values first, in this order, where they are lines,\n"
    "                     panels or bar groups (e.g. the paper's recursive,packet,\n"
    "                     dynamic); the rest after them, sorted (default: all sorted)\n"
    "  --script FILE.gp   also write the gnuplot script (data inline), to adjust\n"
    "                     the figure by hand\n"
    "  -o FILE            the plot: .png (pngcairo) or .svg\n"
    "  -h, --help         this text\n";

static bool add_where(const char *text, void *dst) {
  struct plot_plan *p = dst;
  if (p->nwhere == PLOT_WHERE_MAX || !strchr(text, '=')) return false;
  p->where[p->nwhere++] = text;
  return true;
}

static bool add_mark(const char *text, void *dst) {
  struct plot_plan *p = dst;
  double v;
  if (p->nmark == PLOT_WHERE_MAX || scalar_f64(text, &v) != SCALAR_OK) return false;
  p->mark[p->nmark++] = v;
  return true;
}

/* --yrange LO:HI. */
static bool parse_yrange(const char *text, void *dst) {
  struct plot_plan *p = dst;
  const char *colon = strchr(text, ':');
  char lo[64];
  if (!colon || (size_t)(colon - text) >= sizeof lo) return false;
  snprintf(lo, sizeof lo, "%.*s", (int)(colon - text), text);
  if (scalar_f64(lo, &p->ylo) != SCALAR_OK || scalar_f64(colon + 1, &p->yhi) != SCALAR_OK ||
      !(p->ylo < p->yhi))
    return false;
  p->yrange = true;
  return true;
}

#define PLOT_AT_MOST_(s) " (at most " #s ")"
#define PLOT_AT_MOST(s) PLOT_AT_MOST_(s)

/* The relations between options: one usage error, or OPTS_GO. */
static int check(struct plot_plan *p) {
  if (!p->x || !p->y) return app_usage_error("plot", "missing --%s", p->x ? "y METRIC" : "x KEY");
  if (!p->out) return app_usage_error("plot", "missing -o FILE.png or FILE.svg");
  size_t ol = strlen(p->out);
  p->svg = ol > 4 && !strcmp(p->out + ol - 4, ".svg");
  if (!p->svg && !(ol > 4 && !strcmp(p->out + ol - 4, ".png")))
    return app_usage_error("plot", "-o %s: expected a .png or .svg file", p->out);
  if (p->own_y && p->yrange) return app_usage_error("plot", "--own-y and --yrange: choose one");
  if (p->yrange && p->logy && p->ylo <= 0)
    return app_usage_error("plot", "--yrange %g:%g: a log scale needs LO > 0", p->ylo, p->yhi);
  if (p->stack) p->bars = true;
  if (p->bars && (p->logx || p->logy || p->nmark))
    return app_usage_error("plot", "%s: not with --%s (bars have no numeric x, and start at 0)",
                           p->logx   ? "--logx"
                           : p->logy ? "--logy"
                                     : "--mark-x",
                           p->stack ? "stack" : "bars");
  if (p->points && p->bars)
    return app_usage_error("plot", "--points: not with --%s (a scatter needs a numeric x)",
                           p->stack ? "stack" : "bars");
  if (p->script && !strcmp(p->script, p->out))
    return app_usage_error("plot", "--script %s: the same file as -o", p->script);
  return OPTS_GO;
}

int plot_plan_parse(struct plot_plan *p, int argc, char **argv) {
  memset(p, 0, sizeof *p);
  p->argc = argc;
  p->argv = argv;
  const struct opts_spec spec[] = {
      OPTS_STR("x", 0, &p->x),
      OPTS_STR("y", 0, &p->y),
      OPTS_STR("lines", 0, &p->lines),
      OPTS_STR("panels", 0, &p->panels),
      OPTS_PARSE("where", 0, p, add_where, "KEY=VALUE" PLOT_AT_MOST(PLOT_WHERE_MAX)),
      OPTS_FLAG("logx", 0, &p->logx),
      OPTS_FLAG("logy", 0, &p->logy),
      OPTS_FLAG("bars", 0, &p->bars),
      OPTS_FLAG("stack", 0, &p->stack),
      OPTS_FLAG("own-y", 0, &p->own_y),
      OPTS_FLAG("points", 0, &p->points),
      OPTS_PARSE("yrange", 0, p, parse_yrange, "LO:HI, two numbers with LO < HI"),
      OPTS_STR("script", 0, &p->script),
      OPTS_STR("order", 0, &p->order),
      OPTS_STR("output", 'o', &p->out),
      OPTS_PARSE("mark-x", 0, p, add_mark, "a number" PLOT_AT_MOST(PLOT_WHERE_MAX)),
      OPTS_END};
  struct opts_args args;
  int rc = opts_parse("plot", HELP, spec, argc, argv, &args);
  if (rc != OPTS_GO) return rc;
  p->table = opts_one(&args, "TABLE.csv", "table");
  if (!p->table) return APP_EXIT_USAGE;
  return check(p);
}
