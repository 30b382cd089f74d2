/* The shared pieces of the rtsim program (app.h): error reporting, option
 * values several commands take, the world a command loads. main.c only dispatches. */
#include "app/app.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "renderer/policy.h"
#include "renderer/scene_file.h"
#include "renderer/shade.h"
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

bool app_parse_rays(const char *text, void *mask) { return shade_parse_rays(text, mask); }

bool app_parse_policy(const char *text, void *kind) { return policy_parse(text, kind); }

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
