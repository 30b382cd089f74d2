/* Whole-or-absent outputs (sim/outfile.h): a commit makes the file, an abort
 * or a failure leaves the destination as it was and no temporary behind. */
#include "sim/outfile.h"

#include <dirent.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "sim/err.h"
#include "testing.h"

#define DIR_ RTSIM_TMP "/outfile"

/* The whole content of path, or NULL. */
static char *slurp(const char *path) {
  static char buf[4096];
  FILE *f = fopen(path, "r");
  if (!f) return NULL;
  size_t n = fread(buf, 1, sizeof buf - 1, f);
  fclose(f);
  buf[n] = '\0';
  return buf;
}

/* Entries of DIR_ other than . and .. */
static unsigned entries(void) {
  DIR *d = opendir(DIR_);
  if (!d) return 0;
  unsigned n = 0;
  struct dirent *de;
  while ((de = readdir(d)))
    if (strcmp(de->d_name, ".") && strcmp(de->d_name, "..")) n++;
  closedir(d);
  return n;
}

static void test_commit_and_abort(void) {
  const char *path = DIR_ "/a.txt";
  struct outfile o;
  struct err e = {0};
  EXPECT(outfile_open(&o, path, "the file", &e) && !e.set);
  EXPECT(o.f != NULL && o.tmp != NULL && strstr(o.tmp, DIR_ "/.a.txt.") == o.tmp);
  fputs("new\n", o.f);
  EXPECT(slurp(path) == NULL); /* nothing there until the commit */
  EXPECT(entries() == 1);      /* the temporary, beside the destination */
  EXPECT(outfile_commit(&o, &e) && !e.set);
  EXPECT(o.path == NULL && o.tmp == NULL && o.f == NULL);
  const char *got = slurp(path);
  EXPECTF(got && !strcmp(got, "new\n"), "%s", got ? got : "(missing)");
  EXPECT(entries() == 1);

  /* Abort: the earlier file stays whole, the temporary goes. */
  EXPECT(outfile_open(&o, path, "the file", &e));
  fputs("half a li", o.f);
  fflush(o.f);
  EXPECT(entries() == 2);
  outfile_abort(&o);
  got = slurp(path);
  EXPECT(got && !strcmp(got, "new\n"));
  EXPECT(entries() == 1);
  outfile_abort(&o); /* a reset outfile: nothing to do */
  struct outfile z = {0};
  outfile_abort(&z);

  /* Two writers of one destination at once: separate temporaries. */
  struct outfile o1, o2;
  EXPECT(outfile_open(&o1, path, "the file", &e) && outfile_open(&o2, path, "the file", &e));
  EXPECT(strcmp(o1.tmp, o2.tmp) != 0);
  fputs("one\n", o1.f);
  fputs("two\n", o2.f);
  EXPECT(outfile_commit(&o1, &e) && outfile_commit(&o2, &e));
  got = slurp(path);
  EXPECT(got && !strcmp(got, "two\n"));
  EXPECT(entries() == 1);
  unlink(path);
}

/* A writer that opens the temporary by name, as gnuplot does. */
static void test_named(void) {
  const char *path = DIR_ "/b.txt";
  struct outfile o;
  struct err e = {0};
  EXPECT(outfile_open_named(&o, path, "the plot", &e) && o.f == NULL && o.tmp != NULL);
  testing_write(o.tmp, "drawn\n");
  EXPECT(outfile_commit(&o, &e) && !e.set);
  const char *got = slurp(path);
  EXPECT(got && !strcmp(got, "drawn\n"));
  EXPECT(outfile_open_named(&o, path, "the plot", &e));
  testing_write(o.tmp, "half");
  outfile_abort(&o);
  got = slurp(path);
  EXPECT(got && !strcmp(got, "drawn\n"));
  EXPECT(entries() == 1);
  unlink(path);
}

static void test_failures(void) {
  /* The destination's directory does not exist: no temporary can be made. */
  const char *missing = DIR_ "/no_such_dir/c.txt";
  struct outfile o;
  struct err e = {0};
  EXPECT(!outfile_open(&o, missing, "the table", &e));
  EXPECT(e.set && !strcmp(e.file, missing));
  EXPECTF(strstr(e.msg, "cannot write the table: cannot create a temporary file") &&
              strstr(e.msg, "No such file or directory"),
          "%s", e.msg);
  EXPECT(o.path == NULL && o.tmp == NULL && o.f == NULL);
  memset(&e, 0, sizeof e);
  EXPECT(!outfile_open_named(&o, missing, "the plot", &e) && e.set);

  /* The rename fails (the destination is a non-empty directory): error with
   * the reason, the directory untouched, no temporary left. */
  const char *dir_dest = DIR_ "/d.txt";
  EXPECT(mkdir(dir_dest, 0777) == 0);
  testing_write(DIR_ "/d.txt/keep", "kept\n");
  memset(&e, 0, sizeof e);
  EXPECT(outfile_open(&o, dir_dest, "EXR", &e));
  fputs("data\n", o.f);
  EXPECT(!outfile_commit(&o, &e));
  EXPECT(e.set && !strcmp(e.file, dir_dest));
  EXPECTF(strstr(e.msg, "cannot write EXR: cannot rename the temporary file into place: Is a "
                        "directory"),
          "%s", e.msg);
  EXPECT(o.path == NULL && o.tmp == NULL);
  const char *got = slurp(DIR_ "/d.txt/keep");
  EXPECT(got && !strcmp(got, "kept\n"));
  EXPECT(entries() == 1);
  unlink(DIR_ "/d.txt/keep");
  rmdir(dir_dest);

  /* A write error the stream saw (here: writing to a stream made read-only
   * under it) fails the commit and leaves nothing. */
  const char *path = DIR_ "/e.txt";
  memset(&e, 0, sizeof e);
  EXPECT(outfile_open(&o, path, "the file", &e));
  FILE *ro = freopen(NULL, "r", o.f);
  EXPECT(ro != NULL);
  o.f = ro;
  fputs("x", o.f);
  EXPECT(!outfile_commit(&o, &e) && e.set && !strcmp(e.file, path));
  EXPECT(access(path, F_OK) != 0);
  EXPECT(entries() == 0);
}

/* Temporaries of a killed process are removed; live ones and other files stay. */
static void test_stale(void) {
  pid_t child = fork();
  if (child == 0) _exit(0);
  EXPECT(child > 0 && waitpid(child, NULL, 0) == child); /* now no process has that pid */
  char dead[512], live[512];
  snprintf(dead, sizeof dead, DIR_ "/.f.txt.%ld.0.tmp", (long)child);
  snprintf(live, sizeof live, DIR_ "/.f.txt.%ld.0.tmp", (long)getpid());
  testing_write(dead, "stale");
  testing_write(live, "in progress");
  testing_write(DIR_ "/.f.txt.tmp", "not a temporary of ours");
  testing_write(DIR_ "/f.1.2.tmp", "not hidden: not ours");
  EXPECT(outfile_remove_stale(DIR_) == 1);
  EXPECT(access(dead, F_OK) != 0 && access(live, F_OK) == 0);
  EXPECT(access(DIR_ "/.f.txt.tmp", F_OK) == 0 && access(DIR_ "/f.1.2.tmp", F_OK) == 0);
  EXPECT(outfile_remove_stale(DIR_ "/no_such_dir") == 0);
  unlink(live);
  unlink(DIR_ "/.f.txt.tmp");
  unlink(DIR_ "/f.1.2.tmp");
}

int main(void) {
  int rc = system("rm -rf '" DIR_ "' && mkdir -p '" DIR_ "'");
  EXPECT(rc == 0);
  test_commit_and_abort();
  test_named();
  test_failures();
  test_stale();
  return testing_done("test_outfile");
}
