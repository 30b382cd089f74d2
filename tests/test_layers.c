/* The one door: sim/ never includes a renderer/ header; renderer/ includes from
 * sim/ only the memory interface (mem.h) and the file utilities that know
 * nothing of cycles or caches (cfg.h: YAML with positions, err.h: user-error
 * records, outfile.h: whole-or-absent output files), shared so that scene and
 * machine files report errors alike and every output is written one way. */
#include <dirent.h>
#include <stdio.h>
#include <string.h>

#include "testing.h"

/* Call check on each .c and .h file of dir, open for reading; the number of
 * files. */
typedef void (*check_fn)(const char *path, const char *name, FILE *f, const void *arg);
static int each_source(const char *dir, check_fn check, const void *arg) {
  char path[1024];
  int files = 0;
  DIR *d = opendir(dir);
  EXPECTF(d != NULL, "cannot open %s", dir);
  if (!d) return 0;
  struct dirent *de;
  while ((de = readdir(d))) {
    size_t n = strlen(de->d_name);
    if (n < 3 || (strcmp(de->d_name + n - 2, ".c") && strcmp(de->d_name + n - 2, ".h"))) continue;
    snprintf(path, sizeof path, "%s/%s", dir, de->d_name);
    FILE *f = fopen(path, "r");
    if (!f) continue;
    files++;
    check(path, de->d_name, f, arg);
    fclose(f);
  }
  closedir(d);
  return files;
}

/* Includes of arg[0] (a directory prefix) other than those in arg[1..]. */
static void no_crossing(const char *path, const char *name, FILE *f, const void *arg) {
  (void)name;
  const char *const *rule = arg, *forbidden_prefix = rule[0], *const *allowed = rule + 1;
  char line[1024];
  int lineno = 0;
  while (fgets(line, sizeof line, f)) {
    lineno++;
    const char *inc = strstr(line, "#include \"");
    if (!inc) continue;
    const char *hdr = inc + 10;
    if (strncmp(hdr, forbidden_prefix, strlen(forbidden_prefix)) != 0) continue;
    int ok = 0;
    for (int i = 0; allowed[i]; i++)
      if (strncmp(hdr, allowed[i], strlen(allowed[i])) == 0 && hdr[strlen(allowed[i])] == '"')
        ok = 1;
    EXPECTF(ok, "%s:%d: crosses the layer line: %s", path, lineno, line);
  }
}

/* A dir/x.c that has a dir/x.h includes it first, before any other header,
 * to prove the header stands alone. arg: "dir". */
static void own_header_first(const char *path, const char *name, FILE *f, const void *arg) {
  char hpath[1024], line[1024], want[256];
  size_t n = strlen(name);
  if (strcmp(name + n - 2, ".c") != 0) return;
  snprintf(hpath, sizeof hpath, "%.*s.h", (int)(strlen(path) - 2), path);
  FILE *h = fopen(hpath, "r");
  if (!h) return;
  fclose(h);
  snprintf(want, sizeof want, "#include \"%s/%.*s.h\"", (const char *)arg, (int)(n - 2), name);
  while (fgets(line, sizeof line, f))
    if (!strncmp(line, "#include", 8)) {
      line[strcspn(line, "\n")] = '\0';
      EXPECTF(!strcmp(line, want), "%s: first include is '%s', want '%s'", path, line, want);
      return;
    }
}

int main(void) {
  static const char *const sim_rule[] = {"renderer/", NULL};
  static const char *const renderer_rule[] = {"sim/",      "sim/mem.h",     "sim/cfg.h",
                                              "sim/err.h", "sim/outfile.h", NULL};
  EXPECT(each_source(RTSIM_SOURCE_DIR "/sim", no_crossing, sim_rule) > 0);
  EXPECT(each_source(RTSIM_SOURCE_DIR "/renderer", no_crossing, renderer_rule) > 0);
  EXPECT(each_source(RTSIM_SOURCE_DIR "/sim", own_header_first, "sim") > 0);
  EXPECT(each_source(RTSIM_SOURCE_DIR "/renderer", own_header_first, "renderer") > 0);
  EXPECT(each_source(RTSIM_SOURCE_DIR "/app", own_header_first, "app") > 0);
  return testing_done("test_layers");
}
