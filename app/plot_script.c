/* rtsim plot's gnuplot script (app/plot_script.h): the axes (x the same in
 * every panel; y one range for all panels unless --own-y), the legend, the
 * layout in pixels, then the script: a head, a panel at a time with its data
 * inline, and the frame (title, legend, caption) over the whole canvas. */
#include "app/plot_script.h"

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "app/csv.h"
#include "app/plot_axis.h"
#include "app/plot_figure.h"
#include "sim/err.h"

/* The figure's layout in pixels: a panel's cell, the plot box inside it, the
 * strips for the title, the legend's rows and the caption's lines. gnuplot's
 * own placement sizes each panel to its tick labels and repeats the key in
 * every panel; fixed margins keep the panels aligned. */
#define PX_PANEL_W 520
#define PX_PANEL_H 390
/* Widest a panel of bars grows, and widest a row of panels. */
#define PX_PANEL_W_MAX 1400
#define PX_BOX_LEFT 100
#define PX_BOX_RIGHT 32
#define PX_BOX_TOP 34
#define PX_BOX_BOTTOM 66
#define PX_TITLE 40
/* A title's further lines. */
#define PX_TITLE_LINE 20
#define PX_LEGEND_ROW 21
#define PX_CAPTION_LINE 18
/* The tag of the peak line's arrow (--mark-x's take the first tags). */
#define PEAK_ARROW 1000
/* Most points a line draws with markers. */
#define PLOT_MARKERS_MAX 60
/* Colours before the series repeat them dashed. */
#define PLOT_COLOURS 7
/* About the width of a character of the 11-point font (pngcairo and svg). */
#define PX_CHAR 7.2

void plot_script_str(FILE *f, const char *s) {
  fputc('\'', f);
  for (; *s; s++) {
    if (*s == '\'') fputc('\'', f);
    if (*s != '\n') fputc(*s, f);
  }
  fputc('\'', f);
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

/* A gnuplot tick list: ('label' pos, ...). */
static void gp_ticks(FILE *f, const char *axis, const struct plot_axis *a, const char *unit) {
  fprintf(f, "set %stics (", axis);
  for (unsigned i = 0; i < a->nticks; i++) {
    char l[64];
    plot_fmt_tick(a->ticks[i], unit, l, sizeof l);
    if (i) fputs(", ", f);
    plot_script_str(f, l);
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
static void axis_fixed(struct plot_axis *a, double lo, double hi, bool log, int base) {
  struct plot_axis n;
  plot_axis_nice(&n, lo, hi, log, base, false, false);
  a->lo = lo;
  a->hi = hi;
  a->log = log;
  a->nticks = 0;
  for (unsigned i = 0; i < n.nticks; i++)
    if (n.ticks[i] >= lo * (1 - 1e-12) && n.ticks[i] <= hi * (1 + 1e-12))
      a->ticks[a->nticks++] = n.ticks[i];
}

/* The y extent of rows [a, b): each value with its seeds' range, or for
 * stacked bars each bar's sum. */
static void y_extent(const struct plot_row *rows, unsigned a, unsigned b, unsigned ny, bool stack,
                     double *min, double *max) {
  *min = INFINITY;
  *max = -INFINITY;
  for (unsigned i = a; i < b; i++) {
    double sum = 0;
    for (unsigned k = 0; k < ny; k++) {
      sum += rows[i].y[k];
      if (!stack) *min = fmin(*min, rows[i].ylo[k]), *max = fmax(*max, rows[i].yhi[k]);
    }
    if (stack) *min = fmin(*min, sum), *max = fmax(*max, sum);
  }
}

/* Wrap text at sep ("; " or " ") into lines of at most width characters
 * (a longer word is cut); the number of lines. Each line is written to out
 * as a NUL-separated run. */
static unsigned wrap(const char *text, unsigned width, const char *sep, char *out, size_t cap) {
  unsigned n = 0;
  size_t o = 0;
  const char *p = text;
  while (*p && o + 2 < cap) {
    size_t len = strlen(p), take = len, last = 0;
    if (len > width) {
      take = 0;
      for (const char *s = p; (s = strstr(s, sep)) && (size_t)(s - p) + 1 <= width;
           s += strlen(sep))
        take = (size_t)(s - p) + 1;
      /* A part too long for a line: at a space, else anywhere. */
      for (const char *s = p; !take && (s = strchr(s, ' ')) && (size_t)(s - p) <= width; s++)
        last = (size_t)(s - p);
      if (!take) take = last ? last : width;
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

/* Rows a and b are on one series: the same line and dash. */
static bool same_series(const struct plot_row *a, const struct plot_row *b) {
  return a->line == b->line && a->dash == b->dash;
}

/* What the script draws besides the figure: axes, legend, layout. */
struct layout {
  const char *xunit;
  struct plot_axis xa;
  struct plot_axis *yaxes; /* one a panel */
  int ybase;
  unsigned nside;   /* bars side by side in a group */
  char (*leg)[512]; /* the legend's entries, one a colour */
  unsigned nleg;
  char (*blab)[256]; /* the labels under stacked bars side by side */
  bool twolevel;     /* stacked bars side by side: labels under bars and groups */
  size_t xtlen;      /* the longest x tick label, in characters */
  bool rotate;       /* x tick labels turned */
  unsigned pw, cols; /* a panel's width, panels a row */
  unsigned W, H;     /* the canvas */
  unsigned legrows, legh, ncap, caph, boxbottom;
  char caplines[4096];                /* the caption wrapped: NUL-separated lines */
  char title[2200], titlelines[2400]; /* the title, and wrapped as caplines */
  unsigned ntitle, titleh;            /* its lines, and the strip they take */
  char ylabel[1100];
  char peakleg[160];               /* the peak line's legend entry, or "" */
  char dleg[PLOT_DASHES_MAX][512]; /* --dash's entries, a dash pattern each */
  unsigned ndleg;
  bool dense; /* a series has more points than markers can show apart */
};

/* The axes. x: the same in every panel; at the values themselves when a
 * sweep's few, else round ticks. y: one range for every panel unless
 * --own-y; a fraction on 0..1. */
static void make_axes(const struct plot_figure *f, struct layout *L) {
  const struct plot_plan *p = f->plan;
  const unsigned nkept = f->nrows, ny = f->ys->n;
  const struct plot_row *rows = f->rows;
  const bool yfrac = !strcmp(f->yunit, "fraction");
  double *xs = xcalloc(nkept, sizeof *xs), *yv = xcalloc((size_t)nkept * ny, sizeof *yv);
  unsigned nx = 0;
  for (unsigned i = 0; i < nkept; i++) {
    xs[nx++] = rows[i].x;
    for (unsigned k = 0; k < ny; k++) yv[(size_t)i * ny + k] = rows[i].y[k];
  }
  L->ybase = all_powers_of_two(yv, nkept * ny) ? 2 : 10;
  const int xbase = all_powers_of_two(xs, nx) ? 2 : 10;
  qsort(xs, nx, sizeof *xs, cmp_double);
  unsigned nd = 0;
  for (unsigned i = 0; i < nx; i++)
    if (!nd || xs[i] != xs[nd - 1]) xs[nd++] = xs[i];
  if (f->bars) {
    L->xa.lo = -0.5;
    L->xa.hi = f->groups.n - 0.5;
    L->xa.log = false;
    L->xa.nticks = 0;
  } else if (!plot_axis_at_values(&L->xa, xs, nd, p->logx)) {
    plot_axis_nice(&L->xa, xs[0], xs[nd - 1], p->logx, xbase, false, false);
  }
  free(xs);
  free(yv);
  L->yaxes = xcalloc(f->panels.n, sizeof *L->yaxes);
  unsigned at = 0;
  double gmin = INFINITY, gmax = -INFINITY;
  /* From 0 unless asked otherwise: a range around the values makes a small
   * change look steep. Bars start at 0 whatever is asked. */
  const bool zero = f->bars || (!p->y_from_data && !p->logy);
  for (unsigned pn = 0; pn < f->panels.n; pn++) {
    unsigned end = at;
    while (end < nkept && rows[end].panel == pn) end++;
    double mn, mx;
    y_extent(rows, at, end, ny, f->stacked, &mn, &mx);
    /* The peak line is in the range: it says how far the values are from it. */
    if (f->peak[pn] > 0) mn = fmin(mn, f->peak[pn]), mx = fmax(mx, f->peak[pn]);
    gmin = fmin(gmin, mn);
    gmax = fmax(gmax, mx);
    if (p->own_y) plot_axis_nice(&L->yaxes[pn], mn, mx, p->logy, L->ybase, yfrac, zero);
    at = end;
  }
  for (unsigned pn = 0; pn < f->panels.n && !p->own_y; pn++) {
    if (p->yrange) axis_fixed(&L->yaxes[pn], p->ylo, p->yhi, p->logy, L->ybase);
    else plot_axis_nice(&L->yaxes[pn], gmin, gmax, p->logy, L->ybase, yfrac, zero);
  }
}

/* The series: what one colour stands for. Lines: a --lines value or a --y
 * column. Bars: side by side in a group, a --lines value or (unstacked) a
 * --y column; stacked, the colours are the --y columns. */
static void make_legend(const struct plot_figure *f, struct layout *L) {
  const unsigned ny = f->ys->n;
  L->nside = f->bars ? (f->lc >= 0 ? f->lines.n : f->stacked ? 1 : ny) : 1;
  L->leg = xcalloc(PLOT_LINES_MAX + PLOT_Y_MAX, sizeof *L->leg);
  if (f->stacked) {
    for (unsigned k = 0; k < ny; k++)
      snprintf(L->leg[L->nleg++], sizeof L->leg[0], "%s", f->ys->title[k]);
  } else if (f->lc >= 0) {
    const char *lu = plot_unit_of(f->plan->lines);
    for (unsigned l = 0; l < f->lines.n; l++) {
      char v[256];
      plot_fmt_value(f->lines.v[l], lu, v, sizeof v);
      snprintf(L->leg[L->nleg++], sizeof L->leg[0], "%s = %s", f->plan->lines, v);
    }
  } else if (ny > 1) {
    for (unsigned k = 0; k < ny; k++)
      snprintf(L->leg[L->nleg++], sizeof L->leg[0], "%s", f->ys->title[k]);
  }
  /* --dash's patterns, in grey: the colours are the lines'. */
  for (unsigned d = 0; f->dc >= 0 && d < f->dashes.n; d++) {
    char v[256];
    plot_fmt_value(f->dashes.v[d], plot_unit_of(f->plan->dash), v, sizeof v);
    snprintf(L->dleg[L->ndleg++], sizeof L->dleg[0], "%s = %s", f->plan->dash, v);
  }
  /* Markers apart need room: a box about 400 pixels wide shows 60 a line. */
  for (unsigned i = 0, run = 0; i < f->nrows; i++) {
    const bool same =
        i && f->rows[i].panel == f->rows[i - 1].panel && same_series(&f->rows[i], &f->rows[i - 1]);
    run = same ? run + 1 : 1;
    L->dense |= run > PLOT_MARKERS_MAX;
  }
  /* The peak line's entry: its value when every panel has the same. */
  double peak = 0;
  bool one = true;
  for (unsigned pn = 0; pn < f->panels.n; pn++) {
    if (f->peak[pn] > 0 && peak > 0 && f->peak[pn] != peak) one = false;
    if (f->peak[pn] > 0) peak = f->peak[pn];
  }
  L->peakleg[0] = '\0';
  if (peak > 0) {
    const char *what = f->dram_peak ? "DRAM peak" : "peak";
    char v[64];
    plot_fmt_tick(peak, f->yunit, v, sizeof v);
    /* The unit is the y axis's: the entry stays short, the legend a row. */
    if (!one) snprintf(L->peakleg, sizeof L->peakleg, "%s", what);
    else snprintf(L->peakleg, sizeof L->peakleg, "%s: %s", what, v);
  }
}

/* A column's axis label without the unit in parentheses (a title's words:
 * work_s "work", not "work s"). */
static void words_of(const char *name, const char *unit, char *out, size_t cap) {
  plot_axis_label(name, unit, out, cap);
  const size_t n = strlen(out), u = strlen(unit);
  if (u && n > u + 3 && !strncmp(out + n - u - 3, " (", 2) && !strncmp(out + n - u - 1, unit, u))
    out[n - u - 3] = '\0';
}

/* The y axis in words without its unit (the default title's). */
static void y_words(const struct plot_figure *f, char *out, size_t cap) {
  const struct plot_ycols *ys = f->ys;
  if (ys->n == 1 || strchr(ys->pattern, '*')) {
    words_of(ys->pattern, f->yunit, out, cap);
    return;
  }
  /* Columns with nothing in common: each named. */
  size_t len = 0;
  out[0] = '\0';
  for (unsigned k = 0; k < ys->n; k++) {
    char w[256];
    words_of(ys->name[k], f->yunit, w, sizeof w);
    len += (size_t)snprintf(out + len, len < cap ? cap - len : 0, "%s%s", k ? ", " : "", w);
  }
}

/* The title, --title's or the axes' words, wrapped at spaces to the canvas's
 * width in the title's 13-point font, so no line runs off an edge. */
static void make_title(const struct plot_figure *f, struct layout *L, unsigned W) {
  const struct plot_plan *p = f->plan;
  if (p->title) {
    snprintf(L->title, sizeof L->title, "%s", p->title);
  } else {
    char y[1024], x[512];
    y_words(f, y, sizeof y);
    words_of(p->x, L->xunit, x, sizeof x);
    snprintf(L->title, sizeof L->title, "%s %s %s", y, f->bars ? "by" : "against", x);
  }
  const unsigned width = (unsigned)((W - 40) / (PX_CHAR * 13 / 11 * 1.1));
  L->ntitle = L->title[0] ? wrap(L->title, width, " ", L->titlelines, sizeof L->titlelines) : 0;
  L->titleh = L->ntitle > 1 ? PX_TITLE + (L->ntitle - 1) * PX_TITLE_LINE : PX_TITLE;
}

/* The layout. Bars get the width their labels need (up to a limit, past
 * which the labels turn), and panels too wide to sit side by side go one
 * under another. */
static void make_layout(const struct plot_figure *f, struct layout *L) {
  size_t ticklen = 0, grouplen = 0;
  const bool bars = f->bars;
  L->blab = xcalloc(f->lines.n ? f->lines.n : 1, sizeof *L->blab);
  L->twolevel = bars && f->stacked && L->nside > 1;
  for (unsigned g = 0; bars && g < f->groups.n; g++) {
    char v[256];
    plot_fmt_value(f->groups.v[g], L->xunit, v, sizeof v);
    if (strlen(v) > grouplen) grouplen = strlen(v);
  }
  for (unsigned l = 0; L->twolevel && l < f->lines.n; l++) {
    plot_fmt_value(f->lines.v[l], plot_unit_of(f->plan->lines), L->blab[l], sizeof L->blab[l]);
    if (strlen(L->blab[l]) > ticklen) ticklen = strlen(L->blab[l]);
  }
  unsigned pw = PX_PANEL_W;
  if (bars) {
    double group = grouplen * PX_CHAR + 16;
    if (L->twolevel && L->nside * (ticklen * PX_CHAR + 10) > group)
      group = L->nside * (ticklen * PX_CHAR + 10);
    double want = group * f->groups.n + PX_BOX_LEFT + PX_BOX_RIGHT;
    if (want > pw) pw = want > PX_PANEL_W_MAX ? PX_PANEL_W_MAX : (unsigned)want;
  }
  const unsigned npanels = f->panels.n;
  unsigned cols = (unsigned)ceil(sqrt((double)npanels));
  /* A few wide panels go one under another; many keep the square grid (a
   * column of them would be tens of thousands of pixels tall). */
  while (cols > 1 && npanels <= 4 && pw > PX_PANEL_W && cols * pw > PX_PANEL_W_MAX) cols--;
  const unsigned prow = (npanels + cols - 1) / cols;
  const unsigned W = cols * pw;
  size_t legw = strlen(L->peakleg);
  const unsigned nent = L->nleg + L->ndleg + (L->peakleg[0] != '\0');
  for (unsigned i = 0; i < L->nleg; i++)
    if (strlen(L->leg[i]) > legw) legw = strlen(L->leg[i]);
  for (unsigned i = 0; i < L->ndleg; i++)
    if (strlen(L->dleg[i]) > legw) legw = strlen(L->dleg[i]);
  unsigned perrow = nent ? (unsigned)((W - 40) / (legw * PX_CHAR + 80)) : 1;
  if (!perrow) perrow = 1;
  L->legrows = nent ? (nent + perrow - 1) / perrow : 0;
  make_title(f, L, W);
  /* Wrapped a little short: the font's average is not its widest. */
  const char *capt = f->caption;
  L->ncap = capt[0] ? wrap(capt, (unsigned)((W - 20) / (PX_CHAR * 1.1)), "; ", L->caplines,
                           sizeof L->caplines)
                    : 0;
  L->legh = L->legrows ? L->legrows * PX_LEGEND_ROW + 8 : 0;
  L->caph = L->ncap ? L->ncap * PX_CAPTION_LINE + 12 : 0;
  const double boxw = pw - PX_BOX_LEFT - PX_BOX_RIGHT;
  const unsigned nxt = bars ? (L->twolevel ? f->groups.n * L->nside : f->groups.n) : 0;
  L->xtlen = L->twolevel ? ticklen : grouplen;
  L->rotate = bars && nxt && L->xtlen * PX_CHAR > boxw / nxt * 0.95;
  L->boxbottom = PX_BOX_BOTTOM + (L->twolevel ? 18 : 0) +
                 (L->rotate ? (unsigned)(L->xtlen * PX_CHAR * 0.5) : 0);
  L->pw = pw;
  L->cols = cols;
  L->W = W;
  L->H = L->titleh + L->legh + prow * PX_PANEL_H + L->caph;
}

/* The script's head: colours, grid, the x label, log scales, --mark-x lines;
 * the y label goes to L->ylabel (each panel sets its own). */
static void write_head(FILE *gp, const struct plot_figure *f, struct layout *L) {
  const struct plot_plan *p = f->plan;
  char label[1100];
  /* Okabe and Ito's colour-blind-safe colours without their yellow, which
   * vanishes on white (gnuplot's own sixth and seventh colours do too); the
   * eighth series on repeats them dashed, so no two series look alike. */
  static const char *const COLOURS[] = {"#0072B2", "#D55E00", "#009E73", "#CC79A7",
                                        "#E69F00", "#56B4E9", "#000000"};
  for (unsigned c = 0; c < 2 * PLOT_COLOURS; c++)
    fprintf(gp, "set linetype %u lc rgb '%s' dt %u\n", c + 1, COLOURS[c % PLOT_COLOURS],
            c < PLOT_COLOURS ? 1 : 2);
  fprintf(gp, "set linetype cycle %u\nset grid\nunset key\nset pointsize 0.8\nset multiplot\n",
          2 * PLOT_COLOURS);
  if (f->bars) {
    fputs("set grid noxtics ytics\nset xtics scale 0\n", gp);
    if (L->rotate) fputs("set xtics rotate by 30 right\n", gp);
  }
  /* Stacked bars side by side say what the bars under a group are. */
  char xw[512], lw[512];
  plot_axis_label(p->x, "", xw, sizeof xw);
  if (p->xlabel) snprintf(label, sizeof label, "%s", p->xlabel);
  else if (L->twolevel) {
    plot_axis_label(p->lines, "", lw, sizeof lw);
    snprintf(label, sizeof label, "%s (bars: %s)", xw, lw);
  } else if (f->bars) snprintf(label, sizeof label, "%s", xw);
  else plot_axis_label(p->x, L->xunit, label, sizeof label);
  fputs("set xlabel ", gp);
  plot_script_str(gp, label);
  fputc('\n', gp);
  /* Columns with nothing in common: their unit says what the axis is. */
  if (p->ylabel) snprintf(L->ylabel, sizeof L->ylabel, "%s", p->ylabel);
  else if (f->ys->n > 1 && !strchr(f->ys->pattern, '*') && f->yunit[0])
    snprintf(L->ylabel, sizeof L->ylabel, "%s", f->yunit);
  else if (f->ys->n > 1 && !strchr(f->ys->pattern, '*')) y_words(f, L->ylabel, sizeof L->ylabel);
  else plot_axis_label(f->ys->pattern, f->yunit, L->ylabel, sizeof L->ylabel);
  if (L->twolevel) fputs("set xlabel offset 0,-1.2\n", gp);
  if (p->logx)
    fprintf(gp, "set logscale x %d\n",
            L->xa.lo > 0 && all_powers_of_two(L->xa.ticks, L->xa.nticks) ? 2 : 10);
  if (p->logy) fprintf(gp, "set logscale y %d\n", L->ybase);
  for (unsigned m = 0; m < p->nmark; m++)
    fprintf(gp,
            "set arrow from %.17g, graph 0 to %.17g, graph 1 nohead dt 2 lw 1.5 lc rgb 'gray30'\n",
            p->mark[m], p->mark[m]);
}

/* A bar panel's x axis: a tick a group, or with stacked bars side by side a
 * tick a bar and the group's name under them. */
static void write_bar_ticks(FILE *gp, const struct plot_figure *f, const struct layout *L) {
  fprintf(gp, "set xrange [%.17g:%.17g]\n", L->xa.lo, L->xa.hi);
  fputs("unset label\nset xtics (", gp);
  for (unsigned g = 0, n = 0; g < f->groups.n; g++) {
    char v[256];
    plot_fmt_value(f->groups.v[g], L->xunit, v, sizeof v);
    if (!L->twolevel) {
      fputs(n++ ? ", " : "", gp);
      plot_script_str(gp, v);
      fprintf(gp, " %u", g);
      continue;
    }
    for (unsigned b = 0; b < L->nside; b++) {
      fputs(n++ ? ", " : "", gp);
      plot_script_str(gp, L->blab[b]);
      fprintf(gp, " %.17g", g - 0.4 + (b + 0.5) * 0.8 / L->nside);
    }
  }
  fputs(")\n", gp);
  for (unsigned g = 0; L->twolevel && g < f->groups.n; g++) {
    char v[256];
    plot_fmt_value(f->groups.v[g], L->xunit, v, sizeof v);
    fputs("set label ", gp);
    plot_script_str(gp, v);
    fprintf(gp, " at first %u, graph 0 center offset 0,%.1f\n", g,
            -2.3 - (L->rotate ? L->xtlen * 0.25 : 0));
  }
}

/* Where a bar of rows[i] sits: its left and right ends, and its [lo, hi]
 * for colour c. */
static void bar_of(const struct plot_figure *f, const struct layout *L, unsigned i, unsigned c,
                   double *l, double *r, double *lo, double *hi) {
  const struct plot_row *w = &f->rows[i];
  const unsigned b = f->lc >= 0 ? w->line : f->stacked ? 0 : c;
  *l = w->x - 0.4 + b * 0.8 / L->nside;
  *r = *l + 0.8 / L->nside;
  *lo = 0;
  if (f->stacked) {
    for (unsigned k = 0; k < c; k++) *lo += w->y[k];
    *hi = *lo + w->y[c];
  } else {
    *hi = w->y[f->lc >= 0 ? 0 : c];
  }
}

/* Rows [at, end) as bars: one data block a colour, x y xlow xhigh ylow
 * yhigh per box; with seeds (bars side by side), a block of error bars over
 * them. */
static void write_bars(FILE *gp, const struct plot_figure *f, const struct layout *L, unsigned at,
                       unsigned end) {
  const unsigned ny = f->ys->n, nside = L->nside;
  const unsigned ncolour = f->stacked ? ny : nside;
  const bool whiskers = f->seeds_max && !f->stacked;
  fputs("plot ", gp);
  for (unsigned c = 0; c < ncolour; c++)
    fprintf(gp,
            "%s'-' using 1:2:3:4:5:6 with boxxyerror lc %u fs solid 0.85 border lc rgb "
            "'gray20' notitle",
            c ? ", " : "", c % PLOT_COLOURS + 1);
  if (whiskers) fputs(", '-' using 1:2:3:4 with yerrorbars lc rgb 'black' pt 0 notitle", gp);
  fputc('\n', gp);
  for (unsigned c = 0; c < ncolour; c++) {
    for (unsigned i = at; i < end; i++) {
      const struct plot_row *w = &f->rows[i];
      if (!f->stacked && f->lc >= 0 && w->line != c) continue;
      double l, r, lo, hi;
      bar_of(f, L, i, c, &l, &r, &lo, &hi);
      const double gap = 0.06 * 0.8 / nside;
      fprintf(gp, "%.17g %.17g %.17g %.17g %.17g %.17g\n", (l + r) / 2, hi, l + gap, r - gap, lo,
              hi);
    }
    /* gnuplot needs a point in every block: an empty one is a box of nothing. */
    fputs("NaN NaN NaN NaN NaN NaN\ne\n", gp);
  }
  if (!whiskers) return;
  for (unsigned c = 0; c < ncolour; c++)
    for (unsigned i = at; i < end; i++) {
      const struct plot_row *w = &f->rows[i];
      if (f->lc >= 0 && w->line != c) continue;
      const unsigned k = f->lc >= 0 ? 0 : c;
      double l, r, lo, hi;
      bar_of(f, L, i, c, &l, &r, &lo, &hi);
      fprintf(gp, "%.17g %.17g %.17g %.17g\n", (l + r) / 2, hi, w->ylo[k], w->yhi[k]);
    }
  fputs("NaN NaN NaN NaN\ne\n", gp);
}

/* A series' style: lines with points (with the seeds' error bars when a row
 * has several), or markers only; a series of more points than a marker can
 * be told apart at (a timeline's) is a plain line. */
static const char *line_style(const struct plot_figure *f, const struct layout *L) {
  if (f->plan->points) return "points ps 1.3";
  if (f->seeds_max) return "yerrorlines lw 2";
  return L->dense ? "lines lw 1.5" : "linespoints lw 2";
}

/* Rows [at, end) as lines (or markers): a data block a line and --y column. */
static void write_lines(FILE *gp, const struct plot_figure *f, const struct layout *L, unsigned at,
                        unsigned end) {
  const unsigned ny = f->ys->n;
  const struct plot_row *rows = f->rows;
  const bool seeds = f->seeds_max && !f->plan->points;
  fputs("plot ", gp);
  unsigned nplotted = 0;
  for (unsigned i = at; i < end; i++) {
    if (i > at && same_series(&rows[i], &rows[i - 1])) continue;
    for (unsigned k = 0; k < ny; k++) {
      const unsigned c = f->lc >= 0 ? rows[i].line : k;
      fprintf(gp, "%s'-' using 1:2%s with %s lt %u pt %u", nplotted++ ? ", " : "",
              seeds ? ":3:4" : "", line_style(f, L), c + 1, c % 13 + 1);
      if (f->dc >= 0) fprintf(gp, " dt %u", rows[i].dash + 1);
      fputs(" notitle", gp);
    }
  }
  fputc('\n', gp);
  for (unsigned i = at, first = at; i < end; i++) {
    if (i + 1 < end && same_series(&rows[i + 1], &rows[i])) continue;
    for (unsigned k = 0; k < ny; k++) {
      for (unsigned j = first; j <= i; j++) {
        fprintf(gp, "%.17g %.17g", rows[j].x, rows[j].y[k]);
        if (seeds) fprintf(gp, " %.17g %.17g", rows[j].ylo[k], rows[j].yhi[k]);
        fputc('\n', gp);
      }
      fputs("e\n", gp);
    }
    first = i + 1;
  }
}

/* Each panel: its place on the canvas, title, y label, axes and data. */
static void write_panels(FILE *gp, const struct plot_figure *f, const struct layout *L) {
  const struct plot_plan *p = f->plan;
  const double W = L->W, H = L->H;
  unsigned at = 0;
  for (unsigned pn = 0; pn < f->panels.n; pn++) {
    const unsigned col = pn % L->cols, prw = pn / L->cols;
    const double left = col * L->pw, top = L->titleh + L->legh + prw * PX_PANEL_H;
    fprintf(gp, "set lmargin at screen %.6f\nset rmargin at screen %.6f\n",
            (left + PX_BOX_LEFT) / W, (left + L->pw - PX_BOX_RIGHT) / W);
    fprintf(gp, "set tmargin at screen %.6f\nset bmargin at screen %.6f\n",
            1 - (top + PX_BOX_TOP) / H, 1 - (top + PX_PANEL_H - L->boxbottom) / H);
    char pt[512] = "";
    if (f->pc >= 0) {
      char v[256];
      plot_fmt_value(f->panels.v[pn], plot_unit_of(p->panels), v, sizeof v);
      snprintf(pt, sizeof pt, "%s = %s", p->panels, v);
    }
    fputs("set title ", gp);
    plot_script_str(gp, pt);
    /* One y label a row of panels when they share the range. */
    fputs("\nset ylabel ", gp);
    plot_script_str(gp, p->own_y || col == 0 ? L->ylabel : "");
    fputc('\n', gp);
    if (f->bars) write_bar_ticks(gp, f, L);
    else gp_range(gp, "x", &L->xa, L->xunit);
    gp_range(gp, "y", &L->yaxes[pn], f->yunit);
    /* The peak: a dashed line across the panel, named in the legend (a label
     * beside it could cover a point). */
    const double pk = f->peak[pn];
    if (pk > 0 && pk >= L->yaxes[pn].lo && pk <= L->yaxes[pn].hi)
      fprintf(gp,
              "set arrow %d from graph 0, first %.17g to graph 1, first %.17g nohead dt 2 lw 2 lc "
              "rgb 'gray20' back\n",
              PEAK_ARROW, pk, pk);
    else fprintf(gp, "unset arrow %d\n", PEAK_ARROW);
    unsigned end = at;
    while (end < f->nrows && f->rows[end].panel == pn) end++;
    if (f->bars) write_bars(gp, f, L, at, end);
    else write_lines(gp, f, L, at, end);
    at = end;
  }
}

/* The frame: title, the one legend and the caption, over the whole canvas. */
static void write_frame(FILE *gp, const struct plot_figure *f, const struct layout *L) {
  const double W = L->W, H = L->H;
  fputs("unset logscale\nunset arrow\nunset label\nunset title\nunset xlabel\nunset ylabel\n"
        "unset grid\nunset border\nunset tics\nset origin 0,0\nset size 1,1\n"
        "set lmargin at screen 0\nset rmargin at screen 1\nset tmargin at screen 1\n"
        "set bmargin at screen 0\nset xrange [0:1]\nset yrange [0:1]\n",
        gp);
  for (unsigned i = 0, o = 0; i < L->ntitle; i++) {
    fputs("set label ", gp);
    plot_script_str(gp, L->titlelines + o);
    fprintf(gp, " at screen 0.5, screen %.6f center font ',13'\n",
            1 - (18.0 + i * PX_TITLE_LINE) / H);
    o += (unsigned)strlen(L->titlelines + o) + 1;
  }
  for (unsigned i = 0, o = 0; i < L->ncap; i++) {
    fputs("set label ", gp);
    plot_script_str(gp, L->caplines + o);
    fprintf(gp, " at screen %.6f, screen %.6f left\n", 10.0 / W,
            (L->caph - 8 - (i + 0.5) * PX_CAPTION_LINE) / H);
    o += (unsigned)strlen(L->caplines + o) + 1;
  }
  if (L->nleg || L->ndleg || L->peakleg[0]) {
    fprintf(gp,
            "set key at screen 0.5, screen %.6f center top horizontal Left reverse maxrows %u "
            "samplen 3 spacing 1.1\n",
            1 - (L->titleh - 4.0) / H, L->legrows);
    fputs("plot ", gp);
    for (unsigned i = 0; i < L->nleg; i++) {
      if (f->bars)
        fprintf(gp, "%sNaN with boxxyerror lc %u fs solid 0.85 border lc rgb 'gray20' title ",
                i ? ", " : "", i % PLOT_COLOURS + 1);
      else
        fprintf(gp, "%sNaN with %s lt %u pt %u title ", i ? ", " : "",
                f->seeds_max && !f->plan->points ? "linespoints lw 2" : line_style(f, L), i + 1,
                i % 13 + 1);
      plot_script_str(gp, L->leg[i]);
    }
    for (unsigned d = 0; d < L->ndleg; d++) {
      fprintf(gp, "%sNaN with lines lw 2 lc rgb 'gray30' dt %u title ", L->nleg + d ? ", " : "",
              d + 1);
      plot_script_str(gp, L->dleg[d]);
    }
    if (L->peakleg[0]) {
      fprintf(gp, "%sNaN with lines dt 2 lw 2 lc rgb 'gray20' title ",
              L->nleg + L->ndleg ? ", " : "");
      plot_script_str(gp, L->peakleg);
    }
    fputc('\n', gp);
  } else {
    fputs("plot NaN notitle\n", gp);
  }
  fputs("unset multiplot\n", gp);
}

void plot_script_write(const struct plot_figure *f, char **body, size_t *len, unsigned *width,
                       unsigned *height) {
  struct layout *L = xcalloc(1, sizeof *L);
  L->xunit = plot_unit_of(f->plan->x);
  make_axes(f, L);
  make_legend(f, L);
  make_layout(f, L);
  FILE *gp = open_memstream(body, len);
  CHECK(gp);
  write_head(gp, f, L);
  write_panels(gp, f, L);
  write_frame(gp, f, L);
  CHECK(fclose(gp) == 0);
  *width = L->W;
  *height = L->H;
  free(L->leg);
  free(L->blab);
  free(L->yaxes);
  free(L);
}
