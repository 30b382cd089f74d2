/* What a signal removes of the outputs a command has not finished. While
 * anything is guarded, SIGINT, SIGTERM and SIGHUP remove this process's
 * temporaries (sim/outfile.h's ".<name>.<pid>.<n>.tmp", our pid, nested ones
 * too) in the directories of the guarded outputs, and each guarded staging
 * directory whole, then end the process by the same signal, so its parent (a
 * shell, rtsim sweep) sees how it ended. A signal the caller ignores (nohup)
 * stays ignored. NOTE: process-wide state, since a signal handler reaches
 * nothing else: one table a process, filled by the command's own thread. */
#ifndef RTSIM_APP_OUTGUARD_H
#define RTSIM_APP_OUTGUARD_H

#include <sys/types.h>

/* Guard the temporaries this process makes beside path (an output file):
 * on a signal, path's directory is searched for them. */
void outguard_beside(const char *path);

/* Guard dir, a directory this process made and alone writes into (a run's
 * fresh sibling): on a signal its entries, then dir itself, are removed. */
void outguard_tree(const char *dir);
/* Stop guarding dir (outguard_tree's): it was swapped in or removed. */
void outguard_untree(const char *dir);

/* A helper process drawing an output (gnuplot): on a signal it is killed
 * and reaped before anything is removed, so it cannot write after. Forget
 * it once it is waited for (signals held). */
void outguard_helper(pid_t pid);
void outguard_helper_done(pid_t pid);

/* Hold the signals off while several names change (a swap); they land at
 * outguard_release, on what is then guarded. Calls nest. */
void outguard_hold(void);
void outguard_release(void);

/* Forget everything guarded and give the signals their earlier actions.
 * Safe when nothing is guarded. */
void outguard_clear(void);

#endif
