/* User-error records and the fatal paths for broken invariants and allocation. */
#include "sim/err.h"

#include <errno.h>
#include <fcntl.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

void err_escape(char *out, size_t cap, const char *s) {
  static const char hex[] = "0123456789abcdef";
  size_t n = 0;
  for (; *s && n + 1 < cap; s++) {
    unsigned char c = (unsigned char)*s;
    char esc[5] = {(char)c, 0};
    if (c == '\n') memcpy(esc, "\\n", 3);
    else if (c == '\r') memcpy(esc, "\\r", 3);
    else if (c == '\t') memcpy(esc, "\\t", 3);
    else if (c < 0x20 || c == 0x7f)
      esc[0] = '\\', esc[1] = 'x', esc[2] = hex[c >> 4], esc[3] = hex[c & 15];
    size_t k = strlen(esc);
    if (n + k >= cap) break;
    memcpy(out + n, esc, k);
    n += k;
  }
  if (cap) out[n] = '\0';
}

bool err_set(struct err *e, const char *file, int line, int col, const char *fmt, ...) {
  if (!e || e->set) return false;
  e->set = true;
  err_escape(e->file, sizeof e->file, file ? file : "");
  e->line = line;
  e->col = col;
  /* The message as formatted, then made one line. */
  char raw[ERR_MSG_MAX];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(raw, sizeof raw, fmt, ap);
  va_end(ap);
  err_escape(e->msg, sizeof e->msg, raw);
  return false;
}

void err_format(const struct err *e, char *buf, unsigned buf_size) {
  if (!e->file[0]) snprintf(buf, buf_size, "error: %s", e->msg);
  else if (e->line <= 0) snprintf(buf, buf_size, "%s: error: %s", e->file, e->msg);
  else if (e->col <= 0) snprintf(buf, buf_size, "%s:%d: error: %s", e->file, e->line, e->msg);
  else snprintf(buf, buf_size, "%s:%d:%d: error: %s", e->file, e->line, e->col, e->msg);
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

void *xcalloc_aligned(unsigned long long align, unsigned long long size) {
  /* aligned_alloc wants a multiple of align; at least one. */
  const unsigned long long n = size ? (size + align - 1) / align * align : align;
  void *p = aligned_alloc(align, n);
  if (!p) return oom(n);
  return memset(p, 0, n);
}

void *xrealloc(void *p, unsigned long long size) {
  void *q = realloc(p, size ? size : 1);
  return q ? q : oom(size);
}

/* What a file that is not regular is, for messages. */
static const char *irregular(mode_t m) {
  if (S_ISFIFO(m)) return "not a regular file (a named pipe)";
  if (S_ISCHR(m)) return "not a regular file (a character device)";
  if (S_ISBLK(m)) return "not a regular file (a block device)";
  if (S_ISDIR(m)) return "not a regular file (a directory)";
  if (S_ISSOCK(m)) return "not a regular file (a socket)";
  return "not a regular file";
}

const char *err_not_regular(const char *path) {
  struct stat sb;
  if (stat(path, &sb) != 0) return strerror(errno);
  return S_ISREG(sb.st_mode) ? NULL : irregular(sb.st_mode);
}

FILE *err_fopen_regular(const char *path, const char **why) {
  if ((*why = err_not_regular(path))) return NULL;
  int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    *why = strerror(errno);
    return NULL;
  }
  struct stat sb;
  int flags;
  if (fstat(fd, &sb) != 0) {
    *why = strerror(errno);
  } else if (!S_ISREG(sb.st_mode)) {
    *why = irregular(sb.st_mode);
  } else if ((flags = fcntl(fd, F_GETFL)) < 0 || fcntl(fd, F_SETFL, flags & ~O_NONBLOCK) != 0) {
    *why = strerror(errno);
  } else {
    FILE *f = fdopen(fd, "rb");
    if (f) return f;
    *why = strerror(errno);
  }
  close(fd);
  return NULL;
}
