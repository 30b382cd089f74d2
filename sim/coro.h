/* Stackful coroutines: each runs a function on its own stack and can suspend
 * anywhere (inside any call depth) back to the code that resumed it. The switch
 * is Boost.Context's fcontext (per-architecture assembly, C linkage), a few
 * nanoseconds, no system call. Stacks are mmap'ed with a guard page below them,
 * so an overflow faults cleanly instead of corrupting a neighbour; switches are
 * annotated for AddressSanitizer's fiber API when it is on. One pool hands out
 * and takes back stacks, so only coroutines alive at once cost memory. */
#ifndef RTSIM_SIM_CORO_H
#define RTSIM_SIM_CORO_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

typedef void (*coro_fn)(void *arg);

struct coro_pool;
struct coro;

/* A pool of stacks of stack_bytes each (rounded up to pages; plus a guard
 * page). paint: fill each new stack with a pattern so coro_stack_used can
 * measure the deepest use (touches every page: for measurement, not runs).
 * Caller destroys, after every coroutine of the pool is destroyed. */
struct coro_pool *coro_pool_create(size_t stack_bytes, bool paint);
void coro_pool_destroy(struct coro_pool *p); /* NULL ok */

/* The default stack size: the deepest measured use of the renderer's workers
 * with a wide margin (see coro.c); larger under the sanitizers. */
size_t coro_default_stack_bytes(void);

/* How many coroutine stacks this host lets a process map at once: each takes
 * two memory mappings (its guard page and the stack), and the kernel allows
 * vm.max_map_count of them (/proc/sys/vm/max_map_count), some of which the
 * program, its libraries and its heap hold (a reserve of 4096 is kept; it
 * also covers the up to 63 stacks of a pool's last chunk not yet handed out).
 * UINT64_MAX when the limit cannot be read. */
uint64_t coro_host_stack_limit(void);

/* A coroutine that will run fn(arg) when first resumed. */
struct coro *coro_create(struct coro_pool *p, coro_fn fn, void *arg);
/* Give its stack back to the pool. The coroutine must have finished or never
 * started (a suspended one would be abandoned mid-call: CHECKed). NULL ok. */
void coro_destroy(struct coro *c);

/* Run c until it suspends (coro_suspend) or its function returns. Call from
 * outside any coroutine of the pool. */
void coro_resume(struct coro *c);
/* From inside c: go back to whoever resumed it. */
void coro_suspend(struct coro *c);
bool coro_finished(const struct coro *c);
/* Where a suspended c's stack is hot: its saved registers, with the frames it
 * returns through just above (higher addresses). NULL before its first
 * resume and once finished. For a caller that knows c will run soon and
 * fetches these lines into the host cache ahead of coro_resume. */
const void *coro_resume_point(const struct coro *c);

/* Deepest stack use in bytes seen on a painted stack (0 if not painted). */
size_t coro_stack_used(const struct coro *c);

/* Host micro-benchmark for `rtsim bench`: nanoseconds per switch (one resume
 * or one suspend), from `switches` round trips. Never part of a result. */
double coro_bench_switch_ns(unsigned long switches);

#endif
