/* rtsim plot's plan (app/plot_plan.h) from command lines, without a table or
 * gnuplot: what each option sets, what --stack implies, and the usage errors
 * (exit code 2) that need no table. Hand-written cases. */
#include <stdlib.h>
#include <string.h>

#include "app/opts.h"
#include "app/plot_plan.h"
#include "testing.h"

/* Parse "plot " + line into *p; argv is split at spaces into words that
 * outlive the plan (freed by the caller through *words). */
static int parse(struct plot_plan *p, const char *line, char **words) {
  static char *argv[64];
  size_t n = strlen("plot ") + strlen(line) + 1;
  *words = malloc(n);
  snprintf(*words, n, "plot %s", line);
  int argc = 0;
  for (char *t = strtok(*words, " "); t && argc < 63; t = strtok(NULL, " ")) argv[argc++] = t;
  argv[argc] = NULL;
  return plot_plan_parse(p, argc, argv);
}

static void test_fields(void) {
  struct plot_plan p;
  char *w;
  int rc = parse(&p,
                 "t.csv --x cores --y cycles,dram_bytes --lines policy --panels scene --where "
                 "l2.size=1MiB --where policy=packet --mark-x 2 --mark-x 4.5 --logx --yrange 1:10 "
                 "--order a,b --script s.gp -o out.svg",
                 &w);
  EXPECTF(rc == OPTS_GO, "rc %d", rc);
  EXPECT(p.table && !strcmp(p.table, "t.csv"));
  EXPECT(p.x && !strcmp(p.x, "cores") && p.y && !strcmp(p.y, "cycles,dram_bytes"));
  EXPECT(p.lines && !strcmp(p.lines, "policy") && p.panels && !strcmp(p.panels, "scene"));
  EXPECT(p.nwhere == 2 && !strcmp(p.where[0], "l2.size=1MiB") &&
         !strcmp(p.where[1], "policy=packet"));
  EXPECT(p.nmark == 2 && p.mark[0] == 2 && p.mark[1] == 4.5);
  EXPECT(p.logx && !p.logy && !p.bars && !p.stack && !p.points && !p.own_y);
  EXPECT(p.yrange && p.ylo == 1 && p.yhi == 10);
  EXPECT(p.format == PLOT_SVG && !strcmp(p.out, "out.svg") && !strcmp(p.script, "s.gp"));
  EXPECT(p.order && !strcmp(p.order, "a,b"));
  free(w);

  /* --stack asks for bars; a .png is not an svg; nothing else is set. */
  rc = parse(&p, "t.csv --x policy --y a,b --stack -o f.png", &w);
  EXPECTF(rc == OPTS_GO, "rc %d", rc);
  EXPECT(p.stack && p.bars && p.format == PLOT_PNG && !p.yrange && p.nwhere == 0 && p.nmark == 0);
  EXPECT(!p.lines && !p.panels && !p.script && !p.order);
  EXPECT(!p.title && !p.xlabel && !p.ylabel && !p.y_from_data && !p.peak_given && !p.no_peak);
  free(w);

  /* The extension names the format, in any case; the labels are taken as
   * typed (one word each here: the test splits at spaces). */
  rc = parse(&p,
             "t.csv --x a --y b --title Traffic --xlabel Cores --ylabel Bytes --y-from-data "
             "--peak 13.5 -o f.PDF",
             &w);
  EXPECTF(rc == OPTS_GO, "rc %d", rc);
  EXPECT(p.format == PLOT_PDF && p.y_from_data && p.peak_given && p.peak == 13.5);
  EXPECT(p.title && !strcmp(p.title, "Traffic") && p.xlabel && !strcmp(p.xlabel, "Cores") &&
         p.ylabel && !strcmp(p.ylabel, "Bytes"));
  free(w);
  rc = parse(&p, "t.csv --x a --y b --no-peak -o dir.v2/f.svg", &w);
  EXPECT(rc == OPTS_GO && p.format == PLOT_SVG && p.no_peak && !p.peak_given);
  free(w);
}

static void test_refusals(void) {
  static const char *const bad[] = {
      "--x a --y b -o f.png",       /* no table */
      "t.csv --y b -o f.png",       /* no --x */
      "t.csv --x a -o f.png",       /* no --y */
      "t.csv --x a --y b",          /* no -o */
      "t.csv --x a --y b -o f.jpg", /* not png, pdf or svg */
      "t.csv --x a --y b -o f.eps",
      "t.csv --x a --y b -o pdf",      /* no extension */
      "t.csv --x a --y b -o f.png.gp", /* the extension is the last */
      "t.csv --x a --y b -o f.png --yrange 0:1 --y-from-data",
      "t.csv --x a --y b -o f.png --peak 2 --no-peak",
      "t.csv --x a --y b -o f.png --peak high",
      "t.csv --x a --y b -o f.png --peak 0",
      "t.csv --x a --y b -o f.png --bars --dash c",
      "t.csv --x a --y b -o f.png --own-y --yrange 0:1",
      "t.csv --x a --y b -o f.png --logy --yrange 0:1",
      "t.csv --x a --y b -o f.png --yrange 2:1",
      "t.csv --x a --y b -o f.png --stack --logx",
      "t.csv --x a --y b -o f.png --bars --mark-x 3",
      "t.csv --x a --y b -o f.png --bars --points",
      "t.csv --x a --y b -o f.png --script f.png",
      "t.csv --x a --y b -o f.png --where nokey",
      "t.csv --x a --y b -o f.png --mark-x two",
      "t.csv u.csv --x a --y b -o f.png", /* two tables */
  };
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    struct plot_plan p;
    char *w;
    int rc = parse(&p, bad[i], &w);
    EXPECTF(rc == 2, "'%s': got %d, expected 2", bad[i], rc);
    free(w);
  }
}

int main(void) {
  test_fields();
  test_refusals();
  return testing_done("test_plot_plan");
}
