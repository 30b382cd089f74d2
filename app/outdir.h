/* rtsim run's output directory, whole or absent: a run writes its outputs
 * into a fresh sibling ".NAME.run-PID" and puts it in DIR's place at the end
 * with one rename (each file in it is whole already: sim/outfile.h). DIR
 * absent, the sibling is renamed to DIR; DIR present (an earlier run, a
 * sweep's point with its command.sh and point.csv), the sibling first gets
 * the entries of DIR that are not the run's own outputs, then the two swap
 * with one atomic rename (renameat2 RENAME_EXCHANGE) and the old contents,
 * now under the sibling's name, are removed. A run that fails or is stopped
 * before that leaves DIR as it was (absent, or the earlier run whole) and no
 * sibling. Where the file system cannot exchange two names, the swap is two
 * renames (old aside, new in): DIR is briefly absent, never mixed.
 *
 * SIGINT, SIGTERM and SIGHUP while a run writes: app/outguard.h removes the
 * sibling with what it holds. */
#ifndef RTSIM_APP_OUTDIR_H
#define RTSIM_APP_OUTDIR_H

#include <stdbool.h>
#include <stddef.h>

struct err;

#define OUTDIR_PATH_MAX 4096

struct outdir {
  char path[OUTDIR_PATH_MAX];   /* the directory as given */
  char write[OUTDIR_PATH_MAX];  /* the fresh sibling the outputs go to */
  char target[OUTDIR_PATH_MAX]; /* path made absolute */
  bool fresh;                   /* write exists and is ours */
  const char *const *outputs;   /* outdir_begin's */
};

/* Make the fresh sibling of path (removing siblings of runs into path that
 * were killed outright) and guard it against signals. outputs: the names the
 * run writes (NULL-terminated; static storage), never carried over from an
 * earlier DIR. False with e set when path cannot be a directory (its parent
 * does not exist, it is a file) or the sibling cannot be made. */
bool outdir_begin(struct outdir *d, const char *path, const char *const *outputs, struct err *e);

/* Where the run writes an output of its own given as path (a DRAM trace, a
 * heat map): inside the sibling when path's directory is DIR, so it comes and
 * goes with the run's other outputs; else path itself. False when path is in
 * DIR under one of the run's output names. */
bool outdir_place(const struct outdir *d, const char *path, char *buf, size_t cap);

/* The outputs are written: put the sibling in DIR's place (signals held off
 * meanwhile). False with e set when that fails: DIR then stays as it was and
 * the sibling is removed. */
bool outdir_commit(struct outdir *d, struct err *e);

/* Give up (a failed write): remove the sibling; DIR is untouched. Safe after
 * commit or on a zeroed d. */
void outdir_abort(struct outdir *d);

/* Name a file of the sibling in e by its place in DIR (as given), so a
 * message says DIR/stats.csv, not the sibling's. */
void outdir_name_in_err(const struct outdir *d, struct err *e);

#endif
