/* libFuzzer target: sweep files (app/sweep.c): read, checked and expanded
 * into points, each point's machine config checked and each scene loaded
 * (small, as in fuzz_scene.c), but nothing run and nothing written (the
 * output folder is only named in the points' commands). The input is a YAML
 * file in configs/sweeps/ of the scratch folder, so ../tiny.yaml and
 * ../../scenes/small/room.yaml resolve as in the repository. Any bytes must
 * give points with distinct, non-empty names that are one path component,
 * or one error on one line. */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "app/sweep.h"
#include "sim/err.h"
#include "tests/fuzz/fuzz_util.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static int cmp_name(const void *a, const void *b) {
  return strcmp(*(const char *const *)a, *(const char *const *)b);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  const char *path = fuzz_file("configs/sweeps/fuzz.yaml", data, size);
  char out[600];
  snprintf(out, sizeof out, "%s/out", fuzz_dir());
  struct sweep s;
  struct err e;
  memset(&e, 0, sizeof e);
  if (!sweep_load(&s, path, out, &e)) {
    fuzz_check_err(&e);
    CHECK_EQ(s.npoints, 0);
    sweep_free(&s);
    return 0;
  }
  CHECK(!e.set);
  CHECK_GT(s.npoints, 0);
  for (unsigned i = 0; i < s.npoints; i++) {
    const struct sweep_point *p = &s.points[i];
    CHECK_EQ(p->index, i);
    CHECK(p->name[0] != '\0' && strchr(p->name, '/') == NULL && strchr(p->name, '\n') == NULL);
    CHECK(strcmp(p->name, ".") != 0 && strcmp(p->name, "..") != 0);
    CHECK(p->args != NULL && p->args[0] != NULL);
    for (char **a = p->args; *a; a++) CHECK(strchr(*a, '\n') == NULL);
  }
  const char **names = malloc(s.npoints * sizeof *names);
  CHECK(names != NULL);
  for (unsigned i = 0; i < s.npoints; i++) names[i] = s.points[i].name;
  qsort(names, s.npoints, sizeof *names, cmp_name);
  for (unsigned i = 1; i < s.npoints; i++) CHECK(strcmp(names[i - 1], names[i]) != 0);
  free(names);
  sweep_free(&s);
  return 0;
}
