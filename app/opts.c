/* The one option parser of the rtsim commands (opts.h): a table of options
 * turned into getopt_long's, values checked and stored by kind. */
#include "app/opts.h"

#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "app/app.h"
#include "sim/err.h"
#include "sim/near.h"
#include "sim/scalar.h"

/* getopt_long's value for options without a letter: past every char; and
 * for --help-full: past every option's. */
enum { OPTS_LONG_ONLY = 256, OPTS_HELP_FULL = 1 << 20 };

bool opts_u64(const char *text, uint64_t lo, uint64_t hi, uint64_t *out) {
  uint64_t v;
  if (scalar_u64(text, &v) != SCALAR_OK || v < lo || v > hi) return false;
  *out = v;
  return true;
}

/* Store the value of option s, named as the user typed it; false after the
 * message. */
static bool take(const char *cmd, const struct opts_spec *s, const char *opt, const char *text) {
  switch (s->kind) {
  case OPTS_KIND_FLAG: *(bool *)s->dst = true; break;
  case OPTS_KIND_STR: *(const char **)s->dst = text; break;
  case OPTS_KIND_U64:
    if (!opts_u64(text, s->lo, s->hi, s->dst)) {
      uint64_t v;
      enum scalar_why w = scalar_u64(text, &v);
      const bool why = w != SCALAR_OK && w != SCALAR_SYNTAX;
      app_usage_error(cmd, "%s: got '%s'%s%s%s, expected a whole number from %llu to %llu", opt,
                      text, why ? " (" : "", scalar_why_text(w), why ? ")" : "",
                      (unsigned long long)s->lo, (unsigned long long)s->hi);
      return false;
    }
    break;
  case OPTS_KIND_PARSE:
    if (!s->parse(text, s->dst)) {
      app_usage_error(cmd, "%s: got '%s', expected %s", opt, text, s->expect);
      return false;
    }
    break;
  }
  if (s->given) *s->given = true;
  return true;
}

/* The spec getopt_long answered c for, or NULL. */
static const struct opts_spec *find(const struct opts_spec *spec, unsigned n, int c) {
  for (unsigned i = 0; i < n; i++)
    if (spec[i].letter ? c == spec[i].letter : c == OPTS_LONG_ONLY + (int)i) return &spec[i];
  return NULL;
}

/* "unknown option '--x'", naming the nearest long options of spec (and
 * --help) when some are near. Returns APP_EXIT_USAGE. */
static int unknown_option(const char *cmd, const struct opts_spec *spec, unsigned n,
                          const char *typed) {
  char names[2048] = "--help, --help-full", near[256], word[128];
  for (unsigned i = 0; i < n; i++)
    snprintf(names + strlen(names), sizeof names - strlen(names), ", --%s", spec[i].name);
  snprintf(word, sizeof word, "%.*s", (int)strcspn(typed, "="), typed);
  if (strncmp(typed, "--", 2) == 0 && near_words(word, names, near, sizeof near))
    return app_usage_error(cmd, "unknown option '%s' (did you mean %s?)", typed, near);
  return app_usage_error(cmd, "unknown option '%s'", typed);
}

/* The help's first part, what --help prints: up to its form feed. */
static size_t screen_len(const char *help) { return strcspn(help, "\f"); }

/* Whether help[0..screen) holds word. */
static bool names(const char *help, size_t screen, const char *word) {
  const char *at = strstr(help, word);
  return at && (size_t)(at - help) < screen;
}

/* Every option of spec is named in help's first part ("--name", or "-x "
 * for one with a letter), so that an option cannot be added without a line
 * in --help (a programmer error: CHECK). */
static void check_help(const char *help, const struct opts_spec *spec, unsigned n) {
  const size_t screen = screen_len(help);
  for (unsigned i = 0; i < n; i++) {
    char opt[128], letter[8];
    snprintf(opt, sizeof opt, "--%s", spec[i].name);
    snprintf(letter, sizeof letter, "-%c ", spec[i].letter);
    if (!names(help, screen, opt) && !(spec[i].letter && names(help, screen, letter))) {
      fprintf(stderr, "rtsim: internal error: the help text does not name %s\n", opt);
      CHECK(!"every option in the help's first part");
    }
  }
}

void opts_help_write(const char *help, bool full, FILE *f) {
  const size_t screen = screen_len(help);
  fwrite(help, 1, screen, f);
  if (full && help[screen]) fputs(help + screen + 1, f);
}

int opts_parse(const char *cmd, const char *help, const struct opts_spec *spec, int argc,
               char **argv, struct opts_args *rest) {
  unsigned n = 0;
  while (spec[n].name) n++;
  check_help(help, spec, n);
  /* getopt_long's tables: ours, then --help and --help-full, then the
   * terminator. */
  struct option *lo = xcalloc(n + 3, sizeof *lo);
  char *shorts = xmalloc(2 * n + 3);
  size_t k = 0;
  shorts[k++] = ':'; /* a missing value is ':', not '?' */
  for (unsigned i = 0; i < n; i++) {
    const bool value = spec[i].kind != OPTS_KIND_FLAG;
    lo[i].name = spec[i].name;
    lo[i].has_arg = value ? required_argument : no_argument;
    lo[i].val = spec[i].letter ? spec[i].letter : OPTS_LONG_ONLY + (int)i;
    if (spec[i].letter) {
      CHECK_NE(spec[i].letter, 'h'); /* -h is help */
      shorts[k++] = spec[i].letter;
      if (value) shorts[k++] = ':';
    }
  }
  lo[n] = (struct option){"help", no_argument, NULL, 'h'};
  lo[n + 1] = (struct option){"help-full", no_argument, NULL, OPTS_HELP_FULL};
  shorts[k++] = 'h';
  shorts[k] = '\0';

  int rc = OPTS_GO;
  opterr = 0; /* we say what is wrong, once */
  optind = 1;
  while (rc == OPTS_GO) {
    int li = -1;
    int c = getopt_long(argc, argv, shorts, lo, &li);
    if (c == -1) break;
    const struct opts_spec *s = find(spec, n, c);
    if (c == 'h' || c == OPTS_HELP_FULL) {
      opts_help_write(help, c == OPTS_HELP_FULL, stdout);
      rc = 0;
    } else if (c == ':') {
      rc = app_usage_error(cmd, "option %s needs a value", argv[optind - 1]);
    } else if (c == '?' && optopt &&
               (optopt == 'h' || optopt == OPTS_HELP_FULL || find(spec, n, optopt))) {
      /* --flag=value: getopt_long names the flag in optopt. */
      const struct opts_spec *f = find(spec, n, optopt);
      rc = app_usage_error(cmd, "option --%s takes no value",
                           f                          ? f->name
                           : optopt == OPTS_HELP_FULL ? "help-full"
                                                      : "help");
    } else if (c == '?' && optopt) {
      rc = app_usage_error(cmd, "unknown option '-%c'", optopt);
    } else if (c == '?' || !s) {
      rc = unknown_option(cmd, spec, n, argv[optind - 1]);
    } else {
      char opt[128];
      if (li >= 0) snprintf(opt, sizeof opt, "--%s", s->name);
      else snprintf(opt, sizeof opt, "-%c", s->letter);
      if (!take(cmd, s, opt, optarg)) rc = APP_EXIT_USAGE;
    }
  }
  free(lo);
  free(shorts);
  rest->cmd = cmd;
  rest->n = argc - optind;
  rest->v = argv + optind;
  return rc;
}

const char *opts_one(const struct opts_args *a, const char *what, const char *noun) {
  if (a->n == 1) return a->v[0];
  if (a->n == 0) app_usage_error(a->cmd, "missing %s", what);
  else app_usage_error(a->cmd, "expected one %s, got %d", noun, a->n);
  return NULL;
}

const char *opts_one_scene(const struct opts_args *a) {
  return opts_one(a, "SCENE.yaml", "scene file");
}
