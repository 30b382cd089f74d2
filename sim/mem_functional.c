/* Functional backend: line splitting in front of the LRU stack analyser.
 * NOTE: the analyser stays opaque: it gets the lines (except repeats of the
 * last line, counted here) in batches of records, which lets it fetch ahead
 * (lru_stack_access_batch); inlining its lookup here would save little against
 * a hash probe and list update that cost far more.
 * With a second host thread (mem_functional_create's analyser_thread), the
 * lines bound for the analyser go into batches handed to that thread through a
 * ring of FN_BATCHES: the tracer and the analyser then run at once, the
 * analyser seeing the same lines in the same order, so its counts are the
 * same. Everything else (line splitting, the repeat filter, the din trace,
 * the request counts) stays on the caller's thread. */
#define _GNU_SOURCE /* sched_getaffinity, CPU_COUNT */
#include "sim/mem_functional.h"

#include <pthread.h>
#include <sched.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdlib.h>

#include "sim/din.h"
#include "sim/err.h"

/* Lines a batch carries, and batches in the ring: 4 x 65,536 lines (512 KiB
 * of records each) keep the two threads a batch or more apart, with one
 * handover a batch. A handover to a sleeping thread is a system call and a
 * wake-up, slow on a virtual host, so batches are large: 16,384 lines cost
 * a few percent more wall time. */
#define FN_BATCH_LINES 65536u
#define FN_BATCHES 4u
/* A thread that finds the ring empty (full) polls it this many times (a few
 * microseconds) before it sleeps: a handover then costs no system call while
 * the two keep pace, and polling longer would take a host core from other
 * work (a sweep runs a process per core). */
#define FN_SPINS 200
/* Lines held back on the caller's thread (no analyser thread) to be analysed
 * together: the analyser fetches the host cache lines of the accesses ahead
 * of the one it works on (lru_stack_access_batch). 8 KiB of records. */
#define FN_LOCAL_LINES 1024u

/* A line's record: line << 5 | cls << 2 | op (a line number is below 2^59
 * with lines of 32 bytes or more). Each batch starts a host cache line, so
 * the two threads share none but the ones they hand over. */
#define FN_REC LRU_STACK_REC
struct fn_batch {
  _Alignas(64) uint32_t n;
  uint64_t rec[FN_BATCH_LINES];
};

/* The ring between the caller (producer) and the analyser thread (consumer).
 * Batches [tail, head) are published and not yet analysed; the producer fills
 * batch head % FN_BATCHES, which it owns while head - tail < FN_BATCHES. Only
 * the producer moves head and only the consumer tail. A thread about to sleep
 * raises its flag and looks at the ring again, and a thread that moved its
 * index looks at the other's flag (both sequentially consistent), so one of
 * the two always sees the other: no wake-up is lost. */
struct fn_pipe {
  pthread_t thread;
  pthread_mutex_t mu;
  pthread_cond_t filled, emptied;
  struct lru_stack *ls; /* borrowed from the backend */
  _Atomic bool stop;
  /* Each thread's own writes on a host cache line of their own. */
  _Alignas(64) _Atomic uint64_t head;
  _Atomic bool producer_sleeps;
  _Alignas(64) _Atomic uint64_t tail;
  _Atomic bool consumer_sleeps;
  struct fn_batch b[FN_BATCHES];
};

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
  struct fn_pipe *pipe;           /* NULL: the analyser runs on the caller's thread */
  uint64_t *fill;                 /* the records of the batch being filled (a pipe's or local) */
  uint32_t fill_n;                /* and how many it holds */
  uint32_t fill_cap;              /* 0: records unused (lines under 32 bytes): one call a line */
  bool fast_loads;                /* records in use and no din trace: fn_load's short path */
  uint64_t local[FN_LOCAL_LINES]; /* the batch without a pipe */
};

#define FN_NO_CLASS MEM_CLASS_MAX

static void lock(pthread_mutex_t *mu) { CHECK(pthread_mutex_lock(mu) == 0); }
static void unlock(pthread_mutex_t *mu) { CHECK(pthread_mutex_unlock(mu) == 0); }

static inline void relax(void) {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#endif
}

/* Wake the other side if it sleeps (or is about to) on cv. */
static void poke(struct fn_pipe *q, _Atomic bool *sleeps, pthread_cond_t *cv) {
  if (!atomic_load(sleeps)) return;
  lock(&q->mu);
  CHECK(pthread_cond_signal(cv) == 0);
  unlock(&q->mu);
}

/* The consumer: true when batch tail is published, false when stopped with
 * nothing left. */
static bool wait_filled(struct fn_pipe *q, uint64_t tail) {
  for (int i = 0; i < FN_SPINS; i++) {
    if (atomic_load_explicit(&q->head, memory_order_acquire) != tail) return true;
    relax();
  }
  lock(&q->mu);
  atomic_store(&q->consumer_sleeps, true);
  while (atomic_load(&q->head) == tail && !atomic_load(&q->stop))
    CHECK(pthread_cond_wait(&q->filled, &q->mu) == 0);
  atomic_store(&q->consumer_sleeps, false);
  unlock(&q->mu);
  return atomic_load(&q->head) != tail;
}

/* The producer: until fewer than `most` batches are published and not yet
 * analysed. */
static void wait_emptied(struct fn_pipe *q, uint64_t head, uint64_t most) {
  for (int i = 0; i < FN_SPINS; i++) {
    if (head - atomic_load_explicit(&q->tail, memory_order_acquire) < most) return;
    relax();
  }
  lock(&q->mu);
  atomic_store(&q->producer_sleeps, true);
  while (head - atomic_load(&q->tail) >= most) CHECK(pthread_cond_wait(&q->emptied, &q->mu) == 0);
  atomic_store(&q->producer_sleeps, false);
  unlock(&q->mu);
}

static void *analyser_main(void *arg) {
  struct fn_pipe *q = arg;
  for (uint64_t tail = 0; wait_filled(q, tail);) {
    const struct fn_batch *bt = &q->b[tail % FN_BATCHES];
    lru_stack_access_batch(q->ls, bt->rec, bt->n);
    atomic_store(&q->tail, ++tail);
    poke(q, &q->producer_sleeps, &q->emptied);
  }
  return NULL;
}

/* Publish the batch being filled (if it holds lines) and take the next one,
 * waiting while the ring is full. */
static void pipe_publish(struct mem_functional *b) {
  struct fn_pipe *q = b->pipe;
  if (b->fill_n == 0) return;
  const uint64_t head = atomic_load_explicit(&q->head, memory_order_relaxed) + 1;
  q->b[(head - 1) % FN_BATCHES].n = b->fill_n;
  atomic_store(&q->head, head);
  poke(q, &q->consumer_sleeps, &q->filled);
  wait_emptied(q, head, FN_BATCHES);
  b->fill = q->b[head % FN_BATCHES].rec;
  b->fill_n = 0;
}

/* Every line published so far analysed: the analyser is the caller's to read. */
static void pipe_drain(struct mem_functional *b) {
  pipe_publish(b);
  wait_emptied(b->pipe, atomic_load_explicit(&b->pipe->head, memory_order_relaxed), 1);
}

/* Analyse the local batch (no pipe). */
static void local_flush(struct mem_functional *b) {
  lru_stack_access_batch(b->ls, b->fill, b->fill_n);
  b->fill_n = 0;
}

static void analyse(struct mem_functional *b, uint64_t line, enum lru_stack_op op, unsigned cls) {
  if (b->fill_cap == 0) {
    lru_stack_access(b->ls, line, op, cls);
    return;
  }
  b->fill[b->fill_n] = FN_REC(line, op, cls);
  if (++b->fill_n == b->fill_cap) {
    if (b->pipe) pipe_publish(b);
    else local_flush(b);
  }
}

/* The last line again, same class, and no clean line to dirty: a hit in every
 * size that changes nothing but counters (a quarter of the accesses on grove).
 * Counted here (true: skip the analyser's call; mem_functional_stack hands the
 * counts over); otherwise the line becomes the last one. A whole-line store to
 * it is such a store too: no fetch either way. */
static inline bool fn_repeat(struct mem_functional *b, uint64_t line, unsigned cls, bool store) {
  if (line == b->last_line && cls == b->last_cls && (!store || b->last_dirty)) {
    b->repeats[cls][store]++;
    return true;
  }
  b->last_dirty = store || (line == b->last_line && b->last_dirty);
  b->last_line = line;
  b->last_cls = cls;
  return false;
}

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
  if (!fn_repeat(b, line, cls, op != LRU_STACK_READ)) analyse(b, line, op, cls);
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

/* fn_load's general case: a load over several lines, or one with a din trace. */
static __attribute__((noinline)) void fn_load_lines(struct mem_functional *b, uint64_t addr,
                                                    uint32_t size_bytes, unsigned cls) {
  fn_access(b, addr, size_bytes, false, cls);
}

/* fn_line for a load of one line that the batch has room for. */
static inline void fast_load_line(struct mem_functional *b, uint64_t line, unsigned cls) {
  if (!fn_repeat(b, line, cls, false)) b->fill[b->fill_n++] = FN_REC(line, LRU_STACK_READ, cls);
}

/* Most loads (a node, a triangle, a ray) fall within one or two lines: that
 * case is inlined here, fn_line's steps for a load done in place, so a load
 * costs a few instructions, not a call of the general path (which saves and
 * restores half the registers). A load that wraps past 2^64 has lines far
 * apart and takes the general path, which CHECKs it. */
static void fn_load(void *ctx, uint64_t addr, uint32_t size_bytes, unsigned cls) {
  struct mem_functional *b = ctx;
  CHECK_LT(cls, MEM_CLASS_MAX);
  b->st.loads[cls]++;
  b->st.bytes_loaded[cls] += size_bytes;
  const uint64_t line = addr >> b->lg2_line,
                 span = ((addr + (size_bytes - 1)) >> b->lg2_line) - line;
  if (!b->fast_loads || size_bytes == 0 || span > 1 || b->fill_n + 2 >= b->fill_cap) {
    fn_load_lines(b, addr, size_bytes, cls);
    return;
  }
  b->st.line_accesses[cls] += span + 1;
  fast_load_line(b, line, cls);
  if (span) fast_load_line(b, line + 1, cls);
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
                                             struct din_writer *din, bool analyser_thread) {
  struct mem_functional *b = xcalloc(1, sizeof *b);
  b->ls = lru_stack_create(p);
  b->din = din;
  b->lg2_line = p->lg2_line;
  b->last_cls = FN_NO_CLASS;
  if (analyser_thread && p->lg2_line >= 5) { /* (records need lines of 32 bytes or more) */
    struct fn_pipe *q = xcalloc(1, sizeof *q);
    q->ls = b->ls;
    CHECK(pthread_mutex_init(&q->mu, NULL) == 0);
    CHECK(pthread_cond_init(&q->filled, NULL) == 0);
    CHECK(pthread_cond_init(&q->emptied, NULL) == 0);
    if (pthread_create(&q->thread, NULL, analyser_main, q) != 0)
      err_check_failed(__FILE__, __LINE__, "pthread_create of the analyser thread");
    b->pipe = q;
    b->fill = q->b[0].rec;
    b->fill_cap = FN_BATCH_LINES;
  } else if (p->lg2_line >= 5) {
    b->fill = b->local;
    b->fill_cap = FN_LOCAL_LINES;
  }
  b->fast_loads = b->fill_cap > 0 && !din;
  return b;
}

void mem_functional_destroy(struct mem_functional *b) {
  if (!b) return;
  if (b->pipe) {
    struct fn_pipe *q = b->pipe;
    /* Lines not yet published are dropped: nobody reads them. */
    lock(&q->mu);
    atomic_store(&q->stop, true);
    CHECK(pthread_cond_signal(&q->filled) == 0);
    unlock(&q->mu);
    CHECK(pthread_join(q->thread, NULL) == 0);
    pthread_cond_destroy(&q->filled);
    pthread_cond_destroy(&q->emptied);
    pthread_mutex_destroy(&q->mu);
    free(q);
  }
  lru_stack_destroy(b->ls);
  free(b);
}

bool mem_functional_threaded(const struct mem_functional *b) { return b->pipe != NULL; }

struct mem_port mem_functional_port(struct mem_functional *b) {
  struct mem_port port = {&fn_ops, b};
  return port;
}

struct lru_stack *mem_functional_stack(struct mem_functional *b) {
  if (b->pipe) pipe_drain(b);
  else if (b->fill_n) local_flush(b);
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

unsigned mem_functional_host_cpus(void) {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) != 0) return 1;
  const int n = CPU_COUNT(&set);
  return n > 0 ? (unsigned)n : 1;
}
