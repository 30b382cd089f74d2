/* rtsim plot: figures of a tidy table (rtsim merge's, or any CSV with a
 * header) through gnuplot: METRIC against KEY as lines (a numeric KEY) or bars
 * (a categorical one), a line or bar per value of a --lines column, a panel
 * per value of a --panels column. Plan (app/plot_plan.h), figure
 * (app/plot_figure.h) and script (app/plot_script.h) are made in turn; here
 * the script goes to gnuplot on a pipe, and the picture is written under a
 * temporary name and renamed (sim/outfile.h). */
#include "app/app.h"

#include <stdio.h>
#include <stdlib.h>

#include "app/csv.h"
#include "app/gnuplot.h"
#include "app/opts.h"
#include "app/outguard.h"
#include "app/plot_figure.h"
#include "app/plot_plan.h"
#include "app/plot_script.h"
#include "sim/err.h"
#include "sim/outfile.h"

/* The terminal's line and `set output`. A PDF's size is in inches: at 72
 * pixels an inch its 11-point font stands to the page as the PNG's to its
 * pixels, so the three formats lay out alike. */
static void terminal(FILE *f, const struct plot_plan *p, unsigned w, unsigned h, const char *out) {
  if (p->format == PLOT_PDF)
    fprintf(f, "set terminal pdfcairo size %.4gin,%.4gin noenhanced font ',11'\nset output ",
            w / 72.0, h / 72.0);
  else
    fprintf(f, "set terminal %s size %u,%u noenhanced font ',11'\nset output ",
            p->format == PLOT_SVG ? "svg" : "pngcairo", w, h);
  plot_script_str(f, out);
  fputc('\n', f);
}

/* The picture through gnuplot, and the --script file: both or neither. A
 * signal from here on stops gnuplot and removes the temporaries. Returns 0,
 * or 1 with e set. */
static int write_outputs(const struct plot_plan *p, const char *body, size_t len, unsigned w,
                         unsigned h, struct err *e) {
  struct outfile plot = {0}, gpfile = {0};
  int rc = 1;
  outguard_beside(p->out);
  if (p->script) outguard_beside(p->script);
  if (!outfile_open_named(&plot, p->out, "the plot", e)) goto done;
  struct gnuplot gnu;
  if (!gnuplot_open(&gnu, false)) {
    err_set(e, p->out, 0, 0, "cannot run gnuplot (install gnuplot-nox)");
    goto done;
  }
  terminal(gnu.in, p, w, h, plot.tmp);
  fwrite(body, 1, len, gnu.in);
  if (!gnuplot_close(&gnu)) {
    err_set(e, p->out, 0, 0, "gnuplot could not draw the plot (is gnuplot-nox installed?)");
    goto done;
  }
  if (p->script) {
    if (!outfile_open(&gpfile, p->script, "the script", e)) goto done;
    fputs("# rtsim plot's gnuplot script, data inline; made by:\n# rtsim", gpfile.f);
    for (int i = 0; i < p->argc; i++) fprintf(gpfile.f, " %s", p->argv[i]);
    fputc('\n', gpfile.f);
    terminal(gpfile.f, p, w, h, p->out);
    fwrite(body, 1, len, gpfile.f);
  }
  if (!outfile_commit(&plot, e) || (p->script && !outfile_commit(&gpfile, e))) goto done;
  rc = 0;
done:
  outfile_abort(&plot);
  outfile_abort(&gpfile);
  outguard_clear();
  return rc;
}

int cmd_plot(int argc, char **argv) {
  struct plot_plan plan;
  int rc = plot_plan_parse(&plan, argc, argv);
  if (rc != OPTS_GO) return rc;
  struct csv_table t;
  struct err e = {0};
  if (!csv_read(&t, plan.table, &e)) return app_report(&e);
  struct plot_figure f;
  char *body = NULL;
  size_t len = 0;
  unsigned w, h;
  rc = APP_EXIT_USAGE;
  if (!plot_figure_build(&f, &plan, &t, &e)) goto done;
  plot_script_write(&f, &body, &len, &w, &h);
  if ((rc = write_outputs(&plan, body, len, w, h, &e)) != 0) goto done;
  const unsigned ny = f.ys->n, ng = f.groups.n, np = f.panels.n, nl = f.lines.n * ny;
  if (f.bars)
    fprintf(stderr, "plot: %u bars in %u group%s, %u panel%s into %s\n",
            f.nrows * (f.stacked ? 1 : ny), ng, ng == 1 ? "" : "s", np, np == 1 ? "" : "s",
            plan.out);
  else
    fprintf(stderr, "plot: %u points, %u line%s, %u panel%s into %s\n", f.nrows * ny, nl,
            nl == 1 ? "" : "s", np, np == 1 ? "" : "s", plan.out);
done:
  if (e.set) app_report(&e);
  free(body);
  plot_figure_fini(&f);
  csv_free(&t);
  return rc;
}
