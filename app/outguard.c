/* The signal handler that removes unfinished outputs (outguard.h). Paths are
 * copied into a fixed table beforehand, so the handler formats and allocates
 * nothing: it calls only open, close, unlinkat, rmdir, raise and getdents64,
 * and reads the table. */
#define _GNU_SOURCE /* syscall, SYS_getdents64 */
#include "app/outguard.h"

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include "sim/err.h"

/* A command guards a few places: a run's sibling and the directories of its
 * trace and heat map; render's image and preview. */
enum { OUTGUARD_SLOTS = 16, OUTGUARD_PATH = 4096, OUTGUARD_HELPERS = 4 };
enum { KIND_NONE, KIND_TEMPS, KIND_TREE };

static const int SIGNALS[3] = {SIGINT, SIGTERM, SIGHUP};

/* A slot is written whole before its kind is set, and never reused until
 * outguard_clear (signals held): a handler in any thread reads whole slots. */
static struct {
  struct {
    atomic_int kind;
    char path[OUTGUARD_PATH];
  } slot[OUTGUARD_SLOTS];
  unsigned used;
  atomic_int helper[OUTGUARD_HELPERS]; /* pids, 0 when free */
  char pid[32]; /* ".<pid>", what our temporaries' names hold before ".<n>.tmp" */
  size_t pid_len;
  bool installed[3];
  struct sigaction old[3];
  bool armed;
  unsigned holds;
  sigset_t held_old;
} g;

/* sim/outfile.h's temporary of this process: ".<...>.<pid>.<n>.tmp". */
static bool is_ours(const char *name) {
  size_t n = strlen(name);
  if (name[0] != '.' || n < 6 || memcmp(name + n - 4, ".tmp", 4) != 0) return false;
  size_t i = n - 4;
  while (i > 0 && name[i - 1] >= '0' && name[i - 1] <= '9') i--;
  if (i == n - 4 || i == 0 || name[i - 1] != '.') return false; /* <n> */
  i--;                                                          /* at ".<n>" */
  return i > g.pid_len && memcmp(name + i - g.pid_len, g.pid, g.pid_len) == 0;
}

/* getdents64's record (linux/dirent.h; not in glibc's headers before 2.30). */
struct outguard_dirent {
  uint64_t ino;
  int64_t off;
  unsigned short reclen;
  unsigned char type;
  char name[];
};

/* Remove the entries of dir that are ours (all: every one); a pass that
 * removed some is followed by another, since removing while reading may skip
 * names. NOTE: getdents64 is a plain system call, safe in a handler, unlike
 * readdir; this ties the file to Linux, as renameat2 and prctl already do. */
static void clear_entries(const char *dir, bool all) {
  int fd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  _Alignas(8) char buf[4096];
  for (int pass = 0; pass < 8; pass++) {
    bool removed = false;
    long len;
    if (lseek(fd, 0, SEEK_SET) != 0) break;
    while ((len = syscall(SYS_getdents64, fd, buf, sizeof buf)) > 0)
      for (long off = 0; off < len;) {
        const struct outguard_dirent *de = (const void *)(buf + off);
        off += de->reclen;
        const char *n = de->name;
        if (!strcmp(n, ".") || !strcmp(n, "..") || !(all || is_ours(n))) continue;
        if (unlinkat(fd, n, 0) == 0 || (errno == EISDIR && unlinkat(fd, n, AT_REMOVEDIR) == 0))
          removed = true;
      }
    if (!removed) break;
  }
  close(fd);
}

static void on_signal(int sig) {
  const int saved = errno;
  for (unsigned i = 0; i < OUTGUARD_HELPERS; i++) {
    pid_t pid = (pid_t)atomic_load(&g.helper[i]);
    if (pid <= 0) continue;
    kill(pid, SIGKILL);
    waitpid(pid, NULL, 0);
  }
  for (unsigned i = 0; i < OUTGUARD_SLOTS; i++) {
    int kind = atomic_load(&g.slot[i].kind);
    if (kind == KIND_NONE) continue;
    clear_entries(g.slot[i].path, kind == KIND_TREE);
    if (kind == KIND_TREE) rmdir(g.slot[i].path);
  }
  errno = saved;
  /* SA_RESETHAND restored the default action; the signal is blocked inside
   * its handler, so it lands on return. */
  raise(sig);
}

static void arm(void) {
  if (g.armed) return;
  g.armed = true;
  g.pid_len = (size_t)snprintf(g.pid, sizeof g.pid, ".%ld", (long)getpid());
  for (int i = 0; i < 3; i++) {
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sa.sa_flags = SA_RESETHAND;
    sigemptyset(&sa.sa_mask);
    g.installed[i] = false;
    if (sigaction(SIGNALS[i], NULL, &g.old[i]) == 0 && g.old[i].sa_handler != SIG_IGN)
      g.installed[i] = sigaction(SIGNALS[i], &sa, NULL) == 0;
  }
}

static void add(const char *path, int kind) {
  if (strlen(path) >= OUTGUARD_PATH) return; /* unguarded: a signal leaves it */
  for (unsigned i = 0; i < g.used; i++)
    if (atomic_load(&g.slot[i].kind) == kind && !strcmp(g.slot[i].path, path)) return;
  CHECK_LT(g.used, (unsigned)OUTGUARD_SLOTS);
  arm();
  memcpy(g.slot[g.used].path, path, strlen(path) + 1);
  atomic_store(&g.slot[g.used].kind, kind);
  g.used++;
}

void outguard_beside(const char *path) {
  const char *slash = strrchr(path, '/');
  char dir[OUTGUARD_PATH];
  if (!slash) snprintf(dir, sizeof dir, ".");
  else if (slash == path) snprintf(dir, sizeof dir, "/");
  else if ((size_t)(slash - path) < sizeof dir)
    snprintf(dir, sizeof dir, "%.*s", (int)(slash - path), path);
  else return;
  add(dir, KIND_TEMPS);
}

void outguard_tree(const char *dir) { add(dir, KIND_TREE); }

void outguard_untree(const char *dir) {
  for (unsigned i = 0; i < g.used; i++)
    if (atomic_load(&g.slot[i].kind) == KIND_TREE && !strcmp(g.slot[i].path, dir))
      atomic_store(&g.slot[i].kind, KIND_NONE);
}

void outguard_helper(pid_t pid) {
  arm();
  for (unsigned i = 0; i < OUTGUARD_HELPERS; i++) {
    int free_slot = 0;
    if (atomic_compare_exchange_strong(&g.helper[i], &free_slot, (int)pid)) return;
  }
  CHECK(!"more helper processes than outguard's table holds");
}

void outguard_helper_done(pid_t pid) {
  for (unsigned i = 0; i < OUTGUARD_HELPERS; i++) {
    int was = (int)pid;
    atomic_compare_exchange_strong(&g.helper[i], &was, 0);
  }
}

void outguard_hold(void) {
  if (g.holds++ > 0) return;
  sigset_t set;
  sigemptyset(&set);
  for (int i = 0; i < 3; i++) sigaddset(&set, SIGNALS[i]);
  sigprocmask(SIG_BLOCK, &set, &g.held_old);
}

void outguard_release(void) {
  CHECK_GT(g.holds, 0u);
  if (--g.holds == 0) sigprocmask(SIG_SETMASK, &g.held_old, NULL);
}

void outguard_clear(void) {
  if (!g.armed) return;
  outguard_hold();
  for (unsigned i = 0; i < g.used; i++) atomic_store(&g.slot[i].kind, KIND_NONE);
  g.used = 0;
  for (int i = 0; i < 3; i++)
    if (g.installed[i]) sigaction(SIGNALS[i], &g.old[i], NULL);
  g.armed = false;
  outguard_release();
}
