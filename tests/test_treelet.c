/* Treelet formation. Oracles: a five-node tree worked by hand (areas, the
 * greedy order, a triangle shared by two leaves counted once, the budget met
 * exactly, a subtree without triangles taken whatever the budget); and on the
 * small scenes' trees, the structural properties of a partition (every node in
 * one treelet, each treelet connected under its root, bytes recounted by brute
 * force, the budget kept but for the stated exceptions). */
#include <stdlib.h>
#include <string.h>

#include "renderer/kdtree.h"
#include "renderer/policy/treelet.h"
#include "renderer/scene.h"
#include "renderer/scene/scene_file.h"
#include "sim/err.h"
#include "testing.h"

/* ---- by hand ------------------------------------------------------------------
 * Root box x 0..8, y 0..1, z 0..1 (half area dx dy + dy dz + dz dx = 17).
 *   0 interior, x split 6
 *     1 interior x 0..6 (area 13), x split 2
 *       2 leaf x 0..2 (area 5): triangles {0, 1}
 *       3 leaf x 2..6 (area 9): triangles {1, 2, 3}
 *     4 leaf x 6..8 (area 5): triangles {4}, or none
 * With 10-byte triangles: nodes cost 8, leaf 2 costs 28 alone and 18 beside
 * leaf 3 (triangle 1 is shared), leaf 3 costs 38, leaf 4 costs 18. */
static void hand_tree(struct kd_tree *kd, int leaf4_empty) {
  memset(kd, 0, sizeof *kd);
  kd->node_count = 5;
  kd->nodes = calloc(5, sizeof *kd->nodes);
  kd->prims = calloc(8, sizeof *kd->prims);
  kd->lo = v3(0, 0, 0);
  kd->hi = v3(8, 1, 1);
  float s6 = 6.0f, s2 = 2.0f;
  memcpy(&kd->nodes[0].w0, &s6, 4);
  kd->nodes[0].w1 = (4u << 3) | 0u;
  memcpy(&kd->nodes[1].w0, &s2, 4);
  kd->nodes[1].w1 = (3u << 3) | 0u;
  static const uint32_t prims[] = {0, 1, 1, 2, 3, 4};
  memcpy(kd->prims, prims, sizeof prims);
  kd->prim_ref_count = leaf4_empty ? 5 : 6;
  kd->nodes[2] = (struct kd_node){0, (2u << 3) | 3u};
  kd->nodes[3] = (struct kd_node){2, (3u << 3) | 3u};
  kd->nodes[4] = (struct kd_node){5, ((leaf4_empty ? 0u : 1u) << 3) | 3u};
}

static void expect_partition(const struct treelet_set *ts, const char *what, uint32_t count,
                             const uint32_t *of, const uint32_t *root, const uint64_t *bytes) {
  int same = ts->count == count;
  for (uint32_t i = 0; same && i < 5; i++) same = ts->of[i] == of[i];
  for (uint32_t t = 0; same && t < count; t++)
    same = ts->root[t] == root[t] && ts->bytes[t] == bytes[t];
  EXPECTF(same, "%s: %u treelets, of = %u %u %u %u %u, bytes[0] %llu", what, ts->count, ts->of[0],
          ts->of[1], ts->of[2], ts->of[3], ts->of[4], (unsigned long long)ts->bytes[0]);
}

static void check_hand(void) {
  struct kd_tree kd;
  struct treelet_set ts;
  hand_tree(&kd, 0);

  /* Everything fits: 5 nodes and 5 distinct triangles. */
  treelet_build(&ts, &kd, 10, 1000);
  expect_partition(&ts, "budget 1000", 1, (uint32_t[]){0, 0, 0, 0, 0}, (uint32_t[]){0},
                   (uint64_t[]){90});
  treelet_fini(&ts);

  /* 40: root 8, node 1 (area 13) 16; leaf 3 (area 9) would make 54; of the
   * tied leaves 2 and 4 (area 5) the lower index comes first and would make
   * 44; leaf 4 makes 34. Then leaf 3 and leaf 2 start treelets, in that order. */
  treelet_build(&ts, &kd, 10, 40);
  expect_partition(&ts, "budget 40", 3, (uint32_t[]){0, 0, 2, 1, 0}, (uint32_t[]){0, 3, 2},
                   (uint64_t[]){34, 38, 28});
  treelet_fini(&ts);

  /* 72: root, node 1, leaf 3 (54), then leaf 2 for 18 only (triangle 1 is in
   * already): exactly 72. Leaf 4 would make 90. */
  treelet_build(&ts, &kd, 10, 72);
  expect_partition(&ts, "budget 72", 2, (uint32_t[]){0, 0, 0, 0, 1}, (uint32_t[]){0, 4},
                   (uint64_t[]){72, 18});
  treelet_fini(&ts);
  /* 71: leaf 2 no longer fits; alone it costs 28 (its triangle 1 again). */
  treelet_build(&ts, &kd, 10, 71);
  expect_partition(&ts, "budget 71", 3, (uint32_t[]){0, 0, 1, 0, 2}, (uint32_t[]){0, 2, 4},
                   (uint64_t[]){54, 28, 18});
  treelet_fini(&ts);

  /* 0: every node its own treelet, in the order they leave the heap: node 1
   * before leaf 4 (larger), then leaf 3 before leaf 2. */
  treelet_build(&ts, &kd, 10, 0);
  expect_partition(&ts, "budget 0", 5, (uint32_t[]){0, 1, 4, 3, 2}, (uint32_t[]){0, 1, 4, 3, 2},
                   (uint64_t[]){8, 8, 18, 38, 28});
  treelet_fini(&ts);
  free(kd.nodes);
  free(kd.prims);

  /* An empty leaf 4 joins the root's treelet whatever the budget. */
  hand_tree(&kd, 1);
  treelet_build(&ts, &kd, 10, 0);
  expect_partition(&ts, "budget 0, empty leaf", 4, (uint32_t[]){0, 1, 3, 2, 0},
                   (uint32_t[]){0, 1, 3, 2}, (uint64_t[]){16, 8, 38, 28});
  treelet_fini(&ts);
  free(kd.nodes);
  free(kd.prims);
}

/* ---- real trees --------------------------------------------------------------- */

static void check_scene(const char *path) {
  struct scene s;
  struct err e;
  memset(&e, 0, sizeof e);
  if (!scene_file_load(&s, path, &e)) {
    EXPECTF(0, "%s: %s", path, e.msg);
    return;
  }
  struct kd_build_params bp;
  kd_build_params_default(&bp);
  struct kd_tree kd;
  kd_build(&kd, &s, &bp, NULL);
  const uint32_t n = kd.node_count;
  uint32_t *parent = malloc(n * sizeof *parent);
  uint32_t *has_tris = calloc(n, sizeof *has_tris); /* triangles in the subtree */
  parent[0] = UINT32_MAX;
  for (uint32_t i = 0; i < n; i++)
    if (!kd_is_leaf(kd.nodes[i])) parent[i + 1] = parent[kd_above(kd.nodes[i])] = i;
  for (uint32_t i = n; i-- > 0;) {
    struct kd_node nd = kd.nodes[i];
    if (kd_is_leaf(nd)) has_tris[i] = kd_leaf_count(nd) > 0;
    if (i > 0 && has_tris[i]) has_tris[parent[i]] = 1;
  }
  uint32_t *stamp = calloc(s.tri_count, sizeof *stamp);
  const uint64_t budgets[] = {0, 256, 4096, 65536, 1u << 20, UINT64_MAX / 2};
  for (size_t c = 0; c < sizeof budgets / sizeof budgets[0]; c++) {
    struct treelet_set ts;
    treelet_build(&ts, &kd, 128, budgets[c]);
    EXPECT(ts.count >= 1 && ts.root[0] == 0 && ts.of[0] == 0);
    int out_of_range = 0, disconnected = 0, bad_root = 0, bad_bytes = 0, over = 0;
    for (uint32_t i = 0; i < n; i++) {
      out_of_range += ts.of[i] >= ts.count;
      if (ts.of[i] >= ts.count) continue;
      int is_root = ts.root[ts.of[i]] == i;
      /* Connected: a node other than its treelet's root shares its parent's
       * treelet; a root's parent is in another (or it is the tree's root). */
      if (!is_root) disconnected += i == 0 || ts.of[parent[i]] != ts.of[i];
      else bad_root += i != 0 && (ts.of[parent[i]] == ts.of[i] || !has_tris[i]);
    }
    /* Bytes by brute force: per treelet, 8 a node, 128 a distinct triangle. */
    uint64_t *bytes = calloc(ts.count, sizeof *bytes), *empty = calloc(ts.count, sizeof *empty);
    for (uint32_t t = 0; t < ts.count; t++) {
      for (uint32_t i = 0; i < n; i++) {
        if (ts.of[i] != t) continue;
        bytes[t] += 8;
        empty[t] += has_tris[i] ? 0 : 8;
        struct kd_node nd = kd.nodes[i];
        if (!kd_is_leaf(nd)) continue;
        for (uint32_t k = 0; k < kd_leaf_count(nd); k++) {
          uint32_t p = kd.prims[kd_leaf_offset(nd) + k];
          if (stamp[p] != t + 1) {
            stamp[p] = t + 1;
            bytes[t] += 128;
          }
        }
      }
      bad_bytes += bytes[t] != ts.bytes[t];
      /* Over budget only by subtrees without triangles, or a root too big alone. */
      uint32_t r = ts.root[t];
      uint64_t root_alone = 8 + (kd_is_leaf(kd.nodes[r]) ? 128ull * kd_leaf_count(kd.nodes[r]) : 0);
      over += bytes[t] - empty[t] > budgets[c] && !(bytes[t] - empty[t] == root_alone);
      for (uint32_t i = 0; i < n; i++) /* reset the stamps for the next treelet's count */
        if (ts.of[i] == t && kd_is_leaf(kd.nodes[i]))
          for (uint32_t k = 0; k < kd_leaf_count(kd.nodes[i]); k++)
            stamp[kd.prims[kd_leaf_offset(kd.nodes[i]) + k]] = 0;
      if (t > 500) break; /* brute force is quadratic: a sample of treelets */
    }
    EXPECTF(out_of_range == 0 && disconnected == 0 && bad_root == 0, "%s budget %llu: %d/%d/%d",
            path, (unsigned long long)budgets[c], out_of_range, disconnected, bad_root);
    EXPECTF(bad_bytes == 0 && over == 0, "%s budget %llu: %d wrong byte counts, %d over budget",
            path, (unsigned long long)budgets[c], bad_bytes, over);
    /* A budget above the whole tree: one treelet. */
    if (budgets[c] == UINT64_MAX / 2) EXPECT(ts.count == 1);
    free(bytes);
    free(empty);
    treelet_fini(&ts);
  }
  free(stamp);
  free(has_tris);
  free(parent);
  kd_fini(&kd);
  scene_fini(&s);
}

int main(void) {
  check_hand();
  check_scene(RTSIM_SOURCE_DIR "/scenes/small/sphereflake.yaml");
  check_scene(RTSIM_SOURCE_DIR "/scenes/small/grove.yaml");
  check_scene(RTSIM_SOURCE_DIR "/scenes/small/room.yaml");
  return testing_done("test_treelet");
}
