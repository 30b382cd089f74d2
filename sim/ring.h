/* A growable FIFO ring of fixed-size elements, addressed by sequence number:
 * the elements pushed so far are numbered 0, 1, 2, ... and those from head
 * (the oldest kept) to tail - 1 (the newest) are in the ring. Holds: the
 * capacity is 0 or a power of two, and element s sits at index s mod cap, so
 * growing (doubling) keeps every element at its sequence number and a
 * caller may hold sequence numbers across pushes. Every call takes the
 * element size, a constant at each call site (the RING_ macros), so the
 * inline accessors compile to a mask and a multiply-free shift. */
#ifndef RTSIM_SIM_RING_H
#define RTSIM_SIM_RING_H

#include <stddef.h>
#include <stdint.h>

struct ring {
  void *v;
  uint64_t cap, head, tail;
};

/* Double r's capacity (the first growth: to 4 elements of `size` bytes),
 * keeping each element at its sequence number. */
void ring_grow(struct ring *r, size_t size);
void ring_free(struct ring *r);

static inline uint64_t ring_len(const struct ring *r) { return r->tail - r->head; }

/* Element seq (head <= seq < tail). */
static inline void *ring_at(const struct ring *r, size_t size, uint64_t seq) {
  return (char *)r->v + (seq & (r->cap - 1)) * size;
}

/* A new element at the tail (its sequence number: tail - 1 after the call). */
static inline void *ring_push(struct ring *r, size_t size) {
  if (r->tail - r->head == r->cap) ring_grow(r, size);
  return ring_at(r, size, r->tail++);
}

static inline void ring_pop(struct ring *r) { r->head++; }

#define RING_AT(r, type, seq) ((type *)ring_at((r), sizeof(type), (seq)))
#define RING_HEAD(r, type) RING_AT((r), type, (r)->head)
#define RING_BACK(r, type) RING_AT((r), type, (r)->tail - 1)
#define RING_PUSH(r, type) ((type *)ring_push((r), sizeof(type)))

#endif
