/* rtsim plot: figures of a tidy table (rtsim merge's, or any CSV with a
 * header) through gnuplot: METRIC against KEY as lines (a numeric KEY) or bars
 * (a categorical one), a line or bar per value of a --lines column, a panel
 * per value of a --panels column. Ranges, ticks and the layout (one legend and
 * one caption for the figure) are computed here, not left to gnuplot, so the
 * panels share them. The script goes to gnuplot on a pipe with the data
 * inline; the picture is written under a temporary name and renamed
 * (sim/outfile.h). */
#include "app/app.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "app/csv.h"
#include "app/gnuplot.h"
#include "app/opts.h"
#include "app/outguard.h"
#include "app/plot_axis.h"
#include "sim/err.h"
#include "sim/outfile.h"
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

#define PLOT_WHERE_MAX 32
/* Most panels a plot may have: the picture grows with them (a square grid of
 * 520x380-pixel panels: 100 make 5200x3800 pixels, about 100 MB for gnuplot;
 * 2,500 took gnuplot a minute and 2.5 GB), and past a hundred no panel can
 * be read anyway. */
#define PLOT_PANELS_MAX 100
/* Most lines a panel may have, and most bar groups: a legend of more cannot
 * be read, and the colours repeat long before. */
#define PLOT_LINES_MAX 100
/* Most --y columns: stacked data classes are five (geometry, node, ray, queue,
 * other). */
#define PLOT_Y_MAX 8

/* The figure's layout in pixels: a panel's cell, the plot box inside it, the
 * strips for the title, the legend's rows and the caption's lines. gnuplot's
 * own placement sizes each panel to its tick labels and repeats the key in
 * every panel; fixed margins keep the panels aligned. */
#define PX_PANEL_W 520
#define PX_PANEL_H 390
/* Widest a panel of bars grows, and widest a row of panels. */
#define PX_PANEL_W_MAX 1400
#define PX_BOX_LEFT 100
#define PX_BOX_RIGHT 18
#define PX_BOX_TOP 34
#define PX_BOX_BOTTOM 66
#define PX_TITLE 40
#define PX_LEGEND_ROW 21
#define PX_CAPTION_LINE 18
/* About the width of a character of the 11-point font (pngcairo and svg). */
#define PX_CHAR 7.2

static void axis_label(const char *name, char *out, size_t cap) {
  const char *u = plot_unit_of(name);
  if (!u[0] || !strcmp(u, name)) snprintf(out, cap, "%s", name);
  else snprintf(out, cap, "%s (%s)", name, u);
}

/* A gnuplot single-quoted string of s. */
static void gp_str(FILE *f, const char *s) {
  fputc('\'', f);
  for (; *s; s++) {
    if (*s == '\'') fputc('\'', f);
    if (*s != '\n') fputc(*s, f);
  }
  fputc('\'', f);
}

/* Column `name` of t for option opt; else -1 and a message listing every
 * column (printed here: the list outgrows an error record). */
static int column(const struct csv_table *t, const char *opt, const char *name) {
  int c = csv_column(t, name);
  if (c >= 0) return c;
  char *msg = NULL;
  size_t len = 0;
  FILE *f = open_memstream(&msg, &len);
  CHECK(f);
  char esc[1024];
  err_escape(esc, sizeof esc, name);
  fprintf(f, "%s:1: error: %s: no column '%s' (columns: ", t->file, opt, esc);
  for (unsigned i = 0; i < t->ncols; i++) {
    err_escape(esc, sizeof esc, t->names[i]); /* a quoted name may hold a line break */
    fprintf(f, "%s%s", i ? ", " : "", esc);
  }
  fputs(")\n", f);
  CHECK(fclose(f) == 0);
  fputs(msg, stderr);
  free(msg);
  return -1;
}

/* Cells equal as text, or as numbers when both are numbers. */
static bool same_value(const char *a, const char *b) {
  double x, y;
  if (!strcmp(a, b)) return true;
  return csv_number(a, &x) && csv_number(b, &y) && x == y;
}

/* Distinct values of column c over the kept rows: in numeric order when all
 * are numbers, else in natural order. */
struct values {
  const char **v;
  unsigned n;
};

static int cmp_num(const void *a, const void *b) {
  double x, y;
  csv_number(*(const char *const *)a, &x);
  csv_number(*(const char *const *)b, &y);
  return (x > y) - (x < y);
}

static int cmp_nat(const void *a, const void *b) {
  return csv_natural_cmp(*(const char *const *)a, *(const char *const *)b);
}

/* At most limit + 1 values are collected (the caller refuses more than
 * limit): the search for a seen value is linear, so the work stays bounded by
 * rows x limit. */
static void distinct(const struct csv_table *t, int c, const unsigned *rows, unsigned nrows,
                     unsigned limit, struct values *out) {
  out->v = xcalloc(nrows ? nrows : 1, sizeof *out->v);
  out->n = 0;
  if (c < 0) {
    out->v[out->n++] = "";
    return;
  }
  bool numeric = true;
  for (unsigned i = 0; i < nrows && out->n <= limit; i++) {
    const char *s = csv_cell(t, rows[i], (unsigned)c);
    bool seen = false;
    for (unsigned k = 0; k < out->n && !seen; k++) seen = same_value(out->v[k], s);
    if (seen) continue;
    double x;
    numeric &= csv_number(s, &x);
    out->v[out->n++] = s;
  }
  qsort(out->v, out->n, sizeof *out->v, numeric ? cmp_num : cmp_nat);
}

/* --order: the values it names first, in its order, wherever they are lines,
 * panels or bar groups; the rest after them, sorted as before. A name no
 * value has is ignored (one order serves several plots of a table). */
static void apply_order(struct values *v, const char *order) {
  if (!order) return;
  unsigned front = 0;
  for (const char *p = order; *p;) {
    const char *q = strchr(p, ',');
    const size_t len = q ? (size_t)(q - p) : strlen(p);
    for (unsigned k = front; k < v->n; k++)
      if (strlen(v->v[k]) == len && !strncmp(v->v[k], p, len)) {
        const char *x = v->v[k];
        memmove(&v->v[front + 1], &v->v[front], (k - front) * sizeof *v->v);
        v->v[front++] = x;
        break;
      }
    p = q ? q + 1 : p + len;
  }
}

/* The swept keys a point name states ("a=1,b=2" -> a, b), for messages. */
static void differing_keys(const struct csv_table *t, unsigned r1, unsigned r2, char *out,
                           size_t cap) {
  out[0] = '\0';
  size_t len = 0;
  int pc = csv_column(t, "point");
  char name[4096];
  snprintf(name, sizeof name, "%s", pc >= 0 ? csv_cell(t, r1, (unsigned)pc) : "");
  for (char *tok = strtok(name, ","); tok; tok = strtok(NULL, ",")) {
    char *eq = strchr(tok, '=');
    if (!eq) continue;
    *eq = '\0';
    int c = csv_column(t, tok);
    if (c < 0 || same_value(csv_cell(t, r1, (unsigned)c), csv_cell(t, r2, (unsigned)c))) continue;
    len += (size_t)snprintf(out + len, len < cap ? cap - len : 0, "%s%s", len ? ", " : "", tok);
  }
  /* Not a sweep's table: name the first column that differs. */
  for (unsigned c = 0; !out[0] && c < t->ncols; c++)
    if (!same_value(csv_cell(t, r1, c), csv_cell(t, r2, c))) snprintf(out, cap, "%s", t->names[c]);
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

static bool all_powers_of_two(const double *v, unsigned n) {
  for (unsigned i = 0; i < n; i++) {
    int ex;
    if (frexp(v[i], &ex) != 0.5) return false;
  }
  return true;
}

struct row {
  unsigned r;
  double x; /* the value, or for bars the group's index */
  double y[PLOT_Y_MAX];
  unsigned panel, line;
};

static int cmp_row(const void *a, const void *b) {
  const struct row *p = a, *q = b;
  if (p->panel != q->panel) return p->panel < q->panel ? -1 : 1;
  if (p->line != q->line) return p->line < q->line ? -1 : 1;
  if (p->x != q->x) return p->x < q->x ? -1 : 1;
  return (p->r > q->r) - (p->r < q->r);
}

static unsigned index_of(const struct values *v, const char *s) {
  for (unsigned k = 0; k < v->n; k++)
    if (same_value(v->v[k], s)) return k;
  CHECK(!"value not among the distinct values");
  return 0;
}

/* The --where filters, KEY=VALUE each (argv's strings). */
struct wheres {
  const char *v[PLOT_WHERE_MAX];
  unsigned n;
};

static bool add_where(const char *text, void *dst) {
  struct wheres *w = dst;
  if (w->n == PLOT_WHERE_MAX || !strchr(text, '=')) return false;
  w->v[w->n++] = text;
  return true;
}

/* The --mark-x values. */
struct marks {
  double v[PLOT_WHERE_MAX];
  unsigned n;
};

static bool add_mark(const char *text, void *dst) {
  struct marks *m = dst;
  double v;
  if (m->n == PLOT_WHERE_MAX || scalar_f64(text, &v) != SCALAR_OK) return false;
  m->v[m->n++] = v;
  return true;
}

/* --yrange LO:HI. */
struct yrange {
  bool set;
  double lo, hi;
};

static bool parse_yrange(const char *text, void *dst) {
  struct yrange *y = dst;
  const char *colon = strchr(text, ':');
  char lo[64];
  if (!colon || (size_t)(colon - text) >= sizeof lo) return false;
  snprintf(lo, sizeof lo, "%.*s", (int)(colon - text), text);
  if (scalar_f64(lo, &y->lo) != SCALAR_OK || scalar_f64(colon + 1, &y->hi) != SCALAR_OK ||
      !(y->lo < y->hi))
    return false;
  y->set = true;
  return true;
}

/* The --y columns: the names, and the part of each that differs from the
 * others (fetch_geometry_bytes, fetch_ray_bytes: geometry, ray) for legends,
 * with the shared rest as a pattern for the axis (fetch_*_bytes). */
struct ycols {
  char buf[1024], toks[1024];
  const char *name[PLOT_Y_MAX];
  int col[PLOT_Y_MAX];
  char title[PLOT_Y_MAX][256];
  char pattern[1024];
  unsigned n;
};

static void y_titles(struct ycols *y) {
  if (y->n == 1) {
    snprintf(y->title[0], sizeof y->title[0], "%s", y->name[0]);
    snprintf(y->pattern, sizeof y->pattern, "%s", y->name[0]);
    return;
  }
  /* The common prefix and suffix, cut back to a '_' or '.' so words stay whole. */
  size_t pre = strlen(y->name[0]), suf = pre;
  for (unsigned k = 1; k < y->n; k++) {
    const char *a = y->name[0], *b = y->name[k];
    size_t la = strlen(a), lb = strlen(b), i = 0, j = 0;
    while (i < pre && a[i] && a[i] == b[i]) i++;
    pre = i;
    while (j < suf && j < la && j < lb && a[la - 1 - j] == b[lb - 1 - j]) j++;
    suf = j;
  }
  const char *a = y->name[0];
  size_t la = strlen(a);
  while (pre && a[pre - 1] != '_' && a[pre - 1] != '.') pre--;
  while (suf && a[la - suf] != '_' && a[la - suf] != '.') suf--;
  bool ok = true;
  for (unsigned k = 0; k < y->n; k++) ok &= strlen(y->name[k]) > pre + suf;
  if (!ok) pre = suf = 0;
  for (unsigned k = 0; k < y->n; k++)
    snprintf(y->title[k], sizeof y->title[k], "%.*s", (int)(strlen(y->name[k]) - pre - suf),
             y->name[k] + pre);
  if (pre || suf) snprintf(y->pattern, sizeof y->pattern, "%.*s*%s", (int)pre, a, a + la - suf);
  else snprintf(y->pattern, sizeof y->pattern, "%s", y->buf);
}

/* Columns that name the machine and the workload: what a caption says when
 * they do not vary over the plotted rows, with the keys a sweep varied (in
 * its point names) and the --where keys. */
static const char *const CAPTION_KEYS[] = {"scene",    "policy",           "rays",
                                           "width",    "height",           "fidelity",
                                           "cores",    "threads_per_core", "rays_per_thread",
                                           "l1.size",  "l2.size",          "l2.ways",
                                           "clock_ghz"};

static bool in_point_name(const struct csv_table *t, int pc, unsigned r, const char *key) {
  if (pc < 0) return false;
  const char *s = csv_cell(t, r, (unsigned)pc);
  size_t n = strlen(key);
  for (const char *p = s; (p = strstr(p, key)); p++)
    if ((p == s || p[-1] == ',') && p[n] == '=') return true;
  return false;
}

/* The caption: "key = value unit" for every caption column that is constant
 * over the kept rows and not drawn (x, y, lines, panels), in table order. A
 * table none of whose columns is such a key (not rtsim's) gets every constant
 * column that is not drawn. */
static void caption(const struct csv_table *t, const unsigned *kept, unsigned nkept,
                    const bool *drawn, const int *wcol, unsigned nwhere, char *out, size_t cap) {
  int pc = csv_column(t, "point");
  bool known = pc >= 0;
  for (size_t k = 0; k < sizeof CAPTION_KEYS / sizeof CAPTION_KEYS[0]; k++)
    known |= csv_column(t, CAPTION_KEYS[k]) >= 0;
  size_t len = 0;
  out[0] = '\0';
  int wc = csv_column(t, "width"), hc = csv_column(t, "height");
  for (unsigned c = 0; c < t->ncols; c++) {
    if (drawn[c] || (int)c == pc) continue;
    const char *name = t->names[c];
    bool want = !known;
    for (size_t k = 0; k < sizeof CAPTION_KEYS / sizeof CAPTION_KEYS[0] && !want; k++)
      want = !strcmp(name, CAPTION_KEYS[k]);
    for (unsigned w = 0; w < nwhere && !want; w++) want = wcol[w] == (int)c;
    want = want || in_point_name(t, pc, kept[0], name);
    if (!want) continue;
    const char *v0 = csv_cell(t, kept[0], c);
    bool constant = v0[0] != '\0';
    for (unsigned i = 1; i < nkept && constant; i++)
      constant = same_value(csv_cell(t, kept[i], c), v0);
    if (!constant) continue;
    char item[512];
    if ((int)c == hc && wc >= 0 && !drawn[wc]) {
      /* Said with the width, as "256x256 pixels", when both are fixed. */
      bool wfixed = true;
      const char *w0 = csv_cell(t, kept[0], (unsigned)wc);
      for (unsigned i = 1; i < nkept && wfixed; i++)
        wfixed = same_value(csv_cell(t, kept[i], (unsigned)wc), w0);
      if (wfixed && w0[0]) continue;
    }
    if ((int)c == wc && hc >= 0 && !drawn[hc]) {
      const char *h0 = csv_cell(t, kept[0], (unsigned)hc);
      bool hfixed = h0[0] != '\0';
      for (unsigned i = 1; i < nkept && hfixed; i++)
        hfixed = same_value(csv_cell(t, kept[i], (unsigned)hc), h0);
      if (hfixed) {
        snprintf(item, sizeof item, "%sx%s pixels", v0, h0);
        len +=
            (size_t)snprintf(out + len, len < cap ? cap - len : 0, "%s%s", len ? "; " : "", item);
        continue;
      }
    }
    char val[256];
    plot_fmt_value(v0, plot_unit_of(name), val, sizeof val);
    snprintf(item, sizeof item, "%s = %s", name, val);
    len += (size_t)snprintf(out + len, len < cap ? cap - len : 0, "%s%s", len ? "; " : "", item);
  }
  if (len >= cap && cap > 4) strcpy(out + cap - 4, "...");
}

/* A gnuplot tick list: ('label' pos, ...). */
static void gp_ticks(FILE *f, const char *axis, const struct plot_axis *a, const char *unit) {
  fprintf(f, "set %stics (", axis);
  for (unsigned i = 0; i < a->nticks; i++) {
    char l[64];
    plot_fmt_tick(a->ticks[i], unit, l, sizeof l);
    if (i) fputs(", ", f);
    gp_str(f, l);
    fprintf(f, " %.12g", a->ticks[i]);
  }
  fputs(")\n", f);
}

static void gp_range(FILE *f, const char *axis, const struct plot_axis *a, const char *unit) {
  /* NOTE: gnuplot drops a tick that sits exactly on the end of a log axis
   * (rounding in its logarithms): widen such an axis by a hair. */
  const double hair = a->log ? 1e-9 : 0;
  fprintf(f, "set %srange [%.17g:%.17g]\n", axis, a->lo * (1 - hair), a->hi * (1 + hair));
  gp_ticks(f, axis, a, unit);
}

/* A --yrange: exactly LO..HI, with the round ticks inside it. */
static void axis_fixed(struct plot_axis *a, const struct yrange *yr, bool log, int base) {
  struct plot_axis n;
  plot_axis_nice(&n, yr->lo, yr->hi, log, base, false, false);
  a->lo = yr->lo;
  a->hi = yr->hi;
  a->log = log;
  a->nticks = 0;
  for (unsigned i = 0; i < n.nticks; i++)
    if (n.ticks[i] >= yr->lo * (1 - 1e-12) && n.ticks[i] <= yr->hi * (1 + 1e-12))
      a->ticks[a->nticks++] = n.ticks[i];
}

/* The y extent of rows [a, b): each value, or for stacked bars each bar's sum. */
static void y_extent(const struct row *rows, unsigned a, unsigned b, unsigned ny, bool stack,
                     double *min, double *max) {
  *min = INFINITY;
  *max = -INFINITY;
  for (unsigned i = a; i < b; i++) {
    double sum = 0;
    for (unsigned k = 0; k < ny; k++) {
      double v = rows[i].y[k];
      sum += v;
      if (!stack) *min = fmin(*min, v), *max = fmax(*max, v);
    }
    if (stack) *min = fmin(*min, sum), *max = fmax(*max, sum);
  }
}

/* Wrap text at "; " into lines of at most width characters; the number of
 * lines. Each line is written to out as a NUL-separated run. */
static unsigned wrap(const char *text, unsigned width, char *out, size_t cap) {
  unsigned n = 0;
  size_t o = 0;
  const char *p = text;
  while (*p && o + 2 < cap) {
    size_t len = strlen(p), take = len;
    if (len > width) {
      take = 0;
      for (const char *s = p; (s = strstr(s, "; ")) && (size_t)(s - p) + 1 <= width; s += 2)
        take = (size_t)(s - p) + 1;
      if (!take) take = width;
    }
    if (o + take + 1 >= cap) take = cap - o - 2;
    memcpy(out + o, p, take);
    o += take;
    out[o++] = '\0';
    n++;
    p += take;
    while (*p == ' ') p++;
  }
  return n;
}

#define PLOT_AT_MOST_(s) " (at most " #s ")"
#define PLOT_AT_MOST(s) PLOT_AT_MOST_(s)

int cmd_plot(int argc, char **argv) {
  const char *xk = NULL, *yarg = NULL, *lk = NULL, *pk = NULL, *out = NULL, *script = NULL;
  const char *order = NULL;
  struct wheres wh = {.n = 0};
  struct marks mk = {.n = 0};
  struct yrange yr = {.set = false};
  bool logx = false, logy = false, bars = false, stack = false, own_y = false, points = false;
  const struct opts_spec spec[] = {
      OPTS_STR("x", 0, &xk),
      OPTS_STR("y", 0, &yarg),
      OPTS_STR("lines", 0, &lk),
      OPTS_STR("panels", 0, &pk),
      OPTS_PARSE("where", 0, &wh, add_where, "KEY=VALUE" PLOT_AT_MOST(PLOT_WHERE_MAX)),
      OPTS_FLAG("logx", 0, &logx),
      OPTS_FLAG("logy", 0, &logy),
      OPTS_FLAG("bars", 0, &bars),
      OPTS_FLAG("stack", 0, &stack),
      OPTS_FLAG("own-y", 0, &own_y),
      OPTS_FLAG("points", 0, &points),
      OPTS_PARSE("yrange", 0, &yr, parse_yrange, "LO:HI, two numbers with LO < HI"),
      OPTS_STR("script", 0, &script),
      OPTS_STR("order", 0, &order),
      OPTS_STR("output", 'o', &out),
      OPTS_PARSE("mark-x", 0, &mk, add_mark, "a number" PLOT_AT_MOST(PLOT_WHERE_MAX)),
      OPTS_END};
  struct opts_args args;
  int rc = opts_parse("plot", HELP, spec, argc, argv, &args);
  if (rc != OPTS_GO) return rc;
  const char **where = wh.v;
  const unsigned nwhere = wh.n;
  const char *table = opts_one(&args, "TABLE.csv", "table");
  if (!table) return APP_EXIT_USAGE;
  if (!xk || !yarg) return app_usage_error("plot", "missing --%s", xk ? "y METRIC" : "x KEY");
  if (!out) return app_usage_error("plot", "missing -o FILE.png or FILE.svg");
  size_t ol = strlen(out);
  bool svg = ol > 4 && !strcmp(out + ol - 4, ".svg");
  if (!svg && !(ol > 4 && !strcmp(out + ol - 4, ".png")))
    return app_usage_error("plot", "-o %s: expected a .png or .svg file", out);
  if (own_y && yr.set) return app_usage_error("plot", "--own-y and --yrange: choose one");
  if (yr.set && logy && yr.lo <= 0)
    return app_usage_error("plot", "--yrange %g:%g: a log scale needs LO > 0", yr.lo, yr.hi);
  if (stack) bars = true;
  if (bars && (logx || logy || mk.n))
    return app_usage_error("plot", "%s: not with --%s (bars have no numeric x, and start at 0)",
                           logx   ? "--logx"
                           : logy ? "--logy"
                                  : "--mark-x",
                           stack ? "stack" : "bars");
  if (points && bars)
    return app_usage_error("plot", "--points: not with --%s (a scatter needs a numeric x)",
                           stack ? "stack" : "bars");
  if (script && !strcmp(script, out))
    return app_usage_error("plot", "--script %s: the same file as -o", script);

  struct csv_table t;
  struct err e = {0};
  rc = APP_EXIT_USAGE;
  unsigned *kept = NULL;
  struct row *rows = NULL;
  struct values lines = {0}, panels = {0}, groups = {0};
  struct outfile plot = {0}, gpfile = {0};
  char *body = NULL;
  size_t bodylen = 0;
  bool *drawn = NULL;
  struct ycols *ys = xcalloc(1, sizeof *ys);
  if (!csv_read(&t, table, &e)) {
    free(ys);
    return app_report(&e);
  }
  int xc = column(&t, "--x", xk);
  if (xc < 0) goto fail;
  /* --y: one column, or several comma-separated (a name with a comma is
   * taken whole when the table has it). */
  snprintf(ys->buf, sizeof ys->buf, "%s", yarg);
  if (csv_column(&t, yarg) >= 0 || !strchr(yarg, ',')) {
    ys->name[0] = yarg;
    ys->n = 1;
  } else {
    snprintf(ys->toks, sizeof ys->toks, "%s", yarg);
    for (char *tok = strtok(ys->toks, ","); tok; tok = strtok(NULL, ",")) {
      if (ys->n == PLOT_Y_MAX) {
        err_set(&e, t.file, 0, 0, "--y %s: more than %d columns", yarg, PLOT_Y_MAX);
        goto fail;
      }
      ys->name[ys->n++] = tok;
    }
  }
  if (!ys->n) {
    err_set(&e, t.file, 0, 0, "--y '%s': no column named", yarg);
    goto fail;
  }
  for (unsigned k = 0; k < ys->n; k++)
    if ((ys->col[k] = column(&t, "--y", ys->name[k])) < 0) goto fail;
  const char *yunit = plot_unit_of(ys->name[0]);
  for (unsigned k = 1; k < ys->n; k++)
    if (strcmp(plot_unit_of(ys->name[k]), yunit)) {
      err_set(&e, t.file, 0, 0, "--y: %s (%s) and %s (%s) cannot share an axis (expected one unit)",
              ys->name[0], yunit[0] ? yunit : "a count", ys->name[k],
              plot_unit_of(ys->name[k])[0] ? plot_unit_of(ys->name[k]) : "a count");
      goto fail;
    }
  y_titles(ys);
  const unsigned ny = ys->n;
  int lc = -1, pc = -1;
  if (lk && (lc = column(&t, "--lines", lk)) < 0) goto fail;
  if (pk && (pc = column(&t, "--panels", pk)) < 0) goto fail;

  /* The rows --where keeps. */
  int wcol[PLOT_WHERE_MAX];
  for (unsigned w = 0; w < nwhere; w++) {
    char key[256];
    snprintf(key, sizeof key, "%.*s", (int)(strchr(where[w], '=') - where[w]), where[w]);
    if ((wcol[w] = column(&t, "--where", key)) < 0) goto fail;
  }
  kept = xcalloc(t.nrows ? t.nrows : 1, sizeof *kept);
  unsigned nkept = 0;
  for (unsigned r = 0; r < t.nrows; r++) {
    bool keep = true;
    for (unsigned w = 0; w < nwhere && keep; w++)
      keep = same_value(csv_cell(&t, r, (unsigned)wcol[w]), strchr(where[w], '=') + 1);
    keep = keep && csv_cell(&t, r, (unsigned)xc)[0];
    for (unsigned k = 0; k < ny && keep; k++) keep = csv_cell(&t, r, (unsigned)ys->col[k])[0];
    if (keep) kept[nkept++] = r;
  }
  if (!nkept) {
    /* Name a --where that matches nothing, with the values its column has. */
    for (unsigned w = 0; w < nwhere && !e.set; w++) {
      bool any = false;
      for (unsigned r = 0; r < t.nrows && !any; r++)
        any = same_value(csv_cell(&t, r, (unsigned)wcol[w]), strchr(where[w], '=') + 1);
      if (any) continue;
      unsigned *all = xcalloc(t.nrows ? t.nrows : 1, sizeof *all);
      for (unsigned r = 0; r < t.nrows; r++) all[r] = r;
      struct values v;
      distinct(&t, wcol[w], all, t.nrows, 64, &v);
      char list[512] = "";
      for (unsigned k = 0; k < v.n && strlen(list) + 64 < sizeof list; k++) {
        size_t l = strlen(list);
        snprintf(list + l, sizeof list - l, "%s%s", k ? ", " : "", v.v[k]);
      }
      err_set(&e, t.file, 0, 0, "--where %s: no row has it (the column holds: %s)", where[w], list);
      free(v.v);
      free(all);
    }
    if (!e.set)
      err_set(&e, t.file, 0, 0, "no row to plot (%s)",
              nwhere ? "no row matches every --where together" : "the columns are empty");
    goto fail;
  }
  /* A text --x draws bars; an x of numbers and text is a mistake in the
   * table, reported at the first text cell below (unless --bars asks for
   * groups). */
  if (!bars) {
    bool any_number = false;
    for (unsigned i = 0; i < nkept && !any_number; i++) {
      double v;
      any_number = csv_number(csv_cell(&t, kept[i], (unsigned)xc), &v);
    }
    bars = !any_number;
  }
  const bool stacked = stack && ny > 1;
  if (ny > 1 && lc >= 0 && !stacked) {
    err_set(&e, t.file, 0, 0,
            "--y %s with --lines %s: several --y columns draw a %s each, and so does --lines "
            "(expected one of them; --stack stacks the columns in each --lines bar)",
            yarg, lk, bars ? "bar" : "line");
    goto fail;
  }
  if (bars && (logx || logy || mk.n || points)) {
    err_set(&e, t.file, 0, 0, "--x %s holds text: bars have no numeric x and start at 0 (got %s)",
            xk,
            logx   ? "--logx"
            : logy ? "--logy"
            : mk.n ? "--mark-x"
                   : "--points");
    goto fail;
  }
  distinct(&t, lc, kept, nkept, PLOT_LINES_MAX, &lines);
  distinct(&t, pc, kept, nkept, PLOT_PANELS_MAX, &panels);
  if (bars) distinct(&t, xc, kept, nkept, PLOT_LINES_MAX, &groups);
  apply_order(&lines, order);
  apply_order(&panels, order);
  if (bars) apply_order(&groups, order);
  if (panels.n > PLOT_PANELS_MAX) {
    err_set(&e, t.file, 1, 0,
            "--panels %s: more than %d values (expected at most %d panels: keep fewer with "
            "--where KEY=VALUE, or draw the column with --lines)",
            pk, PLOT_PANELS_MAX, PLOT_PANELS_MAX);
    goto fail;
  }
  if (lines.n > PLOT_LINES_MAX) {
    err_set(&e, t.file, 1, 0,
            "--lines %s: more than %d values (expected at most %d lines: keep fewer with "
            "--where KEY=VALUE, or spread them with --panels)",
            lk, PLOT_LINES_MAX, PLOT_LINES_MAX);
    goto fail;
  }
  if (bars && groups.n > PLOT_LINES_MAX) {
    err_set(&e, t.file, 1, 0,
            "--x %s: more than %d values for bar groups (expected at most %d: keep fewer with "
            "--where KEY=VALUE)",
            xk, PLOT_LINES_MAX, PLOT_LINES_MAX);
    goto fail;
  }
  rows = xcalloc(nkept, sizeof *rows);
  for (unsigned i = 0; i < nkept; i++) {
    unsigned r = kept[i];
    struct row *w = &rows[i];
    w->r = r;
    for (unsigned a = 0; a <= ny; a++) {
      /* a == ny is --x. */
      const int c = a == ny ? xc : ys->col[a];
      if (a == ny && bars) {
        w->x = index_of(&groups, csv_cell(&t, r, (unsigned)xc));
        continue;
      }
      double *dst = a == ny ? &w->x : &w->y[a];
      unsigned k = (size_t)r * t.ncols + (unsigned)c;
      const char *s = t.cells[k];
      if (!csv_number(s, dst)) {
        double ignored;
        enum scalar_why why = scalar_f64(s, &ignored);
        err_set(&e, t.file, t.lines[k], t.cols[k], "%s %s: not a number%s%s (got '%s'); %s",
                a == ny ? "--x" : "--y", t.names[c], why == SCALAR_SYNTAX ? "" : ": ",
                scalar_why_text(why), s,
                a == ny ? "--x needs a numeric column for lines (--bars draws its values as "
                          "groups)"
                        : "--y needs numeric columns (use a text column for --lines or --panels)");
        goto fail;
      }
      const bool lg = a == ny ? logx : logy;
      if (lg && *dst <= 0) {
        err_set(&e, t.file, t.lines[k], t.cols[k], "%s %s: %s on a log scale (got %s)",
                a == ny ? "--x" : "--y", t.names[c], "a value must be positive", s);
        goto fail;
      }
      if (stacked && a < ny && *dst < 0) {
        err_set(&e, t.file, t.lines[k], t.cols[k],
                "--y %s: a stacked value must not be "
                "negative (got %s)",
                t.names[c], s);
        goto fail;
      }
    }
    w->line = lc < 0 ? 0 : index_of(&lines, csv_cell(&t, r, (unsigned)lc));
    w->panel = pc < 0 ? 0 : index_of(&panels, csv_cell(&t, r, (unsigned)pc));
  }
  qsort(rows, nkept, sizeof *rows, cmp_row);
  /* A scatter's series may hold several rows at one x (they are points
   * apart, not a line's one value). */
  for (unsigned i = 1; i < nkept && !points; i++) {
    const struct row *a = &rows[i - 1], *b = &rows[i];
    if (a->panel != b->panel || a->line != b->line || a->x != b->x) continue;
    char keys[1024];
    differing_keys(&t, a->r, b->r, keys, sizeof keys);
    err_set(&e, t.file, t.lines[(size_t)b->r * t.ncols], 0,
            "rows at lines %d and %d fall on the same %s at %s = %s but differ in %s: fix "
            "it with --where KEY=VALUE, or show it with --lines or --panels",
            t.lines[(size_t)a->r * t.ncols], t.lines[(size_t)b->r * t.ncols], bars ? "bar" : "line",
            xk, csv_cell(&t, b->r, (unsigned)xc), keys);
    goto fail;
  }

  /* The axes. x: the same in every panel; at the values themselves when a
   * sweep's few, else round ticks. y: one range for every panel unless
   * --own-y; a fraction on 0..1. */
  const char *xunit = plot_unit_of(xk);
  const bool yfrac = !strcmp(yunit, "fraction");
  struct plot_axis xa;
  int ybase = 10;
  {
    double *xs = xcalloc(nkept, sizeof *xs), *yv = xcalloc((size_t)nkept * ny, sizeof *yv);
    unsigned nx = 0;
    for (unsigned i = 0; i < nkept; i++) {
      xs[nx++] = rows[i].x;
      for (unsigned k = 0; k < ny; k++) yv[(size_t)i * ny + k] = rows[i].y[k];
    }
    ybase = all_powers_of_two(yv, nkept * ny) ? 2 : 10;
    const int xbase = all_powers_of_two(xs, nx) ? 2 : 10;
    qsort(xs, nx, sizeof *xs, cmp_double);
    unsigned nd = 0;
    for (unsigned i = 0; i < nx; i++)
      if (!nd || xs[i] != xs[nd - 1]) xs[nd++] = xs[i];
    if (bars) {
      xa.lo = -0.5;
      xa.hi = groups.n - 0.5;
      xa.log = false;
      xa.nticks = 0;
    } else if (!plot_axis_at_values(&xa, xs, nd, logx)) {
      plot_axis_nice(&xa, xs[0], xs[nd - 1], logx, xbase, false, false);
    }
    free(xs);
    free(yv);
  }
  struct plot_axis *yaxes = xcalloc(panels.n, sizeof *yaxes);
  {
    unsigned at = 0;
    double gmin = INFINITY, gmax = -INFINITY;
    for (unsigned p = 0; p < panels.n; p++) {
      unsigned end = at;
      while (end < nkept && rows[end].panel == p) end++;
      double mn, mx;
      y_extent(rows, at, end, ny, stacked, &mn, &mx);
      gmin = fmin(gmin, mn);
      gmax = fmax(gmax, mx);
      if (own_y) plot_axis_nice(&yaxes[p], mn, mx, logy, ybase, yfrac, bars);
      at = end;
    }
    for (unsigned p = 0; p < panels.n && !own_y; p++) {
      if (yr.set) axis_fixed(&yaxes[p], &yr, logy, ybase);
      else plot_axis_nice(&yaxes[p], gmin, gmax, logy, ybase, yfrac, bars);
    }
  }

  /* The series: what one colour stands for. Lines: a --lines value or a --y
   * column. Bars: side by side in a group, a --lines value or (unstacked) a
   * --y column; stacked, the colours are the --y columns. */
  const unsigned nside = bars ? (lc >= 0 ? lines.n : stacked ? 1 : ny) : 1;
  unsigned nleg = 0;
  char(*leg)[512] = xcalloc(PLOT_LINES_MAX + PLOT_Y_MAX, sizeof *leg);
  if (stacked) {
    for (unsigned k = 0; k < ny; k++) snprintf(leg[nleg++], sizeof leg[0], "%s", ys->title[k]);
  } else if (lc >= 0) {
    const char *lu = plot_unit_of(lk);
    for (unsigned l = 0; l < lines.n; l++) {
      char v[256];
      plot_fmt_value(lines.v[l], lu, v, sizeof v);
      snprintf(leg[nleg++], sizeof leg[0], "%s = %s", lk, v);
    }
  } else if (ny > 1) {
    for (unsigned k = 0; k < ny; k++) snprintf(leg[nleg++], sizeof leg[0], "%s", ys->title[k]);
  }

  /* The caption: the fixed parameters. */
  drawn = xcalloc(t.ncols, sizeof *drawn);
  drawn[xc] = true;
  for (unsigned k = 0; k < ny; k++) drawn[ys->col[k]] = true;
  if (lc >= 0) drawn[lc] = true;
  if (pc >= 0) drawn[pc] = true;
  char capt[4096];
  caption(&t, kept, nkept, drawn, wcol, nwhere, capt, sizeof capt);

  /* The layout. Bars get the width their labels need (up to a limit, past
   * which the labels turn), and panels too wide to sit side by side go one
   * under another. */
  size_t ticklen = 0, grouplen = 0;
  char(*blab)[256] = xcalloc(lines.n ? lines.n : 1, sizeof *blab);
  const bool twolevel = bars && stacked && nside > 1;
  for (unsigned g = 0; bars && g < groups.n; g++) {
    char v[256];
    plot_fmt_value(groups.v[g], xunit, v, sizeof v);
    if (strlen(v) > grouplen) grouplen = strlen(v);
  }
  for (unsigned l = 0; twolevel && l < lines.n; l++) {
    plot_fmt_value(lines.v[l], plot_unit_of(lk), blab[l], sizeof blab[l]);
    if (strlen(blab[l]) > ticklen) ticklen = strlen(blab[l]);
  }
  unsigned pw = PX_PANEL_W;
  if (bars) {
    double group = grouplen * PX_CHAR + 16;
    if (twolevel && nside * (ticklen * PX_CHAR + 10) > group)
      group = nside * (ticklen * PX_CHAR + 10);
    double want = group * groups.n + PX_BOX_LEFT + PX_BOX_RIGHT;
    if (want > pw) pw = want > PX_PANEL_W_MAX ? PX_PANEL_W_MAX : (unsigned)want;
  }
  unsigned cols = (unsigned)ceil(sqrt((double)panels.n));
  /* A few wide panels go one under another; many keep the square grid (a
   * column of them would be tens of thousands of pixels tall). */
  while (cols > 1 && panels.n <= 4 && pw > PX_PANEL_W && cols * pw > PX_PANEL_W_MAX) cols--;
  const unsigned prow = (panels.n + cols - 1) / cols;
  const unsigned W = cols * pw;
  size_t legw = 0;
  for (unsigned i = 0; i < nleg; i++)
    if (strlen(leg[i]) > legw) legw = strlen(leg[i]);
  unsigned perrow = nleg ? (unsigned)((W - 40) / (legw * PX_CHAR + 80)) : 1;
  if (!perrow) perrow = 1;
  const unsigned legrows = nleg ? (nleg + perrow - 1) / perrow : 0;
  char caplines[4096];
  /* Wrapped a little short: the font's average is not its widest. */
  const unsigned ncap =
      capt[0] ? wrap(capt, (unsigned)((W - 20) / (PX_CHAR * 1.1)), caplines, sizeof caplines) : 0;
  const unsigned legh = legrows ? legrows * PX_LEGEND_ROW + 8 : 0,
                 caph = ncap ? ncap * PX_CAPTION_LINE + 12 : 0;
  const double boxw = pw - PX_BOX_LEFT - PX_BOX_RIGHT;
  const unsigned nxt = bars ? (twolevel ? groups.n * nside : groups.n) : 0;
  const size_t xtlen = twolevel ? ticklen : grouplen;
  const bool rotate = bars && nxt && xtlen * PX_CHAR > boxw / nxt * 0.95;
  const unsigned boxbottom =
      PX_BOX_BOTTOM + (twolevel ? 18 : 0) + (rotate ? (unsigned)(xtlen * PX_CHAR * 0.5) : 0);
  const unsigned H = PX_TITLE + legh + prow * PX_PANEL_H + caph;

  /* The gnuplot script after `set output`, data inline. */
  FILE *gp = open_memstream(&body, &bodylen);
  CHECK(gp);
  char label[1100];
  /* Okabe and Ito's colour-blind-safe colours, yellow last: gnuplot's
   * default sixth and seventh colours vanish on white. */
  static const char *const COLOURS[] = {"#0072B2", "#D55E00", "#009E73", "#CC79A7",
                                        "#E69F00", "#56B4E9", "#000000", "#F0E442"};
  for (unsigned c = 0; c < 8; c++) fprintf(gp, "set linetype %u lc rgb '%s'\n", c + 1, COLOURS[c]);
  fputs("set linetype cycle 8\nset grid\nunset key\nset pointsize 0.8\nset multiplot\n", gp);
  if (bars) {
    fputs("set grid noxtics ytics\nset xtics scale 0\n", gp);
    if (rotate) fputs("set xtics rotate by 30 right\n", gp);
  }
  /* Stacked bars side by side say what the bars under a group are. */
  if (twolevel) snprintf(label, sizeof label, "%s (bars: %s)", xk, lk);
  else if (bars) snprintf(label, sizeof label, "%s", xk);
  else axis_label(xk, label, sizeof label);
  fputs("set xlabel ", gp);
  gp_str(gp, label);
  fputc('\n', gp);
  if (yunit[0] && strcmp(yunit, ys->pattern))
    snprintf(label, sizeof label, "%s (%s)", ys->pattern, yunit);
  else snprintf(label, sizeof label, "%s", ys->pattern);
  if (twolevel) fputs("set xlabel offset 0,-1.2\n", gp);
  if (logx)
    fprintf(gp, "set logscale x %d\n",
            xa.lo > 0 && all_powers_of_two(xa.ticks, xa.nticks) ? 2 : 10);
  if (logy) fprintf(gp, "set logscale y %d\n", ybase);
  for (unsigned m = 0; m < mk.n; m++)
    fprintf(gp,
            "set arrow from %.17g, graph 0 to %.17g, graph 1 nohead dt 2 lw 1.5 lc rgb 'gray30'\n",
            mk.v[m], mk.v[m]);
  unsigned at = 0;
  for (unsigned p = 0; p < panels.n; p++) {
    const unsigned col = p % cols, prw = p / cols;
    const double left = col * pw, top = PX_TITLE + legh + prw * PX_PANEL_H;
    fprintf(gp, "set lmargin at screen %.6f\nset rmargin at screen %.6f\n",
            (left + PX_BOX_LEFT) / W, (left + pw - PX_BOX_RIGHT) / W);
    fprintf(gp, "set tmargin at screen %.6f\nset bmargin at screen %.6f\n",
            1 - (top + PX_BOX_TOP) / H, 1 - (top + PX_PANEL_H - boxbottom) / H);
    char pt[512] = "";
    if (pc >= 0) {
      char v[256];
      plot_fmt_value(panels.v[p], plot_unit_of(pk), v, sizeof v);
      snprintf(pt, sizeof pt, "%s = %s", pk, v);
    }
    fputs("set title ", gp);
    gp_str(gp, pt);
    /* One y label a row of panels when they share the range. */
    fputs("\nset ylabel ", gp);
    gp_str(gp, own_y || col == 0 ? label : "");
    fputc('\n', gp);
    if (bars) {
      fprintf(gp, "set xrange [%.17g:%.17g]\n", xa.lo, xa.hi);
      fputs("unset label\nset xtics (", gp);
      for (unsigned g = 0, n = 0; g < groups.n; g++) {
        char v[256];
        plot_fmt_value(groups.v[g], xunit, v, sizeof v);
        if (!twolevel) {
          fputs(n++ ? ", " : "", gp);
          gp_str(gp, v);
          fprintf(gp, " %u", g);
          continue;
        }
        for (unsigned b = 0; b < nside; b++) {
          fputs(n++ ? ", " : "", gp);
          gp_str(gp, blab[b]);
          fprintf(gp, " %.17g", g - 0.4 + (b + 0.5) * 0.8 / nside);
        }
      }
      fputs(")\n", gp);
      for (unsigned g = 0; twolevel && g < groups.n; g++) {
        char v[256];
        plot_fmt_value(groups.v[g], xunit, v, sizeof v);
        fputs("set label ", gp);
        gp_str(gp, v);
        fprintf(gp, " at first %u, graph 0 center offset 0,%.1f\n", g,
                -2.3 - (rotate ? xtlen * 0.25 : 0));
      }
    } else {
      gp_range(gp, "x", &xa, xunit);
    }
    gp_range(gp, "y", &yaxes[p], yunit);
    unsigned end = at;
    while (end < nkept && rows[end].panel == p) end++;
    if (bars) {
      /* One data block a colour: x y xlow xhigh ylow yhigh per box. */
      const unsigned ncolour = stacked ? ny : nside;
      fputs("plot ", gp);
      for (unsigned c = 0; c < ncolour; c++)
        fprintf(gp,
                "%s'-' using 1:2:3:4:5:6 with boxxyerror lc %u fs solid 0.85 border lc rgb "
                "'gray20' notitle",
                c ? ", " : "", c + 1);
      fputc('\n', gp);
      for (unsigned c = 0; c < ncolour; c++) {
        for (unsigned i = at; i < end; i++) {
          const struct row *w = &rows[i];
          unsigned b = lc >= 0 ? w->line : stacked ? 0 : c;
          if (!stacked && lc >= 0 && b != c) continue;
          const double l = w->x - 0.4 + b * 0.8 / nside, r = l + 0.8 / nside;
          const double gap = 0.06 * 0.8 / nside;
          double lo = 0, hi;
          if (stacked) {
            for (unsigned k = 0; k < c; k++) lo += w->y[k];
            hi = lo + w->y[c];
          } else {
            hi = w->y[lc >= 0 ? 0 : c];
          }
          fprintf(gp, "%.17g %.17g %.17g %.17g %.17g %.17g\n", (l + r) / 2, hi, l + gap, r - gap,
                  lo, hi);
        }
        /* gnuplot needs a point in every block: an empty one is a box of nothing. */
        fputs("NaN NaN NaN NaN NaN NaN\ne\n", gp);
      }
    } else {
      fputs("plot ", gp);
      unsigned nplotted = 0;
      for (unsigned i = at; i < end; i++) {
        if (i > at && rows[i].line == rows[i - 1].line) continue;
        for (unsigned k = 0; k < ny; k++) {
          const unsigned c = lc >= 0 ? rows[i].line : k;
          fprintf(gp, "%s'-' using 1:2 with %s lc %u pt %u notitle", nplotted++ ? ", " : "",
                  points ? "points ps 1.3" : "linespoints lw 2", c + 1, c % 13 + 1);
        }
      }
      fputc('\n', gp);
      for (unsigned i = at, first = at; i < end; i++) {
        if (i + 1 < end && rows[i + 1].line == rows[i].line) continue;
        for (unsigned k = 0; k < ny; k++) {
          for (unsigned j = first; j <= i; j++)
            fprintf(gp, "%.17g %.17g\n", rows[j].x, rows[j].y[k]);
          fputs("e\n", gp);
        }
        first = i + 1;
      }
    }
    at = end;
  }
  /* The frame: title, the one legend and the caption, over the whole canvas. */
  fputs("unset logscale\nunset arrow\nunset label\nunset title\nunset xlabel\nunset ylabel\n"
        "unset grid\nunset border\nunset tics\nset origin 0,0\nset size 1,1\n"
        "set lmargin at screen 0\nset rmargin at screen 1\nset tmargin at screen 1\n"
        "set bmargin at screen 0\nset xrange [0:1]\nset yrange [0:1]\n",
        gp);
  char title[2200];
  snprintf(title, sizeof title, "%s %s %s", ys->pattern, bars ? "by" : "against", xk);
  fputs("set label ", gp);
  gp_str(gp, title);
  fprintf(gp, " at screen 0.5, screen %.6f center font ',13'\n", 1 - 18.0 / H);
  for (unsigned i = 0, o = 0; i < ncap; i++) {
    fputs("set label ", gp);
    gp_str(gp, caplines + o);
    fprintf(gp, " at screen %.6f, screen %.6f left\n", 10.0 / W,
            (caph - 8 - (i + 0.5) * PX_CAPTION_LINE) / H);
    o += (unsigned)strlen(caplines + o) + 1;
  }
  if (nleg) {
    fprintf(gp,
            "set key at screen 0.5, screen %.6f center top horizontal Left reverse maxrows %u "
            "samplen 3 spacing 1.1\n",
            1 - (PX_TITLE - 4.0) / H, legrows);
    fputs("plot ", gp);
    for (unsigned i = 0; i < nleg; i++) {
      if (bars)
        fprintf(gp, "%sNaN with boxxyerror lc %u fs solid 0.85 border lc rgb 'gray20' title ",
                i ? ", " : "", i + 1);
      else
        fprintf(gp, "%sNaN with %s lc %u pt %u title ", i ? ", " : "",
                points ? "points ps 1.3" : "linespoints lw 2", i + 1, i % 13 + 1);
      gp_str(gp, leg[i]);
    }
    fputc('\n', gp);
  } else {
    fputs("plot NaN notitle\n", gp);
  }
  fputs("unset multiplot\n", gp);
  CHECK(fclose(gp) == 0);
  free(leg);
  free(blab);
  free(yaxes);

  /* The script's head: the terminal and the output, then the body. A signal
   * from here on stops gnuplot and removes the temporaries. */
  outguard_beside(out);
  if (script) outguard_beside(script);
  if (!outfile_open_named(&plot, out, "the plot", &e)) {
    rc = 1;
    goto fail;
  }
  struct gnuplot gnu;
  if (!gnuplot_open(&gnu, false)) {
    err_set(&e, out, 0, 0, "cannot run gnuplot (install gnuplot-nox)");
    rc = 1;
    goto fail;
  }
  FILE *gpipe = gnu.in;
  fprintf(gpipe, "set terminal %s size %u,%u noenhanced font ',11'\nset output ",
          svg ? "svg" : "pngcairo", W, H);
  gp_str(gpipe, plot.tmp);
  fputc('\n', gpipe);
  fwrite(body, 1, bodylen, gpipe);
  if (!gnuplot_close(&gnu)) {
    err_set(&e, out, 0, 0, "gnuplot could not draw the plot (is gnuplot-nox installed?)");
    rc = 1;
    goto fail;
  }
  if (script) {
    if (!outfile_open(&gpfile, script, "the script", &e)) {
      rc = 1;
      goto fail;
    }
    fputs("# rtsim plot's gnuplot script, data inline; made by:\n# rtsim", gpfile.f);
    for (int i = 0; i < argc; i++) fprintf(gpfile.f, " %s", argv[i]);
    fprintf(gpfile.f, "\nset terminal %s size %u,%u noenhanced font ',11'\nset output ",
            svg ? "svg" : "pngcairo", W, H);
    gp_str(gpfile.f, out);
    fputc('\n', gpfile.f);
    fwrite(body, 1, bodylen, gpfile.f);
  }
  if (!outfile_commit(&plot, &e) || (script && !outfile_commit(&gpfile, &e))) {
    rc = 1;
    goto fail;
  }
  if (bars)
    fprintf(stderr, "plot: %u bars in %u group%s, %u panel%s into %s\n", nkept * (stacked ? 1 : ny),
            groups.n, groups.n == 1 ? "" : "s", panels.n, panels.n == 1 ? "" : "s", out);
  else
    fprintf(stderr, "plot: %u points, %u line%s, %u panel%s into %s\n", nkept * ny, lines.n * ny,
            lines.n * ny == 1 ? "" : "s", panels.n, panels.n == 1 ? "" : "s", out);
  rc = 0;
fail:
  outfile_abort(&plot);
  outfile_abort(&gpfile);
  outguard_clear();
  if (e.set) app_report(&e);
  free(body);
  free(drawn);
  free(kept);
  free(rows);
  free(lines.v);
  free(panels.v);
  free(groups.v);
  free(ys);
  csv_free(&t);
  return rc;
}
