/* rtsim plot's figures, through the command line and the gnuplot script it
 * writes with --script: a fraction on 0..1, panels sharing one y range (and
 * their own with --own-y), tick labels with SI and binary prefixes, one
 * legend with units, a caption of the fixed parameters, bar charts for a
 * text x (side by side and stacked), PNG and SVG, and bad options refused
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

static void write_file(const char *path, const char *text) {
  FILE *f = fopen(path, "w");
  EXPECT(f != NULL);
  if (!f) return;
  fputs(text, f);
  fclose(f);
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
  write_file(t, SWEEP);
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
  s = plot(t, "--x rays_per_thread --y cycles --lines dram.latency --panels scene --own-y");
  if (s) {
    const char *r = lines_with(s, "set yrange");
    EXPECTF(strstr(r, "set yrange [900:1100]\n") && strstr(r, "set yrange [90000:120000]\n"),
            "own ranges: %s", r);
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
    write_file(t2, "cores,cycles\n256,9000\n1024,3000\n2000,2500\n");
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
  write_file(t, "scene,policy,l2.size,fetch_geometry_bytes,fetch_ray_bytes,cycles\n"
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
    EXPECT(strstr(s, "set ylabel 'fetch_*_bytes (bytes)'"));
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
  static const struct {
    const char *name, *row;
  } cases[] = {
      {"dram_refresh_cycles", "dram_refresh_cycles"},           /* _cycles: core cycles */
      {"dram.controller_cycles", "dram.controller_cycles"},     /* _cycles: core cycles */
      {"issue_slots", "issue_slots"},                           /* no ending: a count */
      {"seconds_ci95_low", "seconds_ci95_low"},                 /* no ending: a count */
      {"l2_miss_queue_length_max", "l2_miss_queue_length_max"}, /* no ending: a count */
      {"l2_node_accesses", "l2_<class>_accesses"},              /* fits l2_<class>_accesses */
  };
  for (unsigned i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    const char *name = cases[i].name;
    const char *table = T "units.csv";
    char unit[64], want[160];
    EXPECTF(table_unit(name, cases[i].row, unit, sizeof unit), "%s: not in rtsim run's tables",
            cases[i].row);
    char csv[256];
    snprintf(csv, sizeof csv, "x,%s\n1,2\n2,3\n", name);
    write_file(table, csv);
    if (!strcmp(unit, "count")) snprintf(want, sizeof want, "set ylabel '%s'\n", name);
    else snprintf(want, sizeof want, "set ylabel '%s (%s)'\n", name, unit);
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
  write_file(t, "rung,speedup,error\nfixed,2,0.5\nfixed,2,3\nfixed,4,1\nanalytic,8,20\n");
  char *s = plot(t, "--x speedup --y error --lines rung --points --logx --logy");
  if (s) {
    EXPECTF(count(s, "with points") == 4 && !strstr(s, "linespoints"), "not markers only: %s",
            lines_with(s, "plot"));
    EXPECT(strstr(s, "title 'rung = fixed'") != NULL);
    free(s);
  }
  run("rm -f " T "bad.png");
  int rc = run("%s plot %s --x speedup --y error --lines rung -o " T "bad.png", RTSIM_BINARY, t);
  EXPECTF(rc == 2 && strstr(out, "fall on the same line"), "lines at one x: exit %d: %s", rc, out);
  unlink(t);
}

static void test_refusals(void) {
  const char *t = T "sweep.csv", *b = T "bars.csv", *m = T "mixed.csv";
  write_file(m, "x,y\n1,2\nfour,3\n");
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
    run("rm -f " T "bad.png");
    int rc = run("%s plot %s %s -o " T "bad.png", RTSIM_BINARY, bad[i].table, bad[i].args);
    EXPECTF(rc == 2 && strstr(out, bad[i].want), "'%s': exit %d: %s", bad[i].args, rc, out);
    EXPECTF(!strchr(out, '\n') || strchr(out, '\n')[1] == '\0' ||
                strstr(out, "--help"), /* usage errors add a hint line */
            "'%s': more than one message: %s", bad[i].args, out);
    EXPECT(access(T "bad.png", F_OK) != 0);
  }
  unlink(m);
}

int main(void) {
  test_lines();
  test_bars();
  test_points();
  test_units();
  test_refusals();
  return testing_done("test_plot");
}
