/* Functional backend: line splitting in front of the LRU stack analyser.
 * NOTE: the analyser stays opaque (one call per line, except repeats of the
 * last line, counted here); inlining its lookup here would save a call (~1 ns)
 * against a hash probe and list update that cost far more, so it is not worth
 * exposing its internals. */
#include "sim/mem_functional.h"

#include <stdbool.h>
#include <stdlib.h>

#include "sim/din.h"
#include "sim/err.h"

struct mem_functional {
  struct lru_stack *ls;
  struct din_writer *din; /* borrowed, may be NULL */
  unsigned lg2_line;
  /* The line last passed to the analyser (its top line), the class of that
   * line's last access (FN_NO_CLASS before the first) and whether it has been
   * stored to since it reached the top, i.e. is dirty in every size. */
  uint64_t last_line;
  unsigned last_cls;
  bool last_dirty;
  /* Repeats kept from the analyser, by class: [0] loads, [1] stores. */
  uint64_t repeats[MEM_CLASS_MAX][2];
  struct mem_functional_stats st;
};

#define FN_NO_CLASS MEM_CLASS_MAX

/* Feed every line of [addr, addr + size) to the analyser (and the trace). A
 * store covering a line whole allocates it without a fetch (LRU_STACK_WRITE_LINE);
 * a store to part of a line fetches it first (LRU_STACK_WRITE). In the din trace the
 * latter is a read record then a write record, so Dinero IV replays both kinds
 * exactly with its write-allocate policy "nofetch" (-lN-Twalloc f). */
static inline void fn_line(struct mem_functional *b, uint64_t line, enum lru_stack_op op,
                           unsigned cls) {
  if (b->din) {
    uint64_t a = line << b->lg2_line;
    if (op != LRU_STACK_WRITE_LINE) din_writer_record(b->din, a, false);
    if (op != LRU_STACK_READ) din_writer_record(b->din, a, true);
  }
  /* The last line again, same class, and no clean line to dirty: a hit in every
   * size that changes nothing but counters (a quarter of the accesses on grove).
   * Count it here and skip the analyser's call; mem_functional_stack hands the
   * counts over. A whole-line store to it is such a store too: no fetch either way. */
  const bool store = op != LRU_STACK_READ;
  if (line == b->last_line && cls == b->last_cls && (!store || b->last_dirty)) {
    b->repeats[cls][store]++;
    return;
  }
  b->last_dirty = store || (line == b->last_line && b->last_dirty);
  b->last_line = line;
  b->last_cls = cls;
  lru_stack_access(b->ls, line, op, cls);
}

static inline void fn_access(struct mem_functional *b, uint64_t addr, uint32_t size, bool is_store,
                             unsigned cls) {
  CHECK_GT(size, 0);
  CHECK_LT(cls, MEM_CLASS_MAX);
  uint64_t last = addr + (size - 1);
  CHECK_GE(last, addr); /* an access may not wrap past 2^64 */
  uint64_t line = addr >> b->lg2_line, end = last >> b->lg2_line;
  b->st.line_accesses[cls] += end - line + 1;
  if (!is_store) {
    for (;;) {
      fn_line(b, line, LRU_STACK_READ, cls);
      if (line == end) break;
      line++;
    }
    return;
  }
  const uint64_t lmask = (UINT64_C(1) << b->lg2_line) - 1;
  /* Lines first..final are covered whole; the ends may be partial. */
  uint64_t first = (addr & lmask) ? line + 1 : line;
  bool last_whole = (last & lmask) == lmask;
  for (;;) {
    bool whole = line >= first && (line < end || last_whole);
    fn_line(b, line, whole ? LRU_STACK_WRITE_LINE : LRU_STACK_WRITE, cls);
    if (line == end) break;
    line++;
  }
}

static void fn_load(void *ctx, uint64_t addr, uint32_t size_bytes, unsigned cls) {
  struct mem_functional *b = ctx;
  fn_access(b, addr, size_bytes, false, cls);
  b->st.loads[cls]++;
  b->st.bytes_loaded[cls] += size_bytes;
}

static void fn_store(void *ctx, uint64_t addr, uint32_t size_bytes, unsigned cls) {
  struct mem_functional *b = ctx;
  fn_access(b, addr, size_bytes, true, cls);
  b->st.stores[cls]++;
  b->st.bytes_stored[cls] += size_bytes;
}

/* compute and wait are NULL: skipped without an indirect call. */
static const struct mem_ops fn_ops = {fn_load, fn_store, NULL, NULL, NULL, NULL};

struct mem_functional *mem_functional_create(const struct lru_stack_params *p,
                                             struct din_writer *din) {
  struct mem_functional *b = xcalloc(1, sizeof *b);
  b->ls = lru_stack_create(p);
  b->din = din;
  b->lg2_line = p->lg2_line;
  b->last_cls = FN_NO_CLASS;
  return b;
}

void mem_functional_destroy(struct mem_functional *b) {
  if (!b) return;
  lru_stack_destroy(b->ls);
  free(b);
}

struct mem_port mem_functional_port(struct mem_functional *b) {
  struct mem_port port = {&fn_ops, b};
  return port;
}

struct lru_stack *mem_functional_stack(struct mem_functional *b) {
  for (unsigned c = 0; c < MEM_CLASS_MAX; c++) {
    if (b->repeats[c][0] | b->repeats[c][1])
      lru_stack_count_repeats(b->ls, c, b->repeats[c][0], b->repeats[c][1]);
    b->repeats[c][0] = b->repeats[c][1] = 0;
  }
  return b->ls;
}

const struct mem_functional_stats *mem_functional_get_stats(const struct mem_functional *b) {
  return &b->st;
}
