#include "testing.h"

#include <dirent.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>

#include "renderer/image.h"
#include "renderer/kdtree.h"
#include "renderer/policy/policy.h"
#include "renderer/ray.h"
#include "renderer/scene.h"
#include "renderer/scene/scene_file.h"
#include "sim/dram.h"
#include "sim/dram_banked.h"
#include "sim/err.h"
#include "sim/stats.h"

int testing_failures = 0;
int testing_checks = 0;

int testing_done(const char *name) {
  printf("%s: %d checks, %d failed\n", name, testing_checks, testing_failures);
  return testing_failures ? 1 : 0;
}

int testing_runf(char *buf, unsigned buf_size, const char *fmt, ...) {
  char cmd[8192];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(cmd, sizeof cmd, fmt, ap);
  va_end(ap);
  return testing_run(cmd, buf, buf_size);
}

bool testing_writef(const char *path, const char *fmt, ...) {
  FILE *f = fopen(path, "w");
  EXPECTF(f != NULL, "cannot write %s", path);
  if (!f) return false;
  va_list ap;
  va_start(ap, fmt);
  vfprintf(f, fmt, ap);
  va_end(ap);
  bool ok = fclose(f) == 0;
  EXPECTF(ok, "cannot write %s", path);
  return ok;
}

double testing_stat(const struct stats_table *t, const char *name) {
  for (unsigned i = 0; i < t->n; i++)
    if (!strcmp(t->e[i].name, name))
      return t->e[i].kind == STATS_U64 ? (double)t->e[i].u : t->e[i].f;
  return NAN;
}

bool testing_write(const char *path, const char *text) { return testing_writef(path, "%s", text); }

int testing_run(const char *cmd, char *buf, unsigned buf_size) {
  char full[8192];
  snprintf(full, sizeof full, "%s 2>&1", cmd);
  FILE *p = popen(full, "r");
  if (!p) return -1;
  size_t n = fread(buf, 1, buf_size ? buf_size - 1 : 0, p);
  if (buf_size) buf[n] = '\0';
  char sink[4096];
  while (fread(sink, 1, sizeof sink, p) > 0) {
  }
  int st = pclose(p);
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

unsigned testing_temps_of(const char *path) {
  const char *slash = strrchr(path, '/');
  char dir[4096], prefix[1024];
  snprintf(dir, sizeof dir, "%.*s", slash ? (int)(slash - path) : 1, slash ? path : ".");
  snprintf(prefix, sizeof prefix, ".%s.", slash ? slash + 1 : path);
  DIR *d = opendir(dir);
  if (!d) return 0;
  unsigned n = 0;
  struct dirent *de;
  while ((de = readdir(d))) {
    size_t len = strlen(de->d_name);
    n += !strncmp(de->d_name, prefix, strlen(prefix)) && len > 4 &&
         !strcmp(de->d_name + len - 4, ".tmp");
  }
  closedir(d);
  return n;
}

int testing_load_world(struct scene *s, struct kd_tree *kd, const char *path) {
  struct err e;
  memset(&e, 0, sizeof e);
  if (!scene_file_load(s, path, &e)) {
    fprintf(stderr, "%s:%d:%d: %s\n", e.file, e.line, e.col, e.msg);
    return 0;
  }
  struct kd_build_params p;
  kd_build_params_default(&p);
  kd_build(kd, s, &p, NULL);
  return 1;
}

int testing_load_small(struct scene *s, struct kd_tree *kd, const char *name) {
  char path[1024];
  snprintf(path, sizeof path, "%s/scenes/small/%s.yaml", RTSIM_SOURCE_DIR, name);
  const int ok = testing_load_world(s, kd, path);
  EXPECTF(ok, "cannot load %s", path);
  return ok;
}

void testing_policy_setup(struct policy_setup *ps, const struct scene *s, const struct kd_tree *kd,
                          const struct shade_ctx *sc, struct framebuffer *fb) {
  memset(ps, 0, sizeof *ps);
  ps->scene = s;
  ps->kd = kd;
  trace_layout_default(&ps->layout);
  ps->sc = sc;
  ps->fb = fb;
}

struct ray testing_make_ray(float ox, float oy, float oz, float dx, float dy, float dz, float tmin,
                            float tmax) {
  struct ray r;
  memset(&r, 0, sizeof r);
  r.o = v3(ox, oy, oz);
  r.d = v3(dx, dy, dz);
  r.tmin = tmin;
  r.tmax = tmax;
  r.ignore_prim = -1;
  r.hit_prim = -1;
  return r;
}

void testing_slots_access(struct testing_slots *t, uint64_t k, bool store) {
  if (k >= t->n) {
    uint64_t n = 2 * k + 1024;
    t->pending = xrealloc(t->pending, n);
    memset(t->pending + t->n, 0, n - t->n);
    t->n = n;
  }
  t->bad += t->pending[k] != !store; /* overwritten before read, or read unstored */
  t->pending[k] = (uint8_t)store;
  if (store) t->stores++;
  else t->loads++;
}

uint64_t testing_slots_left(const struct testing_slots *t) {
  uint64_t n = 0;
  for (uint64_t k = 0; k < t->n; k++) n += t->pending[k];
  return n;
}

void testing_slots_fini(struct testing_slots *t) {
  free(t->pending);
  memset(t, 0, sizeof *t);
}

/* The whole of a file (caller frees), or NULL. */
char *testing_slurp(const char *dir, const char *name, size_t *len) {
  char p[2048];
  snprintf(p, sizeof p, "%s/%s", dir, name);
  FILE *f = fopen(p, "rb");
  if (!f) return NULL;
  size_t cap = 1 << 16, n = 0;
  char *b = malloc(cap + 1);
  for (size_t k; (k = fread(b + n, 1, cap - n, f)) > 0;)
    if ((n += k) == cap) b = realloc(b, (cap *= 2) + 1);
  fclose(f);
  b[n] = '\0';
  if (len) *len = n;
  return b;
}

/* A number member of stats.json ("cycles"); NAN when absent. */
double testing_json_num(const char *dir, const char *name) {
  char *j = testing_slurp(dir, "stats.json", NULL);
  if (!j) return NAN;
  char pat[128];
  snprintf(pat, sizeof pat, "\n  \"%s\": ", name);
  const char *at = strstr(j, pat);
  double v = at ? strtod(at + strlen(pat), NULL) : NAN;
  free(j);
  return v;
}

/* RGB planes of two EXR files are equal, bit for bit. */
bool testing_same_rgb(const char *a, const char *b) {
  struct image x, y;
  struct err e;
  memset(&e, 0, sizeof e);
  if (!image_read_exr(&x, a, &e)) return false;
  if (!image_read_exr(&y, b, &e)) {
    image_fini(&x);
    return false;
  }
  bool same = x.width == y.width && x.height == y.height;
  const char *ch[] = {"R", "G", "B"};
  for (int i = 0; i < 3 && same; i++) {
    int cx = image_channel(&x, ch[i]), cy = image_channel(&y, ch[i]);
    same = cx >= 0 && cy >= 0 &&
           !memcmp(x.planes[cx], y.planes[cy], (size_t)x.width * x.height * sizeof(float));
  }
  image_fini(&x);
  image_fini(&y);
  return same;
}

struct dram_params testing_dram_params(unsigned model, uint32_t depth) {
  struct dram_params p;
  memset(&p, 0, sizeof p);
  p.model = (enum dram_model)model;
  p.latency_cycles = 40;
  p.bytes_per_cycle = 8.0;
  p.queue_depth = depth;
  p.clock_mhz = 1200;
  p.banked = testing_ddr4_params();
  return p;
}

struct dram_banked_params testing_ddr4_params(void) {
  struct dram_banked_params p;
  memset(&p, 0, sizeof p);
  p.clock_mhz = 1200;
  p.channels = 1;
  p.ranks = 1;
  p.bank_groups = 4;
  p.banks_per_group = 4;
  p.rows = 65536;
  p.columns = 1024;
  p.bus_bytes = 8;
  p.burst_length = 8;
  strcpy(p.mapping, "rochrababgco");
  p.page = DRAM_BANKED_OPEN_PAGE;
  p.read_queue = 32;
  p.write_queue = 32;
  p.write_high = 24;
  p.write_low = 8;
  p.idle_drain_cycles = 1000; /* the presets' */
  p.tCL = 16, p.tCWL = 16, p.tRCD = 16, p.tRP = 16, p.tRAS = 39, p.tRC = 55;
  p.tCCD_S = 4, p.tCCD_L = 6, p.tRRD_S = 4, p.tRRD_L = 6, p.tFAW = 26;
  p.tWR = 19, p.tWTR_S = 3, p.tWTR_L = 9, p.tRTW = 6, p.tRTP = 9;
  p.tREFI = 0, p.tRFC = 420;
  p.device_width = 8; /* DRAMsim3's DDR4_8Gb_x8_2400.ini */
  p.VDD = 1.2, p.IDD0 = 48, p.IDD2N = 34, p.IDD3N = 43, p.IDD4R = 135, p.IDD4W = 123;
  p.IDD5AB = 250;
  return p;
}

/* ---- two-line CSV files (a header and one row: stats.csv, dram-replay) ---- */

/* Split one line into at most TESTING_CSV_COLS fields (RFC 4180 quotes undone). */
static int csv_split(const char *line, char (*out)[128], size_t cap_each, int max) {
  int n = 0;
  const char *p = line;
  while (n < max) {
    size_t k = 0;
    bool quoted = *p == '"';
    if (quoted) p++;
    while (*p && (quoted ? !(p[0] == '"' && p[1] != '"') : (*p != ',' && *p != '\n'))) {
      if (quoted && p[0] == '"') p++; /* a doubled quote */
      if (k + 1 < cap_each) out[n][k++] = *p;
      p++;
    }
    if (quoted && *p == '"') p++;
    out[n][k] = '\0';
    n++;
    if (*p != ',') break;
    p++;
  }
  return n;
}

bool testing_csv_load(const char *path, struct testing_csv *c) {
  static char vals[TESTING_CSV_COLS][128];
  char line[65536];
  memset(c, 0, sizeof *c);
  FILE *f = fopen(path, "r");
  if (!f) return false;
  bool ok = fgets(line, sizeof line, f) != NULL;
  if (ok) {
    int n = csv_split(line, vals, sizeof vals[0], TESTING_CSV_COLS);
    for (int i = 0; i < n; i++) memcpy(c->name[i], vals[i], sizeof vals[i]);
    c->n = n;
    ok = fgets(line, sizeof line, f) != NULL;
  }
  if (ok) ok = csv_split(line, c->value, sizeof c->value[0], TESTING_CSV_COLS) == c->n;
  fclose(f);
  return ok;
}

const char *testing_csv_get(const struct testing_csv *c, const char *name) {
  for (int i = 0; i < c->n; i++)
    if (!strcmp(c->name[i], name)) return c->value[i];
  EXPECTF(false, "no column %s", name);
  return "";
}

double testing_csv_num(const struct testing_csv *c, const char *name) {
  return strtod(testing_csv_get(c, name), NULL);
}
