/* sim/cfg: YAML tree with positions, typed getters, unknown-key errors. */
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
      cfg_check_keys(&d, &d.root, "", "k", &e);
    if (!cfg_get(&d.root, "k") && !e.set) cfg_fail(&d, &d.root, "", &e, "missing required key 'k'");
  }
  cfg_free(&d);
  if (e.set) err_format(&e, out, cap);
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
      {"k: 1\nkk: 2\n", "t.yaml:2:1: error: kk: unknown key 'kk' (expected one of: k)"},
      {"k: 1\nk: 2\n", "t.yaml:2:1: error: duplicate key 'k' (first at line 1)"},
      {"k: [1, 2\n", "t.yaml:2:1: error: YAML syntax"},
      {"k: 'unterminated\n", "t.yaml:"},
      {"", "t.yaml: error: empty file"},
      {"- 1\n- 2\n", "t.yaml:1:1: error: wrong type (got a list, expected a map"},
      {"k: nan\n", "not a number"},
      {"k: 1e999\n", "not a number"},
      {"  # comment\n\n   k: 2\n", ""},
      {"a: &x [1]\nk: *x\n", "t.yaml:1:4: error: k: wrong type (got a list"},
  };
  char buf[2048];
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    run_case(cases[i].text, buf, sizeof buf);
    if (!cases[i].want[0])
      EXPECTF(buf[0] == '\0', "case %zu: unexpected error: %s", i, buf);
    else
      EXPECTF(strstr(buf, cases[i].want) != NULL, "case %zu: got '%s', want '%s'", i, buf,
              cases[i].want);
  }

  /* Getters: whole numbers, enums, lists, booleans, strings, positions. */
  struct cfg_doc d;
  struct err e;
  memset(&e, 0, sizeof e);
  EXPECT(cfg_load_text(&d, "g.yaml",
                       "n: 0x40\npolicy: lru\nv: [1, 2.5, -3]\nb: true\ns: hello\nneg: -1\n", &e));
  uint64_t u = 0;
  EXPECT(cfg_u64(&d, cfg_get(&d.root, "n"), "n", 0, 100, &u, &e) && u == 64);
  int which = -1;
  static const char *const pol[] = {"fifo", "lru", "random", NULL};
  EXPECT(cfg_enum(&d, cfg_get(&d.root, "policy"), "policy", pol, &which, &e) && which == 1);
  double v[3];
  EXPECT(cfg_f64_list(&d, cfg_get(&d.root, "v"), "v", 3, -10, 10, v, &e) && v[1] == 2.5 && v[2] == -3);
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
  EXPECT(cfg_check_keys(&d, &d.root, "", "-", &e));
  cfg_free(&d);

  /* A missing file names the file. */
  memset(&e, 0, sizeof e);
  EXPECT(!cfg_load_file(&d, "/nonexistent/x.yaml", &e));
  EXPECT(strcmp(e.file, "/nonexistent/x.yaml") == 0 && strstr(e.msg, "cannot open"));
  cfg_free(&d);
  return testing_done("test_cfg");
}
