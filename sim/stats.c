/* Tables of named scalars and their CSV and JSON forms. */
#include "sim/stats.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sim/err.h"

static struct stats_entry *add(struct stats_table *t, const char *name, enum stats_kind k) {
  CHECK_LT(strlen(name), sizeof t->e[0].name);
  if (t->n == t->cap) {
    t->cap = t->cap ? 2 * t->cap : 64;
    t->e = xrealloc(t->e, (unsigned long long)t->cap * sizeof *t->e);
  }
  struct stats_entry *x = &t->e[t->n++];
  memset(x, 0, sizeof *x);
  strcpy(x->name, name);
  x->kind = k;
  return x;
}

void stats_u64(struct stats_table *t, const char *name, uint64_t v) { add(t, name, STATS_U64)->u = v; }

void stats_f64(struct stats_table *t, const char *name, double v) {
  CHECK(isfinite(v));
  add(t, name, STATS_F64)->f = v;
}

void stats_str(struct stats_table *t, const char *name, const char *v) {
  struct stats_entry *x = add(t, name, STATS_STR);
  snprintf(x->s, sizeof x->s, "%s", v);
}

void stats_fini(struct stats_table *t) {
  free(t->e);
  memset(t, 0, sizeof *t);
}

void stats_f64_text(double v, int min_digits, char *buf, size_t cap) {
  for (int prec = min_digits; prec <= 17; prec++) {
    snprintf(buf, cap, "%.*g", prec, v);
    if (strtod(buf, NULL) == v) break;
  }
}

void stats_write_json_f64(FILE *f, double v) {
  char buf[64];
  stats_f64_text(v, 15, buf, sizeof buf);
  /* JSON has no bare "inf"/"nan"; stats_f64 refuses them, configs never hold them. */
  fputs(buf, f);
}

void stats_write_json_str(FILE *f, const char *s) {
  fputc('"', f);
  for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
    if (*p == '"' || *p == '\\') fprintf(f, "\\%c", *p);
    else if (*p < 0x20) fprintf(f, "\\u%04x", *p);
    else fputc(*p, f);
  }
  fputc('"', f);
}

void stats_write_csv_str(FILE *f, const char *s) {
  if (!strpbrk(s, ",\"\r\n")) {
    fputs(s, f);
    return;
  }
  fputc('"', f);
  for (const char *p = s; *p; p++) {
    if (*p == '"') fputc('"', f);
    fputc(*p, f);
  }
  fputc('"', f);
}

static void csv_value(const struct stats_entry *x, FILE *f) {
  switch (x->kind) {
  case STATS_U64: fprintf(f, "%llu", (unsigned long long)x->u); break;
  case STATS_F64: stats_write_json_f64(f, x->f); break;
  case STATS_STR: stats_write_csv_str(f, x->s); break;
  }
}

void stats_write_csv_header(const struct stats_table *t, FILE *f) {
  for (unsigned i = 0; i < t->n; i++) fprintf(f, "%s%s", i ? "," : "", t->e[i].name);
  fputc('\n', f);
}

void stats_write_csv_row(const struct stats_table *t, FILE *f) {
  for (unsigned i = 0; i < t->n; i++) {
    if (i) fputc(',', f);
    csv_value(&t->e[i], f);
  }
  fputc('\n', f);
}

void stats_write_json_members(const struct stats_table *t, FILE *f, const char *indent) {
  for (unsigned i = 0; i < t->n; i++) {
    const struct stats_entry *x = &t->e[i];
    fprintf(f, "%s%s", i ? ",\n" : "", indent);
    stats_write_json_str(f, x->name);
    fputs(": ", f);
    if (x->kind == STATS_STR) stats_write_json_str(f, x->s);
    else csv_value(x, f);
  }
}
