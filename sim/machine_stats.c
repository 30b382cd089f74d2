/* The machine's numbers (docs/stats.md): the cores' and threads'
 * counters, and at its places the L1's, the L2's, the DRAM's and the
 * engine's, each from its own table registered there (env->ctx is the
 * machine); and the timeline's columns. */
#include "sim/machine_state.h"

#include "sim/cache.h"
#include "sim/derived.h"
#include "sim/dram.h"
#include "sim/engine.h"
#include "sim/l2.h"
#include "sim/stats.h"

#define M_ST(st) ((const struct machine_stats *)(st))
#define M_OF(env) ((const struct machine *)(env)->ctx)
static double m_seconds(const void *st, const struct stats_env *env) {
  return derived_seconds((double)M_ST(st)->cycles, M_OF(env)->p.clock_ghz);
}
static double m_core_utilization(const void *st, const struct stats_env *env) {
  return derived_core_utilization((double)M_ST(st)->issue_slots, (double)M_OF(env)->p.cores,
                                  (double)M_ST(st)->cycles);
}
static double m_thread_cycles(const void *st) {
  return (double)M_ST(st)->threads * (double)M_ST(st)->cycles;
}
static double m_busy_fraction(const void *st, const struct stats_env *env) {
  (void)env;
  return stats_ratio((double)M_ST(st)->thread_busy_cycles, m_thread_cycles(st));
}
static double m_idle_fraction(const void *st, const struct stats_env *env) {
  (void)env;
  const struct machine_stats *s = st;
  return stats_ratio(
      (double)(s->thread_wait_cycles + s->thread_parked_cycles + s->thread_done_cycles),
      m_thread_cycles(st));
}
static double m_wait_fraction(const void *st, const struct stats_env *env) {
  (void)env;
  return stats_ratio((double)M_ST(st)->thread_wait_cycles, m_thread_cycles(st));
}
static double m_parked_fraction(const void *st, const struct stats_env *env) {
  (void)env;
  return stats_ratio((double)M_ST(st)->thread_parked_cycles, m_thread_cycles(st));
}
static double m_done_fraction(const void *st, const struct stats_env *env) {
  (void)env;
  return stats_ratio((double)M_ST(st)->thread_done_cycles, m_thread_cycles(st));
}
static double m_slots_per_blocking_load(const void *st, const struct stats_env *env) {
  (void)env;
  return stats_ratio((double)M_ST(st)->issue_slots, (double)M_ST(st)->blocking_loads);
}

#define MS struct machine_stats
static const struct stats_desc machine_desc[] = {
    STATS_FIELD(MS, cycles, "cycles", "cycles", "the run: last ray done and the DRAM drained"),
    STATS_F64(MS, cycles, m_seconds, "seconds", "seconds", "the run at clock_ghz"),
    STATS_AT(MACHINE_STATS_AT_RUN),
    STATS_FIELD(MS, contexts, "ray_contexts", "count", "ray contexts: cores x threads x rays"),
    STATS_FIELD(MS, threads, "threads", "count", "hardware threads: cores x threads_per_core"),
    STATS_FIELD(MS, issue_slots, "issue_slots", "cycles",
                "issue slots used (compute, loads, stores)"),
    STATS_F64(MS, issue_slots, m_core_utilization, "core_utilization", "fraction",
              "issue slots used / cores x cycles"),
    STATS_F64(MS, thread_busy_cycles, m_busy_fraction, "thread_busy_fraction", "fraction",
              "thread-cycles with a ray ready, running or being switched to"),
    STATS_F64(MS, thread_done_cycles, m_idle_fraction, "thread_idle_fraction", "fraction",
              "thread-cycles with no ray ready: waiting, parked or done"),
    STATS_F64(MS, thread_wait_cycles, m_wait_fraction, "thread_wait_fraction", "fraction",
              "thread-cycles with live rays, all waiting on memory (or mem_wait)"),
    STATS_F64(MS, thread_parked_cycles, m_parked_fraction, "thread_parked_fraction", "fraction",
              "thread-cycles with live rays, all parked (no work)"),
    STATS_F64(MS, thread_done_cycles, m_done_fraction, "thread_done_fraction", "fraction",
              "thread-cycles with no work left"),
    STATS_FIELD(MS, ray_switches, "ray_switches", "count",
                "a thread taking another ray than its last"),
    STATS_FIELD(MS, switch_cycles, "ray_switch_cycles", "cycles", "thread cycles paid for them"),
    STATS_FIELD(MS, blocks, "ray_blocks", "count",
                "runs of a ray between waits: issuing until it waits, parks or ends"),
    STATS_FIELD(MS, waits, "waits", "count", "mem_wait calls: a worker idle by its own choice"),
    STATS_FIELD(MS, wait_cycles, "wait_cycles", "cycles", "cycles they asked for"),
    STATS_FIELD(MS, parks, "parks", "count", "mem_park calls: a context leaving with no work"),
    STATS_FIELD(MS, wakes, "wakes", "count", "mem_wake calls"),
    STATS_FIELD(MS, loads, "loads", "count", "loads issued"),
    STATS_FIELD(MS, stores, "stores", "count", "stores issued"),
    STATS_FIELD(MS, computes, "computes", "count",
                "compute steps issued (their cycles are in issue_slots)"),
    STATS_FIELD(MS, blocking_loads, "blocking_loads", "count",
                "loads that left the L1 and suspended their ray"),
    STATS_F64(MS, blocking_loads, m_slots_per_blocking_load, "issue_slots_per_blocking_load",
              "cycles", "issue slots / blocking loads"),
    STATS_AT(MACHINE_STATS_AT_RUN_MISSES),
    STATS_AT("l1"),
    STATS_AT("l2"),
    STATS_AT("dram"),
    STATS_HIST_MEAN(MS, load_latency, "load_latency_mean", "cycles",
                    "loads, issue to data (L1 hits too): mean"),
    STATS_HIST_Q(MS, load_latency, 0.95, "load_latency_p95", "cycles", "the same, 95th percentile"),
    STATS_FIELD(MS, load_latency.max, "load_latency_max", "cycles", "the same, most"),
    STATS_AT("engine"),
    STATS_FIELD(MS, stacks_max, "coroutine_stacks_max", "count",
                "coroutine stacks alive at once (parked contexts hold none)"),
};
static const struct stats_skip machine_skip[] = {
    STATS_SKIP_BY(MS, l1_accesses, machine_l1_stats_descs),
    STATS_SKIP_BY(MS, l1_hits, machine_l1_stats_descs),
    STATS_SKIP_BY(MS, l2, l2_stats_descs),
    STATS_SKIP_BY(MS, dram, dram_stats_descs),
    STATS_SKIP_BY(MS, events, machine_engine_stats_descs),
};
const struct stats_descs machine_stats_descs = {
    "machine",  machine_desc, STATS_COUNT(machine_desc),
    sizeof(MS), machine_skip, STATS_COUNT(machine_skip)};

/* The L1s' counters, kept by the machine in its own stats (NOTE: fields of
 * struct machine_stats, listed there as skips naming this table). */
static const struct stats_desc l1_desc[] = {
    STATS_FIELD(MS, l1_accesses, "l1_accesses", "count", "loads that looked in an L1"),
    STATS_FIELD(MS, l1_hits, "l1_hits", "count", "those that found their line"),
};
const struct stats_descs machine_l1_stats_descs = {"l1", l1_desc, STATS_COUNT(l1_desc), 0, NULL, 0};

static const struct stats_desc engine_desc[] = {
    STATS_FIELD(MS, events, "events", "count",
                "events the engine handled (a load's lines that miss the L1 together are one)"),
};
const struct stats_descs machine_engine_stats_descs = {
    "engine", engine_desc, STATS_COUNT(engine_desc), 0, NULL, 0};

/* The DRAM's share of its peak, for the levels that do not report their own
 * (the channel does: dram_channel_stats_descs). */
static bool m_dram_util_present(const void *st, const struct stats_env *env) {
  (void)st;
  const struct machine_params *p = &M_OF(env)->p;
  return machine_dram_peak_bytes_per_cycle(p) > 0 &&
         machine_fidelity_dram(p->fidelity) != DRAM_MODEL_CHANNEL;
}
static double m_dram_utilization(const void *st, const struct stats_env *env) {
  const struct machine_stats *s = st;
  const double b = (double)(s->dram.read_bytes + s->dram.write_bytes);
  return stats_ratio(b, (double)s->cycles) / machine_dram_peak_bytes_per_cycle(&M_OF(env)->p);
}
static const struct stats_desc dram_util_desc[] = {
    {.name = "dram_utilization",
     .unit = "fraction",
     .desc = "DRAM bytes per cycle / the level's peak (banked)",
     .how = STATS_HOW_F64,
     .f64 = m_dram_utilization,
     .present = m_dram_util_present},
};
const struct stats_descs machine_dram_util_stats_descs = {
    "dram", dram_util_desc, STATS_COUNT(dram_util_desc), 0, NULL, 0};
#undef MS

void machine_stats_emit(const struct machine *m, struct stats_table *t,
                        const char *const *class_names, unsigned classes,
                        const struct stats_part *parts, unsigned n) {
  struct stats_part all[16] = {
      {"l1", &machine_l1_stats_descs, &m->st, NULL},
      {"l2", &l2_stats_descs, &m->st.l2, NULL},
      {"dram", &dram_stats_descs, &m->st.dram, NULL},
      {DRAM_STATS_AT_UTILIZATION, &machine_dram_util_stats_descs, &m->st, NULL},
      {"engine", &machine_engine_stats_descs, &m->st, NULL},
  };
  unsigned k = 5;
  k += dram_level_stats(m->dram, &all[k]);
  CHECK_LE(k + n, STATS_COUNT(all));
  for (unsigned i = 0; i < n; i++) all[k++] = parts[i];
  const struct stats_env env = {.cycles = m->st.cycles,
                                .ctx = m,
                                .class_names = class_names,
                                .classes = classes,
                                .parts = all,
                                .nparts = k};
  stats_emit(t, &machine_stats_descs, &m->st, &env);
}

/* The timeline's columns (enum machine_tl_col), as timeline.csv writes them. */
const struct timeline_col machine_tl_cols[] = {
    {"dram_read_bytes", "bytes",
     "bytes the DRAM delivered in the window (at fidelity channel each transfer spread over its "
     "cycles on the channel; else whole lines at the cycle served)",
     MACHINE_TL_DRAM_READ_BYTES, 1, 2, false, false},
    {"dram_write_bytes", "bytes", "bytes the DRAM wrote in the window (the same way)",
     MACHINE_TL_DRAM_WRITE_BYTES, 1, 2, false, false},
    {"read_%s_bytes", "bytes", "of the bytes read, those of each data class",
     MACHINE_TL_READ_CLASS0, MEM_CLASS_MAX, 2, true, false},
    {"l2_accesses", "count", "accesses that reached the L2", MACHINE_TL_L2_ACCESSES, 1, 0, false,
     false},
    {"l2_misses", "count", "those that missed", MACHINE_TL_L2_MISSES, 1, 0, false, false},
    {"issued_ops", "cycles", "issue slots used, all cores", MACHINE_TL_ISSUED_OPS, 1, 0, false,
     false},
    {"busy_threads", "threads", "mean threads with a ray ready, running or being switched to",
     MACHINE_TL_BUSY_THREAD_CYCLES, 1, 4, false, true},
    {"dram_energy_j", "J",
     "the DRAM's energy in the window: banked's commands and rank states, or the cheaper rung's "
     "estimate (windows sum to dram_energy_j)",
     MACHINE_TL_DRAM_ENERGY, 1, -10, false, false},
    {"chip_dynamic_energy_j", "J", "the chip's dynamic energy in the window: L1s, L2, cores",
     MACHINE_TL_CHIP_DYNAMIC_ENERGY, 1, -10, false, false},
    {"chip_leakage_energy_j", "J", "the chip's leakage in the window: L1s, L2, cores",
     MACHINE_TL_CHIP_LEAKAGE_ENERGY, 1, -10, false, false},
    {"energy_j", "J", "the three above (windows sum to energy_j)", MACHINE_TL_ENERGY, 1, -10, false,
     false},
    {"power_w", "W", "energy_j over the window's seconds", MACHINE_TL_POWER, 1, -10, false, true},
};
const unsigned machine_tl_col_count = sizeof machine_tl_cols / sizeof machine_tl_cols[0];
