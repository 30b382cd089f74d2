/* The one door: sim/ never includes a renderer/ header; renderer/ includes from
 * sim/ only the memory interface (mem.h) and the file utilities that know
 * nothing of cycles or caches (cfg.h: YAML with positions, err.h: user-error
 * records, outfile.h: whole-or-absent output files), shared so that scene and
 * machine files report errors alike and every output is written one way. */
#include <dirent.h>
#include <stdio.h>
#include <string.h>

#include "testing.h"

static int scan(const char *dir, const char *forbidden_prefix, const char *const *allowed) {
  char path[1024], line[1024];
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
    int lineno = 0;
    while (fgets(line, sizeof line, f)) {
      lineno++;
      const char *inc = strstr(line, "#include \"");
      if (!inc) continue;
      const char *name = inc + 10;
      if (strncmp(name, forbidden_prefix, strlen(forbidden_prefix)) != 0) continue;
      int ok = 0;
      for (int i = 0; allowed[i]; i++)
        if (strncmp(name, allowed[i], strlen(allowed[i])) == 0 && name[strlen(allowed[i])] == '"')
          ok = 1;
      EXPECTF(ok, "%s:%d: crosses the layer line: %s", path, lineno, line);
    }
    fclose(f);
  }
  closedir(d);
  return files;
}

/* Each dir/x.c that has a dir/x.h includes it first, before any other
 * header, to prove the header stands alone. Returns the files checked. */
static int own_header_first(const char *dir, const char *rel) {
  char path[1024], line[1024], want[256];
  int files = 0;
  DIR *d = opendir(dir);
  EXPECTF(d != NULL, "cannot open %s", dir);
  if (!d) return 0;
  struct dirent *de;
  while ((de = readdir(d))) {
    size_t n = strlen(de->d_name);
    if (n < 3 || strcmp(de->d_name + n - 2, ".c") != 0) continue;
    snprintf(path, sizeof path, "%s/%.*s.h", dir, (int)(n - 2), de->d_name);
    FILE *h = fopen(path, "r");
    if (!h) continue;
    fclose(h);
    snprintf(want, sizeof want, "#include \"%s/%.*s.h\"", rel, (int)(n - 2), de->d_name);
    snprintf(path, sizeof path, "%s/%s", dir, de->d_name);
    FILE *f = fopen(path, "r");
    if (!f) continue;
    files++;
    while (fgets(line, sizeof line, f))
      if (!strncmp(line, "#include", 8)) {
        line[strcspn(line, "\n")] = '\0';
        EXPECTF(!strcmp(line, want), "%s: first include is '%s', want '%s'", path, line, want);
        break;
      }
    fclose(f);
  }
  closedir(d);
  return files;
}

int main(void) {
  static const char *const none[] = {NULL};
  static const char *const door[] = {"sim/mem.h", "sim/cfg.h", "sim/err.h", "sim/outfile.h", NULL};
  EXPECT(scan(RTSIM_SOURCE_DIR "/sim", "renderer/", none) > 0);
  EXPECT(scan(RTSIM_SOURCE_DIR "/renderer", "sim/", door) > 0);
  EXPECT(own_header_first(RTSIM_SOURCE_DIR "/sim", "sim") > 0);
  EXPECT(own_header_first(RTSIM_SOURCE_DIR "/renderer", "renderer") > 0);
  EXPECT(own_header_first(RTSIM_SOURCE_DIR "/app", "app") > 0);
  return testing_done("test_layers");
}
