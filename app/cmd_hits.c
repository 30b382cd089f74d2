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
#include "sim/scalar.h"

static const char HELP[] =
    "usage: rtsim hits SCENE.yaml < rays.csv > hits.csv\n"
    "\n"
    "Read rays as CSV on stdin, header 'id,ox,oy,oz,dx,dy,dz,tmin,tmax' (id a whole\n"
    "number; the others decimal numbers, tmax may be 'inf'; no spaces, no leading\n"
    "zeros such as 01.5; rows of up to 1 MiB), and write 'id,t,prim':\n"
    "the nearest hit with tmin < t < tmax (ties to the smaller prim), prim being the\n"
    "face index in 'rtsim export' order; a miss is 'id,inf,-1'. t is printed with 9\n"
    "significant digits, which round-trips a 32-bit float.\n"
    "\n"
    "example (one ray straight down from (0, 1, 0)):\n"
    "  printf 'id,ox,oy,oz,dx,dy,dz,tmin,tmax\\n1,0,1,0,0,-1,0,0,inf\\n' |\n"
    "      rtsim hits scenes/small/room.yaml\n"
    "\n"
    "options:\n"
    "  --accel A           the structure traced: kd, bvh2 or bvh8 (default: the scene's\n"
    "                      accel key)\n"
    "  -h, --help          this text\n";

static const char HEADER[] = "id,ox,oy,oz,dx,dy,dz,tmin,tmax";

/* Bytes a row may have, its line break not counted: far above any row of
 * nine numbers, low enough that a stream without line breaks is refused
 * before it takes the host's memory. */
#define HITS_ROW_MAX (1u << 20)

/* Read the next row of f, whole, into *buf (grown as needed; its line break
 * not kept): 1, 0 at the end of the input, -1 with e set on a NUL byte, a
 * row longer than HITS_ROW_MAX or a read error. lineno is the row's line. */
static int read_row(FILE *f, char **buf, size_t *cap, size_t *len, unsigned long lineno,
                    struct err *e) {
  size_t n = 0;
  int c;
  while ((c = getc(f)) != EOF && c != '\n') {
    if (c == '\0')
      return err_set(e, "<stdin>", (int)lineno, (int)n + 1,
                     "a NUL byte (expected text: a CSV holds none)"),
             -1;
    if (n == HITS_ROW_MAX)
      return err_set(e, "<stdin>", (int)lineno, (int)n + 1,
                     "row too long (got more than %u bytes, expected at most %u)", HITS_ROW_MAX,
                     HITS_ROW_MAX),
             -1;
    if (n + 1 >= *cap) {
      *cap = *cap ? 2 * *cap : 256;
      *buf = xrealloc(*buf, *cap);
    }
    (*buf)[n++] = (char)c;
  }
  if (c == EOF && ferror(f))
    return err_set(e, "<stdin>", (int)lineno, 0, "cannot read: %s", strerror(errno)), -1;
  if (c == EOF && n == 0) return 0;
  if (n + 1 > *cap) {
    *cap = 256;
    *buf = xrealloc(*buf, *cap);
  }
  (*buf)[n] = '\0';
  *len = n;
  return 1;
}

/* Parse one data line (its fields cut apart in place); on error fill e at
 * (line, column). Numbers are strict (sim/scalar.h); tmax may be inf. */
static bool parse_line(char *line, unsigned long lineno, unsigned long long *id, float v[8],
                       struct err *e) {
  static const char *const names[9] = {"id", "ox", "oy", "oz", "dx", "dy", "dz", "tmin", "tmax"};
  char *p = line;
  for (int f = 0; f < 9; f++) {
    int col = (int)(p - line) + 1;
    char *end = p + strcspn(p, ",");
    if (f < 8 && *end != ',')
      return err_set(e, "<stdin>", (int)lineno, (int)(end - line) + 1,
                     "expected ',' (a row has 9 fields: %s)", HEADER);
    if (f == 8 && *end)
      return err_set(e, "<stdin>", (int)lineno, (int)(end - line) + 1,
                     "unexpected text after tmax (expected 9 fields)");
    *end = '\0';
    enum scalar_why w;
    if (f == 0) {
      uint64_t u = 0;
      w = scalar_u64(p, &u);
      *id = u;
      if (w != SCALAR_OK)
        return err_set(e, "<stdin>", (int)lineno, col,
                       "id: not a whole number%s%s (got '%.60s', expected 0 to 2^64-1)",
                       w == SCALAR_SYNTAX ? "" : ": ", scalar_why_text(w), p);
    } else if (f == 8 && !strcmp(p, "inf")) {
      v[7] = INFINITY;
    } else if ((w = scalar_f32(p, &v[f - 1])) != SCALAR_OK) {
      return err_set(e, "<stdin>", (int)lineno, col,
                     "field %d (%s): not a number%s%s (got '%.60s', expected a decimal number%s)",
                     f + 1, names[f], w == SCALAR_SYNTAX ? "" : ": ", scalar_why_text(w), p,
                     f == 8 ? " or inf" : "");
    }
    p = end + 1;
  }
  return true;
}

int app_hits_answer(struct trace_ctx *tr, FILE *in, FILE *out) {
  struct err e;
  memset(&e, 0, sizeof e);
  char *line = NULL;
  size_t cap = 0, len = 0;
  unsigned long lineno = 0;
  int rc = 0;
  for (;;) {
    int got = read_row(in, &line, &cap, &len, lineno + 1, &e);
    if (got < 0) rc = app_report(&e);
    if (got <= 0) break;
    lineno++;
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
    unsigned long long id = 0;
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
    if (trace_closest(tr, &r, &h)) fprintf(out, "%llu,%.9g,%d\n", id, (double)h.t, h.prim);
    else fprintf(out, "%llu,inf,-1\n", id);
  }
  free(line);
  if (rc == 0 && lineno == 0) {
    err_set(&e, "<stdin>", 0, 0, "no input (expected the header '%s')", HEADER);
    rc = app_report(&e);
  }
  return rc;
}

int cmd_hits(int argc, char **argv) {
  int accel = -1;
  const struct opts_spec spec[] = {APP_ACCEL_OPT(&accel), OPTS_END};
  struct opts_args args;
  int rc = opts_parse("hits", HELP, spec, argc, argv, &args);
  if (rc != OPTS_GO) return rc;
  const char *scene_path = opts_one_scene(&args);
  if (!scene_path) return APP_EXIT_USAGE;
  struct app_world w;
  if (!app_world_load_as(&w, scene_path, accel)) return 2;
  struct trace_ctx tr;
  struct trace_layout layout;
  trace_layout_default(&layout);
  trace_init(&tr, &w.scene, &w.kd, mem_port_native(), &layout);
  tr.bvh = app_world_bvh(&w);
  rc = app_hits_answer(&tr, stdin, stdout);
  app_world_fini(&w);
  return rc;
}
