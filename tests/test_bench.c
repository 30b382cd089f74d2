/* rtsim bench --timed MACHINE.yaml --policies LIST against rtsim run itself:
 * the events and image size it reports for each policy are those of the same
 * run made directly (an independent process writing its own stats.json), its
 * ratios are its own columns divided as it says, it leaves no temporary
 * folder behind, and a run that fails stops it with that run's message and
 * exit code. Host seconds are a benchmark's figures, not checked here beyond
 * being positive. */
#include <dirent.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testing.h"

#define SCN RTSIM_TEST_DATA "/scenes/good_room_tiny.yaml"
#define CFG RTSIM_SOURCE_DIR "/configs/tiny.yaml"

/* The n-th comma-separated field of line (quoted fields kept whole). */
static void field(const char *line, unsigned n, char *out, unsigned cap) {
  unsigned i = 0, k = 0;
  bool q = false;
  for (const char *p = line; *p && *p != '\n'; p++) {
    if (*p == '"') q = !q;
    else if (*p == ',' && !q) i++;
    else if (i == n && k + 1 < cap) out[k++] = *p;
  }
  out[k] = '\0';
}

static double field_f(const char *line, unsigned n) {
  char t[64];
  field(line, n, t, sizeof t);
  return atof(t);
}

/* Events of a direct rtsim run of policy p into dir (extra: more options). */
static double direct_events(const char *p, const char *dir, const char *extra) {
  char out[8192], path[600];
  int rc = testing_runf(out, sizeof out,
                        RTSIM_BINARY " run " CFG " " SCN " --policy %s --rays primary,shadow "
                                     "--width 8 --height 8 --set cores=4 %s -o %s",
                        p, extra, dir);
  EXPECTF(rc == 0, "direct run of %s: exit %d: %s", p, rc, out);
  snprintf(path, sizeof path, "%s/stats.json", dir);
  FILE *f = fopen(path, "r");
  EXPECTF(f != NULL, "no %s", path);
  if (!f) return -1;
  char line[512];
  double ev = -1;
  while (fgets(line, sizeof line, f))
    if (strncmp(line, "  \"events\": ", 12) == 0) ev = atof(line + 12);
  fclose(f);
  return ev;
}

/* Folders named rtsim-bench-* in dir. */
static int bench_dirs(const char *dir) {
  DIR *d = opendir(dir);
  if (!d) return 0;
  int n = 0;
  for (struct dirent *de; (de = readdir(d));) n += strncmp(de->d_name, "rtsim-bench-", 12) == 0;
  closedir(d);
  return n;
}

/* The renderer's bench names the structure each scene traced, and its node
 * count is the one rtsim render reports for that structure. */
static void test_native_accel(void) {
  char out[4096], ren[4096];
  const char *bvh = RTSIM_TEST_DATA "/scenes/good_room_tiny_bvh8.yaml";
  int rc = testing_runf(out, sizeof out,
                        RTSIM_BINARY " bench --width 8 --height 8 --repeat 1 %s %s 2>&1", SCN, bvh);
  EXPECTF(rc == 0, "bench: exit %d: %s", rc, out);
  const char *r1 = strchr(out, '\n'), *r2 = r1 ? strchr(r1 + 1, '\n') : NULL;
  EXPECTF(r1 && r2 && strncmp(out, "scene,triangles,kd_nodes,", 25) == 0 && r1 - out >= 17 &&
              strncmp(r1 - 17, ",rays_per_s,accel", 17) == 0,
          "header: %s", out);
  if (!r1 || !r2) return;
  char a[16];
  field(r1 + 1, 9, a, sizeof a);
  EXPECTF(strcmp(a, "kd") == 0, "first scene's accel: %s", a);
  field(r2 + 1, 9, a, sizeof a);
  EXPECTF(strcmp(a, "bvh8") == 0, "second scene's accel: %s", a);
  rc = testing_runf(ren, sizeof ren,
                    RTSIM_BINARY " render %s --width 8 --height 8 -o %s/bench-bvh8.exr", bvh,
                    RTSIM_TMP);
  EXPECTF(rc == 0, "render: exit %d: %s", rc, ren);
  const char *n = strstr(ren, "bvh_nodes: ");
  EXPECTF(n && atof(n + 11) == field_f(r2 + 1, 2) && atof(n + 11) > 0,
          "bench's nodes %.0f, render's %s", field_f(r2 + 1, 2), n ? n : "(none)");
}

int main(void) {
  test_native_accel();
  char out[16384];
  int rc = testing_runf(out, sizeof out,
                        "TMPDIR=%s " RTSIM_BINARY " bench --timed " CFG
                        " --policies dynamic,packet,recursive --rays primary,shadow --width 8 "
                        "--height 8 --set cores=4 --repeat 2 " SCN " 2>/dev/null",
                        RTSIM_TMP);
  EXPECTF(rc == 0, "bench --policies: exit %d: %s", rc, out);
  EXPECTF(bench_dirs(RTSIM_TMP) == 0, "bench left its temporary folder in %s", RTSIM_TMP);
  /* The header and one row per policy, in LIST's order, base last. */
  const char *row[3];
  const char *p = strchr(out, '\n');
  EXPECTF(p && strncmp(out, "scene,width,height,rays,machine,set,policy,rounds,", 50) == 0,
          "header: %s", out);
  for (int i = 0; i < 3; i++) {
    row[i] = p ? p + 1 : "";
    p = p ? strchr(p + 1, '\n') : NULL;
  }
  static const char *const pol[3] = {"dynamic", "packet", "recursive"};
  double ev[3];
  char dir[512];
  for (int i = 0; i < 3; i++) {
    char t[64];
    field(row[i], 6, t, sizeof t);
    EXPECTF(strcmp(t, pol[i]) == 0, "row %d is policy '%s', want %s", i, t, pol[i]);
    field(row[i], 3, t, sizeof t);
    EXPECTF(strcmp(t, "primary,shadow") == 0, "row %d rays '%s'", i, t);
    field(row[i], 5, t, sizeof t);
    EXPECTF(strcmp(t, "cores=4") == 0, "row %d set '%s'", i, t);
    field(row[i], 19, t, sizeof t);
    EXPECTF(strcmp(t, "recursive") == 0, "row %d base '%s'", i, t);
    EXPECTF(field_f(row[i], 1) == 8 && field_f(row[i], 2) == 8 && field_f(row[i], 7) == 2,
            "row %d: width, height, rounds: %s", i, row[i]);
    ev[i] = field_f(row[i], 12);
    snprintf(dir, sizeof dir, "%s/bench-direct-%s", RTSIM_TMP, pol[i]);
    double want = direct_events(pol[i], dir, "");
    EXPECTF(ev[i] == want, "%s: bench says %.0f events, a direct run %.0f", pol[i], ev[i], want);
    EXPECTF(field_f(row[i], 8) > 0 && field_f(row[i], 9) >= field_f(row[i], 8) &&
                field_f(row[i], 10) > 0 && field_f(row[i], 11) >= field_f(row[i], 10) &&
                field_f(row[i], 13) > 0,
            "row %d: host and run seconds, best <= median, memory: %s", i, row[i]);
  }
  /* Against the base: its own events over the base's (3 decimals). */
  for (int i = 0; i < 3; i++) {
    double r = field_f(row[i], 17), want = ev[i] / ev[2];
    EXPECTF(r > want - 0.0006 && r < want + 0.0006, "%s: events_vs_base %.3f, want %.4f", pol[i], r,
            want);
  }
  EXPECTF(field_f(row[2], 14) == 1 && field_f(row[2], 16) == 1, "the base against itself: %s",
          row[2]);

  /* --levels: one row per level in LIST's order; native (a render: no
   * events) and each rung as a direct run at that fidelity. */
  rc = testing_runf(out, sizeof out,
                    "TMPDIR=%s " RTSIM_BINARY " bench --timed " CFG
                    " --levels native,fixed,channel --policy packet --rays primary,shadow "
                    "--width 8 --height 8 --set cores=4 --repeat 1 " SCN " 2>/dev/null",
                    RTSIM_TMP);
  EXPECTF(rc == 0, "bench --levels: exit %d: %s", rc, out);
  EXPECTF(bench_dirs(RTSIM_TMP) == 0, "bench --levels left its temporary folder");
  p = strchr(out, '\n');
  EXPECTF(p && strncmp(out, "scene,width,height,rays,machine,set,level,rounds,", 49) == 0,
          "--levels header: %s", out);
  static const char *const lvl[3] = {"native", "fixed", "channel"};
  for (int i = 0; i < 3; i++) {
    row[i] = p ? p + 1 : "";
    p = p ? strchr(p + 1, '\n') : NULL;
    char t[64];
    field(row[i], 6, t, sizeof t);
    EXPECTF(strcmp(t, lvl[i]) == 0, "--levels row %d is '%s', want %s", i, t, lvl[i]);
    field(row[i], 5, t, sizeof t);
    EXPECTF(strcmp(t, "policy=packet;cores=4") == 0, "--levels row %d set '%s'", i, t);
    EXPECTF(field_f(row[i], 1) == 8 && field_f(row[i], 2) == 8 && field_f(row[i], 8) > 0,
            "--levels row %d: width, height, host seconds: %s", i, row[i]);
  }
  EXPECTF(field_f(row[0], 12) == 0, "native has no events: %s", row[0]);
  for (int i = 1; i < 3; i++) {
    char extra[64];
    snprintf(extra, sizeof extra, "--set fidelity=%s", lvl[i]);
    snprintf(dir, sizeof dir, "%s/bench-direct-level-%s", RTSIM_TMP, lvl[i]);
    double want = direct_events("packet", dir, extra);
    EXPECTF(field_f(row[i], 12) == want, "%s: bench says %.0f events, a direct run %.0f", lvl[i],
            field_f(row[i], 12), want);
  }
  rc = testing_runf(out, sizeof out,
                    RTSIM_BINARY " bench --timed " CFG " --levels banked,exact " SCN " 2>&1");
  EXPECTF(rc == 2 && strstr(out, "--levels"), "bad --levels: exit %d: %s", rc, out);

  /* A run that fails: its message, its exit code, no header, no folder. */
  rc = testing_runf(out, sizeof out,
                    "TMPDIR=%s " RTSIM_BINARY " bench --timed " CFG
                    " --policies dynamic,recursive --repeat 1 %s/no_such_scene.yaml",
                    RTSIM_TMP, RTSIM_TEST_DATA);
  EXPECTF(rc == 2 && strstr(out, "the run of ") && strstr(out, "no_such_scene.yaml: error:") &&
              !strstr(out, "scene,width"),
          "failing run: exit %d: %s", rc, out);
  EXPECTF(bench_dirs(RTSIM_TMP) == 0, "a failed bench left its temporary folder");
  return testing_done("test_bench");
}
