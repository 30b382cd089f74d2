/* The sweep's supervisor: a sweep's jobs run here as `rtsim run` processes,
 * N at a time (app/sweep_run.c says how points are claimed and stopped). */
#ifndef RTSIM_APP_SWEEP_RUN_H
#define RTSIM_APP_SWEEP_RUN_H

struct sweep;
struct sweep_job;

/* Run todo[0..n) with program bin, `jobs` at a time, in that order; returns
 * the number that failed, or -1 when interrupted by a signal (*sig set). A
 * point another process is running is left to it (its job marked busy,
 * counted in *busy); one found complete once claimed (run elsewhere
 * meanwhile) counts as done. A tty on stderr gets a progress line. */
int sweep_run_jobs(const char *bin, struct sweep_job **todo, unsigned n, unsigned jobs,
                   const struct sweep *s, int *sig, unsigned *busy);

#endif
