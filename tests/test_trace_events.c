/* rtsim run --trace-events (README "Trace events"): the JSON parses (a
 * strict reader below, no library); two hand-timed machines give exactly the
 * slices worked out in their comments; a whole run's slices tile [0, cycles)
 * on every thread and sum, state by state, to stats.json's thread figures; a
 * window and a core subset bound the file, and so does the event cap; an
 * output that cannot be written is one message, exit 2, and no file. */
#include <inttypes.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "sim/machine.h"
#include "sim/machine_cfg.h"
#include "sim/mem.h"
#include "testing.h"

/* ---- a strict JSON reader, keeping what trace events hold ---- */

struct tev {
  char ph, name[64];
  int64_t pid, tid, ts, dur;
  double value; /* a counter's (its args' one number) */
};

struct trace {
  struct tev *v;
  size_t n, cap;
  bool ok;          /* the whole text is one JSON value, nothing after */
  char capped[128]; /* otherData.capped */
};

struct rd {
  const char *s;
  bool ok;
};

static void sp(struct rd *r) {
  while (*r->s == ' ' || *r->s == '\n' || *r->s == '\t' || *r->s == '\r') r->s++;
}

static bool eat(struct rd *r, char c) {
  sp(r);
  if (*r->s != c) return false;
  r->s++;
  return true;
}

/* A string into out (cut to cap; escapes kept as read), r past it. */
static void str(struct rd *r, char *out, size_t cap) {
  size_t n = 0;
  if (!eat(r, '"')) {
    r->ok = false;
    return;
  }
  for (; *r->s != '"'; r->s++) {
    if ((unsigned char)*r->s < 0x20) {
      r->ok = false;
      return;
    }
    if (*r->s == '\\') {
      r->s++;
      if (!strchr("\"\\/bfnrtu", *r->s)) {
        r->ok = false;
        return;
      }
    }
    if (n + 1 < cap) out[n++] = *r->s;
  }
  r->s++;
  if (cap) out[n] = 0;
}

static double num(struct rd *r) {
  sp(r);
  const char *s = r->s;
  if (*s == '-') s++;
  if (!(*s >= '0' && *s <= '9')) r->ok = false;
  char *end;
  double v = strtod(r->s, &end);
  if (end == r->s) r->ok = false;
  r->s = end;
  return v;
}

static void value(struct rd *r, int depth);

/* An object or array's members, after its opening bracket. */
static void members(struct rd *r, char close, int depth) {
  if (eat(r, close)) return;
  do {
    if (close == '}') {
      str(r, NULL, 0);
      if (!eat(r, ':')) r->ok = false;
    }
    value(r, depth + 1);
  } while (r->ok && eat(r, ','));
  if (!eat(r, close)) r->ok = false;
}

static void value(struct rd *r, int depth) {
  sp(r);
  if (depth > 64) r->ok = false;
  if (!r->ok) return;
  if (eat(r, '{')) members(r, '}', depth);
  else if (eat(r, '[')) members(r, ']', depth);
  else if (*r->s == '"') str(r, NULL, 0);
  else if (!strncmp(r->s, "true", 4) || !strncmp(r->s, "null", 4)) r->s += 4;
  else if (!strncmp(r->s, "false", 5)) r->s += 5;
  else num(r);
}

/* One event object: the members a trace event's checks read. */
static void event(struct rd *r, struct tev *e) {
  memset(e, 0, sizeof *e);
  e->pid = e->tid = e->ts = e->dur = -1;
  if (!eat(r, '{')) {
    r->ok = false;
    return;
  }
  do {
    char key[32], ph[4];
    str(r, key, sizeof key);
    if (!eat(r, ':')) r->ok = false;
    if (!strcmp(key, "ph")) {
      str(r, ph, sizeof ph);
      e->ph = ph[0];
    } else if (!strcmp(key, "name")) {
      str(r, e->name, sizeof e->name);
    } else if (!strcmp(key, "pid") || !strcmp(key, "tid") || !strcmp(key, "ts") ||
               !strcmp(key, "dur")) {
      const int64_t v = (int64_t)num(r);
      *(key[0] == 'p' ? &e->pid : key[0] == 'd' ? &e->dur : key[1] == 'i' ? &e->tid : &e->ts) = v;
    } else if (!strcmp(key, "args") && e->ph == 'C') {
      char name[64];
      if (!eat(r, '{')) r->ok = false;
      str(r, name, sizeof name);
      if (!eat(r, ':')) r->ok = false;
      e->value = num(r);
      if (!eat(r, '}')) r->ok = false;
    } else {
      value(r, 2);
    }
  } while (r->ok && eat(r, ','));
  if (!eat(r, '}')) r->ok = false;
}

static void trace_parse(struct trace *t, const char *text) {
  memset(t, 0, sizeof *t);
  struct rd r = {text, true};
  if (!eat(&r, '{')) return;
  do {
    char key[32];
    str(&r, key, sizeof key);
    if (!eat(&r, ':')) r.ok = false;
    if (!strcmp(key, "traceEvents") && eat(&r, '[') && !eat(&r, ']')) {
      do {
        if (t->n == t->cap) t->v = realloc(t->v, (t->cap = 2 * t->cap + 64) * sizeof *t->v);
        event(&r, &t->v[t->n++]);
      } while (r.ok && eat(&r, ','));
      if (!eat(&r, ']')) r.ok = false;
    } else if (!strcmp(key, "otherData") && eat(&r, '{')) {
      do {
        char k[32], v[128];
        str(&r, k, sizeof k);
        if (!eat(&r, ':')) r.ok = false;
        str(&r, v, sizeof v);
        if (!strcmp(k, "capped")) snprintf(t->capped, sizeof t->capped, "%s", v);
      } while (r.ok && eat(&r, ','));
      if (!eat(&r, '}')) r.ok = false;
    } else {
      value(&r, 1);
    }
  } while (r.ok && eat(&r, ','));
  r.ok = r.ok && eat(&r, '}');
  sp(&r);
  t->ok = r.ok && *r.s == 0;
}

/* Parse dir/name into t: true when it is JSON. */
static bool trace_load(struct trace *t, const char *dir, const char *name) {
  size_t len;
  char *text = testing_slurp(dir, name, &len);
  memset(t, 0, sizeof *t);
  if (!text) return false;
  trace_parse(t, text);
  free(text);
  return t->ok;
}

/* ---- checks ---- */

static int by_thread(const void *a, const void *b) {
  const struct tev *x = a, *y = b;
  if (x->tid != y->tid) return x->tid < y->tid ? -1 : 1;
  return x->ts < y->ts ? -1 : x->ts > y->ts;
}

/* Slices of the threads of the first `cores` cores (core c: pid c + 2;
 * thread i of them all: tid i + cores + 2, no tid a pid): each tiles [from,
 * to) with slices of positive length, in time order; sums[k] gets each
 * state's cycles (k: 0 busy, 1 waiting, 2 parked, 3 done). True when all
 * hold. */
static bool tiles(struct trace *t, unsigned cores, unsigned threads, int64_t from, int64_t to,
                  double sums[4]) {
  qsort(t->v, t->n, sizeof *t->v, by_thread);
  int64_t at[1024];
  bool ok = threads <= 1024 && cores && threads % cores == 0;
  for (unsigned i = 0; i < threads && ok; i++) at[i] = from;
  for (size_t i = 0; i < t->n && ok; i++) {
    const struct tev *e = &t->v[i];
    if (e->ph != 'X') continue;
    const int64_t k = e->tid - cores - 2;
    ok = k >= 0 && k < (int64_t)threads && e->pid == k / (threads / cores) + 2 && e->ts == at[k] &&
         e->dur > 0;
    if (!ok) {
      fprintf(stderr, "slice pid %" PRId64 " tid %" PRId64 " ts %" PRId64 " dur %" PRId64 " %s\n",
              e->pid, e->tid, e->ts, e->dur, e->name);
      break;
    }
    at[k] += e->dur;
    const int s = !strncmp(e->name, "wait", 4) ? 1
                  : !strcmp(e->name, "parked") ? 2
                  : !strcmp(e->name, "done")   ? 3
                                               : 0;
    sums[s] += (double)e->dur;
  }
  for (unsigned i = 0; i < threads && ok; i++) ok = at[i] == to;
  return ok;
}

/* Counters' samples lie in [from, to]; slices and counters counted. */
static void count(const struct trace *t, int64_t from, int64_t to, size_t *slices, size_t *counters,
                  bool *in_window) {
  *slices = *counters = 0;
  *in_window = true;
  for (size_t i = 0; i < t->n; i++) {
    const struct tev *e = &t->v[i];
    if (e->ph == 'X') ++*slices;
    if (e->ph == 'C') ++*counters;
    if ((e->ph == 'X' || e->ph == 'C') && (e->ts < from || e->ts > to)) *in_window = false;
  }
}

/* ---- hand-timed machines ---- */

static struct machine_params tiny(uint32_t threads, uint32_t rays, uint32_t mshrs) {
  struct machine_params p;
  memset(&p, 0, sizeof p);
  struct machine_cfg c;
  machine_cfg_defaults(&c);
  p = c.p;
  p.clock_ghz = 1.0;
  p.cores = 1;
  p.threads_per_core = threads;
  p.rays_per_thread = rays;
  p.l1_size_bytes = 0;
  p.l2_size_bytes = 1u << 20;
  p.l2_ways = 0;
  p.l2_latency_cycles = 20;
  p.l2_banks = 8;
  p.l2_mshrs = mshrs;
  p.l2_write_buffer = 16;
  p.fidelity = MACHINE_FIDELITY_FIXED;
  p.dram_latency_cycles = 100;
  p.cost_ray_switch_cycles = 2;
  p.timeline_window_cycles = 1000;
  return p;
}

/* Ray 0: compute 10, a load that misses, compute 5; the others: compute 4. */
static void w_switch(void *arg, const struct machine_worker_info *info, struct mem_port port) {
  (void)arg;
  if (info->ray == 0) {
    mem_compute(&port, 10);
    mem_load(&port, 1 << 12, 4, 0);
    mem_compute(&port, 5);
  } else {
    mem_compute(&port, 4);
  }
}

/* Each context loads a line of its own, nothing else. */
static void w_load(void *arg, const struct machine_worker_info *info, struct mem_port port) {
  (void)arg;
  mem_load(&port, (uint64_t)(info->id + 1) << 12, 4, 0);
}

/* Compute 3, wait 50 cycles by its own choice (mem_wait), compute 2. */
static void w_wait(void *arg, const struct machine_worker_info *info, struct mem_port port) {
  (void)arg;
  (void)info;
  mem_compute(&port, 3);
  mem_wait(&port, 50);
  mem_compute(&port, 2);
}

/* The traced run of fn on p, parsed into t. */
static void trace_of(struct trace *t, struct machine_params p, machine_worker_fn fn) {
  struct machine *m = machine_create(&p, 0);
  struct machine_trace_params tp = {0, UINT64_MAX, 1, 1000, 1000};
  machine_trace_enable(m, &tp);
  machine_run(m, fn, NULL, NULL, NULL);
  char *buf = NULL;
  size_t len = 0;
  FILE *f = open_memstream(&buf, &len);
  machine_trace_write(m, f);
  fclose(f);
  trace_parse(t, buf);
  free(buf);
  machine_destroy(m);
}

struct want {
  int64_t tid, ts, dur;
  const char *name;
};

/* t's slices, thread by thread in time order, are exactly w[0..n). */
static void expect_slices(struct trace *t, const struct want *w, size_t n, const char *what) {
  EXPECTF(t->ok, "%s: the JSON parses", what);
  qsort(t->v, t->n, sizeof *t->v, by_thread);
  size_t j = 0;
  for (size_t i = 0; i < t->n; i++) {
    const struct tev *e = &t->v[i];
    if (e->ph != 'X') continue;
    const bool same = j < n && e->tid == w[j].tid && e->ts == w[j].ts && e->dur == w[j].dur &&
                      !strcmp(e->name, w[j].name);
    EXPECTF(same, "%s: slice %zu: got tid %" PRId64 " [%" PRId64 ", +%" PRId64 ") %s", what, j,
            e->tid, e->ts, e->dur, e->name);
    j++;
  }
  EXPECTF(j == n, "%s: %zu slices, expected %zu", what, j, n);
}

static void hand_timed(void) {
  /* One thread, two rays, switch 2 cycles; a miss takes the L2's 20 cycles
   * to reach the DRAM, then its 100: ray 0 runs [0, 11) (its load is slot
   * 11), the thread switches to ray 1 [11, 13), which runs [13, 17) and
   * ends; the thread waits on ray 0's load from 17 to 11 + 20 + 100 = 131,
   * switches back [131, 133) and ray 0 runs its 5 cycles [133, 138). */
  struct trace t;
  trace_of(&t, tiny(1, 2, 64), w_switch);
  const struct want a[] = {{3, 0, 11, "run"},          {3, 11, 2, "switch"},  {3, 13, 4, "run"},
                           {3, 17, 114, "wait: load"}, {3, 131, 2, "switch"}, {3, 133, 5, "run"}};
  expect_slices(&t, a, sizeof a / sizeof a[0], "switch");
  free(t.v);
  /* Two threads, one MSHR: thread 0 issues at 0, its load leaves at 1 and
   * takes the MSHR (back at 1 + 20 + 100 = 121); thread 1, ready at 0, gets
   * the port at 1, its load at 2 queues at the L2 for want of an MSHR until
   * 121, then misses: back at 121 + 20 + 100 = 241. Thread 0 runs its empty
   * last block at 121 and is done until the run ends at 241. */
  trace_of(&t, tiny(2, 1, 1), w_load);
  const struct want b[] = {{3, 0, 1, "run"},           {3, 1, 120, "wait: load"},
                           {3, 121, 120, "done"},      {4, 0, 1, "ready"},
                           {4, 1, 1, "run"},           {4, 2, 119, "wait: L2 MSHRs full"},
                           {4, 121, 120, "wait: load"}};
  expect_slices(&t, b, sizeof b / sizeof b[0], "mshr");
  free(t.v);
  /* The kernel's own wait: [3, 53), resumed with no switch (its last ray). */
  trace_of(&t, tiny(1, 1, 64), w_wait);
  const struct want c[] = {{3, 0, 3, "run"}, {3, 3, 50, "wait: mem_wait"}, {3, 53, 2, "run"}};
  expect_slices(&t, c, sizeof c / sizeof c[0], "mem_wait");
  free(t.v);
}

/* ---- rtsim run ---- */

#define CFG RTSIM_SOURCE_DIR "/configs/default.yaml"
#define SCENE RTSIM_SOURCE_DIR "/scenes/small/grove.yaml"
#define TMP RTSIM_TMP "/trace_events"
#define CORES 16 /* configs/default.yaml's */

static off_t file_size(const char *path) {
  struct stat st;
  return stat(path, &st) == 0 ? st.st_size : -1;
}

/* Every core, the whole run of policy: tiles and sums against stats.json
 * (the dynamic policy's contexts park). */
static void whole_run(char *out, unsigned cap, const char *policy) {
  int rc = testing_runf(out, cap,
                        "%s run %s %s -o %s/whole --width 32 --height 32 --trace-events "
                        "%s/whole.json --trace-events-cores 1000 --policy %s 2>&1",
                        RTSIM_BINARY, CFG, SCENE, TMP, TMP, policy);
  EXPECTF(rc == 0, "whole run: %s", out);
  const double cycles = testing_json_num(TMP "/whole", "cycles");
  const double threads = testing_json_num(TMP "/whole", "threads");
  struct trace t;
  EXPECT(trace_load(&t, TMP, "whole.json"));
  EXPECT(!strcmp(t.capped, "no"));
  double sums[4] = {0};
  EXPECT(tiles(&t, CORES, (unsigned)threads, 0, (int64_t)cycles, sums));
  static const char *const frac[4] = {"thread_busy_fraction", "thread_wait_fraction",
                                      "thread_parked_fraction", "thread_done_fraction"};
  for (int k = 0; k < 4; k++) {
    const double want = testing_json_num(TMP "/whole", frac[k]) * threads * cycles;
    EXPECTF(fabs(sums[k] - want) < 0.5, "%s %s: slices sum to %.0f, stats.json %.3f", policy,
            frac[k], sums[k], want);
  }
  if (!strcmp(policy, "dynamic")) EXPECT(sums[2] > 0); /* parked slices too */
  size_t slices, counters;
  bool in;
  count(&t, 0, (int64_t)cycles, &slices, &counters, &in);
  EXPECT(in && counters > 0 && slices > 0);
  /* The power track, a step function to the run's end, integrates to
   * energy_j (each sample written to 9 significant digits). */
  double joules = 0;
  int64_t at = -1;
  double w = 0;
  for (size_t i = 0; i < t.n; i++) {
    const struct tev *e = &t.v[i];
    if (e->ph != 'C' || strcmp(e->name, "power: chip and DRAM")) continue;
    EXPECT(e->ts > at);
    if (at >= 0) joules += w * (double)(e->ts - at);
    at = e->ts;
    w = e->value;
  }
  if (at >= 0) joules += w * ((double)cycles - (double)at);
  joules *= testing_json_num(TMP "/whole", "seconds") / cycles; /* cycles to seconds */
  const double want = testing_json_num(TMP "/whole", "energy_j");
  EXPECTF(at >= 0 && fabs(joules - want) <= 1e-6 * want,
          "%s: the power track integrates to %.9g J, energy_j %.9g", policy, joules, want);
  free(t.v);
}

/* A window and one core: only its threads, only those cycles, a file far
 * smaller than the whole run's; then a cap of 1000 events. */
static void bounded(char *out, unsigned cap) {
  int rc = testing_runf(out, cap,
                        "%s run %s %s -o %s/win --width 32 --height 32 --trace-events %s/win.json "
                        "--trace-events-cores 1 --trace-events-window 20000:30000 2>&1",
                        RTSIM_BINARY, CFG, SCENE, TMP, TMP);
  EXPECTF(rc == 0, "window: %s", out);
  struct trace t;
  EXPECT(trace_load(&t, TMP, "win.json"));
  double sums[4] = {0};
  const unsigned T = (unsigned)testing_json_num(TMP "/win", "threads") / CORES;
  EXPECT(tiles(&t, 1, T, 20000, 30000, sums));
  size_t slices, counters;
  bool in;
  count(&t, 20000, 30000, &slices, &counters, &in);
  EXPECT(in && slices > 0 && counters > 0);
  const off_t whole = file_size(TMP "/whole.json"), win = file_size(TMP "/win.json");
  EXPECTF(win > 0 && win * 20 < whole, "window %lld bytes, whole run %lld", (long long)win,
          (long long)whole);
  free(t.v);

  rc = testing_runf(out, cap,
                    "%s run %s %s -o %s/cap --width 32 --height 32 --trace-events %s/cap.json "
                    "--trace-events-cores 1000 --trace-events-max 1000 2>&1",
                    RTSIM_BINARY, CFG, SCENE, TMP, TMP);
  EXPECTF(rc == 0 && strstr(out, "warning: --trace-events: ") && strstr(out, "ends at cycle"),
          "cap: %s", out);
  EXPECT(trace_load(&t, TMP, "cap.json"));
  count(&t, 0, INT64_MAX, &slices, &counters, &in);
  EXPECTF(slices + counters <= 1000, "cap: %zu events", slices + counters);
  const char *at = strstr(t.capped, "at cycle ");
  const int64_t cut = at ? strtoll(at + 9, NULL, 10) : -1;
  EXPECT(cut > 0 &&
         tiles(&t, CORES, (unsigned)testing_json_num(TMP "/cap", "threads"), 0, cut, sums));
  EXPECTF(file_size(TMP "/cap.json") < 1000 * 100, "cap: %lld bytes",
          (long long)file_size(TMP "/cap.json"));
  free(t.v);
}

/* A file that cannot be written, and a rung with no machine: exit 2, one
 * line, nothing written. */
static void refused(char *out, unsigned cap) {
  int rc = testing_runf(out, cap,
                        "%s run %s %s -o %s/nodir --width 8 --height 8 --trace-events "
                        "%s/no/such/dir/t.json 2>&1",
                        RTSIM_BINARY, CFG, SCENE, TMP, TMP);
  EXPECTF(rc == 2 && strstr(out, "no/such/dir/t.json") && strchr(out, '\n') == strrchr(out, '\n'),
          "unwritable: rc %d: %s", rc, out);
  EXPECT(access(TMP "/nodir", F_OK) != 0);
  rc = testing_runf(out, cap,
                    "%s run %s %s -o %s/an --width 8 --height 8 --set fidelity=analytic "
                    "--trace-events %s/an.json 2>&1",
                    RTSIM_BINARY, CFG, SCENE, TMP, TMP);
  EXPECTF(rc == 2 && strstr(out, "--trace-events"), "analytic: rc %d: %s", rc, out);
  EXPECT(access(TMP "/an.json", F_OK) != 0 && access(TMP "/an", F_OK) != 0);
  rc = testing_runf(out, cap,
                    "%s run %s %s -o %s/bw --trace-events %s/bw.json --trace-events-window 9:3 "
                    "2>&1",
                    RTSIM_BINARY, CFG, SCENE, TMP, TMP);
  EXPECTF(rc == 2 && strstr(out, "--trace-events-window"), "window 9:3: rc %d: %s", rc, out);
}

int main(void) {
  hand_timed();
  char cmd[512];
  snprintf(cmd, sizeof cmd, "rm -rf %s && mkdir -p %s", TMP, TMP);
  EXPECT(system(cmd) == 0);
  static char out[1 << 16];
  whole_run(out, sizeof out, "dynamic");
  whole_run(out, sizeof out, "recursive");
  bounded(out, sizeof out);
  refused(out, sizeof out);
  return testing_done("test_trace_events");
}
