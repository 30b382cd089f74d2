/* The sweep's supervisor: runs points as `rtsim run` processes of this same
 * program, N at a time, on this machine. Each point is claimed first (its
 * .running lock), so two runners never run one point; its stderr is kept as
 * error.txt when it fails; a point stops with the sweep (PR_SET_PDEATHSIG)
 * and is stopped on SIGINT, SIGTERM or SIGHUP, staying incomplete. Signals
 * are taken synchronously, so no handler touches shared state. */
#include "app/sweep_run.h"

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "app/app.h"
#include "app/sweep.h"
#include "app/sweep_job.h"
#include "sim/err.h"
#include "sim/outfile.h"

struct running {
  pid_t pid;
  struct sweep_job *j;
  struct outfile err; /* its stderr, to become DIR/<point>/error.txt if it fails */
  int lock;           /* its claim (sweep_job_claim()) */
};

/* Start job j: stdout to /dev/null, stderr to err_path. */
static pid_t launch(const char *bin, struct sweep_job *j, const char *err_path,
                    const sigset_t *mask) {
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
static bool settle(struct sweep_job *j, int status, struct outfile *err) {
  j->complete = sweep_exists(j->dir, "stats.json");
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
  outfile_commit(err, &e); /* on failure sweep_first_error() says "(no message)" */
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
    sweep_format_duration(el * (t->cost_total - t->cost_done) / t->cost_done, eta, sizeof eta);
  fprintf(stderr, "\r\033[Ksweep: %u/%u done, %u failed, %u running, ETA %s", t->done, t->total,
          t->failed, t->running, eta);
  fflush(stderr);
}

/* The running sweep: its points in flight and its counts. */
struct supervisor {
  const char *bin;
  const struct sweep *s;
  struct running *run; /* jobs slots; pid 0 when free */
  unsigned jobs;
  struct tally t;
  bool tty;
  sigset_t old; /* the signal mask before the sweep, for its points */
};

/* Start job j in a free slot, or settle it at once: left to the process that
 * holds its claim (busy), complete already, or failed to start. */
static void start(struct supervisor *sv, struct sweep_job *j) {
  struct err e = {0};
  char err_path[8192];
  snprintf(err_path, sizeof err_path, "%s/error.txt", j->dir);
  struct outfile err;
  bool taken = false;
  int lock = sweep_make_dirs(j->dir, &e) ? sweep_job_claim(j, &taken) : -1;
  if (taken) {
    j->busy = true;
    sv->t.busy++;
    return;
  }
  if (sweep_exists(j->dir, "stats.json")) {
    sweep_job_release(j, lock);
    j->complete = true;
    sv->t.done++;
    return;
  }
  if (!sweep_job_prepare(sv->s, j, &e) || !outfile_open_named(&err, err_path, "the file", &e)) {
    if (sv->tty) fputs("\r\033[K", stderr);
    app_report(&e);
    sweep_job_release(j, lock);
    sv->t.failed++;
    return;
  }
  pid_t pid = launch(sv->bin, j, err.tmp, &sv->old);
  if (pid < 0) {
    fprintf(stderr, "rtsim sweep: cannot start a process: %s\n", strerror(errno));
    outfile_abort(&err);
    sweep_job_release(j, lock);
    sv->t.failed++;
    return;
  }
  for (unsigned k = 0; k < sv->jobs; k++)
    if (!sv->run[k].pid) {
      sv->run[k] = (struct running){pid, j, err, lock};
      break;
    }
  sv->t.running++;
}

/* Settle every point that has ended. */
static void reap(struct supervisor *sv) {
  int status;
  pid_t pid;
  while ((pid = waitpid(-1, &status, WNOHANG)) > 0)
    for (unsigned k = 0; k < sv->jobs; k++) {
      struct running *r = &sv->run[k];
      if (r->pid != pid) continue;
      struct sweep_job *j = r->j;
      r->pid = 0;
      sv->t.running--;
      const bool ok = settle(j, status, &r->err);
      sweep_job_release(j, r->lock);
      if (ok) {
        sv->t.done++;
        sv->t.cost_done += j->p->cost;
      } else {
        char msg[1024];
        sweep_first_error(j->dir, msg, sizeof msg);
        if (sv->tty) fputs("\r\033[K", stderr);
        fprintf(stderr, "rtsim sweep: point %s failed: %s\n", j->p->name, msg);
        sv->t.failed++;
      }
    }
}

/* Stop the running points: they remove their temporaries and stay
 * incomplete, to be retried. One that ignores SIGTERM for 10 s gets
 * SIGKILL. A point whose stats.json was written meanwhile is complete
 * however it ended (see settle): an earlier attempt's error.txt goes. */
static void stop_all(struct supervisor *sv) {
  struct running *run = sv->run;
  for (unsigned k = 0; k < sv->jobs; k++)
    if (run[k].pid) kill(run[k].pid, SIGTERM);
  const double deadline = app_now() + 10;
  for (unsigned k = 0; k < sv->jobs; k++) {
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
    if (sweep_exists(run[k].j->dir, "stats.json")) settle(run[k].j, status, &run[k].err);
    else outfile_abort(&run[k].err);
    sweep_job_release(run[k].j, run[k].lock);
  }
}

int sweep_run_jobs(const char *bin, struct sweep_job **todo, unsigned n, unsigned jobs,
                   const struct sweep *s, int *sig, unsigned *busy) {
  struct supervisor sv = {.bin = bin, .s = s, .jobs = jobs, .tty = isatty(2)};
  sv.run = xcalloc(jobs, sizeof *sv.run);
  sv.t = (struct tally){n, 0, 0, 0, 0, 0, 0, app_now()};
  for (unsigned i = 0; i < n; i++) sv.t.cost_total += todo[i]->p->cost;
  /* SIGCHLD needs a handler only so that it is not discarded. */
  sigset_t set;
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
  sigprocmask(SIG_BLOCK, &set, &sv.old);
  unsigned next = 0;
  *sig = 0;
  while ((next < n || sv.t.running > 0) && !*sig) {
    while (sv.t.running < jobs && next < n) start(&sv, todo[next++]);
    if (sv.tty) progress(&sv.t);
    struct timespec tick = {1, 0};
    int got = sigtimedwait(&set, NULL, &tick);
    if (got == SIGINT || got == SIGTERM || got == SIGHUP) *sig = got;
    reap(&sv);
  }
  if (*sig) stop_all(&sv);
  if (sv.tty) fputs("\r\033[K", stderr);
  sigprocmask(SIG_SETMASK, &sv.old, NULL);
  sigaction(SIGCHLD, &old_sa, NULL);
  free(sv.run);
  *busy = sv.t.busy;
  return *sig ? -1 : (int)sv.t.failed;
}
