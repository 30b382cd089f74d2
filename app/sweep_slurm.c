/* The Slurm emitter (app/sweep_slurm.h): points dealt to tasks, and the
 * time and memory each task asks for, from the sweep's estimates and what
 * complete points measured. */
#include "app/sweep_slurm.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "app/csv.h"
#include "app/sweep.h"
#include "app/sweep_emit.h"
#include "app/sweep_job.h"
#include "sim/err.h"

/* What the complete points say about host time and memory: the most seconds
 * of simulation per unit of the sweep's cost estimate, and the largest peak
 * memory (MiB); 0 when no complete point says. */
static void calibrate(struct sweep_job *all, unsigned n, double *rate, double *peak_mb) {
  *rate = *peak_mb = 0;
  for (unsigned i = 0; i < n; i++) {
    if (!all[i].complete || all[i].p->cost <= 0) continue;
    char path[8192], v[64];
    snprintf(path, sizeof path, "%s/stats.json", all[i].dir);
    const char *why;
    FILE *f = err_fopen_regular(path, &why);
    if (!f) continue;
    char text[1 << 16];
    /* The members read sit at the end of stats.json: read its tail. */
    if (fseek(f, -(long)(sizeof text - 1), SEEK_END) != 0) rewind(f);
    size_t got = fread(text, 1, sizeof text - 1, f);
    fclose(f);
    text[got] = '\0';
    double x;
    if (csv_json_member(text, "wall_s", v, sizeof v) && csv_number(v, &x) &&
        x / all[i].p->cost > *rate)
      *rate = x / all[i].p->cost;
    if (csv_json_member(text, "peak_rss_mb", v, sizeof v) && csv_number(v, &x) && x > *peak_mb)
      *peak_mb = x;
  }
}

/* Seconds of simulation per unit of the cost estimate when no point has run
 * yet: 3x the most measured on the project's machine, 5.3 us (the example
 * sweep, every ray type, on 2 shared cores; a 256x256 primary-ray image of
 * the small room took 1.3 us). Too high a rate only asks for more time. */
#define SWEEP_DEFAULT_RATE 1.6e-5

/* --emit-slurm: a job array script, task k running the points of line k.
 * Points go to tasks in a snake (longest first: task 1, 2, ..., K, K, ...,
 * 1, ...) so the tasks' expected times come out alike; the time request is
 * twice the longest task's (at the complete points' measured rate when there
 * are some), the memory request the largest point's estimate or twice the
 * complete points' measured peak, whichever is larger. Slurm keeps its own copy of a script at
 * submission, so a script emitted later cannot change an array already queued. */
void sweep_emit_slurm(const struct sweep_line_base *b, struct sweep_job **todo, unsigned n,
                      unsigned per, struct sweep_job *all, unsigned npoints, unsigned complete) {
  const char *sweep_file = b->sweep;
  CHECK(n > 0 && per > 0); /* cmd_sweep.c writes no script when nothing is left */
  const unsigned tasks = (n + per - 1) / per;
  /* per slots a task: the snake may give a later task per points while an
   * earlier one has fewer. */
  struct sweep_job **by_task = xcalloc((size_t)tasks * per, sizeof *by_task);
  unsigned *count = xcalloc(tasks, sizeof *count);
  double *secs = xcalloc(tasks, sizeof *secs);
  double rate, seen_mb, mem = 0;
  calibrate(all, npoints, &rate, &seen_mb);
  const bool measured = rate > 0;
  if (!measured) rate = SWEEP_DEFAULT_RATE;
  for (unsigned i = 0; i < n; i++) {
    const unsigned round = i / tasks, k = round % 2 ? tasks - 1 - i % tasks : i % tasks;
    by_task[k * per + count[k]++] = todo[i];
    secs[k] += todo[i]->p->setup_s + rate * todo[i]->p->cost;
    if (todo[i]->p->mem_mb > mem) mem = todo[i]->p->mem_mb;
  }
  double longest = 0;
  for (unsigned k = 0; k < tasks; k++)
    if (secs[k] > longest) longest = secs[k];
  if (2 * seen_mb + 16 > mem) mem = 2 * seen_mb + 16;
  unsigned minutes = (unsigned)ceil(2 * longest / 60);
  if (minutes < 5) minutes = 5;
  const unsigned mib = 16 * (unsigned)ceil(mem / 16);
  printf("#!/bin/sh\n"
         "# Written by rtsim sweep --emit-slurm %u: %u task%s of at most %u of the %u incomplete\n"
         "# points of the sweep %s (%u points) into %s.\n"
         "# Submit with: sbatch THIS_FILE. Slurm keeps its own copy at submission, so emitting\n"
         "# again later changes no task of an array already queued; a task names its points,\n"
         "# skips one complete (or running elsewhere) when it starts, keeps a failed one's\n"
         "# stderr in its error.txt, and exits 2 when its number is not in this file.\n"
         "# Requests: time twice the longest task's expected %.0f s; memory the largest\n"
         "# point's %s (docs/sweeps.md).\n",
         per, tasks, tasks == 1 ? "" : "s", per, n, sweep_file, npoints, b->dir, longest,
         measured ? "estimate, or twice the complete points' peak if larger"
                  : "estimate (no point is complete to measure from)");
  printf("#SBATCH --job-name=rtsim-sweep\n#SBATCH --array=1-%u\n#SBATCH --ntasks=1\n"
         "#SBATCH --cpus-per-task=1\n#SBATCH --time=%u\n#SBATCH --mem=%uM\n",
         tasks, minutes, mib);
  printf("case \"${SLURM_ARRAY_TASK_ID:-}\" in\n");
  for (unsigned k = 0; k < tasks; k++) {
    printf("%u) exec ", k + 1);
    sweep_job_line(stdout, b, &by_task[k * per], count[k]);
    printf(" ;;\n");
  }
  printf("*) echo \"rtsim sweep: no task '${SLURM_ARRAY_TASK_ID:-}' in $0 (it has tasks 1 to %u;"
         " run it as a Slurm array, sbatch $0)\" >&2; exit 2 ;;\nesac\n",
         tasks);
  if (tasks > 1000)
    fprintf(stderr,
            "rtsim sweep: warning: %u array tasks; clusters often cap arrays at 1000 "
            "(MaxArraySize): raise N\n",
            tasks);
  fprintf(stderr, "rtsim sweep: %u array tasks (%u incomplete points of %u, %u complete)\n", tasks,
          n, npoints, complete);
  free(by_task);
  free(count);
  free(secs);
}
