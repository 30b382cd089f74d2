/* Tables of named scalars alone (sim/stats.h), against hand-written output:
 * insertion order past the first growth, the CSV header and row (RFC 4180
 * quoting), JSON members and string escapes, doubles that read back the same
 * bits in their shortest 15-17 digit form, and the CHECKs on bad input. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "sim/dram.h"
#include "sim/dram_energy_estimate.h"
#include "sim/l2.h"
#include "sim/machine.h"
#include "sim/stats.h"
#include "sim/timeline.h"
#include "testing.h"

/* What a writer prints, as a string (caller frees). */
typedef void (*writer)(FILE *f, const void *arg);

static char *capture(writer w, const void *arg) {
  char *buf = NULL;
  size_t len = 0;
  FILE *f = open_memstream(&buf, &len);
  w(f, arg);
  fclose(f);
  return buf;
}

static void w_csv_str(FILE *f, const void *s) { stats_write_csv_str(f, s); }
static void w_json_str(FILE *f, const void *s) { stats_write_json_str(f, s); }
static void w_f64(FILE *f, const void *v) { stats_write_json_f64(f, *(const double *)v); }
static void w_header(FILE *f, const void *t) { stats_write_csv_header(t, f); }
static void w_row(FILE *f, const void *t) { stats_write_csv_row(t, f); }
static void w_members(FILE *f, const void *t) { stats_write_json_members(t, f, "  "); }

static void expect_out(writer w, const void *arg, const char *want, const char *what) {
  char *got = capture(w, arg);
  EXPECTF(strcmp(got, want) == 0, "%s: got [%s], want [%s]", what, got, want);
  free(got);
}

static void test_csv_str(void) {
  expect_out(w_csv_str, "plain", "plain", "no special character");
  expect_out(w_csv_str, "", "", "empty");
  expect_out(w_csv_str, "a b;c", "a b;c", "space and semicolon need no quotes");
  expect_out(w_csv_str, "a,b", "\"a,b\"", "comma");
  expect_out(w_csv_str, "say \"hi\"", "\"say \"\"hi\"\"\"", "quotes doubled");
  expect_out(w_csv_str, "two\nlines", "\"two\nlines\"", "line feed");
  expect_out(w_csv_str, "cr\r", "\"cr\r\"", "carriage return");
}

static void test_json_str(void) {
  expect_out(w_json_str, "plain", "\"plain\"", "plain");
  expect_out(w_json_str, "", "\"\"", "empty");
  expect_out(w_json_str, "a\"b\\c", "\"a\\\"b\\\\c\"", "quote and backslash");
  expect_out(w_json_str, "t\tn\n\x01\x1f", "\"t\\u0009n\\u000a\\u0001\\u001f\"", "controls");
  /* Bytes from 0x20 up pass as they are: DEL, and UTF-8 (e acute). */
  expect_out(w_json_str, "\x7f\xc3\xa9/", "\"\x7f\xc3\xa9/\"", "DEL, UTF-8 and slash");
}

static void expect_f64(double v, const char *want) {
  char what[64];
  snprintf(what, sizeof what, "double %a", v);
  expect_out(w_f64, &v, want, what);
}

static void test_f64(void) {
  /* Hand-computed: %.15g when it reads back, else %.16g, else %.17g. */
  expect_f64(0.0, "0");
  expect_f64(-0.0, "-0");
  expect_f64(1.0, "1");
  expect_f64(0.5, "0.5");
  expect_f64(0.1, "0.1");
  expect_f64(-2.25, "-2.25");
  expect_f64(1e300, "1e+300");
  expect_f64(1.0 / 3.0, "0.3333333333333333");        /* 16 digits */
  expect_f64(9007199254740992.0, "9007199254740992"); /* 2^53: 16 digits */
  expect_f64(0.1 + 0.2, "0.30000000000000004");       /* 17 digits */
  expect_f64(1.7976931348623157e308, "1.7976931348623157e+308");
  expect_f64(5e-324, "4.94065645841247e-324"); /* 15 digits read it back; not "5e-324" */
  expect_f64(1386126720.0, "1386126720");
  /* From 1 digit up (machine config values): the shortest, exponent and all. */
  static const struct {
    double v;
    const char *want;
  } shortest[] = {{1.4, "1.4"},
                  {1000, "1e+03"},
                  {1386126720.0, "1.38612672e+09"},
                  {5e-324, "5e-324"},
                  {0.1 + 0.2, "0.30000000000000004"},
                  {1e-6, "1e-06"}};
  for (size_t i = 0; i < sizeof shortest / sizeof shortest[0]; i++) {
    char buf[64];
    stats_f64_text(shortest[i].v, 1, buf, sizeof buf);
    EXPECTF(!strcmp(buf, shortest[i].want), "%a: got %s, expected %s", shortest[i].v, buf,
            shortest[i].want);
  }
  /* Random bit patterns: every finite one reads back the same bits. */
  uint64_t s = 21, bad = 0, tried = 0;
  for (unsigned i = 0; i < 20000; i++) {
    s = s * 6364136223846793005ull + 1442695040888963407ull;
    uint64_t bits = s ^ (s >> 29);
    double v;
    memcpy(&v, &bits, sizeof v);
    if (!isfinite(v)) continue;
    tried++;
    char *txt = capture(w_f64, &v);
    double back = strtod(txt, NULL);
    if (memcmp(&back, &v, sizeof v) != 0 && bad++ < 5)
      fprintf(stderr, "%a printed %s read back %a\n", v, txt, back);
    free(txt);
  }
  EXPECTF(bad == 0, "%llu of %llu doubles did not read back", (unsigned long long)bad,
          (unsigned long long)tried);
}

static void test_table(void) {
  struct stats_table t = {0};
  stats_u64(&t, "cycles", 12345);
  stats_u64(&t, "max_u64", UINT64_MAX);
  stats_f64(&t, "hit_fraction", 0.75);
  stats_str(&t, "scene", "room, small");
  stats_str(&t, "policy", "say \"hi\"");
  EXPECT(t.n == 5);
  EXPECT(t.e[1].kind == STATS_U64 && t.e[1].u == UINT64_MAX);
  EXPECT(t.e[2].kind == STATS_F64 && t.e[2].f == 0.75);
  expect_out(w_header, &t, "cycles,max_u64,hit_fraction,scene,policy\n", "CSV header");
  expect_out(w_row, &t, "12345,18446744073709551615,0.75,\"room, small\",\"say \"\"hi\"\"\"\n",
             "CSV row");
  expect_out(w_members, &t,
             "  \"cycles\": 12345,\n  \"max_u64\": 18446744073709551615,\n"
             "  \"hit_fraction\": 0.75,\n  \"scene\": \"room, small\",\n"
             "  \"policy\": \"say \\\"hi\\\"\"",
             "JSON members");
  stats_fini(&t);
  EXPECT(t.e == NULL && t.n == 0 && t.cap == 0);

  /* Empty: an empty line of CSV, no JSON members. */
  expect_out(w_header, &t, "\n", "empty header");
  expect_out(w_row, &t, "\n", "empty row");
  expect_out(w_members, &t, "", "no members");

  /* Insertion order kept past the table's growth; 63-character names fit. */
  char name[64];
  for (unsigned i = 0; i < 200; i++) {
    snprintf(name, sizeof name, "n%u", i);
    stats_u64(&t, name, 1000u + i);
  }
  memset(name, 'x', 63);
  name[63] = 0;
  stats_u64(&t, name, 7);
  unsigned out_of_order = 0;
  for (unsigned i = 0; i < 200; i++) {
    char want[16];
    snprintf(want, sizeof want, "n%u", i);
    out_of_order += strcmp(t.e[i].name, want) != 0 || t.e[i].u != 1000u + i;
  }
  EXPECTF(out_of_order == 0, "%u of 200 entries moved or changed", out_of_order);
  EXPECT(t.n == 201 && strcmp(t.e[200].name, name) == 0);
  stats_fini(&t);

  /* A string value keeps its first 255 bytes. */
  char longv[400];
  memset(longv, 'v', sizeof longv - 1);
  longv[sizeof longv - 1] = 0;
  stats_str(&t, "long", longv);
  EXPECT(strlen(t.e[0].s) == 255);
  stats_fini(&t);
}

/* A stats call in a child that must die of its CHECK (stderr silenced). */
static bool dies(void (*fn)(void)) {
  fflush(NULL);
  pid_t pid = fork();
  if (pid == 0) {
    if (!freopen("/dev/null", "w", stderr)) _exit(0);
    fn();
    _exit(0);
  }
  int st = 0;
  waitpid(pid, &st, 0);
  return !(WIFEXITED(st) && WEXITSTATUS(st) == 0);
}

static void add_nan(void) {
  struct stats_table t = {0};
  stats_f64(&t, "x", NAN);
}
static void add_inf(void) {
  struct stats_table t = {0};
  stats_f64(&t, "x", -INFINITY);
}
static void add_long_name(void) {
  struct stats_table t = {0};
  char name[65];
  memset(name, 'x', 64);
  name[64] = 0;
  stats_u64(&t, name, 1);
}
static void add_fine(void) {
  struct stats_table t = {0};
  stats_f64(&t, "x", 1.0);
  stats_fini(&t);
}

static void test_checks(void) {
  EXPECT(dies(add_nan));
  EXPECT(dies(add_inf));
  EXPECT(dies(add_long_name)); /* 64 characters leave no room for the NUL */
  EXPECT(!dies(add_fine));     /* the harness itself does not die */
}

/* ---- descriptors ---- */

/* A component with three counters; its table below forgets one. */
struct toy_stats {
  uint64_t a, b, c;
  struct toy_sub {
    uint64_t x, y;
  } sub;
};
static const struct stats_desc toy_sub_desc[] = {
    STATS_FIELD(struct toy_sub, x, "x", "count", "x"),
    STATS_FIELD(struct toy_sub, y, "y", "count", "y"),
};
static const struct stats_descs toy_sub = {"sub", toy_sub_desc, 2, sizeof(struct toy_sub), NULL, 0};
static const struct stats_descs toy_sub_short = {
    "sub", toy_sub_desc, 1, sizeof(struct toy_sub), NULL, 0};
static const struct stats_desc toy_desc[] = {
    STATS_FIELD(struct toy_stats, a, "a", "count", "a"),
    STATS_FIELD(struct toy_stats, c, "c", "count", "c"),
};

static void test_uncovered(void) {
  char buf[256];
  /* b has no descriptor and no reason: found, with its bytes */
  const struct stats_skip sub[] = {STATS_SKIP_BY(struct toy_stats, sub, toy_sub)};
  struct stats_descs g = {"toy", toy_desc, 2, sizeof(struct toy_stats), sub, 1};
  const char *why = stats_uncovered(&g, buf, sizeof buf);
  EXPECT(why && strstr(why, "toy: bytes 8..15 "));
  /* a reason covers it */
  const struct stats_skip both[] = {STATS_SKIP_BY(struct toy_stats, sub, toy_sub),
                                    STATS_SKIP(struct toy_stats, b, "not written, because")};
  g.skip = both;
  g.nskip = 2;
  EXPECT(stats_uncovered(&g, buf, sizeof buf) == NULL);
  /* a field the other table forgets is found through it */
  const struct stats_skip short_sub[] = {STATS_SKIP_BY(struct toy_stats, sub, toy_sub_short),
                                         STATS_SKIP(struct toy_stats, b, "not written, because")};
  g.skip = short_sub;
  why = stats_uncovered(&g, buf, sizeof buf);
  EXPECTF(why && strstr(why, "bytes 32..39 "), "%s", why ? why : "(none)");
}

/* Every component's table: every byte of its stats struct reaches the files
 * or is skipped with a reason; names are unique (but for a figure written
 * only when present, in place of another's: dram_utilization) and say a unit. */
static void test_components(void) {
  const struct stats_descs *const all[] = {
      &machine_stats_descs,           &machine_l1_stats_descs,  &machine_engine_stats_descs,
      &machine_dram_util_stats_descs, &l2_stats_descs,          &dram_stats_descs,
      &dram_channel_stats_descs,      &dram_banked_stats_descs, &dram_energy_estimate_stats_descs};
  const unsigned n = sizeof all / sizeof all[0];
  char buf[256];
  for (unsigned i = 0; i < n; i++) {
    const char *why = stats_uncovered(all[i], buf, sizeof buf);
    EXPECTF(why == NULL, "%s", why);
    for (unsigned j = 0; j < all[i]->n; j++) {
      const struct stats_desc *d = &all[i]->d[j];
      if (d->how == STATS_HOW_AT) continue;
      EXPECTF(d->unit[0] && d->desc[0], "%s: unit and description", d->name);
      for (unsigned k = i; k < n; k++)
        for (unsigned l = k == i ? j + 1 : 0; l < all[k]->n; l++)
          EXPECTF(strcmp(d->name, all[k]->d[l].name) || all[k]->d[l].how == STATS_HOW_AT ||
                      d->present || all[k]->d[l].present,
                  "%s named twice", d->name);
    }
  }
}

/* Every column the machine adds to its timeline is written: declared once. */
static void test_timeline_cols(void) {
  unsigned seen[MACHINE_TL_COLS] = {0};
  for (unsigned j = 0; j < machine_tl_col_count; j++) {
    const struct timeline_col *c = &machine_tl_cols[j];
    EXPECT(c->span >= 1 && c->unit[0] && c->desc[0]);
    EXPECT(c->per_class ? c->span == MEM_CLASS_MAX : c->span == 1);
    for (unsigned k = 0; k < c->span && c->col + k < MACHINE_TL_COLS; k++) seen[c->col + k]++;
    EXPECT(c->col + c->span <= MACHINE_TL_COLS);
  }
  for (unsigned i = 0; i < MACHINE_TL_COLS; i++)
    EXPECTF(seen[i] == 1, "timeline column %u: %u descriptors", i, seen[i]);
}

/* docs/stats.md's table of numbers is `rtsim run --help-stats-markdown`. */
static void test_readme(void) {
  FILE *p = popen(RTSIM_BINARY " run --help-stats-markdown", "r");
  static char want[1 << 16], readme[1 << 20];
  size_t wn = fread(want, 1, sizeof want - 1, p);
  want[wn] = '\0';
  EXPECT(pclose(p) == 0 && wn > 0);
  FILE *f = fopen(RTSIM_SOURCE_DIR "/docs/stats.md", "r");
  EXPECT(f != NULL);
  if (!f) return;
  size_t rn = fread(readme, 1, sizeof readme - 1, f);
  readme[rn] = '\0';
  fclose(f);
  static const char begin[] = "<!-- numbers: rtsim run --help-stats-markdown -->\n";
  const char *a = strstr(readme, begin);
  const char *h = a ? strstr(a, "|---|") : NULL;
  const char *b = strstr(readme, "<!-- numbers end -->");
  EXPECTF(a && h && b && h < b, "docs/stats.md: the table between the markers");
  if (!(a && h && b && h < b)) return;
  h = strchr(h, '\n') + 1;
  const size_t have = (size_t)(b - h);
  EXPECTF(have == wn && !memcmp(h, want, wn),
          "docs/stats.md differs from rtsim run --help-stats-markdown: paste its output "
          "between the markers");
}

int main(void) {
  test_uncovered();
  test_components();
  test_timeline_cols();
  test_readme();
  test_csv_str();
  test_json_str();
  test_f64();
  test_table();
  test_checks();
  return testing_done("test_stats");
}
