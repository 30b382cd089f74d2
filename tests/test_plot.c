/* rtsim plot's figures, through the command line and the gnuplot script it
 * writes with --script: a fraction on 0..1, panels sharing one y range (and
 * their own with --own-y), tick labels with SI and binary prefixes, one
 * legend with units, a caption of the fixed parameters, bar charts for a
 * text x (side by side and stacked), PNG, PDF and SVG by the extension,
 * titles and labels of the user's or in words, error bars over seeds, a y
 * axis from 0, the DRAM's peak line, dash patterns, and bad options refused
 * with exit code 2 and one line. Tables are written here, a few rows each. */
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "testing.h"

#define T RTSIM_TMP "/pl_"

static char out[1 << 16];

/* Run a shell command (stderr with stdout into `out`); its exit code. */
#define run(...) testing_runf(out, sizeof out, __VA_ARGS__)

/* `rtsim plot TABLE ARGS -o bad.png` is refused: exit 2, a message holding
 * want (the whole output in `out` for further checks), no picture. */
static bool expect_refused(const char *table, const char *args, const char *want) {
  run("rm -f " T "bad.png");
  int rc = run("%s plot %s %s -o " T "bad.png", RTSIM_BINARY, table, args);
  bool ok = rc == 2 && strstr(out, want) && access(T "bad.png", F_OK) != 0;
  EXPECTF(ok, "'%s': exit %d: %s", args, rc, out);
  return ok;
}

static char *read_all(const char *path) {
  size_t len;
  return testing_slurp(RTSIM_TMP, path + strlen(RTSIM_TMP "/"), &len);
}

static unsigned count(const char *hay, const char *needle) {
  unsigned n = 0;
  for (const char *p = hay; p && (p = strstr(p, needle)); p += strlen(needle)) n++;
  return n;
}

/* The lines of s that start with prefix, joined by newlines (static). */
static const char *lines_with(const char *s, const char *prefix) {
  static char buf[1 << 15];
  size_t o = 0, n = strlen(prefix);
  buf[0] = '\0';
  for (const char *p = s; p && *p; p = strchr(p, '\n'), p = p ? p + 1 : NULL) {
    const char *e = strchr(p, '\n');
    size_t len = e ? (size_t)(e - p) : strlen(p);
    if (len >= n && !strncmp(p, prefix, n) && o + len + 2 < sizeof buf) {
      memcpy(buf + o, p, len);
      o += len;
      buf[o++] = '\n';
      buf[o] = '\0';
    }
  }
  return buf;
}

/* The caption's lines (labels placed left) joined by spaces (static). */
static const char *caption_of(const char *s) {
  static char buf[1 << 13];
  size_t o = 0;
  buf[0] = '\0';
  for (const char *p = s; (p = strstr(p, "set label '")); p++) {
    const char *e = strstr(p, "' at screen "), *nl = strchr(p, '\n');
    if (!e || !nl || e > nl || !strstr(e, " left\n") || strstr(e, " left\n") > nl) continue;
    o += (size_t)snprintf(buf + o, o < sizeof buf ? sizeof buf - o : 0, "%s%.*s", o ? " " : "",
                          (int)(e - p - 11), p + 11);
  }
  return buf;
}

/* Plot table with args into pl_out.png and pl_out.gp; the script (caller
 * frees), or NULL when the plot failed. */
static char *plot(const char *table, const char *args) {
  run("rm -f " T "out.png " T "out.svg " T "out.gp");
  int rc = run("%s plot %s %s -o " T "out.png --script " T "out.gp", RTSIM_BINARY, table, args);
  EXPECTF(rc == 0, "plot %s: exit %d: %s", args, rc, out);
  if (rc) return NULL;
  return read_all(T "out.gp");
}

/* A sweep-like table: two scenes, utilization and bytes, dram.latency and
 * l2.size as lines; cores and the scene's size fixed. */
static const char SWEEP[] =
    "point,scene,cores,dram.latency,l2.size,policy,width,height,rays_per_thread,"
    "core_utilization,dram_bytes,cycles\n"
    "\"scene=a,dram.latency=25\",a,16,25,524288,recursive,64,48,1,0.21,44000000,1000\n"
    "\"scene=a,dram.latency=25\",a,16,25,524288,recursive,64,48,2,0.35,45000000,900\n"
    "\"scene=a,dram.latency=50\",a,16,50,524288,recursive,64,48,1,0.18,43000000,1100\n"
    "\"scene=a,dram.latency=50\",a,16,50,524288,recursive,64,48,2,0.30,44500000,950\n"
    "\"scene=b,dram.latency=25\",b,16,25,524288,recursive,64,48,1,0.55,12000000,100000\n"
    "\"scene=b,dram.latency=25\",b,16,25,524288,recursive,64,48,2,0.86,13000000,90000\n"
    "\"scene=b,dram.latency=50\",b,16,50,524288,recursive,64,48,1,0.40,12500000,120000\n"
    "\"scene=b,dram.latency=50\",b,16,50,524288,recursive,64,48,2,0.61,12800000,95000\n";

static void test_lines(void) {
  const char *t = T "sweep.csv";
  testing_write(t, SWEEP);
  /* A utilization on 0..1 in both panels, though its values span 0.18-0.86. */
  char *s = plot(t, "--x rays_per_thread --y core_utilization --lines dram.latency --panels scene");
  if (s) {
    EXPECTF(count(s, "set yrange [0:1]\nset ytics") == 2,
            "a utilization is not on [0:1] in each panel: %s", lines_with(s, "set yrange"));
    /* One legend for the figure, with units; no title in the panels' plots. */
    EXPECTF(count(s, "title 'dram.latency = 25 cycles'") == 1 &&
                count(s, "title 'dram.latency = 50 cycles'") == 1,
            "the legend is not once, with units: %s", lines_with(s, "plot"));
    EXPECT(count(s, "set key at screen") == 1);
    /* The caption: the fixed machine and workload, not what is drawn. */
    const char *cap = lines_with(s, "set label 'cores = 16");
    EXPECTF(strstr(cap, "l2.size = 512 KiB") && strstr(cap, "policy = recursive") &&
                strstr(cap, "64x48 pixels") && !strstr(cap, "scene =") &&
                !strstr(cap, "dram.latency") && !strstr(cap, "rays_per_thread"),
            "the caption: '%s'", cap);
    /* The panels' titles say their value. */
    EXPECT(strstr(s, "set title 'scene = a'") && strstr(s, "set title 'scene = b'"));
    free(s);
  }
  /* Panels share the y range of every value unless --own-y. */
  s = plot(t, "--x rays_per_thread --y cycles --lines dram.latency --panels scene");
  if (s) {
    const char *r = lines_with(s, "set yrange");
    EXPECTF(count(r, "set yrange [0:125000]\n") == 2, "a shared range: %s", r);
    free(s);
  }
  /* Each its own, from 0 (scene a's 900-1100 cycles: steps of 1100 / 5 made
   * round, 250); around the values only when asked. */
  s = plot(t, "--x rays_per_thread --y cycles --lines dram.latency --panels scene --own-y");
  if (s) {
    const char *r = lines_with(s, "set yrange");
    EXPECTF(strstr(r, "set yrange [0:1250]\n") && strstr(r, "set yrange [0:125000]\n"),
            "own ranges from 0: %s", r);
    free(s);
  }
  s = plot(t, "--x rays_per_thread --y cycles --lines dram.latency --panels scene --own-y "
              "--y-from-data");
  if (s) {
    const char *r = lines_with(s, "set yrange");
    EXPECTF(strstr(r, "set yrange [900:1100]\n") && strstr(r, "set yrange [90000:120000]\n"),
            "own ranges from the data: %s", r);
    free(s);
  }
  s = plot(t, "--x rays_per_thread --y cycles --lines dram.latency --panels scene --yrange 0:2e5");
  if (s) {
    EXPECTF(count(s, "set yrange [0:200000]\n") == 2, "--yrange: %s", lines_with(s, "set yrange"));
    free(s);
  }
  /* Readable ticks: 44M, never 4.4e+07; bytes in MB. */
  s = plot(t, "--x rays_per_thread --y cycles --where scene=a --lines dram.latency --logy");
  if (s) {
    const char *y = lines_with(s, "set ytics");
    EXPECTF(strstr(y, "'1k' 1000") && !strstr(y, "e+"), "log ticks: %s", y);
    free(s);
  }
  s = plot(t, "--x rays_per_thread --y dram_bytes --lines dram.latency --panels scene");
  if (s) {
    const char *y = lines_with(s, "set ytics");
    EXPECTF(strstr(y, "'40 MB' 40000000") && !strstr(y, "e+") && !strstr(y, "e0"), "byte ticks: %s",
            y);
    /* A sweep's x values are the ticks. */
    EXPECTF(strstr(s, "set xtics ('1' 1, '2' 2)"), "x ticks: %s", lines_with(s, "set xtics"));
    free(s);
  }
  /* A whole number under 10,000 in full where a prefix would make it a
   * long fraction (1024, not 1.024k); round ones keep their prefix. */
  {
    const char *t2 = T "cores.csv";
    testing_write(t2, "cores,cycles\n256,9000\n1024,3000\n2000,2500\n");
    s = plot(t2, "--x cores --y cycles");
    if (s) {
      const char *x = lines_with(s, "set xtics");
      EXPECTF(strstr(x, "'1024' 1024") && strstr(x, "'2k' 2000") && !strstr(x, "1.024k"),
              "x ticks: %s", x);
      free(s);
    }
  }
  /* A byte-sized key in the legend in binary units. */
  s = plot(t, "--x rays_per_thread --y cycles --lines l2.size --where scene=a --where "
              "dram.latency=25");
  if (s) {
    EXPECTF(strstr(s, "title 'l2.size = 512 KiB'"), "%s", lines_with(s, "plot NaN"));
    EXPECTF(strstr(s, "scene = a") && strstr(s, "dram.latency = 25 cycles"),
            "the --where keys are in the caption: %s", lines_with(s, "set label"));
    free(s);
  }
  /* SVG: the legend's entries once, though there are two panels. */
  run("rm -f " T "out.svg");
  int rc = run("%s plot %s --x rays_per_thread --y core_utilization --lines dram.latency --panels "
               "scene -o " T "out.svg",
               RTSIM_BINARY, t);
  char *svg = read_all(T "out.svg");
  EXPECTF(rc == 0 && svg && strstr(svg, "<svg") && count(svg, "dram.latency = 25 cycles") == 1 &&
              strstr(svg, "cores = 16"),
          "svg: exit %d: %s", rc, out);
  free(svg);
  rc = run("%s plot %s --x rays_per_thread --y cycles --where scene=a --lines dram.latency -o " T
           "out.png",
           RTSIM_BINARY, t);
  char *png = read_all(T "out.png");
  EXPECTF(rc == 0 && png && !memcmp(png, "\x89PNG", 4), "png: exit %d: %s", rc, out);
  free(png);
}

/* Bars: a text x, side by side per --lines value, stacked by --y column. */
static void test_bars(void) {
  const char *t = T "bars.csv";
  testing_write(t, "scene,policy,l2.size,fetch_geometry_bytes,fetch_ray_bytes,cycles\n"
                   "grove,recursive,524288,3000000,1000000,50\n"
                   "grove,packet,524288,2000000,500000,40\n"
                   "grove,dynamic,524288,1000000,2000000,30\n"
                   "grove,recursive,4194304,1500000,500000,45\n"
                   "grove,packet,4194304,1000000,250000,35\n"
                   "grove,dynamic,4194304,500000,1000000,25\n");
  char *s = plot(t, "--x policy --y cycles --lines l2.size");
  if (s) {
    EXPECTF(strstr(s, "with boxxyerror") && !strstr(s, "linespoints"), "not bars: %s", s);
    EXPECTF(strstr(s, "set xtics ('dynamic' 0, 'packet' 1, 'recursive' 2)"), "groups: %s",
            lines_with(s, "set xtics"));
    /* Bars start at 0. */
    EXPECTF(strstr(s, "set yrange [0:50]"), "%s", lines_with(s, "set yrange"));
    EXPECT(strstr(s, "title 'l2.size = 512 KiB'") && strstr(s, "title 'l2.size = 4 MiB'"));
    EXPECTF(strstr(s, "scene = grove"), "caption: %s", lines_with(s, "set label"));
    free(s);
  }
  /* --order: the paper's order of the groups, and of the lines where it names
   * them (4194304 first; 524288, not named, after it). */
  s = plot(t,
           "--x policy --y cycles --lines l2.size --order recursive,packet,dynamic,4194304,nope");
  if (s) {
    EXPECTF(strstr(s, "set xtics ('recursive' 0, 'packet' 1, 'dynamic' 2)"), "ordered groups: %s",
            lines_with(s, "set xtics"));
    const char *a = strstr(s, "title 'l2.size = 4 MiB'"),
               *b = strstr(s, "title 'l2.size = 512 KiB'");
    EXPECTF(a && b && a < b, "ordered lines: %s", lines_with(s, "title"));
    free(s);
  }
  /* Stacked: ray bytes sit on the geometry bytes (recursive, 512 KiB: 3M to
   * 4M); the legend names the classes; the bars under a group say their size. */
  s = plot(t, "--x policy --y fetch_geometry_bytes,fetch_ray_bytes --stack --lines l2.size");
  if (s) {
    EXPECTF(strstr(s, " 3000000 4000000\n") && strstr(s, " 0 3000000\n"), "stacks: %s", s);
    EXPECT(strstr(s, "title 'geometry'") && strstr(s, "title 'ray'"));
    EXPECTF(strstr(s, "'512 KiB'") && strstr(s, "set label 'recursive' at first 2"), "labels: %s",
            lines_with(s, "set"));
    /* The columns' shared words and unit, not their names. */
    EXPECTF(strstr(s, "set ylabel 'fetch bytes'\n"), "%s", lines_with(s, "set ylabel"));
    free(s);
  }
  /* A numeric x as groups with --bars. */
  s = plot(t, "--x l2.size --y cycles --lines policy --bars");
  if (s) {
    EXPECTF(strstr(s, "set xtics ('512 KiB' 0, '4 MiB' 1)"), "%s", lines_with(s, "set xtics"));
    free(s);
  }
}

/* The unit rtsim run's tables give name: `rtsim run --help-stats` (name in
 * 36 columns, unit in 16) or, for a dotted config key, --help-keys' 4th
 * column; per-class names as their <class> row. Into unit; false if absent. */
static bool table_unit(const char *name, const char *row, char *unit, size_t cap) {
  bool key = strchr(name, '.') != NULL;
  if (run("%s run %s", RTSIM_BINARY, key ? "--help-keys" : "--help-stats")) return false;
  char pat[96];
  snprintf(pat, sizeof pat, key ? "\n| `%s` |" : "\n%-36s ", row);
  const char *p = strstr(out, pat);
  if (!p) return false;
  p += strlen(pat);
  if (key)
    for (int bar = 0; bar < 2; bar++) p = strstr(p, " | ") + 3; /* past default and range */
  size_t n = key ? strcspn(p, "|") : 16;
  snprintf(unit, cap, "%.*s", (int)n, p);
  while (n && unit[n - 1] == ' ') unit[--n] = '\0';
  return true;
}

/* A column's unit is its table's, not its name's ending: each case but the
 * last has a name that misleads the guess (the comment after it), so only the
 * lookup labels the axis "name (the table's unit)"; the last reaches its row
 * through the class pattern. A count has no unit on the axis. */
static void test_units(void) {
  /* label: the name in words, then the table's unit unless the words end
   * with it (a count has none). */
  static const struct {
    const char *name, *row, *label;
  } cases[] = {
      {"dram_refresh_cycles", "dram_refresh_cycles", "DRAM refresh cycles"},
      {"dram.controller_cycles", "dram.controller_cycles", "DRAM controller cycles"},
      {"issue_slots", "issue_slots", "issue slots"},
      {"seconds_ci95_low", "seconds_ci95_low", "seconds 95% CI low"},
      {"l2_miss_queue_length_max", "l2_miss_queue_length_max", "L2 miss queue length max"},
      {"l2_node_accesses", "l2_<class>_accesses", "L2 node accesses"},
  };
  for (unsigned i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    const char *name = cases[i].name;
    const char *table = T "units.csv";
    char unit[64], want[160];
    EXPECTF(table_unit(name, cases[i].row, unit, sizeof unit), "%s: not in rtsim run's tables",
            cases[i].row);
    char csv[256];
    snprintf(csv, sizeof csv, "x,%s\n1,2\n2,3\n", name);
    testing_write(table, csv);
    if (!strcmp(unit, "count")) snprintf(want, sizeof want, "set ylabel '%s'\n", cases[i].label);
    else snprintf(want, sizeof want, "set ylabel '%s (%s)'\n", cases[i].label, unit);
    char args[128];
    snprintf(args, sizeof args, "--x x --y %s", name);
    char *s = plot(table, args);
    if (s) {
      EXPECTF(strstr(s, want), "%s: expected %s got %s", name, want, lines_with(s, "set ylabel"));
      free(s);
    }
  }
}

/* Bad options and tables: exit 2, one line, no picture. */
/* --points: a scatter, markers only; a series may hold several rows at one x
 * (refused without it: they would be one line's two values). */
static void test_points(void) {
  const char *t = T "scatter.csv";
  testing_write(t, "rung,speedup,error\nfixed,2,0.5\nfixed,2,3\nfixed,4,1\nanalytic,8,20\n");
  char *s = plot(t, "--x speedup --y error --lines rung --points --logx --logy");
  if (s) {
    EXPECTF(count(s, "with points") == 4 && !strstr(s, "linespoints"), "not markers only: %s",
            lines_with(s, "plot"));
    EXPECT(strstr(s, "title 'rung = fixed'") != NULL);
    free(s);
  }
  expect_refused(t, "--x speedup --y error --lines rung", "fall on the same line");
  unlink(t);
}

static void test_refusals(void) {
  const char *t = T "sweep.csv", *b = T "bars.csv", *m = T "mixed.csv";
  testing_write(m, "x,y\n1,2\nfour,3\n");
  static const struct {
    const char *table, *args, *want;
  } bad[] = {
      {T "sweep.csv", "--x rays_per_thread --y cycles --bogus", "unknown option '--bogus'"},
      {T "sweep.csv", "--x rays_per_thread --y cycles --yrange 5:1",
       "--yrange: got '5:1', expected LO:HI"},
      {T "sweep.csv", "--x rays_per_thread --y cycles --yrange 1:2 --own-y",
       "--own-y and --yrange: choose one"},
      {T "bars.csv", "--x policy --y cycles --lines l2.size --logy",
       "--x policy holds text: bars have no numeric x and start at 0 (got --logy)"},
      {T "bars.csv", "--x policy --y cycles --stack --mark-x 2",
       "--mark-x: not with --stack (bars have no numeric x"},
      {T "bars.csv", "--x policy --y cycles,fetch_ray_bytes --stack",
       "--y: cycles (cycles) and fetch_ray_bytes (bytes) cannot share an axis"},
      {T "bars.csv", "--x policy --y fetch_geometry_bytes,fetch_ray_bytes --lines l2.size",
       "several --y columns draw a bar each, and so does --lines"},
      {T "bars.csv", "--x policy --y cycles", "fall on the same bar at policy = "},
      {T "mixed.csv", "--x x --y y", "pl_mixed.csv:3:1: error: --x x: not a number (got 'four')"},
      {T "sweep.csv", "--x rays_per_thread --y cycles,nope", "--y: no column 'nope'"},
      {T "bars.csv", "--x policy --y cycles --points",
       "--x policy holds text: bars have no numeric x and start at 0 (got --points)"},
      {T "bars.csv", "--x policy --y cycles --bars --points", "--points: not with --bars"},
  };
  (void)t, (void)b;
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    if (!expect_refused(bad[i].table, bad[i].args, bad[i].want)) continue;
    EXPECTF(!strchr(out, '\n') || strchr(out, '\n')[1] == '\0' ||
                strstr(out, "--help"), /* usage errors add a hint line */
            "'%s': more than one message: %s", bad[i].args, out);
  }
  unlink(m);
}

/* What a paper needs: titles and labels of the user's, the format by the
 * extension, error bars over seeds, the y axis from 0, the DRAM's peak. */
static void test_paper(void) {
  const char *t = T "seeds.csv";
  /* Three seeds a point: at x = 1 the values 10, 20, 30 (mean 20); at x = 2
   * the values 40, 44, 54 (mean 46). The seeds are the only difference. */
  testing_write(t, "point,scene,l2.size,seed,rays_per_thread,cycles\n"
                   "\"seed=1,rays_per_thread=1\",a,1024,1,1,10\n"
                   "\"seed=2,rays_per_thread=1\",a,1024,2,1,30\n"
                   "\"seed=3,rays_per_thread=1\",a,1024,3,1,20\n"
                   "\"seed=1,rays_per_thread=2\",a,1024,1,2,54\n"
                   "\"seed=2,rays_per_thread=2\",a,1024,2,2,40\n"
                   "\"seed=3,rays_per_thread=2\",a,1024,3,2,44\n");
  char *s = plot(t, "--x rays_per_thread --y cycles --title 'Cycles of a frame' --xlabel 'rays a "
                    "thread' --ylabel 'time (cycles)'");
  if (s) {
    EXPECTF(strstr(s, "set label 'Cycles of a frame' at screen 0.5"), "title: %s",
            lines_with(s, "set label"));
    EXPECT(strstr(s, "set xlabel 'rays a thread'\n") && strstr(s, "set ylabel 'time (cycles)'\n"));
    EXPECTF(strstr(s, "with yerrorlines") && strstr(s, "\n1 20 10 30\n2 46 40 54\ne\n"),
            "seeds: mean, smallest, largest: %s", lines_with(s, "plot"));
    EXPECTF(strstr(caption_of(s),
                   "points: the mean of 3 seeds, error bars from the smallest to the largest"),
            "the caption says what the bars are: %s", caption_of(s));
    /* From 0 though the values start at 10: 54 / 5 made round is 20. */
    EXPECTF(strstr(s, "set yrange [0:60]\n"), "%s", lines_with(s, "set yrange"));
    free(s);
  }
  s = plot(t, "--x rays_per_thread --y cycles --y-from-data");
  if (s) {
    EXPECTF(strstr(s, "set yrange [10:60]\n"), "%s", lines_with(s, "set yrange"));
    free(s);
  }
  /* Bars of seeds get whiskers; a default title in words. */
  s = plot(t, "--x scene --y cycles --where rays_per_thread=2");
  if (s) {
    EXPECTF(strstr(s, "with yerrorbars") && strstr(s, "\n0 46 40 54\n"), "whiskers: %s", s);
    EXPECTF(strstr(s, "set label 'cycles by scene' at screen 0.5"), "%s",
            lines_with(s, "set label"));
    free(s);
  }
  /* The default title in words without units; the label with them, once. */
  testing_write(T "work.csv", "cores,work_s\n1,2\n4,3\n");
  s = plot(T "work.csv", "--x cores --y work_s");
  if (s) {
    EXPECTF(strstr(s, "set label 'work against cores' at screen 0.5") &&
                strstr(s, "set ylabel 'work (seconds)'\n"),
            "%s", lines_with(s, "set"));
    free(s);
  }
  unlink(T "work.csv");
  /* Markers on a line of 60 points; a plain line past that (a timeline). */
  for (unsigned n = 60; n <= 61; n++) {
    char csv[2048] = "x,cycles\n";
    for (unsigned i = 1; i <= n; i++)
      snprintf(csv + strlen(csv), sizeof csv - strlen(csv), "%u,%u\n", i, i % 7);
    testing_write(T "dense.csv", csv);
    s = plot(T "dense.csv", "--x x --y cycles");
    if (s) {
      EXPECTF(strstr(s, n == 60 ? "with linespoints lw 2" : "with lines lw 1.5"), "%u points: %s",
              n, lines_with(s, "plot"));
      free(s);
    }
  }
  unlink(T "dense.csv");
  /* Rows that differ in a parameter besides the seed stay refused. */
  testing_write(T "seeds2.csv", "point,l2.size,seed,x,cycles\n"
                                "\"seed=1,l2.size=1024\",1024,1,1,10\n"
                                "\"seed=2,l2.size=2048\",2048,2,1,30\n");
  if (expect_refused(T "seeds2.csv", "--x x --y cycles", "differ in"))
    EXPECTF(strstr(out, "l2.size") != NULL, "%s", out);
  unlink(t);
  unlink(T "seeds2.csv");
}

/* A long title wraps; the extension chooses the format, and another is
 * refused before anything is written. */
static void test_formats(void) {
  const char *t = T "formats.csv";
  testing_write(t, "rays_per_thread,cycles\n1,10\n2,20\n");
  /* A long title wraps to the canvas (one panel: 520 pixels, about 50
   * characters of the title's font a line). */
  char *s;
  int rc;
  s = plot(t, "--x rays_per_thread --y cycles --title 'DRAM traffic per cycle of every policy "
              "on the grove at 256x256 with primary and hard-shadow rays, sixteen cores'");
  if (s) {
    const char *l = lines_with(s, "set label");
    EXPECTF(count(l, "center font ',13'") == 3 && strstr(l, "set label 'DRAM traffic per cycle"),
            "%s", l);
    for (const char *q = strstr(l, "set label '"); q; q = strstr(q + 1, "set label '")) {
      const char *e = strstr(q, "' at screen 0.5");
      if (e && e < strchr(q, '\n'))
        EXPECTF(e - q - 11 <= 52, "a title line of %d characters", (int)(e - q - 11));
    }
    free(s);
  }

  /* The extension chooses gnuplot's terminal, and the file is that format. */
  static const struct {
    const char *ext, *term, *magic;
  } fmts[] = {{"png", "set terminal pngcairo ", "\x89PNG"},
              {"pdf", "set terminal pdfcairo ", "%PDF"},
              {"svg", "set terminal svg ", "<?xml"}};
  for (unsigned i = 0; i < 3; i++) {
    run("rm -f " T "fmt.%s " T "fmt.gp", fmts[i].ext);
    rc = run("%s plot %s --x rays_per_thread --y cycles -o " T "fmt.%s --script " T "fmt.gp",
             RTSIM_BINARY, t, fmts[i].ext);
    char path[256];
    snprintf(path, sizeof path, T "fmt.%s", fmts[i].ext);
    char *pic = read_all(path), *gp = read_all(T "fmt.gp");
    EXPECTF(rc == 0 && pic && !memcmp(pic, fmts[i].magic, strlen(fmts[i].magic)), "%s: exit %d: %s",
            fmts[i].ext, rc, out);
    EXPECTF(gp && strstr(gp, fmts[i].term), "%s: %s", fmts[i].ext,
            gp ? lines_with(gp, "set term") : "");
    free(pic);
    free(gp);
    unlink(path);
  }
  /* Another extension: exit 2 before anything is written, script included. */
  run("rm -f " T "fmt.jpg " T "fmt.gp");
  rc = run("%s plot %s --x rays_per_thread --y cycles -o " T "fmt.jpg --script " T "fmt.gp",
           RTSIM_BINARY, t);
  EXPECTF(rc == 2 && strstr(out, "expected a .png, .pdf or .svg file"), "jpg: exit %d: %s", rc,
          out);
  EXPECT(access(T "fmt.jpg", F_OK) != 0 && access(T "fmt.gp", F_OK) != 0);
  rc = run("ls " T "fmt* 2>/dev/null | wc -l");
  EXPECTF(atoi(out) == 0, "files left: %s", out);
  unlink(t);
}

/* --dash: a colour a --lines value, a dash pattern a --dash value; the
 * legend names each once (the dashes in grey). */
static void test_dash(void) {
  const char *t = T "dash.csv";
  testing_write(t, "source,series,x,y\n"
                   "ours,a,1,10\nours,a,2,20\nours,b,1,30\nours,b,2,40\n"
                   "paper,a,1,11\npaper,a,2,21\npaper,b,1,31\npaper,b,2,41\n");
  char *s = plot(t, "--x x --y y --lines series --dash source --order ours,paper");
  if (s) {
    /* Series a is colour 1 both ways: solid for ours, dashed for the paper. */
    EXPECTF(count(s, " lt 1 pt 1 dt 1 notitle") == 1 && count(s, " lt 1 pt 1 dt 2 notitle") == 1 &&
                count(s, " lt 2 pt 2 dt 2 notitle") == 1,
            "%s", lines_with(s, "plot '-'"));
    /* The paper's a (second of a's series) holds its numbers. */
    EXPECTF(strstr(s, "\ne\n1 11\n2 21\ne\n"), "%s", s);
    EXPECTF(strstr(s, "title 'series = a'") && strstr(s, "title 'series = b'") &&
                strstr(s, "lc rgb 'gray30' dt 2 title 'source = paper'") &&
                count(s, "title 'source = ") == 2,
            "%s", lines_with(s, "plot NaN"));
    free(s);
  }
  testing_write(t, "source,x,y\na,1,1\nb,1,2\nc,1,3\nd,1,4\ne,1,5\n");
  expect_refused(t, "--x x --y y --dash source", "--dash source: more than 4 values");
  unlink(t);
}

/* The DRAM's peak: a dashed line and a legend entry where the y axis is DRAM
 * bytes per cycle and the table names the DRAM, in the caption too. */
static void test_peak(void) {
  const char *t = T "peak.csv";
  /* Banked: 1 channel x 8-byte bus x 2 transfers x 1200 MHz / 1400 MHz of the
   * cores = 13.714... bytes a core cycle. */
  testing_write(t, "scene,fidelity,clock_ghz,dram.channels,dram.bus_bytes,dram.clock_mhz,"
                   "dram.latency,dram.bytes_per_cycle,cycles,dram_bytes_per_cycle\n"
                   "a,banked,1.4,1,8,1200,50,13,1000,2.5\n"
                   "a,banked,1.4,1,8,1200,50,13,2000,7\n");
  char *s = plot(t, "--x cycles --y dram_bytes_per_cycle");
  if (s) {
    EXPECTF(strstr(s, "set arrow 1000 from graph 0, first 13.714285714285714"), "%s",
            lines_with(s, "set arrow"));
    EXPECTF(strstr(s, "title 'DRAM peak: 13.71'"), "%s", lines_with(s, "plot"));
    EXPECTF(
        strstr(caption_of(s), "DRAM: banked, 1 channel at 1200 MHz, peak 13.71 bytes per cycle"),
        "%s", caption_of(s));
    /* The peak is in the range; the label is in words. */
    EXPECTF(strstr(s, "set yrange [0:15]\n"), "%s", lines_with(s, "set yrange"));
    EXPECT(strstr(s, "set ylabel 'DRAM bytes per cycle'\n") != NULL);
    free(s);
  }
  s = plot(t, "--x cycles --y dram_bytes_per_cycle --no-peak");
  if (s) {
    EXPECTF(!strstr(s, "set arrow 1000 from") && !strstr(s, "peak:"), "%s", lines_with(s, "set"));
    free(s);
  }
  /* --peak on any axis. */
  s = plot(t, "--x cycles --y dram_bytes_per_cycle --peak 20");
  if (s) {
    EXPECTF(strstr(s, "first 20 to graph 1, first 20 ") && strstr(s, "title 'peak: 20'"), "%s",
            lines_with(s, "set arrow"));
    free(s);
  }
  /* A channel's peak is its dram.bytes_per_cycle. */
  testing_write(t, "fidelity,dram.latency,dram.bytes_per_cycle,cycles,dram_bytes_per_cycle\n"
                   "channel,50,6.5,1000,2.5\nchannel,50,6.5,2000,3\n");
  s = plot(t, "--x cycles --y dram_bytes_per_cycle");
  if (s) {
    EXPECTF(strstr(s, "first 6.5 to graph 1, first 6.5 ") &&
                strstr(caption_of(s), "DRAM: channel, 50 cycles, 6.5 bytes per cycle"),
            "%s", lines_with(s, "set"));
    free(s);
  }
  unlink(t);
}

int main(void) {
  test_lines();
  test_bars();
  test_points();
  test_units();
  test_refusals();
  test_paper();
  test_formats();
  test_peak();
  test_dash();
  return testing_done("test_plot");
}
