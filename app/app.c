/* The shared pieces of the rtsim program (app.h): error reporting, option
 * values, the world a command loads. main.c only dispatches. */
#include "app/app.h"

#include <errno.h>
#include <getopt.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "renderer/scene_file.h"
#include "sim/err.h"

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
  if (!scene_file_load(&w->scene, path, &e)) {
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
