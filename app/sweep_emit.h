/* Job lines: a sweep's incomplete points as shell commands, each the sweep's
 * own runner (rtsim sweep ... -j 1 --point NAME...) on points it names, so a
 * line means the same whatever list it sits in and however often the jobs
 * are emitted again. --emit-jobs prints one a point for GNU parallel; the
 * Slurm script (app/sweep_slurm.h) runs one a task. */
#ifndef RTSIM_APP_SWEEP_EMIT_H
#define RTSIM_APP_SWEEP_EMIT_H

#include <stdint.h>
#include <stdio.h>

struct sweep_job;

/* What every job line repeats: this program, the sweep, DIR. */
struct sweep_line_base {
  const char *bin, *sweep; /* absolute */
  const char *dir;
  uint64_t max_points;
};

/* Append the job line of points js[0..n) to f (no line break). */
void sweep_job_line(FILE *f, const struct sweep_line_base *b, struct sweep_job *const *js,
                    unsigned n);
/* --emit-jobs: the line of each of todo[0..n) on stdout, one a line, then
 * the count on stderr (npoints in the sweep, complete of them). */
void sweep_emit_jobs(const struct sweep_line_base *b, struct sweep_job **todo, unsigned n,
                     unsigned npoints, unsigned complete);

#endif
