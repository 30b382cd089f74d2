/* Runs that fail whole, through the real binary: a write that fails part way
 * (the file-size limit, RLIMIT_FSIZE with SIGXFSZ ignored, makes the kernel
 * refuse the bytes of any file past the limit: a true write error that needs
 * no hook in the program) leaves nothing under the output's name, no
 * temporary and no sibling, one message and exit code 2; an earlier DIR (or
 * image, or table) stays exactly as it was. Covers rtsim run (new, complete
 * and incomplete DIR, a DRAM trace in DIR or beside it), rtsim render with its
 * preview, rtsim traffic's table and a sweep's point. */
#include <dirent.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>

#include "testing.h"

#define TINY RTSIM_SOURCE_DIR "/configs/tiny.yaml"
#define ROOM_TINY RTSIM_TEST_DATA "/scenes/good_room_tiny.yaml"
#define RUN RTSIM_BINARY " run " TINY " " ROOM_TINY " --width 16 --height 12"

static char out[1 << 16];

#define run(...) testing_runf(out, sizeof out, __VA_ARGS__)

/* run() with files limited to `bytes` (a write past it fails with EFBIG). */
static int run_limited(unsigned long bytes, const char *fmt, ...) {
  char cmd[8192];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(cmd, sizeof cmd, fmt, ap);
  va_end(ap);
  struct rlimit old, lim;
  EXPECT(getrlimit(RLIMIT_FSIZE, &old) == 0);
  lim = old;
  lim.rlim_cur = bytes;
  void (*was)(int) = signal(SIGXFSZ, SIG_IGN);
  EXPECT(setrlimit(RLIMIT_FSIZE, &lim) == 0);
  int rc = testing_run(cmd, out, sizeof out);
  EXPECT(setrlimit(RLIMIT_FSIZE, &old) == 0);
  signal(SIGXFSZ, was);
  return rc;
}

static bool exists(const char *path) {
  struct stat sb;
  return lstat(path, &sb) == 0;
}

/* Entries of dir whose name starts with prefix and ends with suffix. */
static int count_named(const char *dir, const char *prefix, const char *suffix) {
  DIR *d = opendir(dir);
  if (!d) return 0;
  int n = 0;
  struct dirent *de;
  while ((de = readdir(d))) {
    size_t l = strlen(de->d_name), ls = strlen(suffix);
    n += !strncmp(de->d_name, prefix, strlen(prefix)) && l >= ls &&
         !strcmp(de->d_name + l - ls, suffix);
  }
  closedir(d);
  return n;
}

/* The output is one line: "<file>: error: <what>", file ending in `name`. */
static bool one_message(const char *name, const char *what) {
  const char *nl = strchr(out, '\n');
  char expect[512];
  snprintf(expect, sizeof expect, "%s: error: %s", name, what);
  return nl && nl[1] == '\0' && strstr(out, expect) != NULL && strstr(out, expect) < nl;
}

/* A checksum of everything in dir (names, hidden ones too, and bytes), to
 * tell "exactly as it was". */
static void fingerprint(const char *dir, char *buf, size_t cap) {
  run("cd %s && ls -A | LC_ALL=C sort | while read f; do echo \"== $f\"; cat \"$f\"; done | cksum",
      dir);
  size_t n = strlen(out) < cap ? strlen(out) : cap - 1; /* cksum's one short line */
  memcpy(buf, out, n);
  buf[n] = '\0';
}

/* rtsim run into a new DIR, failing at timeline.csv (a window of 10 cycles
 * makes it the largest file before the plot), then at stats.json (fidelity
 * analytic: image.exr 0.8 KB, stats.csv 3.7 KB, stats.json 5.2 KB), the last
 * file: nothing named DIR, no sibling, no trace in DIR or beside it. */
static void test_run_new(void) {
  const char *dir = RTSIM_TMP "/od_new", *trace = RTSIM_TMP "/od_new.trace";
  run("rm -rf %s %s", dir, trace);
  int rc = run_limited(20000, "%s -o %s --set timeline.window=10 --dram-trace %s", RUN, dir, trace);
  EXPECTF(rc == 2 && one_message("od_new/timeline.csv", "cannot write the file: File too large"),
          "timeline.csv: %d %s", rc, out);
  EXPECTF(!exists(dir), "a failed run left its directory");
  EXPECTF(!exists(trace), "a failed run left its DRAM trace");
  EXPECT(testing_temps_of(trace) == 0);
  EXPECTF(count_named(RTSIM_TMP, ".od_new.", "") == 0, "a sibling is left");

  rc = run_limited(4500, "%s -o %s --set fidelity=analytic", RUN, dir);
  EXPECTF(rc == 2 && one_message("od_new/stats.json", "cannot write the file: File too large"),
          "stats.json: %d %s", rc, out);
  EXPECT(!exists(dir));
  EXPECT(count_named(RTSIM_TMP, ".od_new.", "") == 0);

  /* The trace asked for in DIR goes with DIR: absent on failure, there on
   * success. */
  char in_dir[512];
  snprintf(in_dir, sizeof in_dir, "%s/dram.trace", dir);
  rc = run_limited(20000, "%s -o %s --set timeline.window=10 --dram-trace %s", RUN, dir, in_dir);
  EXPECTF(rc == 2 && !exists(dir), "a trace in DIR: %d %s", rc, out);
  rc = run("%s -o %s --dram-trace %s", RUN, dir, in_dir);
  EXPECTF(rc == 0 && exists(in_dir), "a trace in DIR, no limit: %d %s", rc, out);
  char stats[512];
  snprintf(stats, sizeof stats, "%s/stats.json", dir);
  EXPECT(exists(stats));
  /* ... but not under a name of the run's own. */
  rc = run("%s -o %s --dram-trace %s", RUN, dir, stats);
  EXPECTF(rc == 2 && strstr(out, "one of the run's own outputs"), "trace over stats.json: %d %s",
          rc, out);
}

/* A rerun over a complete DIR (with a file of its own, a sweep's command.sh)
 * and over an incomplete one (an earlier run's image.exr without stats.json)
 * that fails leaves DIR exactly as it was; one that succeeds replaces the
 * outputs, keeps command.sh and drops the earlier run's leftovers. */
static void test_run_existing(void) {
  const char *dir = RTSIM_TMP "/od_old";
  char before[256], after[256];
  run("rm -rf %s", dir);
  int rc = run("%s -o %s --seed 1 && echo keep > %s/command.sh", RUN, dir, dir);
  EXPECTF(rc == 0, "the first run: %s", out);
  fingerprint(dir, before, sizeof before);
  rc = run_limited(20000, "%s -o %s --seed 2 --set timeline.window=10", RUN, dir);
  EXPECTF(rc == 2 && one_message("od_old/timeline.csv", "cannot write the file: File too large"),
          "complete DIR: %d %s", rc, out);
  fingerprint(dir, after, sizeof after);
  EXPECTF(!strcmp(before, after), "a failed rerun changed the complete directory");
  EXPECT(count_named(RTSIM_TMP, ".od_old.", "") == 0);

  run("rm -rf %s && mkdir %s && echo old > %s/image.exr && echo keep > %s/point.csv", dir, dir, dir,
      dir);
  fingerprint(dir, before, sizeof before);
  rc = run_limited(4500, "%s -o %s --set fidelity=analytic", RUN, dir);
  EXPECTF(rc == 2 && one_message("od_old/stats.json", "cannot write the file: File too large"),
          "incomplete DIR: %d %s", rc, out);
  fingerprint(dir, after, sizeof after);
  EXPECTF(!strcmp(before, after), "a failed rerun changed the incomplete directory");
  rc = run("%s -o %s --set fidelity=analytic", RUN, dir);
  EXPECTF(rc == 0, "incomplete DIR, no limit: %s", out);
  char *keep = testing_slurp(dir, "point.csv", NULL);
  size_t len = 0;
  char *image = testing_slurp(dir, "image.exr", &len);
  EXPECTF(keep && !strcmp(keep, "keep\n"), "point.csv not carried over");
  EXPECTF(image && len > 100, "the earlier image.exr kept");
  free(keep);
  free(image);
  EXPECT(count_named(RTSIM_TMP, ".od_old.", "") == 0);
}

/* OUTDIR that cannot be a directory: a file of that name (left as it was),
 * or a parent that does not exist. One message, exit 2, nothing made. */
static void test_run_refused(void) {
  const char *file = RTSIM_TMP "/od_file";
  run("rm -rf %s && echo keep > %s", file, file);
  int rc = run("%s -o %s", RUN, file);
  EXPECTF(rc == 2 && one_message("od_file", "cannot create the directory: a file of that name "
                                            "exists"),
          "a file: %d %s", rc, out);
  char *keep = testing_slurp(RTSIM_TMP, "od_file", NULL);
  EXPECT(keep && !strcmp(keep, "keep\n"));
  free(keep);
  rc = run("%s -o %s/od_no_such/dir", RUN, RTSIM_TMP);
  EXPECTF(rc == 2 && one_message("od_no_such/dir",
                                 "cannot create the directory: No such file or directory"),
          "no parent: %d %s", rc, out);
  EXPECT(!exists(RTSIM_TMP "/od_no_such"));
  EXPECT(count_named(RTSIM_TMP, ".od_file.", "") == 0);
}

/* rtsim render: a preview that cannot be written leaves no image either, and
 * an earlier image stays; an image past the limit (64x64: some 20 KB) leaves
 * neither. */
static void test_render(void) {
  const char *exr = RTSIM_TMP "/od_render.exr", *png = RTSIM_TMP "/od_render.png";
  const char *render = RTSIM_BINARY " render " ROOM_TINY " --width 16 --height 12";
  run("rm -f %s %s", exr, png);
  int rc = run("%s -o %s --preview %s/no-such-folder/p.png", render, exr, RTSIM_TMP);
  EXPECTF(rc == 2 && !exists(exr), "preview in no folder: %d %s", rc, out);
  EXPECT(testing_temps_of(exr) == 0);
  run("echo old > %s", exr);
  rc = run("%s -o %s --preview %s/no-such-folder/p.png", render, exr, RTSIM_TMP);
  char *old = testing_slurp(RTSIM_TMP, "od_render.exr", NULL);
  EXPECTF(rc == 2 && old && !strcmp(old, "old\n"), "an earlier image replaced: %d %s", rc, out);
  free(old);
  run("rm -f %s", exr);
  rc = run_limited(2000, "%s -o %s --preview %s --width 64 --height 64", render, exr, png);
  EXPECTF(rc == 2 && one_message("od_render.exr", "cannot write EXR"), "EXR past the limit: %d %s",
          rc, out);
  EXPECT(!exists(exr) && !exists(png));
  EXPECT(testing_temps_of(exr) == 0 && testing_temps_of(png) == 0);
  rc = run("%s -o %s --preview %s", render, exr, png);
  EXPECTF(rc == 0 && exists(exr) && exists(png), "render: %d %s", rc, out);
}

/* rtsim traffic: the table past the limit is not left, nor its temporary. */
static void test_traffic(void) {
  const char *csv = RTSIM_TMP "/od_traffic.csv";
  run("rm -f %s", csv);
  int rc =
      run_limited(500, "%s traffic %s --policy recursive --rays primary --width 8 --height 8 -o %s",
                  RTSIM_BINARY, ROOM_TINY, csv);
  EXPECTF(rc == 2 && strstr(out, "od_traffic.csv: error: cannot write the table: File too large"),
          "traffic: %d %s", rc, out);
  EXPECT(!exists(csv) && testing_temps_of(csv) == 0);
}

/* A sweep's point that fails writing keeps only what the sweep wrote
 * (command.sh, point.csv, error.txt with the message) and completes on the
 * next sweep. */
static void test_sweep_point(void) {
  const char *file = RTSIM_TMP "/od_sweep.yaml", *dir = RTSIM_TMP "/od_sweep";
  testing_writef(file,
                 "machine: %s\nworkload:\n  scene: %s\n  width: 16\n  height: 12\n"
                 "set:\n  timeline.window: 10\naxes:\n  seed: [1]\n",
                 TINY, ROOM_TINY);
  run("rm -rf %s", dir);
  int rc = run_limited(20000, "%s sweep %s -o %s -j 1", RTSIM_BINARY, file, dir);
  EXPECTF(rc == 1 && strstr(out, "File too large"), "the sweep: %d %s", rc, out);
  run("cd %s/seed=1 && ls -A | LC_ALL=C sort | tr '\\n' ' '", dir);
  EXPECTF(!strcmp(out, "command.sh error.txt point.csv "), "the failed point holds: %s", out);
  EXPECT(count_named(dir, ".seed=1.", "") == 0);
  rc = run("%s sweep %s -o %s -j 1", RTSIM_BINARY, file, dir);
  run("cd %s/seed=1 && ls -A | LC_ALL=C sort | tr '\\n' ' '", dir);
  EXPECTF(rc == 0 && !strcmp(out, "command.sh image.exr point.csv stats.csv stats.json "
                                  "timeline.csv traffic.png "),
          "the rerun point holds: %d %s", rc, out);
}

int main(void) {
  test_run_new();
  test_run_existing();
  test_run_refused();
  test_render();
  test_traffic();
  test_sweep_point();
  return testing_done("test_outdir");
}
