/* libFuzzer target: rtsim merge's reading of a sweep directory
 * (app/cmd_merge.c: the points' stats.csv, stats.json and point.csv, through
 * app/csv.c). The input is up to nine files separated by NUL bytes: file k is
 * point k / 3's stats.csv, stats.json or point.csv (k % 3), the points named
 * a=1, a=2 and a=10 (natural order differs from byte order); an empty file
 * is absent. Any bytes must give exit 2 (one message) or exit 0 with a table
 * that reads back: one row per point holding a stats.json, the first column
 * the points' names in natural order. Never a crash, a leak or a hang. */
#define _XOPEN_SOURCE 700 /* nftw */
#include <ftw.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

#include "app/app.h"
#include "app/csv.h"
#include "sim/err.h"
#include "tests/fuzz/fuzz_util.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static const char *const POINTS[3] = {"a=1", "a=2", "a=10"};
static const char *const FILES[3] = {"stats.csv", "stats.json", "point.csv"};

static int remove_one(const char *path, const struct stat *st, int flag, struct FTW *ftw) {
  (void)st, (void)flag, (void)ftw;
  remove(path);
  return 0;
}

static void put(const char *path, const uint8_t *data, size_t size) {
  FILE *f = fopen(path, "wb");
  CHECK(f != NULL);
  CHECK(size == 0 || fwrite(data, 1, size, f) == size);
  CHECK(fclose(f) == 0);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  static char dir[1024], table[1024], cmd[] = "merge", dash_o[] = "-o";
  snprintf(dir, sizeof dir, "%s/sweep", fuzz_dir());
  snprintf(table, sizeof table, "%s/table.csv", fuzz_dir());
  nftw(dir, remove_one, 16, FTW_DEPTH | FTW_PHYS);
  remove(table);
  CHECK(mkdir(dir, 0755) == 0);
  bool complete[3] = {false, false, false};
  const uint8_t *p = data, *end = data + size;
  for (unsigned k = 0; k < 9 && p <= end; k++) {
    const uint8_t *nul = memchr(p, '\0', (size_t)(end - p));
    const uint8_t *stop = nul ? nul : end;
    char path[1200];
    snprintf(path, sizeof path, "%s/%s", dir, POINTS[k / 3]);
    mkdir(path, 0755);
    if (stop > p) {
      snprintf(path, sizeof path, "%s/%s/%s", dir, POINTS[k / 3], FILES[k % 3]);
      put(path, p, (size_t)(stop - p));
      if (k % 3 == 1) complete[k / 3] = true;
    }
    if (!nul) break;
    p = nul + 1;
  }
  char *argv[] = {cmd, dir, dash_o, table, NULL};
  int rc = cmd_merge(4, argv);
  CHECK(rc == 0 || rc == 2);
  if (rc != 0) return 0;
  struct csv_table t;
  struct err e;
  memset(&e, 0, sizeof e);
  CHECK(csv_read(&t, table, &e));
  const char *want[3];
  unsigned n = 0;
  for (unsigned i = 0; i < 3; i++)
    if (complete[i]) want[n++] = POINTS[i];
  CHECK_EQ(t.nrows, n);
  CHECK(t.ncols >= 1 && !strcmp(t.names[0], "point"));
  for (unsigned i = 0; i < n; i++) CHECK(!strcmp(csv_cell(&t, i, 0), want[i]));
  csv_free(&t);
  return 0;
}
