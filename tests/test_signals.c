/* Signals, through the real binary: rtsim run interrupted while it rewrites a
 * complete directory leaves the old run or the new one, whole, never a mix
 * (and no temporaries); rtsim sweep stopped by SIGTERM stops its points and
 * leaves no error.txt in the points that completed; a sweep killed outright
 * (SIGKILL) does not leave its point running. This program is a child
 * subreaper, so a point orphaned by its sweep becomes its child and can be
 * waited for. Every wait polls against a deadline; no fixed sleeps. */
#include <dirent.h>
#include <errno.h>
#include <signal.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "testing.h"

#define TINY RTSIM_SOURCE_DIR "/configs/tiny.yaml"
#define ROOM_TINY RTSIM_TEST_DATA "/scenes/good_room_tiny.yaml"

static char out[1 << 16];

/* Run a shell command (stderr with stdout into `out`); its exit code. */
#define run(...) testing_runf(out, sizeof out, __VA_ARGS__)

static double now(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static void nap(void) {
  struct timespec t = {0, 2000000};
  nanosleep(&t, NULL);
}

static bool exists(const char *path) {
  struct stat sb;
  return stat(path, &sb) == 0;
}

/* Start argv (a NULL-terminated list) with stdout and stderr to /dev/null and
 * the default action for SIGINT and SIGTERM; its pid. */
static pid_t start(const char *const *argv) {
  pid_t pid = fork();
  if (pid == 0) {
    signal(SIGINT, SIG_DFL);
    signal(SIGTERM, SIG_DFL);
    if (!freopen("/dev/null", "w", stdout) || !freopen("/dev/null", "w", stderr)) _exit(126);
    execv(argv[0], (char *const *)argv);
    _exit(127);
  }
  return pid;
}

/* Wait up to `seconds` for child pid: true with *status when it ended. */
static bool wait_for(pid_t pid, double seconds, int *status) {
  const double end = now() + seconds;
  for (;;) {
    pid_t got = waitpid(pid, status, WNOHANG);
    if (got == pid) return true;
    if (got < 0 || now() > end) return false;
    nap();
  }
}

/* A child of parent, from /proc (0 if none). */
static pid_t child_of(pid_t parent) {
  DIR *d = opendir("/proc");
  if (!d) return 0;
  pid_t found = 0;
  struct dirent *de;
  while (!found && (de = readdir(d))) {
    char *end;
    long pid = strtol(de->d_name, &end, 10);
    if (pid <= 0 || *end) continue;
    char path[64], buf[512];
    snprintf(path, sizeof path, "/proc/%ld/stat", pid);
    FILE *f = fopen(path, "r");
    if (!f) continue;
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    fclose(f);
    buf[n] = '\0';
    char *rp = strrchr(buf, ')'); /* after "pid (comm)": " state ppid" */
    char state;
    long ppid;
    if (rp && sscanf(rp + 1, " %c %ld", &state, &ppid) == 2 && ppid == parent && state != 'Z')
      found = (pid_t)pid;
  }
  closedir(d);
  return found;
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

/* dir/name and ref/name hold the same bytes. */
static bool same_file(const char *dir, const char *ref, const char *name) {
  size_t la, lb;
  char *x = testing_slurp(dir, name, &la), *y = testing_slurp(ref, name, &lb);
  bool same = x && y && la == lb && !memcmp(x, y, la);
  free(x);
  free(y);
  return same;
}

/* dir holds one whole run, ref's: image.exr, stats.csv and timeline.csv equal
 * to ref's (bit-identical run to run), and stats.json's seed (the rest of it
 * holds the wall time). */
static bool same_run(const char *dir, const char *ref) {
  if (testing_json_num(dir, "seed") != testing_json_num(ref, "seed")) return false;
  if (!same_file(dir, ref, "stats.csv") || !same_file(dir, ref, "timeline.csv")) return false;
  char a[4096], b[4096];
  snprintf(a, sizeof a, "%s/image.exr", dir);
  snprintf(b, sizeof b, "%s/image.exr", ref);
  return testing_same_rgb(a, b);
}

#define RUN_ARGS "--width", "40", "--height", "30"

/* A complete directory (seed 1) rerun with seed 2 and interrupted (SIGINT)
 * at three moments: never (the new run swaps in), while it simulates, and
 * once its outputs are being written. Each time DIR is the old run or the
 * new one, whole; the file the run does not write (a sweep's command.sh)
 * stays; no sibling or temporary is left. */
static void test_run_rerun(void) {
  const char *ref1 = RTSIM_TMP "/sig_ref1", *ref2 = RTSIM_TMP "/sig_ref2";
  const char *dir = RTSIM_TMP "/sig_run";
  run("rm -rf %s %s %s", ref1, ref2, dir);
  for (int s = 1; s <= 2; s++) {
    int rc = run("%s run %s %s -o %s --width 40 --height 30 --seed %d", RTSIM_BINARY, TINY,
                 ROOM_TINY, s == 1 ? ref1 : ref2, s);
    EXPECTF(rc == 0, "reference run %d: %d %s", s, rc, out);
  }
  int old_seen = 0, new_seen = 0;
  for (int moment = 0; moment < 3; moment++) {
    run("rm -rf %s && cp -a %s %s && echo keep > %s/command.sh", dir, ref1, dir, dir);
    const char *argv[] = {RTSIM_BINARY, "run",    TINY,     ROOM_TINY, "-o",
                          dir,          RUN_ARGS, "--seed", "2",       NULL};
    pid_t pid = start(argv);
    char sibling[4096], sib_image[4200];
    snprintf(sibling, sizeof sibling, "%s/.sig_run.run-%ld", RTSIM_TMP, (long)pid);
    snprintf(sib_image, sizeof sib_image, "%s/image.exr", sibling);
    int status = 0;
    bool ended = false;
    if (moment > 0) {
      const char *await = moment == 1 ? sibling : sib_image;
      const double end = now() + 60;
      while (!exists(await) && now() < end && !(ended = waitpid(pid, &status, WNOHANG) == pid))
        nap();
      if (!ended) kill(pid, SIGINT);
    }
    if (!ended) ended = wait_for(pid, 60, &status);
    EXPECTF(ended, "moment %d: the run did not end", moment);
    if (!ended) {
      kill(pid, SIGKILL);
      waitpid(pid, NULL, 0);
      continue;
    }
    EXPECTF((WIFEXITED(status) && WEXITSTATUS(status) == 0) ||
                (WIFSIGNALED(status) && WTERMSIG(status) == SIGINT),
            "moment %d: status %#x", moment, status);
    const bool is_old = same_run(dir, ref1), is_new = same_run(dir, ref2);
    EXPECTF(is_old || is_new, "moment %d: the directory is neither the old run nor the new one",
            moment);
    old_seen += is_old;
    new_seen += is_new;
    if (moment == 0) EXPECTF(is_new, "an uninterrupted rerun did not swap in");
    char *k = testing_slurp(dir, "command.sh", NULL);
    EXPECTF(k && !strcmp(k, "keep\n"), "moment %d: command.sh lost", moment);
    free(k);
    EXPECTF(!exists(sibling), "moment %d: the fresh sibling is left", moment);
    EXPECTF(count_named(RTSIM_TMP, ".sig_run.", "") == 0, "moment %d: a sibling is left", moment);
    EXPECTF(count_named(dir, ".", ".tmp") == 0, "moment %d: temporaries left", moment);
  }
  fprintf(stderr, "test_signals: rerun interrupted: %d old, %d new\n", old_seen, new_seen);

  /* A new DIR, and an incomplete one (an earlier run's image.exr without
   * stats.json): SIGTERM once the sibling holds the new image leaves DIR as
   * it was and no sibling. */
  for (int incomplete = 0; incomplete < 2; incomplete++) {
    run("rm -rf %s", dir);
    if (incomplete) run("mkdir %s && echo old > %s/image.exr", dir, dir);
    const char *argv[] = {RTSIM_BINARY, "run", TINY, ROOM_TINY, "-o", dir, RUN_ARGS, NULL};
    pid_t pid = start(argv);
    char image[4200];
    snprintf(image, sizeof image, "%s/.sig_run.run-%ld/image.exr", RTSIM_TMP, (long)pid);
    int status = 0;
    bool ended = false;
    const double end = now() + 60;
    while (!exists(image) && now() < end && !(ended = waitpid(pid, &status, WNOHANG) == pid)) nap();
    if (!ended) kill(pid, SIGTERM);
    EXPECT(ended || wait_for(pid, 60, &status));
    EXPECTF(WIFSIGNALED(status) ? WTERMSIG(status) == SIGTERM : WEXITSTATUS(status) == 0,
            "status %#x", status);
    EXPECTF(count_named(RTSIM_TMP, ".sig_run.", "") == 0, "a sibling is left");
    if (!WIFSIGNALED(status)) continue;
    char *old = testing_slurp(dir, "image.exr", NULL);
    EXPECTF(incomplete ? old && !strcmp(old, "old\n") : !exists(dir),
            "incomplete %d: the directory changed", incomplete);
    free(old);
    EXPECT(!exists(RTSIM_TMP "/sig_run/stats.json"));
  }
}

/* rtsim render stopped (SIGTERM) while gnuplot draws its preview: gnuplot is
 * stopped first, then neither the image nor the preview nor a temporary of
 * either is left. The preview's temporary appears just before gnuplot starts;
 * a run that ends first is tried again (three times at most). */
static void test_render(void) {
  const char *exr = RTSIM_TMP "/sig_render.exr", *png = RTSIM_TMP "/sig_render.png";
  int stopped = 0;
  for (int attempt = 0; attempt < 3 && !stopped; attempt++) {
    run("rm -f %s %s", exr, png);
    const char *argv[] = {RTSIM_BINARY, "render",  ROOM_TINY, "-o",       exr,  "--preview",
                          png,          "--width", "64",      "--height", "48", NULL};
    pid_t pid = start(argv);
    int status = 0;
    bool ended = false;
    const double end = now() + 60;
    while (count_named(RTSIM_TMP, ".sig_render.png.", ".tmp") == 0 && now() < end &&
           !(ended = waitpid(pid, &status, WNOHANG) == pid))
      nap();
    if (!ended) kill(pid, SIGTERM);
    EXPECT(ended || wait_for(pid, 60, &status));
    stopped += WIFSIGNALED(status);
    EXPECTF(WIFSIGNALED(status) ? WTERMSIG(status) == SIGTERM : WEXITSTATUS(status) == 0,
            "render: status %#x", status);
    if (!WIFSIGNALED(status)) continue;
    /* rtsim reaped gnuplot before it ended: nothing can appear after. */
    EXPECT(!exists(exr) && !exists(png));
    EXPECTF(count_named(RTSIM_TMP, ".sig_render.", ".tmp") == 0, "render: temporaries left");
  }
  fprintf(stderr, "test_signals: render stopped while drawing %d time(s)\n", stopped);
}

/* A sweep of a short point (width 8) and a long one (width 96 of the small
 * room: tens of seconds), two at a time. */
static void write_sweep(const char *path) {
  FILE *f = fopen(path, "w");
  EXPECT(f != NULL);
  if (!f) return;
  fprintf(f,
          "machine: %s\nworkload:\n  scene: %s/scenes/small/room.yaml\n  height: 72\n"
          "axes:\n  width: [8, 96]\n",
          TINY, RTSIM_SOURCE_DIR);
  fclose(f);
}

/* SIGTERM to a sweep once its short point is complete and the long one runs:
 * the long point is stopped (gone: reaped by the sweep, not orphaned), the
 * sweep exits 128 + 15, the complete point has no error.txt and no
 * temporary, the stopped one no temporary either. */
static void test_sweep_sigterm(void) {
  const char *file = RTSIM_TMP "/sig_sweep.yaml", *dir = RTSIM_TMP "/sig_sweep";
  write_sweep(file);
  run("rm -rf %s && mkdir -p %s/width=8", dir, dir);
  /* An earlier failed attempt's error.txt: the point's success removes it. */
  run("echo 'an earlier failure' > %s/width=8/error.txt", dir);
  const char *argv[] = {RTSIM_BINARY, "sweep", file, "-o", dir, "-j", "2", NULL};
  pid_t pid = start(argv);
  const char *done = RTSIM_TMP "/sig_sweep/width=8/stats.json";
  const double end = now() + 120;
  while (!exists(done) && now() < end) nap();
  EXPECTF(exists(done), "the short point did not complete");
  pid_t child = child_of(pid); /* the long point */
  EXPECTF(child > 0, "no point running");
  kill(pid, SIGTERM);
  int status = 0;
  bool ended = wait_for(pid, 60, &status);
  EXPECTF(ended && WIFEXITED(status) && WEXITSTATUS(status) == 128 + SIGTERM,
          "the sweep: ended %d, status %#x", ended, status);
  if (!ended) {
    kill(pid, SIGKILL);
    waitpid(pid, NULL, 0);
  }
  /* Reaped by its sweep: neither running nor handed to this subreaper. */
  EXPECTF(child <= 0 || (kill(child, 0) != 0 && errno == ESRCH), "the point %ld still runs",
          (long)child);
  EXPECTF(!exists(RTSIM_TMP "/sig_sweep/width=8/error.txt"), "error.txt in a complete point");
  EXPECTF(count_named(RTSIM_TMP "/sig_sweep/width=8", ".", ".tmp") == 0,
          "temporaries in the complete point");
  EXPECTF(count_named(RTSIM_TMP "/sig_sweep/width=96", ".", ".tmp") == 0,
          "temporaries in the stopped point");
  EXPECTF(!exists(RTSIM_TMP "/sig_sweep/width=96/stats.json"), "the stopped point looks complete");

  /* A temporary of a sweep killed outright, in a complete point (the point
   * finished just before): the next sweep over DIR removes it. */
  char stale[4200];
  snprintf(stale, sizeof stale, "%s/width=8/.error.txt.%ld.0.tmp", dir, (long)pid);
  run("touch '%s'", stale);
  int rc = run("%s sweep %s -o %s --emit-jobs", RTSIM_BINARY, file, dir);
  EXPECTF(rc == 0 && !exists(stale), "a stale temporary in a complete point: %d %s", rc, out);
}

/* SIGKILL to a sweep while its point runs: the point notices its parent's
 * death (it gets SIGTERM) and ends within seconds, though it had tens of
 * seconds left; it leaves no temporary of its own. */
static void test_sweep_sigkill(void) {
  const char *file = RTSIM_TMP "/sig_kill.yaml", *dir = RTSIM_TMP "/sig_kill";
  write_sweep(file);
  run("rm -rf %s", dir);
  const char *argv[] = {RTSIM_BINARY, "sweep", file, "-o", dir, "-j", "1", NULL};
  pid_t pid = start(argv);
  /* The long point is expected to take longest: it runs first. Wait until
   * it has started writing (its directory exists) and runs rtsim run. */
  char point[4200], proc[64];
  snprintf(point, sizeof point, "%s/width=96/command.sh", dir);
  pid_t child = 0;
  const double end = now() + 60;
  while (now() < end) {
    child = exists(point) ? child_of(pid) : 0;
    snprintf(proc, sizeof proc, "/proc/%ld", (long)child);
    size_t len = 0;
    char *cmd = child > 0 ? testing_slurp(proc, "cmdline", &len) : NULL;
    /* argv[1] is "run" once the child has exec'd rtsim run. */
    bool running = cmd && strlen(cmd) + 4 < len && !strcmp(cmd + strlen(cmd) + 1, "run");
    free(cmd);
    if (running) break;
    child = 0;
    nap();
  }
  EXPECTF(child > 0, "the point never started");
  kill(pid, SIGKILL);
  waitpid(pid, NULL, 0);
  if (child <= 0) return;
  int status = 0;
  bool ended = wait_for(child, 10, &status);
  EXPECTF(ended, "the point still runs 10 s after its sweep was killed");
  if (!ended) {
    kill(child, SIGKILL);
    waitpid(child, NULL, 0);
    return;
  }
  EXPECTF(WIFSIGNALED(status) && WTERMSIG(status) == SIGTERM, "the point ended with status %#x",
          status);
  EXPECTF(count_named(RTSIM_TMP "/sig_kill/width=96", ".", ".tmp") <= 1 &&
              count_named(RTSIM_TMP "/sig_kill/width=96", ".error.txt.", ".tmp") ==
                  count_named(RTSIM_TMP "/sig_kill/width=96", ".", ".tmp"),
          "the point left temporaries of its own");
  EXPECT(!exists(RTSIM_TMP "/sig_kill/width=96/stats.json"));
}

int main(void) {
  /* Orphans of the sweeps killed here become this program's children. */
  EXPECT(prctl(PR_SET_CHILD_SUBREAPER, 1) == 0);
  test_run_rerun();
  test_render();
  test_sweep_sigterm();
  test_sweep_sigkill();
  /* Reap anything left (nothing is expected). */
  while (waitpid(-1, NULL, WNOHANG) > 0) {
  }
  return testing_done("test_signals");
}
