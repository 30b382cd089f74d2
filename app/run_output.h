/* What rtsim run writes: image.exr, stats.csv, timeline.csv, traffic.png and,
 * last, stats.json (its presence marks the directory complete). Each file is
 * written under a temporary name and renamed when whole, into a directory
 * swapped in whole at the end (app/outdir.h). At fidelity analytic
 * there is no timeline.csv or traffic.png, and the stats hold only the
 * numbers the estimate knows, under the timed rungs' names. */
#ifndef RTSIM_APP_RUN_OUTPUT_H
#define RTSIM_APP_RUN_OUTPUT_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

struct err;
struct machine;
struct machine_cfg;
struct sampler;
struct render_stats;
struct trace_stats;
struct framebuffer;
struct app_analytic;
struct machine_costs;
struct image;
struct outfile;
struct rung_error;

struct run_output_report {
  const char *out_dir, *machine_path, *scene_path, *scene_name, *policy;
  uint32_t mask, width, height;
  uint64_t seed;
  uint64_t scene_hash;   /* scene_hash() of the loaded scene */
  const char *kd_splits; /* "whole" or "clipped": how the k-d tree was built */
  const char *accel;     /* the structure traced: "kd", "bvh2" or "bvh8" */
  const struct machine_cfg *cfg;
  const struct machine *machine;       /* a timed rung's; NULL at fidelity analytic */
  const struct app_analytic *analytic; /* fidelity analytic's counts and estimate, else NULL */
  const struct sampler *sample;        /* a sampled run's estimates (NULL: a full run) */
  const struct rung_error *rung; /* a whole run at a cheaper rung: its measured error (else NULL) */
  const struct spot_check *spot; /* --spot-check: a banked sample of this point (else NULL) */
  const struct render_stats *rstats;
  const struct trace_stats *tstats;
  const struct framebuffer *fb;
  const struct machine_costs *costs; /* per-pixel costs (NULL: not counted) */
  struct outfile *cost_preview;      /* a heat map PNG of cost_channel, drawn into it and not
                                        committed (NULL: none) */
  const char *cost_channel;
  double cost_max; /* the colour scale's top (0: the largest value) */
  double wall_s;
};

/* The cost channels image.exr carries when the run counted them (docs/outputs.md,
 * "Cost in the picture"), NULL-terminated; and whether name is one. */
extern const char *const run_output_cost_channels[];
bool run_output_is_cost_channel(const char *name);
/* The image rtsim run writes: the framebuffer's channels, then r->costs'
 * (im initialised here). */
void run_output_image(const struct run_output_report *r, struct image *im);

/* The names run_output_write writes or removes in out_dir, NULL-terminated
 * (app/outdir.h: what a signal removes, what a rerun does not carry over). */
extern const char *const run_output_files[];
/* Write every output into r->out_dir, and the heat map into r->cost_preview
 * (left for the caller to commit); on failure fills e (file = the one that
 * failed). */
bool run_output_write(const struct run_output_report *r, struct err *e);
/* What a person reads on stdout after a run (app/run_summary.c): the policy
 * and the machine, then the main numbers as "name: value unit" (the names
 * are stats.json's), DRAM bytes read and written, the host seconds and
 * OUTDIR. */
void run_output_summary(const struct run_output_report *r, FILE *f);
/* The run's measured numbers as stats.json and stats.csv hold them (t
 * zero-initialised; stats_fini it). */
struct stats_table;
void run_output_measured(const struct run_output_report *r, struct stats_table *t);

/* Every number a whole timed run writes, table by table (each component's in
 * its order), then what only stats.json holds, fidelity analytic's and a
 * sampled run's numbers, a cheaper rung's measured error (app/rung_error.h),
 * then timeline.csv's columns: name, unit, component, description, one a line
 * (`rtsim run --help-stats`), or as Markdown table rows (docs/stats.md). */
void run_output_stats_help(FILE *f, bool markdown);
/* The unit the tables state for NAME: a machine config key's (--help-keys),
 * else a number's or timeline column's (--help-stats; fetch_node_bytes
 * matches fetch_<class>_bytes), as written there ("cycles", "count", "" for a
 * key's count); NULL when no table holds NAME. */
const char *run_output_unit_of(const char *name);
/* The run's own tables: its numbers at the machine's slots (over a struct
 * run_output_report), what only stats.json holds, and fidelity analytic's
 * numbers (over a struct app_analytic; a sampled run's: app/sample.h). */
struct stats_descs;
extern const struct stats_descs run_output_stats_descs, run_output_misses_stats_descs,
    run_output_json_stats_descs, run_output_analytic_stats_descs;

#endif
