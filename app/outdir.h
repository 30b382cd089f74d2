/* rtsim run's output directory, complete or incomplete as a whole, never a mix
 * of two runs (each file in it is whole already: sim/outfile.h). A directory
 * is complete when it holds stats.json, which a run writes last.
 *
 * Into an incomplete (or new) directory a run writes in place: interrupted,
 * it stays incomplete. A complete directory is never written in place: the
 * run writes a fresh sibling ".NAME.run-PID" and swaps it in at the end with
 * one atomic rename (renameat2 RENAME_EXCHANGE), after carrying over the
 * entries that are not the run's own outputs (a sweep's command.sh and
 * point.csv, a DRAM trace written into the directory); the old directory,
 * now under the sibling's name, is then removed. Interrupted before the swap,
 * the old directory is untouched. Where the file system cannot exchange two
 * names, the swap is two renames (old aside, new in): DIR is briefly absent,
 * never mixed.
 *
 * SIGINT, SIGTERM and SIGHUP while a run writes: the handler removes the run's
 * temporaries (and the fresh sibling with what it holds), then ends the
 * process by the same signal. NOTE: that needs process-wide state (a signal
 * handler reaches nothing else): one output directory per process. */
#ifndef RTSIM_APP_OUTDIR_H
#define RTSIM_APP_OUTDIR_H

#include <stdbool.h>

struct err;

#define OUTDIR_PATH_MAX 4096

struct outdir {
  char path[OUTDIR_PATH_MAX];   /* the directory as given */
  char write[OUTDIR_PATH_MAX];  /* where the outputs go: path, or the fresh sibling */
  char target[OUTDIR_PATH_MAX]; /* path made absolute, when fresh */
  bool fresh;                   /* write is the fresh sibling of a complete path */
  const char *const *outputs;   /* outdir_begin's */
};

/* Make the directory ready to write (create it, or a fresh sibling of a
 * complete one; remove temporaries and siblings of runs that were killed
 * outright) and arm the signal handler. outputs: the names the run writes
 * (NULL-terminated; static storage): their temporaries are what a signal
 * removes, and they are never carried over. False with e set when a
 * directory cannot be made; nothing is armed then. */
bool outdir_begin(struct outdir *d, const char *path, const char *const *outputs, struct err *e);

/* Also remove this temporary (another outfile's, e.g. the DRAM trace's) on a
 * signal; NULL forgets it. The string must stay valid until then. */
void outdir_watch(const char *tmp);

/* The outputs are written: swap a fresh sibling in (signals held off while
 * it happens) and disarm. False with e set when the swap fails (the old
 * directory then stays as it was, and the sibling is removed). */
bool outdir_commit(struct outdir *d, struct err *e);

/* Give up (a failed write): remove a fresh sibling and disarm. The old
 * directory is untouched. Safe after commit or on a zeroed d. */
void outdir_abort(struct outdir *d);

#endif
