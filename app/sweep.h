/* Sweep files (configs/sweeps/NAME.yaml; the format is in docs/sweeps.md):
 * a base machine config, a workload, fixed --set overrides, and axes over
 * machine config keys or workload keys, expanded into points: the cartesian
 * product of the axes and zipped groups, first dimension slowest. Everything
 * is checked when the file is read, every point's machine config included,
 * so a bad value is refused (file:line:col) before any point runs. Each point
 * is one `rtsim run` with absolute paths, named by its swept values. */
#ifndef RTSIM_APP_SWEEP_H
#define RTSIM_APP_SWEEP_H

#include <stdbool.h>

struct err;

/* Longest point directory name; longer names are cut and end in a hash. */
#define SWEEP_NAME_MAX 200
/* Most points a sweep may have unless raised (rtsim sweep --max-points), and
 * the most it can be raised to. The cap is checked before any point is
 * expanded or any file written: a few lines of axes multiply into millions of
 * points, each a directory and an `rtsim run`. Expanded, a point takes about
 * 2 KB of memory here (its name and arguments). */
#define SWEEP_POINTS_DEFAULT 10000u
#define SWEEP_POINTS_MAX 1000000u

struct sweep_point {
  char name[SWEEP_NAME_MAX + 1]; /* directory name: "key=value,key=value" sanitised */
  unsigned index;                /* position in sweep order */
  const char **values;           /* the swept keys' values as written (sweep.nkeys; borrowed) */
  char **args;                   /* `rtsim run` arguments after the program name,
                                    NULL-terminated (owned) */
  double cost;                   /* expected host time, relative (see sweep.c) */
  double setup_s;                /* expected host seconds before the simulation starts
                                    (loading the scene, building its tree) */
  double mem_mb;                 /* expected peak host memory of its run, MiB (an
                                    over-estimate: see sweep.c) */
};

struct sweep {
  char file[512];    /* the sweep file as given */
  const char **keys; /* swept keys in dimension order (nkeys; owned by the sweep) */
  unsigned nkeys;
  struct sweep_point *points;
  unsigned npoints;
  void *priv; /* axis storage */
};

/* Read and check the sweep file at path and expand its points, each writing
 * into out_dir/<point name> (out_dir should be absolute: it goes into the
 * points' commands as given). On bad input fills e and returns false (s is
 * then empty, safe to free). */
bool sweep_load(struct sweep *s, const char *path, const char *out_dir, struct err *e);
/* The same with a cap on the points other than SWEEP_POINTS_DEFAULT (1 to
 * SWEEP_POINTS_MAX): a sweep with more is refused, at the axis or group that
 * takes the count past the cap. */
bool sweep_load_capped(struct sweep *s, const char *path, const char *out_dir, unsigned max_points,
                       struct err *e);
void sweep_free(struct sweep *s);

#endif
