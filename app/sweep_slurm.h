/* --emit-slurm: a sweep's incomplete points as a Slurm job array script on
 * stdout, a task per N points, each task one job line (app/sweep_emit.h);
 * submitted with sbatch. Nothing runs here. */
#ifndef RTSIM_APP_SWEEP_SLURM_H
#define RTSIM_APP_SWEEP_SLURM_H

struct sweep_job;
struct sweep_line_base;

/* The script of todo[0..n) (longest first; n > 0), per points a task, on stdout,
 * then the count on stderr. all[0..npoints): every point of the sweep, the
 * complete ones (complete of them) measured for the requests. */
void sweep_emit_slurm(const struct sweep_line_base *b, struct sweep_job **todo, unsigned n,
                      unsigned per, struct sweep_job *all, unsigned npoints, unsigned complete);

#endif
