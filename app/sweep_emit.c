/* Job lines (app/sweep_emit.h): every word shell-quoted, every path
 * absolute, so a line runs from any directory on any node that sees them. */
#include "app/sweep_emit.h"

#include "app/sweep.h"
#include "app/sweep_job.h"

/* A job line: the sweep's runner on points js[0..n), one at a time (-j 1: a
 * cluster job has one core unless it asks for more). It names its points, so
 * it means the same whatever list it sits in; a name the sweep no longer has
 * is refused when it runs. */
void sweep_job_line(FILE *f, const struct sweep_line_base *b, struct sweep_job *const *js,
                    unsigned n) {
  sweep_shell_word(f, b->bin);
  fputs(" sweep ", f);
  sweep_shell_word(f, b->sweep);
  fputs(" -o ", f);
  sweep_shell_word(f, b->dir);
  fputs(" -j 1", f);
  if (b->max_points != SWEEP_POINTS_DEFAULT)
    fprintf(f, " --max-points %llu", (unsigned long long)b->max_points);
  for (unsigned i = 0; i < n; i++) {
    fputs(" --point ", f);
    sweep_shell_word(f, js[i]->p->name);
  }
}

void sweep_emit_jobs(const struct sweep_line_base *b, struct sweep_job **todo, unsigned n,
                     unsigned npoints, unsigned complete) {
  for (unsigned i = 0; i < n; i++) {
    sweep_job_line(stdout, b, &todo[i], 1);
    putchar('\n');
  }
  fprintf(stderr, "rtsim sweep: %u job lines (%u points, %u complete)\n", n, npoints, complete);
}
