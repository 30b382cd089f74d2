/* End to end: `rtsim trace` writes a din trace of a small run; replaying it
 * through a plain LRU simulation per cache size (an oracle independent of the
 * one-pass analyser) gives exactly the misses and write-backs the analyser
 * reported. Also: `rtsim traffic` writes a table whose recursive rows are the
 * baseline (relative columns 1) and whose bytes match the trace's counts. */
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "sim/din.h"
#include "sim/err.h"
#include "testing.h"

#define SIZES 13
#define MAX_LINES 65536

/* Naive fully associative LRU of `cap` lines: timestamps, linear search for
 * the victim, an open hash table from line to slot. */
struct naive {
  uint64_t cap, used, clock, misses, writebacks;
  uint64_t line[MAX_LINES], stamp[MAX_LINES];
  unsigned char dirty[MAX_LINES];
  int64_t *table; /* slot+1, 0 empty; size 4*MAX_LINES, rebuilt on eviction */
  uint64_t tsize;
};

static uint64_t hsh(uint64_t x) {
  x ^= x >> 33;
  x *= 0xff51afd7ed558ccdull;
  x ^= x >> 33;
  return x;
}

static int64_t find(struct naive *n, uint64_t line) {
  for (uint64_t i = hsh(line) & (n->tsize - 1);; i = (i + 1) & (n->tsize - 1)) {
    if (n->table[i] == 0) return -1;
    if (n->table[i] > 0 && n->line[n->table[i] - 1] == line) return n->table[i] - 1;
  }
}

static void put(struct naive *n, uint64_t line, int64_t slot) {
  uint64_t i = hsh(line) & (n->tsize - 1);
  while (n->table[i] > 0) i = (i + 1) & (n->tsize - 1);
  n->table[i] = slot + 1;
}

static void drop(struct naive *n, uint64_t line) {
  for (uint64_t i = hsh(line) & (n->tsize - 1);; i = (i + 1) & (n->tsize - 1))
    if (n->table[i] > 0 && n->line[n->table[i] - 1] == line) {
      n->table[i] = -1; /* tombstone */
      return;
    }
}

static void naive_access(struct naive *n, uint64_t line, int store) {
  n->clock++;
  int64_t s = find(n, line);
  if (s < 0) {
    /* A write record allocates without a fetch (Dinero's -walloc f): rtsim
     * writes a partial-line store as a read record, then a write record. */
    n->misses += !store;
    if (n->used < n->cap) {
      s = (int64_t)n->used++;
    } else {
      s = 0;
      for (uint64_t i = 1; i < n->cap; i++)
        if (n->stamp[i] < n->stamp[s]) s = (int64_t)i;
      n->writebacks += n->dirty[s];
      drop(n, n->line[s]);
    }
    n->line[s] = line;
    n->dirty[s] = 0;
    put(n, line, s);
  }
  n->stamp[s] = n->clock;
  if (store) n->dirty[s] = 1;
}

struct replay {
  struct naive *caches[SIZES];
};

static void on_record(void *ctx, unsigned label, uint64_t addr) {
  struct replay *r = ctx;
  for (int k = 0; k < SIZES; k++) naive_access(r->caches[k], addr >> 6, label == 1);
}

int main(void) {
  char cmd[2048], out[16384];
  const char *din = RTSIM_TMP "/traffic_test.din";
  /* Dynamic's schedule is made for 8 KB; its queues store whole lines. The
   * third run is on a tree built with clipped (perfect) splits; the fourth is
   * the treelet policy, its treelets made for 8 KB; the last eight trace the
   * binary and the 8-wide BVH, single rays, packets, queue points and
   * treelets. */
  static const char *const policies[] = {"recursive", "dynamic",   "dynamic", "treelet",
                                         "recursive", "recursive", "packet",  "packet",
                                         "dynamic",   "dynamic",   "treelet", "treelet"};
  /* Each run's scene: under the source's scenes/ (small/room) or the test
   * data's (the tiny room on a clipped tree or a BVH). */
  static const char *const scene_files[] = {
      "small/room",          "small/room",          "good_room_tiny_clipped",
      "small/room",          "good_room_tiny_bvh2", "good_room_tiny_bvh8",
      "good_room_tiny_bvh2", "good_room_tiny_bvh8", "good_room_tiny_bvh2",
      "good_room_tiny_bvh8", "good_room_tiny_bvh8", "good_room_tiny_bvh2"};
  char scenes[12][1024];
  for (size_t k = 0; k < 12; k++)
    snprintf(scenes[k], sizeof scenes[k], "%s/scenes/%s.yaml",
             strncmp(scene_files[k], "small/", 6) ? RTSIM_TEST_DATA : RTSIM_SOURCE_DIR,
             scene_files[k]);
  unsigned long long dyn_misses_8k = 0, tl_misses_8k = 0;
  for (size_t p = 0; p < sizeof policies / sizeof policies[0]; p++) {
    unlink(din);
    /* The analyser on the tracer's thread and on its own, alternately: each
     * is held to the replay. */
    snprintf(cmd, sizeof cmd,
             "%s trace %s --policy %s --cache 8192 --rays shadow --width 24 --height 24 --din %s "
             "--threads %zu",
             RTSIM_BINARY, scenes[p], policies[p], din, 1 + p % 2);
    int rc = testing_run(cmd, out, sizeof out);
    EXPECTF(rc == 0, "%s", out);
    if (rc != 0) continue;
    /* The replay command for --cache 8192: fully associative is 8192 / 64 ways
     * (Dinero IV reads -l1-uassoc as ways; 0 would be direct-mapped). */
    char want[1024];
    snprintf(want, sizeof want,
             "dineroIV -informat d -l1-ubsize 64 -l1-usize 8k -l1-uassoc 128 -l1-urepl l "
             "-l1-uwback a -l1-uwalloc f < %s\n",
             din);
    EXPECTF(strstr(out, want) != NULL, "replay command missing or wrong: %s", out);
    struct replay r;
    for (int k = 0; k < SIZES; k++) {
      r.caches[k] = calloc(1, sizeof(struct naive));
      r.caches[k]->cap = (1024u << k) / 64;
      r.caches[k]->tsize = 4 * MAX_LINES;
      r.caches[k]->table = calloc(r.caches[k]->tsize, sizeof(int64_t));
    }
    struct err e;
    memset(&e, 0, sizeof e);
    uint64_t records = 0;
    EXPECTF(din_read_file(din, on_record, &r, &records, &e), "%s", e.msg);
    EXPECTF(records > 2000, "%s: %llu records", scenes[p], (unsigned long long)records);
    /* The analyser's counts, as `rtsim trace` printed them. */
    const char *head = strstr(out, "cache_bytes,misses,writebacks\n");
    const char *line = head ? strchr(head, '\n') : NULL;
    EXPECTF(line != NULL, "%s", out);
    for (int k = 0; k < SIZES && line; k++) {
      unsigned long long cb = 0, m = 0, wb = 0;
      EXPECT(sscanf(line + 1, "%llu,%llu,%llu", &cb, &m, &wb) == 3);
      EXPECTF(cb == 1024ull << k, "size %d: %llu", k, cb);
      EXPECTF(m == r.caches[k]->misses, "%s %llu B: analyser %llu misses, replay %llu", policies[p],
              cb, m, (unsigned long long)r.caches[k]->misses);
      if (p == 1 && cb == 8192) dyn_misses_8k = m;
      if (p == 3 && cb == 8192) tl_misses_8k = m;
      EXPECTF(wb == r.caches[k]->writebacks, "%s %llu B: analyser %llu write-backs, replay %llu",
              policies[p], cb, wb, (unsigned long long)r.caches[k]->writebacks);
      line = strchr(line + 1, '\n');
    }
    for (int k = 0; k < SIZES; k++) {
      free(r.caches[k]->table);
      free(r.caches[k]);
    }
  }

  /* The traffic table: header, 13 recursive rows with relative columns 1. */
  const char *csv = RTSIM_TMP "/traffic_test.csv";
  unlink(csv);
  snprintf(
      cmd, sizeof cmd,
      "%s traffic %s/scenes/small/room.yaml --policy recursive --rays shadow --width 24 --height 24 -o %s && cat %s",
      RTSIM_BINARY, RTSIM_SOURCE_DIR, csv, csv);
  EXPECT(testing_run(cmd, out, sizeof out) == 0);
  const char *row = strstr(
      out,
      "scene,rays,width,height,policy,cache_bytes,frac_pot_vis,geometry_mb,total_mb,rel_geometry,rel_total");
  EXPECT(row != NULL);
  int rows = 0;
  for (const char *q = row ? strchr(row, '\n') : NULL; q && q[1]; q = strchr(q + 1, '\n')) {
    EXPECTF(strstr(q, ",recursive,") && strstr(q, ",1.0000,1.0000,"), "row: %.120s", q + 1);
    rows++;
  }
  EXPECT(rows == SIZES);

  /* The traffic table's dynamic and treelet rows at 8 KB (each run analyses
   * that size alone) equal the full analyser's count for the same schedule. */
  static const char *const queued[] = {"dynamic", "treelet"};
  const unsigned long long want_8k[] = {dyn_misses_8k, tl_misses_8k};
  for (int q = 0; q < 2; q++) {
    snprintf(
        cmd, sizeof cmd,
        "%s traffic %s/scenes/small/room.yaml --policy %s --rays shadow --width 24 --height 24 -o %s && cat %s",
        RTSIM_BINARY, RTSIM_SOURCE_DIR, queued[q], csv, csv);
    EXPECT(testing_run(cmd, out, sizeof out) == 0);
    char key[32];
    snprintf(key, sizeof key, ",%s,8192,", queued[q]);
    const char *row8 = strstr(out, key);
    EXPECTF(row8 != NULL, "%s", out);
    if (!row8) continue;
    /* After cache_bytes: frac, geometry_mb, total_mb, rel x2, then fetch by class. */
    double f0, f1, f2, f3, f4;
    unsigned long long fc[5];
    EXPECT(sscanf(row8 + strlen(key), "%lf,%lf,%lf,%lf,%lf,%llu,%llu,%llu,%llu,%llu", &f0, &f1, &f2,
                  &f3, &f4, &fc[0], &fc[1], &fc[2], &fc[3], &fc[4]) == 10);
    unsigned long long lines = (fc[0] + fc[1] + fc[2] + fc[3] + fc[4]) / 64;
    EXPECTF(want_8k[q] > 0 && lines == want_8k[q], "%s 8 KB: table %llu lines, trace %llu",
            queued[q], lines, want_8k[q]);
  }

  /* The whole table, every policy, is the same byte for byte whichever
   * thread the analyser runs on (diffuse rays: dynamic's generations too). */
  {
    char one[16384];
    snprintf(
        cmd, sizeof cmd,
        "%s traffic %s/scenes/small/room.yaml --policy all --rays diffuse --width 16 --height 16 "
        "--threads 1 -o %s > /dev/null && cat %s",
        RTSIM_BINARY, RTSIM_SOURCE_DIR, csv, csv);
    EXPECT(testing_run(cmd, one, sizeof one) == 0);
    snprintf(
        cmd, sizeof cmd,
        "%s traffic %s/scenes/small/room.yaml --policy all --rays diffuse --width 16 --height 16 "
        "--threads 2 -o %s > /dev/null && cat %s",
        RTSIM_BINARY, RTSIM_SOURCE_DIR, csv, csv);
    EXPECT(testing_run(cmd, out, sizeof out) == 0);
    EXPECTF(strlen(one) > 1000 && strcmp(one, out) == 0, "threads 1:\n%.300s\nthreads 2:\n%.300s",
            one, out);
  }

  /* Without --cache the replay command is for 512 KB: 8192 ways. --help shows
   * the same, and nowhere the direct-mapped -l1-uassoc 0. */
  snprintf(
      cmd, sizeof cmd,
      "%s trace %s/scenes/small/room.yaml --policy packet --rays primary --width 4 --height 4 --din %s",
      RTSIM_BINARY, RTSIM_SOURCE_DIR, din);
  EXPECT(testing_run(cmd, out, sizeof out) == 0);
  EXPECTF(strstr(out, "-l1-usize 512k -l1-uassoc 8192 ") != NULL, "%s", out);
  snprintf(cmd, sizeof cmd, "%s trace --help-full", RTSIM_BINARY);
  EXPECT(testing_run(cmd, out, sizeof out) == 0);
  EXPECTF(strstr(out, "-l1-usize 512k -l1-uassoc 8192\n") != NULL && !strstr(out, "-l1-uassoc 0"),
          "%s", out);
  /* The dynamic settings are columns of every row: as given, and changing the
   * dynamic rows only (one ray of buffer frees cache for geometry). */
  snprintf(
      cmd, sizeof cmd,
      "%s traffic %s/scenes/small/room.yaml --rays shadow --width 24 --height 24 --dyn-batch 7 "
      "--dyn-ray-buffer 0 -o %s && cat %s",
      RTSIM_BINARY, RTSIM_SOURCE_DIR, csv, csv);
  EXPECT(testing_run(cmd, out, sizeof out) == 0);
  EXPECT(
      strstr(out, ",pot_vis_tris,pot_vis_bytes,dyn_batch,dyn_ray_buffer_bytes,kd_splits,accel\n") !=
      NULL);
  int tagged = 0;
  for (const char *q = strstr(out, "\nroom"); q; q = strchr(q + 1, '\n')) {
    const char *eol = strchr(q + 1, '\n');
    if (!eol) break;
    tagged += eol - q > 15 && !strncmp(eol - 14, ",7,64,whole,kd", 14);
  }
  EXPECTF(tagged == 3 * SIZES,
          "%d of %d rows end with the dynamic settings, the tree and the structure", tagged,
          3 * SIZES);

  /* Bad command lines: exit 2. */
  snprintf(cmd, sizeof cmd, "%s traffic %s/scenes/small/room.yaml --rays glossy -o %s",
           RTSIM_BINARY, RTSIM_SOURCE_DIR, csv);
  EXPECT(testing_run(cmd, out, sizeof out) == 2 && strstr(out, "--rays: got 'glossy'"));
  snprintf(cmd, sizeof cmd,
           "%s trace %s/scenes/small/room.yaml --rays primary --policy fifo --din %s", RTSIM_BINARY,
           RTSIM_SOURCE_DIR, din);
  EXPECT(testing_run(cmd, out, sizeof out) == 2 && strstr(out, "--policy: got 'fifo'"));
  snprintf(
      cmd, sizeof cmd,
      "%s trace %s/scenes/small/room.yaml --rays primary --policy dynamic --cache 3000 --din %s",
      RTSIM_BINARY, RTSIM_SOURCE_DIR, din);
  EXPECT(testing_run(cmd, out, sizeof out) == 2 &&
         strstr(out, "--cache: got '3000', expected a power of two"));
  snprintf(
      cmd, sizeof cmd,
      "%s trace %s/scenes/small/room.yaml --rays primary --policy recursive --din /nonexistent/x.din",
      RTSIM_BINARY, RTSIM_SOURCE_DIR);
  EXPECT(testing_run(cmd, out, sizeof out) == 2 && strstr(out, "/nonexistent/x.din"));
  return testing_done("test_traffic");
}
