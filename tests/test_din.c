/* sim/din: the exact record text, write -> read -> replay gives the same misses
 * as feeding the accesses directly (through a naive LRU and the one-pass stack),
 * the functional backend's trace replays to its own counts, malformed input
 * fails with file:line:column, and failed or abandoned writes leave no file. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "sim/din.h"
#include "sim/err.h"
#include "sim/lru_stack.h"
#include "sim/mem_functional.h"
#include "testing.h"

/* ---- A naive oracle: per size, an array of (line, last use, dirty). ------ */
enum { NV_SIZES = 7, NV_MAX = 64 }; /* 1 .. 64 lines */

struct nv_cache {
  unsigned cap, count;
  uint64_t line[NV_MAX], used[NV_MAX];
  int dirty[NV_MAX];
  uint64_t misses, wb;
};

struct nv {
  uint64_t clock;
  struct nv_cache c[NV_SIZES];
};

static void nv_init(struct nv *n) {
  memset(n, 0, sizeof *n);
  for (unsigned i = 0; i < NV_SIZES; i++) n->c[i].cap = 1u << i;
}

/* Replays as Dinero IV with write-allocate "nofetch" (-walloc f), the policy
 * rtsim's traces are written for: a write record allocates without a fetch. */
static void nv_access(struct nv *n, uint64_t line, int store) {
  n->clock++;
  for (unsigned i = 0; i < NV_SIZES; i++) {
    struct nv_cache *c = &n->c[i];
    unsigned k = 0;
    while (k < c->count && c->line[k] != line) k++;
    if (k == c->count) {
      c->misses += !store;
      if (c->count == c->cap) {
        k = 0;
        for (unsigned j = 1; j < c->count; j++)
          if (c->used[j] < c->used[k]) k = j;
        c->wb += c->dirty[k] != 0;
      } else {
        c->count++;
      }
      c->line[k] = line;
      c->dirty[k] = 0;
    }
    c->used[k] = n->clock;
    c->dirty[k] |= store;
  }
}

/* ---- Replay sinks. ------------------------------------------------------ */
struct sink {
  struct nv nv;
  struct lru_stack *ls;
  uint64_t records, reads, writes;
};

static void sink_init(struct sink *s) {
  nv_init(&s->nv);
  struct lru_stack_params p = {6, 6, 12};
  s->ls = lru_stack_create(&p);
  s->records = s->reads = s->writes = 0;
}

static void sink_line(struct sink *s, uint64_t addr, int store) {
  nv_access(&s->nv, addr >> 6, store);
  lru_stack_access(s->ls, addr >> 6, store ? LRU_STACK_WRITE_LINE : LRU_STACK_READ, 0);
}

static void on_record(void *ctx, unsigned label, uint64_t addr) {
  struct sink *s = ctx;
  s->records++;
  s->reads += label == DIN_LABEL_READ;
  s->writes += label == DIN_LABEL_WRITE;
  sink_line(s, addr, label == DIN_LABEL_WRITE);
}

static void expect_same(const char *what, struct sink *a, struct sink *b) {
  for (unsigned i = 0; i < NV_SIZES; i++) {
    EXPECTF(a->nv.c[i].misses == b->nv.c[i].misses, "%s: naive size %u: %llu vs %llu misses", what,
            i, (unsigned long long)a->nv.c[i].misses, (unsigned long long)b->nv.c[i].misses);
    EXPECTF(a->nv.c[i].wb == b->nv.c[i].wb, "%s: naive size %u writebacks", what, i);
    EXPECTF(lru_stack_misses(a->ls, i, 0) == lru_stack_misses(b->ls, i, 0),
            "%s: stack size %u: %llu vs %llu misses", what, i,
            (unsigned long long)lru_stack_misses(a->ls, i, 0),
            (unsigned long long)lru_stack_misses(b->ls, i, 0));
    EXPECTF(lru_stack_writebacks(a->ls, i, 0) == lru_stack_writebacks(b->ls, i, 0),
            "%s: stack size %u writebacks", what, i);
    /* And the oracle agrees with the stack. */
    EXPECT(a->nv.c[i].misses == lru_stack_misses(a->ls, i, 0));
    EXPECT(a->nv.c[i].wb == lru_stack_writebacks(a->ls, i, 0));
  }
}

static int file_exists(const char *path) { return access(path, F_OK) == 0; }

static char *slurp(const char *path) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  static char buf[1 << 16];
  size_t n = fread(buf, 1, sizeof buf - 1, f);
  buf[n] = '\0';
  fclose(f);
  return buf;
}

static void write_text(const char *path, const char *text) {
  FILE *f = fopen(path, "wb");
  CHECK(f != NULL);
  fputs(text, f);
  fclose(f);
}

static uint64_t rng_next(uint64_t *s) {
  uint64_t z = (*s += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

static void test_exact_text(void) {
  const char *path = RTSIM_TMP "/test_din_text.din";
  remove(path); /* from an earlier run */
  struct err e = {0};
  struct din_writer *w = din_writer_open(path, 6, &e);
  EXPECT(w != NULL && !e.set);
  if (!w) return;
  din_writer_access(w, 0x1000, 4, false);          /* one line */
  din_writer_access(w, 0x103c, 8, true);           /* crosses into the next line */
  din_writer_access(w, 0, 1, false);               /* address zero */
  din_writer_access(w, 0x7f0, 0x81, false);        /* 0x7f0 .. 0x870: three lines */
  din_writer_access(w, UINT64_MAX - 63, 64, true); /* the very last line */
  din_writer_record(w, 0xabcdef, false);
  EXPECT(din_writer_records(w) == 9);
  EXPECT(!file_exists(path));
  EXPECT(din_writer_close(w, &e) && !e.set);
  const char *want = "0 1000\n1 103c\n1 1040\n0 0\n0 7f0\n0 800\n0 840\n1 ffffffffffffffc0\n"
                     "0 abcdef\n";
  const char *got = slurp(path);
  EXPECTF(got && strcmp(got, want) == 0, "din text:\n%s", got ? got : "(missing)");
  EXPECT(testing_temps_of(path) == 0);
  EXPECT(din_writer_close(NULL, &e));
}

/* Write a random trace, read it back, replay; compare with direct feeding. */
static void test_roundtrip(void) {
  const char *path = RTSIM_TMP "/test_din_roundtrip.din";
  struct err e = {0};
  struct din_writer *w = din_writer_open(path, 6, &e);
  EXPECT(w != NULL);
  if (!w) return;
  struct sink direct, replay;
  sink_init(&direct);
  sink_init(&replay);
  uint64_t rng = 5, lines_fed = 0;
  const uint64_t base = UINT64_C(0x7fff00000000);
  for (int k = 0; k < 40000; k++) {
    uint64_t r = rng_next(&rng);
    /* Mostly a 100-line region, sometimes far away; sizes 1..200 bytes. */
    uint64_t addr = (r % 8 ? base : base * 3) + (r >> 8) % (100 * 64);
    uint32_t size = 1 + (uint32_t)((r >> 32) % 200);
    int store = (r >> 50) % 10 < 3;
    din_writer_access(w, addr, size, store);
    for (uint64_t l = addr >> 6; l <= (addr + size - 1) >> 6; l++) {
      sink_line(&direct, l << 6, store);
      lines_fed++;
    }
  }
  EXPECT(din_writer_records(w) == lines_fed);
  EXPECT(din_writer_close(w, &e));
  uint64_t n = 0;
  EXPECT(din_read_file(path, on_record, &replay, &n, &e) && !e.set);
  EXPECTF(n == lines_fed && replay.records == lines_fed, "%llu records read, %llu written",
          (unsigned long long)n, (unsigned long long)lines_fed);
  EXPECT(replay.reads + replay.writes == n);
  expect_same("din replay", &direct, &replay);
  lru_stack_destroy(direct.ls);
  lru_stack_destroy(replay.ls);
}

/* The functional backend's din trace replays to the backend's own counts. */
static void test_backend_trace(void) {
  const char *path = RTSIM_TMP "/test_din_backend.din";
  struct err e = {0};
  struct din_writer *w = din_writer_open(path, 6, &e);
  EXPECT(w != NULL);
  if (!w) return;
  struct lru_stack_params p = {6, 6, 12};
  struct mem_functional *b = mem_functional_create(&p, w, false);
  struct mem_port port = mem_functional_port(b);
  uint64_t rng = 11;
  for (int k = 0; k < 30000; k++) {
    uint64_t r = rng_next(&rng);
    uint64_t addr = 4096 + (r % (120 * 64));
    uint32_t size = (r >> 20) % 3 == 0 ? 64 : (r >> 20) % 3 == 1 ? 8 : 128;
    unsigned cls = (unsigned)((r >> 40) % MEM_CLASS_MAX);
    if ((r >> 50) % 4 == 0) mem_store(&port, addr, size, cls);
    else mem_load(&port, addr, size, cls);
    mem_compute(&port, 10);
  }
  /* A line access is one record, or two (read, write) for a store to part of
   * a line. */
  uint64_t lines = 0, records = din_writer_records(w);
  for (unsigned c = 0; c < MEM_CLASS_MAX; c++)
    lines += mem_functional_get_stats(b)->line_accesses[c];
  EXPECTF(records > lines && records < 2 * lines, "%llu records for %llu line accesses",
          (unsigned long long)records, (unsigned long long)lines);
  EXPECT(din_writer_close(w, &e));
  struct sink replay;
  sink_init(&replay);
  EXPECT(din_read_file(path, on_record, &replay, NULL, &e));
  EXPECT(replay.records == records);
  struct lru_stack *ls = mem_functional_stack(b);
  struct lru_stack_results r;
  lru_stack_get_results(ls, &r);
  for (unsigned i = 0; i < NV_SIZES; i++) {
    uint64_t m = 0, wb = 0;
    for (unsigned c = 0; c < MEM_CLASS_MAX; c++) {
      m += r.size[i].misses[c];
      wb += r.size[i].writebacks[c];
    }
    EXPECTF(m == replay.nv.c[i].misses, "backend size %u: %llu misses, replay %llu", i,
            (unsigned long long)m, (unsigned long long)replay.nv.c[i].misses);
    EXPECT(m == lru_stack_misses(replay.ls, i, 0));
    EXPECT(wb == replay.nv.c[i].wb);
  }
  mem_functional_destroy(b);
  lru_stack_destroy(replay.ls);
}

static void noop_record(void *ctx, unsigned label, uint64_t addr) {
  (void)label;
  (void)addr;
  (*(uint64_t *)ctx)++;
}

struct collect {
  unsigned n;
  unsigned label[8];
  uint64_t addr[8];
};

static void collect_record(void *ctx, unsigned label, uint64_t addr) {
  struct collect *c = ctx;
  if (c->n < 8) {
    c->label[c->n] = label;
    c->addr[c->n] = addr;
  }
  c->n++;
}

static void test_malformed(void) {
  static const struct {
    const char *text;
    int line, col;
    uint64_t delivered;
    const char *msg;
  } cases[] = {
      {"0 1000\nx 2000\n", 2, 1, 1, "bad label"},
      {"0 1000\n0 12g4\n", 2, 5, 1, "bad address (got 'g'"},
      {"0 1000\n1\n", 2, 2, 1, "missing address"},
      {"0 1000\n1  \t\n", 2, 5, 1, "missing address"},
      {"1 20", 0, 0, 1, ""},
      {"0 1000\n\n0 2000\n", 2, 1, 1, "missing label"},
      {"7 1000\n", 1, 1, 0, "unknown label"},
      {"  10 1000\n", 1, 3, 0, "unknown label"},
      {"0z 100\n", 1, 2, 0, "bad label (got 'z'"},
      {"0 0x\n", 1, 5, 0, "bad address (got end of line"},
      {"0 x12\n", 1, 3, 0, "bad address (got 'x'"},
      {"2 10000000000000000\n", 1, 3, 0, "beyond 64 bits"},
      {"2 ffffffffffffffff\n0 0x0000000000000000001\n", 0, 0, 2, ""},
      {"0 -5\n", 1, 3, 0, "bad address (got '-'"},
  };
  const char *path = RTSIM_TMP "/test_din_bad.din";
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    write_text(path, cases[i].text);
    struct err e = {0};
    uint64_t n = 0, seen = 0;
    bool ok = din_read_file(path, noop_record, &seen, &n, &e);
    EXPECTF(n == cases[i].delivered && seen == n, "case %zu: %llu records delivered", i,
            (unsigned long long)n);
    if (!cases[i].msg[0]) {
      EXPECTF(ok && !e.set, "case %zu: unexpected error %s", i, e.msg);
      continue;
    }
    char buf[2048];
    err_format(&e, buf, sizeof buf);
    EXPECTF(!ok && e.set && e.line == cases[i].line && e.col == cases[i].col &&
                strcmp(e.file, path) == 0 && strstr(e.msg, cases[i].msg),
            "case %zu: got '%s', want %d:%d '%s'", i, buf, cases[i].line, cases[i].col,
            cases[i].msg);
  }
  /* What Dinero's reader tolerates: blanks, 0x prefixes, comments after. */
  write_text(path, "0 0x1f a comment\n  2\tabc\n0x1 20\n1 FfE0 rest\n4 40\n");
  struct collect c = {0};
  struct err e = {0};
  EXPECT(din_read_file(path, collect_record, &c, NULL, &e));
  EXPECT(c.n == 5);
  EXPECT(c.label[0] == 0 && c.addr[0] == 0x1f);
  EXPECT(c.label[1] == 2 && c.addr[1] == 0xabc);
  EXPECT(c.label[2] == 1 && c.addr[2] == 0x20);
  EXPECT(c.label[3] == 1 && c.addr[3] == 0xffe0);
  EXPECT(c.label[4] == DIN_LABEL_COPYBACK && c.addr[4] == 0x40);
  /* A missing file. */
  struct err e2 = {0};
  const char *missing = RTSIM_TMP "/no_such_file.din";
  EXPECT(!din_read_file(missing, noop_record, &c, NULL, &e2));
  EXPECT(e2.set && strcmp(e2.file, missing) == 0 && e2.line == 0);
}

static void test_write_failures(void) {
  /* Into a directory that does not exist: fails cleanly, leaves nothing. */
  const char *path = RTSIM_TMP "/no_such_dir/trace.din";
  struct err e = {0};
  struct din_writer *w = din_writer_open(path, 6, &e);
  EXPECT(w == NULL);
  EXPECT(e.set && strcmp(e.file, path) == 0 && strstr(e.msg, "cannot create"));
  EXPECT(!file_exists(path));

  /* Abandoned: no file, no temporary; an earlier complete trace survives. */
  const char *keep = RTSIM_TMP "/test_din_keep.din";
  remove(keep);
  struct err e3 = {0};
  w = din_writer_open(keep, 6, &e3);
  EXPECT(w != NULL);
  if (w) {
    din_writer_access(w, 64, 1, true);
    EXPECT(din_writer_close(w, &e3));
  }
  w = din_writer_open(keep, 6, &e3);
  EXPECT(w != NULL);
  if (w) {
    din_writer_access(w, 128, 1, false);
    din_writer_discard(w);
  }
  EXPECT(testing_temps_of(keep) == 0);
  const char *got = slurp(keep);
  EXPECT(got && strcmp(got, "1 40\n") == 0);
  din_writer_discard(NULL);
  EXPECT(!e3.set);
}

int main(void) {
  test_exact_text();
  test_roundtrip();
  test_backend_trace();
  test_malformed();
  test_write_failures();
  return testing_done("test_din");
}
