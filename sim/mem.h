/* The memory interface: the only door between the renderer and the simulator.
 * The renderer announces every access of scene data (address, size, data class)
 * and every block of computation; a backend behind the door decides what that
 * costs. Integers and function pointers only: no ray, triangle or cache type. */
#ifndef RTSIM_SIM_MEM_H
#define RTSIM_SIM_MEM_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* Data classes are small integers below MEM_CLASS_MAX: the simulator keeps
 * statistics per class without knowing what a class holds; the renderer names
 * them (renderer/trace.h). */
#define MEM_CLASS_MAX 8

/* Backend operations. addr is a simulated byte address, size_bytes > 0,
 * cls < MEM_CLASS_MAX. compute announces work in core cycles (it takes issue
 * slots). wait: the caller has nothing to do for `cycles` cycles (a worker
 * waiting for work other workers will make): it takes no issue slot, and on
 * the timed machine its thread may run other rays meanwhile; with a single
 * worker (native, functional) it is never needed.
 * park and wake, for a worker with nothing to do until another makes it some
 * (backends of many workers only): after park the caller returns from its
 * worker function without another access; it is then parked, and costs
 * nothing (no event, no issue slot, no stack) until another worker calls
 * wake(id) with its id (the id the backend gave it), which makes it run again
 * from the waker's current time: the backend calls its worker function again
 * from the start, so a worker that parks keeps what it needs in its own state.
 * Waking a worker that is not parked is a programmer error.
 * Any pointer may be NULL (ignored; mem_park tells). */
struct mem_ops {
  void (*load)(void *ctx, uint64_t addr, uint32_t size_bytes, unsigned cls);
  void (*store)(void *ctx, uint64_t addr, uint32_t size_bytes, unsigned cls);
  void (*compute)(void *ctx, uint64_t cycles);
  void (*wait)(void *ctx, uint64_t cycles);
  void (*park)(void *ctx);
  void (*wake)(void *ctx, uint32_t id);
};

/* A port: a backend's operations plus its context. ops == NULL is the native
 * backend, which does nothing: the renderer's own speed, the baseline. */
struct mem_port {
  const struct mem_ops *ops;
  void *ctx;
};

/* The native backend's port (does nothing). */
static inline struct mem_port mem_port_native(void) {
  struct mem_port p = {NULL, NULL};
  return p;
}

/* NOTE: the native case is one well-predicted branch per access; an empty
 * function behind a pointer would cost an indirect call on every access. */
static inline void mem_load(const struct mem_port *p, uint64_t addr, uint32_t size_bytes,
                            unsigned cls) {
  if (p->ops && p->ops->load) p->ops->load(p->ctx, addr, size_bytes, cls);
}

static inline void mem_store(const struct mem_port *p, uint64_t addr, uint32_t size_bytes,
                             unsigned cls) {
  if (p->ops && p->ops->store) p->ops->store(p->ctx, addr, size_bytes, cls);
}

static inline void mem_compute(const struct mem_port *p, uint64_t cycles) {
  if (p->ops && p->ops->compute) p->ops->compute(p->ctx, cycles);
}

static inline void mem_wait(const struct mem_port *p, uint64_t cycles) {
  if (p->ops && p->ops->wait) p->ops->wait(p->ctx, cycles);
}

/* Park the caller (see struct mem_ops): true when the backend parks it, and
 * the caller must now return from its worker function; false when the
 * backend cannot park (one worker: nothing to wait for). */
static inline bool mem_park(const struct mem_port *p) {
  if (!p->ops || !p->ops->park) return false;
  p->ops->park(p->ctx);
  return true;
}

static inline void mem_wake(const struct mem_port *p, uint32_t id) {
  if (p->ops && p->ops->wake) p->ops->wake(p->ctx, id);
}

#endif
