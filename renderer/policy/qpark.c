/* Parked workers of the queue scheduler (qpark.h): intrusive lists through
 * next[], and the slot waits as an unordered array (a few at a time: one
 * a worker at most). */
#include "renderer/policy/qpark.h"

#include <stdlib.h>

#include "sim/err.h"
#include "sim/mem.h"

#define QPARK_NONE UINT32_MAX

void qpark_init(struct qpark *pk, uint32_t cores, uint32_t workers) {
  *pk = (struct qpark){0};
  pk->idle.head = pk->idle.tail = QPARK_NONE;
  pk->pass = xmalloc((uint64_t)cores * sizeof *pk->pass);
  for (uint32_t c = 0; c < cores; c++) pk->pass[c] = pk->idle;
  pk->next = xmalloc((uint64_t)workers * sizeof *pk->next);
}

void qpark_fini(struct qpark *pk) {
  free(pk->pass);
  free(pk->next);
  free(pk->slot_wait);
  *pk = (struct qpark){0};
}

void qpark_add(struct qpark *pk, struct qpark_list *l, uint32_t id) {
  if (l) {
    pk->next[id] = QPARK_NONE;
    if (l->tail == QPARK_NONE) l->head = id;
    else pk->next[l->tail] = id;
    l->tail = id;
  }
  pk->parked++;
  pk->busy += l != &pk->idle;
}

void qpark_wait_slot(struct qpark *pk, uint64_t slot, uint32_t id) {
  if (pk->slot_waits == pk->slot_wait_cap) {
    pk->slot_wait_cap = pk->slot_wait_cap ? 2 * pk->slot_wait_cap : 16;
    pk->slot_wait = xrealloc(pk->slot_wait, (uint64_t)pk->slot_wait_cap * sizeof *pk->slot_wait);
  }
  pk->slot_wait[pk->slot_waits++] = (struct qpark_slot_wait){slot, id};
}

uint64_t qpark_wake(struct qpark *pk, struct qpark_list *l, uint64_t n,
                    const struct mem_port *mem) {
  uint64_t k = 0;
  for (; k < n && l->head != QPARK_NONE; k++) {
    const uint32_t id = l->head;
    l->head = pk->next[id];
    if (l->head == QPARK_NONE) l->tail = QPARK_NONE;
    pk->parked--;
    pk->busy -= l != &pk->idle;
    mem_wake(mem, id);
  }
  return k;
}

void qpark_wake_slot(struct qpark *pk, uint64_t slot, const struct mem_port *mem) {
  for (uint32_t i = 0; i < pk->slot_waits; i++) {
    if (pk->slot_wait[i].slot != slot) continue;
    const uint32_t id = pk->slot_wait[i].id;
    pk->slot_wait[i] = pk->slot_wait[--pk->slot_waits];
    pk->parked--;
    pk->busy--;
    mem_wake(mem, id);
    return;
  }
}
