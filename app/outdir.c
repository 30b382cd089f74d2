/* rtsim run's output directory (outdir.h): in place when incomplete, a fresh
 * sibling swapped in when complete; a signal handler that removes what an
 * interrupted run leaves half done. */
#define _GNU_SOURCE /* renameat2 and RENAME_EXCHANGE (glibc 2.28 and later) */
#include "app/outdir.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "sim/err.h"
#include "sim/outfile.h"

/* Outputs a run may name, and the temporaries of each the handler removes:
 * sim/outfile.h's ".<name>.<pid>.<n>.tmp", n counting up past names that
 * exist; only a stale temporary of an earlier process with our pid can push
 * n past 0, so a few suffice. */
enum { OUTDIR_OUTPUTS_MAX = 8, OUTDIR_TRIES = 4, OUTDIR_NAME = OUTDIR_PATH_MAX + 300 };

static const int SIGNALS[3] = {SIGINT, SIGTERM, SIGHUP};

/* What the signal handler removes, formatted beforehand: a handler may call
 * only async-signal-safe functions (unlink, rmdir, raise), so nothing is
 * formatted or allocated there. */
static struct {
  volatile sig_atomic_t armed;
  char tmp[OUTDIR_OUTPUTS_MAX * OUTDIR_TRIES][OUTDIR_NAME];
  unsigned ntmp;
  char out[OUTDIR_OUTPUTS_MAX][OUTDIR_NAME]; /* outputs in the fresh sibling */
  unsigned nout;
  char dir[OUTDIR_PATH_MAX]; /* the fresh sibling, "" when writing in place */
  char watched[OUTDIR_NAME]; /* another temporary, "" if none */
  struct sigaction old[3];
  bool installed[3];
} g;

static void on_signal(int sig) {
  if (g.armed) {
    for (unsigned i = 0; i < g.ntmp; i++) unlink(g.tmp[i]);
    if (g.watched[0]) unlink(g.watched);
    for (unsigned i = 0; i < g.nout; i++) unlink(g.out[i]);
    if (g.dir[0]) rmdir(g.dir);
  }
  /* SA_RESETHAND restored the default action: end by the same signal, so
   * the parent (a shell, rtsim sweep) sees how the run ended. The signal is
   * blocked inside its handler, so it lands on return. */
  raise(sig);
}

static void arm(const struct outdir *d, const char *const *outputs) {
  memset(g.tmp, 0, sizeof g.tmp);
  g.ntmp = g.nout = 0;
  g.dir[0] = g.watched[0] = '\0';
  const long pid = (long)getpid();
  for (unsigned k = 0; outputs[k]; k++) {
    CHECK_LT(k, (unsigned)OUTDIR_OUTPUTS_MAX);
    for (unsigned n = 0; n < OUTDIR_TRIES; n++)
      snprintf(g.tmp[g.ntmp++], OUTDIR_NAME, "%s/.%s.%ld.%u.tmp", d->write, outputs[k], pid, n);
    if (d->fresh) snprintf(g.out[g.nout++], OUTDIR_NAME, "%s/%s", d->write, outputs[k]);
  }
  if (d->fresh) snprintf(g.dir, sizeof g.dir, "%s", d->write);
  g.armed = 1;
  for (int i = 0; i < 3; i++) {
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sa.sa_flags = SA_RESETHAND;
    sigemptyset(&sa.sa_mask);
    g.installed[i] = false;
    /* A signal the caller ignores (nohup) stays ignored. */
    if (sigaction(SIGNALS[i], NULL, &g.old[i]) == 0 && g.old[i].sa_handler != SIG_IGN)
      g.installed[i] = sigaction(SIGNALS[i], &sa, NULL) == 0;
  }
}

static void disarm(void) {
  if (!g.armed) return;
  g.armed = 0;
  for (int i = 0; i < 3; i++)
    if (g.installed[i]) sigaction(SIGNALS[i], &g.old[i], NULL);
}

void outdir_watch(const char *tmp) {
  /* Copied, so the caller may free its string (outfile_commit does). */
  g.watched[0] = '\0';
  if (tmp && strlen(tmp) < sizeof g.watched) memcpy(g.watched, tmp, strlen(tmp) + 1);
}

static bool is_output(const char *name, const char *const *outputs) {
  for (unsigned k = 0; outputs[k]; k++)
    if (!strcmp(name, outputs[k])) return true;
  return false;
}

/* sim/outfile.h's temporaries (".<name>.<pid>.<n>.tmp"), loosely. */
static bool is_temporary(const char *name) {
  size_t n = strlen(name);
  return name[0] == '.' && n > 4 && !strcmp(name + n - 4, ".tmp");
}

/* Remove dir and the files in it (a run's outputs and temporaries, and
 * links to carried-over files). A subdirectory is not removed: then dir
 * stays and false is returned. */
static bool clear_dir(const char *dir) {
  DIR *dp = opendir(dir);
  if (dp) {
    struct dirent *de;
    while ((de = readdir(dp))) {
      if (!strcmp(de->d_name, ".") || !strcmp(de->d_name, "..")) continue;
      char p[OUTDIR_NAME];
      snprintf(p, sizeof p, "%s/%s", dir, de->d_name);
      unlink(p);
    }
    closedir(dp);
  }
  return rmdir(dir) == 0;
}

/* The siblings of runs into parent/base killed outright (SIGKILL, a crash):
 * ".base.run-PID" and ".base.old-PID" whose PID no longer runs. */
static void remove_stale_siblings(const char *parent, const char *base) {
  DIR *dp = opendir(parent);
  if (!dp) return;
  const size_t bl = strlen(base);
  struct dirent *de;
  while ((de = readdir(dp))) {
    const char *n = de->d_name;
    if (n[0] != '.' || strncmp(n + 1, base, bl) ||
        (strncmp(n + 1 + bl, ".run-", 5) && strncmp(n + 1 + bl, ".old-", 5)))
      continue;
    char *end;
    long pid = strtol(n + bl + 6, &end, 10);
    if (pid <= 0 || *end || kill((pid_t)pid, 0) == 0 || errno != ESRCH) continue;
    char p[OUTDIR_NAME];
    snprintf(p, sizeof p, "%s/%s", parent, n);
    clear_dir(p);
  }
  closedir(dp);
}

bool outdir_begin(struct outdir *d, const char *path, const char *const *outputs, struct err *e) {
  memset(d, 0, sizeof *d);
  if (strlen(path) >= sizeof d->path)
    return err_set(e, path, 0, 0, "cannot create the directory: the path is too long");
  snprintf(d->path, sizeof d->path, "%s", path);
  d->outputs = outputs;
  char stats[OUTDIR_NAME];
  snprintf(stats, sizeof stats, "%s/stats.json", path);
  struct stat sb;
  char *real = stat(stats, &sb) == 0 ? realpath(path, NULL) : NULL;
  char *slash = real ? strrchr(real, '/') : NULL;
  if (slash && slash[1] && strlen(real) + 32 < sizeof d->target) {
    /* Complete: a fresh sibling, swapped in by outdir_commit. */
    snprintf(d->target, sizeof d->target, "%s", real);
    *slash = '\0';
    const char *parent = real[0] ? real : "/";
    remove_stale_siblings(parent, slash + 1);
    snprintf(d->write, sizeof d->write, "%s/.%s.run-%ld", real[0] ? real : "", slash + 1,
             (long)getpid());
    free(real);
    d->fresh = true;
    /* Armed first: a signal right after mkdir must find the sibling to remove. */
    arm(d, outputs);
    if (mkdir(d->write, 0777) != 0 &&
        (errno != EEXIST || !clear_dir(d->write) || mkdir(d->write, 0777) != 0)) {
      int code = errno;
      d->fresh = false;
      disarm();
      return err_set(e, d->write, 0, 0, "cannot create the directory for the new outputs: %s",
                     strerror(code));
    }
    return true;
  } else {
    free(real); /* incomplete, new, or the root: in place */
    if (mkdir(path, 0777) != 0 && errno != EEXIST)
      return err_set(e, path, 0, 0, "cannot create the directory: %s", strerror(errno));
    /* A killed run's temporaries would stay forever. */
    outfile_remove_stale(path);
    snprintf(d->write, sizeof d->write, "%s", path);
  }
  arm(d, outputs);
  return true;
}

/* Undo a carry-over that failed half way: entries moved into the sibling go
 * back (links are just removed), then the sibling goes. */
static void restore(const struct outdir *d, const char *const *outputs) {
  DIR *dp = opendir(d->write);
  if (dp) {
    struct dirent *de;
    while ((de = readdir(dp))) {
      const char *n = de->d_name;
      if (!strcmp(n, ".") || !strcmp(n, "..") || is_output(n, outputs) || is_temporary(n)) continue;
      char from[OUTDIR_NAME], to[OUTDIR_NAME];
      snprintf(from, sizeof from, "%s/%s", d->write, n);
      snprintf(to, sizeof to, "%s/%s", d->target, n);
      struct stat sb;
      if (lstat(to, &sb) != 0) rename(from, to);
    }
    closedir(dp);
  }
  clear_dir(d->write);
}

/* Give the sibling what the old directory holds besides the run's outputs:
 * regular files as hard links (the old directory stays whole until the
 * swap), anything else (a subdirectory, a link) moved. */
static bool carry_over(const struct outdir *d, const char *const *outputs, struct err *e) {
  DIR *dp = opendir(d->target);
  if (!dp) return err_set(e, d->path, 0, 0, "cannot read the directory: %s", strerror(errno));
  bool ok = true;
  struct dirent *de;
  while (ok && (de = readdir(dp))) {
    const char *n = de->d_name;
    if (!strcmp(n, ".") || !strcmp(n, "..") || is_output(n, outputs) || is_temporary(n)) continue;
    char from[OUTDIR_NAME], to[OUTDIR_NAME];
    snprintf(from, sizeof from, "%s/%s", d->target, n);
    snprintf(to, sizeof to, "%s/%s", d->write, n);
    struct stat sb;
    if (lstat(from, &sb) != 0) continue; /* gone meanwhile */
    if (S_ISREG(sb.st_mode) && link(from, to) == 0) continue;
    if (rename(from, to) != 0)
      ok = err_set(e, from, 0, 0, "cannot carry it over into the new outputs' directory: %s",
                   strerror(errno));
  }
  closedir(dp);
  return ok;
}

/* Put the sibling in the old directory's place; on success d->write names
 * what holds the old contents now. */
static bool swap(struct outdir *d, struct err *e) {
  if (renameat2(AT_FDCWD, d->write, AT_FDCWD, d->target, RENAME_EXCHANGE) == 0) return true;
  if (errno != EINVAL && errno != ENOSYS)
    return err_set(e, d->path, 0, 0, "cannot swap the new outputs in: %s", strerror(errno));
  /* No exchange on this file system: the old aside, then the new in. */
  char aside[OUTDIR_PATH_MAX];
  const char *slash = strrchr(d->target, '/');
  snprintf(aside, sizeof aside, "%.*s/.%s.old-%ld", (int)(slash - d->target), d->target, slash + 1,
           (long)getpid());
  if (rename(d->target, aside) != 0)
    return err_set(e, d->path, 0, 0, "cannot move the old outputs aside: %s", strerror(errno));
  if (rename(d->write, d->target) != 0) {
    int code = errno;
    rename(aside, d->target);
    return err_set(e, d->path, 0, 0, "cannot swap the new outputs in: %s", strerror(code));
  }
  snprintf(d->write, sizeof d->write, "%s", aside);
  return true;
}

bool outdir_commit(struct outdir *d, struct err *e) {
  if (!d->fresh) {
    disarm();
    return true;
  }
  /* No signal between the carry-over and the removal of the old contents: a
   * signal that comes meanwhile lands after, on a finished directory. */
  sigset_t set, old;
  sigemptyset(&set);
  for (int i = 0; i < 3; i++) sigaddset(&set, SIGNALS[i]);
  sigprocmask(SIG_BLOCK, &set, &old);
  bool ok = carry_over(d, d->outputs, e) && swap(d, e);
  if (!ok) restore(d, d->outputs);
  else if (!clear_dir(d->write))
    fprintf(stderr,
            "rtsim run: warning: the previous outputs are left in %s (it holds a "
            "directory made meanwhile)\n",
            d->write);
  d->fresh = false;
  disarm();
  sigprocmask(SIG_SETMASK, &old, NULL);
  return ok;
}

void outdir_abort(struct outdir *d) {
  if (d->fresh) {
    sigset_t set, old;
    sigemptyset(&set);
    for (int i = 0; i < 3; i++) sigaddset(&set, SIGNALS[i]);
    sigprocmask(SIG_BLOCK, &set, &old);
    restore(d, d->outputs);
    d->fresh = false;
    disarm();
    sigprocmask(SIG_SETMASK, &old, NULL);
    return;
  }
  disarm();
}
