/* The event engine: simulated time in 64-bit cycles and a queue of events
 * ordered by (cycle, insertion sequence), so ties break by the order events
 * were scheduled and a run never depends on the host. An event is a function,
 * a context pointer and one 64-bit argument. Events less than ENGINE_WINDOW
 * cycles ahead go to a calendar of per-cycle FIFO buckets (O(1)); later ones
 * to a binary heap, moved into the calendar as time comes within reach (before
 * any event could be scheduled directly for the same cycle, which keeps the
 * insertion order). */
#ifndef RTSIM_SIM_ENGINE_H
#define RTSIM_SIM_ENGINE_H

#include <stdint.h>

typedef void (*engine_fn)(void *ctx, uint64_t arg);

#define ENGINE_WINDOW_BITS 12
#define ENGINE_WINDOW (1u << ENGINE_WINDOW_BITS)

struct engine;

struct engine *engine_create(void);    /* fatal on allocation failure; caller destroys */
void engine_destroy(struct engine *e); /* NULL ok */

/* The cycle of the event being handled (or of the last one handled). */
uint64_t engine_now(const struct engine *e);

/* Schedule fn(ctx, arg) at cycle `at` (>= engine_now, CHECKed). Returns its
 * sequence number: (at, sequence) is its key, and events run in key order. */
uint64_t engine_at(struct engine *e, uint64_t at, engine_fn fn, void *ctx, uint64_t arg);

/* The sequence number of the event being handled (of the last one handled;
 * 0 before the first): with engine_now, its key. */
uint64_t engine_seq(const struct engine *e);

/* Key (a, sa) comes before key (b, sb). */
static inline int engine_key_before(uint64_t a, uint64_t sa, uint64_t b, uint64_t sb) {
  return a < b || (a == b && sa < sb);
}

/* An event its maker keeps for now: take the sequence number engine_at would
 * give it here (its place among the events scheduled before and after), and
 * later either do what it stands for without the engine, where nothing can
 * tell the difference, or hand it over with engine_at_reserved. A reserved
 * number is never handled by the engine unless handed over. */
uint64_t engine_reserve(struct engine *e);
/* Schedule fn(ctx, arg) with key (at, seq), seq from engine_reserve: it runs
 * where engine_at, called when seq was taken, would have run it. The key must
 * still be to come: after the event being handled (CHECKed). */
void engine_at_reserved(struct engine *e, uint64_t at, uint64_t seq, engine_fn fn, void *ctx,
                        uint64_t arg);

/* A tick: fn(ctx, now) is called once, before the first event at a cycle >=
 * at is handled (now: that event's cycle; every event before it handled), so
 * a watcher samples counters at boundaries of simulated time without an
 * event of its own (an event would count in engine_events and take a
 * sequence number). fn reads state and may set the next tick; it schedules no
 * event. One tick at a time: a new one replaces the old. */
typedef void (*engine_tick_fn)(void *ctx, uint64_t now);
void engine_tick(struct engine *e, uint64_t at, engine_tick_fn fn, void *ctx);

/* Handle events in key order until none is left. Returns the events handled. */
uint64_t engine_run(struct engine *e);

/* Events handled so far, and events still queued. */
uint64_t engine_events(const struct engine *e);
uint64_t engine_pending(const struct engine *e);

/* Host micro-benchmark for `rtsim bench`: `events` events with `depth`
 * pending at any time (each handled event schedules one more 1 to max_delay
 * cycles later, pseudo-randomly). Returns events per second of wall time.
 * Never part of a result. */
double engine_bench(uint64_t events, uint32_t depth, uint64_t max_delay);

#endif
