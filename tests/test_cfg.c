/* sim/cfg: YAML tree with positions, typed getters, unknown-key errors. */
#include <stdarg.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "sim/cfg.h"
#include "sim/err.h"
#include "testing.h"

/* Load text, read key `k` of the root as a number in [0, 10] and check keys;
 * return the formatted error ("" when none). */
static void run_case(const char *text, char *out, unsigned cap) {
  struct cfg_doc d;
  struct err e;
  memset(&e, 0, sizeof e);
  out[0] = '\0';
  if (cfg_load_text(&d, "t.yaml", text, &e)) {
    struct cfg_node *n;
    double v;
    if (cfg_expect_map(&d, &d.root, "", &e) && (n = cfg_get(&d.root, "k")) &&
        cfg_f64(&d, n, "k", 0, 10, &v, &e))
      cfg_check_keys(&d, &d.root, "", &e);
    if (!cfg_get(&d.root, "k") && !e.set) cfg_fail(&d, &d.root, "", &e, "missing required key 'k'");
  }
  cfg_free(&d);
  if (e.set) err_format(&e, out, cap);
}

/* Load text; return the formatted error, "" when none. */
static const char *load_error(const char *text, char *out, unsigned cap) {
  struct cfg_doc d;
  struct err e;
  memset(&e, 0, sizeof e);
  out[0] = '\0';
  if (!cfg_load_text(&d, "h.yaml", text, &e)) err_format(&e, out, cap);
  cfg_free(&d);
  return out;
}

/* A growing text buffer for generated documents. */
struct text {
  char *s;
  size_t len, cap;
};

static void add(struct text *t, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void add(struct text *t, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  int n = vsnprintf(NULL, 0, fmt, ap);
  va_end(ap);
  if (t->len + (size_t)n + 1 > t->cap) {
    t->cap = 2 * (t->len + (size_t)n + 1);
    t->s = realloc(t->s, t->cap);
  }
  va_start(ap, fmt);
  vsnprintf(t->s + t->len, (size_t)n + 1, fmt, ap);
  va_end(ap);
  t->len += (size_t)n;
}

static void add_repeat(struct text *t, const char *item, const char *sep, unsigned n) {
  for (unsigned i = 0; i < n; i++) add(t, "%s%s", i ? sep : "", item);
}

/* The documented limits of cfg.h hold exactly at their bounds, and hostile
 * documents are refused where they cross one. */
static void test_limits(void) {
  char buf[2048];
  struct text t = {0};

  /* Billion laughs: ten levels of ten aliases. Level sizes 11, 111, 1111:
   * through aliases 110 + 1110 nodes after b and c, and the 8th *c of d takes
   * the count to 1220 + 8 * 1111 = 10108. */
  add(&t, "a: &a [");
  add_repeat(&t, "x", ", ", 10);
  add(&t, "]\n");
  for (char c = 'b'; c <= 'j'; c++) {
    add(&t, "%c: &%c [", c, c);
    for (int i = 0; i < 10; i++) add(&t, "%s*%c", i ? ", " : "", c - 1);
    add(&t, "]\n");
  }
  EXPECTF(strstr(load_error(t.s, buf, sizeof buf),
                 "h.yaml:4:36: error: alias '*c': too many YAML nodes reached through aliases "
                 "(got 10108, expected at most 10000)"),
          "%s", buf);

  /* Fan-out: CFG_MAX_ALIAS_NODES aliases of one scalar pass, one more fails
   * at its own position. */
  for (unsigned extra = 0; extra < 2; extra++) {
    t.len = 0;
    add(&t, "a: &a x\nk: [");
    add_repeat(&t, "*a", ", ", CFG_MAX_ALIAS_NODES + extra);
    add(&t, "]\n");
    load_error(t.s, buf, sizeof buf);
    if (!extra) EXPECTF(buf[0] == '\0', "%s", buf);
    else
      EXPECTF(strstr(buf, "h.yaml:2:40005: error: alias '*a': too many YAML nodes reached "
                          "through aliases (got 10001, expected at most 10000)"),
              "%s", buf);
  }
  /* Aliases of a map count all its nodes: 12 * (1 + 2 * 400) = 9612 pass. */
  t.len = 0;
  add(&t, "m: &m {");
  for (int i = 0; i < 400; i++) add(&t, "%sk%d: %d", i ? ", " : "", i, i);
  add(&t, "}\nl: [");
  add_repeat(&t, "*m", ", ", 12);
  add(&t, "]\n");
  EXPECTF(load_error(t.s, buf, sizeof buf)[0] == '\0', "%s", buf);
  add(&t, "n: *m\n");
  EXPECTF(strstr(load_error(t.s, buf, sizeof buf), "h.yaml:3:4: error: alias '*m': too many"), "%s",
          buf);

  /* All nodes: the root map, key 'a', its list and N scalars: N + 3. */
  for (unsigned extra = 0; extra < 2; extra++) {
    t.len = 0;
    add(&t, "a: [");
    add_repeat(&t, "1", ",", CFG_MAX_NODES - 3 + extra);
    add(&t, "]\n");
    load_error(t.s, buf, sizeof buf);
    if (!extra) EXPECTF(buf[0] == '\0', "%s", buf);
    else
      EXPECTF(strstr(buf, "h.yaml:1:199999: error: too many YAML nodes (got more than 100000, "
                          "expected at most 100000)"),
              "%s", buf);
  }

  /* Many anchors, each found again by name (the table grows). */
  t.len = 0;
  add(&t, "a: [");
  for (int i = 0; i < 5000; i++) add(&t, "%s&n%d %d", i ? ", " : "", i, i);
  add(&t, "]\nk: [");
  for (int i = 0; i < 5000; i += 7) add(&t, "%s*n%d", i ? ", " : "", i);
  add(&t, "]\n");
  struct cfg_doc d;
  struct err e;
  memset(&e, 0, sizeof e);
  EXPECT(cfg_load_text(&d, "h.yaml", t.s, &e));
  struct cfg_node *k = cfg_get(&d.root, "k");
  EXPECT(k && k->kind == CFG_SEQ && k->count == 715);
  for (uint32_t i = 0; k && i < k->count; i++) {
    char want[16];
    snprintf(want, sizeof want, "%u", 7 * i);
    EXPECTF(strcmp(k->items[i].text, want) == 0, "alias %u: got %s", i, k->items[i].text);
  }
  cfg_free(&d);

  /* Duplicate keys in a large map: the first repeat in file order, named with
   * the line of the key it repeats. */
  t.len = 0;
  for (int i = 0; i < 3000; i++) add(&t, "k%d: %d\n", i, i);
  add(&t, "k7: 1\nk2: 1\n");
  EXPECTF(strstr(load_error(t.s, buf, sizeof buf),
                 "h.yaml:3001:1: error: duplicate key 'k7' (first at line 8)"),
          "%s", buf);

  /* Depth: a scalar CFG_MAX_DEPTH levels below the root passes; one level
   * more fails, also when the extra levels come through an alias. */
  for (unsigned extra = 0; extra < 2; extra++) {
    t.len = 0;
    add(&t, "k: ");
    add_repeat(&t, "[", "", CFG_MAX_DEPTH - 1 + extra);
    add(&t, "1");
    add_repeat(&t, "]", "", CFG_MAX_DEPTH - 1 + extra);
    add(&t, "\n");
    load_error(t.s, buf, sizeof buf);
    if (!extra) EXPECTF(buf[0] == '\0', "%s", buf);
    else EXPECTF(strstr(buf, "h.yaml:1:68: error: nesting deeper than 64 levels"), "%s", buf);
  }
  t.len = 0;
  add(&t, "a: &a ");
  add_repeat(&t, "[", "", 40);
  add(&t, "1");
  add_repeat(&t, "]", "", 40);
  add(&t, "\nb: ");
  add_repeat(&t, "[", "", 24);
  add(&t, "*a");
  add_repeat(&t, "]", "", 24);
  add(&t, "\n");
  EXPECTF(strstr(load_error(t.s, buf, sizeof buf),
                 "h.yaml:2:28: error: alias '*a': nesting deeper than 64 levels"),
          "%s", buf);

  /* Scalars: CFG_MAX_SCALAR_BYTES pass, one byte more fails at the scalar. */
  for (unsigned extra = 0; extra < 2; extra++) {
    t.len = 0;
    add(&t, "k: 1\ns: ");
    add_repeat(&t, "x", "", CFG_MAX_SCALAR_BYTES + extra);
    add(&t, "\n");
    load_error(t.s, buf, sizeof buf);
    if (!extra) EXPECTF(buf[0] == '\0', "%s", buf);
    else
      EXPECTF(
          strstr(buf, "h.yaml:2:4: error: scalar too long (got 4097 bytes, expected at most 4096)"),
          "%s", buf);
  }

  /* Size: CFG_MAX_FILE_BYTES pass (a long comment line), one more fails at
   * the first byte past the limit. */
  for (unsigned extra = 0; extra < 2; extra++) {
    t.len = 0;
    add(&t, "k: 1\n#");
    add_repeat(&t, "c", "", CFG_MAX_FILE_BYTES - 7 + extra);
    add(&t, "\n");
    EXPECT(t.len == CFG_MAX_FILE_BYTES + extra);
    load_error(t.s, buf, sizeof buf);
    if (!extra) EXPECTF(buf[0] == '\0', "%s", buf);
    else
      EXPECTF(strstr(buf, "h.yaml:2:1048572: error: file too large (got more than 1048576 bytes, "
                          "expected at most 1048576)"),
              "%s", buf);
  }
  free(t.s);
}

int main(void) {
  static const struct {
    const char *text, *want; /* want: substring of the error, "" = success */
  } cases[] = {
      {"k: 3\n", ""},
      {"k: 3.5e0\n", ""},
      {"k: 11\n", "t.yaml:1:4: error: k: out of range (got 11, expected 0 to 10)"},
      {"k: abc\n", "t.yaml:1:4: error: k: not a number (got 'abc'"},
      {"k: [1, 2]\n", "t.yaml:1:4: error: k: wrong type (got a list, expected a number)"},
      {"k: 1\nkk: 2\n", "t.yaml:2:1: error: kk: unknown key 'kk' (did you mean 'k'?)"},
      {"k: 1\nzzz: 2\n", "t.yaml:2:1: error: zzz: unknown key 'zzz' (expected one of: k)"},
      {"k: 1\nk: 2\n", "t.yaml:2:1: error: duplicate key 'k' (first at line 1)"},
      {"k: [1, 2\n", "t.yaml:2:1: error: YAML syntax"},
      {"k: 'unterminated\n", "t.yaml:"},
      {"", "t.yaml: error: empty file"},
      {"- 1\n- 2\n", "t.yaml:1:1: error: wrong type (got a list, expected a map"},
      {"k: nan\n", "not a number"},
      {"k: 1e999\n", "not a number"},
      {"  # comment\n\n   k: 2\n", ""},
      {"a: &x [1]\nk: *x\n", "t.yaml:1:4: error: k: wrong type (got a list"},
      /* Aliases: anchors are found by name, the later of two wins; an alias
       * must follow its anchor, outside it; keys stay scalars. */
      {"a: &x 1\nb: &x [1]\nk: *x\n", "t.yaml:2:4: error: k: wrong type (got a list"},
      {"a: &x 1\nk: *x\n", "t.yaml:1:1: error: a: unknown key 'a'"},
      {"a: &a [1, *a]\n", "t.yaml:1:11: error: alias '*a' refers to a node that contains it"},
      {"k: *nowhere\n",
       "t.yaml:1:4: error: alias '*nowhere' refers to no anchor defined before it"},
      {"k: *x\na: &x 1\n", "t.yaml:1:4: error: alias '*x' refers to no anchor defined before it"},
      {"? [1]\n: 2\n", "t.yaml:1:3: error: a key must be a plain word, not a list or map"},
      {"a: &x [1]\n*x : 2\n", "t.yaml:2:1: error: a key must be a plain word, not a list or map"},
      {"&x k: 1\n*x : 2\n", "t.yaml:2:1: error: duplicate key 'k' (first at line 1)"},
      {"k: 1\n---\nk: [\n", ""}, /* the first document only */
      /* Strict numbers (sim/scalar.h): the whole text, no whitespace around
       * it, no leading zero; a NUL escape refused where it is written. */
      {"k: .5\n", ""},
      {"k: 2.5e-01\n", ""},
      {"k: \" 3\"\n",
       "t.yaml:1:4: error: k: not a number: whitespace before or after it (got ' 3', expected a decimal number)"},
      {"k: \"3 \"\n",
       "t.yaml:1:4: error: k: not a number: whitespace before or after it (got '3 '"},
      {"k: \"\\n1.5\"\n",
       "t.yaml:1:4: error: k: not a number: whitespace before or after it (got '\\n1.5'"},
      {"k: 01.5\n",
       "t.yaml:1:4: error: k: not a number: a leading zero, ambiguous between octal and decimal (got '01.5'"},
      {"k: 1e-400\n",
       "t.yaml:1:4: error: k: not a number: too small (it would read as 0) (got '1e-400'"},
      {"k: 0x8\n", "t.yaml:1:4: error: k: not a number (got '0x8'"},
      {"k: \"4\\0xyz\"\n",
       "t.yaml:1:4: error: a NUL character (\\0) in a value (got '4\\0...', expected text without one)"},
      {"k: \"4\\x00\"\n", "t.yaml:1:4: error: a NUL character (\\0) in a value"},
      {"k: \"4\\u0000\"\n", "t.yaml:1:4: error: a NUL character (\\0) in a value"},
      {"k: 1\n\"k\\0x\": 2\n", "t.yaml:2:1: error: a NUL character (\\0) in a key (got 'k\\0...'"},
      {"\" k\": 1\n", "t.yaml:1:1: error: key: whitespace before or after it (got ' k'"},
      {"\"k\\t\": 1\n", "t.yaml:1:1: error: key: whitespace before or after it (got 'k\\t'"},
      {"\"a\\nb\": 1\n", "t.yaml:1:1: error: key: a control character in it (got 'a\\nb'"},
      {"\"\": 1\n", "t.yaml:1:1: error: key: empty"},
  };
  char buf[2048];
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    run_case(cases[i].text, buf, sizeof buf);
    if (!cases[i].want[0]) EXPECTF(buf[0] == '\0', "case %zu: unexpected error: %s", i, buf);
    else
      EXPECTF(strstr(buf, cases[i].want) != NULL, "case %zu: got '%s', want '%s'", i, buf,
              cases[i].want);
  }

  /* Getters: whole numbers, enums, lists, booleans, strings, positions. */
  struct cfg_doc d;
  struct err e;
  memset(&e, 0, sizeof e);
  EXPECT(cfg_load_text(&d, "g.yaml",
                       "n: 64\npolicy: lru\nv: [1, 2.5, -3]\nb: true\ns: hello\nneg: -1\n"
                       "oct: 010\nhex: 0x40\nsp: ' 4'\nbig: 18446744073709551616\n"
                       "ws: 'a '\ntab: \"a\\tb\"\n",
                       &e));
  uint64_t u = 0;
  EXPECT(cfg_u64(&d, cfg_get(&d.root, "n"), "n", 0, 100, &u, &e) && u == 64);
  /* One rule for leading zeros: 010 is neither octal 8 nor 10; no hex. */
  static const struct {
    const char *key, *want;
  } bad_u64[] = {
      {"oct",
       "oct: not a whole number: a leading zero, ambiguous between octal and decimal (got '010', expected 0 to 100)"},
      {"hex", "hex: not a whole number (got '0x40', expected 0 to 100)"},
      {"sp", "sp: not a whole number: whitespace before or after it (got ' 4', expected 0 to 100)"},
      {"big", "big: out of range (got 18446744073709551616, expected 0 to 100)"},
  };
  for (size_t i = 0; i < sizeof bad_u64 / sizeof bad_u64[0]; i++) {
    memset(&e, 0, sizeof e);
    u = 12345;
    EXPECT(!cfg_u64(&d, cfg_get(&d.root, bad_u64[i].key), bad_u64[i].key, 0, 100, &u, &e));
    EXPECTF(u == 12345 && strstr(e.msg, bad_u64[i].want), "%s: %s", bad_u64[i].key, e.msg);
  }
  /* Strings: no whitespace around them, no control characters. */
  char str[64];
  memset(&e, 0, sizeof e);
  EXPECT(!cfg_str(&d, cfg_get(&d.root, "ws"), "ws", str, sizeof str, &e));
  EXPECTF(strstr(e.msg, "ws: whitespace before or after it (got 'a '") && e.line == 11, "%s",
          e.msg);
  memset(&e, 0, sizeof e);
  EXPECT(!cfg_str(&d, cfg_get(&d.root, "tab"), "tab", str, sizeof str, &e));
  EXPECTF(strstr(e.msg, "tab: a control character in it (got 'a\\tb'"), "%s", e.msg);
  memset(&e, 0, sizeof e);
  EXPECT(cfg_str(&d, cfg_get(&d.root, "policy"), "policy", str, sizeof str, &e) &&
         !strcmp(str, "lru"));
  int which = -1;
  static const char *const pol[] = {"fifo", "lru", "random", NULL};
  EXPECT(cfg_enum(&d, cfg_get(&d.root, "policy"), "policy", pol, &which, &e) && which == 1);
  double v[3];
  EXPECT(cfg_f64_list(&d, cfg_get(&d.root, "v"), "v", 3, -10, 10, v, &e) && v[1] == 2.5 &&
         v[2] == -3);
  bool b = false;
  EXPECT(cfg_bool(&d, cfg_get(&d.root, "b"), "b", &b, &e) && b);
  char s[4];
  EXPECT(!cfg_str(&d, cfg_get(&d.root, "s"), "s", s, sizeof s, &e));
  EXPECTF(strstr(e.msg, "too long") && e.line == 5 && e.col == 4, "%d:%d %s", e.line, e.col, e.msg);
  memset(&e, 0, sizeof e);
  EXPECT(!cfg_u64(&d, cfg_get(&d.root, "neg"), "neg", 0, 100, &u, &e) && e.line == 6 && e.col == 6);
  memset(&e, 0, sizeof e);
  EXPECT(!cfg_enum(&d, cfg_get(&d.root, "s"), "s", pol, &which, &e));
  EXPECT(strstr(e.msg, "expected one of: fifo, lru, random") != NULL);
  memset(&e, 0, sizeof e);
  EXPECT(!cfg_f64_list(&d, cfg_get(&d.root, "v"), "v", 2, -10, 10, v, &e));
  EXPECT(strstr(e.msg, "wrong length (got 3 numbers, expected 2)") != NULL);
  memset(&e, 0, sizeof e);
  EXPECT(cfg_check_keys(&d, &d.root, "", &e));
  cfg_free(&d);

  test_limits();

  /* A missing file names the file. */
  memset(&e, 0, sizeof e);
  EXPECT(!cfg_load_file(&d, "/nonexistent/x.yaml", &e));
  EXPECT(strcmp(e.file, "/nonexistent/x.yaml") == 0 && strstr(e.msg, "cannot open"));
  cfg_free(&d);
  return testing_done("test_cfg");
}
