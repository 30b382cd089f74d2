/* The renderer on the timed machine: the 1 x 1 x 1, no-L1, fully associative
 * machine fetches and writes back exactly what the functional model counts, at
 * any DRAM latency and bandwidth; many workers give the same image as one; and
 * rtsim run's outputs (image, determinism, bad input) through the command. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <sys/stat.h>
#include <unistd.h>

#include "renderer/framebuffer.h"
#include "renderer/image.h"
#include "renderer/kdtree.h"
#include "renderer/policy.h"
#include "renderer/scene.h"
#include "renderer/shade.h"
#include "renderer/trace.h"
#include "sim/lru_stack.h"
#include "sim/machine.h"
#include "sim/coro.h"
#include "sim/err.h"
#include "sim/machine_cfg.h"
#include "sim/mem_functional.h"
#include "testing.h"

#define W 32
#define H 24

struct world {
  struct scene s;
  struct kd_tree kd;
};

struct render {
  struct shade_ctx sc;
  struct framebuffer fb;
  struct policy_setup setup;
};

static void render_init(struct render *r, struct world *w, uint32_t mask) {
  memset(r, 0, sizeof *r);
  r->sc.scene = &w->s;
  r->sc.ray_mask = mask;
  r->sc.seed = w->s.seed;
  r->setup.scene = &w->s;
  r->setup.kd = &w->kd;
  trace_layout_default(&r->setup.layout);
  r->setup.sc = &r->sc;
  fb_init(&r->fb, W, H, r->setup.layout.fb_base);
  r->setup.fb = &r->fb;
}

/* Functional fetch and write-back bytes of a fully associative LRU cache of
 * 2^lg2 bytes. */
static void functional(struct world *w, enum policy_kind k, uint32_t mask, unsigned lg2,
                       uint64_t *fetch, uint64_t *wb) {
  struct lru_stack_params lp = lru_stack_params_default();
  struct fn_backend *b = fn_backend_create(&lp, NULL);
  struct render r;
  render_init(&r, w, mask);
  struct policy_params pp;
  policy_params_default(&pp);
  struct render_stats st;
  policy_run(k, &r.setup, &pp, fn_backend_port(b), &st, NULL);
  struct lru_stack_results res;
  lru_stack_get_results(fn_backend_stack(b), &res);
  *fetch = *wb = 0;
  for (unsigned c = 0; c < MEM_CLASS_MAX; c++) {
    *fetch += res.size[lg2 - lp.lg2_min].misses[c] * 64;
    *wb += res.size[lg2 - lp.lg2_min].writebacks[c] * 64;
  }
  fb_fini(&r.fb);
  fn_backend_destroy(b);
}

/* The deepest coroutine stack any run of this test used (painted stacks). */
static uint64_t stack_used_max;

struct timed_ctx {
  struct policy_job *job;
  struct policy_worker *workers;
};

static void timed_worker(void *arg, const struct machine_worker_info *info, struct mem_port port) {
  struct timed_ctx *t = arg;
  struct policy_worker *w = &t->workers[info->id];
  policy_worker_init(w, t->job, info->id, info->core, info->thread, port);
  policy_job_work(t->job, w);
  policy_worker_fini(t->job, w);
}

/* Run on machine p; the machine's stats are copied out, the framebuffer kept
 * in r (caller finishes it). */
static void timed(struct world *w, enum policy_kind k, uint32_t mask, const struct machine_params *p,
                  struct machine_stats *out, struct render *r) {
  render_init(r, w, mask);
  r->setup.layout.node_cycles = p->cost_node_cycles;
  r->setup.layout.tri_cycles = p->cost_triangle_cycles;
  r->sc.shade_cycles = p->cost_shade_cycles;
  struct policy_params pp;
  policy_params_default(&pp);
  uint32_t n = p->cores * p->threads_per_core * p->rays_per_thread;
  struct timed_ctx t = {policy_job_create(k, &r->setup, &pp, n, p->cores), NULL};
  t.workers = calloc(n, sizeof *t.workers);
  struct machine *m = machine_create_painted(p, 0);
  machine_run(m, timed_worker, &t, NULL, NULL);
  if (machine_stack_used_max(m) > stack_used_max) stack_used_max = machine_stack_used_max(m);
  struct render_stats st;
  policy_job_finish(t.job, &st, NULL);
  *out = *machine_get_stats(m);
  machine_destroy(m);
  free(t.workers);
  policy_job_destroy(t.job);
}

static struct machine_params one_by_one(uint64_t l2_bytes) {
  struct machine_cfg c;
  machine_cfg_defaults(&c);
  struct machine_params p = c.p;
  p.cores = p.threads_per_core = p.rays_per_thread = 1;
  p.l1_size_bytes = 0;
  p.l2_size_bytes = l2_bytes;
  p.l2_ways = 0;
  return p;
}

static int same_image(const struct framebuffer *a, const struct framebuffer *b) {
  return memcmp(a->acc, b->acc, (size_t)W * H * 3 * sizeof *a->acc) == 0;
}

static void test_cross_check(struct world *w) {
  const uint32_t mask = RAY_MASK(RAY_PRIMARY) | RAY_MASK(RAY_SHADOW) | RAY_MASK(RAY_DIFFUSE);
  const enum policy_kind kinds[] = {POLICY_RECURSIVE, POLICY_PACKET};
  const unsigned sizes[] = {12, 16};
  const struct {
    uint64_t latency;
    double bw;
    uint32_t mshrs, queue;
  } drams[] = {{0, 1e4, 64, 32}, {200, 16, 64, 32}, {1000, 0.5, 2, 1}};
  for (unsigned k = 0; k < 2; k++)
    for (unsigned s = 0; s < 2; s++) {
      uint64_t fetch, wb;
      functional(w, kinds[k], mask, sizes[s], &fetch, &wb);
      EXPECT(fetch > 0);
      for (unsigned d = 0; d < 3; d++) {
        struct machine_params p = one_by_one(1ull << sizes[s]);
        p.dram_latency_cycles = drams[d].latency;
        p.dram_bytes_per_cycle = drams[d].bw;
        p.l2_mshrs = drams[d].mshrs;
        p.dram_queue_depth = drams[d].queue;
        struct machine_stats st;
        struct render r;
        timed(w, kinds[k], mask, &p, &st, &r);
        EXPECTF(st.l2_fetch_bytes == fetch && st.l2_writeback_bytes == wb,
                "%s at 2^%u, DRAM %llu cycles %.1f B/c: timed %llu/%llu, functional %llu/%llu",
                policy_name(kinds[k]), sizes[s], (unsigned long long)drams[d].latency, drams[d].bw,
                (unsigned long long)st.l2_fetch_bytes, (unsigned long long)st.l2_writeback_bytes,
                (unsigned long long)fetch, (unsigned long long)wb);
        fb_fini(&r.fb);
      }
    }
}

/* Many ray contexts interleaved on the tiny machine: the same picture, every
 * ray accounted for, and the machine busy. */
static void test_many_workers(struct world *w) {
  const uint32_t mask = RAY_MASK(RAY_PRIMARY) | RAY_MASK(RAY_SHADOW) | RAY_MASK(RAY_SPECULAR) |
                        RAY_MASK(RAY_DIFFUSE);
  struct machine_cfg c;
  machine_cfg_defaults(&c);
  struct err e;
  memset(&e, 0, sizeof e);
  CHECK(machine_cfg_load(&c, RTSIM_SOURCE_DIR "/configs/tiny.yaml", &e));
  struct render ref;
  struct machine_stats st;
  struct machine_params one = one_by_one(1 << 20);
  timed(w, POLICY_RECURSIVE, mask, &one, &st, &ref);
  for (int k = 0; k < 2; k++) {
    struct render r;
    timed(w, k ? POLICY_PACKET : POLICY_RECURSIVE, mask, &c.p, &st, &r);
    EXPECTF(same_image(&ref.fb, &r.fb), "%s on tiny.yaml: image differs", k ? "packet" : "recursive");
    EXPECT(st.l2_mshr_merges > 0 && st.l2_misses > 0 && st.issue_slots > 0);
    fb_fini(&r.fb);
  }
  fb_fini(&ref.fb);
}

/* RGB planes of two EXR files are equal, bit for bit. */
static int same_rgb(const char *a, const char *b) {
  struct image x, y;
  struct err e;
  memset(&e, 0, sizeof e);
  if (!image_read_exr(&x, a, &e)) return 0;
  if (!image_read_exr(&y, b, &e)) {
    image_fini(&x);
    return 0;
  }
  int same = x.width == y.width && x.height == y.height;
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

static int same_file(const char *a, const char *b, int skip_wall) {
  FILE *fa = fopen(a, "rb"), *fb = fopen(b, "rb");
  int same = fa && fb;
  char la[4096], lb[4096];
  while (same) {
    char *ra = fgets(la, sizeof la, fa), *rb = fgets(lb, sizeof lb, fb);
    if (!ra || !rb) {
      same = !ra && !rb;
      break;
    }
    if (skip_wall && ((strstr(la, "\"wall_s\"") && strstr(lb, "\"wall_s\"")) ||
                      (strstr(la, "\"peak_rss_mb\"") && strstr(lb, "\"peak_rss_mb\""))))
      continue;
    same = !strcmp(la, lb);
  }
  if (fa) fclose(fa);
  if (fb) fclose(fb);
  return same;
}

static int exists(const char *dir, const char *name) {
  char p[2048];
  snprintf(p, sizeof p, "%s/%s", dir, name);
  struct stat sb;
  return stat(p, &sb) == 0;
}

/* rtsim run through the command line: the image of rtsim render, the same
 * bytes twice, every output present; bad input refused with exit 2. */
static void test_command(void) {
  char cmd[4096], out[8192];
  const char *scene = RTSIM_SOURCE_DIR "/scenes/small/grove.yaml";
  const char *tiny = RTSIM_SOURCE_DIR "/configs/tiny.yaml";
  const char *ref = RTSIM_TMP "/run_ref.exr";
  snprintf(cmd, sizeof cmd, "%s render %s --width 24 --height 16 -o %s", RTSIM_BINARY, scene, ref);
  EXPECT(testing_run(cmd, out, sizeof out) == 0);
  const char *dirs[] = {RTSIM_TMP "/run_a", RTSIM_TMP "/run_b", RTSIM_TMP "/run_p"};
  for (int i = 0; i < 3; i++) {
    snprintf(cmd, sizeof cmd, "%s run %s %s --width 24 --height 16 %s -o %s", RTSIM_BINARY, tiny,
             scene, i == 2 ? "--policy packet --set cores=3 --set l2.size=8KiB" : "", dirs[i]);
    int rc = testing_run(cmd, out, sizeof out);
    EXPECTF(rc == 0, "%s: exit %d: %s", cmd, rc, out);
    const char *files[] = {"image.exr", "stats.json", "stats.csv", "timeline.csv", "traffic.png"};
    for (int f = 0; f < 5; f++) EXPECTF(exists(dirs[i], files[f]), "%s/%s missing", dirs[i], files[f]);
    char img[2048];
    snprintf(img, sizeof img, "%s/image.exr", dirs[i]);
    EXPECTF(same_rgb(ref, img), "%s: RGB differs from rtsim render's", dirs[i]);
  }
  const char *names[] = {"stats.csv", "timeline.csv", "image.exr", "stats.json"};
  for (int f = 0; f < 4; f++) {
    char a[2048], b[2048];
    snprintf(a, sizeof a, "%s/%s", dirs[0], names[f]);
    snprintf(b, sizeof b, "%s/%s", dirs[1], names[f]);
    EXPECTF(same_file(a, b, f == 3), "%s differs between two runs", names[f]);
  }
  /* stats.csv's columns are unique names (a merged table joins them by name). */
  char csvp[2048], hdr[8192];
  snprintf(csvp, sizeof csvp, "%s/stats.csv", dirs[0]);
  FILE *hf = fopen(csvp, "r");
  EXPECT(hf && fgets(hdr, sizeof hdr, hf));
  if (hf) fclose(hf);
  hdr[strcspn(hdr, "\n")] = '\0';
  char *names_at[256];
  unsigned ncols = 0;
  for (char *tok = strtok(hdr, ","); tok && ncols < 256; tok = strtok(NULL, ",")) {
    for (unsigned j = 0; j < ncols; j++)
      EXPECTF(strcmp(names_at[j], tok) != 0, "stats.csv has column '%s' twice", tok);
    names_at[ncols++] = tok;
  }
  EXPECT(ncols > 30);
  /* The override is in the resolved config. */
  char js[2048];
  snprintf(js, sizeof js, "%s/stats.json", dirs[2]);
  FILE *f = fopen(js, "r");
  static char json[1 << 16];
  size_t n = f ? fread(json, 1, sizeof json - 1, f) : 0;
  json[n] = '\0';
  if (f) fclose(f);
  EXPECT(strstr(json, "\"cores\": 3,") && strstr(json, "\"l2.size\": 8192,") &&
         strstr(json, "\"policy\": \"packet\""));
  /* Traceable: the scene's hash (16 hex digits) and the build's revision. */
  const char *hash = strstr(json, "\"scene_hash\": \"");
  EXPECT(hash && strspn(hash + 15, "0123456789abcdef") == 16 && hash[31] == '"');
  const char *rev = strstr(json, "\"revision\": \"");
  EXPECT(rev && rev[13] != '"');

  static const struct {
    const char *args, *want;
  } bad[] = {
      {"run CFG SCN -o DIR --set cores=0", "--set cores=0: error: cores: out of range (got 0"},
      {"run CFG SCN -o DIR --set l2.size=32", "l2.size: smaller than one 64-byte line"},
      {"run CFG SCN -o DIR --set dram.bytes_per_cycle=0", "dram.bytes_per_cycle: out of range"},
      {"run CFG SCN -o DIR --set l3.size=1", "unknown key 'l3.size'"},
      {"run " RTSIM_TEST_DATA "/configs/bad_size_unit.yaml SCN -o DIR", "bad_size_unit.yaml:2:9: error: l2.size"},
      {"run CFG SCN -o DIR --policy dynamic", "does not run on the machine yet"},
      {"run CFG SCN -o DIR --policy fastest", "--policy: got 'fastest'"},
      {"run CFG -o DIR", "expected MACHINE.yaml SCENE.yaml, got 1 file"},
      {"run CFG SCN", "missing -o OUTDIR"},
      {"run CFG SCN -o DIR --width 0", "--width: got '0'"},
      {"run CFG " RTSIM_TEST_DATA "/scenes/bad_color.yaml -o DIR", "bad_color.yaml:"},
  };
  const char *bad_dir = RTSIM_TMP "/run_bad";
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    char args[2048] = "", *o = args;
    for (const char *p = bad[i].args; *p;) {
      if (!strncmp(p, "CFG", 3)) o += sprintf(o, "%s", tiny), p += 3;
      else if (!strncmp(p, "SCN", 3)) o += sprintf(o, "%s", scene), p += 3;
      else if (!strncmp(p, "DIR", 3)) o += sprintf(o, "%s", bad_dir), p += 3;
      else *o++ = *p++;
    }
    *o = '\0';
    snprintf(cmd, sizeof cmd, "%s %s --width 8 --height 8", RTSIM_BINARY, args);
    if (strstr(bad[i].args, "--width")) snprintf(cmd, sizeof cmd, "%s %s", RTSIM_BINARY, args);
    int rc = testing_run(cmd, out, sizeof out);
    EXPECTF(rc == 2 && strstr(out, bad[i].want), "%s: exit %d, '%s'", bad[i].args, rc, out);
    EXPECTF(!exists(bad_dir, "stats.json"), "%s left a stats.json", bad[i].args);
  }
}

/* Whole runs at the machine's extremes: every output written, no nan or inf. */
static void test_command_extremes(void) {
  static const char *const sets[] = {
      "--set cores=1 --set threads_per_core=1 --set rays_per_thread=1",
      "--set cores=256 --set threads_per_core=8 --set rays_per_thread=8",
      "--set dram.latency=0 --set dram.bytes_per_cycle=10000",
      "--set dram.latency=1000000 --set timeline.window=1",
      "--set dram.bytes_per_cycle=0.01 --set l2.size=64 --set l2.ways=full --set l2.mshrs=1",
  };
  char cmd[4096], out[8192];
  const char *dir = RTSIM_TMP "/run_extreme";
  for (unsigned i = 0; i < sizeof sets / sizeof sets[0]; i++) {
    snprintf(cmd, sizeof cmd, "%s run %s/configs/tiny.yaml %s/scenes/small/room.yaml --width 6 --height 4 %s -o %s",
             RTSIM_BINARY, RTSIM_SOURCE_DIR, RTSIM_SOURCE_DIR, sets[i], dir);
    int rc = testing_run(cmd, out, sizeof out);
    EXPECTF(rc == 0, "%s: exit %d: %s", sets[i], rc, out);
    const char *files[] = {"stats.json", "stats.csv", "timeline.csv"};
    for (int f = 0; f < 3; f++) {
      char p[2048];
      snprintf(p, sizeof p, "cat %s/%s", dir, files[f]);
      static char text[1 << 20];
      testing_run(p, text, sizeof text);
      EXPECTF(!strstr(text, "nan") && !strstr(text, "inf") && strlen(text) > 10, "%s: %s: nan or inf",
              sets[i], files[f]);
    }
  }
}

int main(void) {
  struct world w;
  if (!testing_load_world(&w.s, &w.kd, RTSIM_SOURCE_DIR "/scenes/small/room.yaml")) return 1;
  test_cross_check(&w);
  test_many_workers(&w);
  test_command();
  test_command_extremes();
  /* The kernels' deepest stack, against the size the machine gives them: the
   * margin coro.c states (at least 4x) must hold. */
  printf("deepest coroutine stack: %llu bytes of %zu\n", (unsigned long long)stack_used_max,
         coro_default_stack_bytes());
  EXPECT(stack_used_max > 0 && 4 * stack_used_max <= coro_default_stack_bytes());
  kd_fini(&w.kd);
  scene_fini(&w.s);
  return testing_done("test_run");
}
