/* Dinero IV din trace writer and reader. The writer formats records by hand into
 * its own buffer (no printf per record: traces run to billions of records) and
 * writes to a temporary renamed on success, so a half trace never looks whole. */
#include "sim/din.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sim/err.h"
#include "sim/outfile.h"

enum { DIN_BUF_BYTES = 1 << 16, DIN_RECORD_MAX = 2 + 16 + 1 };

struct din_writer {
  struct outfile out;
  unsigned lg2_line;
  int write_errno; /* first write error, 0 if none */
  uint64_t records;
  size_t used;
  char buf[DIN_BUF_BYTES];
};

static void writer_flush(struct din_writer *w) {
  if (w->used && !w->write_errno && fwrite(w->buf, 1, w->used, w->out.f) != w->used)
    w->write_errno = errno ? errno : EIO;
  w->used = 0;
}

struct din_writer *din_writer_open(const char *path, unsigned lg2_line, struct err *e) {
  CHECK_GE(lg2_line, 2);
  CHECK_LE(lg2_line, 20);
  struct din_writer *w = xcalloc(1, sizeof *w);
  if (!outfile_open(&w->out, path, "din trace", e)) {
    free(w);
    return NULL;
  }
  w->lg2_line = lg2_line;
  return w;
}

void din_writer_record(struct din_writer *w, uint64_t addr, bool is_store) {
  if (w->used + DIN_RECORD_MAX > DIN_BUF_BYTES) writer_flush(w);
  static const char hex[] = "0123456789abcdef";
  char digits[16];
  int nd = 0;
  do {
    digits[nd++] = hex[addr & 15];
    addr >>= 4;
  } while (addr);
  char *o = w->buf + w->used;
  *o++ = is_store ? '1' : '0';
  *o++ = ' ';
  while (nd) *o++ = digits[--nd];
  *o++ = '\n';
  w->used = (size_t)(o - w->buf);
  w->records++;
}

void din_writer_access(struct din_writer *w, uint64_t addr, uint32_t size_bytes, bool is_store) {
  CHECK_GT(size_bytes, 0);
  uint64_t last = addr + (size_bytes - 1);
  CHECK_GE(last, addr); /* no wrap past 2^64 */
  uint64_t line = addr >> w->lg2_line, end = last >> w->lg2_line;
  din_writer_record(w, addr, is_store);
  while (line != end) {
    line++;
    din_writer_record(w, line << w->lg2_line, is_store);
  }
}

uint64_t din_writer_records(const struct din_writer *w) { return w->records; }

bool din_writer_close(struct din_writer *w, struct err *e) {
  if (!w) return true;
  writer_flush(w);
  bool ok;
  if (w->write_errno) {
    err_set(e, w->out.path, 0, 0, "cannot write din trace: %s", strerror(w->write_errno));
    outfile_abort(&w->out);
    ok = false;
  } else {
    ok = outfile_commit(&w->out, e);
  }
  free(w);
  return ok;
}

void din_writer_discard(struct din_writer *w) {
  if (!w) return;
  outfile_abort(&w->out);
  free(w);
}

static int hex_value(int c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

static bool is_blank(int c) { return c == ' ' || c == '\t' || c == '\r'; }

static bool is_end(int c) { return c == '\0' || c == '\n'; }

/* Describe a character for a message. */
static const char *char_name(int c, char *buf, size_t cap) {
  if (is_end(c)) return "end of line";
  if (c >= 0x21 && c < 0x7f) snprintf(buf, cap, "'%c'", c);
  else snprintf(buf, cap, "byte 0x%02x", (unsigned)(unsigned char)c);
  return buf;
}

/* Parse one record from s (NUL-terminated, may end in '\n'). */
static bool parse_record(const char *path, int lineno, const char *s, unsigned *label,
                         uint64_t *addr, struct err *e) {
  char what[16];
  size_t i = 0;
  while (is_blank(s[i])) i++;
  if (is_end(s[i])) return err_set(e, path, lineno, (int)i + 1, "din: missing label (blank line)");
  size_t label_col = i;
  uint64_t v = 0;
  if (s[i] == '0' && (s[i + 1] == 'x' || s[i + 1] == 'X')) i += 2;
  if (hex_value(s[i]) < 0)
    return err_set(e, path, lineno, (int)i + 1, "din: bad label (got %s, expected a hex digit 0-5)",
                   char_name(s[i], what, sizeof what));
  while (hex_value(s[i]) >= 0) {
    if (v <= DIN_LABEL_MAX) v = v * 16 + (uint64_t)hex_value(s[i]);
    i++;
  }
  if (!is_blank(s[i]) && !is_end(s[i]))
    return err_set(e, path, lineno, (int)i + 1,
                   "din: bad label (got %s, expected a hex digit or a blank)",
                   char_name(s[i], what, sizeof what));
  if (v > DIN_LABEL_MAX)
    return err_set(e, path, lineno, (int)label_col + 1,
                   "din: unknown label (expected 0 read, 1 write, 2 instruction fetch, 3 misc, "
                   "4 copy-back or 5 invalidate)");
  *label = (unsigned)v;
  while (is_blank(s[i])) i++;
  if (is_end(s[i])) return err_set(e, path, lineno, (int)i + 1, "din: missing address");
  if (s[i] == '0' && (s[i + 1] == 'x' || s[i + 1] == 'X')) i += 2;
  if (hex_value(s[i]) < 0)
    return err_set(e, path, lineno, (int)i + 1, "din: bad address (got %s, expected a hex digit)",
                   char_name(s[i], what, sizeof what));
  size_t addr_col = i;
  v = 0;
  bool overflow = false;
  for (; hex_value(s[i]) >= 0; i++) {
    if (v >> 60) overflow = true;
    v = v << 4 | (uint64_t)hex_value(s[i]);
  }
  if (!is_blank(s[i]) && !is_end(s[i]))
    return err_set(e, path, lineno, (int)i + 1, "din: bad address (got %s, expected a hex digit)",
                   char_name(s[i], what, sizeof what));
  if (overflow) return err_set(e, path, lineno, (int)addr_col + 1, "din: address beyond 64 bits");
  *addr = v;
  return true; /* the rest of the line is a comment, as in Dinero */
}

bool din_read_file(const char *path, din_record_fn fn, void *ctx, uint64_t *records_out,
                   struct err *e) {
  uint64_t records = 0;
  if (records_out) *records_out = 0;
  const char *why;
  FILE *f = err_fopen_regular(path, &why);
  if (!f) return err_set(e, path, 0, 0, "cannot open din trace: %s", why);
  bool ok = true;
  char *line = NULL;
  size_t cap = 0;
  ssize_t len;
  int lineno = 0;
  errno = 0;
  while ((len = getline(&line, &cap, f)) >= 0) {
    lineno++;
    if (memchr(line, '\0', (size_t)len)) {
      ok = err_set(e, path, lineno, (int)strlen(line) + 1, "din: NUL byte in trace");
      goto done;
    }
    unsigned label = 0;
    uint64_t addr = 0;
    if (!parse_record(path, lineno, line, &label, &addr, e)) {
      ok = false;
      goto done;
    }
    fn(ctx, label, addr);
    records++;
  }
  if (ferror(f)) ok = err_set(e, path, lineno + 1, 0, "cannot read din trace: %s", strerror(errno));
done:
  free(line);
  fclose(f);
  if (records_out) *records_out = records;
  return ok;
}
