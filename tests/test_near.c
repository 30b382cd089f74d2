/* sim/near: the nearest names to a mistyped one. Distances computed by hand
 * (each case's edits named), then which names a word suggests from a list:
 * the nearest only, at most three, none when all are far. */
#include "sim/near.h"

#include <string.h>

#include "testing.h"

static void test_distance(void) {
  static const struct {
    const char *a, *b;
    unsigned d;
  } cases[] = {
      {"", "", 0},
      {"size", "size", 0},
      {"", "abc", 3},            /* three inserts */
      {"l2.szie", "l2.size", 1}, /* one swap of neighbours */
      {"l2.sise", "l2.size", 1}, /* one change */
      {"core", "cores", 1},      /* one insert */
      {"polcy", "policy", 1},    /* one insert */
      {"kitten", "sitting", 3},  /* k->s, e->i, +g */
      {"ca", "abc", 3},          /* OSA, not Damerau: no edit inside a swapped pair */
      {"abcd", "badc", 2},       /* two swaps */
      {"lites", "lights", 3},    /* +g, +h, -e */
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    unsigned got = near_distance(cases[i].a, cases[i].b);
    EXPECTF(got == cases[i].d, "distance('%s', '%s') = %u, want %u", cases[i].a, cases[i].b, got,
            cases[i].d);
    unsigned back = near_distance(cases[i].b, cases[i].a);
    EXPECTF(back == got, "distance is not symmetric for '%s', '%s'", cases[i].a, cases[i].b);
  }
}

static void test_words(void) {
  const char *keys = "cores, l1.size, l1.ways, l2.size, l2.ways, l2.mshrs, dram.latency, fidelity";
  static const struct {
    const char *word;
    unsigned n;
    const char *want;
  } cases[] = {
      {"l2.szie", 1, "'l2.size'"},
      {"l2.mshr", 1, "'l2.mshrs'"},
      {"core", 1, "'cores'"},
      /* The last dotted part names two keys. */
      {"size", 2, "'l1.size' or 'l2.size'"},
      /* l3.size is one change from l1.size and from l2.size. */
      {"l3.size", 2, "'l1.size' or 'l2.size'"},
      /* l.ways: one delete from either ways key. */
      {"l.ways", 2, "'l1.ways' or 'l2.ways'"},
      /* Far from everything: 3 letters allow 1 edit. */
      {"zzz", 0, ""},
      {"latency", 1, "'dram.latency'"},
      {"fidelty", 1, "'fidelity'"},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    char buf[256];
    unsigned n = near_words(cases[i].word, keys, buf, sizeof buf);
    EXPECTF(n == cases[i].n && !strcmp(buf, cases[i].want), "near '%s': %u \"%s\", want %u \"%s\"",
            cases[i].word, n, buf, cases[i].n, cases[i].want);
  }
  /* At most three names, the first three in list order. */
  char buf[256];
  unsigned n = near_words("ab", "ax, bb, ac, ad, ae", buf, sizeof buf);
  EXPECTF(n == 3 && !strcmp(buf, "'ax', 'bb' or 'ac'"), "three of five: %u %s", n, buf);
  /* A short buffer stays terminated. */
  n = near_words("ab", "ax, bb", buf, 5);
  EXPECTF(strlen(buf) < 5, "short buffer: %s", buf);
}

int main(void) {
  test_distance();
  test_words();
  return testing_done("test_near");
}
