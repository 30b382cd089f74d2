/* rtsim run's output directory (outdir.h): outputs go to a fresh sibling put
 * in DIR's place at the end; app/outguard.h removes it on a signal. */
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

#include "app/outguard.h"
#include "sim/err.h"
#include "sim/outfile.h"

enum { OUTDIR_NAME = OUTDIR_PATH_MAX + 300 };

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

/* path made absolute with its links resolved, whether it exists or not (then
 * its parent must): false with errno set when it cannot be. */
static bool resolve(const char *path, char *out, size_t cap) {
  char copy[OUTDIR_PATH_MAX];
  size_t n = strlen(path);
  if (n == 0 || n >= sizeof copy) {
    errno = n ? ENAMETOOLONG : ENOENT;
    return false;
  }
  memcpy(copy, path, n + 1);
  while (n > 1 && copy[n - 1] == '/') copy[--n] = '\0'; /* "DIR/" is DIR */
  char *real = realpath(copy, NULL);
  if (real) {
    bool fits = strlen(real) < cap;
    if (fits) snprintf(out, cap, "%s", real);
    free(real);
    if (!fits) errno = ENAMETOOLONG;
    return fits;
  }
  if (errno != ENOENT) return false;
  /* Absent: its parent resolved, and its own name. */
  char *slash = strrchr(copy, '/');
  const char *base = slash ? slash + 1 : copy;
  if (!strcmp(base, ".") || !strcmp(base, "..")) return false;
  if (slash == copy) real = realpath("/", NULL);
  else if (slash) {
    *slash = '\0';
    real = realpath(copy, NULL);
  } else real = realpath(".", NULL);
  if (!real) return false;
  int len = snprintf(out, cap, "%s/%s", strcmp(real, "/") ? real : "", base);
  free(real);
  if (len < 0 || (size_t)len >= cap) {
    errno = ENAMETOOLONG;
    return false;
  }
  return true;
}

bool outdir_begin(struct outdir *d, const char *path, const char *const *outputs, struct err *e) {
  memset(d, 0, sizeof *d);
  if (strlen(path) >= sizeof d->path)
    return err_set(e, path, 0, 0, "cannot create the directory: the path is too long");
  snprintf(d->path, sizeof d->path, "%s", path);
  d->outputs = outputs;
  if (!resolve(path, d->target, sizeof d->target))
    return err_set(e, path, 0, 0, "cannot create the directory: %s", strerror(errno));
  struct stat sb;
  if (stat(d->target, &sb) == 0 && !S_ISDIR(sb.st_mode))
    return err_set(e, path, 0, 0, "cannot create the directory: a file of that name exists");
  /* An output's name that an earlier DIR holds as a directory would stay
   * behind the swap: refused before anything runs. */
  for (unsigned k = 0; stat(d->target, &sb) == 0 && outputs[k]; k++) {
    char p[OUTDIR_NAME];
    snprintf(p, sizeof p, "%s/%s", path, outputs[k]);
    if (lstat(p, &sb) == 0 && S_ISDIR(sb.st_mode))
      return err_set(e, p, 0, 0, "cannot write the file over it: %s", strerror(EISDIR));
  }
  char *slash = strrchr(d->target, '/');
  if (!slash || !slash[1] || strlen(d->target) + 32 >= sizeof d->write)
    return err_set(e, path, 0, 0, "cannot write the outputs into the root directory");
  *slash = '\0';
  const char *parent = d->target[0] ? d->target : "/";
  remove_stale_siblings(parent, slash + 1);
  /* (fits: checked above; the length is used so that gcc sees it is) */
  const int wn =
      snprintf(d->write, sizeof d->write, "%s/.%s.run-%ld", d->target, slash + 1, (long)getpid());
  CHECK(wn > 0 && (size_t)wn < sizeof d->write);
  *slash = '/';
  /* Guarded first: a signal right after mkdir must find the sibling. */
  outguard_tree(d->write);
  if (mkdir(d->write, 0777) != 0 &&
      (errno != EEXIST || !clear_dir(d->write) || mkdir(d->write, 0777) != 0)) {
    int code = errno;
    outguard_untree(d->write);
    return err_set(e, path, 0, 0, "cannot create the directory: %s", strerror(code));
  }
  /* Killed runs' temporaries in an earlier DIR would otherwise stay there
   * until a run succeeds. */
  if (stat(d->target, &sb) == 0) outfile_remove_stale(d->target);
  d->fresh = true;
  return true;
}

bool outdir_place(const struct outdir *d, const char *path, char *buf, size_t cap) {
  const char *slash = strrchr(path, '/');
  const char *base = slash ? slash + 1 : path;
  char dir[OUTDIR_PATH_MAX], real[OUTDIR_PATH_MAX];
  snprintf(dir, sizeof dir, "%.*s", slash ? (int)(slash - path) : 1, slash ? path : ".");
  if (slash == path) snprintf(dir, sizeof dir, "/");
  if (base[0] && strcmp(base, ".") && strcmp(base, "..") && resolve(dir, real, sizeof real) &&
      !strcmp(real, d->target)) {
    if (is_output(base, d->outputs)) return false;
    snprintf(buf, cap, "%s/%s", d->write, base);
  } else snprintf(buf, cap, "%s", path);
  return true;
}

/* What a carry-over moved (not linked) into the sibling, to move back if the
 * swap fails. */
struct moved {
  char **name;
  unsigned n;
};

/* Undo a carry-over that failed half way or whose swap failed: what was
 * moved goes back (links are just removed with the sibling), then the
 * sibling goes. */
static void restore(const struct outdir *d, struct moved *m) {
  for (unsigned i = 0; i < m->n; i++) {
    char from[OUTDIR_NAME], to[OUTDIR_NAME];
    snprintf(from, sizeof from, "%s/%s", d->write, m->name[i]);
    snprintf(to, sizeof to, "%s/%s", d->target, m->name[i]);
    struct stat sb;
    if (lstat(to, &sb) != 0) rename(from, to);
  }
  clear_dir(d->write);
}

static void moved_free(struct moved *m) {
  for (unsigned i = 0; i < m->n; i++) free(m->name[i]);
  free(m->name);
  m->name = NULL;
  m->n = 0;
}

/* Give the sibling what DIR holds besides the run's outputs and what the run
 * wrote there itself: regular files as hard links (DIR stays whole until the
 * swap), anything else (a subdirectory, a link) moved. */
static bool carry_over(const struct outdir *d, struct moved *m, struct err *e) {
  DIR *dp = opendir(d->target);
  if (!dp) return err_set(e, d->path, 0, 0, "cannot read the directory: %s", strerror(errno));
  bool ok = true;
  struct dirent *de;
  while (ok && (de = readdir(dp))) {
    const char *n = de->d_name;
    if (!strcmp(n, ".") || !strcmp(n, "..") || is_output(n, d->outputs) || is_temporary(n))
      continue;
    char from[OUTDIR_NAME], to[OUTDIR_NAME];
    snprintf(from, sizeof from, "%s/%s", d->target, n);
    snprintf(to, sizeof to, "%s/%s", d->write, n);
    struct stat sb;
    if (lstat(from, &sb) != 0 || lstat(to, &sb) == 0) continue; /* gone, or the run's own */
    if (S_ISREG(sb.st_mode) && link(from, to) == 0) continue;
    if (rename(from, to) != 0)
      ok = err_set(e, from, 0, 0, "cannot carry it over into the new outputs' directory: %s",
                   strerror(errno));
    else {
      m->name = xrealloc(m->name, (m->n + 1ull) * sizeof *m->name);
      m->name[m->n] = xmalloc(strlen(n) + 1);
      memcpy(m->name[m->n++], n, strlen(n) + 1);
    }
  }
  closedir(dp);
  return ok;
}

/* Put the sibling in DIR's place; on success d->write names what holds the
 * old contents now (nothing when DIR was absent). */
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
  CHECK(d->fresh);
  /* No signal between the carry-over and the removal of the old contents: a
   * signal that comes meanwhile lands after, on a finished directory. */
  outguard_hold();
  char sibling[OUTDIR_PATH_MAX];
  snprintf(sibling, sizeof sibling, "%s", d->write);
  struct moved m = {NULL, 0};
  bool ok = false, placed = false, failed = false;
  struct stat sb;
  if (stat(d->target, &sb) != 0 && errno == ENOENT) {
    /* DIR absent: the sibling takes its name. A directory made meanwhile
     * under that name is swapped with instead. */
    int rc = renameat2(AT_FDCWD, d->write, AT_FDCWD, d->target, RENAME_NOREPLACE);
    if (rc != 0 && (errno == EINVAL || errno == ENOSYS)) rc = rename(d->write, d->target);
    if (rc == 0) ok = placed = true;
    else if (errno != EEXIST && errno != ENOTEMPTY)
      failed =
          !err_set(e, d->path, 0, 0, "cannot move the new outputs into place: %s", strerror(errno));
  }
  if (!placed && !failed) ok = carry_over(d, &m, e) && swap(d, e);
  if (!ok) restore(d, &m);
  else if (!placed && !clear_dir(d->write))
    fprintf(stderr,
            "rtsim run: warning: the previous outputs are left in %s (it holds a "
            "directory made meanwhile)\n",
            d->write);
  moved_free(&m);
  outguard_untree(sibling);
  d->fresh = false;
  outguard_release();
  return ok;
}

void outdir_abort(struct outdir *d) {
  if (!d->fresh) return;
  outguard_hold();
  clear_dir(d->write);
  outguard_untree(d->write);
  d->fresh = false;
  outguard_release();
}

void outdir_name_in_err(const struct outdir *d, struct err *e) {
  char w[ERR_FILE_MAX];
  err_escape(w, sizeof w, d->write);
  size_t n = strlen(w);
  if (!e->set || strncmp(e->file, w, n) || e->file[n] != '/') return;
  char rest[ERR_FILE_MAX];
  memcpy(rest, e->file + n, strlen(e->file + n) + 1);
  err_escape(e->file, sizeof e->file, d->path);
  size_t g = strlen(e->file), r = strlen(rest);
  if (g + r >= sizeof e->file) r = sizeof e->file - 1 - g; /* cut short, as err_set would */
  memcpy(e->file + g, rest, r);
  e->file[g + r] = '\0';
}
