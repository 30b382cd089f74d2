/* rtsim run's stdout summary (run_output.h): what ran, on what, and the main
 * numbers with their units, for a person; stats.json and stats.csv hold every
 * number for programs. Each line is "name: value unit", the name as
 * stats.json has it, so a line can be found again in the files. */
#include "app/run_output.h"

#include <stdbool.h>
#include <stdio.h>
#include <string.h>

#include "app/sample.h"
#include "sim/machine.h"
#include "sim/machine_cfg.h"
#include "sim/stats.h"

/* The numbers shown, in order, and the unit each is shown in when the stats
 * tables' own unit would not say enough (NULL: the tables' unit). */
static const char *const SHOWN[][2] = {
    /* name, unit */
    {"cycles", "core cycles"},
    {"cycles_ci95_low", "core cycles"},
    {"cycles_ci95_high", "core cycles"},
    {"seconds", "simulated seconds"},
    {"sample_detailed_fraction", "of the work items run in detail"},
    {"rays_traced", "rays"},
    {"rays_per_second", "rays per simulated second"},
    {"core_utilization", "(fraction of issue slots used)"},
    {"thread_idle_fraction", "(fraction of thread-cycles)"},
    {"l2_miss_rate", "(fraction of L2 accesses)"},
    {"dram_bytes", NULL}, /* with its read and written parts (dram_line) */
    {"dram_bytes_per_cycle", "bytes per core cycle"},
    {"dram_read_latency_mean", "core cycles"},
    {"load_latency_mean", "core cycles"},
    {"energy_mj_per_frame", NULL}, /* with power_w and rays_per_joule (energy_line) */
    {"events", "engine events"},
    {"rung_cycles_error_min", "(fraction; measured against fidelity banked)"},
    {"rung_cycles_error_max", "(fraction; measured against fidelity banked)"},
    {"rung_error_warning", "(1: not to be trusted here; the warning on stderr says why)"},
};

/* bytes as "4 MiB", "48 KiB" or "1000 bytes": the largest unit it is a whole
 * number of. */
static void size_text(uint64_t bytes, char *buf, size_t cap) {
  static const char *const unit[] = {"bytes", "KiB", "MiB", "GiB"};
  unsigned u = 0;
  while (u < 3 && bytes >= 1024 && bytes % 1024 == 0) bytes /= 1024, u++;
  snprintf(buf, cap, "%llu %s", (unsigned long long)bytes, unit[u]);
}

/* The machine in one line: its shape, L2, rung, clock, and sampling. */
static void machine_line(const struct run_output_report *r, FILE *f) {
  const struct machine_params *p = &r->cfg->p;
  char l2[32];
  size_text(p->l2_size_bytes, l2, sizeof l2);
  fprintf(f,
          "machine: %u x %u x %u (cores x threads_per_core x rays_per_thread), L2 %s, "
          "fidelity %s, %g GHz\n",
          p->cores, p->threads_per_core, p->rays_per_thread, l2,
          machine_cfg_fidelity_name(p->fidelity), p->clock_ghz);
  if (r->sample) fprintf(f, "sampled: sample.fraction %g\n", r->cfg->sample.fraction);
}

static const struct stats_entry *entry(const struct stats_table *t, const char *name) {
  for (unsigned j = 0; j < t->n; j++)
    if (!strcmp(t->e[j].name, name)) return &t->e[j];
  return NULL;
}

/* dram_bytes, or its parts' sum where a rung writes only the parts, with the
 * parts when known. */
static void dram_line(const struct stats_table *t, FILE *f) {
  const struct stats_entry *all = entry(t, "dram_bytes"), *rd = entry(t, "dram_read_bytes"),
                           *wr = entry(t, "dram_write_bytes");
  const bool parts = rd && wr && rd->kind == STATS_U64 && wr->kind == STATS_U64;
  if (all && all->kind == STATS_F64) fprintf(f, "dram_bytes: %.6g bytes", all->f);
  else if (all) fprintf(f, "dram_bytes: %llu bytes", (unsigned long long)all->u);
  else if (parts) fprintf(f, "dram_bytes: %llu bytes", (unsigned long long)(rd->u + wr->u));
  else return;
  if (parts)
    fprintf(f, " (read %llu, written %llu)", (unsigned long long)rd->u, (unsigned long long)wr->u);
  fputc('\n', f);
}

/* energy_mj_per_frame with the run's average watts and rays a joule. */
static void energy_line(const struct stats_table *t, FILE *f) {
  const struct stats_entry *mj = entry(t, "energy_mj_per_frame"), *w = entry(t, "power_w"),
                           *rj = entry(t, "rays_per_joule");
  if (!mj || !w || !rj) return;
  fprintf(f, "energy_mj_per_frame: %.6g mJ a frame (power_w %.6g W, rays_per_joule %.6g)\n", mj->f,
          w->f, rj->f);
}

void run_output_summary(const struct run_output_report *r, FILE *f) {
  struct stats_table t = {0};
  run_output_measured(r, &t);
  fprintf(f, "policy: %s\n", r->policy);
  machine_line(r, f);
  fprintf(f, "scene: %s, %u x %u pixels\n", r->scene_name, r->width, r->height);
  for (unsigned i = 0; i < sizeof SHOWN / sizeof SHOWN[0]; i++) {
    if (!strcmp(SHOWN[i][0], "dram_bytes")) {
      dram_line(&t, f);
      continue;
    }
    if (!strcmp(SHOWN[i][0], "energy_mj_per_frame")) {
      energy_line(&t, f);
      continue;
    }
    const struct stats_entry *e = entry(&t, SHOWN[i][0]);
    if (!e) continue;
    const char *unit = SHOWN[i][1] ? SHOWN[i][1] : run_output_unit_of(e->name);
    if (e->kind == STATS_F64) fprintf(f, "%s: %.6g", e->name, e->f);
    else fprintf(f, "%s: %llu", e->name, (unsigned long long)e->u);
    fprintf(f, "%s%s\n", unit && *unit ? " " : "", unit ? unit : "");
  }
  fprintf(f, "wall_s: %.3f host seconds\noutput: %s\n", r->wall_s, r->out_dir);
  stats_fini(&t);
}
