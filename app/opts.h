/* Command-line options of the rtsim commands in one shape: a command declares
 * a table of its options (name, kind, where the value goes), and opts_parse
 * reads argv against it through getopt_long. Every bad option gets one
 * message naming the command and the option as typed, "rtsim CMD: error:
 * --width: got '0', expected a whole number from 1 to 16384 (see 'rtsim CMD
 * --help')", and exit code 2. -h and --help print the command's help: its
 * text up to a form feed ('\f'), a screen's worth; --help-full all of it
 * (the rest is the reference that the man page also holds). */
#ifndef RTSIM_APP_OPTS_H
#define RTSIM_APP_OPTS_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

enum opts_kind {
  OPTS_KIND_FLAG,  /* no value: *(bool *)dst = true */
  OPTS_KIND_STR,   /* any text: *(const char **)dst = it (argv's, not copied) */
  OPTS_KIND_U64,   /* a whole number in [lo, hi]: *(uint64_t *)dst */
  OPTS_KIND_PARSE, /* parse(text, dst) decides (lists, names, repeatable options) */
};

/* Store text's value in dst; false if text is not a good value. */
typedef bool (*opts_parse_fn)(const char *text, void *dst);

struct opts_spec {
  const char *name; /* long name without "--"; NULL ends a table */
  char letter;      /* short name (-o), or 0 */
  enum opts_kind kind;
  void *dst;
  uint64_t lo, hi;     /* OPTS_KIND_U64: the accepted range, inclusive */
  opts_parse_fn parse; /* OPTS_KIND_PARSE */
  const char *expect;  /* OPTS_KIND_PARSE: what a good value is ("KEY=VALUE") */
  bool *given;         /* optional: set true when the option appears */
};

/* Table entries. dst's type is checked: OPTS_FLAG takes a bool *, OPTS_STR a
 * const char **, OPTS_U64 a uint64_t *. */
#define OPTS_FLAG(n_, l_, d_)                                                                      \
  { .name = (n_), .letter = (l_), .kind = OPTS_KIND_FLAG, .dst = OPTS_DST_(bool, d_) }
#define OPTS_STR(n_, l_, d_)                                                                       \
  { .name = (n_), .letter = (l_), .kind = OPTS_KIND_STR, .dst = OPTS_DST_(const char *, d_) }
#define OPTS_U64(n_, l_, d_, lo_, hi_)                                                             \
  {                                                                                                \
    .name = (n_), .letter = (l_), .kind = OPTS_KIND_U64, .dst = OPTS_DST_(uint64_t, d_),           \
    .lo = (lo_), .hi = (hi_)                                                                       \
  }
#define OPTS_PARSE(n_, l_, d_, fn_, expect_)                                                       \
  {                                                                                                \
    .name = (n_), .letter = (l_), .kind = OPTS_KIND_PARSE, .dst = (d_), .parse = (fn_),            \
    .expect = (expect_)                                                                            \
  }
/* OPTS_PARSE that also sets *given_ (a bool) when the option appears. */
#define OPTS_PARSE_GIVEN(n_, l_, d_, fn_, expect_, given_)                                         \
  {                                                                                                \
    .name = (n_), .letter = (l_), .kind = OPTS_KIND_PARSE, .dst = (d_), .parse = (fn_),            \
    .expect = (expect_), .given = (given_)                                                         \
  }
#define OPTS_END                                                                                   \
  { .name = NULL }
/* A pointer of the named type (a mismatch is a compile error under -Werror). */
#define OPTS_DST_(type, d_) ((void *)(1 ? (d_) : (type *)0))

/* What follows the options: the operands, in order. */
struct opts_args {
  const char *cmd;
  int n;
  char **v;
};

/* Continue with the command (returned by opts_parse). */
#define OPTS_GO (-1)

/* Write help's screen (up to its form feed), or all of it when full. */
void opts_help_write(const char *help, bool full, FILE *f);

/* Parse argv[1..argc) (argv[0] is the command's name) against spec. Every
 * option of spec must be named ("--name") in help's screen (a CHECK). Returns
 * OPTS_GO with the operands in *rest (getopt_long moves them last, so they
 * are also argv[optind..argc)); else the exit code: 0 after printing help on
 * stdout, 2 after one message on stderr. */
int opts_parse(const char *cmd, const char *help, const struct opts_spec *spec, int argc,
               char **argv, struct opts_args *rest);

/* text as a whole number in [lo, hi]: decimal digits only, no leading zero
 * (sim/scalar.h). */
bool opts_u64(const char *text, uint64_t lo, uint64_t hi, uint64_t *out);

/* Exactly one operand: it, or NULL after printing "missing WHAT" or "expected
 * one NOUN, got N". */
const char *opts_one(const struct opts_args *a, const char *what, const char *noun);
/* Exactly one SCENE.yaml. */
const char *opts_one_scene(const struct opts_args *a);

#endif
