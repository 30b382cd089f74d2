/* Parked workers of the queue scheduler (qsched.c): who waits for what, and
 * who is woken first. A worker with nothing to do parks in a list: the idle
 * list, or its core's list of those waiting for the end of the core's pass;
 * lists are first parked, first woken. A worker whose claim waits for a ray's
 * store waits on that slot instead. Host bookkeeping only: parking itself
 * (mem_park) is the worker's, waking goes through the waker's port
 * (mem_wake), so the order of wakes is the order of the lists. Private to
 * renderer/. */
#ifndef RTSIM_RENDERER_POLICY_QPARK_H
#define RTSIM_RENDERER_POLICY_QPARK_H

#include <stdint.h>

struct mem_port;

/* A list of parked workers (by worker id). */
struct qpark_list {
  uint32_t head, tail;
};

/* Worker id waits for the ray in slot to be stored. */
struct qpark_slot_wait {
  uint64_t slot;
  uint32_t id;
};

/* Caller-provided storage: qpark_init, qpark_fini. */
struct qpark {
  struct qpark_list idle, *pass; /* pass[core]: waiting for its pass */
  uint32_t *next;                /* next[id]: the next in id's list */
  struct qpark_slot_wait *slot_wait;
  uint32_t slot_waits, slot_wait_cap;
  uint32_t parked, busy; /* all, and those that are not idle */
};

void qpark_init(struct qpark *pk, uint32_t cores, uint32_t workers);
void qpark_fini(struct qpark *pk);

/* Count worker id parked, last in list l, or (l NULL) waiting for the slot
 * qpark_wait_slot gave it. */
void qpark_add(struct qpark *pk, struct qpark_list *l, uint32_t id);

/* Worker id's claim waits for the ray in slot to be stored (then qpark_add
 * with l NULL, as the worker parks). */
void qpark_wait_slot(struct qpark *pk, uint64_t slot, uint32_t id);

/* Wake up to n workers of list l, first parked first, through mem (the
 * waker's port, at its time). Returns how many. */
uint64_t qpark_wake(struct qpark *pk, struct qpark_list *l, uint64_t n, const struct mem_port *mem);

/* The ray in slot is stored: wake the worker waiting for it, if any. */
void qpark_wake_slot(struct qpark *pk, uint64_t slot, const struct mem_port *mem);

#endif
