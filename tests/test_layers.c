/* The layers in the includes. The base pieces of sim/ (err, cfg, scalar,
 * outfile, stats, hist: what both layers use, knowing nothing of cycles,
 * caches or rays; the rtsim_base library) include from sim/ only each other;
 * sim/ never includes a renderer/ header; renderer/ and its rooms include from
 * sim/ only the memory interface (mem.h) and the base headers. The same door
 * is held at link time by the renderer_door program (CMakeLists.txt). Each
 * x.c with an x.h includes it first. A module's private header is included
 * only by the module's own files and their tests. */
#include <dirent.h>
#include <stdbool.h>
#include <stdio.h>
#include <string.h>

#include "testing.h"

/* Call check on each .c and .h file under RTSIM_SOURCE_DIR/rel, subfolders
 * included (the renderer's rooms), open for reading, with its path from the
 * source top ("renderer/policy/qwalk.c"); the number of files. */
typedef void (*check_fn)(const char *path, const char *name, FILE *f, const void *arg);
static int each_source(const char *rel, check_fn check, const void *arg) {
  char dir[1024], path[1024], sub[1024];
  int files = 0;
  snprintf(dir, sizeof dir, "%s/%s", RTSIM_SOURCE_DIR, rel);
  DIR *d = opendir(dir);
  EXPECTF(d != NULL, "cannot open %s", dir);
  if (!d) return 0;
  struct dirent *de;
  while ((de = readdir(d))) {
    if (de->d_name[0] == '.') continue;
    if (snprintf(path, sizeof path, "%s/%s", dir, de->d_name) >= (int)sizeof path ||
        snprintf(sub, sizeof sub, "%s/%s", rel, de->d_name) >= (int)sizeof sub) {
      EXPECTF(false, "path too long under %s", dir);
      continue;
    }
    DIR *inner = opendir(path);
    if (inner) {
      closedir(inner);
      files += each_source(sub, check, arg);
      continue;
    }
    size_t n = strlen(de->d_name);
    if (n < 3 || (strcmp(de->d_name + n - 2, ".c") && strcmp(de->d_name + n - 2, ".h"))) continue;
    FILE *f = fopen(path, "r");
    if (!f) continue;
    files++;
    check(sub, de->d_name, f, arg);
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
 * to prove the header stands alone. path is from the source top. */
static void own_header_first(const char *path, const char *name, FILE *f, const void *arg) {
  (void)arg;
  char hpath[1024], line[1024], want[1100];
  size_t n = strlen(name), p = strlen(path);
  if (strcmp(name + n - 2, ".c") != 0) return;
  snprintf(hpath, sizeof hpath, "%s/%.*s.h", RTSIM_SOURCE_DIR, (int)(p - 2), path);
  FILE *h = fopen(hpath, "r");
  if (!h) return;
  fclose(h);
  snprintf(want, sizeof want, "#include \"%.*s.h\"", (int)(p - 2), path);
  while (fgets(line, sizeof line, f))
    if (!strncmp(line, "#include", 8)) {
      line[strcspn(line, "\n")] = '\0';
      EXPECTF(!strcmp(line, want), "%s: first include is '%s', want '%s'", path, line, want);
      return;
    }
}

/* A private header, arg[0], is included only by files whose path (from the
 * source top) starts with one of arg[1..]. */
static void private_to(const char *path, const char *name, FILE *f, const void *arg) {
  (void)name;
  const char *const *rule = arg;
  for (int i = 1; rule[i]; i++)
    if (!strncmp(path, rule[i], strlen(rule[i]))) return;
  char want[256], line[1024];
  snprintf(want, sizeof want, "#include \"%s\"", rule[0]);
  int lineno = 0;
  while (fgets(line, sizeof line, f)) {
    lineno++;
    if (strncmp(line, "#include", 8) != 0) continue;
    EXPECTF(strncmp(line, want, strlen(want)) != 0, "%s:%d: includes %s, private to %s*", path,
            lineno, rule[0], rule[1]);
  }
}

/* The base pieces: a file of sim/ named for one of them. */
static const char *const BASE[] = {"err",     "cfg",   "scalar", "near",
                                   "outfile", "stats", "hist",   NULL};

static bool is_base(const char *name) {
  for (int i = 0; BASE[i]; i++) {
    size_t n = strlen(BASE[i]);
    if (!strncmp(name, BASE[i], n) && (!strcmp(name + n, ".c") || !strcmp(name + n, ".h")))
      return true;
  }
  return false;
}

/* A base piece's includes of sim/: base headers only. */
static void base_only(const char *path, const char *name, FILE *f, const void *arg) {
  if (is_base(name)) no_crossing(path, name, f, arg);
}

int main(void) {
  static const char *const base_rule[] = {"sim/",         "sim/err.h",  "sim/cfg.h",
                                          "sim/scalar.h", "sim/near.h", "sim/outfile.h",
                                          "sim/stats.h",  "sim/hist.h", NULL};
  static const char *const base_up[] = {"renderer/", NULL};
  static const char *const sim_rule[] = {"renderer/", NULL};
  static const char *const renderer_rule[] = {
      "sim/",       "sim/mem.h",     "sim/err.h",   "sim/cfg.h",  "sim/scalar.h",
      "sim/near.h", "sim/outfile.h", "sim/stats.h", "sim/hist.h", NULL};
  EXPECT(each_source("sim", base_only, base_rule) > 0);
  EXPECT(each_source("sim", base_only, base_up) > 0);
  EXPECT(each_source("sim", no_crossing, sim_rule) > 0);
  EXPECT(each_source("renderer", no_crossing, renderer_rule) > 0);
  /* The rooms are read too (a file in renderer/policy/ is checked). */
  EXPECT(each_source("renderer/policy", no_crossing, renderer_rule) > 0);
  EXPECT(each_source("renderer/scene", no_crossing, renderer_rule) > 0);
  static const char *const dirs[] = {"sim", "renderer", "app", NULL};
  for (int i = 0; dirs[i]; i++) EXPECT(each_source(dirs[i], own_header_first, NULL) > 0);
  /* The banked DRAM level's inside: its files' and their tests' alone. */
  static const char *const banked_private[] = {"sim/dram_banked_state.h", "sim/dram_banked",
                                               "tests/test_dram_banked", NULL};
  static const char *const all_dirs[] = {"sim", "renderer", "app", "tests", NULL};
  for (int i = 0; all_dirs[i]; i++)
    EXPECT(each_source(all_dirs[i], private_to, banked_private) > 0);
  /* The timed machine's inside: its own files alone. */
  static const char *const machine_private[] = {"sim/machine_state.h", "sim/machine", NULL};
  for (int i = 0; all_dirs[i]; i++)
    EXPECT(each_source(all_dirs[i], private_to, machine_private) > 0);
  return testing_done("test_layers");
}
