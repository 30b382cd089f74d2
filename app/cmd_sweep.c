/* rtsim sweep: run a sweep file's points as `rtsim run` processes of this same
 * program, N at a time, longest expected first; or print them as job lines
 * for GNU parallel, or as a Slurm array script; or say what state each point
 * is in. A point is complete when its stats.json exists (rtsim run writes it
 * last), so a rerun skips complete points and retries the rest. A job line
 * names its points (rtsim sweep ... --point NAME), never a position in a
 * list, and runs them through this same runner, so it stays valid however
 * often the jobs are emitted again and writes a failed point's error.txt
 * whoever runs it. Everything about a point lives in DIR/<point>/:
 * command.sh (its exact command), point.csv (its swept values, for merge),
 * error.txt (its stderr, when it failed), .running (locked while a runner
 * runs it), and rtsim run's outputs. */
#define _XOPEN_SOURCE 700 /* realpath */

#include "app/app.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "app/csv.h"
#include "app/opts.h"
#include "app/sweep.h"
#include "sim/err.h"
#include "sim/outfile.h"
#include "sim/stats.h"

static const char HELP[] =
    "usage: rtsim sweep SWEEP.yaml -o DIR [-j N] [--max-points N] [--point NAME]...\n"
    "       rtsim sweep SWEEP.yaml -o DIR (--emit-jobs | --emit-slurm N | --status)\n"
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
    "  --point NAME      run only the point NAME (repeatable; a NAME that is not a\n"
    "                    point of the sweep is refused, exit 2): what job lines do\n"
    "  --emit-jobs       run nothing: print one shell command per incomplete point\n"
    "                    on stdout (absolute paths, one line each, naming its\n"
    "                    point), for 'rtsim sweep S -o D --emit-jobs | parallel';\n"
    "                    DIR and the points' command.sh are written first\n"
    "  --emit-slurm N    run nothing: print a Slurm job array script on stdout, a\n"
    "                    task per N incomplete points, with --time and --mem from\n"
    "                    the sweep's estimates (submit it with sbatch)\n"
    "  --status          run and write nothing: count and list the points complete,\n"
    "                    failed (with the first error line), running, and not run;\n"
    "                    exit 0 when every point is complete, else 1\n"
    "  -h, --help        this text\n"
    "\n"
    "Then 'rtsim merge DIR -o TABLE.csv' joins the complete points into one table.\n";

/* What a point needs besides the sweep: its command and completion state. */
struct job {
  const struct sweep_point *p;
  char *dir;  /* DIR/<point> */
  char *line; /* the whole command, shell-quoted */
  bool complete;
  bool busy; /* claimed by another process when its turn came (claim()) */
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
static char *command_line(const char *bin, const struct sweep_point *p) {
  char *buf = NULL;
  size_t len = 0;
  FILE *f = open_memstream(&buf, &len);
  CHECK(f);
  shell_word(f, bin);
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

/* Split a command line as shell_word wrote it into its words, in place
 * (plain characters, '...' quoted runs, \' for a quote); at most cap words.
 * Returns the count, or cap + 1 when there are more. */
static unsigned split_words(char *s, char **w, unsigned cap) {
  unsigned n = 0;
  char *to = s;
  while (*s) {
    while (*s == ' ') s++;
    if (!*s) break;
    if (n == cap) return cap + 1;
    w[n++] = to;
    for (; *s && *s != ' '; s++) {
      if (*s == '\'') {
        for (s++; *s && *s != '\''; s++) *to++ = *s;
        if (!*s) break;
      } else if (*s == '\\' && s[1]) {
        *to++ = *++s;
      } else {
        *to++ = *s;
      }
    }
    char *end = to;
    if (*s) s++;
    to++;
    *end = '\0';
  }
  return n;
}

static const char *base_name(const char *p) {
  const char *b = strrchr(p, '/');
  return b ? b + 1 : p;
}

/* Where the sweep directory was (old) and is (dir): the parts before their
 * longest common tail of whole path components, so that a tree moved as one
 * (/home/a/proj/build/sw to /scratch/proj/build/sw) maps old paths inside it
 * to new ones (/home/a to /scratch). */
struct moved {
  char from[4096], to[4096];
};

static void moved_init(struct moved *m, const char *old, const char *dir) {
  const size_t lo = strlen(old), ld = strlen(dir);
  size_t t = 0; /* the common tail's length */
  while (t < lo && t < ld && old[lo - 1 - t] == dir[ld - 1 - t]) t++;
  while (t > 0 && old[lo - t] != '/') t--; /* whole components only */
  snprintf(m->from, sizeof m->from, "%.*s", (int)(lo - t), old);
  snprintf(m->to, sizeof m->to, "%.*s", (int)(ld - t), dir);
}

/* Whether path words a (the old command's) and b (ours) name one file: the
 * same text; or both resolve to one file; or a, no longer there, lies in the
 * tree moved to b's place (m). */
static bool same_path(const char *a, const char *b, const struct moved *m) {
  if (!strcmp(a, b)) return true;
  if (a[0] != '/' || b[0] != '/') return false;
  char *ra = realpath(a, NULL), *rb = realpath(b, NULL);
  bool same = ra && rb && !strcmp(ra, rb);
  bool gone = !ra;
  free(ra);
  free(rb);
  if (same || !gone) return same;
  size_t f = strlen(m->from);
  return !strncmp(a, m->from, f) && a[f] == '/' && !strncmp(b, m->to, strlen(m->to)) &&
         !strcmp(a + f, b + strlen(m->to));
}

/* A complete point made by another command (the sweep file changed under
 * the same DIR) must not pass for this sweep's: compare the arguments of its
 * command.sh with ours, word by word. The program's path may differ, and so
 * may paths that name the same files: the point's own directory (-o: where
 * its command.sh was found, so only its name must match), configs and scenes
 * by their resolved paths, or moved with DIR (a sweep directory moved or
 * copied elsewhere resumes). */
static bool same_command(const struct job *j, const char *dir) {
  char path[8192], line[65536];
  snprintf(path, sizeof path, "%s/command.sh", j->dir);
  const char *why;
  FILE *f = err_fopen_regular(path, &why);
  if (!f) return true; /* made by hand with rtsim run: nothing to compare */
  bool same = false;
  enum { MAX_WORDS = 1024 };
  char **w = xcalloc(MAX_WORDS, sizeof *w);
  while (fgets(line, sizeof line, f)) {
    if (strncmp(line, "exec ", 5)) continue;
    line[strcspn(line, "\n")] = '\0';
    unsigned n = split_words(line + 5, w, MAX_WORDS), a = 0;
    while (j->p->args[a]) a++;
    same = n == a + 1;
    /* The old sweep directory, from the old -o (DIR/<point>). */
    struct moved m = {{0}, {0}};
    for (unsigned i = 1; same && i + 1 < n; i++)
      if (!strcmp(w[i], "-o")) {
        char old[4096];
        snprintf(old, sizeof old, "%s", w[i + 1]);
        char *slash = strrchr(old, '/');
        if (slash) *slash = '\0';
        moved_init(&m, old, dir);
      }
    for (unsigned i = 0; same && i < a; i++) {
      const char *o = w[i + 1], *ours = j->p->args[i];
      if (i > 0 && !strcmp(j->p->args[i - 1], "-o")) same = !strcmp(base_name(o), base_name(ours));
      else same = same_path(o, ours, &m);
    }
  }
  free(w);
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

/* Claim point j for this process: a write lock (fcntl) on DIR/<point>/.running,
 * held while the point runs and dropped with the process however it ends. Two
 * runners (a job array emitted and submitted twice, a local sweep beside it)
 * so never run one point at once, and --status can tell a running point. The
 * file says who holds it: host, pid, start time (Unix seconds). Returns the
 * lock's descriptor; -1 with *busy when another process holds it; -1 without
 * when the file system cannot lock (NOTE: then the point runs unguarded). */
static int claim(const struct job *j, bool *busy) {
  char path[8192];
  snprintf(path, sizeof path, "%s/.running", j->dir);
  *busy = false;
  for (int tries = 0; tries < 8; tries++) {
    int fd = open(path, O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0) return -1;
    struct flock l = {.l_type = F_WRLCK, .l_whence = SEEK_SET};
    if (fcntl(fd, F_SETLK, &l) != 0) {
      *busy = errno == EACCES || errno == EAGAIN;
      close(fd);
      return -1;
    }
    /* The holder before us may have removed the file after we opened it:
     * then our lock is on a name no one sees; take the new file. */
    struct stat a, b;
    if (fstat(fd, &a) == 0 && stat(path, &b) == 0 && a.st_ino == b.st_ino && a.st_dev == b.st_dev) {
      char host[256] = "?", text[512];
      gethostname(host, sizeof host - 1);
      int n =
          snprintf(text, sizeof text, "%s %ld %lld\n", host, (long)getpid(), (long long)time(NULL));
      if (ftruncate(fd, 0) != 0 || write(fd, text, (size_t)n) != n) {
        /* the lock holds all the same; --status then shows no holder */
      }
      return fd;
    }
    close(fd);
  }
  return -1;
}

/* Drop a claim: the file goes first, so no one takes the lock of a point
 * whose run is over and finds nothing to do in an empty name. */
static void release(const struct job *j, int fd) {
  if (fd < 0) return;
  char path[8192];
  snprintf(path, sizeof path, "%s/.running", j->dir);
  unlink(path);
  close(fd);
}

/* Whether a process holds point dir's claim; its holder's line in who. */
static bool claimed(const char *dir, char *who, size_t cap) {
  char path[8192];
  snprintf(path, sizeof path, "%s/.running", dir);
  int fd = open(path, O_RDONLY | O_CLOEXEC);
  if (fd < 0) return false;
  struct flock l = {.l_type = F_WRLCK, .l_whence = SEEK_SET};
  bool held = fcntl(fd, F_GETLK, &l) == 0 && l.l_type != F_UNLCK;
  who[0] = '\0';
  ssize_t n = read(fd, who, cap - 1);
  who[n > 0 ? n : 0] = '\0';
  who[strcspn(who, "\n")] = '\0';
  close(fd);
  return held;
}

struct running {
  pid_t pid;
  struct job *j;
  struct outfile err; /* its stderr, to become DIR/<point>/error.txt if it fails */
  int lock;           /* its claim (claim()) */
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
  unsigned total, done, failed, running, busy;
  double cost_total, cost_done, t0;
};

static void progress(const struct tally *t) {
  char eta[32] = "?";
  double el = app_now() - t->t0;
  if (t->cost_done > 0)
    format_duration(el * (t->cost_total - t->cost_done) / t->cost_done, eta, sizeof eta);
  fprintf(stderr, "\r\033[Ksweep: %u/%u done, %u failed, %u running, ETA %s", t->done, t->total,
          t->failed, t->running, eta);
  fflush(stderr);
}

/* Run the jobs N at a time; returns the number that failed, or -1 when
 * interrupted by a signal (*sig set). A point another process is running is
 * left to it (its job marked busy, counted in *busy); one found complete
 * once claimed (run elsewhere meanwhile) counts as done. */
static int run_jobs(const char *bin, struct job **todo, unsigned n, unsigned jobs,
                    const struct sweep *s, int *sig, unsigned *busy) {
  const bool tty = isatty(2);
  struct running *run = xcalloc(jobs, sizeof *run);
  struct tally t = {n, 0, 0, 0, 0, 0, 0, app_now()};
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
      bool taken = false;
      int lock = make_dirs(j->dir, &e) ? claim(j, &taken) : -1;
      if (taken) {
        j->busy = true;
        t.busy++;
        continue;
      }
      if (exists(j->dir, "stats.json")) {
        release(j, lock);
        j->complete = true;
        t.done++;
        continue;
      }
      if (!prepare(s, j, &e) || !outfile_open_named(&err, err_path, "the file", &e)) {
        if (tty) fputs("\r\033[K", stderr);
        app_report(&e);
        release(j, lock);
        t.failed++;
        continue;
      }
      pid_t pid = launch(bin, j, err.tmp, &old);
      if (pid < 0) {
        fprintf(stderr, "rtsim sweep: cannot start a process: %s\n", strerror(errno));
        outfile_abort(&err);
        release(j, lock);
        t.failed++;
        continue;
      }
      for (unsigned k = 0; k < jobs; k++)
        if (!run[k].pid) {
          run[k] = (struct running){pid, j, err, lock};
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
        const bool ok = settle(j, status, &run[k].err);
        release(j, run[k].lock);
        if (ok) {
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
      if (exists(run[k].j->dir, "stats.json")) settle(run[k].j, status, &run[k].err);
      else outfile_abort(&run[k].err);
      release(run[k].j, run[k].lock);
    }
  }
  if (tty) fputs("\r\033[K", stderr);
  sigprocmask(SIG_SETMASK, &old, NULL);
  sigaction(SIGCHLD, &old_sa, NULL);
  free(run);
  *busy = t.busy;
  return *sig ? -1 : (int)t.failed;
}

/* The longest expected point first; equal estimates keep the sweep's order. */
static int by_cost(const void *a, const void *b) {
  const struct job *x = *(struct job *const *)a, *y = *(struct job *const *)b;
  if (x->p->cost != y->p->cost) return x->p->cost < y->p->cost ? 1 : -1;
  return (x->p->index > y->p->index) - (x->p->index < y->p->index);
}

/* The --point names (argv's strings). */
struct names {
  const char **v;
  unsigned n;
};

static bool add_name(const char *text, void *dst) {
  struct names *n = dst;
  if (!*text || strpbrk(text, "/\n\r")) return false;
  n->v = xrealloc(n->v, (n->n + 1ull) * sizeof *n->v);
  n->v[n->n++] = text;
  return true;
}

/* What every job line repeats: this program, the sweep, DIR. */
struct line_base {
  const char *bin, *sweep; /* absolute */
  const char *dir;
  uint64_t max_points;
};

/* A job line: the sweep's runner on points js[0..n), one at a time (-j 1: a
 * cluster job has one core unless it asks for more). It names its points, so
 * it means the same whatever list it sits in; a name the sweep no longer has
 * is refused when it runs. */
static void job_line(FILE *f, const struct line_base *b, struct job *const *js, unsigned n) {
  shell_word(f, b->bin);
  fputs(" sweep ", f);
  shell_word(f, b->sweep);
  fputs(" -o ", f);
  shell_word(f, b->dir);
  fputs(" -j 1", f);
  if (b->max_points != SWEEP_POINTS_DEFAULT)
    fprintf(f, " --max-points %llu", (unsigned long long)b->max_points);
  for (unsigned i = 0; i < n; i++) {
    fputs(" --point ", f);
    shell_word(f, js[i]->p->name);
  }
}

/* What the complete points say about host time and memory: the most seconds
 * of simulation per unit of the sweep's cost estimate, and the largest peak
 * memory (MiB); 0 when no complete point says. */
static void calibrate(struct job *all, unsigned n, double *rate, double *peak_mb) {
  *rate = *peak_mb = 0;
  for (unsigned i = 0; i < n; i++) {
    if (!all[i].complete || all[i].p->cost <= 0) continue;
    char path[8192], v[64];
    snprintf(path, sizeof path, "%s/stats.json", all[i].dir);
    const char *why;
    FILE *f = err_fopen_regular(path, &why);
    if (!f) continue;
    char text[1 << 16];
    /* The members read sit at the end of stats.json: read its tail. */
    if (fseek(f, -(long)(sizeof text - 1), SEEK_END) != 0) rewind(f);
    size_t got = fread(text, 1, sizeof text - 1, f);
    fclose(f);
    text[got] = '\0';
    double x;
    if (csv_json_member(text, "wall_s", v, sizeof v) && csv_number(v, &x) &&
        x / all[i].p->cost > *rate)
      *rate = x / all[i].p->cost;
    if (csv_json_member(text, "peak_rss_mb", v, sizeof v) && csv_number(v, &x) && x > *peak_mb)
      *peak_mb = x;
  }
}

/* Seconds of simulation per unit of the cost estimate when no point has run
 * yet: 3x the most measured on the project's machine, 5.3 us (the example
 * sweep, every ray type, on 2 shared cores; a 256x256 primary-ray image of
 * the small room took 1.3 us). Too high a rate only asks for more time. */
#define SWEEP_DEFAULT_RATE 1.6e-5

/* --emit-slurm: a job array script, task k running the points of line k.
 * Points go to tasks in a snake (longest first: task 1, 2, ..., K, K, ...,
 * 1, ...) so the tasks' expected times come out alike; the time request is
 * twice the longest task's (at the complete points' measured rate when there
 * are some), the memory request the largest point's estimate or twice the
 * complete points' measured peak, whichever is larger. Slurm keeps its own copy of a script at
 * submission, so a script emitted later cannot change an array already queued. */
static void emit_slurm(const struct line_base *b, struct job **todo, unsigned n, unsigned per,
                       struct job *all, unsigned npoints, const char *sweep_file) {
  const unsigned tasks = (n + per - 1) / per;
  struct job **by_task = xcalloc(n ? n : 1, sizeof *by_task);
  unsigned *count = xcalloc(tasks ? tasks : 1, sizeof *count);
  double *secs = xcalloc(tasks ? tasks : 1, sizeof *secs);
  double rate, seen_mb, mem = 0;
  calibrate(all, npoints, &rate, &seen_mb);
  const bool measured = rate > 0;
  if (!measured) rate = SWEEP_DEFAULT_RATE;
  for (unsigned i = 0; i < n; i++) {
    const unsigned round = i / tasks, k = round % 2 ? tasks - 1 - i % tasks : i % tasks;
    by_task[k * per + count[k]++] = todo[i];
    secs[k] += todo[i]->p->setup_s + rate * todo[i]->p->cost;
    if (todo[i]->p->mem_mb > mem) mem = todo[i]->p->mem_mb;
  }
  double longest = 0;
  for (unsigned k = 0; k < tasks; k++)
    if (secs[k] > longest) longest = secs[k];
  if (2 * seen_mb + 16 > mem) mem = 2 * seen_mb + 16;
  unsigned minutes = (unsigned)ceil(2 * longest / 60);
  if (minutes < 5) minutes = 5;
  const unsigned mib = 16 * (unsigned)ceil(mem / 16);
  printf("#!/bin/sh\n"
         "# Written by rtsim sweep --emit-slurm %u: %u task%s of at most %u of the %u incomplete\n"
         "# points of the sweep %s (%u points) into %s.\n"
         "# Submit with: sbatch THIS_FILE. Slurm keeps its own copy at submission, so emitting\n"
         "# again later changes no task of an array already queued; a task names its points,\n"
         "# skips one complete (or running elsewhere) when it starts, keeps a failed one's\n"
         "# stderr in its error.txt, and exits 2 when its number is not in this file.\n"
         "# Requests: time twice the longest task's expected %.0f s; memory the largest\n"
         "# point's %s (README.md, Sweeps).\n",
         per, tasks, tasks == 1 ? "" : "s", per, n, sweep_file, npoints, b->dir, longest,
         measured ? "estimate, or twice the complete points' peak if larger"
                  : "estimate (no point is complete to measure from)");
  printf("#SBATCH --job-name=rtsim-sweep\n#SBATCH --array=1-%u\n#SBATCH --ntasks=1\n"
         "#SBATCH --cpus-per-task=1\n#SBATCH --time=%u\n#SBATCH --mem=%uM\n",
         tasks ? tasks : 1, minutes, mib);
  printf("case \"${SLURM_ARRAY_TASK_ID:-}\" in\n");
  for (unsigned k = 0; k < tasks; k++) {
    printf("%u) exec ", k + 1);
    job_line(stdout, b, &by_task[k * per], count[k]);
    printf(" ;;\n");
  }
  printf("*) echo \"rtsim sweep: no task '${SLURM_ARRAY_TASK_ID:-}' in $0 (it has tasks 1 to %u;"
         " run it as a Slurm array, sbatch $0)\" >&2; exit 2 ;;\nesac\n",
         tasks);
  if (tasks > 1000)
    fprintf(stderr,
            "rtsim sweep: warning: %u array tasks; clusters often cap arrays at 1000 "
            "(MaxArraySize): raise N\n",
            tasks);
  free(by_task);
  free(count);
  free(secs);
}

/* Whether point dir holds anything but what the sweep writes before a run. */
static bool has_outputs(const char *dir) {
  DIR *d = opendir(dir);
  if (!d) return false;
  bool any = false;
  struct dirent *de;
  while (!any && (de = readdir(d)))
    any = strcmp(de->d_name, ".") && strcmp(de->d_name, "..") && strcmp(de->d_name, "command.sh") &&
          strcmp(de->d_name, "point.csv") && strcmp(de->d_name, ".running") &&
          strcmp(de->d_name, "error.txt");
  closedir(d);
  return any;
}

/* --status: each point's state, failed ones first; nothing written. */
static int status(const struct sweep *s, struct job *all, const char *dir) {
  enum { FAILED, RUNNING, NOT_RUN, COMPLETE, NSTATES };
  static const char *const label[NSTATES] = {"failed", "running", "not run", "complete"};
  unsigned count[NSTATES] = {0};
  char **detail = xcalloc(s->npoints, sizeof *detail);
  unsigned char *state = xcalloc(s->npoints, 1);
  for (unsigned i = 0; i < s->npoints; i++) {
    struct job *j = &all[i];
    char text[1024] = "", who[512];
    if (j->complete) {
      state[i] = COMPLETE;
      if (!same_command(j, dir))
        snprintf(text, sizeof text, "made by another command (see its command.sh)");
    } else if (claimed(j->dir, who, sizeof who)) {
      state[i] = RUNNING;
      char host[256] = "?";
      long pid = 0;
      long long since = 0;
      if (sscanf(who, "%255s %ld %lld", host, &pid, &since) == 3) {
        char took[32];
        format_duration((double)(time(NULL) - since), took, sizeof took);
        snprintf(text, sizeof text, "on %s, pid %ld, for %s", host, pid, took);
      }
    } else if (exists(j->dir, "error.txt")) {
      state[i] = FAILED;
      first_error(j->dir, text, sizeof text);
    } else {
      state[i] = NOT_RUN;
      if (has_outputs(j->dir)) snprintf(text, sizeof text, "stopped part way (no stats.json)");
    }
    count[state[i]]++;
    detail[i] = text[0] ? strdup(text) : NULL;
  }
  printf("%s into %s: %u points: %u complete, %u failed, %u running, %u not run\n", s->file, dir,
         s->npoints, count[COMPLETE], count[FAILED], count[RUNNING], count[NOT_RUN]);
  for (unsigned st = 0; st < NSTATES; st++)
    for (unsigned i = 0; i < s->npoints; i++) {
      if (state[i] != st) continue;
      printf("%-9s %s%s%s\n", label[st], all[i].p->name, detail[i] ? ": " : "",
             detail[i] ? detail[i] : "");
      free(detail[i]);
    }
  free(detail);
  free(state);
  return count[COMPLETE] == s->npoints ? 0 : 1;
}

int cmd_sweep(int argc, char **argv) {
  const char *out = NULL;
  long cores = sysconf(_SC_NPROCESSORS_ONLN);
  uint64_t jobs = cores > 0 ? (uint64_t)cores : 1;
  bool emit = false, show = false, slurm = false;
  uint64_t max_points = SWEEP_POINTS_DEFAULT, per_task = 1;
  struct names names = {0};
  const struct opts_spec spec[] = {
      OPTS_STR("output", 'o', &out),
      OPTS_U64("jobs", 'j', &jobs, 1, 4096),
      OPTS_U64("max-points", 0, &max_points, 1, SWEEP_POINTS_MAX),
      OPTS_FLAG("emit-jobs", 0, &emit),
      {.name = "emit-slurm",
       .kind = OPTS_KIND_U64,
       .dst = &per_task,
       .lo = 1,
       .hi = 100000,
       .given = &slurm},
      OPTS_FLAG("status", 0, &show),
      OPTS_PARSE("point", 0, &names, add_name, "a point's name (a directory name, no '/')"),
      OPTS_END};
  struct opts_args args;
  int rc = opts_parse("sweep", HELP, spec, argc, argv, &args);
  if (rc != OPTS_GO) goto early;
  rc = APP_EXIT_USAGE;
  const char *sweep_path = opts_one(&args, "SWEEP.yaml", "sweep file");
  if (!sweep_path) goto early;
  if (!out) {
    rc = app_usage_error("sweep", "missing -o DIR");
    goto early;
  }
  if (strpbrk(out, "\n\r")) {
    rc = app_usage_error("sweep", "-o: a path with a line break cannot go into a job line");
    goto early;
  }
  if (emit + slurm + show + (names.n > 0) > 1) {
    rc = app_usage_error("sweep", "--emit-jobs, --emit-slurm, --status and --point go alone "
                                  "(got more than one)");
    goto early;
  }

  /* Absolute paths throughout, so commands run from any directory. */
  char dir[8192], bin[4096], cwd[4096];
  if (out[0] == '/') snprintf(dir, sizeof dir, "%s", out);
  else if (getcwd(cwd, sizeof cwd)) snprintf(dir, sizeof dir, "%s/%s", cwd, out);
  else {
    rc = app_usage_error("sweep", "cannot read the current directory: %s", strerror(errno));
    goto early;
  }
  for (size_t l = strlen(dir); l > 1 && dir[l - 1] == '/';) dir[--l] = '\0';
  ssize_t bl = readlink("/proc/self/exe", bin, sizeof bin - 1);
  if (bl <= 0) {
    fprintf(stderr, "rtsim sweep: error: cannot find this program's path (/proc/self/exe)\n");
    rc = 1;
    goto early;
  }
  bin[bl] = '\0';

  struct sweep s;
  struct err e = {0};
  if (!sweep_load_capped(&s, sweep_path, dir, (unsigned)max_points, &e)) {
    sweep_free(&s);
    rc = app_report(&e);
    goto early;
  }
  /* The sweep file made absolute, for job lines (it was just read). */
  char *sweep_abs = realpath(sweep_path, NULL);
  CHECK(sweep_abs);
  struct job *all = xcalloc(s.npoints, sizeof *all);
  struct job **todo = xcalloc(s.npoints, sizeof *todo);
  bool *chosen = xcalloc(s.npoints, sizeof *chosen);
  unsigned ntodo = 0, complete = 0, nchosen = 0;
  rc = 0;
  if (strpbrk(sweep_abs, "\n\r")) {
    rc = app_usage_error("sweep", "%s: a path with a line break cannot go into a job line",
                         sweep_path);
    goto done;
  }
  /* --point: only the named points, each of them a point of the sweep. */
  for (unsigned k = 0; k < names.n; k++) {
    unsigned i = 0;
    while (i < s.npoints && strcmp(s.points[i].name, names.v[k])) i++;
    if (i == s.npoints) {
      fprintf(stderr,
              "rtsim sweep: error: --point '%s': no such point in %s (the sweep file changed "
              "since the job was written? emit the jobs again)\n",
              names.v[k], sweep_path);
      rc = APP_EXIT_USAGE;
      goto done;
    }
    chosen[i] = true;
  }
  for (unsigned i = 0; i < s.npoints; i++) {
    struct job *j = &all[i];
    j->p = &s.points[i];
    size_t n = strlen(dir) + strlen(j->p->name) + 2;
    j->dir = xmalloc(n);
    snprintf(j->dir, n, "%s/%s", dir, j->p->name);
    j->line = command_line(bin, j->p);
    if (names.n && !chosen[i]) continue;
    nchosen++;
    j->complete = exists(j->dir, "stats.json");
    if (show) continue; /* --status writes nothing and refuses nothing */
    /* A sweep killed outright cannot remove its temporaries (a point's
     * stderr, kept as .error.txt.<pid>.<n>.tmp), even in a point that
     * completed just before. */
    if (j->complete) outfile_remove_stale(j->dir);
    if (j->complete && !same_command(j, dir)) {
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
  if (show) {
    rc = status(&s, all, dir);
    goto done;
  }
  qsort(todo, ntodo, sizeof *todo, by_cost);
  if (!make_dirs(dir, &e)) {
    rc = app_report(&e);
    goto done;
  }
  const struct line_base base = {bin, sweep_abs, dir, max_points};
  if (emit || slurm) {
    for (unsigned i = 0; i < ntodo; i++)
      if (!prepare(&s, todo[i], &e)) {
        rc = app_report(&e);
        goto done;
      }
    if (slurm) {
      emit_slurm(&base, todo, ntodo, (unsigned)per_task, all, s.npoints, sweep_abs);
      fprintf(stderr, "rtsim sweep: %u array tasks (%u incomplete points of %u, %u complete)\n",
              (ntodo + (unsigned)per_task - 1) / (unsigned)per_task, ntodo, s.npoints, complete);
      goto done;
    }
    for (unsigned i = 0; i < ntodo; i++) {
      job_line(stdout, &base, &todo[i], 1);
      putchar('\n');
    }
    fprintf(stderr, "rtsim sweep: %u job lines (%u points, %u complete)\n", ntodo, s.npoints,
            complete);
    goto done;
  }
  if (names.n)
    fprintf(stderr, "sweep: %u of %u points named, %u complete, running %u, %u at a time\n",
            nchosen, s.npoints, complete, ntodo, (unsigned)(jobs < ntodo ? jobs : ntodo));
  else
    fprintf(stderr, "sweep: %u points, %u complete, running %u, %u at a time\n", s.npoints,
            complete, ntodo, (unsigned)(jobs < ntodo ? jobs : ntodo));
  double t0 = app_now();
  int sig;
  unsigned busy = 0;
  int failed = run_jobs(bin, todo, ntodo, (unsigned)jobs, &s, &sig, &busy);
  char took[32];
  format_duration(app_now() - t0, took, sizeof took);
  if (failed < 0) {
    fprintf(stderr, "sweep: interrupted (%s) after %s; rerun the same command to resume\n",
            strsignal(sig), took);
    rc = 128 + sig;
    goto done;
  }
  fprintf(stderr, "sweep: %u run, %d failed, %u already complete, %s\n",
          ntodo - (unsigned)failed - busy, failed, complete, took);
  if (busy) {
    fprintf(stderr, "sweep: %u point%s left to the process%s running them (see --status):", busy,
            busy == 1 ? "" : "s", busy == 1 ? "" : "es");
    for (unsigned i = 0, shown = 0; i < ntodo && shown < 5; i++)
      if (todo[i]->busy) fprintf(stderr, " %s", todo[i]->p->name), shown++;
    fputs(busy > 5 ? " ...\n" : "\n", stderr);
  }
  if (failed) {
    fprintf(stderr, "sweep: %d point%s failed (each one's stderr is in its error.txt):\n", failed,
            failed == 1 ? "" : "s");
    for (unsigned i = 0; i < ntodo; i++) {
      if (todo[i]->complete || todo[i]->busy) continue;
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
  free(chosen);
  free(sweep_abs);
  sweep_free(&s);
early:
  free(names.v);
  return rc;
}
