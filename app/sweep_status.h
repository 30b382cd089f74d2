/* rtsim sweep --status: what state each point of a sweep is in. */
#ifndef RTSIM_APP_SWEEP_STATUS_H
#define RTSIM_APP_SWEEP_STATUS_H

struct sweep;
struct sweep_job;

/* Count and list the points all[0..s->npoints) of sweep directory dir on
 * stdout, failed ones first (with the first error line); nothing written.
 * Returns 0 when every point is complete, else 1. */
int sweep_status(const struct sweep *s, struct sweep_job *all, const char *dir);

#endif
