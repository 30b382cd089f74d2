/* rtsim bench --policies: whole `rtsim run` processes timed against each
 * other (bench_policies.h). */
#define _GNU_SOURCE /* wait4 */
#include "app/bench_policies.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include "app/app.h"
#include "app/csv.h"
#include "renderer/shade.h"
#include "sim/err.h"
#include "sim/machine_cfg.h"
#include "sim/stats.h"

bool bench_parse_policies(const char *text, void *dst) {
  struct bench_policy_list *l = dst;
  char name[32];
  l->n = 0;
  for (const char *p = text;;) {
    size_t len = strcspn(p, ",");
    if (len == 0 || len >= sizeof name || l->n == BENCH_POLICIES_MAX) return false;
    memcpy(name, p, len);
    name[len] = '\0';
    enum policy_kind k;
    if (!policy_parse(name, &k)) return false;
    for (unsigned i = 0; i < l->n; i++)
      if (l->k[i] == k) return false;
    l->k[l->n++] = k;
    if (p[len] == '\0') break;
    p += len + 1;
  }
  return l->n >= 2;
}

bool bench_parse_levels(const char *text, void *dst) {
  static const char *const known[] = {"native", "analytic", "fixed", "channel", "banked"};
  struct bench_level_list *l = dst;
  l->n = 0;
  for (const char *p = text;;) {
    size_t len = strcspn(p, ",");
    if (len == 0 || len >= sizeof l->name[0] || l->n == BENCH_POLICIES_MAX) return false;
    bool ok = false;
    for (unsigned i = 0; i < sizeof known / sizeof known[0]; i++)
      ok |= strlen(known[i]) == len && !strncmp(known[i], p, len);
    if (!ok) return false;
    for (unsigned i = 0; i < l->n; i++)
      if (strlen(l->name[i]) == len && !strncmp(l->name[i], p, len)) return false;
    memcpy(l->name[l->n], p, len);
    l->name[l->n++][len] = '\0';
    if (p[len] == '\0') break;
    p += len + 1;
  }
  return l->n >= 2;
}

/* One run's figures. */
struct bench_run {
  double host_s, run_s, peak_mb;
  uint64_t events;
  char scene[128];
  uint64_t width, height;
};

/* The temporary folder: the run's output folder and its stderr inside. */
struct bench_tmp {
  char dir[4096], out[4200], err[4200];
};

/* Remove the files of out (rtsim run writes plain files only) and out itself. */
static void clear_out(const struct bench_tmp *t) {
  DIR *d = opendir(t->out);
  if (!d) return;
  struct dirent *de;
  char path[8400];
  while ((de = readdir(d))) {
    if (!strcmp(de->d_name, ".") || !strcmp(de->d_name, "..")) continue;
    snprintf(path, sizeof path, "%s/%s", t->out, de->d_name);
    unlink(path);
  }
  closedir(d);
  rmdir(t->out);
}

static void tmp_fini(const struct bench_tmp *t) {
  clear_out(t);
  unlink(t->err);
  rmdir(t->dir);
}

/* Print the failed run's stderr (kept in t->err) under a line saying which. */
static void show_failure(const struct bench_tmp *t, const char *scene, const char *what,
                         int status) {
  fprintf(stderr, "rtsim bench: the run of %s (%s) ", scene, what);
  if (WIFEXITED(status)) fprintf(stderr, "exited with code %d:\n", WEXITSTATUS(status));
  else
    fprintf(stderr, "was killed by signal %d (%s):\n", WTERMSIG(status),
            strsignal(WTERMSIG(status)));
  FILE *f = fopen(t->err, "r");
  if (!f) return;
  char buf[4096];
  size_t n;
  while ((n = fread(buf, 1, sizeof buf, f)) > 0) fwrite(buf, 1, n, stderr);
  fclose(f);
}

/* stats.json of the run just made, whole (NULL if it cannot be read). */
static char *read_stats(const struct bench_tmp *t) {
  char path[8400];
  snprintf(path, sizeof path, "%s/stats.json", t->out);
  size_t len;
  const char *why;
  return csv_slurp(path, &len, &why);
}

static bool member_f64(const char *json, const char *key, double *v) {
  char text[64];
  return csv_json_member(json, key, text, sizeof text) && csv_number(text, v);
}

/* Run `bin args` with stdout to /dev/null and stderr to t->err; its exit
 * status and user + system seconds. False if it could not be started. */
static bool run_child(const char *bin, char **args, const struct bench_tmp *t, int *status,
                      double *host_s, double *peak_mb) {
  fflush(stdout);
  fflush(stderr);
  pid_t pid = fork();
  if (pid < 0) return false;
  if (pid == 0) {
    int fd = open(t->err, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    int null = open("/dev/null", O_WRONLY);
    if (fd >= 0) dup2(fd, 2);
    if (null >= 0) dup2(null, 1);
    execv(bin, args);
    fprintf(stderr, "rtsim bench: cannot run %s: %s\n", bin, strerror(errno));
    _exit(127);
  }
  struct rusage ru;
  while (wait4(pid, status, 0, &ru) < 0)
    if (errno != EINTR) return false;
  *host_s = (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec +
            (double)ru.ru_stime.tv_sec + 1e-6 * (double)ru.ru_stime.tv_usec;
  *peak_mb = (double)ru.ru_maxrss / 1024.0; /* (kilobytes on Linux) */
  return true;
}

static int cmp_f64(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* The median of v[0..n) (v is sorted in place). */
static double median(double *v, uint64_t n) {
  qsort(v, n, sizeof *v, cmp_f64);
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/* The rows of one scene: r[round * n + j] is policy j's run in that round. */
static void print_rows(const char *machine, const char *set_text, const char *rays,
                       const char *const *label, unsigned n, const struct bench_run *r,
                       uint64_t rounds) {
  const unsigned base = n - 1;
  double *a = xmalloc(rounds * sizeof *a), *b = xmalloc(rounds * sizeof *b);
  for (unsigned j = 0; j < n; j++) {
    const struct bench_run *first = &r[j];
    double host_best = first->host_s, run_best = first->run_s;
    for (uint64_t k = 0; k < rounds; k++) {
      const struct bench_run *x = &r[k * n + j];
      if (x->host_s < host_best) host_best = x->host_s;
      if (x->run_s < run_best) run_best = x->run_s;
      a[k] = x->host_s;
      b[k] = x->run_s;
    }
    const double host_med = median(a, rounds), run_med = median(b, rounds);
    double host_ratio_max = 0;
    for (uint64_t k = 0; k < rounds; k++) {
      const struct bench_run *x = &r[k * n + j], *y = &r[k * n + base];
      a[k] = y->host_s > 0 ? x->host_s / y->host_s : 0;
      b[k] = y->run_s > 0 ? x->run_s / y->run_s : 0;
      if (a[k] > host_ratio_max) host_ratio_max = a[k];
    }
    const double host_ratio = median(a, rounds), run_ratio = median(b, rounds);
    const struct bench_run *y = &r[base];
    stats_write_csv_str(stdout, first->scene);
    printf(",%llu,%llu,", (unsigned long long)first->width, (unsigned long long)first->height);
    stats_write_csv_str(stdout, rays);
    putchar(',');
    stats_write_csv_str(stdout, machine);
    putchar(',');
    stats_write_csv_str(stdout, set_text);
    printf(",%s,%llu,%.3f,%.3f,%.4f,%.4f,%llu,%.1f,%.3f,%.3f,%.3f,%.3f,%.3f,%s\n", label[j],
           (unsigned long long)rounds, host_best, host_med, run_best, run_med,
           (unsigned long long)first->events, first->peak_mb, host_ratio, host_ratio_max, run_ratio,
           y->events ? (double)first->events / (double)y->events : 0.0,
           y->peak_mb > 0 ? first->peak_mb / y->peak_mb : 0.0, label[base]);
  }
  fflush(stdout);
  free(a);
  free(b);
}

/* What every child run of one bench shares. */
struct bench_ctx {
  const char *machine, *bin, *rays, *wtext, *htext, *image;
  const struct app_sets *sets;
  const struct bench_policy_list *l; /* NULL: levels */
  const struct bench_level_list *lv;
  enum policy_kind policy;
  uint64_t width, height;
  struct bench_tmp t;
};

/* This program's path (for its children) and a fresh temporary folder; 0 or
 * an exit code after saying why. */
static int bench_setup(char *bin, size_t cap, struct bench_tmp *t) {
  ssize_t bl = readlink("/proc/self/exe", bin, cap - 1);
  if (bl <= 0) {
    fprintf(stderr, "rtsim bench: error: cannot find this program's path (/proc/self/exe)\n");
    return 1;
  }
  bin[bl] = '\0';
  const char *tmpdir = getenv("TMPDIR");
  snprintf(t->dir, sizeof t->dir, "%s/rtsim-bench-XXXXXX", tmpdir && *tmpdir ? tmpdir : "/tmp");
  if (!mkdtemp(t->dir)) {
    fprintf(stderr, "rtsim bench: error: cannot make a temporary folder %s: %s\n", t->dir,
            strerror(errno));
    return 1;
  }
  snprintf(t->out, sizeof t->out, "%s/run", t->dir);
  snprintf(t->err, sizeof t->err, "%s/stderr.txt", t->dir);
  return 0;
}

/* The command line of variant j on scene: bin run MACHINE SCENE --policy P
 * [--set fidelity=L] --rays R [--width W --height H] [--set KV]... -o OUT, or
 * bin render SCENE --rays R [...] -o IMAGE for the native level; NULL-ended. */
static void child_args(const struct bench_ctx *b, unsigned j, const char *fid, const char *scene,
                       const char **args) {
  const bool native = !b->l && !strcmp(b->lv->name[j], "native");
  unsigned a = 0;
  args[a++] = b->bin;
  args[a++] = native ? "render" : "run";
  if (!native) args[a++] = b->machine;
  args[a++] = scene;
  if (!native) {
    args[a++] = "--policy";
    args[a++] = b->l ? policy_name(b->l->k[j]) : policy_name(b->policy);
  }
  if (!b->l && !native) {
    args[a++] = "--set";
    args[a++] = fid;
  }
  args[a++] = "--rays";
  args[a++] = b->rays;
  if (b->width) {
    args[a++] = "--width";
    args[a++] = b->wtext;
  }
  if (b->height) {
    args[a++] = "--height";
    args[a++] = b->htext;
  }
  for (unsigned s = 0; s < b->sets->n && !native; s++) {
    args[a++] = "--set";
    args[a++] = b->sets->v[s];
  }
  args[a++] = "-o";
  args[a++] = native ? b->image : b->t.out;
  args[a] = NULL;
}

/* Run variant j (labelled label) on scene into x: its host time, and for a
 * timed run the figures of its stats.json; 0 or an exit code after saying
 * why. */
static int one_run(struct bench_ctx *b, unsigned j, const char *fid, const char *label,
                   const char *scene, const char **args, struct bench_run *x) {
  const bool native = !b->l && !strcmp(b->lv->name[j], "native");
  child_args(b, j, fid, scene, args);
  if (native && mkdir(b->t.out, 0755) != 0 && errno != EEXIST) {
    fprintf(stderr, "rtsim bench: error: cannot make %s: %s\n", b->t.out, strerror(errno));
    return 1;
  }
  int status = 0;
  double peak_mb = 0;
  if (!run_child(b->bin, (char **)args, &b->t, &status, &x->host_s, &peak_mb)) {
    fprintf(stderr, "rtsim bench: error: cannot run %s: %s\n", b->bin, strerror(errno));
    return 1;
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    show_failure(&b->t, scene, label, status);
    return WIFEXITED(status) ? WEXITSTATUS(status) : 1;
  }
  if (native) {
    /* The render's own figures: its host time, no events. */
    x->run_s = x->host_s;
    x->peak_mb = peak_mb;
    snprintf(x->scene, sizeof x->scene, "%s", "");
    x->width = b->width;
    x->height = b->height;
    clear_out(&b->t);
    return 0;
  }
  char *json = read_stats(&b->t);
  double ev = 0, w = 0, h = 0;
  if (!json || !member_f64(json, "wall_s", &x->run_s) || !member_f64(json, "events", &ev) ||
      !member_f64(json, "peak_rss_mb", &x->peak_mb) || !member_f64(json, "width", &w) ||
      !member_f64(json, "height", &h) ||
      !csv_json_member(json, "scene", x->scene, sizeof x->scene)) {
    fprintf(stderr, "rtsim bench: error: rtsim run of %s wrote no readable %s/stats.json\n", scene,
            b->t.out);
    free(json);
    return 1;
  }
  free(json);
  x->events = (uint64_t)ev;
  x->width = (uint64_t)w;
  x->height = (uint64_t)h;
  clear_out(&b->t);
  return 0;
}

/* A native row takes the scene and image size of the timed rows. */
static void native_rows_fill(struct bench_run *r, uint64_t count) {
  for (uint64_t k = 0; k < count; k++)
    if (!r[k].scene[0]) {
      for (uint64_t m = 0; m < count; m++)
        if (r[m].scene[0]) {
          memcpy(r[k].scene, r[m].scene, sizeof r[k].scene);
          r[k].width = r[m].width;
          r[k].height = r[m].height;
          break;
        }
    }
}

/* The set column: the policy of a levels bench, then the --set values. */
static char *set_text_of(const struct app_sets *sets, const struct bench_policy_list *l,
                         enum policy_kind policy) {
  size_t set_len = 32;
  for (unsigned i = 0; i < sets->n; i++) set_len += strlen(sets->v[i]) + 1;
  char *set_text = xcalloc(set_len, 1);
  if (!l) snprintf(set_text, set_len, "policy=%s", policy_name(policy));
  for (unsigned i = 0; i < sets->n; i++) {
    if (*set_text) strcat(set_text, ";");
    strcat(set_text, sets->v[i]);
  }
  return set_text;
}

int bench_policies(const char *machine, const struct app_sets *sets,
                   const struct bench_policy_list *l, const struct bench_level_list *lv,
                   enum policy_kind policy, uint32_t mask, uint64_t width, uint64_t height,
                   uint64_t rounds, int argc, char **argv, int first_scene) {
  /* The variants: a label each, and what it adds to the command line. */
  const unsigned n = l ? l->n : lv->n;
  const char *label[BENCH_POLICIES_MAX];
  char fid[BENCH_POLICIES_MAX][32];
  for (unsigned j = 0; j < n; j++) {
    label[j] = l ? policy_name(l->k[j]) : lv->name[j];
    if (!l) snprintf(fid[j], sizeof fid[j], "fidelity=%s", lv->name[j]);
  }
  /* The config is refused here, before any run, as rtsim run would. */
  struct machine_cfg mc;
  struct err e = {0};
  if (!app_machine_load(&mc, machine, sets, &e)) return app_report(&e);
  char bin[4096], rays[64], wtext[24], htext[24], image[4300];
  struct bench_ctx b = {.machine = machine,
                        .bin = bin,
                        .rays = rays,
                        .wtext = wtext,
                        .htext = htext,
                        .image = image,
                        .sets = sets,
                        .l = l,
                        .lv = lv,
                        .policy = policy,
                        .width = width,
                        .height = height};
  int rc = bench_setup(bin, sizeof bin, &b.t);
  if (rc) return rc;
  shade_rays_name(mask, rays, sizeof rays);
  snprintf(wtext, sizeof wtext, "%llu", (unsigned long long)width);
  snprintf(htext, sizeof htext, "%llu", (unsigned long long)height);
  char *set_text = set_text_of(sets, l, policy);
  snprintf(image, sizeof image, "%s/image.exr", b.t.out);
  const char **args = xcalloc(18 + 2 * (size_t)sets->n, sizeof *args);
  const bool progress = isatty(2);
  struct bench_run *r = xcalloc(rounds * n, sizeof *r);
  for (int i = first_scene; i < argc && rc == 0; i++) {
    for (uint64_t k = 0; k < rounds && rc == 0; k++) {
      for (unsigned j = 0; j < n && rc == 0; j++) {
        rc = one_run(&b, j, l ? NULL : fid[j], label[j], argv[i], args, &r[k * n + j]);
        const bool native = !l && !strcmp(lv->name[j], "native");
        if (rc == 0 && !native && progress)
          fprintf(stderr, "\rbench: %s, round %llu of %llu   ", argv[i], (unsigned long long)k + 1,
                  (unsigned long long)rounds);
      }
    }
    if (rc == 0) {
      if (progress) fputc('\n', stderr);
      if (i == first_scene) /* the header once a scene has its rows: none when the first fails */
        printf("scene,width,height,rays,machine,set,%s,rounds,host_s_best,host_s_median,"
               "run_s_best,run_s_median,events,peak_rss_mb,host_vs_base_median,host_vs_base_max,"
               "run_vs_base_median,events_vs_base,peak_rss_vs_base,base\n",
               l ? "policy" : "level");
      native_rows_fill(r, rounds * n);
      print_rows(machine, set_text, rays, label, n, r, rounds);
    }
  }
  free(r);
  free(args);
  free(set_text);
  tmp_fini(&b.t);
  return rc;
}
