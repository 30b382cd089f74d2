/* Sweeps, through the command line: expansion (cartesian and zipped, names
 * unique and readable, longest first), bad sweep files refused before any
 * point runs, a run merged into one table, resume after a kill (completed
 * points untouched), a failing point, the job lines through GNU parallel and
 * a simulated Slurm array (the same table), merge's union of columns and its
 * refusals, and plots. Fixtures live in tests/data/sweeps; the points are
 * 8x6 primary-ray images on configs/tiny.yaml, so each takes a fraction of a
 * second. */
#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "testing.h"

#define SW RTSIM_TEST_DATA "/sweeps/"
#define GOOD SW "good.yaml"

/* good.yaml's points in sweep order: policy x rays_per_thread x (l2.size, l2.ways). */
static const char *const GOOD_NAMES[8] = {
    "policy=recursive,rays_per_thread=1,l2.size=16KiB,l2.ways=4",
    "policy=recursive,rays_per_thread=1,l2.size=32KiB,l2.ways=8",
    "policy=recursive,rays_per_thread=2,l2.size=16KiB,l2.ways=4",
    "policy=recursive,rays_per_thread=2,l2.size=32KiB,l2.ways=8",
    "policy=packet,rays_per_thread=1,l2.size=16KiB,l2.ways=4",
    "policy=packet,rays_per_thread=1,l2.size=32KiB,l2.ways=8",
    "policy=packet,rays_per_thread=2,l2.size=16KiB,l2.ways=4",
    "policy=packet,rays_per_thread=2,l2.size=32KiB,l2.ways=8",
};

static char out[1 << 16];

/* Run a shell command (stderr with stdout into `out`); its exit code. */
#define run(...) testing_runf(out, sizeof out, __VA_ARGS__)

static int exists(const char *path) {
  struct stat sb;
  return stat(path, &sb) == 0;
}

static int point_file(const char *dir, const char *point, const char *name, struct stat *sb) {
  char p[16384];
  snprintf(p, sizeof p, "%s/%s/%s", dir, point, name);
  return stat(p, sb) == 0;
}

static int complete_points(const char *dir) {
  int n = 0;
  struct stat sb;
  for (int i = 0; i < 8; i++) n += point_file(dir, GOOD_NAMES[i], "stats.json", &sb);
  return n;
}

static char *read_all(const char *path) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  fseek(f, 0, SEEK_END);
  long n = ftell(f);
  fseek(f, 0, SEEK_SET);
  char *b = malloc((size_t)n + 1);
  size_t got = fread(b, 1, (size_t)n, f);
  b[got] = '\0';
  fclose(f);
  return b;
}

static int same_text(const char *a, const char *b) {
  char *x = read_all(a), *y = read_all(b);
  int same = x && y && !strcmp(x, y);
  free(x);
  free(y);
  return same;
}

static int count_lines(const char *s) {
  int n = 0;
  for (; *s; s++) n += *s == '\n';
  return n;
}

/* --emit-jobs prints the points, one line each, absolute paths, names
 * unique; the longest expected points come first. */
static void test_expansion(void) {
  EXPECT(run("rm -rf %s/sw_emit", RTSIM_TMP) == 0);
  EXPECT(run("cd / && (%s sweep %s -o %s/sw_emit --emit-jobs 2>/dev/null)", RTSIM_BINARY, GOOD,
             RTSIM_TMP) == 0);
  EXPECTF(count_lines(out) == 8, "expected 8 job lines, got: %s", out);
  /* More ray contexts are expected to take longer; equal estimates keep the
   * sweep's order. */
  static const int order[8] = {2, 3, 6, 7, 0, 1, 4, 5};
  char *line = out;
  for (int k = 0; k < 8 && line; k++) {
    const int i = order[k];
    /* A line names its point (#19 item 1): the sweep's runner on it. */
    char want[4096];
    snprintf(want, sizeof want, " sweep %s -o %s/sw_emit -j 1 --point %s", GOOD, RTSIM_TMP,
             GOOD_NAMES[i]);
    char *nl = strchr(line, '\n');
    if (nl) *nl = '\0';
    EXPECTF(!strncmp(line, RTSIM_BINARY " sweep /", strlen(RTSIM_BINARY) + 8),
            "line %d does not start with the absolute program: %s", i, line);
    EXPECTF(strstr(line, want) &&
                !strcmp(line + strlen(line) - strlen(GOOD_NAMES[i]), GOOD_NAMES[i]),
            "line %d: want %s in %s", k, want, line);
    struct stat sb;
    char dir[4096], cmd[8192];
    snprintf(dir, sizeof dir, "%s/sw_emit", RTSIM_TMP);
    snprintf(cmd, sizeof cmd, "%s/%s/command.sh", dir, GOOD_NAMES[i]);
    char *sh = read_all(cmd);
    EXPECTF(sh && strstr(sh, "--set dram.latency=100 --set rays_per_thread="),
            "%s lacks the fixed and swept --set: %s", cmd, sh ? sh : "(missing)");
    free(sh);
    EXPECTF(point_file(dir, GOOD_NAMES[i], "command.sh", &sb) &&
                point_file(dir, GOOD_NAMES[i], "point.csv", &sb),
            "%s: no command.sh or point.csv", GOOD_NAMES[i]);
    line = nl ? nl + 1 : NULL;
  }
  for (int i = 0; i < 8; i++)
    for (int j = 0; j < i; j++) EXPECT(strcmp(GOOD_NAMES[i], GOOD_NAMES[j]) != 0);

  /* Scene values named by their file, commas as '+'; longest first. */
  EXPECT(run("(%s sweep %snames.yaml -o %s/sw_names --emit-jobs 2>/dev/null)", RTSIM_BINARY, SW,
             RTSIM_TMP) == 0);
  EXPECTF(count_lines(out) == 8, "names.yaml: %s", out);
  static const char *const names[] = {
      "scene=room,rays=primary,width=4",         "scene=room,rays=primary,width=8",
      "scene=room,rays=primary+shadow,width=4",  "scene=room,rays=primary+shadow,width=8",
      "scene=grove,rays=primary,width=4",        "scene=grove,rays=primary,width=8",
      "scene=grove,rays=primary+shadow,width=4", "scene=grove,rays=primary+shadow,width=8"};
  for (int i = 0; i < 8; i++) {
    char want[512];
    snprintf(want, sizeof want, "/sw_names -j 1 --point %s\n", names[i]);
    EXPECTF(strstr(out, want) != NULL, "names.yaml: no point %s in %s", names[i], out);
  }
  char *last = out + strlen(out) - 1;
  while (last > out && last[-1] != '\n') last--;
  EXPECTF(strstr(out, "rays=primary+shadow,width=8\n") < strchr(out, '\n') + 1,
          "the first job is not a widest, two-ray-type point: %s", out);
  EXPECTF(strstr(last, "rays=primary,width=4\n") != NULL, "the last job is not a small one: %s",
          last);
  char *sh = read_all(RTSIM_TMP "/sw_names/scene=room,rays=primary+shadow,width=8/command.sh");
  EXPECTF(sh && strstr(sh, "--rays primary,shadow --width 8 --height 4"), "workload arguments: %s",
          sh ? sh : "(no command.sh)");
  free(sh);

  /* Quoted, a rays value keeps its comma (one point); after a space, a comma
   * separates two values. */
  EXPECT(run("(%s sweep %srays_quoted.yaml -o %s/sw_rays --emit-jobs 2>/dev/null)", RTSIM_BINARY,
             SW, RTSIM_TMP) == 0);
  EXPECTF(count_lines(out) == 3 && strstr(out, "--point rays=shadow+specular\n") &&
              strstr(out, "--point rays=shadow\n") && strstr(out, "--point rays=primary\n"),
          "rays_quoted.yaml: %s", out);

  /* A zipped key's value may repeat when the rows differ: three points. */
  EXPECT(run("(%s sweep %szip_repeat.yaml -o %s/sw_zip --emit-jobs 2>/dev/null)", RTSIM_BINARY, SW,
             RTSIM_TMP) == 0);
  EXPECTF(count_lines(out) == 3, "zip_repeat.yaml: %s", out);
  EXPECTF(strstr(out, "--point policy=dynamic,dynamic.sharing=chip\n") &&
              strstr(out, "--point policy=dynamic,dynamic.sharing=partition\n"),
          "zip_repeat.yaml: %s", out);
  sh = read_all(RTSIM_TMP "/sw_zip/policy=dynamic,dynamic.sharing=chip/command.sh");
  EXPECTF(sh && strstr(sh, "--set dynamic.sharing=chip"), "zip_repeat.yaml: %s",
          sh ? sh : "(no command.sh)");
  free(sh);
  /* Three points, two a task: the snake gives task 2 two points, task 1 one. */
  int slurm_rc = run("(%s sweep %szip_repeat.yaml -o %s/sw_zip --emit-slurm 2 2>/dev/null)",
                     RTSIM_BINARY, SW, RTSIM_TMP);
  unsigned named = 0;
  for (const char *q = out; (q = strstr(q, " --point ")); q++) named++;
  EXPECTF(slurm_rc == 0 && strstr(out, "\n#SBATCH --array=1-2\n") && named == 3,
          "zip_repeat.yaml --emit-slurm 2: %d %s", slurm_rc, out);
}

/* Bad sweep files: exit 2, one line at file:line:col, nothing created. */
static void test_bad_files(void) {
  static const struct {
    const char *file, *want;
  } bad[] = {
      {"bad_top_key.yaml",
       "bad_top_key.yaml:3:1: error: axis: unknown key 'axis' (did you mean 'axes'?)"},
      {"bad_axis_key.yaml",
       "bad_axis_key.yaml:5:3: error: axes.l2.sise: unknown key 'l2.sise' (did you mean 'l2.size'?)"},
      {"bad_value.yaml", "bad_value.yaml:4:20: error: l2.size: not a size (got '32MB'"},
      {"bad_relation.yaml",
       "bad_relation.yaml:6:16: error: l2.ways: the ways must divide the number of lines (got 3 ways for 256 lines) [point l2.size=16KiB,l2.ways=3]"},
      {"bad_empty_axis.yaml", "bad_empty_axis.yaml:5:20: error: axes.rays_per_thread: empty list"},
      {"bad_zip_length.yaml",
       "bad_zip_length.yaml:5:14: error: zip[0]: l2.ways: 3 values, but l2.size has 2"},
      {"bad_twice.yaml",
       "bad_twice.yaml:6:5: error: zip[0].l2.size: 'l2.size' is given twice (also in axes at line 4"},
      {"bad_dup_value.yaml", "bad_dup_value.yaml:4:17: error: axes.cores[2]: '1' is listed twice"},
      {"bad_zip_row.yaml",
       "bad_zip_row.yaml:4:52: error: zip[0]: the values at index 3 (one from each key) repeat those at index 1 (line 4)"},
      {"bad_policy.yaml", "bad_policy.yaml:4:23: error: policy: unknown policy (got 'fastest'"},
      {"bad_rays.yaml",
       "bad_rays.yaml:4:19: error: rays: not a list of ray types (got 'primary,glossy'"},
      /* #19 item 6: YAML splits [primary, shadow,specular] into three values. */
      {"bad_rays_flow.yaml",
       "bad_rays_flow.yaml:4:19: error: axes.rays[1]: 'shadow,specular' unquoted in a flow list is two values, so two points (quote it, \"shadow,specular\", for one point"},
      {"bad_scene_missing.yaml",
       "bad_scene_missing.yaml:3:44: error: axes.scene[1]: cannot open '../../../scenes/small/hall.yaml'"},
      {"bad_names.yaml",
       "bad_names.yaml:4:44: error: scene: two points would share the directory name 'scene=room'"},
      {"bad_no_scene.yaml", "bad_no_scene.yaml:2:11: error: workload: missing the scene"},
      {"bad_set_key.yaml", "bad_set_key.yaml:4:3: error: set.policy: unknown key 'policy'"},
      {"bad_nested.yaml",
       "bad_nested.yaml:4:14: error: axes.cores[1]: wrong type (got a list, expected one value)"},
      {"bad_machine.yaml", "configs/bad_size_unit.yaml:2:9: error: l2.size: not a size"},
      /* #17: "\n1.5" was taken as 1.5 and broke --emit-jobs' one line a point. */
      {"bad_value_newline.yaml",
       "bad_value_newline.yaml:4:18: error: clock_ghz: not a number: whitespace before or after it (got '\\n1.5', expected a decimal number)"},
      {"bad_width_leading_zero.yaml",
       "bad_width_leading_zero.yaml:2:59: error: width: not a whole number: a leading zero, ambiguous between octal and decimal (got '010', expected 1 to 16384)"},
      {"bad_path_space.yaml",
       "bad_path_space.yaml:1:10: error: machine: whitespace before or after it (got '../../../configs/tiny.yaml '"},
  };
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    run("rm -rf %s/sw_bad", RTSIM_TMP);
    for (int emit = 0; emit < 2; emit++) {
      int rc = run("%s sweep %s%s -o %s/sw_bad%s", RTSIM_BINARY, SW, bad[i].file, RTSIM_TMP,
                   emit ? " --emit-jobs" : "");
      EXPECTF(rc == 2, "%s: exit %d: %s", bad[i].file, rc, out);
      EXPECTF(strstr(out, bad[i].want) != NULL, "%s: got '%s', want '%s'", bad[i].file, out,
              bad[i].want);
      EXPECTF(count_lines(out) == 1, "%s: expected one line: %s", bad[i].file, out);
      EXPECTF(!exists(RTSIM_TMP "/sw_bad"), "%s: the sweep directory was created", bad[i].file);
    }
  }
  static const struct {
    const char *args, *want;
  } usage[] = {
      {"sweep", "missing SWEEP.yaml"},
      {"sweep " GOOD, "missing -o DIR"},
      {"sweep " GOOD " -o x -j 0", "-j: got '0'"},
      {"merge", "missing DIR"},
      {"merge x", "missing -o TABLE.csv"},
      {"plot t.csv --y cycles -o t.png", "missing --x KEY"},
      {"plot t.csv --x a --y b -o t.jpg", "expected a .png, .pdf or .svg file"},
      {"plot t.csv --x a --y b -o t.png --where a", "--where: got 'a', expected KEY=VALUE"},
      {"plot t.csv --x a --y b -o t.png --mark-x two", "--mark-x: got 'two', expected a number"},
  };
  for (size_t i = 0; i < sizeof usage / sizeof usage[0]; i++) {
    int rc = run("cd %s && %s %s", RTSIM_TMP, RTSIM_BINARY, usage[i].args);
    EXPECTF(rc == 2 && strstr(out, usage[i].want), "'%s': exit %d: %s", usage[i].args, rc, out);
  }
  static const char *const helps[] = {"sweep", "merge", "plot"};
  for (size_t i = 0; i < 3; i++)
    EXPECT(run("%s %s --help", RTSIM_BINARY, helps[i]) == 0 && strstr(out, "usage: rtsim"));
}

/* Run good.yaml into dir with -j 2 and merge it into table: both succeed. */
static void sweep_and_merge(const char *dir, const char *table) {
  int rc = run("%s sweep %s -o %s -j 2", RTSIM_BINARY, GOOD, dir);
  EXPECTF(rc == 0, "sweep into %s: exit %d: %s", dir, rc, out);
  rc = run("%s merge %s -o %s --reproducible", RTSIM_BINARY, dir, table);
  EXPECTF(rc == 0 && strstr(out, "merge: 8 points"), "merge %s: exit %d: %s", dir, rc, out);
}

/* The reference run: every point complete; the table's layout and values. */
static void test_run_and_merge(void) {
  run("rm -rf %s/sw_ref %s/sw_ref.csv", RTSIM_TMP, RTSIM_TMP);
  sweep_and_merge(RTSIM_TMP "/sw_ref", RTSIM_TMP "/sw_ref.csv");
  EXPECT(complete_points(RTSIM_TMP "/sw_ref") == 8);
  char *t = read_all(RTSIM_TMP "/sw_ref.csv");
  EXPECT(t != NULL);
  if (!t) return;
  static const char head[] =
      "point,policy,rays_per_thread,l2.size,l2.ways,scene,scene_hash,accel,kd_splits,rays,width,";
  EXPECTF(!strncmp(t, head, strlen(head)), "header: %.200s", t);
  EXPECT(count_lines(t) == 9);
  /* Rows in natural order of the names; a swept size takes its resolved value. */
  EXPECTF(
      strstr(
          t,
          "\n\"policy=packet,rays_per_thread=1,l2.size=16KiB,l2.ways=4\",packet,1,16384,4,room-small,"),
      "first row: %.300s", strchr(t, '\n'));
  free(t);
  /* Rerunning finds everything complete and runs nothing. */
  int rc = run("%s sweep %s -o %s/sw_ref", RTSIM_BINARY, GOOD, RTSIM_TMP);
  EXPECTF(rc == 0 && strstr(out, "8 points, 8 complete, running 0"), "rerun: %d %s", rc, out);
  EXPECT(run("(%s sweep %s -o %s/sw_ref --emit-jobs 2>/dev/null)", RTSIM_BINARY, GOOD, RTSIM_TMP) ==
             0 &&
         out[0] == '\0');
  /* The same DIR with a changed sweep is refused, not mixed. */
  rc = run("%s sweep %sgood_changed.yaml -o %s/sw_ref", RTSIM_BINARY, SW, RTSIM_TMP);
  EXPECTF(rc == 2 && strstr(out, "was made by another command"), "changed sweep: %d %s", rc, out);
}

/* Kill a -j 1 sweep (its whole process group) once the first point is
 * complete; the rerun completes the rest without touching the first. */
static void test_resume(void) {
  const char *dir = RTSIM_TMP "/sw_resume";
  run("rm -rf %s %s.csv", dir, dir);
  pid_t pid = fork();
  if (pid == 0) {
    setpgid(0, 0);
    freopen("/dev/null", "w", stderr);
    execl(RTSIM_BINARY, RTSIM_BINARY, "sweep", GOOD, "-o", dir, "-j", "1", (char *)NULL);
    _exit(127);
  }
  setpgid(pid, pid);
  struct timespec nap = {0, 2000000};
  for (int i = 0; i < 30000 && complete_points(dir) == 0; i++) nanosleep(&nap, NULL);
  kill(-pid, SIGKILL);
  waitpid(pid, NULL, 0);
  int done = complete_points(dir);
  EXPECTF(done >= 1 && done < 8, "killed sweep: %d points complete (want some, not all)", done);
  struct stat before[8], after;
  int was[8];
  for (int i = 0; i < 8; i++) was[i] = point_file(dir, GOOD_NAMES[i], "stats.json", &before[i]);
  int rc = run("%s sweep %s -o %s -j 2", RTSIM_BINARY, GOOD, dir);
  EXPECTF(rc == 0, "resume: exit %d: %s", rc, out);
  char want[128];
  snprintf(want, sizeof want, "8 points, %d complete, running %d", done, 8 - done);
  EXPECTF(strstr(out, want) != NULL, "resume: want '%s' in %s", want, out);
  EXPECT(complete_points(dir) == 8);
  for (int i = 0; i < 8; i++)
    if (was[i]) {
      EXPECT(point_file(dir, GOOD_NAMES[i], "stats.json", &after));
      EXPECTF(after.st_ino == before[i].st_ino &&
                  after.st_mtim.tv_sec == before[i].st_mtim.tv_sec &&
                  after.st_mtim.tv_nsec == before[i].st_mtim.tv_nsec,
              "%s was run again", GOOD_NAMES[i]);
    }
  rc = run("%s merge %s -o %s.csv --reproducible", RTSIM_BINARY, dir, dir);
  EXPECTF(rc == 0 && same_text(RTSIM_TMP "/sw_resume.csv", RTSIM_TMP "/sw_ref.csv"),
          "resumed table differs from the reference (%d: %s)", rc, out);
}

/* A point that fails (its image.exr is a directory, which the run would not
 * write over): the others finish, its stderr is kept, the
 * summary names it, exit 1; once mended, only it runs. */
static void test_failing_point(void) {
  const char *dir = RTSIM_TMP "/sw_fail";
  const char *bad = GOOD_NAMES[5];
  run("rm -rf %s && mkdir -p '%s/%s/image.exr/keep'", dir, dir, bad);
  int rc = run("%s sweep %s -o %s -j 2", RTSIM_BINARY, GOOD, dir);
  EXPECTF(rc == 1, "exit %d, want 1: %s", rc, out);
  EXPECT(complete_points(dir) == 7);
  char want[512];
  snprintf(want, sizeof want, "1 point failed");
  EXPECTF(strstr(out, want) && strstr(out, bad) && strstr(out, "Is a directory"), "summary: %s",
          out);
  char err_path[4096];
  snprintf(err_path, sizeof err_path, "%s/%s/error.txt", dir, bad);
  char *err = read_all(err_path);
  EXPECTF(err && strstr(err, "cannot write the file over it") && strstr(err, "exited with code 2"),
          "error.txt: %s", err ? err : "(missing)");
  free(err);
  /* Whoever runs the point, its own job line keeps its stderr (#19 item 1). */
  unlink(err_path);
  rc = run("cd / && %s sweep %s -o %s --emit-jobs 2>/dev/null | sh", RTSIM_BINARY, GOOD, dir);
  EXPECTF(rc == 1, "the failing point's job line: exit %d, want 1: %s", rc, out);
  err = read_all(err_path);
  EXPECTF(err && strstr(err, "cannot write the file over it") && strstr(err, "exited with code 2"),
          "error.txt from the job line: %s", err ? err : "(missing)");
  free(err);
  /* Merge takes the complete points and names the other. */
  rc = run("%s merge %s -o %s.csv --reproducible", RTSIM_BINARY, dir, dir);
  EXPECTF(rc == 0 && strstr(out, "merge: 7 points") && strstr(out, "1 incomplete skipped"),
          "merge: %d %s", rc, out);
  run("rm -rf '%s/%s/image.exr'", dir, bad);
  rc = run("%s sweep %s -o %s -j 2", RTSIM_BINARY, GOOD, dir);
  EXPECTF(rc == 0 && strstr(out, "8 points, 7 complete, running 1"), "retry: %d %s", rc, out);
  EXPECTF(!exists(err_path), "error.txt left after the point succeeded");
  rc = run("%s merge %s -o %s.csv --reproducible", RTSIM_BINARY, dir, dir);
  EXPECT(rc == 0 && same_text(RTSIM_TMP "/sw_fail.csv", RTSIM_TMP "/sw_ref.csv"));
}

/* docs/sweeps.md's recipes: job lines through GNU parallel, and a Slurm array
 * (each task runs line $SLURM_ARRAY_TASK_ID), both from another directory. */
static void test_jobs_elsewhere(void) {
  if (run("parallel --version") != 0) {
    EXPECTF(0, "GNU parallel is not installed (sh .ci/setup installs it)");
    return;
  }
  run("rm -rf %s/sw_par %s/sw_slurm", RTSIM_TMP, RTSIM_TMP);
  int rc = run("cd %s && %s sweep %s -o sw_par --emit-jobs 2>/dev/null | (cd / && parallel "
               "--will-cite -j 2)",
               RTSIM_TMP, RTSIM_BINARY, GOOD);
  EXPECTF(rc == 0, "parallel: exit %d: %s", rc, out);
  rc =
      run("%s merge %s/sw_par -o %s/sw_par.csv --reproducible", RTSIM_BINARY, RTSIM_TMP, RTSIM_TMP);
  EXPECTF(rc == 0 && same_text(RTSIM_TMP "/sw_par.csv", RTSIM_TMP "/sw_ref.csv"),
          "the table through GNU parallel differs (%d: %s)", rc, out);

  /* docs/sweeps.md's Slurm recipe (#19 item 1): a script of 3 tasks of at most 3
   * points, which Slurm copies at submission (cp here). Task 2 runs; then the
   * jobs are emitted again (fewer now, over the same names) before tasks 1
   * and 3 of the submitted copy run, and task 2 again: nothing lost. */
  const char *sl = RTSIM_TMP "/sw_slurm";
  rc = run("(cd %s && %s sweep %s -o sw_slurm --emit-slurm 3 > sw_slurm.sbatch && cp "
           "sw_slurm.sbatch sw_slurm.submitted)",
           RTSIM_TMP, RTSIM_BINARY, GOOD);
  EXPECTF(rc == 0 && strstr(out, "3 array tasks (8 incomplete points of 8"), "emit-slurm: %d %s",
          rc, out);
  char *sc = read_all(RTSIM_TMP "/sw_slurm.sbatch");
  /* Uncalibrated: 2 x a few seconds is under the 5-minute floor; the largest
   * point's memory estimate, 32 MiB + 256 B x 5.7K triangles + 64 KiB x 8
   * contexts, about 34 MiB, rounds up to 48M. */
  EXPECTF(sc && strstr(sc, "\n#SBATCH --array=1-3\n") && strstr(sc, "\n#SBATCH --time=5\n") &&
              strstr(sc, "\n#SBATCH --mem=48M\n") && strstr(sc, "#!/bin/sh\n") == sc,
          "the script's requests: %s", sc ? sc : "(missing)");
  free(sc);
  rc = run("cd / && SLURM_ARRAY_TASK_ID=2 sh %s.submitted", sl);
  EXPECTF(rc == 0 && strstr(out, "3 of 8 points named"), "task 2: %d %s", rc, out);
  int done = 0;
  struct stat sb;
  for (int i = 0; i < 8; i++) done += point_file(sl, GOOD_NAMES[i], "stats.json", &sb);
  EXPECTF(done == 3, "after task 2: %d points complete, want 3", done);
  rc = run("(cd %s && %s sweep %s -o sw_slurm --emit-slurm 3 > sw_slurm.sbatch && %s sweep %s -o "
           "sw_slurm --emit-jobs > sw_jobs.txt)",
           RTSIM_TMP, RTSIM_BINARY, GOOD, RTSIM_BINARY, GOOD);
  EXPECTF(rc == 0 && strstr(out, "2 array tasks (5 incomplete points of 8") &&
              strstr(out, "5 job lines"),
          "re-emit: %d %s", rc, out);
  for (int task = 1; task <= 3; task++) {
    rc = run("cd / && SLURM_ARRAY_TASK_ID=%d sh %s.submitted", task == 2 ? 2 : task, sl);
    EXPECTF(rc == 0, "task %d after the re-emit: %d %s", task, rc, out);
  }
  rc = run("%s merge %s -o %s.csv --reproducible", RTSIM_BINARY, sl, sl);
  EXPECTF(rc == 0 && same_text(RTSIM_TMP "/sw_slurm.csv", RTSIM_TMP "/sw_ref.csv"),
          "the table through the Slurm recipe differs (%d: %s)", rc, out);
  /* A task the script does not have, or no array at all, fails loudly. */
  rc = run("SLURM_ARRAY_TASK_ID=4 sh %s.submitted", sl);
  EXPECTF(rc == 2 && strstr(out, "rtsim sweep: no task '4' in ") && strstr(out, "tasks 1 to 3"),
          "task 4: %d %s", rc, out);
  rc = run("unset SLURM_ARRAY_TASK_ID; sh %s.submitted", sl);
  EXPECTF(rc == 2 && strstr(out, "no task ''"), "no task id: %d %s", rc, out);
  /* So does a line naming a point the sweep does not have (an edited file). */
  rc =
      run("%s sweep %s -o %s -j 1 --point policy=packet,rays_per_thread=3", RTSIM_BINARY, GOOD, sl);
  EXPECTF(rc == 2 && strstr(out, "error: --point 'policy=packet,rays_per_thread=3': no such point"),
          "unknown point: %d %s", rc, out);
  rc = run("%s sweep %s -o %s --point ''", RTSIM_BINARY, GOOD, sl);
  EXPECTF(rc == 2 && strstr(out, "--point: got ''"), "empty point: %d %s", rc, out);
  /* Every point complete (#40): emitting again says so and writes no script
   * and no job line, so nothing submitted can run a task that fails. */
  rc = run("(cd %s && %s sweep %s -o sw_slurm --emit-slurm 3 > sw_slurm.sbatch)", RTSIM_TMP,
           RTSIM_BINARY, GOOD);
  EXPECTF(rc == 0 && strstr(out, "nothing to run: all 8 points complete (no script written)"),
          "emit-slurm when complete: %d %s", rc, out);
  struct stat st;
  EXPECTF(stat(RTSIM_TMP "/sw_slurm.sbatch", &st) == 0 && st.st_size == 0,
          "the script of a complete sweep is not empty (%lld bytes)", (long long)st.st_size);
  rc = run("(cd %s && %s sweep %s -o sw_slurm --emit-jobs > sw_jobs.txt)", RTSIM_TMP, RTSIM_BINARY,
           GOOD);
  EXPECTF(rc == 0 && strstr(out, "nothing to run: all 8 points complete (no job line written)"),
          "emit-jobs when complete: %d %s", rc, out);
  EXPECTF(stat(RTSIM_TMP "/sw_jobs.txt", &st) == 0 && st.st_size == 0,
          "job lines for a complete sweep (%lld bytes)", (long long)st.st_size);
}

/* --status (#19 item 2) on a sweep with points complete, failed, running
 * (this process holds the point's claim) and never run; a runner leaves the
 * running point to its holder. */
static void test_status(void) {
  const char *dir = RTSIM_TMP "/sw_status";
  run("rm -rf %s && mkdir -p '%s/%s/image.exr/keep'", dir, dir, GOOD_NAMES[1]);
  int rc = run("%s sweep %s -o %s --status", RTSIM_BINARY, GOOD, dir);
  EXPECTF(rc == 1 && strstr(out, ": 8 points: 0 complete, 0 failed, 0 running, 8 not run\n"),
          "before: %d %s", rc, out);
  EXPECT(!exists(RTSIM_TMP "/sw_status/"
                           "policy=recursive,rays_per_thread=1,l2.size=16KiB,l2.ways=4"));
  rc = run("%s sweep %s -o %s -j 2 --point %s --point %s --point %s --point %s", RTSIM_BINARY, GOOD,
           dir, GOOD_NAMES[0], GOOD_NAMES[1], GOOD_NAMES[2], GOOD_NAMES[3]);
  EXPECTF(rc == 1, "four points, one failing: %d %s", rc, out);
  char lock[8192];
  snprintf(lock, sizeof lock, "%s/%s", dir, GOOD_NAMES[4]);
  mkdir(lock, 0777);
  strcat(lock, "/.running");
  int fd = open(lock, O_RDWR | O_CREAT, 0644);
  struct flock l = {.l_type = F_WRLCK, .l_whence = SEEK_SET};
  EXPECT(fd >= 0 && fcntl(fd, F_SETLK, &l) == 0);
  char who[128];
  int n = snprintf(who, sizeof who, "node7 %ld %lld\n", (long)getpid(), (long long)time(NULL));
  EXPECT(write(fd, who, (size_t)n) == n);
  rc = run("%s sweep %s -o %s --status", RTSIM_BINARY, GOOD, dir);
  EXPECTF(rc == 1 && strstr(out, ": 8 points: 3 complete, 1 failed, 1 running, 3 not run\n"),
          "counts: %d %s", rc, out);
  char want[1024];
  snprintf(want, sizeof want, "\nfailed    %s: ", GOOD_NAMES[1]);
  char *at = strstr(out, want);
  EXPECTF(at && strstr(at, "cannot write the file over it") < strchr(at + 1, '\n'),
          "failed line: %s", out);
  snprintf(want, sizeof want, "\nrunning   %s: on node7, pid %ld, for ", GOOD_NAMES[4],
           (long)getpid());
  EXPECTF(strstr(out, want), "running line (want %s): %s", want, out);
  for (int i = 5; i < 8; i++) {
    snprintf(want, sizeof want, "\nnot run   %s\n", GOOD_NAMES[i]);
    EXPECTF(strstr(out, want), "not-run line %d: %s", i, out);
  }
  for (int i = 0; i < 4; i++) {
    snprintf(want, sizeof want, "\n%-9s %s", i == 1 ? "failed" : "complete", GOOD_NAMES[i]);
    EXPECTF(strstr(out, want), "line %d: %s", i, out);
  }
  /* The failed points are listed before the complete ones. */
  EXPECT(strstr(out, "\nfailed") && strstr(out, "\ncomplete") &&
         strstr(out, "\nfailed") < strstr(out, "\ncomplete"));
  /* A runner leaves the claimed point to its holder (exit 0, not run). */
  rc = run("%s sweep %s -o %s -j 1 --point %s", RTSIM_BINARY, GOOD, dir, GOOD_NAMES[4]);
  EXPECTF(rc == 0 && strstr(out, "1 point left to the process running them"), "busy: %d %s", rc,
          out);
  struct stat sb;
  EXPECT(!point_file(dir, GOOD_NAMES[4], "stats.json", &sb));
  close(fd);
  run("rm -rf '%s/%s/image.exr'", dir, GOOD_NAMES[1]);
  rc = run("%s sweep %s -o %s -j 2", RTSIM_BINARY, GOOD, dir);
  EXPECTF(rc == 0 && strstr(out, "running 5"), "the rest: %d %s", rc, out);
  rc = run("%s sweep %s -o %s --status", RTSIM_BINARY, GOOD, dir);
  EXPECTF(rc == 0 && strstr(out, ": 8 points: 8 complete, 0 failed, 0 running, 0 not run\n"),
          "after: %d %s", rc, out);
}

/* A sweep directory moved or copied elsewhere resumes (#19 item 3): the
 * points' own directories, and configs and scenes moved with the tree, are
 * the same paths; a config that is another file is not. */
static void test_moved(void) {
  const char *dir = RTSIM_TMP "/sw_moved";
  run("rm -rf %s && cp -a %s/sw_ref %s", dir, RTSIM_TMP, dir);
  int rc = run("%s sweep %s -o %s", RTSIM_BINARY, GOOD, dir);
  EXPECTF(rc == 0 && strstr(out, "8 points, 8 complete, running 0"), "copied: %d %s", rc, out);
  /* As if the whole tree, this directory in it, had lived at /gone/tree:
   * every path in the commands, -o's included, under a root that is no more. */
  rc =
      run("cd %s && for f in */command.sh; do sed -i -e 's|/sw_ref/|/sw_moved/|' -e "
          "'s|%s/|/gone/tree/|g' \"$f\"; done && grep -q /gone/tree/configs/tiny.yaml */command.sh",
          dir, RTSIM_SOURCE_DIR);
  EXPECTF(rc == 0, "rewriting the commands: %d %s", rc, out);
  /* The configs moved with the tree only when the build lives inside it. */
  if (strncmp(RTSIM_TMP, RTSIM_SOURCE_DIR "/", strlen(RTSIM_SOURCE_DIR) + 1) != 0) {
    printf("test_moved: the build is outside the source tree; the moved-tree case is skipped\n");
    return;
  }
  rc = run("%s sweep %s -o %s", RTSIM_BINARY, GOOD, dir);
  EXPECTF(rc == 0 && strstr(out, "8 points, 8 complete, running 0"), "moved tree: %d %s", rc, out);
  rc = run(
      "sed -i 's|/gone/tree/configs/tiny.yaml|/gone/tree/configs/other.yaml|' '%s/%s/command.sh'",
      dir, GOOD_NAMES[3]);
  rc = run("%s sweep %s -o %s", RTSIM_BINARY, GOOD, dir);
  EXPECTF(rc == 2 && strstr(out, "was made by another command"), "another config: %d %s", rc, out);
}

/* Merged tables carry each point's provenance (#19 item 3) and warn, still
 * writing the table, when points come from different builds or one scene
 * under two hashes. */
static void test_provenance(void) {
  const char *t = RTSIM_TMP "/sw_prov.csv";
  int rc = run("%s merge %s/sw_ref -o %s", RTSIM_BINARY, RTSIM_TMP, t);
  EXPECTF(rc == 0 && !strstr(out, "warning"), "merge: %d %s", rc, out);
  char *csv = read_all(t);
  EXPECTF(csv && strstr(csv, ",wall_s,peak_rss_mb,host,revision\n"), "header: %.300s",
          csv ? csv : "(missing)");
  char host[256] = "";
  gethostname(host, sizeof host - 1);
  /* Each row ends in a positive wall time, a peak memory, this host and a revision. */
  int rows = 0;
  for (char *r = csv ? strchr(csv, '\n') : NULL; r && r[1]; r = strchr(r + 1, '\n')) {
    char *end = strchr(r + 1, '\n'), *c = end;
    for (int commas = 0; c > r && commas < 4;) commas += *--c == ',';
    double wall = 0, rss = 0;
    char h[256] = "", rev[256] = "";
    int got = c > r ? sscanf(c + 1, "%lf,%lf,%255[^,],%255[^\n]", &wall, &rss, h, rev) : 0;
    EXPECTF(got == 4 && wall > 0 && rss > 0 && !strcmp(h, host) && rev[0], "provenance cells: %.*s",
            (int)(end - c), c);
    rows++;
  }
  EXPECT(rows == 8);
  free(csv);
  /* One point from another build, another with its scene changed. */
  const char *mixed = RTSIM_TMP "/sw_mixed";
  run("rm -rf %s && cp -a %s/sw_ref %s", mixed, RTSIM_TMP, mixed);
  run("sed -i 's|^  \"revision\": \".*\",$|  \"revision\": \"v0-old\",|' '%s/%s/stats.json'", mixed,
      GOOD_NAMES[2]);
  run("sed -i '2s|^room-small,[0-9a-f]*,|room-small,0123456789abcdef,|' '%s/%s/stats.csv'", mixed,
      GOOD_NAMES[6]);
  rc = run("%s merge %s -o %s.csv", RTSIM_BINARY, mixed, mixed);
  EXPECTF(rc == 0 && exists(RTSIM_TMP "/sw_mixed.csv"), "mixed: %d %s", rc, out);
  EXPECTF(strstr(out, "merge: warning: points from different builds: revision '") &&
              strstr(out, "'v0-old' ("
                          "policy=recursive,rays_per_thread=2,l2.size=16KiB,l2.ways=4)"),
          "revision warning: %s", out);
  EXPECTF(
      strstr(out, "merge: warning: a scene changed between points of scene room-small: "
                  "scene_hash '") &&
          strstr(out,
                 "'0123456789abcdef' (policy=packet,rays_per_thread=2,l2.size=16KiB,l2.ways=4)"),
      "scene hash warning: %s", out);
}

/* Points with different columns merge into their union; a directory with no
 * complete point, or a broken stats.csv, is refused. */
static void test_merge_edges(void) {
  const char *d = RTSIM_TMP "/sw_union";
  run("rm -rf %s && mkdir -p %s/p10 %s/p9 %s/q", d, d, d, d);
  char p[4096];
  snprintf(p, sizeof p, "%s/p9/stats.json", d),
      testing_write(p,
                    "{\n  \"revision\": \"r9\",\n  \"host\": \"h\\\"9\",\n  \"wall_s\": 1.5\n}\n");
  snprintf(p, sizeof p, "%s/p9/stats.csv", d), testing_write(p, "x,y\n1,\"a,b\"\n");
  snprintf(p, sizeof p, "%s/p9/point.csv", d), testing_write(p, "k,x\n7,5\n");
  snprintf(p, sizeof p, "%s/p10/stats.json", d), testing_write(p, "{}\n");
  snprintf(p, sizeof p, "%s/p10/stats.csv", d), testing_write(p, "x,z\n3,4\n");
  snprintf(p, sizeof p, "%s/q/command.sh", d), testing_write(p, "exec false\n");
  int rc = run("%s merge %s -o %s.csv", RTSIM_BINARY, d, d);
  EXPECTF(rc == 0 && strstr(out, "1 incomplete skipped: q") &&
              strstr(out, "warning: points from different builds: revision 'r9' (p9) and '' (p10)"),
          "union: %d %s", rc, out);
  char *t = read_all(RTSIM_TMP "/sw_union.csv");
  EXPECTF(t && !strcmp(t, "point,k,x,y,z,wall_s,peak_rss_mb,host,revision\n"
                          "p9,7,1,\"a,b\",,1.5,,\"h\"\"9\",r9\np10,,3,,4,,,,\n"),
          "union table: %s", t ? t : "(missing)");
  free(t);
  rc = run("%s merge %s -o %s.csv --reproducible", RTSIM_BINARY, d, d);
  t = read_all(RTSIM_TMP "/sw_union.csv");
  EXPECTF(rc == 0 && t && !strcmp(t, "point,k,x,y,z,revision\np9,7,1,\"a,b\",,r9\np10,,3,,4,\n"),
          "union table, reproducible: %s", t ? t : "(missing)");
  free(t);

  run("rm -rf %s/sw_none && mkdir -p %s/sw_none/a", RTSIM_TMP, RTSIM_TMP);
  rc = run("%s merge %s/sw_none -o %s/sw_none.csv", RTSIM_BINARY, RTSIM_TMP, RTSIM_TMP);
  EXPECTF(rc == 2 && strstr(out, "sw_none: error: no complete point"), "empty: %d %s", rc, out);
  EXPECT(!exists(RTSIM_TMP "/sw_none.csv"));
  rc = run("%s merge %s/sw_missing -o %s/sw_none.csv", RTSIM_BINARY, RTSIM_TMP, RTSIM_TMP);
  EXPECTF(rc == 2 && strstr(out, "cannot open the sweep directory"), "missing: %d %s", rc, out);

  snprintf(p, sizeof p, "%s/p10/stats.csv", d), testing_write(p, "x,z\n3,4,5\n");
  rc = run("%s merge %s -o %s/sw_broken.csv", RTSIM_BINARY, d, RTSIM_TMP);
  EXPECTF(rc == 2 && strstr(out, "p10/stats.csv:2:1: error: row has 3 fields, the header has 2"),
          "broken: %d %s", rc, out);
  EXPECT(!exists(RTSIM_TMP "/sw_broken.csv"));
}

static int has_magic(const char *path, const char *magic) {
  char *t = read_all(path);
  int ok = t && strstr(t, magic) == t;
  free(t);
  return ok;
}

/* Plots of the reference table; bad columns and ambiguous plots refused. */
static void test_plot(void) {
  const char *t = RTSIM_TMP "/sw_ref.csv";
  run("rm -f %s/sw_plot.png %s/sw_plot.svg", RTSIM_TMP, RTSIM_TMP);
  int rc = run("%s plot %s --x rays_per_thread --y cycles --lines policy --panels l2.size -o "
               "%s/sw_plot.png",
               RTSIM_BINARY, t, RTSIM_TMP);
  EXPECTF(rc == 0 && strstr(out, "8 points, 2 lines, 2 panels"), "png: %d %s", rc, out);
  EXPECT(has_magic(RTSIM_TMP "/sw_plot.png", "\x89PNG"));
  rc = run("%s plot %s --x rays_per_thread --y l2_fetch_bytes --lines policy --where l2.ways=8 "
           "--logx --logy -o %s/sw_plot.svg",
           RTSIM_BINARY, t, RTSIM_TMP);
  EXPECTF(rc == 0 && strstr(out, "4 points, 2 lines, 1 panel"), "svg: %d %s", rc, out);
  char *svg = read_all(RTSIM_TMP "/sw_plot.svg");
  EXPECTF(svg && strstr(svg, "<svg") && strstr(svg, "L2 fetch bytes") &&
              strstr(svg, "policy = packet"),
          "svg lacks its labels or legend");
  free(svg);

  static const struct {
    const char *args, *want;
  } bad[] = {
      {"--x rays_per_thread --y cycls",
       "sw_ref.csv:1: error: --y: no column 'cycls' (columns: point, policy, rays_per_thread,"},
      {"--x rays_per_thread --y cycles --lines polcy", "--lines: no column 'polcy'"},
      {"--x rays_per_thread --y cycles --where l3.size=1", "--where: no column 'l3.size'"},
      {"--x rays_per_thread --y cycles --lines policy",
       "differ in l2.size, l2.ways: fix it with --where"},
      {"--x policy --y cycles",
       "sw_ref.csv:3: error: rows at lines 2 and 3 fall on the same bar at policy = packet but differ in"},
      {"--x rays_per_thread --y fetch_queue_bytes --lines policy --panels l2.size --logy",
       "a value must be positive on a log scale"},
      {"--x rays_per_thread --y cycles --where l2.size=16KiB",
       "--where l2.size=16KiB: no row has it (the column holds: 16384, 32768)"},
  };
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    run("rm -f %s/sw_bad.png", RTSIM_TMP);
    rc = run("%s plot %s %s -o %s/sw_bad.png", RTSIM_BINARY, t, bad[i].args, RTSIM_TMP);
    EXPECTF(rc == 2 && strstr(out, bad[i].want), "'%s': exit %d: %s", bad[i].args, rc, out);
    EXPECTF(count_lines(out) == 1, "'%s': expected one line: %s", bad[i].args, out);
    EXPECT(!exists(RTSIM_TMP "/sw_bad.png"));
  }
}

/* Write path: a sweep over configs/tiny.yaml and scene (absolute), then axes. */
static void write_sweep(const char *path, const char *scene, const char *axes) {
  FILE *f = fopen(path, "w");
  EXPECT(f != NULL);
  if (!f) return;
  fprintf(f,
          "machine: %s/configs/tiny.yaml\nworkload:\n  scene: %s\n  rays: primary\n"
          "  width: 4\n  height: 4\naxes:\n%s",
          RTSIM_SOURCE_DIR, scene, axes);
  fclose(f);
}

/* A list of n values "first, first+1, ..." then extra, as a flow sequence. */
static char *seq(unsigned first, unsigned n, const char *extra) {
  size_t cap = (size_t)n * 12 + 64 + strlen(extra);
  char *b = malloc(cap), *p = b;
  p += sprintf(p, "[");
  for (unsigned i = 0; i < n; i++) p += sprintf(p, "%s%u", i ? ", " : "", first + i);
  sprintf(p, "%s%s]\n", extra[0] && n ? ", " : "", extra);
  return b;
}

/* Bounded work: the point cap refuses a sweep before anything is written
 * (--max-points raises it), a duplicate at the end of a 99,000-value axis is
 * found (the check is n log n: it once took 20 s), a named pipe as the sweep,
 * its machine or its scene is refused at once, and a plot of more panels
 * than the cap is refused. */
static void test_bounded(void) {
  const char *scene = RTSIM_SOURCE_DIR "/scenes/small/room.yaml";
  const char *file = RTSIM_TMP "/sw_cap.yaml", *dir = RTSIM_TMP "/sw_cap";
  char axes[4096];
  char *a = seq(1, 100, ""), *b = seq(0, 100, ""), *c = seq(1, 100, "");
  snprintf(axes, sizeof axes, "  dram.latency: %s  seed: %s  timeline.window: %s", a, b, c);
  free(a), free(b), free(c);
  write_sweep(file, scene, axes);
  for (int emit = 0; emit < 2; emit++) {
    run("rm -rf %s", dir);
    int rc = run("%s sweep %s -o %s%s", RTSIM_BINARY, file, dir, emit ? " --emit-jobs" : "");
    EXPECTF(rc == 2 && count_lines(out) == 1 &&
                strstr(out,
                       "sw_cap.yaml:10:3: error: timeline.window: the sweep has 1000000 points "
                       "(expected at most 10000: fewer values, or raise the cap with rtsim "
                       "sweep --max-points N, up to 1000000)"),
            "a million points: exit %d: %s", rc, out);
    EXPECTF(!exists(dir), "a refused sweep made its directory");
  }
  /* 12 points: over a cap of 11, under one of 12. */
  a = seq(1, 12, "");
  snprintf(axes, sizeof axes, "  seed: %s", a);
  free(a);
  write_sweep(file, scene, axes);
  run("rm -rf %s", dir);
  int rc = run("%s sweep %s -o %s --emit-jobs --max-points 11", RTSIM_BINARY, file, dir);
  EXPECTF(rc == 2 && strstr(out, "seed: the sweep has 12 points (expected at most 11:") &&
              !exists(dir),
          "12 points, cap 11: exit %d: %s", rc, out);
  rc = run("(%s sweep %s -o %s --emit-jobs --max-points 12 2>/dev/null)", RTSIM_BINARY, file, dir);
  EXPECTF(rc == 0 && count_lines(out) == 12, "12 points, cap 12: exit %d: %s", rc, out);
  static const char *const bad_caps[] = {"0", "1000001", "1e3"};
  for (int i = 0; i < 3; i++) {
    rc = run("%s sweep %s -o %s --max-points %s", RTSIM_BINARY, file, dir, bad_caps[i]);
    EXPECTF(rc == 2 && strstr(out, "--max-points: got"), "--max-points %s: %d %s", bad_caps[i], rc,
            out);
  }

  /* 99,000 values, the last repeating the fifth: reported there, with the
   * line of the first. Without the repeat, the whole axis is checked and the
   * cap refuses it. */
  a = seq(1, 98999, "5");
  char *big = malloc(strlen(a) + 64);
  sprintf(big, "  seed: %s", a);
  free(a);
  write_sweep(file, scene, big);
  free(big);
  run("rm -rf %s", dir);
  rc = run("timeout 60 %s sweep %s -o %s", RTSIM_BINARY, file, dir);
  EXPECTF(rc == 2 && count_lines(out) == 1 &&
              strstr(out, "error: axes.seed[98999]: '5' is listed twice (first at line 8)") &&
              !exists(dir),
          "a repeat at the end of a long axis: exit %d: %.300s", rc, out);
  a = seq(1, 99000, "");
  big = malloc(strlen(a) + 64);
  sprintf(big, "  dram.latency: %s", a);
  free(a);
  write_sweep(file, scene, big);
  free(big);
  rc = run("timeout 60 %s sweep %s -o %s", RTSIM_BINARY, file, dir);
  EXPECTF(rc == 2 && strstr(out, "dram.latency: the sweep has 99000 points") && !exists(dir),
          "a long axis of distinct values: exit %d: %.300s", rc, out);

  /* Named pipes: as the sweep file, as its machine, as its scene. */
  const char *fifo = RTSIM_TMP "/sw_fifo.yaml";
  unlink(fifo);
  EXPECT(mkfifo(fifo, 0600) == 0);
  write_sweep(file, fifo, "  seed: [1, 2]\n");
  rc = run("timeout 20 %s sweep %s -o %s", RTSIM_BINARY, file, dir);
  EXPECTF(rc == 2 && count_lines(out) == 1 &&
              strstr(out, "sw_fifo.yaml: error: cannot open: not a regular file (a named pipe)") &&
              !exists(dir),
          "a pipe as the scene: exit %d (124: it blocked): %s", rc, out);
  rc = run("timeout 20 %s sweep %s -o %s", RTSIM_BINARY, fifo, dir);
  EXPECTF(rc == 2 && strstr(out, "sw_fifo.yaml: error: cannot open: not a regular file") &&
              !exists(dir),
          "a pipe as the sweep: exit %d: %s", rc, out);
  FILE *f = fopen(file, "w");
  if (f) {
    fprintf(f, "machine: %s\nworkload:\n  scene: %s\n", fifo, scene);
    fclose(f);
  }
  rc = run("timeout 20 %s sweep %s -o %s", RTSIM_BINARY, file, dir);
  EXPECTF(rc == 2 && strstr(out, "sw_fifo.yaml: error: cannot open: not a regular file") &&
              !exists(dir),
          "a pipe as the machine: exit %d: %s", rc, out);
  unlink(fifo);
  unlink(file);

  /* A plot of 101 panels, or of 101 lines, is refused before gnuplot starts;
   * 100 lines in 2 panels are drawn. */
  const char *csv = RTSIM_TMP "/sw_panels.csv";
  f = fopen(csv, "w");
  if (f) {
    fputs("x,y,p,q\n", f);
    for (int i = 0; i < 101; i++) fprintf(f, "1,2,%d,%d\n", i, i % 2);
    fclose(f);
  }
  static const struct {
    const char *args, *want;
  } caps[] = {
      {"--panels p", "sw_panels.csv:1: error: --panels p: more than 100 values (expected at most "
                     "100 panels"},
      {"--lines p", "sw_panels.csv:1: error: --lines p: more than 100 values (expected at most 100 "
                    "lines"},
  };
  for (int i = 0; i < 2; i++) {
    run("rm -f %s/sw_panels.png", RTSIM_TMP);
    rc = run("%s plot %s --x x --y y %s -o %s/sw_panels.png", RTSIM_BINARY, csv, caps[i].args,
             RTSIM_TMP);
    EXPECTF(rc == 2 && count_lines(out) == 1 && strstr(out, caps[i].want), "'%s': exit %d: %s",
            caps[i].args, rc, out);
    EXPECT(!exists(RTSIM_TMP "/sw_panels.png"));
  }
  f = fopen(csv, "w");
  if (f) {
    fputs("x,y,p,q\n", f);
    for (int i = 0; i < 200; i++) fprintf(f, "%d,%d,%d,%d\n", i % 2, i, i / 2, i / 100);
    fclose(f);
  }
  rc = run("%s plot %s --x x --y y --lines p --panels q -o %s/sw_panels.svg", RTSIM_BINARY, csv,
           RTSIM_TMP);
  EXPECTF(rc == 0 && strstr(out, "200 points, 100 lines, 2 panels"), "100 lines: exit %d: %s", rc,
          out);
  char *svg = read_all(RTSIM_TMP "/sw_panels.svg");
  EXPECTF(svg && strstr(svg, "p = 0") && strstr(svg, "p = 99") && strstr(svg, "q = 1"),
          "the 100-line plot lacks its legend or titles");
  free(svg);
  unlink(csv);
  unlink(RTSIM_TMP "/sw_panels.svg");
}

/* accel is a workload key: each point's command passes --accel, so its run
 * traces that structure; an unknown value, or a structure the point's policy
 * does not trace, is refused before anything is written, at the value. */
static void test_accel_axis(void) {
  const char *scene = RTSIM_SOURCE_DIR "/scenes/small/room.yaml";
  const char *file = RTSIM_TMP "/sw_accel.yaml", *dir = RTSIM_TMP "/sw_accel";
  write_sweep(file, scene, "  accel: [kd, bvh8]\n");
  EXPECT(run("rm -rf %s && (%s sweep %s -o %s --emit-jobs 2>/dev/null)", dir, RTSIM_BINARY, file,
             dir) == 0);
  EXPECTF(count_lines(out) == 2 && strstr(out, "--point accel=bvh8\n") &&
              strstr(out, "--point accel=kd\n"),
          "accel axis: %s", out);
  char *sh = read_all(RTSIM_TMP "/sw_accel/accel=bvh8/command.sh");
  EXPECTF(sh && strstr(sh, " --accel bvh8"), "accel point's command: %s", sh ? sh : "(none)");
  free(sh);
  sh = read_all(RTSIM_TMP "/sw_accel/accel=kd/command.sh");
  EXPECTF(sh && strstr(sh, " --accel kd"), "accel point's command: %s", sh ? sh : "(none)");
  free(sh);
  write_sweep(file, scene, "  accel: [kd, bvh4]\n");
  int rc = run("rm -rf %s && %s sweep %s -o %s --emit-jobs", dir, RTSIM_BINARY, file, dir);
  EXPECTF(rc == 2 && strstr(out, "sw_accel.yaml:8:15: error: accel: unknown structure (got 'bvh4', "
                                 "expected one of kd, bvh2, bvh8)"),
          "bvh4: exit %d: %s", rc, out);
  EXPECTF(access(dir, F_OK) != 0, "bvh4: %s was written", dir);
}

int main(void) {
  test_accel_axis();
  test_bounded();
  test_expansion();
  test_bad_files();
  test_run_and_merge();
  test_resume();
  test_failing_point();
  test_jobs_elsewhere();
  test_status();
  test_moved();
  test_provenance();
  test_merge_edges();
  test_plot();
  return testing_done("test_sweep");
}
