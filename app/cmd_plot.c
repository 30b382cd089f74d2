/* rtsim plot: line plots of a tidy table (rtsim merge's, or any CSV with a
 * header) through gnuplot: METRIC against KEY, one line per value of a
 * --lines column, one panel per value of a --panels column, units on the
 * axes from the column names. The script goes to gnuplot on a pipe with the
 * data inline; the picture is written under a temporary name and renamed
 * (sim/outfile.h). */
#include "app/app.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "app/csv.h"
#include "app/opts.h"
#include "sim/err.h"
#include "sim/outfile.h"
#include "sim/scalar.h"

static const char HELP[] =
    "usage: rtsim plot TABLE.csv --x KEY --y METRIC -o FILE.png|FILE.svg [options]\n"
    "\n"
    "Plot column METRIC against column KEY of a tidy table (rtsim merge's) as\n"
    "lines with points, through gnuplot. Axis labels carry the unit the column\n"
    "name gives: _bytes, l1.size, l2.size: bytes; cycles, _cycles, .latency,\n"
    "costs., timeline.window, _wait_mean, _latency_mean/_p50/_p95/_p99/_max:\n"
    "cycles; _fraction,\n"
    "utilization, _rate: fraction; _per_second: per second; _bytes_per_cycle:\n"
    "bytes per cycle; seconds, _s: seconds; clock_ghz: GHz; _mb: MiB; anything\n"
    "else is a count or a label. Rows with an empty KEY or METRIC cell are left out.\n"
    "\n"
    "options:\n"
    "  --x KEY            the x axis (a numeric column)\n"
    "  --y METRIC         the y axis (a numeric column)\n"
    "  --lines KEY        one line per value of this column, with a legend (at\n"
    "                     most 100)\n"
    "  --panels KEY       one panel per value of this column (at most 100)\n"
    "  --where KEY=VALUE  keep only rows where KEY is VALUE (numbers compare as\n"
    "                     numbers); repeatable. Every other column that varies\n"
    "                     must be fixed so, or be --lines or --panels: two rows\n"
    "                     at the same x on one line are refused\n"
    "  --logx, --logy     logarithmic axis (base 2 when every value is a power of 2)\n"
    "  --mark-x X         a dashed vertical line at x = X in every panel (e.g. a\n"
    "                     value a paper names); repeatable\n"
    "  -o FILE            the plot: .png (pngcairo) or .svg\n"
    "  -h, --help         this text\n";

#define PLOT_WHERE_MAX 32
/* Most panels a plot may have: the picture grows with them (a square grid of
 * 620x420-pixel panels: 100 make 6200x4200 pixels, about 100 MB for gnuplot;
 * 2,500 took gnuplot a minute and 2.5 GB), and past a hundred no panel can
 * be read anyway. */
#define PLOT_PANELS_MAX 100
/* Most lines a panel may have: a legend of more cannot be read, and the
 * colours repeat long before. */
#define PLOT_LINES_MAX 100

/* The unit a column's name states, or "" (a count or a label). */
static const char *unit_of(const char *name) {
  size_t n = strlen(name);
#define ENDS(s) (n >= strlen(s) && !strcmp(name + n - strlen(s), s))
#define STARTS(s) (!strncmp(name, s, strlen(s)))
  if (ENDS("_bytes_per_cycle") || !strcmp(name, "dram.bytes_per_cycle")) return "bytes per cycle";
  if (ENDS("_per_cycle")) return "per cycle";
  if (ENDS("_bytes") || !strcmp(name, "l1.size") || !strcmp(name, "l2.size")) return "bytes";
  if (ENDS("_per_second")) return "per second";
  if (!strcmp(name, "cycles") || ENDS("_cycles") || ENDS(".latency") || STARTS("costs.") ||
      !strcmp(name, "timeline.window") || ENDS("_wait_mean") || STARTS("load_latency_") ||
      (STARTS("dram_") && strstr(name, "_latency_")))
    return "cycles";
  if (ENDS("_fraction") || ENDS("utilization") || ENDS("_rate")) return "fraction";
  if (!strcmp(name, "seconds") || ENDS("_s")) return "seconds";
  if (!strcmp(name, "clock_ghz")) return "GHz";
  if (ENDS("_mb")) return "MiB";
  return "";
#undef ENDS
#undef STARTS
}

static void axis_label(const char *name, char *out, size_t cap) {
  const char *u = unit_of(name);
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

static bool all_powers_of_two(const double *v, unsigned n) {
  for (unsigned i = 0; i < n; i++) {
    int ex;
    if (frexp(v[i], &ex) != 0.5) return false;
  }
  return true;
}

struct row {
  unsigned r;
  double x, y;
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

#define PLOT_AT_MOST_(s) " (at most " #s ")"
#define PLOT_AT_MOST(s) PLOT_AT_MOST_(s)

int cmd_plot(int argc, char **argv) {
  const char *xk = NULL, *yk = NULL, *lk = NULL, *pk = NULL, *out = NULL;
  struct wheres wh = {.n = 0};
  struct marks mk = {.n = 0};
  bool logx = false, logy = false;
  const struct opts_spec spec[] = {
      OPTS_STR("x", 0, &xk),
      OPTS_STR("y", 0, &yk),
      OPTS_STR("lines", 0, &lk),
      OPTS_STR("panels", 0, &pk),
      OPTS_PARSE("where", 0, &wh, add_where, "KEY=VALUE" PLOT_AT_MOST(PLOT_WHERE_MAX)),
      OPTS_FLAG("logx", 0, &logx),
      OPTS_FLAG("logy", 0, &logy),
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
  if (!xk || !yk) return app_usage_error("plot", "missing --%s", xk ? "y METRIC" : "x KEY");
  if (!out) return app_usage_error("plot", "missing -o FILE.png or FILE.svg");
  size_t ol = strlen(out);
  bool svg = ol > 4 && !strcmp(out + ol - 4, ".svg");
  if (!svg && !(ol > 4 && !strcmp(out + ol - 4, ".png")))
    return app_usage_error("plot", "-o %s: expected a .png or .svg file", out);

  struct csv_table t;
  struct err e = {0};
  rc = APP_EXIT_USAGE;
  unsigned *kept = NULL;
  struct row *rows = NULL;
  struct values lines = {0}, panels = {0};
  struct outfile plot = {0};
  if (!csv_read(&t, table, &e)) return app_report(&e);
  int xc = column(&t, "--x", xk), yc = xc < 0 ? -1 : column(&t, "--y", yk);
  int lc = -1, pc = -1;
  if (yc >= 0 && lk && (lc = column(&t, "--lines", lk)) < 0) goto fail;
  if (yc >= 0 && pk && (pc = column(&t, "--panels", pk)) < 0) goto fail;
  if (yc < 0) goto fail;

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
    if (keep && csv_cell(&t, r, (unsigned)xc)[0] && csv_cell(&t, r, (unsigned)yc)[0])
      kept[nkept++] = r;
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
  distinct(&t, lc, kept, nkept, PLOT_LINES_MAX, &lines);
  distinct(&t, pc, kept, nkept, PLOT_PANELS_MAX, &panels);
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
  rows = xcalloc(nkept, sizeof *rows);
  for (unsigned i = 0; i < nkept; i++) {
    unsigned r = kept[i];
    struct row *w = &rows[i];
    w->r = r;
    const int cs[2] = {xc, yc};
    double *dst[2] = {&w->x, &w->y};
    const bool lg[2] = {logx, logy};
    for (int a = 0; a < 2; a++) {
      unsigned k = (size_t)r * t.ncols + (unsigned)cs[a];
      const char *s = t.cells[k];
      if (!csv_number(s, dst[a])) {
        double ignored;
        enum scalar_why why = scalar_f64(s, &ignored);
        err_set(&e, t.file, t.lines[k], t.cols[k],
                "%s %s: not a number%s%s (got '%s'); --x and --y need numeric columns (use a "
                "text column for --lines or --panels)",
                a ? "--y" : "--x", t.names[cs[a]], why == SCALAR_SYNTAX ? "" : ": ",
                scalar_why_text(why), s);
        goto fail;
      }
      if (lg[a] && *dst[a] <= 0) {
        err_set(&e, t.file, t.lines[k], t.cols[k], "%s %s: %s on a log scale (got %s)",
                a ? "--y" : "--x", t.names[cs[a]], "a value must be positive", s);
        goto fail;
      }
    }
    w->line = lc < 0 ? 0 : index_of(&lines, csv_cell(&t, r, (unsigned)lc));
    w->panel = pc < 0 ? 0 : index_of(&panels, csv_cell(&t, r, (unsigned)pc));
  }
  qsort(rows, nkept, sizeof *rows, cmp_row);
  for (unsigned i = 1; i < nkept; i++) {
    const struct row *a = &rows[i - 1], *b = &rows[i];
    if (a->panel != b->panel || a->line != b->line || a->x != b->x) continue;
    char keys[1024];
    differing_keys(&t, a->r, b->r, keys, sizeof keys);
    err_set(&e, t.file, t.lines[(size_t)b->r * t.ncols], 0,
            "rows at lines %d and %d fall on the same line at %s = %s but differ in %s: fix "
            "it with --where KEY=VALUE, or show it with --lines or --panels",
            t.lines[(size_t)a->r * t.ncols], t.lines[(size_t)b->r * t.ncols], xk,
            csv_cell(&t, b->r, (unsigned)xc), keys);
    goto fail;
  }

  /* The gnuplot script, data inline. */
  double *xs = xcalloc(nkept, sizeof *xs), *ys = xcalloc(nkept, sizeof *ys);
  for (unsigned i = 0; i < nkept; i++) xs[i] = rows[i].x, ys[i] = rows[i].y;
  const int xbase = all_powers_of_two(xs, nkept) ? 2 : 10, ybase = all_powers_of_two(ys, nkept) ? 2 : 10;
  free(xs);
  free(ys);
  unsigned cols = (unsigned)ceil(sqrt((double)panels.n)), prow = (panels.n + cols - 1) / cols;
  char label[512];
  if (!outfile_open_named(&plot, out, "the plot", &e)) {
    rc = 1;
    goto fail;
  }
  FILE *gp = popen("gnuplot >/dev/null", "w");
  if (!gp) {
    err_set(&e, out, 0, 0, "cannot run gnuplot (install gnuplot-nox)");
    rc = 1;
    goto fail;
  }
  fprintf(gp, "set terminal %s size %u,%u noenhanced font ',11'\nset output ", svg ? "svg" : "pngcairo",
          cols * 620, prow * 420);
  gp_str(gp, plot.tmp);
  fputs("\nset grid\nset key outside right top\nset pointsize 0.8\n", gp);
  axis_label(xk, label, sizeof label);
  fputs("set xlabel ", gp);
  gp_str(gp, label);
  axis_label(yk, label, sizeof label);
  fputs("\nset ylabel ", gp);
  gp_str(gp, label);
  fputc('\n', gp);
  if (logx) fprintf(gp, "set logscale x %d\n", xbase);
  for (unsigned m = 0; m < mk.n; m++)
    fprintf(gp, "set arrow from %.17g, graph 0 to %.17g, graph 1 nohead dt 2 lw 1.5 lc rgb 'gray30'\n",
            mk.v[m], mk.v[m]);
  if (logy) fprintf(gp, "set logscale y %d\n", ybase);
  char title[1024];
  snprintf(title, sizeof title, "%s against %s%s", yk, xk, nwhere ? " where " : "");
  for (unsigned w = 0; w < nwhere; w++) {
    size_t l = strlen(title);
    snprintf(title + l, sizeof title - l, "%s%s", w ? ", " : "", where[w]);
  }
  fprintf(gp, "set multiplot layout %u,%u title ", prow, cols);
  gp_str(gp, title);
  fputc('\n', gp);
  /* rows are sorted by panel, line and x: each panel is one run of rows, each
   * of its lines a run within it, so the script takes one pass. */
  unsigned at = 0;
  for (unsigned p = 0; p < panels.n; p++) {
    char pt[512] = "";
    if (pc >= 0) snprintf(pt, sizeof pt, "%s = %s", pk, panels.v[p]);
    fputs("set title ", gp);
    gp_str(gp, pt);
    fputs("\nplot ", gp);
    unsigned nplotted = 0, end = at;
    while (end < nkept && rows[end].panel == p) end++;
    for (unsigned i = at; i < end; i++) {
      if (i > at && rows[i].line == rows[i - 1].line) continue;
      const unsigned l = rows[i].line;
      char lt[512];
      if (lc >= 0) snprintf(lt, sizeof lt, "%s = %s", lk, lines.v[l]);
      else snprintf(lt, sizeof lt, "%s", yk);
      fprintf(gp, "%s'-' using 1:2 with linespoints lw 2 lc %u pt %u title ", nplotted ? ", " : "",
              l + 1, l % 13 + 1);
      gp_str(gp, lt);
      nplotted++;
    }
    fputc('\n', gp);
    for (unsigned i = at; i < end; i++) {
      fprintf(gp, "%.17g %.17g\n", rows[i].x, rows[i].y);
      if (i + 1 == end || rows[i + 1].line != rows[i].line) fputs("e\n", gp);
    }
    at = end;
  }
  fputs("unset multiplot\n", gp);
  if (pclose(gp) != 0) {
    err_set(&e, out, 0, 0, "gnuplot could not draw the plot (is gnuplot-nox installed?)");
    rc = 1;
    goto fail;
  }
  if (!outfile_commit(&plot, &e)) {
    rc = 1;
    goto fail;
  }
  fprintf(stderr, "plot: %u points, %u line%s, %u panel%s into %s\n", nkept, lines.n,
          lines.n == 1 ? "" : "s", panels.n, panels.n == 1 ? "" : "s", out);
  rc = 0;
fail:
  outfile_abort(&plot);
  if (e.set) app_report(&e);
  free(kept);
  free(rows);
  free(lines.v);
  free(panels.v);
  csv_free(&t);
  return rc;
}
