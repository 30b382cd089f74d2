/* A sweep point's job: the point, its directory DIR/<point> and its command
 * line, and the files the sweep keeps there: command.sh (its exact command),
 * point.csv (its swept values, for merge), error.txt (its stderr, when it
 * failed) and .running (locked while a runner runs it). A point is complete
 * when its stats.json exists: rtsim run writes it last. */
#ifndef RTSIM_APP_SWEEP_JOB_H
#define RTSIM_APP_SWEEP_JOB_H

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

struct err;
struct sweep;
struct sweep_point;

/* What a point needs besides the sweep: its command and completion state. */
struct sweep_job {
  const struct sweep_point *p;
  char *dir;  /* DIR/<point> (owned) */
  char *line; /* the whole command, shell-quoted (owned) */
  bool complete;
  bool busy; /* claimed by another process when its turn came (sweep_job_claim) */
};

/* Append s to f, quoted for a POSIX shell when it holds anything but plain
 * characters. */
void sweep_shell_word(FILE *f, const char *s);
/* The point's command line: the program bin, then the point's arguments,
 * shell-quoted (caller frees). */
char *sweep_command_line(const char *bin, const struct sweep_point *p);
/* Whether dir/name exists. */
bool sweep_exists(const char *dir, const char *name);
/* mkdir -p path; false with e set when a directory cannot be made. */
bool sweep_make_dirs(const char *path, struct err *e);
/* Make the job's directory with its command.sh and (when the sweep has keys)
 * point.csv, each written whole; false with e set. */
bool sweep_job_prepare(const struct sweep *s, const struct sweep_job *j, struct err *e);
/* Whether the job's command.sh (if any) runs the job's own command, with the
 * sweep directory now at dir: paths may differ where they name the same
 * files (docs/sweeps.md). */
bool sweep_job_same_command(const struct sweep_job *j, const char *dir);
/* The first line of dir/error.txt that says "error", else its first line, or
 * "(no message)". */
void sweep_first_error(const char *dir, char *out, size_t cap);
/* s seconds as "42s", "3m05s" or "2h07m". */
void sweep_format_duration(double s, char *out, size_t cap);
/* Claim job j for this process (a lock on its .running, dropped with the
 * process however it ends): the lock's descriptor; -1 with *busy when
 * another process holds it; -1 without when the file system cannot lock. */
int sweep_job_claim(const struct sweep_job *j, bool *busy);
/* Drop a claim (fd < 0: none). */
void sweep_job_release(const struct sweep_job *j, int fd);
/* Whether a process holds point dir's claim; its holder's line in who. */
bool sweep_claimed(const char *dir, char *who, size_t cap);

#endif
