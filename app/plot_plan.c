/* rtsim plot's command line into a plan (app/plot_plan.h): the options'
 * table, its help text and the checks that need no table. */
#include "app/plot_plan.h"

#include <stdio.h>
#include <string.h>
#include <strings.h>

#include "app/app.h"
#include "app/opts.h"
#include "sim/scalar.h"

static const char HELP[] =
    "usage: rtsim plot TABLE.csv --x KEY --y METRIC -o FILE.png|.pdf|.svg [options]\n"
    "\n"
    "Plot column METRIC against column KEY of a tidy table (rtsim merge's) through\n"
    "gnuplot: lines when KEY holds numbers, bars when it holds text. Labels, units,\n"
    "a caption of the fixed parameters, error bars over seeds and the DRAM's peak\n"
    "come from the table (--help-full: how; docs/sweeps.md: Plotting).\n"
    "\n"
    "example:\n"
    "  rtsim plot results/latency-hiding/grove.csv --x rays_per_thread \\\n"
    "      --y core_utilization --lines threads_per_core --panels dram.latency \\\n"
    "      --where policy=recursive -o build/latency-hiding.png\n"
    "\n"
    "options:\n"
    "  --x KEY, --y METRIC[,...]  the axes (several --y columns of one unit)\n"
    "  --lines KEY        a line (or bar in each group) per value (at most 100)\n"
    "  --panels KEY       a panel per value (at most 100)\n"
    "  --dash KEY         a dash pattern per value (at most 4), colours --lines'\n"
    "  --where KEY=VALUE  keep rows where KEY is VALUE (repeatable)\n"
    "  --title T, --xlabel T, --ylabel T  the figure's words (default: the columns')\n"
    "  --bars, --stack, --points  bars for a numeric KEY; stacked; markers only\n"
    "  --own-y            each panel its own y range\n"
    "  --y-from-data      the y range around the values (default: from 0)\n"
    "  --yrange LO:HI     the y range\n"
    "  --logx, --logy     logarithmic axes (lines only)\n"
    "  --mark-x X         a dashed vertical line at x = X (repeatable)\n"
    "  --peak Y, --no-peak  a peak line at Y; no DRAM peak line\n"
    "  --order A,B,...    these values first, in this order\n"
    "  --script FILE.gp   also write the gnuplot script (data inline)\n"
    "  -o FILE            the plot: .png, .pdf or .svg by its extension\n"
    "  -h, --help         this text; --help-full: the details\n"
    "\f"
    "\n"
    "Lines with points when KEY holds numbers, bars when it holds text (a policy)\n"
    "or with --bars (one group a value). Axis labels are the columns' names in\n"
    "words with the unit rtsim's tables give them (dram_bytes_per_cycle: DRAM bytes\n"
    "per cycle; dram_read_bytes,dram_write_bytes: DRAM bytes); a name the tables\n"
    "lack takes the unit its ending states (_bytes, _cycles, _fraction, _per_second,\n"
    "_s, ...), else it is a count or a label. The y axis starts at 0 (a fraction\n"
    "runs 0..1). Panels share one y range, the figure one legend above them, and a\n"
    "caption names the parameters every plotted row has in common, the DRAM among\n"
    "them. Every other column that varies must be fixed by --where, or be --lines\n"
    "or --panels: two rows at the same x on one line are refused, except rows that\n"
    "differ only in their seed (seed, sample.seed, sample_seed): they are one point,\n"
    "the seeds' mean, with bars from the smallest to the largest value (the caption\n"
    "says so). Where METRIC is DRAM bytes per cycle and the table names the DRAM\n"
    "(fidelity and its keys), a dashed line marks the DRAM's peak. Colours: Okabe\n"
    "and Ito's colour-blind-safe set without its yellow; past seven series they\n"
    "repeat, dashed. Rows with an empty KEY or METRIC cell are left out.\n"
    "--stack stacks the --y columns in one bar (bytes by data class); with\n"
    "--lines, one stacked bar per value. --points draws markers only (a scatter: a\n"
    "series may hold several rows at one x), not with bars. --logx and --logy use\n"
    "base 2 when every value is a power of 2. --mark-x marks a value a paper names.\n"
    "--order puts these values first where they are lines, panels or bar groups\n"
    "(e.g. recursive,packet,dynamic); the rest after them, sorted. --script writes\n"
    "the script that draws the figure, to adjust it by hand.\n";

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

static bool parse_peak(const char *text, void *dst) {
  struct plot_plan *p = dst;
  if (scalar_f64(text, &p->peak) != SCALAR_OK || !(p->peak > 0)) return false;
  p->peak_given = true;
  return true;
}

/* The format -o's extension names (any case); false for another. */
static bool format_of(const char *out, enum plot_format *fmt) {
  static const struct {
    const char *ext;
    enum plot_format fmt;
  } EXTS[] = {{".png", PLOT_PNG}, {".pdf", PLOT_PDF}, {".svg", PLOT_SVG}};
  const size_t ol = strlen(out);
  for (size_t i = 0; i < sizeof EXTS / sizeof EXTS[0]; i++)
    if (ol > 4 && !strcasecmp(out + ol - 4, EXTS[i].ext)) {
      *fmt = EXTS[i].fmt;
      return true;
    }
  return false;
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
  if (!p->out) return app_usage_error("plot", "missing -o FILE.png, FILE.pdf or FILE.svg");
  if (!format_of(p->out, &p->format))
    return app_usage_error("plot", "-o %s: expected a .png, .pdf or .svg file", p->out);
  if (p->own_y && p->yrange) return app_usage_error("plot", "--own-y and --yrange: choose one");
  if (p->yrange && p->y_from_data)
    return app_usage_error("plot", "--y-from-data and --yrange: choose one");
  if (p->peak_given && p->no_peak)
    return app_usage_error("plot", "--peak and --no-peak: choose one");
  if (p->yrange && p->logy && p->ylo <= 0)
    return app_usage_error("plot", "--yrange %g:%g: a log scale needs LO > 0", p->ylo, p->yhi);
  if (p->stack) p->bars = true;
  if (p->bars && (p->logx || p->logy || p->nmark))
    return app_usage_error("plot", "%s: not with --%s (bars have no numeric x, and start at 0)",
                           p->logx   ? "--logx"
                           : p->logy ? "--logy"
                                     : "--mark-x",
                           p->stack ? "stack" : "bars");
  if (p->dash && p->bars)
    return app_usage_error("plot", "--dash: not with --%s (bars have no lines to dash)",
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
      OPTS_STR("dash", 0, &p->dash),
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
      OPTS_STR("title", 0, &p->title),
      OPTS_STR("xlabel", 0, &p->xlabel),
      OPTS_STR("ylabel", 0, &p->ylabel),
      OPTS_FLAG("y-from-data", 0, &p->y_from_data),
      OPTS_PARSE("peak", 0, p, parse_peak, "a number > 0"),
      OPTS_FLAG("no-peak", 0, &p->no_peak),
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
