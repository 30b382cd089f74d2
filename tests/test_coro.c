/* Coroutines alone (sim/coro.h), not through the machine: resume/suspend
 * ordering against a hand-computed interleaving, the finished state, stack
 * reuse (LIFO) after destroy, the painted high-water mark growing with
 * recursion depth, thousands alive at once, and the pool's chunks of 1, 2, 4,
 * ... 64 stacks, each seen through the addresses of the coroutines' frames. */
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "sim/coro.h"
#include "testing.h"

/* Interleaving: each coroutine logs (id, step) and suspends after each step. */
struct step_arg {
  struct coro *self;
  unsigned id, steps;
  char *log; /* shared: one "id step" pair of characters per event */
  unsigned *n;
};

static void step_body(void *arg) {
  struct step_arg *a = arg;
  for (unsigned s = 0; s < a->steps; s++) {
    a->log[(*a->n)++] = (char)('A' + a->id);
    a->log[(*a->n)++] = (char)('0' + s);
    coro_suspend(a->self);
  }
  a->log[(*a->n)++] = (char)('a' + a->id); /* returning: lower case */
}

static void test_interleaving(void) {
  struct coro_pool *p = coro_pool_create(coro_default_stack_bytes(), false);
  char log[64] = {0};
  unsigned n = 0;
  struct step_arg a[3] = {{NULL, 0, 2, log, &n}, {NULL, 1, 1, log, &n}, {NULL, 2, 3, log, &n}};
  for (unsigned i = 0; i < 3; i++) a[i].self = coro_create(p, step_body, &a[i]);
  /* Creating runs nothing. */
  EXPECTF(n == 0, "%u events before any resume", n);
  for (unsigned i = 0; i < 3; i++) EXPECT(!coro_finished(a[i].self));
  /* Resume order C A C B A B C A C: B has 1 step, so its second resume returns; A's third. */
  const unsigned order[] = {2, 0, 2, 1, 0, 1, 2, 0, 2};
  for (unsigned k = 0; k < sizeof order / sizeof order[0]; k++) coro_resume(a[order[k]].self);
  log[n] = 0;
  /* Hand-computed: C0 A0 C1 B0 A1 b C2 a c (b, a, c: their functions returning). */
  EXPECTF(strcmp(log, "C0A0C1B0A1bC2ac") == 0, "log %s", log);
  for (unsigned i = 0; i < 3; i++) EXPECT(coro_finished(a[i].self));
  for (unsigned i = 0; i < 3; i++) coro_destroy(a[i].self);
  coro_destroy(NULL); /* NULL ok */
  coro_pool_destroy(p);
  coro_pool_destroy(NULL);
}

/* A coroutine that records where its frame is, suspends `suspends` times and returns. */
struct where_arg {
  struct coro *self;
  char *frame;
  unsigned suspends;
};

static void where_body(void *arg) {
  struct where_arg *a = arg;
  a->frame = __builtin_frame_address(0);
  for (unsigned i = 0; i < a->suspends; i++) coro_suspend(a->self);
}

/* Where a suspended coroutine resumes (what the machine fetches ahead): none
 * before its first run or once finished; while suspended, on its own stack,
 * below the frame of its body (the switch's saved registers) and no further
 * below it than a few frames. */
static void test_resume_point(void) {
  struct coro_pool *p = coro_pool_create(coro_default_stack_bytes(), false);
  struct where_arg a = {NULL, NULL, 2};
  a.self = coro_create(p, where_body, &a);
  EXPECT(coro_resume_point(a.self) == NULL);
  for (int i = 0; i < 2; i++) {
    coro_resume(a.self);
    const char *rp = coro_resume_point(a.self);
    EXPECTF(rp != NULL && rp < a.frame && a.frame - rp < 1024,
            "resume point %p against the body's frame %p", (const void *)rp, (void *)a.frame);
  }
  coro_resume(a.self);
  EXPECT(coro_finished(a.self));
  EXPECT(coro_resume_point(a.self) == NULL);
  coro_destroy(a.self);
  coro_pool_destroy(p);
}

/* A coroutine destroyed before it ever ran gives its stack back too, and the
 * next one created (finished or not started) gets the stack given back last. */
static void test_reuse(void) {
  struct coro_pool *p = coro_pool_create(coro_default_stack_bytes(), false);
  struct where_arg a = {NULL, NULL, 1}, b = {NULL, NULL, 0};
  a.self = coro_create(p, where_body, &a);
  coro_resume(a.self);
  EXPECT(!coro_finished(a.self)); /* suspended once */
  coro_resume(a.self);
  EXPECT(coro_finished(a.self));
  char *first = a.frame;
  coro_destroy(a.self);
  b.self = coro_create(p, where_body, &b);
  coro_resume(b.self);
  EXPECT(coro_finished(b.self));
  EXPECTF(b.frame == first, "a reused stack's frame at %p, was %p", (void *)b.frame, (void *)first);
  /* Never started: destroyable, and its stack is the next one handed out. */
  struct where_arg c = {NULL, NULL, 0};
  c.self = coro_create(p, where_body, &c);
  coro_destroy(c.self);
  coro_destroy(b.self);
  c.self = coro_create(p, where_body, &c);
  coro_resume(c.self);
  EXPECTF(c.frame == first, "LIFO: the stack given back last is handed out first");
  coro_destroy(c.self);
  coro_pool_destroy(p);
}

/* Recursion: each level keeps a 256-byte buffer alive across its call, so
 * the compiler can neither drop the buffer nor turn the recursion into a loop. */
__attribute__((noinline)) static unsigned recurse(unsigned depth) {
  volatile unsigned char buf[256];
  for (unsigned i = 0; i < sizeof buf; i++) buf[i] = (unsigned char)(depth + i);
  unsigned r = depth > 0 ? recurse(depth - 1) : 0;
  return r + buf[depth % sizeof buf];
}

struct depth_arg {
  unsigned depth, sink;
};

static void depth_body(void *arg) {
  struct depth_arg *a = arg;
  a->sink = recurse(a->depth);
}

static size_t used_at_depth(bool paint, unsigned depth) {
  struct coro_pool *p = coro_pool_create(coro_default_stack_bytes(), paint);
  struct depth_arg a = {depth, 0};
  struct coro *c = coro_create(p, depth_body, &a);
  size_t before = coro_stack_used(c);
  EXPECTF(before == 0, "a fresh painted stack reports %zu bytes used", before);
  coro_resume(c);
  EXPECT(coro_finished(c));
  size_t used = coro_stack_used(c);
  coro_destroy(c);
  coro_pool_destroy(p);
  return used;
}

static void test_stack_used(void) {
  const size_t cap = coro_default_stack_bytes();
  size_t prev = 0;
  /* 256 levels of at least 256 bytes: 64 KB and up, past the default 64 KB
   * stack, so stay at 128. */
  const unsigned depths[] = {1, 8, 32, 128};
  for (unsigned i = 0; i < sizeof depths / sizeof depths[0]; i++) {
    size_t used = used_at_depth(true, depths[i]);
    EXPECTF(used >= (size_t)depths[i] * 256, "depth %u used %zu bytes", depths[i], used);
    EXPECTF(used > prev, "depth %u used %zu bytes, no more than %zu", depths[i], used, prev);
    EXPECTF(used < cap, "depth %u used %zu of %zu", depths[i], used, cap);
    prev = used;
  }
  EXPECT(used_at_depth(false, 32) == 0); /* not painted: nothing measured */
}

static int cmp_ptr(const void *x, const void *y) {
  const char *p = *(char *const *)x, *q = *(char *const *)y;
  return p < q ? -1 : p > q;
}

/* Many alive at once, each suspended inside its function: frames on distinct
 * stacks, all finish, and destroyed in order 0..n-1 they come back n-1..0. */
static void test_many(void) {
  /* 5000 stacks of 64 KB are 320 MB of address space; the sanitizers' 1 MB
   * stacks would be 5 GB, so fewer there. Each stack is two mappings. */
  unsigned n = coro_default_stack_bytes() <= ((size_t)64 << 10) ? 5000 : 600;
  if (coro_host_stack_limit() < n) n = (unsigned)coro_host_stack_limit();
  struct where_arg *a = calloc(n, sizeof *a);
  struct coro_pool *p = coro_pool_create(coro_default_stack_bytes(), false);
  for (unsigned i = 0; i < n; i++) {
    a[i].suspends = 1;
    a[i].self = coro_create(p, where_body, &a[i]);
    coro_resume(a[i].self);
  }
  char **sorted = malloc(n * sizeof *sorted);
  for (unsigned i = 0; i < n; i++) sorted[i] = a[i].frame;
  /* Distinct stacks: sorted, frames at least a stack apart. */
  qsort(sorted, n, sizeof *sorted, cmp_ptr);
  unsigned close = 0;
  for (unsigned i = 1; i < n; i++)
    if ((size_t)(sorted[i] - sorted[i - 1]) < coro_default_stack_bytes()) close++;
  EXPECTF(close == 0, "%u of %u frames closer than a stack", close, n);
  unsigned unfinished = 0;
  for (unsigned i = 0; i < n; i++) {
    EXPECT(!coro_finished(a[i].self));
    coro_resume(a[i].self);
    unfinished += !coro_finished(a[i].self);
  }
  EXPECTF(unfinished == 0, "%u of %u did not finish", unfinished, n);
  char **old = malloc(n * sizeof *old);
  for (unsigned i = 0; i < n; i++) {
    old[i] = a[i].frame;
    coro_destroy(a[i].self);
  }
  unsigned not_lifo = 0;
  for (unsigned i = 0; i < n; i++) {
    a[i].suspends = 0;
    a[i].self = coro_create(p, where_body, &a[i]);
    coro_resume(a[i].self);
    not_lifo += a[i].frame != old[n - 1 - i];
    coro_destroy(a[i].self);
    a[i].self = coro_create(p, where_body, &a[i]); /* hold the stack: the next gets another */
  }
  EXPECTF(not_lifo == 0, "%u of %u stacks not handed out last-in first-out", not_lifo, n);
  for (unsigned i = 0; i < n; i++) coro_destroy(a[i].self);
  coro_pool_destroy(p);
  free(old);
  free(sorted);
  free(a);
}

/* The pool maps 1, 2, 4, ... 64, 64, ... stacks at a time, each a guard page
 * then the stack, and hands a chunk's stacks out in address order, each
 * starting at its page-aligned top. So consecutive coroutines of a fresh pool
 * have frames exactly one stack-plus-page apart within a chunk, and anything
 * else across chunks. */
static void test_chunks(void) {
  enum { N = 300 };
  const size_t page = (size_t)sysconf(_SC_PAGESIZE);
  const size_t stack_bytes = 16 << 10;
  const ptrdiff_t each = (ptrdiff_t)(stack_bytes + page);
  struct coro_pool *p = coro_pool_create(stack_bytes, false);
  static struct where_arg a[N];
  for (unsigned i = 0; i < N; i++) {
    a[i] = (struct where_arg){NULL, NULL, 0};
    a[i].self = coro_create(p, where_body, &a[i]);
    coro_resume(a[i].self);
  }
  /* Chunk boundaries, hand-computed: after 1, 1+2, 1+2+4, ... 127, then every 64. */
  bool want[N] = {false};
  for (unsigned at = 1, size = 1; at < N; size = size < 64 ? 2 * size : 64, at += size)
    want[at] = true;
  unsigned wrong = 0;
  for (unsigned i = 1; i < N; i++) {
    ptrdiff_t step = a[i].frame - a[i - 1].frame;
    bool same = step == each;
    if (same == want[i]) {
      if (wrong++ < 5)
        fprintf(stderr, "coroutine %u: frame %td bytes from the previous (stack + page %td)\n", i,
                step, each);
    }
  }
  EXPECTF(wrong == 0, "%u of %u steps do not match chunks of 1, 2, 4, ... 64", wrong, N - 1);
  for (unsigned i = 0; i < N; i++) coro_destroy(a[i].self);
  coro_pool_destroy(p);
}

int main(void) {
  test_interleaving();
  test_reuse();
  test_resume_point();
  test_stack_used();
  test_many();
  test_chunks();
  return testing_done("test_coro");
}
