/* A sweep point's job and its directory (app/sweep_job.h): the command line
 * and command.sh, point.csv, the check that a complete point was made by this
 * sweep's command, a failed point's first error, and the .running claim that
 * keeps two runners off one point. */
#define _XOPEN_SOURCE 700 /* realpath */

#include "app/sweep_job.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "app/sweep.h"
#include "sim/err.h"
#include "sim/outfile.h"
#include "sim/stats.h"

/* Append s to f, quoted for a POSIX shell when it holds anything but plain
 * characters. */
void sweep_shell_word(FILE *f, const char *s) {
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
char *sweep_command_line(const char *bin, const struct sweep_point *p) {
  char *buf = NULL;
  size_t len = 0;
  FILE *f = open_memstream(&buf, &len);
  CHECK(f);
  sweep_shell_word(f, bin);
  for (char **a = p->args; *a; a++) {
    fputc(' ', f);
    sweep_shell_word(f, *a);
  }
  CHECK(fclose(f) == 0);
  return buf;
}

bool sweep_exists(const char *dir, const char *name) {
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
bool sweep_make_dirs(const char *path, struct err *e) {
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
bool sweep_job_prepare(const struct sweep *s, const struct sweep_job *j, struct err *e) {
  if (!sweep_make_dirs(j->dir, e)) return false;
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
bool sweep_job_same_command(const struct sweep_job *j, const char *dir) {
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
void sweep_first_error(const char *dir, char *out, size_t cap) {
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

void sweep_format_duration(double s, char *out, size_t cap) {
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
int sweep_job_claim(const struct sweep_job *j, bool *busy) {
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
void sweep_job_release(const struct sweep_job *j, int fd) {
  if (fd < 0) return;
  char path[8192];
  snprintf(path, sizeof path, "%s/.running", j->dir);
  unlink(path);
  close(fd);
}

/* Whether a process holds point dir's claim; its holder's line in who. */
bool sweep_claimed(const char *dir, char *who, size_t cap) {
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
