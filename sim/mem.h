/* The memory interface: the only door between the renderer and the simulator.
 * The renderer announces every access of scene data (address, size, data class)
 * and every block of computation; a backend behind the door decides what that
 * costs. Integers and function pointers only: no ray, triangle or cache type. */
#ifndef RTSIM_SIM_MEM_H
#define RTSIM_SIM_MEM_H

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
 * worker (native, functional) it is never needed. Any pointer may be NULL
 * (ignored). */
struct mem_ops {
  void (*load)(void *ctx, uint64_t addr, uint32_t size_bytes, unsigned cls);
  void (*store)(void *ctx, uint64_t addr, uint32_t size_bytes, unsigned cls);
  void (*compute)(void *ctx, uint64_t cycles);
  void (*wait)(void *ctx, uint64_t cycles);
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

#endif
