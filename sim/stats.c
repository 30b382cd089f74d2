/* Tables of named scalars and their CSV and JSON forms. */
#include "sim/stats.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sim/err.h"
#include "sim/hist.h"

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

void stats_u64(struct stats_table *t, const char *name, uint64_t v) {
  add(t, name, STATS_U64)->u = v;
}

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

/* ---- descriptors ---- */

static void emit_one(struct stats_table *t, const struct stats_desc *d, const void *st,
                     const struct stats_env *env, unsigned cls) {
  char name[64];
  if (d->per_class) snprintf(name, sizeof name, d->name, env->class_names[cls]);
  else snprintf(name, sizeof name, "%s", d->name);
  const unsigned char *base = (const unsigned char *)st;
  switch (d->how) {
  case STATS_HOW_FIELD: {
    uint64_t v;
    memcpy(&v, base + d->off + (size_t)cls * sizeof v, sizeof v);
    stats_u64(t, name, v);
    break;
  }
  case STATS_HOW_U64: stats_u64(t, name, d->u64(st, env)); break;
  case STATS_HOW_DOUBLE: {
    double v;
    memcpy(&v, base + d->off, sizeof v);
    stats_f64(t, name, v);
    break;
  }
  case STATS_HOW_F64: stats_f64(t, name, d->f64(st, env)); break;
  case STATS_HOW_HIST_MEAN: stats_f64(t, name, hist_mean((const void *)(base + d->off))); break;
  case STATS_HOW_HIST_Q:
    stats_u64(t, name, hist_quantile((const void *)(base + d->off), d->q));
    break;
  case STATS_HOW_AT: break;
  }
}

static bool has_place(const struct stats_descs *g, const char *at) {
  for (unsigned i = 0; i < g->n; i++)
    if (g->d[i].how == STATS_HOW_AT && strcmp(g->d[i].at, at) == 0) return true;
  return false;
}

static void emit_table(struct stats_table *t, const struct stats_descs *g, const void *st,
                       const struct stats_env *env);

/* The parts registered for place `at`, each with its own ctx. */
static void emit_place(struct stats_table *t, const char *at, const struct stats_env *env) {
  for (unsigned j = 0; j < env->nparts; j++) {
    const struct stats_part *p = &env->parts[j];
    if (strcmp(p->at, at) != 0) continue;
    struct stats_env sub = *env;
    if (p->ctx) sub.ctx = p->ctx;
    emit_table(t, p->g, p->st, &sub);
  }
}

static void emit_table(struct stats_table *t, const struct stats_descs *g, const void *st,
                       const struct stats_env *env) {
  for (unsigned i = 0; i < g->n; i++) {
    const struct stats_desc *d = &g->d[i];
    if (d->how == STATS_HOW_AT) {
      emit_place(t, d->at, env);
      continue;
    }
    if (d->present && !d->present(st, env)) continue;
    if (!d->per_class) {
      emit_one(t, d, st, env, 0);
      continue;
    }
    CHECK(d->how == STATS_HOW_FIELD);
    CHECK_LE((uint64_t)env->classes * sizeof(uint64_t), d->size);
    for (unsigned c = 0; c < env->classes; c++) emit_one(t, d, st, env, c);
  }
}

void stats_emit(struct stats_table *t, const struct stats_descs *g, const void *st,
                const struct stats_env *env) {
  /* A part registered for a place no table has would vanish from the output. */
  for (unsigned j = 0; j < env->nparts; j++) {
    bool found = has_place(g, env->parts[j].at);
    for (unsigned k = 0; k < env->nparts && !found; k++)
      found = has_place(env->parts[k].g, env->parts[j].at);
    CHECK(found);
  }
  emit_table(t, g, st, env);
}

/* Mark the bytes g's descriptors read, and its skips, at base in seen[0..size). */
static void mark(const struct stats_descs *g, size_t base, size_t size, unsigned char *seen) {
  for (unsigned i = 0; i < g->n; i++) {
    CHECK_LE(base + g->d[i].off + g->d[i].size, size);
    memset(seen + base + g->d[i].off, 1, g->d[i].size);
  }
  for (unsigned i = 0; i < g->nskip; i++) {
    const struct stats_skip *k = &g->skip[i];
    CHECK_LE(base + k->off + k->size, size);
    CHECK(k->why && k->why[0]);
    if (!k->by) {
      memset(seen + base + k->off, 1, k->size);
    } else if (k->by->struct_size) {
      CHECK_EQ(k->by->struct_size, k->size);
      mark(k->by, base + k->off, size, seen);
    } else {
      /* by's descriptors are about this same struct: they must cover the skip */
      for (unsigned j = 0; j < k->by->n; j++) {
        const struct stats_desc *d = &k->by->d[j];
        if (d->off >= k->off && d->off + d->size <= k->off + k->size)
          memset(seen + base + d->off, 1, d->size);
      }
    }
  }
}

const char *stats_uncovered(const struct stats_descs *g, char *buf, size_t len) {
  if (g->struct_size == 0) return NULL;
  unsigned char *seen = xcalloc(1, g->struct_size);
  mark(g, 0, g->struct_size, seen);
  const char *r = NULL;
  for (size_t b = 0; b < g->struct_size && !r; b++)
    if (!seen[b]) {
      size_t e = b;
      while (e < g->struct_size && !seen[e]) e++;
      snprintf(buf, len,
               "%s: bytes %zu..%zu of its stats struct (%zu bytes) are neither written "
               "by a descriptor nor listed as skipped",
               g->component, b, e - 1, g->struct_size);
      r = buf;
    }
  free(seen);
  return r;
}

static void help_name(const struct stats_desc *d, char *buf, size_t len) {
  if (d->per_class) snprintf(buf, len, d->name, "<class>");
  else snprintf(buf, len, "%s", d->name);
}

void stats_write_help(const struct stats_descs *g, FILE *f) {
  for (unsigned i = 0; i < g->n; i++) {
    const struct stats_desc *d = &g->d[i];
    if (d->how == STATS_HOW_AT) continue;
    char name[64];
    help_name(d, name, sizeof name);
    fprintf(f, "%-36s %-16s %s: %s\n", name, d->unit, g->component, d->desc);
  }
}

void stats_write_markdown(const struct stats_descs *g, FILE *f) {
  for (unsigned i = 0; i < g->n; i++) {
    const struct stats_desc *d = &g->d[i];
    if (d->how == STATS_HOW_AT) continue;
    char name[64];
    help_name(d, name, sizeof name);
    fprintf(f, "| `%s` | %s | %s | %s |\n", name, d->unit, g->component, d->desc);
  }
}
