/* rtsim plot's figure from a table (app/plot_figure.h): the columns the plan
 * names, the rows it keeps, their values as numbers, the lines, panels and bar
 * groups, and the caption. Cells compare as numbers when both are numbers
 * (same_value), so 0.5 and 5e-1 are one value everywhere. */
#include "app/plot_figure.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "app/csv.h"
#include "app/plot_axis.h"
#include "sim/err.h"
#include "sim/scalar.h"

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

static int cmp_num(const void *a, const void *b) {
  double x, y;
  csv_number(*(const char *const *)a, &x);
  csv_number(*(const char *const *)b, &y);
  return (x > y) - (x < y);
}

static int cmp_nat(const void *a, const void *b) {
  return csv_natural_cmp(*(const char *const *)a, *(const char *const *)b);
}

/* The distinct values of column c over rows[0..nrows): in numeric order when
 * all are numbers, else in natural order; one "" when c < 0. At most limit + 1
 * values are collected (the caller refuses more than
 * limit): the search for a seen value is linear, so the work stays bounded by
 * rows x limit. */
static void distinct(const struct csv_table *t, int c, const unsigned *rows, unsigned nrows,
                     unsigned limit, struct plot_values *out) {
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
static void apply_order(struct plot_values *v, const char *order) {
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

static int cmp_row(const void *a, const void *b) {
  const struct plot_row *p = a, *q = b;
  if (p->panel != q->panel) return p->panel < q->panel ? -1 : 1;
  if (p->line != q->line) return p->line < q->line ? -1 : 1;
  if (p->dash != q->dash) return p->dash < q->dash ? -1 : 1;
  if (p->x != q->x) return p->x < q->x ? -1 : 1;
  return (p->r > q->r) - (p->r < q->r);
}

static unsigned index_of(const struct plot_values *v, const char *s) {
  for (unsigned k = 0; k < v->n; k++)
    if (same_value(v->v[k], s)) return k;
  CHECK(!"value not among the distinct values");
  return 0;
}

static void y_titles(struct plot_ycols *y) {
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

/* Column name's one value over the table rows rows[0..n), or NULL when the
 * table lacks it, it is drawn, or it varies or is empty there. */
static const char *fixed_cell(const struct plot_figure *f, const bool *drawn, const unsigned *rows,
                              unsigned n, const char *name) {
  const int c = csv_column(f->t, name);
  if (c < 0 || (drawn && drawn[c]) || !n) return NULL;
  const char *v = csv_cell(f->t, rows[0], (unsigned)c);
  for (unsigned i = 1; i < n && v[0]; i++)
    if (!same_value(csv_cell(f->t, rows[i], (unsigned)c), v)) return NULL;
  return v[0] ? v : NULL;
}

static double num(const char *cell) {
  double v = 0;
  return cell && csv_number(cell, &v) ? v : 0;
}

/* The DRAM's peak bytes per core cycle over rows (table rows), as the
 * machine reckons it (machine_dram_peak_bytes_per_cycle): a channel's
 * dram.bytes_per_cycle; a banked DRAM's channels x bus x 2 transfers a DRAM
 * cycle, in core cycles; 0 when the rows do not name one DRAM with a peak. */
static double dram_peak_of(const struct plot_figure *f, const unsigned *rows, unsigned n) {
  const char *fid = fixed_cell(f, NULL, rows, n, "fidelity");
  if (!fid) return 0;
  if (!strcmp(fid, "channel")) return num(fixed_cell(f, NULL, rows, n, "dram.bytes_per_cycle"));
  if (strcmp(fid, "banked")) return 0;
  const double ch = num(fixed_cell(f, NULL, rows, n, "dram.channels")),
               bus = num(fixed_cell(f, NULL, rows, n, "dram.bus_bytes")),
               mhz = num(fixed_cell(f, NULL, rows, n, "dram.clock_mhz")),
               ghz = num(fixed_cell(f, NULL, rows, n, "clock_ghz"));
  return ghz > 0 ? ch * bus * 2.0 * mhz / (ghz * 1e3) : 0;
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

/* The DRAM in words, for the caption, from the kept rows' fixed and undrawn
 * columns: its rung, and what sets its speed there (a banked DRAM's
 * channels, clock and peak; a channel's latency and bytes a cycle; a fixed
 * latency). used[c] is set for each column said. Empty without a fidelity
 * column. */
static void dram_words(const struct plot_figure *f, const bool *drawn, bool *used, char *out,
                       size_t cap) {
  static const char *const KEYS[] = {"fidelity", "dram.channels", "dram.clock_mhz", "dram.latency",
                                     "dram.bytes_per_cycle"};
  const char *v[5];
  for (unsigned k = 0; k < 5; k++) v[k] = fixed_cell(f, drawn, f->kept, f->nkept, KEYS[k]);
  out[0] = '\0';
  if (!v[0]) return;
  size_t len = (size_t)snprintf(out, cap, "DRAM: %s", v[0]);
  const bool banked = !strcmp(v[0], "banked"), fixed = !strcmp(v[0], "fixed");
  char a[64], b[64];
#define SAY(...) (len += (size_t)snprintf(out + len, len < cap ? cap - len : 0, __VA_ARGS__))
  if (banked && v[1] && v[2])
    SAY(", %s channel%s at %s MHz", v[1], strcmp(v[1], "1") ? "s" : "", v[2]);
  const double peak = banked ? dram_peak_of(f, f->kept, f->nkept) : 0;
  if (peak > 0) {
    plot_fmt_tick(peak, "", a, sizeof a);
    SAY(", peak %s bytes per cycle", a);
  }
  if (!banked && v[3]) {
    plot_fmt_tick(num(v[3]), "", a, sizeof a);
    SAY(", %s cycles", a);
  }
  if (!banked && !fixed && v[4]) {
    plot_fmt_tick(num(v[4]), "", b, sizeof b);
    SAY(", %s bytes per cycle", b);
  }
#undef SAY
  for (unsigned k = 0; k < 5; k++) {
    const int c = csv_column(f->t, KEYS[k]);
    const bool said = k == 0 || (banked ? k <= 2 : k == 3 || (k == 4 && !fixed));
    if (c >= 0 && v[k] && said) used[c] = true;
  }
}

/* The caption: "key = value unit" for every caption column that is constant
 * over the kept rows and not drawn (x, y, lines, panels), in table order,
 * the DRAM said in words where its fidelity is; then how seeds are drawn. A
 * table none of whose columns is such a key (not rtsim's) gets every
 * constant column that is not drawn. */
static void caption(const struct plot_figure *f, const bool *drawn, char *out, size_t cap) {
  const struct csv_table *t = f->t;
  const unsigned *kept = f->kept, nkept = f->nkept;
  int pc = csv_column(t, "point");
  bool known = pc >= 0;
  for (size_t k = 0; k < sizeof CAPTION_KEYS / sizeof CAPTION_KEYS[0]; k++)
    known |= csv_column(t, CAPTION_KEYS[k]) >= 0;
  size_t len = 0;
  out[0] = '\0';
  int wc = csv_column(t, "width"), hc = csv_column(t, "height"), fc = csv_column(t, "fidelity");
  bool *used = xcalloc(t->ncols, sizeof *used);
  char dram[512];
  dram_words(f, drawn, used, dram, sizeof dram);
  for (unsigned c = 0; c < t->ncols; c++) {
    if (drawn[c] || (int)c == pc) continue;
    if ((int)c == fc && dram[0]) {
      len += (size_t)snprintf(out + len, len < cap ? cap - len : 0, "%s%s", len ? "; " : "", dram);
      continue;
    }
    if (used[c]) continue;
    const char *name = t->names[c];
    bool want = !known;
    for (size_t k = 0; k < sizeof CAPTION_KEYS / sizeof CAPTION_KEYS[0] && !want; k++)
      want = !strcmp(name, CAPTION_KEYS[k]);
    for (unsigned w = 0; w < f->plan->nwhere && !want; w++) want = f->wcol[w] == (int)c;
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
  free(used);
  if (f->seeds_max) {
    char n[32];
    if (f->seeds_min == f->seeds_max) snprintf(n, sizeof n, "%u", f->seeds_max);
    else snprintf(n, sizeof n, "%u to %u", f->seeds_min, f->seeds_max);
    len += (size_t)snprintf(out + len, len < cap ? cap - len : 0,
                            "%s%s: the mean of %s seeds, %s from the smallest to the largest",
                            len ? "; " : "", f->bars ? "bars" : "points", n,
                            f->stacked ? "its total's range not drawn" : "error bars");
  }
  if (len >= cap && cap > 4) strcpy(out + cap - 4, "...");
}

/* The columns the plan names: --x, the --y columns (one unit), --lines,
 * --panels and the --where keys. */
static bool find_columns(struct plot_figure *f, struct err *e) {
  const struct plot_plan *p = f->plan;
  const struct csv_table *t = f->t;
  struct plot_ycols *ys = f->ys;
  if ((f->xc = column(t, "--x", p->x)) < 0) return false;
  /* --y: one column, or several comma-separated (a name with a comma is
   * taken whole when the table has it). */
  snprintf(ys->buf, sizeof ys->buf, "%s", p->y);
  if (csv_column(t, p->y) >= 0 || !strchr(p->y, ',')) {
    ys->name[0] = p->y;
    ys->n = 1;
  } else {
    snprintf(ys->toks, sizeof ys->toks, "%s", p->y);
    for (char *tok = strtok(ys->toks, ","); tok; tok = strtok(NULL, ",")) {
      if (ys->n == PLOT_Y_MAX)
        return err_set(e, t->file, 0, 0, "--y %s: more than %d columns", p->y, PLOT_Y_MAX);
      ys->name[ys->n++] = tok;
    }
  }
  if (!ys->n) return err_set(e, t->file, 0, 0, "--y '%s': no column named", p->y);
  for (unsigned k = 0; k < ys->n; k++)
    if ((ys->col[k] = column(t, "--y", ys->name[k])) < 0) return false;
  f->yunit = plot_unit_of(ys->name[0]);
  for (unsigned k = 1; k < ys->n; k++)
    if (strcmp(plot_unit_of(ys->name[k]), f->yunit))
      return err_set(e, t->file, 0, 0,
                     "--y: %s (%s) and %s (%s) cannot share an axis (expected one unit)",
                     ys->name[0], f->yunit[0] ? f->yunit : "a count", ys->name[k],
                     plot_unit_of(ys->name[k])[0] ? plot_unit_of(ys->name[k]) : "a count");
  y_titles(ys);
  if (p->lines && (f->lc = column(t, "--lines", p->lines)) < 0) return false;
  if (p->panels && (f->pc = column(t, "--panels", p->panels)) < 0) return false;
  if (p->dash && (f->dc = column(t, "--dash", p->dash)) < 0) return false;
  for (unsigned w = 0; w < p->nwhere; w++) {
    char key[256];
    snprintf(key, sizeof key, "%.*s", (int)(strchr(p->where[w], '=') - p->where[w]), p->where[w]);
    if ((f->wcol[w] = column(t, "--where", key)) < 0) return false;
  }
  return true;
}

/* A --where that matches no row, named with the values its column has; else
 * that no row is left. */
static bool no_rows(const struct plot_figure *f, struct err *e) {
  const struct plot_plan *p = f->plan;
  const struct csv_table *t = f->t;
  for (unsigned w = 0; w < p->nwhere && !e->set; w++) {
    bool any = false;
    for (unsigned r = 0; r < t->nrows && !any; r++)
      any = same_value(csv_cell(t, r, (unsigned)f->wcol[w]), strchr(p->where[w], '=') + 1);
    if (any) continue;
    unsigned *all = xcalloc(t->nrows ? t->nrows : 1, sizeof *all);
    for (unsigned r = 0; r < t->nrows; r++) all[r] = r;
    struct plot_values v;
    distinct(t, f->wcol[w], all, t->nrows, 64, &v);
    char list[512] = "";
    for (unsigned k = 0; k < v.n && strlen(list) + 64 < sizeof list; k++) {
      size_t l = strlen(list);
      snprintf(list + l, sizeof list - l, "%s%s", k ? ", " : "", v.v[k]);
    }
    err_set(e, t->file, 0, 0, "--where %s: no row has it (the column holds: %s)", p->where[w],
            list);
    free(v.v);
    free(all);
  }
  if (!e->set)
    err_set(e, t->file, 0, 0, "no row to plot (%s)",
            p->nwhere ? "no row matches every --where together" : "the columns are empty");
  return false;
}

/* The rows --where keeps that have an x and every y. */
static bool keep_rows(struct plot_figure *f, struct err *e) {
  const struct plot_plan *p = f->plan;
  const struct csv_table *t = f->t;
  f->kept = xcalloc(t->nrows ? t->nrows : 1, sizeof *f->kept);
  for (unsigned r = 0; r < t->nrows; r++) {
    bool keep = true;
    for (unsigned w = 0; w < p->nwhere && keep; w++)
      keep = same_value(csv_cell(t, r, (unsigned)f->wcol[w]), strchr(p->where[w], '=') + 1);
    keep = keep && csv_cell(t, r, (unsigned)f->xc)[0];
    for (unsigned k = 0; k < f->ys->n && keep; k++)
      keep = csv_cell(t, r, (unsigned)f->ys->col[k])[0];
    if (keep) f->kept[f->nkept++] = r;
  }
  return f->nkept ? true : no_rows(f, e);
}

/* Lines or bars, and the lines, panels and bar groups with their limits. */
static bool choose_series(struct plot_figure *f, struct err *e) {
  const struct plot_plan *p = f->plan;
  const struct csv_table *t = f->t;
  const unsigned ny = f->ys->n;
  /* A text --x draws bars; an x of numbers and text is a mistake in the
   * table, reported at the first text cell (unless --bars asks for groups). */
  f->bars = p->bars;
  if (!f->bars) {
    bool any_number = false;
    for (unsigned i = 0; i < f->nkept && !any_number; i++) {
      double v;
      any_number = csv_number(csv_cell(t, f->kept[i], (unsigned)f->xc), &v);
    }
    f->bars = !any_number;
  }
  f->stacked = p->stack && ny > 1;
  if (ny > 1 && f->lc >= 0 && !f->stacked)
    return err_set(e, t->file, 0, 0,
                   "--y %s with --lines %s: several --y columns draw a %s each, and so does "
                   "--lines (expected one of them; --stack stacks the columns in each --lines bar)",
                   p->y, p->lines, f->bars ? "bar" : "line");
  if (f->bars && (p->logx || p->logy || p->nmark || p->points || p->dash))
    return err_set(e, t->file, 0, 0,
                   "--x %s holds text: bars have no numeric x and start at 0 (got %s)", p->x,
                   p->logx    ? "--logx"
                   : p->logy  ? "--logy"
                   : p->nmark ? "--mark-x"
                   : p->dash  ? "--dash"
                              : "--points");
  distinct(t, f->lc, f->kept, f->nkept, PLOT_LINES_MAX, &f->lines);
  distinct(t, f->pc, f->kept, f->nkept, PLOT_PANELS_MAX, &f->panels);
  distinct(t, f->dc, f->kept, f->nkept, PLOT_DASHES_MAX, &f->dashes);
  apply_order(&f->dashes, p->order);
  if (f->dashes.n > PLOT_DASHES_MAX)
    return err_set(e, t->file, 1, 0,
                   "--dash %s: more than %d values (expected at most %d dash patterns: keep fewer "
                   "with --where KEY=VALUE)",
                   p->dash, PLOT_DASHES_MAX, PLOT_DASHES_MAX);
  if (f->bars) distinct(t, f->xc, f->kept, f->nkept, PLOT_LINES_MAX, &f->groups);
  apply_order(&f->lines, p->order);
  apply_order(&f->panels, p->order);
  if (f->bars) apply_order(&f->groups, p->order);
  if (f->panels.n > PLOT_PANELS_MAX)
    return err_set(e, t->file, 1, 0,
                   "--panels %s: more than %d values (expected at most %d panels: keep fewer "
                   "with --where KEY=VALUE, or draw the column with --lines)",
                   p->panels, PLOT_PANELS_MAX, PLOT_PANELS_MAX);
  if (f->lines.n > PLOT_LINES_MAX)
    return err_set(e, t->file, 1, 0,
                   "--lines %s: more than %d values (expected at most %d lines: keep fewer with "
                   "--where KEY=VALUE, or spread them with --panels)",
                   p->lines, PLOT_LINES_MAX, PLOT_LINES_MAX);
  if (f->bars && f->groups.n > PLOT_LINES_MAX)
    return err_set(e, t->file, 1, 0,
                   "--x %s: more than %d values for bar groups (expected at most %d: keep fewer "
                   "with --where KEY=VALUE)",
                   p->x, PLOT_LINES_MAX, PLOT_LINES_MAX);
  return true;
}

/* Cell (r, c) as the number w's x (a == ny) or y[a]: on a log axis positive,
 * stacked not negative. */
static bool cell_value(const struct plot_figure *f, struct plot_row *w, unsigned a, struct err *e) {
  const struct plot_plan *p = f->plan;
  const struct csv_table *t = f->t;
  const unsigned ny = f->ys->n;
  const int c = a == ny ? f->xc : f->ys->col[a];
  double *dst = a == ny ? &w->x : &w->y[a];
  unsigned k = (size_t)w->r * t->ncols + (unsigned)c;
  const char *s = t->cells[k];
  if (!csv_number(s, dst)) {
    double ignored;
    enum scalar_why why = scalar_f64(s, &ignored);
    return err_set(e, t->file, t->lines[k], t->cols[k], "%s %s: not a number%s%s (got '%s'); %s",
                   a == ny ? "--x" : "--y", t->names[c], why == SCALAR_SYNTAX ? "" : ": ",
                   scalar_why_text(why), s,
                   a == ny ? "--x needs a numeric column for lines (--bars draws its values as "
                             "groups)"
                           : "--y needs numeric columns (use a text column for --lines or "
                             "--panels)");
  }
  const bool lg = a == ny ? p->logx : p->logy;
  if (lg && *dst <= 0)
    return err_set(e, t->file, t->lines[k], t->cols[k], "%s %s: %s on a log scale (got %s)",
                   a == ny ? "--x" : "--y", t->names[c], "a value must be positive", s);
  if (f->stacked && a < ny && *dst < 0)
    return err_set(e, t->file, t->lines[k], t->cols[k],
                   "--y %s: a stacked value must not be negative (got %s)", t->names[c], s);
  return true;
}

/* Columns that hold a run's seed: rows that differ in one of them and in no
 * parameter are one point measured several times. */
static const char *const SEED_KEYS[] = {"seed", "sample.seed", "sample_seed"};

static bool is_seed(const char *name) {
  for (size_t k = 0; k < sizeof SEED_KEYS / sizeof SEED_KEYS[0]; k++)
    if (!strcmp(name, SEED_KEYS[k])) return true;
  return false;
}

/* Rows r1 and r2 differ in a seed column and in no parameter: no key of
 * their point names, no caption key and no config key (a dotted name). */
static bool seeds_apart(const struct csv_table *t, unsigned r1, unsigned r2) {
  const int pc = csv_column(t, "point");
  bool seed_differs = false;
  for (unsigned c = 0; c < t->ncols; c++) {
    const char *name = t->names[c];
    const bool same = same_value(csv_cell(t, r1, c), csv_cell(t, r2, c));
    if (is_seed(name)) {
      seed_differs |= !same;
      continue;
    }
    bool param =
        strchr(name, '.') || in_point_name(t, pc, r1, name) || in_point_name(t, pc, r2, name);
    for (size_t k = 0; k < sizeof CAPTION_KEYS / sizeof CAPTION_KEYS[0] && !param; k++)
      param = !strcmp(name, CAPTION_KEYS[k]);
    if (param && !same) return false;
  }
  return seed_differs;
}

/* Rows [a, b) (one panel, line and x; seeds apart) into rows[a]: the mean,
 * the smallest and the largest of each y. */
static void merge_seeds(struct plot_figure *f, unsigned a, unsigned b) {
  struct plot_row *w = &f->rows[a];
  for (unsigned k = 0; k < f->ys->n; k++) {
    double sum = 0, lo = w->y[k], hi = w->y[k];
    for (unsigned i = a; i < b; i++) {
      const double v = f->rows[i].y[k];
      sum += v;
      lo = v < lo ? v : lo;
      hi = v > hi ? v : hi;
    }
    w->y[k] = sum / (b - a);
    w->ylo[k] = lo;
    w->yhi[k] = hi;
  }
  w->nseeds = b - a;
  if (!f->seeds_min || w->nseeds < f->seeds_min) f->seeds_min = w->nseeds;
  if (w->nseeds > f->seeds_max) f->seeds_max = w->nseeds;
}

/* The sorted rows with one panel, line and x: seeds of one point merged;
 * else, unless a scatter's (points apart, not a line's one value), refused. */
static bool merge_rows(struct plot_figure *f, struct err *e) {
  const struct csv_table *t = f->t;
  unsigned out = 0;
  for (unsigned a = 0, b; a < f->nkept; a = b) {
    b = a + 1;
    const struct plot_row *r0 = &f->rows[a];
    while (b < f->nkept && f->rows[b].panel == r0->panel && f->rows[b].line == r0->line &&
           f->rows[b].dash == r0->dash && f->rows[b].x == r0->x)
      b++;
    if (f->plan->points) b = a + 1;
    for (unsigned i = a + 1; i < b; i++) {
      bool apart = true;
      for (unsigned j = a; j < i && apart; j++) apart = seeds_apart(t, f->rows[j].r, f->rows[i].r);
      if (apart) continue;
      const struct plot_row *x = &f->rows[i - 1], *y = &f->rows[i];
      char keys[1024];
      differing_keys(t, x->r, y->r, keys, sizeof keys);
      return err_set(e, t->file, t->lines[(size_t)y->r * t->ncols], 0,
                     "rows at lines %d and %d fall on the same %s at %s = %s but differ in %s: "
                     "fix it with --where KEY=VALUE, or show it with --lines or --panels",
                     t->lines[(size_t)x->r * t->ncols], t->lines[(size_t)y->r * t->ncols],
                     f->bars ? "bar" : "line", f->plan->x, csv_cell(t, y->r, (unsigned)f->xc),
                     keys);
    }
    if (b - a > 1) merge_seeds(f, a, b);
    f->rows[out++] = f->rows[a];
  }
  f->nrows = out;
  return true;
}

/* The kept rows as numbers, sorted, seeds merged. */
static bool make_rows(struct plot_figure *f, struct err *e) {
  const struct csv_table *t = f->t;
  const unsigned ny = f->ys->n;
  f->rows = xcalloc(f->nkept, sizeof *f->rows);
  for (unsigned i = 0; i < f->nkept; i++) {
    unsigned r = f->kept[i];
    struct plot_row *w = &f->rows[i];
    w->r = r;
    for (unsigned a = 0; a <= ny; a++) {
      /* a == ny is --x. */
      if (a == ny && f->bars) w->x = index_of(&f->groups, csv_cell(t, r, (unsigned)f->xc));
      else if (!cell_value(f, w, a, e)) return false;
    }
    for (unsigned k = 0; k < ny; k++) w->ylo[k] = w->yhi[k] = w->y[k];
    w->nseeds = 1;
    w->line = f->lc < 0 ? 0 : index_of(&f->lines, csv_cell(t, r, (unsigned)f->lc));
    w->panel = f->pc < 0 ? 0 : index_of(&f->panels, csv_cell(t, r, (unsigned)f->pc));
    w->dash = f->dc < 0 ? 0 : index_of(&f->dashes, csv_cell(t, r, (unsigned)f->dc));
  }
  qsort(f->rows, f->nkept, sizeof *f->rows, cmp_row);
  return merge_rows(f, e);
}

/* Each panel's peak line: --peak's, or where every --y column is DRAM bytes
 * per cycle the DRAM's peak over the panel's rows. */
static void find_peaks(struct plot_figure *f) {
  const struct plot_plan *p = f->plan;
  f->peak = xcalloc(f->panels.n, sizeof *f->peak);
  bool dram = !p->no_peak && !p->peak_given && !strcmp(f->yunit, "bytes per cycle");
  for (unsigned k = 0; k < f->ys->n && dram; k++) dram = !strncmp(f->ys->name[k], "dram", 4);
  f->dram_peak = dram;
  unsigned *rows = xcalloc(f->nkept, sizeof *rows);
  for (unsigned pn = 0; pn < f->panels.n; pn++) {
    if (p->peak_given) {
      f->peak[pn] = p->peak;
      continue;
    }
    if (!dram) continue;
    unsigned n = 0;
    for (unsigned i = 0; i < f->nkept; i++)
      if (f->pc < 0 || same_value(csv_cell(f->t, f->kept[i], (unsigned)f->pc), f->panels.v[pn]))
        rows[n++] = f->kept[i];
    f->peak[pn] = dram_peak_of(f, rows, n);
  }
  free(rows);
}

bool plot_figure_build(struct plot_figure *f, const struct plot_plan *p, const struct csv_table *t,
                       struct err *e) {
  memset(f, 0, sizeof *f);
  f->plan = p;
  f->t = t;
  f->ys = xcalloc(1, sizeof *f->ys);
  f->lc = f->pc = f->dc = -1;
  if (!find_columns(f, e) || !keep_rows(f, e) || !choose_series(f, e) || !make_rows(f, e))
    return false;
  find_peaks(f);
  /* The caption: the fixed parameters, every column not drawn. */
  bool *drawn = xcalloc(t->ncols, sizeof *drawn);
  drawn[f->xc] = true;
  for (unsigned k = 0; k < f->ys->n; k++) drawn[f->ys->col[k]] = true;
  if (f->lc >= 0) drawn[f->lc] = true;
  if (f->pc >= 0) drawn[f->pc] = true;
  if (f->dc >= 0) drawn[f->dc] = true;
  caption(f, drawn, f->caption, sizeof f->caption);
  free(drawn);
  return true;
}

void plot_figure_fini(struct plot_figure *f) {
  free(f->kept);
  free(f->rows);
  free(f->peak);
  free(f->lines.v);
  free(f->panels.v);
  free(f->groups.v);
  free(f->dashes.v);
  free(f->ys);
  memset(f, 0, sizeof *f);
}
