/* rtsim hits: nearest hits for rays given as CSV on stdin. A stable interface
 * for cross-checking our intersection against any other ray tracer. */
#include "app/app.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "app/opts.h"
#include "renderer/ray.h"
#include "renderer/trace.h"
#include "sim/err.h"

static const char HELP[] =
    "usage: rtsim hits SCENE.yaml < rays.csv > hits.csv\n"
    "\n"
    "Read rays as CSV on stdin, header 'id,ox,oy,oz,dx,dy,dz,tmin,tmax' (id a whole\n"
    "number; the others decimal numbers, tmax may be 'inf'), and write 'id,t,prim':\n"
    "the nearest hit with tmin < t < tmax (ties to the smaller prim), prim being the\n"
    "face index in 'rtsim export' order; a miss is 'id,inf,-1'. t is printed with 9\n"
    "significant digits, which round-trips a 32-bit float.\n"
    "\n"
    "options:\n"
    "  -h, --help          this text\n";

static const char HEADER[] = "id,ox,oy,oz,dx,dy,dz,tmin,tmax";

/* Parse one data line; on error fill e at (line, column). */
static bool parse_line(char *line, unsigned long lineno, unsigned long long *id, float v[8],
                       struct err *e) {
  char *p = line;
  for (int f = 0; f < 9; f++) {
    int col = (int)(p - line) + 1;
    char *end = NULL;
    errno = 0;
    if (f == 0) {
      *id = (*p >= '0' && *p <= '9') ? strtoull(p, &end, 10) : 0;
      if (!end || end == p || errno)
        return err_set(e, "<stdin>", (int)lineno, col, "id: not a whole number (expected 0 or more)");
    } else {
      v[f - 1] = strtof(p, &end);
      if (end == p || isnan(v[f - 1]))
        return err_set(e, "<stdin>", (int)lineno, col, "field %d: not a number", f + 1);
    }
    char want = f == 8 ? '\0' : ',';
    if (*end != want)
      return err_set(e, "<stdin>", (int)lineno, (int)(end - line) + 1,
                     f == 8 ? "unexpected text after tmax (expected 9 fields)"
                            : "expected ',' (a row has 9 fields: %s)", HEADER);
    p = end + 1;
  }
  return true;
}

int app_hits_answer(struct trace_ctx *tr, FILE *in, FILE *out) {
  struct err e;
  memset(&e, 0, sizeof e);
  char line[4096];
  unsigned long lineno = 0;
  int rc = 0;
  while (fgets(line, sizeof line, in)) {
    lineno++;
    size_t len = strlen(line);
    if (len && line[len - 1] == '\n') line[--len] = '\0';
    if (len && line[len - 1] == '\r') line[--len] = '\0';
    if (lineno == 1) {
      if (strcmp(line, HEADER) != 0) {
        err_set(&e, "<stdin>", 1, 1, "header: got '%.60s', expected '%s'", line, HEADER);
        rc = app_report(&e);
        break;
      }
      fprintf(out, "id,t,prim\n");
      continue;
    }
    if (len == 0) continue;
    unsigned long long id;
    float v[8];
    if (!parse_line(line, lineno, &id, v, &e)) {
      rc = app_report(&e);
      break;
    }
    struct ray r;
    memset(&r, 0, sizeof r);
    r.o = v3(v[0], v[1], v[2]);
    r.d = v3(v[3], v[4], v[5]);
    r.tmin = v[6];
    r.tmax = v[7];
    r.ignore_prim = -1;
    if (r.d.x == 0.0f && r.d.y == 0.0f && r.d.z == 0.0f) {
      err_set(&e, "<stdin>", (int)lineno, 1, "ray %llu: direction is zero", id);
      rc = app_report(&e);
      break;
    }
    struct trace_hit h;
    if (trace_closest(tr, &r, &h))
      fprintf(out, "%llu,%.9g,%d\n", id, (double)h.t, h.prim);
    else
      fprintf(out, "%llu,inf,-1\n", id);
  }
  if (rc == 0 && lineno == 0) {
    err_set(&e, "<stdin>", 0, 0, "no input (expected the header '%s')", HEADER);
    rc = app_report(&e);
  }
  return rc;
}

int cmd_hits(int argc, char **argv) {
  const struct opts_spec spec[] = {OPTS_END};
  struct opts_args args;
  int rc = opts_parse("hits", HELP, spec, argc, argv, &args);
  if (rc != OPTS_GO) return rc;
  const char *scene_path = opts_one_scene(&args);
  if (!scene_path) return APP_EXIT_USAGE;
  struct app_world w;
  if (!app_world_load(&w, scene_path)) return 2;
  struct trace_ctx tr;
  struct trace_layout layout;
  trace_layout_default(&layout);
  trace_init(&tr, &w.scene, &w.kd, mem_port_native(), &layout);
  rc = app_hits_answer(&tr, stdin, stdout);
  app_world_fini(&w);
  return rc;
}
