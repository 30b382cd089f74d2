/* SAH k-d tree builder with PBRT-v3 KdTreeAccel's cost model and leaf rules,
 * over presorted bound events: each axis's events are radix-sorted once and
 * split stably at every node, so a build is O(N log N) instead of PBRT's
 * per-node sort. Candidate planes are the triangle bounds themselves and are
 * stored exactly, so the tree depends only on the order of coordinates and on
 * SAH costs, both unchanged (up to rounding) when the scene is scaled.
 * Children and their lists are indices and arena offsets. */
#define _DEFAULT_SOURCE /* madvise */
#include "renderer/kdtree.h"

#include <float.h>
#include <math.h>
#include <setjmp.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>

#include "renderer/scene.h"
#include "sim/err.h"

/* Bound events of one axis. A triangle flat in that axis has one PLANAR event,
 * any other one START (at its lower bound) and one END (at its upper bound). */
enum { KD_EV_END = 0, KD_EV_PLANAR = 1, KD_EV_START = 2 };

struct kd_ev {
  float t;
  uint32_t pt; /* prim << 2 | type */
};

struct kd_box {
  float lo[3], hi[3];
};

/* One node's event lists: axis a's list is arena[off + pos[a] .. + len[a]). */
struct kd_lists {
  size_t off;
  uint32_t len[3];
};

struct kd_builder {
  const struct kd_build_params *p;
  const struct scene *scene;
  struct kd_tree *t;
  struct kd_box *tb;   /* triangle bounds */
  uint8_t *side;       /* classification scratch: bit 0 below, bit 1 above */
  struct kd_ev *arena; /* LIFO store of event lists, see build_node */
  size_t arena_top, arena_cap;
  size_t arena_high; /* the arena's pages above this may be resident but dead */
  uint32_t node_cap, prim_cap;
  uint32_t *leaf_scratch;
  /* Perfect splits: the straddlers of the node being split (prims) and the
   * events of their clipped bounds in each child, one list per axis. */
  uint32_t *strad;
  struct kd_ev *sev[2][3];
  uint32_t sev_len[2][3], sev_cap;
  /* Out of host memory: kd_grow jumps here from any depth; everything the
   * build holds hangs off this builder and the tree, so kd_build frees it all. */
  jmp_buf oom;
  unsigned long long oom_bytes;
};

/* realloc for the build: failure unwinds the whole build (kd_build returns
 * false) instead of aborting the program. */
static void *kd_grow(struct kd_builder *b, void *p, unsigned long long size) {
  void *q = size <= SIZE_MAX ? realloc(p, size ? (size_t)size : 1) : NULL;
  if (!q) {
    b->oom_bytes = size;
    longjmp(b->oom, 1);
  }
  return q;
}

void kd_build_params_default(struct kd_build_params *p) {
  p->cost_traversal = 1.0f;
  p->cost_isect = 80.0f;
  p->empty_bonus = 0.5f;
  p->max_prims = 1;
  p->max_depth = -1;
  p->clip = false;
}

void kd_fini(struct kd_tree *t) {
  if (!t) return;
  free(t->nodes);
  free(t->prims);
  memset(t, 0, sizeof *t);
}

/* Order-preserving map of a float to an unsigned key (-0 sorts just below +0). */
static uint32_t float_key(float f) {
  uint32_t u;
  memcpy(&u, &f, sizeof u);
  return (u & 0x80000000u) ? ~u : (u | 0x80000000u);
}

/* Stable sort by t; equal keys keep their input order (prim order): insertion
 * for short lists, LSD radix otherwise. */
static void sort_events(struct kd_builder *b, struct kd_ev *ev, size_t n) {
  if (n <= 64) {
    for (size_t x = 1; x < n; x++) {
      struct kd_ev v = ev[x];
      uint32_t k = float_key(v.t);
      size_t y = x;
      for (; y > 0 && float_key(ev[y - 1].t) > k; y--) ev[y] = ev[y - 1];
      ev[y] = v;
    }
    return;
  }
  struct kd_ev *tmp = kd_grow(b, NULL, n * sizeof *tmp);
  struct kd_ev *src = ev, *dst = tmp;
  for (int pass = 0; pass < 4; pass++) {
    size_t count[257] = {0};
    int shift = 8 * pass;
    for (size_t i = 0; i < n; i++) count[((float_key(src[i].t) >> shift) & 255u) + 1]++;
    for (int k = 0; k < 256; k++) count[k + 1] += count[k];
    for (size_t i = 0; i < n; i++) dst[count[(float_key(src[i].t) >> shift) & 255u]++] = src[i];
    struct kd_ev *sw = src;
    src = dst;
    dst = sw;
  }
  /* Four passes: the sorted data is back in ev. */
  free(tmp);
}

static uint32_t new_node(struct kd_builder *b) {
  struct kd_tree *t = b->t;
  if (t->node_count == b->node_cap) {
    CHECK_LT(b->node_cap, KD_MAX_NODES);
    b->node_cap = b->node_cap ? 2 * b->node_cap : 1024;
    t->nodes = kd_grow(b, t->nodes, (unsigned long long)b->node_cap * sizeof *t->nodes);
  }
  t->stats.nodes++;
  return t->node_count++;
}

static void arena_reserve(struct kd_builder *b, size_t extra) {
  if (b->arena_top + extra <= b->arena_cap) return;
  size_t cap = b->arena_cap ? b->arena_cap : 4096;
  while (cap < b->arena_top + extra) cap *= 2;
  b->arena = kd_grow(b, b->arena, (unsigned long long)cap * sizeof *b->arena);
  b->arena_cap = cap;
}

/* What lies in the arena past the top is dead once a split is done, but
 * its pages stay resident: the root's split of a large scene touches about
 * three times its lists (tens of megabytes), held to the end of the build
 * beside the growing tree. Before a child is built (its lists on top, of
 * `child` events), give back the pages past what can still be written: the
 * top plus twice the child's lists (its subtree's splits), or `floor`, the
 * furthest that a sibling still to be built of it or of an ancestor will
 * write; once they are many. So no page given back is written again, and the
 * build takes no new page faults. */
static void arena_release(struct kd_builder *b, size_t child, size_t floor) {
  const size_t page = 4096, ev = sizeof *b->arena;
  size_t keep = b->arena_top + 2 * child;
  if (keep < floor) keep = floor;
  if (b->arena_high <= keep || (b->arena_high - keep) * ev < ((size_t)4 << 20)) return;
  uintptr_t lo = ((uintptr_t)b->arena + keep * ev + page - 1) & ~(uintptr_t)(page - 1);
  uintptr_t hi = ((uintptr_t)b->arena + b->arena_high * ev) & ~(uintptr_t)(page - 1);
  if (hi > lo) madvise((void *)lo, hi - lo, MADV_DONTNEED);
  b->arena_high = keep;
}

static int cmp_u32(const void *a, const void *b) {
  uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
  return (x > y) - (x < y);
}

/* Make node i a leaf over the n triangles named by axis 0's START/PLANAR events
 * (ascending prim ids, so leaf contents do not depend on event order). */
static void make_leaf(struct kd_builder *b, uint32_t i, const struct kd_lists *l, uint32_t n,
                      int depth) {
  struct kd_tree *t = b->t;
  const struct kd_ev *ev = b->arena + l->off;
  uint32_t k = 0;
  for (uint32_t j = 0; j < l->len[0]; j++)
    if ((ev[j].pt & 3u) != KD_EV_END) b->leaf_scratch[k++] = ev[j].pt >> 2;
  CHECK_EQ(k, n);
  if (n > 16) {
    qsort(b->leaf_scratch, n, sizeof *b->leaf_scratch, cmp_u32);
  } else {
    for (uint32_t x = 1; x < n; x++) {
      uint32_t v = b->leaf_scratch[x], y = x;
      for (; y > 0 && b->leaf_scratch[y - 1] > v; y--) b->leaf_scratch[y] = b->leaf_scratch[y - 1];
      b->leaf_scratch[y] = v;
    }
  }
  if (t->prim_ref_count + n > b->prim_cap) {
    uint64_t cap = b->prim_cap ? b->prim_cap : 1024;
    while (cap < (uint64_t)t->prim_ref_count + n) cap *= 2;
    CHECK_LE(cap, UINT32_MAX);
    b->prim_cap = (uint32_t)cap;
    t->prims = kd_grow(b, t->prims, cap * sizeof *t->prims);
  }
  if (n) memcpy(t->prims + t->prim_ref_count, b->leaf_scratch, n * sizeof *t->prims);
  CHECK_LT(n, 1u << 29);
  t->nodes[i].w0 = t->prim_ref_count;
  t->nodes[i].w1 = (n << 3) | 3u;
  t->prim_ref_count += n;
  t->stats.leaves++;
  if (n == 0) t->stats.empty_leaves++;
  if (n > t->stats.max_leaf_prims) t->stats.max_leaf_prims = n;
  if ((uint32_t)depth > t->stats.max_depth) t->stats.max_depth = (uint32_t)depth;
  t->stats.leaf_prim_refs += n;
}

/* Relative margin within which two box extents or two SAH costs count as a
 * tie: the axis rule below decides as if equal, and a plane keeps the best
 * found first.
 * Scaling a scene rounds its coordinates by up to 2^-24 of their size, and
 * with a strict comparison that decides exact and near ties (cubes, symmetric
 * objects) differently at every scale. Cost: a plane must beat the best by
 * 1e-6 of its cost, far below anything the SAH can see. Ties closer than the
 * rounding to the margin itself still flip; on a box much smaller than its
 * distance to the origin the rounding is relatively larger and can exceed it. */
#define KD_TIE 1e-6

/* Extent x is longer than y by more than a tie. */
static bool longer(float x, float y) { return (double)x > (double)y * (1.0 + KD_TIE); }

/* The best split plane found so far: its SAH cost, position and axis (-1: none). */
struct kd_plane {
  double cost;
  float s;
  int axis;
};

static double box_area(const struct kd_box *bx) {
  double d0 = (double)bx->hi[0] - bx->lo[0], d1 = (double)bx->hi[1] - bx->lo[1],
         d2 = (double)bx->hi[2] - bx->lo[2];
  return 2.0 * (d0 * d1 + d0 * d2 + d1 * d2);
}

/* SAH cost of splitting bx at s on axis a with nb triangles below, na above
 * (PBRT-v3's formula, evaluated in double); kept if it beats the best by more
 * than a tie. */
static inline void consider(const struct kd_builder *b, const struct kd_box *bx, double inv_area,
                            int a, float s, uint32_t nb, uint32_t na, struct kd_plane *best) {
  if (!(s > bx->lo[a] && s < bx->hi[a])) return;
  int o0 = (a + 1) % 3, o1 = (a + 2) % 3;
  double d0 = (double)bx->hi[o0] - bx->lo[o0], d1 = (double)bx->hi[o1] - bx->lo[o1];
  double below = 2.0 * (d0 * d1 + ((double)s - bx->lo[a]) * (d0 + d1));
  double above = 2.0 * (d0 * d1 + ((double)bx->hi[a] - s) * (d0 + d1));
  double eb = (na == 0 || nb == 0) ? b->p->empty_bonus : 0.0;
  double cost = b->p->cost_traversal +
                b->p->cost_isect * (1.0 - eb) * (below * inv_area * nb + above * inv_area * na);
  if (cost < best->cost * (1.0 - KD_TIE)) {
    best->cost = cost;
    best->s = s;
    best->axis = a;
  }
}

/* Sweep axis a's sorted events. Each distinct event value v is a candidate,
 * with counts exact for the plane s = v:
 *   below = #(lower bound < s) + #(flat at s),  above = #(upper bound > s) + #(flat at s).
 * NOTE: every candidate must be treated alike, whatever its bits: the builder
 * once allowed only even mantissas (to free a flag bit) and stepped odd values
 * one float aside, which made the choice depend on the float grid and so on
 * the scene's units. */
static void sweep_axis(const struct kd_builder *b, const struct kd_lists *l,
                       const struct kd_box *bx, double inv_area, int a, struct kd_plane *best) {
  const struct kd_ev *ev = b->arena + l->off;
  size_t base = 0;
  for (int k = 0; k < a; k++) base += l->len[k];
  ev += base;
  uint32_t m = l->len[a];
  uint32_t n_end = 0, n_planar = 0;
  for (uint32_t j = 0; j < m; j++) {
    uint32_t ty = ev[j].pt & 3u;
    n_end += ty == KD_EV_END;
    n_planar += ty == KD_EV_PLANAR;
  }
  /* Counts of events strictly before the current group. */
  uint32_t lt_s = 0, lt_e = 0, lt_p = 0;
  uint32_t j = 0;
  while (j < m) {
    float v = ev[j].t;
    uint32_t g_s = 0, g_e = 0, g_p = 0, k = j;
    while (k < m && ev[k].t == v) {
      uint32_t ty = ev[k].pt & 3u;
      g_s += ty == KD_EV_START;
      g_e += ty == KD_EV_END;
      g_p += ty == KD_EV_PLANAR;
      k++;
    }
    consider(b, bx, inv_area, a, v, lt_s + lt_p + g_p, (n_end - lt_e - g_e) + (n_planar - lt_p),
             best);
    lt_s += g_s;
    lt_e += g_e;
    lt_p += g_p;
    j = k;
  }
}

/* Largest float <= d, and smallest float >= d (d finite, in float range). */
static float float_down(double d) {
  float f = (float)d;
  return (double)f > d ? nextafterf(f, -INFINITY) : f;
}
static float float_up(double d) {
  float f = (float)d;
  return (double)f < d ? nextafterf(f, INFINITY) : f;
}

/* *out = the bounds of the n corners c (widened by m, rounded outwards; none:
 * unbounded) cut back to bx and to triangle p's own bounds; false if empty. */
static bool cut_bounds(const struct kd_builder *b, uint32_t p, const struct kd_box *bx,
                       double (*c)[3], int n, double m, struct kd_box *out) {
  for (int a = 0; a < 3; a++) {
    float lo = -INFINITY, hi = INFINITY;
    if (n > 0) {
      double dl = c[0][a], dh = dl;
      for (int i = 1; i < n; i++) {
        dl = c[i][a] < dl ? c[i][a] : dl;
        dh = c[i][a] > dh ? c[i][a] : dh;
      }
      lo = float_down(dl - m);
      hi = float_up(dh + m);
    }
    out->lo[a] = max_nonnan(lo, max_nonnan(bx->lo[a], b->tb[p].lo[a]));
    out->hi[a] = min_nonnan(hi, min_nonnan(bx->hi[a], b->tb[p].hi[a]));
    if (out->lo[a] > out->hi[a]) return false;
  }
  return true;
}

/* Bounds of what triangle p has inside box bx, conservatively: the triangle is
 * clipped in double against bx widened by a margin m (2^-40 of the largest
 * coordinate involved, far above the clipping's rounding), the result widened
 * by m, rounded outwards to float and cut back to bx and to the triangle's own
 * bounds (both exact). So every point of the triangle in bx lies in *out, and
 * a triangle that touches bx, even at one point, is never dropped. False if
 * the triangle misses the widened box. A triangle clipped by six planes has at
 * most 9 corners; should rounding ever make more (a sliver turned slightly
 * non-convex), the bounds fall back to bx and the triangle's own, which is
 * still conservative. */
#define KD_CLIP_MAX 16
static bool clip_tri(const struct kd_builder *b, uint32_t p, const struct kd_box *bx,
                     struct kd_box *out) {
  double poly[2][KD_CLIP_MAX][3];
  const struct scene_tri *tr = &b->scene->tris[p];
  double mag = 0.0;
  for (int k = 0; k < 3; k++)
    for (int a = 0; a < 3; a++) {
      poly[0][k][a] = v3_get(tr->v[k], a);
      double x = fabs(poly[0][k][a]);
      mag = x > mag ? x : mag;
    }
  for (int a = 0; a < 3; a++) {
    double l = fabs(bx->lo[a]), h = fabs(bx->hi[a]);
    mag = l > mag ? l : mag;
    mag = h > mag ? h : mag;
  }
  double m = mag * 0x1p-40 + DBL_MIN;
  int n = 3, cur = 0;
  for (int a = 0; a < 3; a++)
    for (int hi = 0; hi < 2; hi++) {
      double c = hi ? (double)bx->hi[a] + m : (double)bx->lo[a] - m;
      double(*src)[3] = poly[cur], (*dst)[3] = poly[cur ^ 1];
      int nn = 0;
      for (int i = 0; i < n; i++) {
        if (nn + 2 > KD_CLIP_MAX) return cut_bounds(b, p, bx, NULL, 0, 0.0, out);
        const double *P = src[i], *Q = src[i + 1 == n ? 0 : i + 1];
        double dp = hi ? c - P[a] : P[a] - c, dq = hi ? c - Q[a] : Q[a] - c; /* >= 0 inside */
        if (dp >= 0.0) {
          memcpy(dst[nn++], P, sizeof dst[0]);
        }
        if ((dp >= 0.0) != (dq >= 0.0)) {
          double t = dp / (dp - dq);
          for (int k = 0; k < 3; k++) dst[nn][k] = P[k] + t * (Q[k] - P[k]);
          dst[nn++][a] = c;
        }
      }
      n = nn;
      cur ^= 1;
      if (n == 0) return false;
    }
  return cut_bounds(b, p, bx, poly[cur], n, m, out);
}

static void sev_push(struct kd_builder *b, int child, int a, float t, uint32_t pt) {
  /* Each list holds at most two events per straddler: sized in clip_straddlers. */
  b->sev[child][a][b->sev_len[child][a]].t = t;
  b->sev[child][a][b->sev_len[child][a]++].pt = pt;
}

/* Clip the ns straddlers b->strad[] to each child box, make the events of
 * their clipped bounds (sorted, one list per child and axis) and drop each
 * from the children it misses (adjusting *nb, *na and side[]). */
static void clip_straddlers(struct kd_builder *b, uint32_t ns, const struct kd_box *below,
                            const struct kd_box *above, uint32_t *nb, uint32_t *na) {
  if (2 * ns > b->sev_cap) {
    b->sev_cap = 2 * ns;
    for (int c = 0; c < 2; c++)
      for (int a = 0; a < 3; a++)
        b->sev[c][a] =
            kd_grow(b, b->sev[c][a], (unsigned long long)b->sev_cap * sizeof *b->sev[c][a]);
  }
  for (int c = 0; c < 2; c++)
    for (int a = 0; a < 3; a++) b->sev_len[c][a] = 0;
  for (uint32_t i = 0; i < ns; i++) {
    uint32_t p = b->strad[i];
    for (int c = 0; c < 2; c++) {
      struct kd_box cb;
      if (!clip_tri(b, p, c ? above : below, &cb)) {
        b->side[p] = (uint8_t)(b->side[p] & ~(c ? 2u : 1u));
        (*(c ? na : nb))--;
        continue;
      }
      for (int a = 0; a < 3; a++) {
        if (cb.lo[a] == cb.hi[a]) {
          sev_push(b, c, a, cb.lo[a], (p << 2) | KD_EV_PLANAR);
        } else {
          sev_push(b, c, a, cb.lo[a], (p << 2) | KD_EV_START);
          sev_push(b, c, a, cb.hi[a], (p << 2) | KD_EV_END);
        }
      }
    }
    b->side[p] |= 4u; /* straddler: its old events are replaced */
  }
  for (int c = 0; c < 2; c++)
    for (int a = 0; a < 3; a++) sort_events(b, b->sev[c][a], b->sev_len[c][a]);
}

/* Write to dst, in order of t, the events of ev[0..n) whose triangle is a
 * non-straddler on side `bit`, merged with the straddler events s[0..ns)
 * (ties: the old events first). Returns the count written. */
static size_t merge_events(const struct kd_builder *b, const struct kd_ev *ev, uint32_t n,
                           uint8_t bit, const struct kd_ev *sv, uint32_t ns, struct kd_ev *dst) {
  size_t w = 0;
  uint32_t i = 0, j = 0;
  for (;;) {
    while (i < n && (b->side[ev[i].pt >> 2] & (4u | bit)) != bit) i++;
    if (i == n) break;
    while (j < ns && float_key(sv[j].t) < float_key(ev[i].t)) dst[w++] = sv[j++];
    dst[w++] = ev[i++];
  }
  while (j < ns) dst[w++] = sv[j++];
  return w;
}

/* Build node over the n triangles whose event lists are l (at the arena's top
 * region starting at l->off). On return the arena is popped back to l->off.
 * floor: how far into the arena nodes still to be built after this one will
 * write (arena_release). */
static void build_node(struct kd_builder *b, const struct kd_box *bx, const struct kd_lists *l,
                       uint32_t n, int depth, int depth_left, int bad_refines, size_t floor) {
  struct kd_tree *t = b->t;
  uint32_t i = new_node(b);
  if (n <= b->p->max_prims || depth_left == 0) {
    make_leaf(b, i, l, n, depth);
    b->arena_top = l->off;
    return;
  }

  /* Choose the split: the box's longest axis first (ties: the later axis, as PBRT), the
   * others if it has no candidate. */
  struct kd_plane best = {INFINITY, 0.0f, -1};
  double area = box_area(bx);
  if (area > 0.0) {
    double inv_area = 1.0 / area;
    float d[3] = {bx->hi[0] - bx->lo[0], bx->hi[1] - bx->lo[1], bx->hi[2] - bx->lo[2]};
    int axis = (longer(d[0], d[1]) && longer(d[0], d[2])) ? 0 : (longer(d[1], d[2]) ? 1 : 2);
    for (int retries = 0; retries < 3 && best.axis < 0; retries++, axis = (axis + 1) % 3)
      sweep_axis(b, l, bx, inv_area, axis, &best);
  }
  double old_cost = (double)b->p->cost_isect * n;
  if (best.axis >= 0 && best.cost > old_cost) bad_refines++;
  if (best.axis < 0 || (best.cost > 4.0 * old_cost && n < 16) || bad_refines == 3) {
    make_leaf(b, i, l, n, depth);
    b->arena_top = l->off;
    return;
  }

  /* Classify against the plane, from the split axis's events, i.e. the node's
   * own (clipped) bounds: below if the lower bound is < s, above if the upper
   * bound is > s, both if flat at s. Triangles on both sides are the straddlers. */
  int a = best.axis;
  float s = best.s;
  size_t base_a = 0;
  for (int k = 0; k < a; k++) base_a += l->len[k];
  const struct kd_ev *ea = b->arena + l->off + base_a;
  uint32_t nb = 0, na = 0, ns = 0;
  for (uint32_t j = 0; j < l->len[a]; j++) {
    uint32_t p = ea[j].pt >> 2, ty = ea[j].pt & 3u;
    float v = ea[j].t;
    if (ty == KD_EV_START) {
      b->side[p] = v < s ? 1u : 0u;
      continue;
    }
    if (ty == KD_EV_END) b->side[p] = (uint8_t)(b->side[p] | (v > s ? 2u : 0u));
    else b->side[p] = (uint8_t)(v < s ? 1u : (v > s ? 2u : 3u));
    uint8_t sd = b->side[p];
    CHECK_NE(sd, 0);
    nb += sd & 1u;
    na += sd >> 1;
    if (sd == 3u && b->p->clip) b->strad[ns++] = p;
  }

  struct kd_box below = *bx, above = *bx;
  below.hi[a] = s;
  above.lo[a] = s;
  bool clip = b->p->clip && ns > 0;
  if (clip) clip_straddlers(b, ns, &below, &above, &nb, &na);

  /* Split the lists in one stable pass: above events to the top, below events
   * after room for all (no child list is longer than the parent's: a clipped
   * straddler has at most as many events as before); then close the gap and
   * move both down over this node's lists, which are dead now:
   * [above lists][below lists]. With clipping, the straddlers' old events are
   * dropped and their clipped ones merged in. */
  size_t total = (size_t)l->len[0] + l->len[1] + l->len[2];
  arena_reserve(b, total * 2);
  const struct kd_ev *e = b->arena + l->off;
  struct kd_ev *da = b->arena + b->arena_top, *db = da + total;
  struct kd_lists la = {l->off, {0, 0, 0}}, lb = {0, {0, 0, 0}};
  size_t wa = 0, wb = 0;
  for (int k = 0; k < 3; k++) {
    size_t a0 = wa, b0 = wb;
    if (!clip) {
      for (uint32_t j = 0; j < l->len[k]; j++) {
        uint8_t sd = b->side[e[j].pt >> 2];
        da[wa] = e[j];
        wa += sd >> 1;
        db[wb] = e[j];
        wb += sd & 1u;
      }
    } else {
      wa += merge_events(b, e, l->len[k], 2u, b->sev[1][k], b->sev_len[1][k], da + wa);
      wb += merge_events(b, e, l->len[k], 1u, b->sev[0][k], b->sev_len[0][k], db + wb);
    }
    la.len[k] = (uint32_t)(wa - a0);
    lb.len[k] = (uint32_t)(wb - b0);
    CHECK_LE(la.len[k], l->len[k]);
    CHECK_LE(lb.len[k], l->len[k]);
    e += l->len[k];
  }
  memmove(da + wa, db, wb * sizeof *db);
  memmove(b->arena + l->off, da, (wa + wb) * sizeof *da);
  lb.off = l->off + wa;
  b->arena_top = l->off + wa + wb;
  size_t written = (size_t)(db + wb - b->arena);
  if (written > b->arena_high) b->arena_high = written;

  /* The above child, built second from [l->off, + wa), writes up to 3 wa. */
  size_t floor_below = l->off + 3 * wa > floor ? l->off + 3 * wa : floor;
  arena_release(b, wb, floor_below);
  build_node(b, &below, &lb, nb, depth + 1, depth_left - 1, bad_refines, floor_below);
  uint32_t above_idx = t->node_count;
  CHECK_LT(above_idx, KD_MAX_NODES);
  arena_release(b, wa, floor);
  build_node(b, &above, &la, na, depth + 1, depth_left - 1, bad_refines, floor);
  uint32_t bits;
  memcpy(&bits, &s, sizeof bits);
  t->nodes[i].w0 = bits;
  t->nodes[i].w1 = (above_idx << 3) | (uint32_t)a;
  b->arena_top = l->off;
}

static void kd_builder_free(struct kd_builder *b) {
  free(b->tb);
  free(b->side);
  free(b->leaf_scratch);
  free(b->strad);
  for (int c = 0; c < 2; c++)
    for (int a = 0; a < 3; a++) free(b->sev[c][a]);
  free(b->arena);
}

static void kd_build_all(struct kd_builder *b, const struct scene *s) {
  struct kd_tree *t = b->t;
  const struct kd_build_params *p = b->p;
  uint32_t n = s->tri_count;
  CHECK_LT(n, 1u << 29);
  scene_bounds(s, &t->lo, &t->hi);

  int max_depth = p->max_depth;
  if (max_depth < 0) {
    int lg = 0;
    while (n >> (lg + 1)) lg++;
    max_depth = (int)lroundf(8.0f + 1.3f * (float)lg);
  }
  if (max_depth > KD_DEPTH_LIMIT) max_depth = KD_DEPTH_LIMIT;

  b->tb = kd_grow(b, NULL, (n ? n : 1) * (unsigned long long)sizeof *b->tb);
  b->side = kd_grow(b, NULL, n ? n : 1);
  memset(b->side, 0, n ? n : 1);
  b->leaf_scratch = kd_grow(b, NULL, (n ? n : 1) * (unsigned long long)sizeof *b->leaf_scratch);
  b->scene = s;
  if (p->clip) b->strad = kd_grow(b, NULL, (n ? n : 1) * (unsigned long long)sizeof *b->strad);
  for (uint32_t i = 0; i < n; i++) {
    const struct scene_tri *tr = &s->tris[i];
    for (int a = 0; a < 3; a++) {
      float x = v3_get(tr->v[0], a), y = v3_get(tr->v[1], a), z = v3_get(tr->v[2], a);
      CHECK(isfinite(x) && isfinite(y) && isfinite(z));
      b->tb[i].lo[a] = min_nonnan(x, min_nonnan(y, z));
      b->tb[i].hi[a] = max_nonnan(x, max_nonnan(y, z));
    }
  }

  /* Root event lists, one sorted list per axis, laid out back to back. */
  struct kd_lists root = {0, {0, 0, 0}};
  /* Room for the root lists and the pending children below them (the peak is
   * about three times the root's lists for typical scenes; it grows if not). */
  arena_reserve(b, (size_t)18 * n + 1);
  for (int a = 0; a < 3; a++) {
    struct kd_ev *ev = b->arena + b->arena_top;
    uint32_t m = 0;
    for (uint32_t i = 0; i < n; i++) {
      float lo = b->tb[i].lo[a], hi = b->tb[i].hi[a];
      if (lo == hi) {
        ev[m].t = lo;
        ev[m++].pt = (i << 2) | KD_EV_PLANAR;
      } else {
        ev[m].t = lo;
        ev[m++].pt = (i << 2) | KD_EV_START;
        ev[m].t = hi;
        ev[m++].pt = (i << 2) | KD_EV_END;
      }
    }
    sort_events(b, ev, m);
    root.len[a] = m;
    b->arena_top += m;
  }
  /* Unclipped, the triangles' bounds were needed for the root's events only. */
  if (!p->clip) {
    free(b->tb);
    b->tb = NULL;
  }
  struct kd_box bx = {{t->lo.x, t->lo.y, t->lo.z}, {t->hi.x, t->hi.y, t->hi.z}};
  build_node(b, &bx, &root, n, 0, max_depth, 0, 0);
  CHECK_EQ(b->arena_top, 0);

  /* Trim the arrays to size: the tree lives as long as the scene. */
  t->nodes = kd_grow(b, t->nodes, (unsigned long long)t->node_count * sizeof *t->nodes);
  if (t->prim_ref_count)
    t->prims = kd_grow(b, t->prims, (unsigned long long)t->prim_ref_count * sizeof *t->prims);
}

bool kd_build(struct kd_tree *t, const struct scene *s, const struct kd_build_params *p,
              unsigned long long *failed_bytes) {
  memset(t, 0, sizeof *t);
  /* On the heap, not the stack: what the build changes after setjmp must
   * still be there when kd_grow jumps back (C11 7.13.2.1). */
  struct kd_builder *b = xcalloc(1, sizeof *b);
  b->p = p;
  b->t = t;
  bool ok = setjmp(b->oom) == 0;
  if (ok) kd_build_all(b, s);
  else if (failed_bytes) *failed_bytes = b->oom_bytes;
  kd_builder_free(b);
  free(b);
  if (!ok) kd_fini(t);
  return ok;
}
