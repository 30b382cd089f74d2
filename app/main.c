/* rtsim: entry point. Parses the subcommand and hands over; only this layer
 * prints errors and chooses exit codes. */
#include <errno.h>
#include <getopt.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "app/app.h"
#include "renderer/scene_file.h"
#include "sim/err.h"

static const char USAGE[] =
    "usage: rtsim COMMAND [options]\n"
    "\n"
    "commands:\n"
    "  render SCENE.yaml -o IMAGE.exr   ray trace a scene to an OpenEXR image\n"
    "  export SCENE.yaml -o SCENE.ply   write the scene's triangles (face i = primitive i)\n"
    "  hits SCENE.yaml                  nearest hits for rays read as CSV on stdin\n"
    "  traffic SCENE.yaml --rays R -o T.csv  DRAM-to-L2 traffic of the scheduling\n"
    "                                   policies for every cache size, 1 KB to 4 MB\n"
    "  trace SCENE.yaml --din FILE ...  the access stream as a Dinero IV din trace\n"
    "  run MACHINE.yaml SCENE.yaml -o DIR  render on the timed many-core machine:\n"
    "                                   cycles, utilization, L2 and DRAM statistics\n"
    "  sweep SWEEP.yaml -o DIR          run a sweep file's points (machine configs x\n"
    "                                   workloads) in parallel, resumable; or print\n"
    "                                   them as jobs for GNU parallel or Slurm\n"
    "  merge DIR -o TABLE.csv           a sweep's complete points as one tidy table\n"
    "  plot TABLE.csv --x K --y M -o F  line plots of a merged table (PNG or SVG)\n"
    "  bench SCENE.yaml...              primary-ray throughput (rays/s) per scene\n"
    "\n"
    "Run 'rtsim COMMAND --help' for a command's options.\n";

int app_report(const struct err *e) {
  char buf[ERR_FILE_MAX + ERR_MSG_MAX + 64];
  err_format(e, buf, sizeof buf);
  fprintf(stderr, "%s\n", buf);
  return APP_EXIT_USAGE;
}

int app_usage_error(const char *cmd, const char *fmt, ...) {
  char msg[1024];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  fprintf(stderr, "rtsim %s: error: %s (see 'rtsim %s --help')\n", cmd, msg, cmd);
  return APP_EXIT_USAGE;
}

int app_option_error(const char *cmd, int c, char **argv) {
  if (c == ':') return app_usage_error(cmd, "option %s needs a value", argv[optind - 1]);
  return app_usage_error(cmd, "unknown option '%s'", argv[optind - 1]);
}

const char *app_one_operand(const char *cmd, const char *what, const char *noun, int argc,
                            char **argv) {
  if (optind == argc - 1) return argv[optind];
  if (optind >= argc)
    app_usage_error(cmd, "missing %s", what);
  else
    app_usage_error(cmd, "expected one %s, got %d", noun, argc - optind);
  return NULL;
}

const char *app_one_scene(const char *cmd, int argc, char **argv) {
  return app_one_operand(cmd, "SCENE.yaml", "scene file", argc, argv);
}

double app_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

bool app_world_load(struct app_world *w, const char *path) {
  memset(w, 0, sizeof *w);
  struct err e;
  memset(&e, 0, sizeof e);
  double t0 = app_now();
  if (!scene_load(&w->scene, path, &e)) {
    app_report(&e);
    return false;
  }
  double t1 = app_now();
  struct kd_build_params p;
  kd_build_params_default(&p);
  kd_build(&w->kd, &w->scene, &p);
  w->load_s = t1 - t0;
  w->build_s = app_now() - t1;
  return true;
}

void app_world_fini(struct app_world *w) {
  kd_fini(&w->kd);
  scene_fini(&w->scene);
}

bool app_parse_u64(const char *cmd, const char *opt, const char *text, uint64_t lo, uint64_t hi,
                   uint64_t *out) {
  char *end = NULL;
  errno = 0;
  unsigned long long v = (text[0] >= '0' && text[0] <= '9') ? strtoull(text, &end, 10) : 0;
  if (!end || *end || errno || v < lo || v > hi) {
    app_usage_error(cmd, "%s: got '%s', expected a whole number from %llu to %llu", opt, text,
                    (unsigned long long)lo, (unsigned long long)hi);
    return false;
  }
  *out = v;
  return true;
}

int main(int argc, char **argv) {
  if (argc < 2) {
    fputs(USAGE, stderr);
    return APP_EXIT_USAGE;
  }
  const char *cmd = argv[1];
  if (!strcmp(cmd, "--help") || !strcmp(cmd, "-h") || !strcmp(cmd, "help")) {
    fputs(USAGE, stdout);
    return 0;
  }
  if (!strcmp(cmd, "render")) return cmd_render(argc - 1, argv + 1);
  if (!strcmp(cmd, "export")) return cmd_export(argc - 1, argv + 1);
  if (!strcmp(cmd, "hits")) return cmd_hits(argc - 1, argv + 1);
  if (!strcmp(cmd, "bench")) return cmd_bench(argc - 1, argv + 1);
  if (!strcmp(cmd, "traffic")) return cmd_traffic(argc - 1, argv + 1);
  if (!strcmp(cmd, "trace")) return cmd_trace(argc - 1, argv + 1);
  if (!strcmp(cmd, "run")) return cmd_run(argc - 1, argv + 1);
  if (!strcmp(cmd, "sweep")) return cmd_sweep(argc - 1, argv + 1);
  if (!strcmp(cmd, "merge")) return cmd_merge(argc - 1, argv + 1);
  if (!strcmp(cmd, "plot")) return cmd_plot(argc - 1, argv + 1);
  fprintf(stderr, "rtsim: error: unknown command '%s' (expected one of: render, export, hits, traffic, trace, run, sweep, merge, plot, bench)\n",
          cmd);
  return APP_EXIT_USAGE;
}
