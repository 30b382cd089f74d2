/* Strict numbers and words (scalar.h): a scanner decides whether the text is
 * the value; whole numbers are converted here, decimal ones by strtod and
 * strtof (correctly rounded). */
#include "sim/scalar.h"

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

const char *scalar_why_text(enum scalar_why w) {
  switch (w) {
  case SCALAR_OK:
  case SCALAR_SYNTAX: return "";
  case SCALAR_EMPTY: return "empty";
  case SCALAR_SPACE: return "whitespace before or after it";
  case SCALAR_CONTROL: return "a control character in it";
  case SCALAR_LEADING_ZERO: return "a leading zero, ambiguous between octal and decimal";
  case SCALAR_OVERFLOW: return "too large";
  case SCALAR_UNDERFLOW: return "too small (it would read as 0)";
  }
  return "";
}

static bool is_space(unsigned char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\v' || c == '\f' || c == '\r';
}

static bool is_digit(char c) { return c >= '0' && c <= '9'; }

/* Empty, or whitespace at either end, of the n bytes at s. */
static enum scalar_why ends(const char *s, size_t n) {
  if (n == 0) return SCALAR_EMPTY;
  if (is_space((unsigned char)s[0]) || is_space((unsigned char)s[n - 1])) return SCALAR_SPACE;
  return SCALAR_OK;
}

enum scalar_why scalar_u64_n(const char *s, size_t n, uint64_t *out) {
  enum scalar_why w = ends(s, n);
  if (w != SCALAR_OK) return w;
  for (size_t i = 0; i < n; i++)
    if (!is_digit(s[i])) return SCALAR_SYNTAX;
  if (n > 1 && s[0] == '0') return SCALAR_LEADING_ZERO;
  uint64_t v = 0;
  for (size_t i = 0; i < n; i++) {
    uint64_t d = (uint64_t)(s[i] - '0');
    if (v > (UINT64_MAX - d) / 10) return SCALAR_OVERFLOW;
    v = v * 10 + d;
  }
  *out = v;
  return SCALAR_OK;
}

enum scalar_why scalar_u64(const char *s, uint64_t *out) { return scalar_u64_n(s, strlen(s), out); }

/* The decimal syntax of scalar.h over the whole of s; *nonzero when a digit
 * of the significand is not 0. */
static enum scalar_why decimal(const char *s, bool *nonzero) {
  enum scalar_why w = ends(s, strlen(s));
  if (w != SCALAR_OK) return w;
  const char *p = s;
  *nonzero = false;
  if (*p == '+' || *p == '-') p++;
  const char *whole = p;
  while (is_digit(*p)) *nonzero |= *p++ != '0';
  size_t nwhole = (size_t)(p - whole), nfrac = 0;
  if (*p == '.')
    for (p++; is_digit(*p); p++, nfrac++) *nonzero |= *p != '0';
  if (nwhole == 0 && nfrac == 0) return SCALAR_SYNTAX;
  if (*p == 'e' || *p == 'E') {
    p++;
    if (*p == '+' || *p == '-') p++;
    if (!is_digit(*p)) return SCALAR_SYNTAX;
    while (is_digit(*p)) p++;
  }
  if (*p) return SCALAR_SYNTAX;
  if (nwhole > 1 && whole[0] == '0') return SCALAR_LEADING_ZERO;
  return SCALAR_OK;
}

enum scalar_why scalar_f64(const char *s, double *out) {
  bool nonzero;
  enum scalar_why w = decimal(s, &nonzero);
  if (w != SCALAR_OK) return w;
  double v = strtod(s, NULL);
  if (isinf(v)) return SCALAR_OVERFLOW;
  if (v == 0 && nonzero) return SCALAR_UNDERFLOW;
  *out = v;
  return SCALAR_OK;
}

enum scalar_why scalar_f32(const char *s, float *out) {
  bool nonzero;
  enum scalar_why w = decimal(s, &nonzero);
  if (w != SCALAR_OK) return w;
  float v = strtof(s, NULL);
  if (isinf(v)) return SCALAR_OVERFLOW;
  if (v == 0 && nonzero) return SCALAR_UNDERFLOW;
  *out = v;
  return SCALAR_OK;
}

enum scalar_why scalar_text(const char *s) {
  size_t n = strlen(s);
  enum scalar_why w = ends(s, n);
  if (w != SCALAR_OK) return w;
  for (size_t i = 0; i < n; i++)
    if ((unsigned char)s[i] < 0x20 || s[i] == 0x7f) return SCALAR_CONTROL;
  return SCALAR_OK;
}
