/* Numbers a run reports: a table of named scalars written as one tidy CSV row
 * or as JSON members (histograms are in hist.h). Names carry
 * their units (_cycles, _bytes, _fraction); counters are integers, ratios are
 * computed once at the end. */
#ifndef RTSIM_SIM_STATS_H
#define RTSIM_SIM_STATS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

/* a / b, 0 when b is not positive (a figure of an empty run): every ratio a
 * table reports. */
static inline double stats_ratio(double a, double b) { return b > 0 ? a / b : 0.0; }

/* A table of scalars in insertion order. */
enum stats_kind { STATS_U64, STATS_F64, STATS_STR };
struct stats_entry {
  char name[64];
  enum stats_kind kind;
  uint64_t u;
  double f;
  char s[256];
};
struct stats_table {
  struct stats_entry *e;
  unsigned n, cap;
};

void stats_u64(struct stats_table *t, const char *name, uint64_t v);
void stats_f64(struct stats_table *t, const char *name, double v); /* non-finite: CHECK */
void stats_str(struct stats_table *t, const char *name, const char *v);
void stats_fini(struct stats_table *t);

/* "name,name,...\n" and "value,value,...\n" (strings quoted when needed). */
void stats_write_csv_header(const struct stats_table *t, FILE *f);
void stats_write_csv_row(const struct stats_table *t, FILE *f);
/* One CSV field: s as is, or quoted (quotes doubled) when it holds a comma, a
 * quote or a line break (RFC 4180). */
void stats_write_csv_str(FILE *f, const char *s);
/* Members `"name": value` separated by ",\n" + indent (no braces), for the
 * caller to place inside an object. */
void stats_write_json_members(const struct stats_table *t, FILE *f, const char *indent);

/* A JSON string literal of s. */
void stats_write_json_str(FILE *f, const char *s);
/* v as %g text of the fewest significant digits, from min_digits (1 to 17)
 * up, that read back the same bits: rtsim's one double printer. NOTE: %g
 * turns to an exponent when the exponent reaches the precision, so the floor
 * shows: at 1, 1000 is "1e+03" and 0.1 + 0.2 "0.30000000000000004"; at 15,
 * 1386126720 stays "1386126720" and 5e-324 is "4.94065645841247e-324". Machine
 * config values are written at 1 and measured numbers at 15 (committed
 * results compare byte for byte with a new run only while both keep these
 * floors). buf: 32 bytes. */
void stats_f64_text(double v, int min_digits, char *buf, size_t cap);
/* A double as JSON: stats_f64_text at 15 digits. Not always the shortest form,
 * but stable: outputs compare byte for byte. */
void stats_write_json_f64(FILE *f, double v);

/* ---- descriptors: the numbers a component owns, declared once ----
 * A component keeps its counters as plain uint64_t fields of its stats struct
 * (incremented where they happen, no lookup) and declares them in one
 * constant table: the stats.json key and stats.csv column (its unit in it),
 * the unit, one line of description, and where the value lives (the field's
 * offset, or a function for a derived figure). Writers, `rtsim run
 * --help-stats` and docs/stats.md's table all walk the tables, in table order. */

enum stats_how {
  STATS_HOW_FIELD,     /* the uint64_t at off */
  STATS_HOW_U64,       /* u64(st, env) */
  STATS_HOW_F64,       /* f64(st, env) */
  STATS_HOW_DOUBLE,    /* the double at off */
  STATS_HOW_HIST_MEAN, /* the mean of the struct hist at off */
  STATS_HOW_HIST_Q,    /* its quantile q */
  STATS_HOW_AT         /* a place: the tables registered for it (env->parts) go here */
};

struct stats_descs;

/* Another component's table registered for a place (a STATS_AT entry) of a
 * table it does not know: its numbers are written there, read from st, with
 * ctx as its env's ctx (NULL: the caller's). Several parts at one place are
 * written in registration order. */
struct stats_part {
  const char *at;
  const struct stats_descs *g;
  const void *st;
  const void *ctx;
};

/* What derived figures may read besides the stats struct. */
struct stats_env {
  uint64_t cycles;                /* the run's length */
  const void *ctx;                /* the component's own (its parameters, clocks) */
  const char *const *class_names; /* data class names (the renderer's), for per-class numbers */
  unsigned classes;
  const struct stats_part *parts; /* the tables registered for the places */
  unsigned nparts;
};

struct stats_desc {
  const char *name; /* key and column; with per_class, a format with one %s (the class) */
  const char *unit; /* "cycles", "bytes", "fraction", "count", ... */
  const char *desc; /* one line */
  enum stats_how how;
  /* The bytes of the stats struct this entry reads: the field itself, or for a
   * function the field it is about (the lost-counter test covers the struct
   * with these spans). size 0: none (a place, or a figure of env alone). */
  size_t off, size;
  uint64_t (*u64)(const void *st, const struct stats_env *env);
  double (*f64)(const void *st, const struct stats_env *env);
  bool (*present)(const void *st, const struct stats_env *env); /* NULL: always written */
  const char *at;                                               /* STATS_HOW_AT: the place's name */
  double q;       /* STATS_HOW_HIST_Q: the quantile, 0 to 1 */
  bool per_class; /* one number per data class: field off + 8 x class */
};

/* Bytes of a stats struct another table writes (by), or deliberately not
 * written, and why: the lost-counter test accepts a field only with a
 * descriptor, another table's descriptor, or a reason here. by with a struct
 * of its own: that struct sits at off (size: its size); without: by's
 * descriptors read this same struct (off, size: the fields they cover). */
struct stats_skip {
  size_t off, size;
  const char *why;
  const struct stats_descs *by;
};

/* One component's table. struct_size: its stats struct's (0: its fields live
 * in another component's struct, which lists them as skips naming this table). */
struct stats_descs {
  const char *component;
  const struct stats_desc *d;
  unsigned n;
  size_t struct_size;
  const struct stats_skip *skip;
  unsigned nskip;
};

#define STATS_FIELD_SIZE(T, f) sizeof(((T *)0)->f)
/* A uint64_t counter written as it is. */
#define STATS_FIELD(T, f, nm, un, ds)                                                              \
  {                                                                                                \
    .name = nm, .unit = un, .desc = ds, .how = STATS_HOW_FIELD, .off = offsetof(T, f),             \
    .size = STATS_FIELD_SIZE(T, f)                                                                 \
  }
/* A double field written as it is. */
#define STATS_DOUBLE(T, f, nm, un, ds)                                                             \
  {                                                                                                \
    .name = nm, .unit = un, .desc = ds, .how = STATS_HOW_DOUBLE, .off = offsetof(T, f),            \
    .size = STATS_FIELD_SIZE(T, f)                                                                 \
  }
/* A figure derived by fn, about field f. */
#define STATS_F64(T, f, fn, nm, un, ds)                                                            \
  {                                                                                                \
    .name = nm, .unit = un, .desc = ds, .how = STATS_HOW_F64, .off = offsetof(T, f),               \
    .size = STATS_FIELD_SIZE(T, f), .f64 = fn                                                      \
  }
#define STATS_U64(T, f, fn, nm, un, ds)                                                            \
  {                                                                                                \
    .name = nm, .unit = un, .desc = ds, .how = STATS_HOW_U64, .off = offsetof(T, f),               \
    .size = STATS_FIELD_SIZE(T, f), .u64 = fn                                                      \
  }
/* A figure fn computes from the whole struct and the run (no one field). */
#define STATS_FN_U64(fn, nm, un, ds)                                                               \
  { .name = nm, .unit = un, .desc = ds, .how = STATS_HOW_U64, .u64 = fn }
#define STATS_FN_F64(fn, nm, un, ds)                                                               \
  { .name = nm, .unit = un, .desc = ds, .how = STATS_HOW_F64, .f64 = fn }
/* The mean, and quantile q_ (0 to 1), of histogram field f (a struct hist). */
#define STATS_HIST_MEAN(T, f, nm, un, ds)                                                          \
  {                                                                                                \
    .name = nm, .unit = un, .desc = ds, .how = STATS_HOW_HIST_MEAN, .off = offsetof(T, f),         \
    .size = STATS_FIELD_SIZE(T, f)                                                                 \
  }
#define STATS_HIST_Q(T, f, q_, nm, un, ds)                                                         \
  {                                                                                                \
    .name = nm, .unit = un, .desc = ds, .how = STATS_HOW_HIST_Q, .off = offsetof(T, f),            \
    .size = STATS_FIELD_SIZE(T, f), .q = q_                                                        \
  }
/* A place where the tables registered under `place` are written. */
#define STATS_AT(place)                                                                            \
  { .name = "", .unit = "", .desc = "", .how = STATS_HOW_AT, .at = place }
#define STATS_SKIP(T, f, reason)                                                                   \
  { offsetof(T, f), STATS_FIELD_SIZE(T, f), reason, NULL }
#define STATS_SKIP_BY(T, f, table)                                                                 \
  { offsetof(T, f), STATS_FIELD_SIZE(T, f), "another table", &(table) }
#define STATS_COUNT(a) ((unsigned)(sizeof(a) / sizeof((a)[0])))

/* Append g's numbers for stats struct st to t, in table order, with the
 * parts registered in env at their places (a part whose place is in neither
 * g nor another part's table: CHECK). */
void stats_emit(struct stats_table *t, const struct stats_descs *g, const void *st,
                const struct stats_env *env);
/* NULL if every byte of g's stats struct is read by a descriptor, its own or
 * a skip's other table's, or is a skip with a reason (or g has no struct of
 * its own); else a description of the first byte that is none, in buf. */
const char *stats_uncovered(const struct stats_descs *g, char *buf, size_t len);
/* One line per number: name, unit, description (places left out). */
void stats_write_help(const struct stats_descs *g, FILE *f);
/* The same as Markdown table rows `| name | unit | description |`. */
void stats_write_markdown(const struct stats_descs *g, FILE *f);

#endif
