/* CSV tables (csv.h): the whole file is read, then split into fields with
 * their positions; rows must match the header's width. */
#include "app/csv.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sim/err.h"
#include "sim/scalar.h"

char *csv_slurp(const char *path, size_t *len, const char **why) {
  FILE *f = err_fopen_regular(path, why);
  if (!f) return NULL;
  size_t cap = 1 << 14, n = 0;
  char *buf = xmalloc(cap);
  size_t got;
  while ((got = fread(buf + n, 1, cap - n - 1, f)) > 0) {
    n += got;
    if (cap - n - 1 == 0) buf = xrealloc(buf, cap *= 2);
  }
  bool bad = ferror(f);
  if (bad) *why = strerror(errno);
  fclose(f);
  if (bad) {
    free(buf);
    return NULL;
  }
  buf[n] = '\0';
  *len = n;
  return buf;
}

/* Growing arrays of fields of the row being read and of the table. */
struct builder {
  char **cells;
  int *lines, *cols;
  unsigned n, cap;
};

static void push(struct builder *b, char *cell, int line, int col) {
  if (b->n == b->cap) {
    b->cap = b->cap ? 2 * b->cap : 64;
    b->cells = xrealloc(b->cells, (unsigned long long)b->cap * sizeof *b->cells);
    b->lines = xrealloc(b->lines, (unsigned long long)b->cap * sizeof *b->lines);
    b->cols = xrealloc(b->cols, (unsigned long long)b->cap * sizeof *b->cols);
  }
  b->cells[b->n] = cell;
  b->lines[b->n] = line;
  b->cols[b->n] = col;
  b->n++;
}

bool csv_read(struct csv_table *t, const char *path, struct err *e) {
  memset(t, 0, sizeof *t);
  snprintf(t->file, sizeof t->file, "%s", path);
  size_t size = 0;
  const char *why;
  char *text = csv_slurp(path, &size, &why);
  if (!text) return err_set(e, path, 0, 0, "cannot read: %s", why);
  /* A NUL byte would end the text there, and the rows after it with it. */
  const char *nul = memchr(text, '\0', size);
  if (nul) {
    int nl = 1, nc = 1;
    for (const char *q = text; q < nul; q++) {
      if (*q == '\n') nl++, nc = 1;
      else nc++;
    }
    free(text);
    return err_set(e, path, nl, nc, "a NUL byte (expected text: a CSV holds none)");
  }
  struct builder all = {0};
  bool ok = true;
  unsigned row_start = 0, width = 0, rows = 0;
  int line = 1, col = 1;
  const char *p = text;
  while (ok && *p) {
    /* One row: fields until an unquoted line break or the end. Blank lines
     * are not rows. */
    if (*p == '\n' || (*p == '\r' && p[1] == '\n')) {
      p += *p == '\r' ? 2 : 1;
      line++;
      continue;
    }
    row_start = all.n;
    int row_line = line;
    for (;;) {
      int fl = line, fc = col;
      size_t cap = 16, len = 0;
      char *cell = xmalloc(cap);
      if (*p == '"') {
        p++, col++;
        for (;;) {
          if (!*p) {
            ok = err_set(e, path, fl, fc, "unterminated quoted field");
            break;
          }
          if (*p == '"' && p[1] != '"') {
            p++, col++;
            break;
          }
          if (*p == '"') p++, col++;
          if (*p == '\n') line++, col = 0;
          if (len + 2 > cap) cell = xrealloc(cell, cap *= 2);
          cell[len++] = *p++;
          col++;
        }
      } else {
        while (*p && *p != ',' && *p != '\n' && !(*p == '\r' && p[1] == '\n')) {
          if (len + 2 > cap) cell = xrealloc(cell, cap *= 2);
          cell[len++] = *p++;
          col++;
        }
      }
      cell[len] = '\0';
      push(&all, cell, fl, fc);
      if (!ok) break;
      if (*p == ',') {
        p++, col++;
        continue;
      }
      if (*p == '\r') p++;
      if (*p == '\n') p++, line++, col = 1;
      else if (*p) ok = err_set(e, path, line, col, "unexpected text after a quoted field");
      break;
    }
    if (!ok) break;
    unsigned fields = all.n - row_start;
    if (rows == 0) {
      width = fields;
    } else if (fields != width) {
      ok = err_set(e, path, row_line, 1, "row has %u fields, the header has %u", fields, width);
      break;
    }
    rows++;
  }
  free(text);
  if (ok && rows == 0) ok = err_set(e, path, 0, 0, "empty file (expected a header row)");
  for (unsigned i = 0; ok && i < width; i++) {
    if (!all.cells[i][0]) ok = err_set(e, path, all.lines[i], all.cols[i], "empty column name");
    for (unsigned j = 0; ok && j < i; j++)
      if (!strcmp(all.cells[i], all.cells[j]))
        ok = err_set(e, path, all.lines[i], all.cols[i], "column '%s' appears twice", all.cells[i]);
  }
  if (!ok) {
    for (unsigned i = 0; i < all.n; i++) free(all.cells[i]);
    free(all.cells);
    free(all.lines);
    free(all.cols);
    return false;
  }
  /* The header's cells become the names; the rest stay as the cells. */
  t->ncols = width;
  t->nrows = rows - 1;
  t->names = xmalloc((unsigned long long)width * sizeof *t->names);
  memcpy(t->names, all.cells, width * sizeof *t->names);
  unsigned n = all.n - width;
  t->cells = xmalloc((unsigned long long)(n ? n : 1) * sizeof *t->cells);
  t->lines = xmalloc((unsigned long long)(n ? n : 1) * sizeof *t->lines);
  t->cols = xmalloc((unsigned long long)(n ? n : 1) * sizeof *t->cols);
  memcpy(t->cells, all.cells + width, n * sizeof *t->cells);
  memcpy(t->lines, all.lines + width, n * sizeof *t->lines);
  memcpy(t->cols, all.cols + width, n * sizeof *t->cols);
  free(all.cells);
  free(all.lines);
  free(all.cols);
  return true;
}

void csv_free(struct csv_table *t) {
  if (!t) return;
  for (unsigned i = 0; i < t->ncols; i++) free(t->names[i]);
  for (unsigned i = 0; i < t->nrows * t->ncols; i++) free(t->cells[i]);
  free(t->names);
  free(t->cells);
  free(t->lines);
  free(t->cols);
  memset(t, 0, sizeof *t);
}

int csv_column(const struct csv_table *t, const char *name) {
  for (unsigned i = 0; i < t->ncols; i++)
    if (!strcmp(t->names[i], name)) return (int)i;
  return -1;
}

const char *csv_cell(const struct csv_table *t, unsigned row, unsigned col) {
  return t->cells[(size_t)row * t->ncols + col];
}

int csv_natural_cmp(const char *a, const char *b) {
  while (*a && *b) {
    if (*a >= '0' && *a <= '9' && *b >= '0' && *b <= '9') {
      while (*a == '0') a++;
      while (*b == '0') b++;
      size_t la = strspn(a, "0123456789"), lb = strspn(b, "0123456789");
      if (la != lb) return la < lb ? -1 : 1;
      int c = strncmp(a, b, la);
      if (c) return c;
      a += la, b += lb;
      continue;
    }
    if (*a != *b) return (unsigned char)*a < (unsigned char)*b ? -1 : 1;
    a++, b++;
  }
  return *a ? 1 : *b ? -1 : 0;
}

bool csv_number(const char *s, double *out) { return scalar_f64(s, out) == SCALAR_OK; }

bool csv_json_member(const char *json, const char *key, char *out, unsigned cap) {
  char pat[256];
  snprintf(pat, sizeof pat, "\n  \"%s\": ", key);
  const char *p = strstr(json, pat);
  if (!p || cap == 0) return false;
  p += strlen(pat);
  unsigned n = 0;
  if (*p != '"') {
    while (*p && *p != ',' && *p != '\n' && *p != '}' && *p != '{' && *p != '[' && n + 1 < cap)
      out[n++] = *p++;
    out[n] = '\0';
    return n > 0;
  }
  for (p++; *p && *p != '"'; p++) {
    char c = *p;
    if (c == '\\' && p[1]) {
      c = *++p;
      if (c == 'n') c = '\n';
      else if (c == 't') c = '\t';
      else if (c == 'u') { /* rtsim writes only control characters so: kept as '?' */
        for (int k = 0; k < 4 && p[1]; k++) p++;
        c = '?';
      }
    }
    if (n + 1 < cap) out[n++] = c;
  }
  out[n] = '\0';
  return *p == '"';
}
