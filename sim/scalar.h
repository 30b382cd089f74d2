/* Strict text of numbers and words: the one reader behind every number and
 * word rtsim takes from a user (machine configs, --set, sweep files, scene
 * files, CSV, command-line options). The whole text or nothing, never a
 * prefix; no whitespace around it; no control characters in a word. One rule
 * for leading zeros: an integer, and the whole part of a decimal number, has
 * none but "0" itself, so 010 is refused rather than read as 8 (C's base 0,
 * YAML 1.1) or as 10 (strtoull base 10, a person): rtsim once did both, the
 * first for counts and the second for sizes. Only decimal: no 0x, no octal,
 * no inf or nan (a reader that takes inf says so itself). */
#ifndef RTSIM_SIM_SCALAR_H
#define RTSIM_SIM_SCALAR_H

#include <stddef.h>
#include <stdint.h>

/* Why a text is not the value asked for. */
enum scalar_why {
  SCALAR_OK,
  SCALAR_EMPTY,        /* no text at all */
  SCALAR_SPACE,        /* whitespace before or after the value */
  SCALAR_CONTROL,      /* a control character inside a word (a line break, a tab) */
  SCALAR_LEADING_ZERO, /* 00, 010, 01.5, -07 */
  SCALAR_SYNTAX,       /* anything else that is not the value (letters, 0x10, 1e3 as a count) */
  SCALAR_OVERFLOW,     /* above 2^64 - 1, or a magnitude the floating type cannot hold */
  SCALAR_UNDERFLOW,    /* a nonzero number that would read as 0 */
};

/* What is wrong, as a noun phrase for a message ("a leading zero, ..."), or
 * "" for SCALAR_OK and SCALAR_SYNTAX (the caller says what was expected). */
const char *scalar_why_text(enum scalar_why w);

/* A whole number: decimal digits only (no sign), no leading zero, below 2^64.
 * *out is written only on SCALAR_OK. */
enum scalar_why scalar_u64(const char *s, uint64_t *out);
/* The same on the first n bytes of s (which need not end there). */
enum scalar_why scalar_u64_n(const char *s, size_t n, uint64_t *out);

/* A decimal number: [+-] digits [. digits] [e|E [+-] digits], the digits
 * before or after the point may be absent but not both, no leading zero in
 * the whole part. Rounded to the nearest double (float) as strtod (strtof)
 * does; a magnitude beyond the type is SCALAR_OVERFLOW, a nonzero number that
 * would round to 0 SCALAR_UNDERFLOW (one that rounds to a subnormal is taken).
 * *out is written only on SCALAR_OK. */
enum scalar_why scalar_f64(const char *s, double *out);
enum scalar_why scalar_f32(const char *s, float *out);

/* A word, a name or a path: not empty, no whitespace before or after, no
 * control characters (bytes below 0x20, and 0x7f) anywhere. */
enum scalar_why scalar_text(const char *s);

#endif
