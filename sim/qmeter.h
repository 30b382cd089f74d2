/* A queue's meter for Little's law: how many entered and left, the sum of
 * their waits, and the time integral of the occupancy, kept apart (the
 * integral from the length and the time since it last changed, the waits per
 * request), so that mean length x time = mean wait x requests is a check, not
 * an identity. Integers in cycles; tiny and hot, so inline. */
#ifndef RTSIM_SIM_QMETER_H
#define RTSIM_SIM_QMETER_H

#include <stdint.h>

struct qmeter {
  uint64_t entered, left;
  uint64_t wait_sum; /* cycles, over requests that left */
  uint64_t area;     /* requests x cycles, up to `since` */
  uint64_t len, max; /* requests inside now, and the most at once */
  uint64_t since;    /* cycle of the last change */
};

static inline void qmeter_advance(struct qmeter *q, uint64_t t) {
  if (t > q->since) {
    q->area += q->len * (t - q->since);
    q->since = t;
  }
}

/* A request enters at cycle t (non-decreasing across calls). */
static inline void qmeter_enter(struct qmeter *q, uint64_t t) {
  qmeter_advance(q, t);
  q->entered++;
  if (++q->len > q->max) q->max = q->len;
}

/* A request that entered at `at` leaves at cycle t. */
static inline void qmeter_leave(struct qmeter *q, uint64_t t, uint64_t at) {
  qmeter_advance(q, t);
  q->left++;
  q->len--;
  q->wait_sum += t - at;
}

#endif
