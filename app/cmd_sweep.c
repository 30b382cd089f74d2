/* rtsim sweep: the command. Its options become a plan; the sweep file is
 * loaded and checked whole; each point becomes a job (app/sweep_job.h) in
 * DIR/<point>, complete when its stats.json exists, so a rerun skips
 * complete points and retries the rest. Then one of: --status
 * (app/sweep_status.h), job lines for GNU parallel (app/sweep_emit.h), a
 * Slurm array script (app/sweep_slurm.h), or running the points here
 * (app/sweep_run.h), longest expected first. */
#define _XOPEN_SOURCE 700 /* realpath */

#include "app/app.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "app/opts.h"
#include "app/sweep.h"
#include "app/sweep_emit.h"
#include "app/sweep_job.h"
#include "app/sweep_run.h"
#include "app/sweep_slurm.h"
#include "app/sweep_status.h"
#include "sim/err.h"
#include "sim/outfile.h"

static const char HELP[] =
    "usage: rtsim sweep SWEEP.yaml -o DIR [-j N] [--max-points N] [--point NAME]...\n"
    "       rtsim sweep SWEEP.yaml -o DIR (--emit-jobs | --emit-slurm N | --status)\n"
    "\n"
    "Run every point of a sweep file (a base machine config, a workload, and axes\n"
    "over config or workload keys: docs/sweeps.md) as an 'rtsim run' into\n"
    "DIR/<point>, named for its values (policy=packet,dram.latency=400). Everything\n"
    "is checked before anything runs; points run N at a time, longest first. A\n"
    "point with a stats.json is complete and skipped, so the same command resumes\n"
    "a sweep and retries failed points; a failed point keeps its stderr in\n"
    "DIR/<point>/error.txt and the sweep exits 1.\n"
    "\n"
    "example:\n"
    "  rtsim sweep configs/sweeps/example.yaml -o build/sweep -j 2\n"
    "  rtsim merge build/sweep -o build/sweep.csv\n"
    "\n"
    "options:\n"
    "  -o, --output DIR  where the points go (created if needed)\n"
    "  -j, --jobs N      points at a time (default: the number of cores)\n"
    "  --max-points N    refuse a sweep of more than N points (default 10000, at\n"
    "                    most 1000000), before anything is written\n"
    "  --point NAME      run only the point NAME (repeatable): what job lines do\n"
    "  --emit-jobs       run nothing: print one shell command per incomplete point,\n"
    "                    for 'rtsim sweep S -o D --emit-jobs | parallel'\n"
    "  --emit-slurm N    run nothing: print a Slurm job array script, a task per N\n"
    "                    incomplete points, with --time and --mem (submit: sbatch)\n"
    "  --status          run and write nothing: count and list the points complete,\n"
    "                    failed, running and not run; exit 0 when all are complete\n"
    "  -h, --help        this text; --help-full: also the details\n"
    "\f"
    "\n"
    "Every point's exact command is in DIR/<point>/command.sh. A progress line\n"
    "(done, failed, ETA) goes to stderr when it is a terminal. SIGINT or SIGTERM\n"
    "stops the running points (they stay incomplete); a point also stops when its\n"
    "sweep is killed outright. A --point NAME that is not a point of the sweep is\n"
    "refused (exit 2). --emit-jobs writes DIR and the points' command.sh first; its\n"
    "lines use absolute paths and name their points. When every point is complete,\n"
    "--emit-jobs and --emit-slurm say \"nothing to run\", print nothing and exit 0,\n"
    "so nothing is submitted that could fail. --status gives each failed point's\n"
    "first error line. Then 'rtsim merge DIR -o TABLE.csv' joins the complete\n"
    "points into one table.\n";

/* The longest expected point first; equal estimates keep the sweep's order. */
static int by_cost(const void *a, const void *b) {
  const struct sweep_job *x = *(struct sweep_job *const *)a, *y = *(struct sweep_job *const *)b;
  if (x->p->cost != y->p->cost) return x->p->cost < y->p->cost ? 1 : -1;
  return (x->p->index > y->p->index) - (x->p->index < y->p->index);
}

/* The --point names (argv's strings). */
struct names {
  const char **v;
  unsigned n;
};

static bool add_name(const char *text, void *dst) {
  struct names *n = dst;
  if (!*text || strpbrk(text, "/\n\r")) return false;
  n->v = xrealloc(n->v, (n->n + 1ull) * sizeof *n->v);
  n->v[n->n++] = text;
  return true;
}

/* The command line: what to do, and where. */
struct plan {
  const char *sweep_path, *out;
  uint64_t jobs, max_points, per_task;
  bool emit, show, slurm;
  struct names names;        /* --point (names.v owned) */
  char dir[8192], bin[4096]; /* DIR and this program, absolute */
};

/* Absolute paths throughout, so commands run from any directory: DIR without
 * a trailing '/', and this program's path. Returns OPTS_GO or the exit code. */
static int plan_paths(struct plan *p) {
  char cwd[4096];
  if (p->out[0] == '/') snprintf(p->dir, sizeof p->dir, "%s", p->out);
  else if (getcwd(cwd, sizeof cwd)) snprintf(p->dir, sizeof p->dir, "%s/%s", cwd, p->out);
  else return app_usage_error("sweep", "cannot read the current directory: %s", strerror(errno));
  for (size_t l = strlen(p->dir); l > 1 && p->dir[l - 1] == '/';) p->dir[--l] = '\0';
  ssize_t bl = readlink("/proc/self/exe", p->bin, sizeof p->bin - 1);
  if (bl <= 0) {
    fprintf(stderr, "rtsim sweep: error: cannot find this program's path (/proc/self/exe)\n");
    return 1;
  }
  p->bin[bl] = '\0';
  return OPTS_GO;
}

/* Read argv into *p. Returns OPTS_GO, or the exit code after the help or
 * one message. */
static int plan_parse(struct plan *p, int argc, char **argv) {
  memset(p, 0, sizeof *p);
  long cores = sysconf(_SC_NPROCESSORS_ONLN);
  p->jobs = cores > 0 ? (uint64_t)cores : 1;
  p->max_points = SWEEP_POINTS_DEFAULT;
  p->per_task = 1;
  const struct opts_spec spec[] = {
      OPTS_STR("output", 'o', &p->out),
      OPTS_U64("jobs", 'j', &p->jobs, 1, 4096),
      OPTS_U64("max-points", 0, &p->max_points, 1, SWEEP_POINTS_MAX),
      OPTS_FLAG("emit-jobs", 0, &p->emit),
      {.name = "emit-slurm",
       .kind = OPTS_KIND_U64,
       .dst = &p->per_task,
       .lo = 1,
       .hi = 100000,
       .given = &p->slurm},
      OPTS_FLAG("status", 0, &p->show),
      OPTS_PARSE("point", 0, &p->names, add_name, "a point's name (a directory name, no '/')"),
      OPTS_END};
  struct opts_args args;
  int rc = opts_parse("sweep", HELP, spec, argc, argv, &args);
  if (rc != OPTS_GO) return rc;
  p->sweep_path = opts_one(&args, "SWEEP.yaml", "sweep file");
  if (!p->sweep_path) return APP_EXIT_USAGE;
  if (!p->out) return app_usage_error("sweep", "missing -o DIR");
  if (strpbrk(p->out, "\n\r"))
    return app_usage_error("sweep", "-o: a path with a line break cannot go into a job line");
  if (p->emit + p->slurm + p->show + (p->names.n > 0) > 1)
    return app_usage_error("sweep", "--emit-jobs, --emit-slurm, --status and --point go alone "
                                    "(got more than one)");
  return plan_paths(p);
}

/* The loaded sweep and its jobs. */
struct jobs {
  struct sweep s;
  char *sweep_abs; /* the sweep file, absolute (for job lines) */
  struct sweep_job *all;
  struct sweep_job **todo; /* the incomplete chosen points */
  bool *chosen;            /* by --point */
  unsigned ntodo, complete, nchosen;
};

/* A job for every point; the chosen incomplete ones in todo, longest
 * expected first. Returns 0, or the exit code after one message. A complete
 * point made by another command is refused unless --status. */
static int make_jobs(const struct plan *p, struct jobs *J) {
  struct sweep *s = &J->s;
  /* --point: only the named points, each of them a point of the sweep. */
  for (unsigned k = 0; k < p->names.n; k++) {
    unsigned i = 0;
    while (i < s->npoints && strcmp(s->points[i].name, p->names.v[k])) i++;
    if (i == s->npoints) {
      fprintf(stderr,
              "rtsim sweep: error: --point '%s': no such point in %s (the sweep file changed "
              "since the job was written? emit the jobs again)\n",
              p->names.v[k], p->sweep_path);
      return APP_EXIT_USAGE;
    }
    J->chosen[i] = true;
  }
  for (unsigned i = 0; i < s->npoints; i++) {
    struct sweep_job *j = &J->all[i];
    j->p = &s->points[i];
    size_t n = strlen(p->dir) + strlen(j->p->name) + 2;
    j->dir = xmalloc(n);
    snprintf(j->dir, n, "%s/%s", p->dir, j->p->name);
    j->line = sweep_command_line(p->bin, j->p);
    if (p->names.n && !J->chosen[i]) continue;
    J->nchosen++;
    j->complete = sweep_exists(j->dir, "stats.json");
    if (p->show) continue; /* --status writes nothing and refuses nothing */
    /* A sweep killed outright cannot remove its temporaries (a point's
     * stderr, kept as .error.txt.<pid>.<n>.tmp), even in a point that
     * completed just before. */
    if (j->complete) outfile_remove_stale(j->dir);
    if (j->complete && !sweep_job_same_command(j, p->dir)) {
      fprintf(stderr,
              "rtsim sweep: error: %s is complete but was made by another command (see its "
              "command.sh): the sweep changed since; use another -o DIR, or delete the point "
              "to run it again\n",
              j->dir);
      return APP_EXIT_USAGE;
    }
    if (j->complete) J->complete++;
    else J->todo[J->ntodo++] = j;
  }
  if (!p->show) qsort(J->todo, J->ntodo, sizeof *J->todo, by_cost);
  return 0;
}

/* Run the points here, and say how it went. Returns the exit code. */
static int run_here(const struct plan *p, struct jobs *J) {
  const unsigned ntodo = J->ntodo, at_once = (unsigned)(p->jobs < ntodo ? p->jobs : ntodo);
  if (p->names.n)
    fprintf(stderr, "sweep: %u of %u points named, %u complete, running %u, %u at a time\n",
            J->nchosen, J->s.npoints, J->complete, ntodo, at_once);
  else
    fprintf(stderr, "sweep: %u points, %u complete, running %u, %u at a time\n", J->s.npoints,
            J->complete, ntodo, at_once);
  double t0 = app_now();
  int sig;
  unsigned busy = 0;
  int failed = sweep_run_jobs(p->bin, J->todo, ntodo, (unsigned)p->jobs, &J->s, &sig, &busy);
  char took[32];
  sweep_format_duration(app_now() - t0, took, sizeof took);
  if (failed < 0) {
    fprintf(stderr, "sweep: interrupted (%s) after %s; rerun the same command to resume\n",
            strsignal(sig), took);
    return 128 + sig;
  }
  fprintf(stderr, "sweep: %u run, %d failed, %u already complete, %s\n",
          ntodo - (unsigned)failed - busy, failed, J->complete, took);
  if (busy) {
    fprintf(stderr, "sweep: %u point%s left to the process%s running them (see --status):", busy,
            busy == 1 ? "" : "s", busy == 1 ? "" : "es");
    for (unsigned i = 0, shown = 0; i < ntodo && shown < 5; i++)
      if (J->todo[i]->busy) fprintf(stderr, " %s", J->todo[i]->p->name), shown++;
    fputs(busy > 5 ? " ...\n" : "\n", stderr);
  }
  if (!failed) return 0;
  fprintf(stderr, "sweep: %d point%s failed (each one's stderr is in its error.txt):\n", failed,
          failed == 1 ? "" : "s");
  for (unsigned i = 0; i < ntodo; i++) {
    if (J->todo[i]->complete || J->todo[i]->busy) continue;
    char msg[1024];
    sweep_first_error(J->todo[i]->dir, msg, sizeof msg);
    fprintf(stderr, "  %s: %s\n", J->todo[i]->p->name, msg);
  }
  return 1;
}

/* What the plan asks of the jobs: --status, job lines, a Slurm script, or a
 * run here. Returns the exit code. */
static int dispatch(const struct plan *p, struct jobs *J) {
  struct err e = {0};
  if (p->show) return sweep_status(&J->s, J->all, p->dir);
  if (!sweep_make_dirs(p->dir, &e)) return app_report(&e);
  const struct sweep_line_base base = {p->bin, J->sweep_abs, p->dir, p->max_points};
  if (!p->emit && !p->slurm) return run_here(p, J);
  /* Nothing incomplete: no job line and no script, so that nothing handed to
   * parallel or sbatch can run and fail (a Slurm array needs a task). */
  if (J->ntodo == 0) {
    fprintf(stderr, "rtsim sweep: nothing to run: all %u points complete (no %s written)\n",
            J->complete, p->slurm ? "script" : "job line");
    return 0;
  }
  for (unsigned i = 0; i < J->ntodo; i++)
    if (!sweep_job_prepare(&J->s, J->todo[i], &e)) return app_report(&e);
  if (p->slurm)
    sweep_emit_slurm(&base, J->todo, J->ntodo, (unsigned)p->per_task, J->all, J->s.npoints,
                     J->complete);
  else sweep_emit_jobs(&base, J->todo, J->ntodo, J->s.npoints, J->complete);
  return 0;
}

int cmd_sweep(int argc, char **argv) {
  struct plan p;
  int rc = plan_parse(&p, argc, argv);
  if (rc != OPTS_GO) goto early;
  struct jobs J = {0};
  struct err e = {0};
  if (!sweep_load_capped(&J.s, p.sweep_path, p.dir, (unsigned)p.max_points, &e)) {
    sweep_free(&J.s);
    rc = app_report(&e);
    goto early;
  }
  /* The sweep file made absolute, for job lines (it was just read). */
  J.sweep_abs = realpath(p.sweep_path, NULL);
  CHECK(J.sweep_abs);
  J.all = xcalloc(J.s.npoints, sizeof *J.all);
  J.todo = xcalloc(J.s.npoints, sizeof *J.todo);
  J.chosen = xcalloc(J.s.npoints, sizeof *J.chosen);
  if (strpbrk(J.sweep_abs, "\n\r"))
    rc = app_usage_error("sweep", "%s: a path with a line break cannot go into a job line",
                         p.sweep_path);
  else if ((rc = make_jobs(&p, &J)) == 0) rc = dispatch(&p, &J);
  for (unsigned i = 0; i < J.s.npoints; i++) {
    free(J.all[i].dir);
    free(J.all[i].line);
  }
  free(J.all);
  free(J.todo);
  free(J.chosen);
  free(J.sweep_abs);
  sweep_free(&J.s);
early:
  free(p.names.v);
  return rc;
}
