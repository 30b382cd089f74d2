/* Output files that are either whole or absent: write to a temporary beside
 * the destination, rename over it only when everything went well. A reader
 * never sees a half file, a failed write leaves an earlier file as it was, and
 * no temporary is left behind on error. Knows nothing of what is written.
 *
 * Temporaries are "<dir>/.<name>.<pid>.<n>.tmp" (n counts up from 0 past names
 * that exist), created exclusively, so two writers never share one. */
#ifndef RTSIM_SIM_OUTFILE_H
#define RTSIM_SIM_OUTFILE_H

#include <stdbool.h>
#include <stdio.h>

struct err;

/* One output in progress. Caller-provided storage; zero-initialised it is
 * "nothing open", which outfile_abort accepts. */
struct outfile {
  FILE *f;          /* the temporary, open for writing; NULL for outfile_open_named */
  char *path;       /* the destination (a copy) */
  char *tmp;        /* the temporary's name (beside path, so rename is atomic) */
  const char *what; /* for messages, "cannot write <what>: ..." (not copied) */
};

/* Create a temporary for path and open it for writing (o->f). what names the
 * output in messages ("EXR", "the table"). False with e set (file = path) when
 * the temporary cannot be created, e.g. path's directory does not exist. */
bool outfile_open(struct outfile *o, const char *path, const char *what, struct err *e);

/* The same for a writer that opens the file by name (gnuplot, a library, a
 * child process): the temporary o->tmp is created empty and closed; hand that
 * name to the writer, then commit or abort as above. */
bool outfile_open_named(struct outfile *o, const char *path, const char *what, struct err *e);

/* Flush and close the temporary, and rename it to the destination. On any
 * failure (a write error seen by the stream, close, rename) the temporary is
 * removed, the destination untouched, and e set (file = path) with the
 * system's reason. Resets o either way. NOTE: no fsync: the guarantee holds
 * against our own failures (a full disk, a crash, a signal), not against a
 * power cut; fsync per file would cost milliseconds on sweeps of many points. */
bool outfile_commit(struct outfile *o, struct err *e);

/* Give up: close and remove the temporary; the destination stays as it was.
 * Resets o; does nothing on a reset or zeroed o. */
void outfile_abort(struct outfile *o);

/* Remove the temporaries in dir of processes that no longer run (a process
 * killed outright cannot remove its own). Returns how many were removed; a
 * directory that cannot be read removes none. */
unsigned outfile_remove_stale(const char *dir);

#endif
