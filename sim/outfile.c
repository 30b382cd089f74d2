/* Whole-or-absent output files (outfile.h): a temporary beside the
 * destination, renamed over it on success, removed on failure. */
#include "sim/outfile.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "sim/err.h"

/* Names tried before giving up: only stale temporaries of an earlier process
 * with our pid can be in the way. */
enum { OUTFILE_TRIES = 1000 };

static void reset(struct outfile *o) {
  free(o->path);
  free(o->tmp);
  memset(o, 0, sizeof *o);
}

static bool fail(struct outfile *o, struct err *e, const char *how, int code) {
  err_set(e, o->path, 0, 0, "cannot write %s: %s%s", o->what, how, strerror(code));
  if (o->f) fclose(o->f);
  if (o->tmp) unlink(o->tmp);
  reset(o);
  return false;
}

/* Create the temporary exclusively; its descriptor, or -1 with errno set. */
static int create_tmp(struct outfile *o, const char *path, const char *what) {
  memset(o, 0, sizeof *o);
  size_t n = strlen(path);
  o->path = xmalloc(n + 1);
  memcpy(o->path, path, n + 1);
  o->what = what;
  const char *slash = strrchr(path, '/');
  const int dir_len = slash ? (int)(slash - path + 1) : 0;
  const size_t cap = n + 64;
  o->tmp = xmalloc(cap);
  for (unsigned k = 0; k < OUTFILE_TRIES; k++) {
    snprintf(o->tmp, cap, "%.*s.%s.%ld.%u.tmp", dir_len, path, path + dir_len, (long)getpid(), k);
    /* 0666 less the umask: the same mode fopen would give the destination. */
    int fd = open(o->tmp, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd >= 0 || errno != EEXIST) return fd;
  }
  return -1;
}

bool outfile_open(struct outfile *o, const char *path, const char *what, struct err *e) {
  int fd = create_tmp(o, path, what);
  if (fd < 0) {
    int code = errno;
    free(o->tmp);
    o->tmp = NULL; /* not ours to remove */
    return fail(o, e, "cannot create a temporary file beside it: ", code);
  }
  o->f = fdopen(fd, "w");
  if (!o->f) {
    int code = errno;
    close(fd);
    return fail(o, e, "", code);
  }
  return true;
}

bool outfile_open_named(struct outfile *o, const char *path, const char *what, struct err *e) {
  if (!outfile_open(o, path, what, e)) return false;
  if (fclose(o->f) != 0) {
    o->f = NULL;
    return fail(o, e, "", errno);
  }
  o->f = NULL;
  return true;
}

bool outfile_commit(struct outfile *o, struct err *e) {
  CHECK(o->path != NULL); /* opened, and not yet committed or aborted */
  if (o->f) {
    errno = 0;
    int code = 0;
    if (fflush(o->f) != 0 || ferror(o->f)) code = errno ? errno : EIO;
    FILE *f = o->f;
    o->f = NULL;
    if (fclose(f) != 0 && !code) code = errno ? errno : EIO;
    if (code) return fail(o, e, "", code);
  }
  if (rename(o->tmp, o->path) != 0)
    return fail(o, e, "cannot rename the temporary file into place: ", errno);
  reset(o);
  return true;
}

void outfile_abort(struct outfile *o) {
  if (!o->path) return;
  if (o->f) fclose(o->f);
  unlink(o->tmp);
  reset(o);
}

/* The pid in a temporary's name ".<name>.<pid>.<n>.tmp", or 0 if it is not
 * one. */
static long tmp_pid(const char *name) {
  size_t len = strlen(name);
  if (name[0] != '.' || len < 9 || strcmp(name + len - 4, ".tmp") != 0) return 0;
  const char *p = name + len - 4; /* at ".tmp" */
  const char *q = p;
  while (q > name && q[-1] >= '0' && q[-1] <= '9') q--;
  if (q == p || q == name || q[-1] != '.') return 0; /* <n> */
  p = --q;                                           /* at ".<n>" */
  while (q > name && q[-1] >= '0' && q[-1] <= '9') q--;
  if (q == p || q - 1 <= name || q[-1] != '.') return 0; /* <pid> */
  return strtol(q, NULL, 10);
}

unsigned outfile_remove_stale(const char *dir) {
  DIR *d = opendir(dir);
  if (!d) return 0;
  unsigned n = 0;
  struct dirent *de;
  while ((de = readdir(d))) {
    long pid = tmp_pid(de->d_name);
    if (pid <= 0 || kill((pid_t)pid, 0) == 0 || errno != ESRCH) continue;
    char path[8192];
    snprintf(path, sizeof path, "%s/%s", dir, de->d_name);
    n += unlink(path) == 0;
  }
  closedir(d);
  return n;
}
