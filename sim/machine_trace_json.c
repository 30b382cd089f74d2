/* The trace layer's record as Chrome trace-event JSON (the object form:
 * {"displayTimeUnit", "otherData", "traceEvents"}), one event a line. Time:
 * ts and dur are cycles, read as microseconds (integers, exact in every
 * viewer; a core cycle at clock_ghz is 1/clock_ghz ns of real time, written
 * in otherData). Processes: "memory" (pid 1, the counters), then core c (pid
 * c + 2) with its hardware threads (tid: after every pid, the global thread
 * index + cores + 2). NOTE: a viewer takes an event without a tid (a
 * counter, a process's name) as its pid's thread of that number, so no tid
 * may equal a pid. Everything is cut to the window. */
#include <inttypes.h>

#include "sim/machine_state.h"
#include "sim/machine_trace.h"

/* Events are separated, not ended, by commas (JSON has no trailing comma). */
static void sep(bool *first, FILE *f) {
  fputs(*first ? "" : ",\n", f);
  *first = false;
}

static unsigned tid_of(const struct mtrace *tr, uint32_t thread) {
  return thread + tr->p.cores + 2;
}

static void meta(FILE *f, bool *first, unsigned pid, unsigned tid, const char *what,
                 const char *key, const char *str, unsigned num) {
  sep(first, f);
  fprintf(f, "{\"ph\":\"M\",\"pid\":%u,", pid);
  if (tid) fprintf(f, "\"tid\":%u,", tid);
  fprintf(f, "\"name\":\"%s\",\"args\":{\"%s\":", what, key);
  if (str) fprintf(f, "\"%s\"}}", str);
  else fprintf(f, "%u}}", num);
}

static void write_names(const struct machine *m, const struct mtrace *tr, bool *first, FILE *f) {
  meta(f, first, 1, 0, "process_name", "name", "memory: L2 and DRAM", 0);
  meta(f, first, 1, 0, "process_sort_index", "sort_index", NULL, 0);
  char name[64];
  const uint32_t T = m->p.threads_per_core;
  for (uint32_t c = 0; c < tr->p.cores; c++) {
    snprintf(name, sizeof name, "core %u", c);
    meta(f, first, c + 2, 0, "process_name", "name", name, 0);
    meta(f, first, c + 2, 0, "process_sort_index", "sort_index", NULL, c + 1);
    for (uint32_t t = 0; t < T; t++) {
      snprintf(name, sizeof name, "thread %u", t);
      meta(f, first, c + 2, tid_of(tr, c * T + t), "thread_name", "name", name, 0);
      meta(f, first, c + 2, tid_of(tr, c * T + t), "thread_sort_index", "sort_index", NULL, t);
    }
  }
}

static void write_other(const struct machine *m, const struct mtrace *tr, FILE *f) {
  fprintf(f,
          "\"otherData\":{\"generator\":\"rtsim run --trace-events\","
          "\"time\":\"1 us of trace time = 1 core cycle (at clock_ghz %g: 1 cycle = %g ns)\","
          "\"clock_ghz\":\"%g\",\"window_cycles\":\"%" PRIu64 ":%" PRIu64 "\","
          "\"cores_traced\":\"%u of %u\",\"counter_period_cycles\":\"%" PRIu64 "\","
          "\"events\":\"%" PRIu64 "\",\"max_events\":\"%" PRIu64 "\",",
          m->p.clock_ghz, 1 / m->p.clock_ghz, m->p.clock_ghz, tr->p.from_cycle, tr->end,
          tr->p.cores, m->p.cores, tr->p.counter_period_cycles, tr->n, tr->p.max_events);
  if (tr->capped)
    fprintf(f, "\"capped\":\"max_events reached: the trace ends at cycle %" PRIu64 "\"},\n",
            tr->end);
  else fprintf(f, "\"capped\":\"no\"},\n");
}

static void write_event(const struct machine *m, const struct mtrace *tr, const struct mtrace_ev *e,
                        bool *first, FILE *f) {
  if (e->ts >= tr->end) return; /* after a cut (a thread that ran ahead) */
  sep(first, f);
  if (e->kind == MTRACE_COUNTER) {
    fprintf(f, "{\"ph\":\"C\",\"pid\":1,\"ts\":%" PRIu64 ",\"name\":\"%s\",\"args\":{\"%s\":%.9g}}",
            e->ts, mtrace_counter_names[e->track][0], mtrace_counter_names[e->track][1],
            e->u.value);
    return;
  }
  const uint64_t end = e->ts + e->u.dur < tr->end ? e->ts + e->u.dur : tr->end;
  fprintf(f,
          "{\"ph\":\"X\",\"pid\":%u,\"tid\":%u,\"ts\":%" PRIu64 ",\"dur\":%" PRIu64
          ",\"name\":\"%s\"}",
          e->track / m->p.threads_per_core + 2, tid_of(tr, e->track), e->ts, end - e->ts,
          machine_trace_kind_names[e->kind]);
}

void machine_trace_write(const struct machine *m, FILE *f) {
  const struct mtrace *tr = m->trace;
  CHECK(tr);
  fputs("{\"displayTimeUnit\":\"ms\",\n", f);
  write_other(m, tr, f);
  fputs("\"traceEvents\":[\n", f);
  bool first = true;
  write_names(m, tr, &first, f);
  for (uint64_t i = 0; i < tr->n; i++) write_event(m, tr, &tr->ev[i], &first, f);
  fputs("\n]}\n", f);
}
