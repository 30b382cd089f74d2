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

/* Schedule fn(ctx, arg) at cycle `at` (>= engine_now, CHECKed). */
void engine_at(struct engine *e, uint64_t at, engine_fn fn, void *ctx, uint64_t arg);

/* A tick: fn(ctx, now) is called once, before the first event at a cycle >=
 * at is handled (now: that event's cycle; every event before it handled), so
 * a watcher samples counters at boundaries of simulated time without an
 * event of its own (an event would count in engine_events and take a
 * sequence number). fn reads state and may set the next tick; it schedules no
 * event. One tick at a time: a new one replaces the old. */
typedef void (*engine_tick_fn)(void *ctx, uint64_t now);
void engine_tick(struct engine *e, uint64_t at, engine_tick_fn fn, void *ctx);

/* Handle events in order until none is left. Returns the events handled. */
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
