/* rtsim merge: the complete points of a sweep directory as one tidy table.
 * A row per subdirectory holding a stats.json (complete), in natural order of
 * the point names; columns: point, the swept keys (point.csv), then the
 * stats.csv columns, each name once (a swept key that stats.csv also has, as
 * every config and workload key, takes stats.csv's resolved value: 16KiB
 * reads 16384). Points with other columns still merge: the union of the
 * columns in order of first appearance, missing cells empty. Last come the
 * provenance columns from each stats.json (wall_s, peak_rss_mb, host,
 * revision), which stats.csv leaves out to stay bit-identical run to run;
 * points of one table from different revisions, or one scene under two
 * hashes, are merged with a warning. */
#include "app/app.h"

#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "app/csv.h"
#include "app/opts.h"
#include "app/outguard.h"
#include "sim/err.h"
#include "sim/outfile.h"
#include "sim/stats.h"

static const char HELP[] =
    "usage: rtsim merge DIR -o TABLE.csv [--reproducible]\n"
    "\n"
    "Join the complete points of a sweep directory (each subdirectory holding a\n"
    "stats.json) into one tidy CSV table, a row per point in natural order of\n"
    "the point names: the column 'point' (the directory name), the swept keys\n"
    "(from each point's point.csv), then the stats.csv columns. A column name\n"
    "appears once: a swept key stats.csv also has takes stats.csv's resolved\n"
    "value (l2.size 16KiB reads 16384). Points with different columns merge into\n"
    "the union of the columns; missing cells stay empty. Incomplete points are\n"
    "skipped and named on stderr; a DIR with no complete point is refused.\n"
    "Last come each point's provenance from its stats.json: wall_s (host seconds\n"
    "of the simulation), peak_rss_mb (MiB), host, revision (the build's git\n"
    "describe). Points from different revisions, or one scene under different\n"
    "scene_hash values, merge with a warning on stderr.\n"
    "\n"
    "example (after rtsim sweep configs/sweeps/example.yaml -o build/sweep):\n"
    "  rtsim merge build/sweep -o build/sweep.csv\n"
    "\n"
    "options:\n"
    "  -o, --output TABLE.csv  the table (written whole or not at all)\n"
    "  --reproducible          leave out wall_s, peak_rss_mb and host, which differ\n"
    "                          run to run: the same points then merge to the same bytes\n"
    "  -h, --help              this text\n";

static int cmp_names(const void *x, const void *y) {
  const char *a = *(char *const *)x, *b = *(char *const *)y;
  int c = csv_natural_cmp(a, b);
  return c ? c : strcmp(a, b);
}

static bool has(const char *dir, const char *sub, const char *name) {
  char p[8192];
  snprintf(p, sizeof p, "%s/%s/%s", dir, sub, name);
  struct stat sb;
  return stat(p, &sb) == 0;
}

/* The provenance columns, read from stats.json; the first three differ run
 * to run (--reproducible leaves them out). */
enum { PROV_WALL, PROV_RSS, PROV_HOST, PROV_REVISION, PROV_COUNT };
static const char *const PROV_NAMES[PROV_COUNT] = {"wall_s", "peak_rss_mb", "host", "revision"};

/* One point: its stats.csv and (when swept) point.csv, one row each. */
struct point {
  char *name;
  struct csv_table stats, swept;
  char prov[PROV_COUNT][256]; /* "" when its stats.json lacks one */
};

/* Read point p's provenance members from its stats.json (dir/name). */
static bool read_provenance(struct point *p, const char *dir, struct err *e) {
  char path[8192];
  snprintf(path, sizeof path, "%s/%s/stats.json", dir, p->name);
  const char *why;
  size_t len;
  char *text = csv_slurp(path, &len, &why);
  if (!text) return err_set(e, path, 0, 0, "cannot read the file: %s", why);
  for (int k = 0; k < PROV_COUNT; k++)
    if (!csv_json_member(text, PROV_NAMES[k], p->prov[k], sizeof p->prov[k])) p->prov[k][0] = '\0';
  free(text);
  return true;
}

static const char *cell(const struct point *p, const char *name);

/* Warn when column `col` (a stats.csv column, or provenance k when col is
 * NULL) takes more than one value over the points, within each group of
 * equal `group` values (NULL: one group). Names the first point of each of
 * the first two values. */
static void warn_mixed(const struct point *pts, unsigned n, const char *col, int k,
                       const char *group, const char *what) {
  for (unsigned i = 0; i < n; i++) {
    const char *g = group ? cell(&pts[i], group) : "";
    const char *a = col ? cell(&pts[i], col) : pts[i].prov[k];
    bool first_of_group = true;
    for (unsigned h = 0; h < i && first_of_group; h++)
      first_of_group = strcmp(group ? cell(&pts[h], group) : "", g) != 0;
    if (!first_of_group) continue;
    for (unsigned j = i + 1; j < n; j++) {
      if (strcmp(group ? cell(&pts[j], group) : "", g)) continue;
      const char *b = col ? cell(&pts[j], col) : pts[j].prov[k];
      if (!strcmp(a, b)) continue;
      fprintf(stderr, "merge: warning: %s%s%s: %s '%s' (%s) and '%s' (%s); the table mixes them\n",
              what, group ? " of scene " : "", group ? g : "", col ? col : PROV_NAMES[k], a,
              pts[i].name, b, pts[j].name);
      break;
    }
  }
}

static bool read_one_row(struct csv_table *t, const char *path, struct err *e) {
  if (!csv_read(t, path, e)) return false;
  if (t->nrows == 1) return true;
  return err_set(e, path, 0, 0, "expected a header and one row (got %u rows)", t->nrows);
}

/* The cell of column `name` for point p: stats.csv's, else point.csv's, else "". */
static const char *cell(const struct point *p, const char *name) {
  int c = csv_column(&p->stats, name);
  if (c >= 0) return csv_cell(&p->stats, 0, (unsigned)c);
  c = csv_column(&p->swept, name);
  return c >= 0 ? csv_cell(&p->swept, 0, (unsigned)c) : "";
}

/* Add name to the column list unless present. */
static void add_column(char ***cols, unsigned *n, const char *name) {
  for (unsigned i = 0; i < *n; i++)
    if (!strcmp((*cols)[i], name)) return;
  *cols = xrealloc(*cols, (*n + 1ull) * sizeof **cols);
  (*cols)[(*n)++] = (char *)name;
}

/* The table: the header cols[0..ncols), then a row a point; columns from
 * nmeasured on may be provenance. Written whole or not at all; false with e
 * set. */
static bool write_table(const char *out, char **cols, unsigned ncols, unsigned nmeasured,
                        const struct point *pts, unsigned n, struct err *e) {
  struct outfile o;
  outguard_beside(out); /* a signal while it is written removes its temporary */
  if (!outfile_open(&o, out, "the table", e)) {
    outguard_clear();
    return false;
  }
  FILE *f = o.f;
  for (unsigned k = 0; k < ncols; k++) {
    if (k) fputc(',', f);
    stats_write_csv_str(f, cols[k]);
  }
  fputc('\n', f);
  for (unsigned i = 0; i < n; i++) {
    stats_write_csv_str(f, pts[i].name);
    for (unsigned k = 1; k < ncols; k++) {
      fputc(',', f);
      int prov = -1;
      for (int q = 0; k >= nmeasured && q < PROV_COUNT; q++)
        if (!strcmp(cols[k], PROV_NAMES[q])) prov = q;
      stats_write_csv_str(f, prov >= 0 ? pts[i].prov[prov] : cell(&pts[i], cols[k]));
    }
    fputc('\n', f);
  }
  bool committed = outfile_commit(&o, e);
  outguard_clear();
  return committed;
}

int cmd_merge(int argc, char **argv) {
  const char *out = NULL;
  bool reproducible = false;
  const struct opts_spec spec[] = {OPTS_STR("output", 'o', &out),
                                   OPTS_FLAG("reproducible", 0, &reproducible), OPTS_END};
  struct opts_args args;
  int rc = opts_parse("merge", HELP, spec, argc, argv, &args);
  if (rc != OPTS_GO) return rc;
  const char *dir = opts_one(&args, "DIR", "directory");
  if (!dir) return APP_EXIT_USAGE;
  if (!out) return app_usage_error("merge", "missing -o TABLE.csv");
  struct err e = {0};
  DIR *d = opendir(dir);
  if (!d) {
    err_set(&e, dir, 0, 0, "cannot open the sweep directory: %s", strerror(errno));
    return app_report(&e);
  }
  /* Subdirectories that are points: complete ones, and incomplete ones to name. */
  char **names = NULL, **partial = NULL;
  unsigned n = 0, npartial = 0;
  struct dirent *de;
  while ((de = readdir(d))) {
    if (de->d_name[0] == '.') continue;
    if (has(dir, de->d_name, "stats.json")) {
      names = xrealloc(names, (n + 1ull) * sizeof *names);
      names[n++] = strdup(de->d_name);
    } else if (has(dir, de->d_name, "command.sh") || has(dir, de->d_name, "point.csv")) {
      partial = xrealloc(partial, (npartial + 1ull) * sizeof *partial);
      partial[npartial++] = strdup(de->d_name);
    }
  }
  closedir(d);
  rc = 0;
  struct point *pts = xcalloc(n, sizeof *pts);
  char **cols = NULL;
  unsigned ncols = 0;
  if (n == 0) {
    err_set(&e, dir, 0, 0,
            "no complete point (no subdirectory holds a stats.json%s): nothing to merge",
            npartial ? "; the points there have not finished" : "");
    rc = app_report(&e);
    goto done;
  }
  qsort(names, n, sizeof *names, cmp_names);
  if (npartial) qsort(partial, npartial, sizeof *partial, cmp_names);
  add_column(&cols, &ncols, "point");
  for (unsigned i = 0; i < n; i++) {
    char path[8192];
    pts[i].name = names[i];
    snprintf(path, sizeof path, "%s/%s/stats.csv", dir, names[i]);
    if (!read_one_row(&pts[i].stats, path, &e) || !read_provenance(&pts[i], dir, &e)) {
      rc = app_report(&e);
      goto done;
    }
    if (has(dir, names[i], "point.csv")) {
      snprintf(path, sizeof path, "%s/%s/point.csv", dir, names[i]);
      if (!read_one_row(&pts[i].swept, path, &e)) {
        rc = app_report(&e);
        goto done;
      }
    }
  }
  /* Swept keys first (in the points' order), then the measured columns. */
  for (unsigned i = 0; i < n; i++)
    for (unsigned k = 0; k < pts[i].swept.ncols; k++)
      add_column(&cols, &ncols, pts[i].swept.names[k]);
  for (unsigned i = 0; i < n; i++)
    for (unsigned k = 0; k < pts[i].stats.ncols; k++)
      add_column(&cols, &ncols, pts[i].stats.names[k]);
  /* Provenance last: a stats.csv column of the same name (none today) would
   * keep its place and its value. */
  const unsigned nmeasured = ncols;
  for (int k = reproducible ? PROV_REVISION : 0; k < PROV_COUNT; k++)
    add_column(&cols, &ncols, PROV_NAMES[k]);
  warn_mixed(pts, n, NULL, PROV_REVISION, NULL, "points from different builds");
  warn_mixed(pts, n, "scene_hash", 0, "scene", "a scene changed between points");

  if (!write_table(out, cols, ncols, nmeasured, pts, n, &e)) {
    rc = app_report(&e);
    goto done;
  }
  fprintf(stderr, "merge: %u point%s, %u columns into %s", n, n == 1 ? "" : "s", ncols, out);
  if (npartial) {
    fprintf(stderr, "; %u incomplete skipped:", npartial);
    for (unsigned i = 0; i < npartial && i < 5; i++) fprintf(stderr, " %s", partial[i]);
    if (npartial > 5) fputs(" ...", stderr);
  }
  fputc('\n', stderr);
done:
  for (unsigned i = 0; i < n; i++) {
    csv_free(&pts[i].stats);
    csv_free(&pts[i].swept);
    free(names[i]);
  }
  for (unsigned i = 0; i < npartial; i++) free(partial[i]);
  free(pts);
  free(names);
  free(partial);
  free(cols);
  return rc;
}
