/* Ray queries: the watertight ray/triangle test (Woop, Benthin, Wald 2013, as in
 * PBRT-v3), front-to-back k-d traversal with an explicit fixed-size stack (plain
 * loops, no recursion: kernels later run as stackful coroutines), and a brute
 * force reference with the same hit rule. Traversal is conservative: split and
 * box planes are thickened by a slack proportional to the ray's distance to the
 * scene, which covers the rounding of both the traversal and the triangle
 * test, so the tree returns exactly what brute force does. */
#include "renderer/trace.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "renderer/bvh_trav.h"
#include "renderer/kdtree.h"
#include "renderer/packet_mask.h"
#include "renderer/ray.h"
#include "renderer/scene.h"
#include "renderer/trav.h"
#include "sim/err.h"

static float gamma_f(int n) {
  float e = 0.5f * FLT_EPSILON;
  return ((float)n * e) / (1.0f - (float)n * e);
}

static float comp(vec3 v, int k) { return k == 0 ? v.x : (k == 1 ? v.y : v.z); }
_Static_assert(sizeof(vec3) == 3 * sizeof(float), "vec3 is three packed floats");

void trace_isect_prepare(struct trace_isect_ray *r, vec3 o, vec3 d) {
  float ax = fabsf(d.x), ay = fabsf(d.y), az = fabsf(d.z);
  int kz = (ax > ay) ? (ax > az ? 0 : 2) : (ay > az ? 1 : 2);
  int kx = kz + 1 == 3 ? 0 : kz + 1;
  int ky = kx + 1 == 3 ? 0 : kx + 1;
  float dz = comp(d, kz);
  /* Swap to keep the winding when looking down -kz (only matters for culling). */
  if (dz < 0.0f) {
    int tmp = kx;
    kx = ky;
    ky = tmp;
  }
  r->o = o;
  r->kx = kx;
  r->ky = ky;
  r->kz = kz;
  r->sx = comp(d, kx) / dz;
  r->sy = comp(d, ky) / dz;
  r->sz = 1.0f / dz;
  r->perm = 2 * kz + (dz < 0.0f);
}

/* True when the triangle's area is zero. Float differences and their products
 * are exact in double for coordinates within a 2^26 range of each other, so
 * this is an exact test for ordinary scenes. Only called for candidate hits. */
static bool tri_degenerate(vec3 a, vec3 b, vec3 c) {
  double e1x = (double)b.x - a.x, e1y = (double)b.y - a.y, e1z = (double)b.z - a.z;
  double e2x = (double)c.x - a.x, e2y = (double)c.y - a.y, e2z = (double)c.z - a.z;
  double nx = e1y * e2z - e1z * e2y, ny = e1z * e2x - e1x * e2z, nz = e1x * e2y - e1y * e2x;
  return nx == 0.0 && ny == 0.0 && nz == 0.0;
}

/* The test for one axis permutation (kx, ky, kz constants after inlining, so
 * every coordinate is picked without a round trip through memory). */
static inline __attribute__((always_inline)) bool isect_perm(const struct trace_isect_ray *r,
                                                             vec3 a, vec3 b, vec3 c, int kx, int ky,
                                                             int kz, float tmin, float tmax,
                                                             float *t, float *b1, float *b2) {
  /* Translate to the ray origin, permute so that kz is the ray's main axis, shear. */
  float oz = v3_get(r->o, kz), ox = v3_get(r->o, kx), oy = v3_get(r->o, ky);
  float az = v3_get(a, kz) - oz, bz = v3_get(b, kz) - oz, cz = v3_get(c, kz) - oz;
  float ax = (v3_get(a, kx) - ox) - r->sx * az, ay = (v3_get(a, ky) - oy) - r->sy * az;
  float bx = (v3_get(b, kx) - ox) - r->sx * bz, by = (v3_get(b, ky) - oy) - r->sy * bz;
  float cx = (v3_get(c, kx) - ox) - r->sx * cz, cy = (v3_get(c, ky) - oy) - r->sy * cz;

  /* Edge functions; e0 is the weight of a. A shared edge gives exactly negated
   * values in its two triangles (same products), hence watertightness. */
  float e0 = bx * cy - by * cx;
  float e1 = cx * ay - cy * ax;
  float e2 = ax * by - ay * bx;
  if (e0 == 0.0f || e1 == 0.0f || e2 == 0.0f) {
    /* On an edge in float: decide in double, where these products are exact. */
    e0 = (float)((double)bx * cy - (double)by * cx);
    e1 = (float)((double)cx * ay - (double)cy * ax);
    e2 = (float)((double)ax * by - (double)ay * bx);
  }
  if ((e0 < 0.0f || e1 < 0.0f || e2 < 0.0f) && (e0 > 0.0f || e1 > 0.0f || e2 > 0.0f)) return false;
  float det = e0 + e1 + e2;
  if (det == 0.0f || isnan(det)) return false;

  /* The sheared z in scene units, for the error bounds of x and y below. */
  float max_z = max_nonnan(fabsf(az), max_nonnan(fabsf(bz), fabsf(cz)));

  /* Scaled distance; compare against the range times det before dividing. The
   * scaled test is loosened by a few ulps so it never rejects a t that the
   * exact test on the divided value below would accept. */
  az *= r->sz;
  bz *= r->sz;
  cz *= r->sz;
  float tsc = e0 * az + e1 * bz + e2 * cz;
  float sdet = det, stsc = tsc;
  if (sdet < 0.0f) {
    sdet = -sdet;
    stsc = -stsc;
  }
  float lo = tmin * sdet, hi = tmax * sdet, loose = 8.0f * FLT_EPSILON;
  if (!(stsc > lo - fabsf(lo) * loose && stsc < hi + fabsf(hi) * loose)) return false;
  float tt = tsc / det;
  if (!(tt > tmin && tt < tmax)) return false;

  /* PBRT-v3: reject hits too close to the origin to be surely in front of it. */
  /* Every value here is finite (a NaN or infinite det or t returned above). */
  float max_zt = max_nonnan(fabsf(az), max_nonnan(fabsf(bz), fabsf(cz)));
  float max_xt = max_nonnan(fabsf(ax), max_nonnan(fabsf(bx), fabsf(cx)));
  float max_yt = max_nonnan(fabsf(ay), max_nonnan(fabsf(by), fabsf(cy)));
  float delta_z = gamma_f(3) * max_zt;
  /* x - sx z is off by at most gamma5 (|x| + |z|) (|sx| <= 1), z in scene units
   * like x. PBRT-v3 adds the z already divided by the ray's main direction
   * component (max_zt), which mixes units: with a direction not of unit length
   * (a shadow ray to a light) the bound then shrinks or grows with the scene's
   * scale, and at 1/1000 of it rejected hits up to 3e-4 of the ray away. */
  float delta_x = gamma_f(5) * (max_xt + max_z);
  float delta_y = gamma_f(5) * (max_yt + max_z);
  float delta_e = 2.0f * (gamma_f(2) * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
  float max_e = max_nonnan(fabsf(e0), max_nonnan(fabsf(e1), fabsf(e2)));
  float delta_t =
      3.0f * (gamma_f(3) * max_e * max_zt + delta_e * max_zt + delta_z * max_e) / fabsf(det);
  if (tt <= delta_t) return false;

  if (tri_degenerate(a, b, c)) return false;
  *t = tt;
  *b1 = e1 / det;
  *b2 = e2 / det;
  return true;
}

bool trace_isect_tri(const struct trace_isect_ray *r, vec3 a, vec3 b, vec3 c, float tmin,
                     float tmax, float *t, float *b1, float *b2) {
  switch (r->perm) {
  case 0: return isect_perm(r, a, b, c, 1, 2, 0, tmin, tmax, t, b1, b2);
  case 1: return isect_perm(r, a, b, c, 2, 1, 0, tmin, tmax, t, b1, b2);
  case 2: return isect_perm(r, a, b, c, 2, 0, 1, tmin, tmax, t, b1, b2);
  case 3: return isect_perm(r, a, b, c, 0, 2, 1, tmin, tmax, t, b1, b2);
  case 4: return isect_perm(r, a, b, c, 0, 1, 2, tmin, tmax, t, b1, b2);
  default: return isect_perm(r, a, b, c, 1, 0, 2, tmin, tmax, t, b1, b2);
  }
}

_Static_assert(TRACE_CLASS_COUNT <= MEM_CLASS_MAX, "the simulator keeps every class apart");

const char *const trace_class_names[TRACE_CLASS_COUNT] = {"geometry", "node", "ray", "queue",
                                                          "other"};

void trace_layout_default(struct trace_layout *l) {
  l->tri_base = 1ull << TRACE_REGION_SHIFT;
  l->node_base = 2ull << TRACE_REGION_SHIFT;
  l->prim_idx_base = 3ull << TRACE_REGION_SHIFT;
  l->qtable_base = 4ull << TRACE_REGION_SHIFT;
  l->queue_base = 5ull << TRACE_REGION_SHIFT;
  l->ray_base = 6ull << TRACE_REGION_SHIFT;
  l->fb_base = 7ull << TRACE_REGION_SHIFT;
  l->camera_base = 8ull << TRACE_REGION_SHIFT;
  l->tri_bytes = 128; /* 3 vertices, 3 normals, material: 76 bytes, padded to two lines */
  l->node_cycles = 7; /* the paper's ray/plane test: multiply, add, compare */
  l->tri_cycles = 30; /* watertight test: ~25 flops plus compares */
}

void trace_init(struct trace_ctx *tr, const struct scene *s, const struct kd_tree *kd,
                struct mem_port mem, const struct trace_layout *layout) {
  memset(tr, 0, sizeof *tr);
  tr->scene = s;
  tr->kd = kd;
  tr->mem = mem;
  if (layout) tr->layout = *layout;
  else trace_layout_default(&tr->layout);
}

/* Shared loop of trace_closest (any_hit false) and trace_any (true). Hits are
 * accepted against the ray's whole (tmin, best t) range, not the node's
 * interval; a node is skipped when the best hit lies before its interval. */
static inline __attribute__((always_inline)) bool traverse_n(struct trace_ctx *tr,
                                                             const struct ray *r, bool any_hit,
                                                             struct trace_hit *h, bool native) {
  h->t = r->tmax;
  h->prim = -1;
  h->b1 = h->b2 = 0.0f;
  const struct kd_tree *kd = tr->kd;
  if (!trav_ray_valid(r) || kd->node_count == 0) return false;
  struct trav_ray tv;
  if (!trav_setup(&tv, kd, r)) return false;
  struct trace_isect_ray ir;
  trace_isect_prepare(&ir, r->o, r->d);

  struct trav_entry stack[KD_DEPTH_LIMIT];
  int sp = 0;
  uint32_t ni = 0;
  float t0 = tv.t0, t1 = tv.t1;
  struct trav_best best;
  trav_best_init(&best, r->tmax);
  for (;;) {
    trav_visit_node(tr, ni, 1, native);
    struct kd_node nd = kd->nodes[ni];
    if (!kd_is_leaf(nd)) {
      if (trav_interior(&tv, nd, ni, &t0, &t1, &ni, stack, &sp)) continue;
    } else if (trav_leaf_n(tr, &ir, r->tmin, r->ignore_prim, any_hit, nd, 0, kd_leaf_count(nd),
                           &best, native)) {
      break; /* any_hit: the first hit */
    }
    /* Next node from the stack, skipping those entirely beyond the best hit. */
    if (!trav_pop(stack, &sp, 0, &best, &ni, &t0, &t1)) break;
  }
  trav_best_hit(&best, h);
  return best.found;
}

/* One copy of the loop for the native port (no backend calls inside), one for
 * the others. */
static bool traverse(struct trace_ctx *tr, const struct ray *r, bool any_hit, struct trace_hit *h) {
  if (tr->bvh) return bvh_traverse(tr, r, any_hit, h);
  if (!tr->mem.ops) return traverse_n(tr, r, any_hit, h, true);
  return traverse_n(tr, r, any_hit, h, false);
}

bool trace_closest(struct trace_ctx *tr, const struct ray *r, struct trace_hit *h) {
  return traverse(tr, r, false, h);
}

bool trace_any(struct trace_ctx *tr, const struct ray *r) {
  struct trace_hit h;
  return traverse(tr, r, true, &h);
}

/* Packet traversal. The per-ray arithmetic (setup, split distances, interval
 * updates, triangle test, hit rule) is that of traverse() above, so each ray
 * meets every node with the interval its own traversal would give it. Only the
 * order differs: the packet goes first to the near side of the majority of the
 * rays in the node, so a ray whose direction disagrees may test triangles its
 * own traversal would have skipped after an earlier hit. Such extra tests
 * cannot change the result: the hit rule is a total order over true hits, and
 * the node holding a ray's winning hit is never skipped (its interval starts at
 * or before the winning t, the property that makes traverse() agree with brute
 * force), so the minimum over a superset of triangles is the same hit. */

/* What one traversal step of a ray reads and writes: one cache line, as rays
 * active in a node are often few and scattered over the packet. */
struct pk_ray {
  float o[3], inv[3], tol[3]; /* struct trav_ray */
  float delta;
  float t0, t1;              /* interval in the current node */
  float tmin, upper, best_t; /* closest hit: upper = nextafter(best_t) once found */
  uint32_t nodes;            /* nodes the ray was active in */
};
_Static_assert(sizeof(struct pk_ray) == 64, "a packet ray's traversal state is one line");

struct pk_entry {
  uint32_t node;
  uint32_t base; /* first (t0, t1) pair of its rays in the pool */
  uint64_t mask; /* rays that need the node */
};

struct trace_packet {
  struct pk_ray ray[TRACE_PACKET_MAX];
  struct trace_isect_ray ir[TRACE_PACKET_MAX];
  uint32_t best_p[TRACE_PACKET_MAX], tris[TRACE_PACKET_MAX];
  int32_t ignore[TRACE_PACKET_MAX];
  uint64_t flat[3], pos[3], neg[3]; /* bit i: ray i does not move / moves up / down the axis */
  /* Deferred nodes; their rays' intervals packed in ascending ray order in a
   * LIFO pool (dense, so a deferred node of two rays touches one line). */
  struct pk_entry stack[KD_DEPTH_LIMIT];
  float pool[KD_DEPTH_LIMIT * TRACE_PACKET_MAX * 2];
  /* The packet's mailbox (host only, as trav_best's for single rays): the last
   * triangles tested, direct mapped, each with the rays it was tested against. */
  uint32_t mb_prim[TRAV_MBOX * 2];
  uint64_t mb_rays[TRAV_MBOX * 2];
  struct bvh_packet *bvh; /* a BVH's packet scratch, made at its first use */
  void *alloc;            /* what to free */
};

struct trace_packet *trace_packet_create(void) {
  char *p = xcalloc(1, sizeof(struct trace_packet) + 63);
  struct trace_packet *pk = (struct trace_packet *)(p + ((64 - (uintptr_t)p % 64) % 64));
  pk->alloc = p;
  return pk;
}

void trace_packet_destroy(struct trace_packet *pk) {
  if (!pk) return;
  bvh_packet_destroy(pk->bvh);
  free(pk->alloc);
}

#define PK_INLINE static inline __attribute__((always_inline))

/* The packet's rays set up for traversal: results cleared, the valid rays'
 * slab state and sign masks filled; the mask of live rays (ignore_prim set:
 * *ign). */
PK_INLINE uint64_t pk_setup(struct trace_ctx *tr, struct trace_packet *pk, const struct ray *rays,
                            uint32_t n, bool any_hit, struct trace_hit *hits, bool *occ,
                            uint64_t *ign) {
  const struct kd_tree *kd = tr->kd;
  uint64_t live = 0;
  *ign = 0;
  for (int a = 0; a < 3; a++) pk->flat[a] = pk->pos[a] = pk->neg[a] = 0;
  memset(pk->mb_prim, 0xff, sizeof pk->mb_prim);
  for (uint32_t i = 0; i < n; i++) {
    const struct ray *r = &rays[i];
    trav_clear_result(r, any_hit, &hits[i], &occ[i]);
    struct pk_ray *q = &pk->ray[i];
    q->nodes = 0;
    pk->tris[i] = 0;
    struct trav_ray tv;
    if (!trav_ray_valid(r) || kd->node_count == 0 || !trav_setup(&tv, kd, r)) continue;
    uint64_t bit = 1ull << i;
    live |= bit;
    for (int a = 0; a < 3; a++) {
      q->o[a] = tv.o[a];
      q->inv[a] = tv.inv[a];
      q->tol[a] = tv.tol[a];
      if (tv.flat[a]) pk->flat[a] |= bit;
      else if (tv.inv[a] > 0.0f) pk->pos[a] |= bit;
      else pk->neg[a] |= bit;
    }
    q->delta = tv.delta;
    q->t0 = tv.t0;
    q->t1 = tv.t1;
    q->tmin = r->tmin;
    q->upper = r->tmax;
    q->best_t = r->tmax;
    trace_isect_prepare(&pk->ir[i], r->o, r->d);
    pk->best_p[i] = 0;
    pk->ignore[i] = r->ignore_prim;
    if (r->ignore_prim >= 0) *ign |= bit;
  }
  return live;
}

/* The rays in act tested against leaf nd's triangles (one fetch a triangle
 * for the packet, a test a ray); a hit ends an any-hit ray (cleared from
 * *live) and improves a closest-hit ray's best (*found). */
PK_INLINE void pk_leaf(struct trace_ctx *tr, struct trace_packet *pk, struct kd_node nd,
                       uint64_t act, uint64_t ign, bool any_hit, struct trace_hit *hits, bool *occ,
                       uint64_t *live, uint64_t *found) {
  const struct scene *s = tr->scene;
  uint32_t off = kd_leaf_offset(nd), cnt = kd_leaf_count(nd);
  uint64_t m_leaf = act;
  for (uint64_t m = act; m; m &= m - 1) pk->ray[packet_mask_first(m)].nodes++;
  for (uint32_t j = 0; j < cnt && m_leaf; j++) {
    const uint32_t p = trav_leaf_prim(tr, off + j);
    uint64_t tm = m_leaf;
    for (uint64_t m = tm & ign; m; m &= m - 1) {
      int i = packet_mask_first(m);
      if ((int64_t)p == (int64_t)pk->ignore[i]) tm &= ~(1ull << i);
    }
    if (!tm) continue;
    const uint32_t k = packet_mask_count(tm);
    trav_announce_tri(tr, p, k);
    const struct scene_tri *tri = &s->tris[p];
    const vec3 v0 = tri->v[0], v1 = tri->v[1], v2 = tri->v[2];
    /* Rays tested against p before skip the arithmetic (see trav_best). */
    const uint32_t slot = p & (2 * TRAV_MBOX - 1);
    if (pk->mb_prim[slot] != p) {
      pk->mb_prim[slot] = p;
      pk->mb_rays[slot] = 0;
    }
    const uint64_t seen = pk->mb_rays[slot];
    pk->mb_rays[slot] |= tm;
    for (uint64_t m = tm; m; m &= m - 1) {
      const int i = packet_mask_first(m);
      const uint64_t bit = 1ull << i;
      struct pk_ray *q = &pk->ray[i];
      pk->tris[i]++;
      if (seen & bit) continue;
      float t, b1, b2;
      if (!trace_isect_tri(&pk->ir[i], v0, v1, v2, q->tmin, q->upper, &t, &b1, &b2)) continue;
      if (any_hit) {
        occ[i] = true;
        *live &= ~bit;
        m_leaf &= ~bit;
        continue;
      }
      if (trav_hit_wins((*found & bit) != 0, t, p, q->best_t, pk->best_p[i])) {
        *found |= bit;
        q->best_t = t;
        q->upper = float_next_up(t); /* equal t still competes on prim id */
        pk->best_p[i] = p;
        hits[i].t = t;
        hits[i].prim = (int32_t)p;
        hits[i].b1 = b1;
        hits[i].b2 = b2;
      }
    }
  }
}

/* The next node from the stack, with the rays still live and not beyond
 * their best hit there (their intervals restored from the pool); 0 when the
 * stack runs out. */
PK_INLINE uint64_t pk_pop(struct trace_packet *pk, int *sp, uint32_t *ptop, uint32_t *ni,
                          uint64_t live) {
  uint64_t act = 0;
  while (*sp > 0 && !act) {
    (*sp)--;
    const struct pk_entry *e = &pk->stack[*sp];
    const float *pool = pk->pool + e->base;
    *ptop = e->base;
    uint32_t k = 0;
    for (uint64_t m = e->mask; m; m &= m - 1, k += 2) {
      const int i = packet_mask_first(m);
      const uint64_t bit = 1ull << i;
      struct pk_ray *q = &pk->ray[i];
      if (!(live & bit) || q->best_t < pool[k]) continue;
      act |= bit;
      q->t0 = pool[k];
      q->t1 = pool[k + 1];
    }
    *ni = e->node;
  }
  return act;
}

/* Shared loop of trace_packet_closest (any_hit false: hits) and
 * trace_packet_any (true: occ): the packet goes down the tree together, each
 * node fetched once for the rays that need it. */
static inline void packet_traverse(struct trace_ctx *tr, struct trace_packet *pk,
                                   const struct ray *rays, uint32_t n, bool any_hit,
                                   struct trace_hit *hits, bool *occ,
                                   struct trace_packet_cost *cost) {
  CHECK_LE(n, TRACE_PACKET_MAX);
  if (tr->bvh) {
    if (!pk->bvh) pk->bvh = bvh_packet_create();
    bvh_packet_traverse(tr, pk->bvh, rays, n, any_hit, hits, occ, cost);
    return;
  }
  const struct kd_tree *kd = tr->kd;
  uint64_t ign, found = 0;
  uint64_t live = pk_setup(tr, pk, rays, n, any_hit, hits, occ, &ign);
  int sp = 0;
  uint32_t ptop = 0; /* pool in use */
  uint32_t ni = 0;
  uint64_t act = live;
  while (live) {
    /* One fetch of the node for the packet; the work of every ray needing it. */
    trav_announce_node(tr, ni, packet_mask_count(act));
    struct kd_node nd = kd->nodes[ni];
    if (!kd_is_leaf(nd)) {
      const uint32_t below = ni + 1, above = kd_above(nd);
      /* Near side of the majority of the rays here (fewest out-of-order rays). */
      const int a = kd_axis(nd);
      const uint64_t up = act & pk->pos[a], down = act & pk->neg[a];
      const bool bf = !down || (up && packet_mask_count(up) >= packet_mask_count(down));
      CHECK_LT(sp, KD_DEPTH_LIMIT);
      float *restrict pool = pk->pool + ptop; /* the second child's intervals */
      const float split = kd_split(nd);
      const uint64_t flat = pk->flat[a];
      uint32_t k = 0;
      uint64_t mf = 0, ms = 0;
      for (uint64_t m = act; m; m &= m - 1) {
        const int i = packet_mask_first(m);
        struct pk_ray *restrict q = &pk->ray[i];
        q->nodes++;
        const float r0 = q->t0, r1 = q->t1;
        float x0, x1, y0, y1; /* intervals in the first and second child */
        bool vx, vy;
        const float ts = (split - q->o[a]) * q->inv[a];
        const float lo_t = ts - q->tol[a], hi_t = ts + q->tol[a];
        if (!((flat >> i) & 1u) && !isnan(lo_t) && !isnan(hi_t)) {
          /* Written as selects: incoherent rays make these branches a coin toss. */
          const float n1 = hi_t < r1 ? hi_t : r1, f0 = lo_t > r0 ? lo_t : r0;
          const bool vn = r0 <= hi_t, vf = lo_t <= r1;
          const bool near_first = (q->inv[a] > 0.0f) == bf; /* below is near if inv > 0 */
          x0 = near_first ? r0 : f0;
          x1 = near_first ? n1 : r1;
          vx = near_first ? vn : vf;
          y0 = near_first ? f0 : r0;
          y1 = near_first ? r1 : n1;
          vy = near_first ? vf : vn;
        } else {
          /* Parallel to the plane (the side(s) within the slack) or NaN (both). */
          bool vb = true, va = true;
          if ((flat >> i) & 1u) {
            vb = q->o[a] - split <= q->delta;
            va = split - q->o[a] <= q->delta;
          }
          x0 = y0 = r0;
          x1 = y1 = r1;
          vx = bf ? vb : va;
          vy = bf ? va : vb;
        }
        /* Skip a side entirely beyond the ray's best hit, as traverse() does
         * (best_t is tmax, beyond every interval, until a hit is found). */
        vx = vx && !(q->best_t < x0);
        vy = vy && !(q->best_t < y0);
        /* Unconditional stores: a ray's current interval is dead after this
         * node, and pool slots past k are free. */
        q->t0 = x0;
        q->t1 = x1;
        pool[k] = y0;
        pool[k + 1] = y1;
        k += vy ? 2u : 0u;
        mf |= (uint64_t)vx << i;
        ms |= (uint64_t)vy << i;
      }
      const uint32_t first = bf ? below : above, second = bf ? above : below;
      if (mf) {
        if (ms) {
          pk->stack[sp].node = second;
          pk->stack[sp].base = ptop;
          pk->stack[sp].mask = ms;
          sp++;
          ptop += k;
        }
        ni = first;
        act = mf;
        continue;
      }
      if (ms) {
        k = 0;
        for (uint64_t m = ms; m; m &= m - 1, k += 2) {
          struct pk_ray *q = &pk->ray[packet_mask_first(m)];
          q->t0 = pool[k];
          q->t1 = pool[k + 1];
        }
        ni = second;
        act = ms;
        continue;
      }
    } else {
      pk_leaf(tr, pk, nd, act, ign, any_hit, hits, occ, &live, &found);
    }
    act = pk_pop(pk, &sp, &ptop, &ni, live);
    if (!act) break;
  }
  if (cost)
    for (uint32_t i = 0; i < n; i++) {
      cost->nodes[i] = pk->ray[i].nodes;
      cost->tris[i] = pk->tris[i];
    }
}
#undef PK_INLINE

void trace_packet_closest(struct trace_ctx *tr, struct trace_packet *pk, const struct ray *rays,
                          uint32_t n, struct trace_hit *hits, struct trace_packet_cost *cost) {
  packet_traverse(tr, pk, rays, n, false, hits, NULL, cost);
}

void trace_packet_any(struct trace_ctx *tr, struct trace_packet *pk, const struct ray *rays,
                      uint32_t n, bool *occluded, struct trace_packet_cost *cost) {
  packet_traverse(tr, pk, rays, n, true, NULL, occluded, cost);
}

bool trace_brute(const struct scene *s, const struct ray *r, struct trace_hit *h) {
  h->t = r->tmax;
  h->prim = -1;
  h->b1 = h->b2 = 0.0f;
  if (!trav_ray_valid(r)) return false;
  struct trace_isect_ray ir;
  trace_isect_prepare(&ir, r->o, r->d);
  struct trav_best best;
  trav_best_init(&best, r->tmax);
  for (uint32_t p = 0; p < s->tri_count; p++) {
    if ((int64_t)p == (int64_t)r->ignore_prim) continue;
    const struct scene_tri *tri = &s->tris[p];
    float t, b1, b2;
    if (trace_isect_tri(&ir, tri->v[0], tri->v[1], tri->v[2], r->tmin, best.upper, &t, &b1, &b2))
      trav_best_offer(&best, t, p, b1, b2);
  }
  trav_best_hit(&best, h);
  return best.found;
}

vec3 trace_hit_point(const struct scene *s, const struct trace_hit *h, vec3 *err) {
  CHECK_GE(h->prim, 0);
  CHECK_LT((uint32_t)h->prim, s->tri_count);
  const struct scene_tri *tri = &s->tris[h->prim];
  float b0 = 1.0f - h->b1 - h->b2;
  vec3 p0 = v3_scale(tri->v[0], b0), p1 = v3_scale(tri->v[1], h->b1),
       p2 = v3_scale(tri->v[2], h->b2);
  vec3 p = v3_add(v3_add(p0, p1), p2);
  if (err) {
    float g = gamma_f(7);
    *err = v3(g * (fabsf(p0.x) + fabsf(p1.x) + fabsf(p2.x)),
              g * (fabsf(p0.y) + fabsf(p1.y) + fabsf(p2.y)),
              g * (fabsf(p0.z) + fabsf(p1.z) + fabsf(p2.z)));
  }
  return p;
}

vec3 trace_geom_normal(const struct scene *s, const struct trace_hit *h) {
  CHECK_GE(h->prim, 0);
  CHECK_LT((uint32_t)h->prim, s->tri_count);
  const struct scene_tri *tri = &s->tris[h->prim];
  vec3 n = v3_cross(v3_sub(tri->v[1], tri->v[0]), v3_sub(tri->v[2], tri->v[0]));
  float l = v3_len(n);
  return l > 0.0f ? v3_scale(n, 1.0f / l) : v3(0, 0, 0);
}

vec3 trace_offset_origin(vec3 p, vec3 err, vec3 n, vec3 d) {
  float dist = fabsf(n.x) * err.x + fabsf(n.y) * err.y + fabsf(n.z) * err.z;
  vec3 off = v3_scale(n, dist);
  if (v3_dot(d, n) < 0.0f) off = v3_scale(off, -1.0f);
  vec3 po = v3_add(p, off);
  /* Round away from p so the offset survives the addition's rounding. */
  float pc[3] = {po.x, po.y, po.z}, oc[3] = {off.x, off.y, off.z};
  for (int i = 0; i < 3; i++) {
    if (oc[i] > 0.0f) pc[i] = nextafterf(pc[i], INFINITY);
    else if (oc[i] < 0.0f) pc[i] = nextafterf(pc[i], -INFINITY);
  }
  return v3(pc[0], pc[1], pc[2]);
}
