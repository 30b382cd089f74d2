/* rtsim sweep: run a sweep file's points as `rtsim run` processes of this same
 * program, N at a time, longest expected first; or print them as job lines
 * for GNU parallel or a Slurm array. A point is complete when its stats.json
 * exists (rtsim run writes it last), so a rerun skips complete points and
 * retries the rest. Everything about a point lives in DIR/<point>/:
 * command.sh (its exact command), point.csv (its swept values, for merge),
 * error.txt (its stderr, when it failed), and rtsim run's outputs. */
#define _XOPEN_SOURCE 700 /* realpath */

#include "app/app.h"

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "app/opts.h"
#include "app/sweep.h"
#include "sim/err.h"
#include "sim/outfile.h"
#include "sim/stats.h"

static const char HELP[] =
    "usage: rtsim sweep SWEEP.yaml -o DIR [-j N] [--max-points N] [--emit-jobs]\n"
    "\n"
    "Run every point of a sweep file (a base machine config, a workload, and axes\n"
    "over config or workload keys: see README.md, Sweeps) as an 'rtsim run' into\n"
    "DIR/<point>, where <point> names the swept values (policy=packet,dram.latency=400).\n"
    "The whole file, every point's machine config and every scene are checked\n"
    "before anything runs. Points run N at a time, longest expected first; a\n"
    "point whose stats.json exists is complete and skipped, so rerunning the\n"
    "same command resumes an interrupted sweep and retries failed points. A\n"
    "failed point does not stop the others: its stderr is kept in\n"
    "DIR/<point>/error.txt and summarised at the end (exit code 1). Every point's\n"
    "exact command is in DIR/<point>/command.sh. A progress line (done, failed,\n"
    "ETA) goes to stderr when it is a terminal. SIGINT or SIGTERM stops the\n"
    "running points (they stay incomplete); a point also stops when its sweep\n"
    "is killed outright.\n"
    "\n"
    "options:\n"
    "  -o, --output DIR  where the points go (created if needed)\n"
    "  -j, --jobs N      points at a time (default: the number of cores)\n"
    "  --max-points N    refuse a sweep of more than N points (default 10000, at\n"
    "                    most 1000000), before anything is written\n"
    "  --emit-jobs       run nothing: print one shell command per incomplete point\n"
    "                    on stdout (absolute paths, one line each), for\n"
    "                    'rtsim sweep S -o D --emit-jobs | parallel' or a Slurm\n"
    "                    array; DIR and the points' command.sh are written first\n"
    "  -h, --help        this text\n"
    "\n"
    "Then 'rtsim merge DIR -o TABLE.csv' joins the complete points into one table.\n";

/* What a point needs besides the sweep: its command and completion state. */
struct job {
  const struct sweep_point *p;
  char *dir;  /* DIR/<point> */
  char *line; /* the whole command, shell-quoted */
  const char *args_text; /* inside line: the arguments after the program */
  bool complete;
};

/* Append s to f, quoted for a POSIX shell when it holds anything but plain
 * characters. */
static void shell_word(FILE *f, const char *s) {
  if (*s && strspn(s, "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_./=,+-:@%") ==
                strlen(s)) {
    fputs(s, f);
    return;
  }
  fputc('\'', f);
  for (; *s; s++) {
    if (*s == '\'') fputs("'\\''", f);
    else fputc(*s, f);
  }
  fputc('\'', f);
}

/* The point's command line: the program, then its arguments. */
static char *command_line(const char *bin, const struct sweep_point *p, size_t *args_at) {
  char *buf = NULL;
  size_t len = 0;
  FILE *f = open_memstream(&buf, &len);
  CHECK(f);
  shell_word(f, bin);
  fflush(f);
  *args_at = len + 1;
  for (char **a = p->args; *a; a++) {
    fputc(' ', f);
    shell_word(f, *a);
  }
  CHECK(fclose(f) == 0);
  return buf;
}

static bool exists(const char *dir, const char *name) {
  char path[8192];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  struct stat sb;
  return stat(path, &sb) == 0;
}

/* Write text to dir/name through a temporary name. */
static bool write_file(const char *dir, const char *name, const char *text, int mode,
                       struct err *e) {
  char path[8192];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  struct outfile o;
  if (!outfile_open(&o, path, "the file", e)) return false;
  fputs(text, o.f);
  if (fchmod(fileno(o.f), (mode_t)mode) != 0) {
    outfile_abort(&o);
    return err_set(e, path, 0, 0, "cannot write the file: %s", strerror(errno));
  }
  return outfile_commit(&o, e);
}

/* mkdir -p. */
static bool make_dirs(const char *path, struct err *e) {
  char p[8192];
  snprintf(p, sizeof p, "%s", path);
  for (char *s = p + 1;; s++) {
    if (*s && *s != '/') continue;
    char c = *s;
    *s = '\0';
    if (mkdir(p, 0777) != 0 && errno != EEXIST)
      return err_set(e, p, 0, 0, "cannot create the directory: %s", strerror(errno));
    if (!c) return true;
    *s = c;
  }
}

/* Make DIR/<point> with its command.sh and point.csv. */
static bool prepare(const struct sweep *s, const struct job *j, struct err *e) {
  if (!make_dirs(j->dir, e)) return false;
  outfile_remove_stale(j->dir); /* of an attempt that was killed */
  char *text = NULL;
  size_t len = 0;
  FILE *f = open_memstream(&text, &len);
  CHECK(f);
  fprintf(f, "#!/bin/sh\n# Point %s of the sweep %s (written by rtsim sweep).\n", j->p->name,
          s->file);
  fprintf(f, "# Rerun it by hand with: sh command.sh\nexec %s\n", j->line);
  CHECK(fclose(f) == 0);
  bool ok = write_file(j->dir, "command.sh", text, 0755, e);
  free(text);
  if (!ok || s->nkeys == 0) return ok;
  f = open_memstream(&text, &len);
  CHECK(f);
  for (unsigned k = 0; k < s->nkeys; k++) {
    if (k) fputc(',', f);
    stats_write_csv_str(f, s->keys[k]);
  }
  fputc('\n', f);
  for (unsigned k = 0; k < s->nkeys; k++) {
    if (k) fputc(',', f);
    stats_write_csv_str(f, j->p->values[k]);
  }
  fputc('\n', f);
  CHECK(fclose(f) == 0);
  ok = write_file(j->dir, "point.csv", text, 0644, e);
  free(text);
  return ok;
}

/* A complete point made by another command (the sweep file changed under
 * the same DIR) must not pass for this sweep's: compare the arguments of its
 * command.sh with ours (the program's path may differ). */
static bool same_command(const struct job *j) {
  char path[8192], line[65536];
  snprintf(path, sizeof path, "%s/command.sh", j->dir);
  const char *why;
  FILE *f = err_fopen_regular(path, &why);
  if (!f) return true; /* made by hand with rtsim run: nothing to compare */
  bool same = false;
  while (fgets(line, sizeof line, f))
    if (!strncmp(line, "exec ", 5)) {
      line[strcspn(line, "\n")] = '\0';
      size_t n = strlen(line), m = strlen(j->args_text);
      same = n > m && line[n - m - 1] == ' ' && !strcmp(line + n - m, j->args_text);
    }
  fclose(f);
  return same;
}

/* The first line of a failed point's stderr that says "error", else its first line. */
static void first_error(const char *dir, char *out, size_t cap) {
  char path[8192], line[1024];
  snprintf(path, sizeof path, "%s/error.txt", dir);
  snprintf(out, cap, "(no message)");
  const char *why;
  FILE *f = err_fopen_regular(path, &why);
  if (!f) return;
  bool have = false;
  while (fgets(line, sizeof line, f)) {
    line[strcspn(line, "\r\n")] = '\0';
    if (!line[0]) continue;
    if (strstr(line, "error")) {
      snprintf(out, cap, "%s", line);
      break;
    }
    if (!have) snprintf(out, cap, "%s", line);
    have = true;
  }
  fclose(f);
}

static void format_duration(double s, char *out, size_t cap) {
  if (s < 60) snprintf(out, cap, "%.0fs", s);
  else if (s < 3600) snprintf(out, cap, "%dm%02ds", (int)s / 60, (int)s % 60);
  else snprintf(out, cap, "%dh%02dm", (int)s / 3600, (int)s / 60 % 60);
}

struct running {
  pid_t pid;
  struct job *j;
  struct outfile err; /* its stderr, to become DIR/<point>/error.txt if it fails */
};

/* Start job j: stdout to /dev/null, stderr to err_path. */
static pid_t launch(const char *bin, struct job *j, const char *err_path, const sigset_t *mask) {
  const pid_t parent = getpid();
  pid_t pid = fork();
  if (pid != 0) return pid;
  /* The child. If the sweep dies, even by SIGKILL (no chance to stop its
   * points), the kernel sends the point SIGTERM, which rtsim run takes as an
   * interruption (app/outdir.h); the setting survives exec. A parent that
   * died before the setting took effect is caught by the pid check (the
   * orphan's parent is then another process). */
  if (prctl(PR_SET_PDEATHSIG, SIGTERM) != 0 || getppid() != parent) _exit(127);
  /* The parent's signal mask must not outlive exec. */
  signal(SIGCHLD, SIG_DFL);
  sigprocmask(SIG_SETMASK, mask, NULL);
  int fd = open(err_path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
  int null = open("/dev/null", O_WRONLY);
  if (fd >= 0) dup2(fd, 2);
  if (null >= 0) dup2(null, 1);
  unsigned n = 0;
  while (j->p->args[n]) n++;
  char **argv = calloc(n + 2, sizeof *argv);
  if (argv) {
    argv[0] = (char *)bin;
    memcpy(argv + 1, j->p->args, n * sizeof *argv);
    execv(bin, argv);
  }
  fprintf(stderr, "rtsim sweep: cannot run %s: %s\n", bin, strerror(errno));
  _exit(127);
}

/* A finished point: complete, or failed with its stderr (err) kept as
 * error.txt. Complete means its stats.json exists, however it ended: rtsim
 * run writes it last and whole, so a point stopped by a signal just after
 * is complete all the same (and must not keep an earlier error.txt). */
static bool settle(struct job *j, int status, struct outfile *err) {
  j->complete = exists(j->dir, "stats.json");
  if (j->complete) {
    unlink(err->path); /* an earlier attempt's */
    outfile_abort(err);
    return true;
  }
  FILE *f = fopen(err->tmp, "a");
  if (f) {
    if (WIFEXITED(status) && WEXITSTATUS(status) == 0)
      fprintf(f, "rtsim sweep: the point exited with code 0 but wrote no stats.json\n");
    else if (WIFEXITED(status))
      fprintf(f, "rtsim sweep: the point exited with code %d\n", WEXITSTATUS(status));
    else if (WIFSIGNALED(status))
      fprintf(f, "rtsim sweep: the point was killed by signal %d (%s)\n", WTERMSIG(status),
              strsignal(WTERMSIG(status)));
    fclose(f);
  }
  struct err e = {0};
  outfile_commit(err, &e); /* on failure first_error() says "(no message)" */
  return false;
}

static void no_op(int sig) { (void)sig; }

struct tally {
  unsigned total, done, failed, running;
  double cost_total, cost_done, t0;
};

static void progress(const struct tally *t) {
  char eta[32] = "?";
  double el = app_now() - t->t0;
  if (t->cost_done > 0) format_duration(el * (t->cost_total - t->cost_done) / t->cost_done, eta, sizeof eta);
  fprintf(stderr, "\r\033[Ksweep: %u/%u done, %u failed, %u running, ETA %s", t->done, t->total,
          t->failed, t->running, eta);
  fflush(stderr);
}

/* Run the jobs N at a time; returns the number that failed, or -1 when
 * interrupted by a signal (*sig set). */
static int run_jobs(const char *bin, struct job **todo, unsigned n, unsigned jobs,
                    const struct sweep *s, int *sig) {
  const bool tty = isatty(2);
  struct running *run = xcalloc(jobs, sizeof *run);
  struct tally t = {n, 0, 0, 0, 0, 0, app_now()};
  for (unsigned i = 0; i < n; i++) t.cost_total += todo[i]->p->cost;
  /* Signals are taken synchronously (sigtimedwait), so no handler touches
   * shared state; SIGCHLD needs a handler only so that it is not discarded. */
  sigset_t set, old;
  sigemptyset(&set);
  sigaddset(&set, SIGCHLD);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGHUP);
  struct sigaction sa, old_sa;
  memset(&sa, 0, sizeof sa);
  sa.sa_handler = no_op;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGCHLD, &sa, &old_sa);
  sigprocmask(SIG_BLOCK, &set, &old);
  unsigned next = 0;
  *sig = 0;
  while ((next < n || t.running > 0) && !*sig) {
    while (t.running < jobs && next < n) {
      struct err e = {0};
      struct job *j = todo[next++];
      char err_path[8192];
      snprintf(err_path, sizeof err_path, "%s/error.txt", j->dir);
      struct outfile err;
      if (!prepare(s, j, &e) || !outfile_open_named(&err, err_path, "the file", &e)) {
        if (tty) fputs("\r\033[K", stderr);
        app_report(&e);
        t.failed++;
        continue;
      }
      pid_t pid = launch(bin, j, err.tmp, &old);
      if (pid < 0) {
        fprintf(stderr, "rtsim sweep: cannot start a process: %s\n", strerror(errno));
        outfile_abort(&err);
        t.failed++;
        continue;
      }
      for (unsigned k = 0; k < jobs; k++)
        if (!run[k].pid) {
          run[k] = (struct running){pid, j, err};
          break;
        }
      t.running++;
    }
    if (tty) progress(&t);
    struct timespec tick = {1, 0};
    int got = sigtimedwait(&set, NULL, &tick);
    if (got == SIGINT || got == SIGTERM || got == SIGHUP) *sig = got;
    int status;
    pid_t pid;
    while ((pid = waitpid(-1, &status, WNOHANG)) > 0)
      for (unsigned k = 0; k < jobs; k++) {
        if (run[k].pid != pid) continue;
        struct job *j = run[k].j;
        run[k].pid = 0;
        t.running--;
        if (settle(j, status, &run[k].err)) {
          t.done++;
          t.cost_done += j->p->cost;
        } else {
          char msg[1024];
          first_error(j->dir, msg, sizeof msg);
          if (tty) fputs("\r\033[K", stderr);
          fprintf(stderr, "rtsim sweep: point %s failed: %s\n", j->p->name, msg);
          t.failed++;
        }
      }
  }
  if (*sig) {
    /* Stop the running points: they remove their temporaries and stay
     * incomplete, to be retried. One that ignores SIGTERM for 10 s gets
     * SIGKILL. A point whose stats.json was written meanwhile is complete
     * however it ended (see settle): an earlier attempt's error.txt goes. */
    for (unsigned k = 0; k < jobs; k++)
      if (run[k].pid) kill(run[k].pid, SIGTERM);
    const double deadline = app_now() + 10;
    for (unsigned k = 0; k < jobs; k++) {
      if (!run[k].pid) continue;
      int status;
      pid_t got;
      struct timespec nap = {0, 5000000};
      while ((got = waitpid(run[k].pid, &status, WNOHANG)) == 0 && app_now() < deadline)
        nanosleep(&nap, NULL);
      if (got == 0) {
        kill(run[k].pid, SIGKILL);
        got = waitpid(run[k].pid, &status, 0);
      }
      if (exists(run[k].j->dir, "stats.json"))
        settle(run[k].j, status, &run[k].err);
      else
        outfile_abort(&run[k].err);
    }
  }
  if (tty) fputs("\r\033[K", stderr);
  sigprocmask(SIG_SETMASK, &old, NULL);
  sigaction(SIGCHLD, &old_sa, NULL);
  free(run);
  return *sig ? -1 : (int)t.failed;
}

/* The longest expected point first; equal estimates keep the sweep's order. */
static int by_cost(const void *a, const void *b) {
  const struct job *x = *(struct job *const *)a, *y = *(struct job *const *)b;
  if (x->p->cost != y->p->cost) return x->p->cost < y->p->cost ? 1 : -1;
  return (x->p->index > y->p->index) - (x->p->index < y->p->index);
}

int cmd_sweep(int argc, char **argv) {
  const char *out = NULL;
  long cores = sysconf(_SC_NPROCESSORS_ONLN);
  uint64_t jobs = cores > 0 ? (uint64_t)cores : 1;
  bool emit = false;
  uint64_t max_points = SWEEP_POINTS_DEFAULT;
  const struct opts_spec spec[] = {OPTS_STR("output", 'o', &out),
                                   OPTS_U64("jobs", 'j', &jobs, 1, 4096),
                                   OPTS_U64("max-points", 0, &max_points, 1, SWEEP_POINTS_MAX),
                                   OPTS_FLAG("emit-jobs", 0, &emit), OPTS_END};
  struct opts_args args;
  int rc = opts_parse("sweep", HELP, spec, argc, argv, &args);
  if (rc != OPTS_GO) return rc;
  const char *sweep_path = opts_one(&args, "SWEEP.yaml", "sweep file");
  if (!sweep_path) return APP_EXIT_USAGE;
  if (!out) return app_usage_error("sweep", "missing -o DIR");
  if (strpbrk(out, "\n\r")) return app_usage_error("sweep", "-o: a path with a line break cannot go into a job line");

  /* Absolute paths throughout, so commands run from any directory. */
  char dir[8192], bin[4096], cwd[4096];
  if (out[0] == '/') snprintf(dir, sizeof dir, "%s", out);
  else if (getcwd(cwd, sizeof cwd)) snprintf(dir, sizeof dir, "%s/%s", cwd, out);
  else return app_usage_error("sweep", "cannot read the current directory: %s", strerror(errno));
  for (size_t l = strlen(dir); l > 1 && dir[l - 1] == '/';) dir[--l] = '\0';
  ssize_t bl = readlink("/proc/self/exe", bin, sizeof bin - 1);
  if (bl <= 0) {
    fprintf(stderr, "rtsim sweep: error: cannot find this program's path (/proc/self/exe)\n");
    return 1;
  }
  bin[bl] = '\0';

  struct sweep s;
  struct err e = {0};
  if (!sweep_load_capped(&s, sweep_path, dir, (unsigned)max_points, &e)) {
    sweep_free(&s);
    return app_report(&e);
  }
  struct job *all = xcalloc(s.npoints, sizeof *all);
  struct job **todo = xcalloc(s.npoints, sizeof *todo);
  unsigned ntodo = 0, complete = 0;
  rc = 0;
  for (unsigned i = 0; i < s.npoints; i++) {
    struct job *j = &all[i];
    j->p = &s.points[i];
    size_t n = strlen(dir) + strlen(j->p->name) + 2, at;
    j->dir = xmalloc(n);
    snprintf(j->dir, n, "%s/%s", dir, j->p->name);
    j->line = command_line(bin, j->p, &at);
    j->args_text = j->line + at;
    j->complete = exists(j->dir, "stats.json");
    /* A sweep killed outright cannot remove its temporaries (a point's
     * stderr, kept as .error.txt.<pid>.<n>.tmp), even in a point that
     * completed just before. */
    if (j->complete) outfile_remove_stale(j->dir);
    if (j->complete && !same_command(j)) {
      fprintf(stderr,
              "rtsim sweep: error: %s is complete but was made by another command (see its "
              "command.sh): the sweep changed since; use another -o DIR, or delete the point "
              "to run it again\n",
              j->dir);
      rc = APP_EXIT_USAGE;
      goto done;
    }
    if (j->complete) complete++;
    else todo[ntodo++] = j;
  }
  qsort(todo, ntodo, sizeof *todo, by_cost);
  if (!make_dirs(dir, &e)) {
    rc = app_report(&e);
    goto done;
  }
  if (emit) {
    for (unsigned i = 0; i < ntodo; i++) {
      if (!prepare(&s, todo[i], &e)) {
        rc = app_report(&e);
        goto done;
      }
      printf("%s\n", todo[i]->line);
    }
    fprintf(stderr, "rtsim sweep: %u job lines (%u points, %u complete)\n", ntodo, s.npoints,
            complete);
    goto done;
  }
  fprintf(stderr, "sweep: %u points, %u complete, running %u, %u at a time\n", s.npoints,
          complete, ntodo, (unsigned)(jobs < ntodo ? jobs : ntodo));
  double t0 = app_now();
  int sig;
  int failed = run_jobs(bin, todo, ntodo, (unsigned)jobs, &s, &sig);
  char took[32];
  format_duration(app_now() - t0, took, sizeof took);
  if (failed < 0) {
    fprintf(stderr, "sweep: interrupted (%s) after %s; rerun the same command to resume\n",
            strsignal(sig), took);
    rc = 128 + sig;
    goto done;
  }
  fprintf(stderr, "sweep: %u run, %d failed, %u already complete, %s\n", ntodo - (unsigned)failed,
          failed, complete, took);
  if (failed) {
    fprintf(stderr, "sweep: %d point%s failed (each one's stderr is in its error.txt):\n", failed,
            failed == 1 ? "" : "s");
    for (unsigned i = 0; i < ntodo; i++) {
      if (todo[i]->complete) continue;
      char msg[1024];
      first_error(todo[i]->dir, msg, sizeof msg);
      fprintf(stderr, "  %s: %s\n", todo[i]->p->name, msg);
    }
    rc = 1;
  }
done:
  for (unsigned i = 0; i < s.npoints; i++) {
    free(all[i].dir);
    free(all[i].line);
  }
  free(all);
  free(todo);
  sweep_free(&s);
  return rc;
}
