/* User-error records and the fatal paths for broken invariants and allocation. */
#include "sim/err.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* src into dst (cap bytes, cut to fit) with control characters written as
 * C escapes ("\n", "\x01"): the message quotes what the user wrote (a key, a
 * --set, a CSV cell), and must stay one line. */
static void one_line(char *dst, size_t cap, const char *src) {
  size_t n = 0;
  for (const unsigned char *p = (const unsigned char *)src; *p; p++) {
    char esc[5] = {(char)*p, 0};
    if (*p == '\n') memcpy(esc, "\\n", 3);
    else if (*p == '\r') memcpy(esc, "\\r", 3);
    else if (*p < 0x20 && *p != '\t') snprintf(esc, sizeof esc, "\\x%02x", *p);
    else if (*p == 0x7f) memcpy(esc, "\\x7f", 5);
    size_t len = strlen(esc);
    if (n + len >= cap) break;
    memcpy(dst + n, esc, len);
    n += len;
  }
  dst[n] = '\0';
}

bool err_set(struct err *e, const char *file, int line, int col, const char *fmt, ...) {
  if (!e || e->set) return false;
  e->set = true;
  one_line(e->file, sizeof e->file, file ? file : "");
  e->line = line;
  e->col = col;
  char msg[ERR_MSG_MAX];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  one_line(e->msg, sizeof e->msg, msg);
  return false;
}

void err_format(const struct err *e, char *buf, unsigned buf_size) {
  if (!e->file[0])
    snprintf(buf, buf_size, "error: %s", e->msg);
  else if (e->line <= 0)
    snprintf(buf, buf_size, "%s: error: %s", e->file, e->msg);
  else if (e->col <= 0)
    snprintf(buf, buf_size, "%s:%d: error: %s", e->file, e->line, e->msg);
  else
    snprintf(buf, buf_size, "%s:%d:%d: error: %s", e->file, e->line, e->col, e->msg);
}

void err_check_failed(const char *file, int line, const char *expr) {
  fprintf(stderr, "%s:%d: internal error: CHECK(%s) failed\n", file, line, expr);
  abort();
}

static void print_value(const char *expr, struct err_value v) {
  fprintf(stderr, "%s = ", expr);
  switch (v.kind) {
  case ERR_VALUE_SIGNED: fprintf(stderr, "%lld", v.i); break;
  case ERR_VALUE_UNSIGNED: fprintf(stderr, "%llu", v.u); break;
  case ERR_VALUE_FLOAT: fprintf(stderr, "%.17Lg", v.f); break;
  case ERR_VALUE_POINTER: fprintf(stderr, "%p", (const void *)v.p); break;
  }
}

void err_check_op_failed(const char *file, int line, const char *a, const char *op, const char *b,
                         struct err_value va, struct err_value vb) {
  fprintf(stderr, "%s:%d: internal error: CHECK(%s %s %s) failed: ", file, line, a, op, b);
  print_value(a, va);
  fputs(", ", stderr);
  print_value(b, vb);
  fputc('\n', stderr);
  abort();
}

static void *oom(unsigned long long size) {
  fprintf(stderr, "rtsim: out of memory allocating %llu bytes\n", size);
  abort();
}

void *xmalloc(unsigned long long size) {
  void *p = malloc(size ? size : 1);
  return p ? p : oom(size);
}

void *xcalloc(unsigned long long n, unsigned long long size) {
  void *p = calloc(n ? n : 1, size ? size : 1);
  return p ? p : oom(n * size);
}

void *xrealloc(void *p, unsigned long long size) {
  void *q = realloc(p, size ? size : 1);
  return q ? q : oom(size);
}
