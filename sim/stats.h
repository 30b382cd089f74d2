/* Numbers a run reports: a table of named scalars written as one tidy CSV row
 * or as JSON members (histograms are in hist.h). Names carry
 * their units (_cycles, _bytes, _fraction); counters are integers, ratios are
 * computed once at the end. */
#ifndef RTSIM_SIM_STATS_H
#define RTSIM_SIM_STATS_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

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
 * config values are written at 1 and measured numbers at 15, as they always
 * were, so outputs compare byte for byte with older ones. buf: 32 bytes. */
void stats_f64_text(double v, int min_digits, char *buf, size_t cap);
/* A double as JSON: stats_f64_text at 15 digits. Not always the shortest form,
 * but stable: outputs compare byte for byte. */
void stats_write_json_f64(FILE *f, double v);

#endif
