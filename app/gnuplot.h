/* gnuplot as a helper process that reads a script on a pipe, its output
 * thrown away. It ends with rtsim: killed first by a signal's cleanup
 * (app/outguard.h), so no file it draws can appear after the cleanup, and
 * sent SIGKILL by the kernel when rtsim dies otherwise (PR_SET_PDEATHSIG). */
#ifndef RTSIM_APP_GNUPLOT_H
#define RTSIM_APP_GNUPLOT_H

#include <stdbool.h>
#include <stdio.h>
#include <sys/types.h>

struct gnuplot {
  FILE *in; /* the script goes here */
  pid_t pid;
};

/* Start gnuplot; its stderr too goes to /dev/null when quiet. False when no
 * process can be started (a gnuplot that is not installed fails at
 * gnuplot_close instead). */
bool gnuplot_open(struct gnuplot *g, bool quiet);

/* End the script and wait for gnuplot: true when it exited with code 0. */
bool gnuplot_close(struct gnuplot *g);

#endif
