/* Tidy CSV tables read whole: a header row of column names, then rows of text
 * cells (RFC 4180 quoting, as stats_write_csv_str writes it). Every cell keeps
 * its 1-based line and column so a bad value is reported where it stands. Used
 * by rtsim merge (stats.csv, point.csv) and rtsim plot (merged tables). */
#ifndef RTSIM_APP_CSV_H
#define RTSIM_APP_CSV_H

#include <stdbool.h>
#include <stddef.h>

struct err;

struct csv_table {
  char file[512];
  char **names; /* ncols column names (owned) */
  unsigned ncols;
  char **cells;      /* nrows x ncols, row-major (owned); "" for an empty cell */
  int *lines, *cols; /* position of each cell (nrows x ncols) */
  unsigned nrows;
};

/* Read a whole regular file into a NUL-terminated buffer (caller frees), its
 * length in *len; NULL on failure, with the reason in *why. What csv_read
 * and the readers of stats.json start from. */
char *csv_slurp(const char *path, size_t *len, const char **why);

/* Read the CSV file at path. A missing or empty file, a NUL byte, an
 * unterminated quote, a duplicate or empty column name, or a row whose field
 * count differs from the header's fails with file:line:col in e; t is then
 * empty (safe to free). Rows are read whole, however long. */
bool csv_read(struct csv_table *t, const char *path, struct err *e);
void csv_free(struct csv_table *t);

/* Index of column `name`, or -1. */
int csv_column(const struct csv_table *t, const char *name);
/* Cell (row, col) text. */
const char *csv_cell(const struct csv_table *t, unsigned row, unsigned col);

/* Natural order of two texts: digit runs compare as numbers, so
 * rays_per_thread=2 comes before rays_per_thread=16. */
int csv_natural_cmp(const char *a, const char *b);
/* The whole of s as a finite decimal number (sim/scalar.h: no whitespace
 * around it, no leading zero). */
bool csv_number(const char *s, double *out);

/* The top-level member `key` of an rtsim stats.json (the text, whole) as
 * text: a string unescaped, a number or literal as written; into out (cap
 * bytes, cut to fit). False when the member is absent or not a scalar. Only
 * what rtsim run writes is read: a member at the top level stands alone on
 * its line, indented two spaces. */
bool csv_json_member(const char *json, const char *key, char *out, unsigned cap);

#endif
