/* --status (app/sweep_status.h): each point's state from its directory alone:
 * complete (stats.json), running (a process holds its .running claim),
 * failed (error.txt), or not run; nothing is written. */
#include "app/sweep_status.h"

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "app/sweep.h"
#include "app/sweep_job.h"
#include "sim/err.h"

/* Whether point dir holds anything but what the sweep writes before a run. */
static bool has_outputs(const char *dir) {
  DIR *d = opendir(dir);
  if (!d) return false;
  bool any = false;
  struct dirent *de;
  while (!any && (de = readdir(d)))
    any = strcmp(de->d_name, ".") && strcmp(de->d_name, "..") && strcmp(de->d_name, "command.sh") &&
          strcmp(de->d_name, "point.csv") && strcmp(de->d_name, ".running") &&
          strcmp(de->d_name, "error.txt");
  closedir(d);
  return any;
}

/* --status: each point's state, failed ones first; nothing written. */
int sweep_status(const struct sweep *s, struct sweep_job *all, const char *dir) {
  enum { FAILED, RUNNING, NOT_RUN, COMPLETE, NSTATES };
  static const char *const label[NSTATES] = {"failed", "running", "not run", "complete"};
  unsigned count[NSTATES] = {0};
  char **detail = xcalloc(s->npoints, sizeof *detail);
  unsigned char *state = xcalloc(s->npoints, 1);
  for (unsigned i = 0; i < s->npoints; i++) {
    struct sweep_job *j = &all[i];
    char text[1024] = "", who[512];
    if (j->complete) {
      state[i] = COMPLETE;
      if (!sweep_job_same_command(j, dir))
        snprintf(text, sizeof text, "made by another command (see its command.sh)");
    } else if (sweep_claimed(j->dir, who, sizeof who)) {
      state[i] = RUNNING;
      char host[256] = "?";
      long pid = 0;
      long long since = 0;
      if (sscanf(who, "%255s %ld %lld", host, &pid, &since) == 3) {
        char took[32];
        sweep_format_duration((double)(time(NULL) - since), took, sizeof took);
        snprintf(text, sizeof text, "on %s, pid %ld, for %s", host, pid, took);
      }
    } else if (sweep_exists(j->dir, "error.txt")) {
      state[i] = FAILED;
      sweep_first_error(j->dir, text, sizeof text);
    } else {
      state[i] = NOT_RUN;
      if (has_outputs(j->dir)) snprintf(text, sizeof text, "stopped part way (no stats.json)");
    }
    count[state[i]]++;
    detail[i] = text[0] ? strdup(text) : NULL;
  }
  printf("%s into %s: %u points: %u complete, %u failed, %u running, %u not run\n", s->file, dir,
         s->npoints, count[COMPLETE], count[FAILED], count[RUNNING], count[NOT_RUN]);
  for (unsigned st = 0; st < NSTATES; st++)
    for (unsigned i = 0; i < s->npoints; i++) {
      if (state[i] != st) continue;
      printf("%-9s %s%s%s\n", label[st], all[i].p->name, detail[i] ? ": " : "",
             detail[i] ? detail[i] : "");
      free(detail[i]);
    }
  free(detail);
  free(state);
  return count[COMPLETE] == s->npoints ? 0 : 1;
}
