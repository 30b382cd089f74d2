/* Coroutines on Boost.Context's fcontext. The two entry points are declared
 * here with their C linkage (boost/context/detail/fcontext.hpp is C++). */
#define _DEFAULT_SOURCE /* MAP_ANONYMOUS */
#include "sim/coro.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <time.h>
#include <unistd.h>

#include "sim/err.h"

#if defined(__SANITIZE_ADDRESS__)
#include <sanitizer/asan_interface.h>
#include <sanitizer/common_interface_defs.h>
#define CORO_ASAN 1
/* NOTE: a finished coroutine leaves its frames' redzones poisoned in ASan's
 * shadow; a stack handed out again (or a new mapping at the same addresses)
 * must start clean. */
#define CORO_UNPOISON(p, n) ASAN_UNPOISON_MEMORY_REGION(p, n)
#else
#define CORO_ASAN 0
#define CORO_UNPOISON(p, n) ((void)(p), (void)(n))
#endif

typedef void *fcontext_t;
typedef struct {
  fcontext_t fctx;
  void *data;
} transfer_t;
extern transfer_t jump_fcontext(fcontext_t const to, void *vp);
extern fcontext_t make_fcontext(void *sp, size_t size, void (*fn)(transfer_t));

#define PAINT 0xA5u

struct stack {
  struct stack *next;  /* free list */
  unsigned char *base; /* mapping: guard page, then the stack */
  size_t usable;
  bool touched; /* handed out before: its top pages are the process's */
};

/* Stacks are mapped a chunk at a time, and a chunk is unmapped whole when
 * the pool goes: every munmap flushes the TLB of every host core, and one
 * a stack cost a 1024-core machine's teardown 14% of its run. */
struct chunk {
  struct chunk *next;
  unsigned char *base;
  size_t bytes;
  struct stack st[];
};

/* Chunks grow 1, 2, 4, ... stacks up to this many (68 KB each by default;
 * untouched pages cost no memory, only address space). */
#define CHUNK_MAX 64u

/* Stack tops are page-aligned, so the hot frames of thousands of stacks
 * share host cache sets: the machine fetches a stack's top ahead of the
 * switch (coro_resume_point), so the shared sets cost no wait, while
 * skewing each top below its page would cost a second page and its
 * first-touch fault on most stacks (measured on 8,192 stacks: 26,000 page
 * faults against 19,000, 15% of that run's host time). */

struct coro_pool {
  size_t stack_bytes, page;
  bool paint;
  struct stack *free;
  struct chunk *chunks;
  unsigned next_chunk; /* stacks in the next chunk */
};

struct coro {
  struct coro_pool *pool;
  struct stack *st;
  fcontext_t ctx;    /* where to jump to enter the coroutine */
  fcontext_t caller; /* where to jump to leave it */
  coro_fn fn;
  void *arg;
  bool started, finished;
#if CORO_ASAN
  void *fake;                /* ASan's fake stack of the side switched away from */
  const void *caller_bottom; /* the resumer's stack, as ASan reported it */
  size_t caller_size;
#endif
};

size_t coro_default_stack_bytes(void) {
  /* Measured by tests/test_run.c on painted stacks (recursive and packet
   * workers, every ray type): the deepest use is under 2 KB, since the
   * workers keep their ray buffers on the heap. 64 KB leaves a wide margin
   * for deeper trees and future kernels (the test requires 4x); the
   * sanitizers' instrumented frames are several times larger, hence 1 MB
   * there. Only touched pages cost memory, and the guard page turns an
   * overflow into a fault. */
  return CORO_ASAN ? (size_t)1 << 20 : (size_t)64 << 10;
}

struct coro_pool *coro_pool_create(size_t stack_bytes, bool paint) {
  struct coro_pool *p = xcalloc(1, sizeof *p);
  p->page = (size_t)sysconf(_SC_PAGESIZE);
  p->stack_bytes = (stack_bytes + p->page - 1) / p->page * p->page;
  p->paint = paint;
  p->next_chunk = 1;
  return p;
}

void coro_pool_destroy(struct coro_pool *p) {
  if (!p) return;
  while (p->chunks) {
    struct chunk *k = p->chunks;
    p->chunks = k->next;
    munmap(k->base, k->bytes);
    free(k);
  }
  free(p);
}

uint64_t coro_host_stack_limit(void) {
  FILE *f = fopen("/proc/sys/vm/max_map_count", "r");
  if (!f) return UINT64_MAX;
  unsigned long long n = 0;
  int ok = fscanf(f, "%llu", &n);
  fclose(f);
  if (ok != 1) return UINT64_MAX;
  return n > 4096 ? (n - 4096) / 2 : 0;
}

/* Map a chunk of p->next_chunk stacks, each a guard page then the stack,
 * onto the free list. */
static void chunk_add(struct coro_pool *p) {
  const unsigned n = p->next_chunk;
  const size_t each = p->stack_bytes + p->page;
  struct chunk *k = xcalloc(1, sizeof *k + n * sizeof k->st[0]);
  k->bytes = each * n;
  void *m = mmap(NULL, k->bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (m == MAP_FAILED) err_check_failed(__FILE__, __LINE__, "mmap of coroutine stacks");
  k->base = m;
  k->next = p->chunks;
  p->chunks = k;
  for (unsigned i = n; i-- > 0;) {
    struct stack *s = &k->st[i];
    s->base = k->base + i * each;
    s->usable = p->stack_bytes;
    /* The lowest page faults on touch: stacks grow down into it on overflow. */
    CHECK(mprotect(s->base, p->page, PROT_NONE) == 0);
    /* A mapping where an earlier pool's stack was inherits its shadow, which
     * holds the redzones of entry()'s frame (it never returns: it ends by a
     * switch); painting the new stack would trip over them. */
    CORO_UNPOISON(s->base + p->page, s->usable);
    if (p->paint) memset(s->base + p->page, PAINT, s->usable);
    s->next = p->free;
    p->free = s;
  }
  if (p->next_chunk < CHUNK_MAX) p->next_chunk *= 2;
}

/* The top page of a stack never handed out is populated in one call when
 * it is first handed out: a first-touch fault cost 12 us on this project's
 * virtual host against 5 us for the call, and a 1024-core machine starts
 * 8,192 stacks within a few thousand cycles (the dynamic policy's room run:
 * 0.91-1.06 s -> 0.87-0.95 s). One page: most coroutines stay in it (the
 * deepest worker measured uses 7 KB), and a second page each would cost
 * 4 KB of memory a stack (33 MB on that run) for no time measured. A hint
 * only: a kernel without it (before Linux 5.14) faults the page in. */
static struct stack *stack_get(struct coro_pool *p) {
  if (!p->free) chunk_add(p);
  struct stack *s = p->free;
  p->free = s->next;
  CORO_UNPOISON(s->base + p->page, s->usable);
  if (!s->touched) {
    s->touched = true;
#if defined(MADV_POPULATE_WRITE)
    (void)madvise(s->base + s->usable, p->page, MADV_POPULATE_WRITE); /* the top page */
#endif
  }
  return s;
}

struct coro *coro_create(struct coro_pool *p, coro_fn fn, void *arg) {
  struct coro *c = xcalloc(1, sizeof *c);
  c->pool = p;
  c->fn = fn;
  c->arg = arg;
  c->st = stack_get(p);
  return c;
}

void coro_destroy(struct coro *c) {
  if (!c) return;
  CHECK(!c->started || c->finished);
  c->st->next = c->pool->free;
  c->pool->free = c->st;
  free(c);
}

bool coro_finished(const struct coro *c) { return c->finished; }

const void *coro_resume_point(const struct coro *c) {
  return c->started && !c->finished ? c->ctx : NULL;
}

static inline void *stack_lo(const struct coro *c) { return c->st->base + c->pool->page; }

static void entry(transfer_t t) {
  struct coro *c = t.data;
  c->caller = t.fctx;
#if CORO_ASAN
  __sanitizer_finish_switch_fiber(NULL, &c->caller_bottom, &c->caller_size);
#endif
  c->fn(c->arg);
  c->finished = true;
#if CORO_ASAN
  /* NULL: this fiber's fake stack is never coming back. */
  __sanitizer_start_switch_fiber(NULL, c->caller_bottom, c->caller_size);
#endif
  jump_fcontext(c->caller, NULL);
  CHECK(!"a finished coroutine was resumed");
}

void coro_resume(struct coro *c) {
  CHECK(!c->finished);
  if (!c->started) {
    c->started = true;
    c->ctx = make_fcontext(stack_lo(c) + c->st->usable, c->st->usable, entry);
  }
#if CORO_ASAN
  void *fake = NULL;
  __sanitizer_start_switch_fiber(&fake, stack_lo(c), c->st->usable);
#endif
  transfer_t t = jump_fcontext(c->ctx, c);
#if CORO_ASAN
  __sanitizer_finish_switch_fiber(fake, NULL, NULL);
#endif
  c->ctx = t.fctx;
}

void coro_suspend(struct coro *c) {
#if CORO_ASAN
  __sanitizer_start_switch_fiber(&c->fake, c->caller_bottom, c->caller_size);
#endif
  transfer_t t = jump_fcontext(c->caller, NULL);
#if CORO_ASAN
  __sanitizer_finish_switch_fiber(c->fake, &c->caller_bottom, &c->caller_size);
#endif
  c->caller = t.fctx;
}

size_t coro_stack_used(const struct coro *c) {
  if (!c->pool->paint) return 0;
  const unsigned char *lo = stack_lo(c);
  size_t i = 0;
  while (i < c->st->usable && lo[i] == PAINT) i++;
  return c->st->usable - i;
}

struct bench_arg {
  struct coro *self;
  unsigned long n;
};

static void bench_body(void *arg) {
  struct bench_arg *b = arg;
  for (unsigned long i = 0; i < b->n; i++) coro_suspend(b->self);
}

double coro_bench_switch_ns(unsigned long switches) {
  struct coro_pool *p = coro_pool_create(coro_default_stack_bytes(), false);
  struct bench_arg b = {NULL, switches};
  b.self = coro_create(p, bench_body, &b);
  struct timespec t0, t1;
  clock_gettime(CLOCK_MONOTONIC, &t0);
  while (!coro_finished(b.self)) coro_resume(b.self);
  clock_gettime(CLOCK_MONOTONIC, &t1);
  coro_destroy(b.self);
  coro_pool_destroy(p);
  double s = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
  return s * 1e9 / (2.0 * (double)(switches + 1));
}
