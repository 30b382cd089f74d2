/* A queue's meter for Little's law: how many entered and left, the sum of
 * their waits, and the time integral of the occupancy, kept apart (the
 * integral from the length and the time since it last changed, the waits per
 * request), so that mean length x time = mean wait x requests is a check, not
 * an identity. The numbers (struct qmeter) sit in a component's stats; the
 * meter's clock (the length now and the cycle it last changed) is the
 * component's own state, not a number it reports. Integers in cycles; tiny
 * and hot, so inline. */
#ifndef RTSIM_SIM_QMETER_H
#define RTSIM_SIM_QMETER_H

#include <stdint.h>

struct qmeter {
  uint64_t entered, left;
  uint64_t wait_sum; /* cycles, over requests that left */
  uint64_t area;     /* requests x cycles, up to the clock's `since` */
  uint64_t max;      /* the most inside at once */
};

struct qmeter_clock {
  uint64_t len;   /* requests inside now */
  uint64_t since; /* cycle of the last change */
};

static inline void qmeter_advance(struct qmeter *q, struct qmeter_clock *c, uint64_t t) {
  if (t > c->since) {
    q->area += c->len * (t - c->since);
    c->since = t;
  }
}

/* A request enters at cycle t (non-decreasing across calls). */
static inline void qmeter_enter(struct qmeter *q, struct qmeter_clock *c, uint64_t t) {
  qmeter_advance(q, c, t);
  q->entered++;
  if (++c->len > q->max) q->max = c->len;
}

/* A request that entered at `at` leaves at cycle t. */
static inline void qmeter_leave(struct qmeter *q, struct qmeter_clock *c, uint64_t t, uint64_t at) {
  qmeter_advance(q, c, t);
  q->left++;
  c->len--;
  q->wait_sum += t - at;
}

#endif
