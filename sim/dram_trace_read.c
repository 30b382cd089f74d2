/* The DRAM trace reader (sim/dram_trace_read.h): a line at a time into a
 * bounded buffer, split at blanks into fields; the first request line fixes
 * the format (its number of fields) for the whole trace. Messages point at
 * the offending field's column, quoting at most ECHO_MAX bytes of it. */
#include "sim/dram_trace_read.h"

#include <errno.h>
#include <stddef.h>
#include <string.h>

#include "sim/err.h"
#include "sim/line.h"

#define FIELDS_MAX 6 /* fields kept of a line (one past the most allowed) */
#define ECHO_MAX 40  /* bytes of a bad field quoted in a message */

struct field {
  const char *s;
  size_t len;
  int col; /* 1-based */
};

void dram_trace_reader_init(struct dram_trace_reader *r, FILE *f, const char *path,
                            struct dram_clock clock, struct err *e) {
  memset(r, 0, sizeof *r);
  r->f = f;
  r->path = path;
  r->e = e;
  r->clock = clock;
  r->dram_cycle_max = UINT64_MAX;
}

void dram_trace_reader_refresh(struct dram_trace_reader *r, uint64_t refresh_every,
                               unsigned channels) {
  r->refresh_every = refresh_every;
  r->dram_cycle_max = DRAM_TRACE_REFRESHES_MAX / channels * refresh_every;
}

static int line_no(const struct dram_trace_reader *r) {
  return r->line > 2147483647ul ? 2147483647 : (int)r->line;
}

/* Quote at most ECHO_MAX bytes of a field for a message. */
static const char *echo(const struct field *f, char *buf, size_t cap) {
  size_t n = f->len < ECHO_MAX ? f->len : ECHO_MAX;
  snprintf(buf, cap, "'%.*s%s'", (int)n, f->s, n < f->len ? "..." : "");
  return buf;
}

static bool is_blank(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

/* A whole decimal number below 2^64. */
static bool parse_dec(const struct field *f, uint64_t *out) {
  uint64_t v = 0;
  if (f->len == 0) return false;
  for (size_t i = 0; i < f->len; i++) {
    char c = f->s[i];
    if (c < '0' || c > '9') return false;
    uint64_t d = (uint64_t)(c - '0');
    if (v > (UINT64_MAX - d) / 10) return false;
    v = v * 10 + d;
  }
  *out = v;
  return true;
}

/* 0x (or 0X) and hexadecimal digits, or decimal; below 2^64 either way. */
static bool parse_addr(const struct field *f, uint64_t *out) {
  if (f->len > 2 && f->s[0] == '0' && (f->s[1] == 'x' || f->s[1] == 'X')) {
    uint64_t v = 0;
    for (size_t i = 2; i < f->len; i++) {
      char c = f->s[i];
      unsigned d;
      if (c >= '0' && c <= '9') d = (unsigned)(c - '0');
      else if (c >= 'a' && c <= 'f') d = (unsigned)(c - 'a' + 10);
      else if (c >= 'A' && c <= 'F') d = (unsigned)(c - 'A' + 10);
      else return false;
      if (v >> 60) return false;
      v = v << 4 | d;
    }
    *out = v;
    return true;
  }
  return parse_dec(f, out);
}

static bool parse_op(const struct field *f, bool *write) {
  static const struct {
    const char *name;
    bool write;
  } ops[] = {{"READ", false}, {"WRITE", true}, {"R", false}, {"W", true}};
  for (size_t i = 0; i < sizeof ops / sizeof ops[0]; i++)
    if (f->len == strlen(ops[i].name) && !memcmp(f->s, ops[i].name, f->len)) {
      *write = ops[i].write;
      return true;
    }
  return false;
}

/* Read one line into r->buf: 1 and its length, 0 at the end of the file, -1
 * on a line too long or a read error (e set). */
static int read_line(struct dram_trace_reader *r, size_t *len) {
  size_t n = 0;
  int c;
  while ((c = getc(r->f)) != EOF && c != '\n') {
    if (n == 0) r->line++;
    if (n == DRAM_TRACE_LINE_MAX)
      return err_set(r->e, r->path, line_no(r), DRAM_TRACE_LINE_MAX + 1,
                     "line too long (got more than %d bytes, expected at most %d)",
                     DRAM_TRACE_LINE_MAX, DRAM_TRACE_LINE_MAX),
             -1;
    r->buf[n++] = (char)c;
  }
  if (c == EOF && ferror(r->f))
    return err_set(r->e, r->path, 0, 0, "cannot read: %s", strerror(errno)), -1;
  if (c == EOF && n == 0) return 0;
  if (n == 0) r->line++; /* an empty line */
  *len = n;
  return 1;
}

int dram_trace_next(struct dram_trace_reader *r, struct dram_trace_request *q) {
  char got[ECHO_MAX + 8];
  for (;;) {
    size_t len;
    int rc = read_line(r, &len);
    if (rc <= 0) return rc;
    struct field f[FIELDS_MAX];
    unsigned n = 0;
    size_t i = 0;
    while (i < len) {
      while (i < len && is_blank(r->buf[i])) i++;
      if (i == len) break;
      size_t start = i;
      while (i < len && !is_blank(r->buf[i])) i++;
      if (n < FIELDS_MAX) f[n] = (struct field){r->buf + start, i - start, (int)start + 1};
      n++;
    }
    if (n == 0 || f[0].s[0] == '#') continue;
    const int line = line_no(r);
    /* Where a missing field would begin: one past the line's end. */
    const int end_col = (int)len + 1;
    if (r->fields && n != r->fields)
      return err_set(r->e, r->path, line, n < r->fields ? end_col : f[r->fields].col,
                     "wrong number of fields (got %u, expected %u as on line %lu: one format a "
                     "trace)",
                     n, r->fields, r->format_line),
             -1;
    if (n < 2)
      return err_set(r->e, r->path, line, end_col,
                     "too few fields (got %u, expected 2 (0xADDR R|W), 3 (0xADDR READ|WRITE "
                     "DRAM_CYCLE) or 5 (rtsim's trace))",
                     n),
             -1;
    if (n == 4 || n > 5)
      return err_set(r->e, r->path, line, f[n == 4 ? 3 : 5].col,
                     "wrong number of fields (got %u, expected 2 (0xADDR R|W), 3 (0xADDR "
                     "READ|WRITE DRAM_CYCLE) or 5 (rtsim's trace))",
                     n),
             -1;
    if (!r->fields) {
      r->fields = n;
      r->format_line = r->line;
    }
    uint64_t addr;
    if (!parse_addr(&f[0], &addr))
      return err_set(r->e, r->path, line, f[0].col,
                     "address: not a number (got %s, expected 0x and hexadecimal digits, or "
                     "decimal digits, below 2^64)",
                     echo(&f[0], got, sizeof got)),
             -1;
    if (!parse_op(&f[1], &q->write))
      return err_set(r->e, r->path, line, f[1].col,
                     "operation: unknown (got %s, expected READ, WRITE, R or W)",
                     echo(&f[1], got, sizeof got)),
             -1;
    q->addr = addr & ~(uint64_t)(SIM_LINE_BYTES - 1);
    /* The arrival as written: Ramulator's is the request's index, in DRAM cycles. */
    uint64_t v = r->requests;
    if (n > 2) {
      const struct field *at = &f[n == 3 ? 2 : 3];
      const char *what = n == 3 ? "arrival DRAM cycle" : "arrival cycle";
      if (!parse_dec(at, &v) || v > DRAM_TRACE_CYCLE_MAX)
        return err_set(r->e, r->path, line, at->col,
                       "%s: not a cycle (got %s, expected a whole number from 0 to %llu)", what,
                       echo(at, got, sizeof got), DRAM_TRACE_CYCLE_MAX),
               -1;
      if (r->requests && v < r->last_at)
        return err_set(r->e, r->path, line, at->col,
                       "%s: earlier than the request before (got %llu, expected at least %llu)",
                       what, (unsigned long long)v, (unsigned long long)r->last_at),
               -1;
    }
    q->arrival = n == 5 ? v : dram_clock_to_core(r->clock, v);
    /* A fast core against a slow DRAM clock multiplies DRAM cycles. */
    if (q->arrival > DRAM_TRACE_CYCLE_MAX)
      return err_set(r->e, r->path, line, n == 3 ? f[2].col : f[0].col,
                     "arrival DRAM cycle: too late (got %llu, core cycle %llu; expected at most "
                     "core cycle %llu)",
                     (unsigned long long)v, (unsigned long long)q->arrival, DRAM_TRACE_CYCLE_MAX),
             -1;
    /* A banked DRAM with refresh steps through every refresh until then. */
    const uint64_t dram_at = n == 5 ? dram_clock_from_core(r->clock, v) : v;
    if (dram_at > r->dram_cycle_max)
      return err_set(r->e, r->path, line, n == 2 ? f[0].col : f[n == 3 ? 2 : 3].col,
                     "%s: too late for the replay (got DRAM cycle %llu, expected at most %llu: "
                     "the DRAM refreshes every tREFI / ranks = %llu DRAM cycles on each channel "
                     "and the replay steps through every refresh, at most %llu in all; "
                     "--set dram.tREFI=0 turns refresh off)",
                     n == 2   ? "request"
                     : n == 3 ? "arrival DRAM cycle"
                              : "arrival cycle",
                     (unsigned long long)dram_at, (unsigned long long)r->dram_cycle_max,
                     (unsigned long long)r->refresh_every, DRAM_TRACE_REFRESHES_MAX),
             -1;
    r->last_at = v;
    r->requests++;
    return 1;
  }
}

const char *dram_trace_format(const struct dram_trace_reader *r) {
  static const char *const formats[6] = {NULL, NULL, "ramulator", "dramsim3", NULL, "rtsim"};
  return r->fields < 6 ? formats[r->fields] : NULL;
}
