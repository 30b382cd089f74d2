/* Queue-point selection. Oracles: the paper's Figure 1 (a hand-built tree
 * whose subtrees hold 26 / 16 / 10 distinct triangles, and the caption's
 * queue points for each range of g_max); brute-force distinct-triangle counts
 * on the procedural scenes' trees; and the structural properties of a
 * selection on them (every branch to geometry crosses exactly one queue point,
 * which is the first node that fits or a leaf). */
#include <stdlib.h>
#include <string.h>

#include "renderer/kdtree.h"
#include "renderer/policy/qpoint.h"
#include "renderer/scene.h"
#include "renderer/scene/scene_file.h"
#include "sim/err.h"
#include "testing.h"

/* ---- Figure 1 ----------------------------------------------------------------
 * Preorder:  0 A
 *              1 B1              8 B2
 *                2 C1   5 C2       9 C3    12 C4
 *                 3 4    6 7        10 11   13 14   (leaves D)
 * Triangles: D leaves {0-5} {5-9} {6-11} {11-15} {10-15} {15-19} {16-21} {21-25},
 * so C = 10 each, B1 = {0-15} and B2 = {10-25} = 16 each (sharing 10-15),
 * A = 26: shared triangles count once in every subtree. */

static const uint32_t FIG_ABOVE[15] = {8, 5, 4, 0, 0, 7, 0, 0, 12, 11, 0, 0, 14, 0, 0};
static const uint32_t FIG_LEAF[8][2] = {{0, 5},   {5, 9},   {6, 11},  {11, 15},
                                        {10, 15}, {15, 19}, {16, 21}, {21, 25}};
static const uint32_t FIG_TRIS[15] = {26, 16, 10, 6, 5, 10, 6, 5, 16, 10, 6, 5, 10, 6, 5};

static void figure1_tree(struct kd_tree *kd) {
  memset(kd, 0, sizeof *kd);
  kd->node_count = 15;
  kd->nodes = calloc(15, sizeof *kd->nodes);
  kd->prims = calloc(64, sizeof *kd->prims);
  uint32_t leaf = 0;
  for (uint32_t i = 0; i < 15; i++) {
    if (FIG_ABOVE[i]) {
      kd->nodes[i].w0 = 0x3f800000u; /* split 1.0f */
      kd->nodes[i].w1 = (FIG_ABOVE[i] << 3) | 0u;
    } else {
      uint32_t lo = FIG_LEAF[leaf][0], hi = FIG_LEAF[leaf][1], n = hi - lo + 1;
      kd->nodes[i].w0 = kd->prim_ref_count;
      kd->nodes[i].w1 = (n << 3) | 3u;
      /* Listed in decreasing order: the count must not depend on it. */
      for (uint32_t p = hi + 1; p-- > lo;) kd->prims[kd->prim_ref_count++] = p;
      leaf++;
    }
  }
}

static void check_figure1(void) {
  struct kd_tree kd;
  figure1_tree(&kd);
  uint32_t tris[15];
  qpoint_subtree_tris(&kd, tris);
  for (int i = 0; i < 15; i++)
    EXPECTF(tris[i] == FIG_TRIS[i], "node %d: %u distinct, want %u", i, tris[i], FIG_TRIS[i]);

  static const uint32_t A[] = {0}, B[] = {1, 8}, C[] = {2, 5, 9, 12},
                        D[] = {3, 4, 6, 7, 10, 11, 13, 14};
  struct {
    uint64_t gmax;
    const uint32_t *want;
    uint32_t n;
  } cases[] = {
      {1000, A, 1}, {26, A, 1},            /* g_max >= 26: the root, Whitted */
      {25, B, 2},   {16, B, 2},            /* 26 > g_max >= 16: B */
      {15, C, 4},   {10, C, 4},            /* 16 > g_max >= 10: C */
      {9, D, 8},    {6, D, 8},  {5, D, 8}, /* below: the leaves */
      {1, D, 8},    {0, D, 8},             /* leaves even when they exceed g_max */
  };
  for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
    struct qpoint_set qs;
    qpoint_select(&qs, &kd, tris, 1, cases[c].gmax);
    int same = qs.count == cases[c].n;
    for (uint32_t k = 0; same && k < qs.count; k++) same = qs.qnode[k] == cases[c].want[k];
    EXPECTF(same, "g_max %llu: %u queue points", (unsigned long long)cases[c].gmax, qs.count);
    uint32_t bits = 0;
    for (uint32_t i = 0; i < 15; i++) {
      bool want = false;
      for (uint32_t k = 0; k < cases[c].n; k++) want |= cases[c].want[k] == i;
      bits += qpoint_marked(qs.mark, i);
      EXPECTF(qpoint_marked(qs.mark, i) == want, "g_max %llu node %u",
              (unsigned long long)cases[c].gmax, i);
    }
    EXPECT(qs.nodes == kd.nodes); /* the tree's own nodes, untouched */
    EXPECT(bits == cases[c].n);
    for (uint32_t k = 0; k < qs.count; k++) EXPECT(qpoint_index(&qs, qs.qnode[k]) == (int64_t)k);
    EXPECT(qpoint_index(&qs, 15) == -1);
    qpoint_fini(&qs);
  }

  /* The budget: the paper's 4 MB split (tree and table capped by their shares)
   * and a floor at zero for tiny caches. */
  struct qpoint_budget b;
  struct qpoint_set qs;
  struct qpoint_reserve r = {4u << 20, 4, 16, 16, 4096, 1};
  qpoint_plan(&qs, &b, &kd, tris, 1, &r);
  EXPECT(b.node_bytes == 8 * 15 && b.ray_bytes == 4096 && b.table_bytes == 8);
  EXPECT(b.gmax_bytes == (4u << 20) - 8 * 15 - 8 - 4096 && qs.count == 1);
  qpoint_fini(&qs);
  r.cache_bytes = 16;
  qpoint_plan(&qs, &b, &kd, tris, 1, &r);
  EXPECT(b.node_bytes == 4 && b.ray_bytes == 1 && b.table_bytes == 1 && b.gmax_bytes == 10);
  EXPECT(qs.count == 4); /* the C nodes */
  qpoint_fini(&qs);
  r.cache_bytes = 4;
  qpoint_plan(&qs, &b, &kd, tris, 1, &r);
  EXPECT(b.gmax_bytes == 3 && qs.count == 8);
  qpoint_fini(&qs);
  r.ray_buffer_bytes = 1u << 20;
  r.ray_share = 1;
  r.cache_bytes = 1024;
  qpoint_plan(&qs, &b, &kd, tris, 1, &r);
  EXPECT(b.gmax_bytes == 0 && qs.count == 8);
  qpoint_fini(&qs);
  /* Several holders share what is left for geometry: 3 holders of a 64-byte
   * cache (16 bytes of nodes, 4 of table, 4 of rays: each at its share) get
   * 40 / 3 = 13 each, which makes the C nodes queue points. */
  r = (struct qpoint_reserve){64, 4, 16, 16, 4, 3};
  qpoint_plan(&qs, &b, &kd, tris, 1, &r);
  EXPECT(b.node_bytes == 16 && b.ray_bytes == 4 && b.table_bytes == 4);
  EXPECTF(b.gmax_bytes == (64 - 16 - 4 - 4) / 3 && qs.count == 4, "gmax %llu, %u queue points",
          (unsigned long long)b.gmax_bytes, qs.count);
  qpoint_fini(&qs);
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
  uint32_t *tris = malloc(n * sizeof *tris);
  qpoint_subtree_tris(&kd, tris);

  /* Brute force: mark each subtree's triangles (parents before children, so a
   * walk with an explicit stack of ancestors). */
  uint32_t *end = malloc(n * sizeof *end);
  for (uint32_t i = n; i-- > 0;)
    end[i] = kd_is_leaf(kd.nodes[i]) ? i + 1 : end[kd_above(kd.nodes[i])];
  uint32_t *stamp = calloc(s.tri_count, sizeof *stamp);
  int bad = 0;
  uint32_t step = n > 4000 ? n / 4000 : 1; /* a sample of nodes, always the root */
  for (uint32_t i = 0; i < n; i += step) {
    uint32_t distinct = 0;
    for (uint32_t j = i; j < end[i]; j++) {
      struct kd_node nd = kd.nodes[j];
      if (!kd_is_leaf(nd)) continue;
      for (uint32_t k = 0; k < kd_leaf_count(nd); k++) {
        uint32_t p = kd.prims[kd_leaf_offset(nd) + k];
        if (stamp[p] != i + 1) {
          stamp[p] = i + 1;
          distinct++;
        }
      }
    }
    bad += distinct != tris[i];
  }
  EXPECTF(bad == 0, "%s: %d nodes with a wrong distinct-triangle count", path, bad);
  EXPECTF(tris[0] <= s.tri_count && tris[0] > 0, "%s: root %u of %u", path, tris[0], s.tri_count);
  /* Counts never grow going down, and a node holds at most its children's sum. */
  int mono = 0;
  for (uint32_t i = 0; i < n; i++) {
    struct kd_node nd = kd.nodes[i];
    if (kd_is_leaf(nd)) {
      mono += tris[i] > kd_leaf_count(nd);
      continue;
    }
    uint32_t b = tris[i + 1], a = tris[kd_above(nd)];
    mono += b > tris[i] || a > tris[i] || tris[i] > a + b || tris[i] < (a > b ? a : b);
  }
  EXPECTF(mono == 0, "%s: %d nodes break monotonicity", path, mono);

  /* Selections over a range of bounds (in bytes of 128-byte triangles). */
  const uint64_t bounds[] = {
      0, 128, 1000, 16384, 1u << 20, (uint64_t)tris[0] * 128, UINT64_MAX / 256};
  uint32_t prev = UINT32_MAX;
  for (size_t c = 0; c < sizeof bounds / sizeof bounds[0]; c++) {
    struct qpoint_set qs;
    qpoint_select(&qs, &kd, tris, 128, bounds[c]);
    /* Walk every root-to-leaf path counting queue points on it. */
    uint32_t *above_qp =
        calloc(n, sizeof *above_qp); /* queue points on the path to i, excluding i */
    int wrong = 0, fit = 0, first = 0;
    for (uint32_t i = 0; i < n; i++) {
      struct kd_node nd = qs.nodes[i];
      uint32_t here = above_qp[i] + qpoint_marked(qs.mark, i);
      if (qpoint_marked(qs.mark, i)) {
        /* Fits, or is a leaf; and its parent (above it) did not qualify. */
        fit += !(kd_is_leaf(nd) || (uint64_t)tris[i] * 128 <= bounds[c]) || tris[i] == 0;
      }
      if (kd_is_leaf(nd)) {
        uint32_t want = kd_leaf_count(nd) > 0 ? 1 : (here <= 1 ? here : 2);
        wrong += here != want;
      } else {
        above_qp[i + 1] = here;
        above_qp[kd_above(nd)] = here;
        /* An interior node above the queue points does not fit (or is empty). */
        if (here == 0) first += tris[i] > 0 && (uint64_t)tris[i] * 128 <= bounds[c];
      }
    }
    EXPECTF(wrong == 0, "%s g_max %llu: %d leaves not under exactly one queue point", path,
            (unsigned long long)bounds[c], wrong);
    EXPECTF(fit == 0 && first == 0, "%s g_max %llu: %d too big, %d not first", path,
            (unsigned long long)bounds[c], fit, first);
    for (uint32_t k = 1; k < qs.count; k++) EXPECT(qs.qnode[k - 1] < qs.qnode[k]);
    /* A larger bound never makes more queue points. */
    EXPECT(qs.count <= prev);
    prev = qs.count;
    if (bounds[c] >= (uint64_t)tris[0] * 128) EXPECT(qs.count == 1 && qs.qnode[0] == 0);
    free(above_qp);
    qpoint_fini(&qs);
  }
  free(stamp);
  free(end);
  free(tris);
  kd_fini(&kd);
  scene_fini(&s);
}

int main(void) {
  check_figure1();
  check_scene(RTSIM_SOURCE_DIR "/scenes/small/sphereflake.yaml");
  check_scene(RTSIM_SOURCE_DIR "/scenes/small/grove.yaml");
  check_scene(RTSIM_SOURCE_DIR "/scenes/small/room.yaml");
  return testing_done("test_qpoint");
}
