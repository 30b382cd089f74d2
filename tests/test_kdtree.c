/* k-d tree tests. Oracles: brute force over all triangles (same primitive and
 * bit-identical t, b1, b2 for trace_closest; same answer for trace_any) on
 * random soups, soups whose coordinates coincide so splits fall on faces,
 * soups whose every coordinate has an odd mantissa, axis-aligned voxel meshes
 * and the procedural scenes; and a walk of the tree with node boxes checking
 * that each leaf holds every triangle overlapping it, that the queue-point bit
 * is clear, and that the stats add up. */
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "renderer/kdtree.h"
#include "renderer/ray.h"
#include "renderer/rng.h"
#include "renderer/scene.h"
#include "renderer/scene/gen.h"
#include "renderer/trace.h"
#include "testing.h"

static float rnd(struct rng *g, float lo, float hi) { return lo + (hi - lo) * rng_f32(g); }
static uint32_t rnd_u(struct rng *g, uint32_t n) { return n ? rng_u32(g) % n : 0; }
/* NOTE: a vector's draws one a statement, z first (the cases were tuned with
 * gcc, which took v3's three arguments last first; clang takes them first
 * first, and C leaves it open). */
static vec3 rnd_v3(struct rng *g, float lo, float hi) {
  float z = rnd(g, lo, hi);
  float y = rnd(g, lo, hi);
  float x = rnd(g, lo, hi);
  return v3(x, y, z);
}
/* A point lo + ext * (u, u, u), u in [0, 1), z drawn first as in rnd_v3. */
static vec3 rnd_in(struct rng *g, vec3 lo, vec3 ext) {
  float uz = rng_f32(g);
  float uy = rng_f32(g);
  float ux = rng_f32(g);
  return v3(lo.x + ext.x * ux, lo.y + ext.y * uy, lo.z + ext.z * uz);
}

static uint32_t fbits(float f) {
  uint32_t u;
  memcpy(&u, &f, sizeof u);
  return u;
}

static float v3_at(vec3 v, int a) { return a == 0 ? v.x : (a == 1 ? v.y : v.z); }
static void v3_put(vec3 *v, int a, float f) {
  if (a == 0) v->x = f;
  else if (a == 1) v->y = f;
  else v->z = f;
}

/* ---- scenes ---------------------------------------------------------------- */

/* Small random triangles in [-1,1]^3, some long and thin, some degenerate. */
static void soup_random(struct scene *s, uint64_t seed, int n) {
  struct rng g = rng_make(seed, 1);
  for (int i = 0; i < n; i++) {
    vec3 c = rnd_v3(&g, -1, 1);
    float sz = i % 10 == 0 ? 1.0f : rnd(&g, 0.02f, 0.25f);
    vec3 v[3];
    for (int k = 0; k < 3; k++) v[k] = v3_add(c, rnd_v3(&g, -sz, sz));
    if (i % 37 == 0) v[2] = v[1];                               /* repeated vertex */
    if (i % 41 == 0) v[2] = v3_sub(v3_scale(v[1], 2.0f), v[0]); /* collinear-ish */
    scene_add_tri(s, v[0], v[1], v[2], NULL, 0);
  }
}

/* Vertices on the grid k/4 (or, with odd set, the same values with the lowest
 * mantissa bit set, which the builder once had to step aside). Many triangles
 * share coordinates; a quarter lie in an axis-aligned plane; some are
 * degenerate or exact duplicates. */
static float grid_value(int k, bool odd) {
  float f = 1.0f + (float)k * 0.25f;
  if (odd) {
    uint32_t u = fbits(f) | 1u;
    memcpy(&f, &u, sizeof f);
  }
  return f;
}

static void soup_grid(struct scene *s, uint64_t seed, int n, bool odd) {
  struct rng g = rng_make(seed, 2);
  for (int i = 0; i < n; i++) {
    if (i > 10 && i % 23 == 0) { /* exact duplicate of an earlier triangle */
      const struct scene_tri *t = &s->tris[rnd_u(&g, s->tri_count)];
      vec3 a = t->v[0], b = t->v[1], c = t->v[2];
      scene_add_tri(s, a, b, c, NULL, 0);
      continue;
    }
    int base[3];
    for (int a = 0; a < 3; a++) base[a] = (int)rnd_u(&g, 13) + 2;
    int flat_axis = i % 4 == 0 ? (int)rnd_u(&g, 3) : -1;
    vec3 v[3];
    for (int k = 0; k < 3; k++)
      for (int a = 0; a < 3; a++) {
        int off = a == flat_axis ? 0 : (int)rnd_u(&g, 5) - 2;
        v3_put(&v[k], a, grid_value(base[a] + off, odd));
      }
    scene_add_tri(s, v[0], v[1], v[2], NULL, 0);
  }
}

/* Axis-aligned voxel columns on a W x W grid, heights 0..4: tops, sides and a
 * floor, two triangles per unit face; coordinates (i * scale + offset). */
static void voxels(struct scene *s, uint64_t seed, int w, float scale, float offset) {
  struct rng g = rng_make(seed, 3);
  int *h = calloc((size_t)(w + 2) * (size_t)(w + 2), sizeof *h);
#define H(x, y) h[(size_t)((y) + 1) * (size_t)(w + 2) + (size_t)((x) + 1)]
  for (int y = 0; y < w; y++)
    for (int x = 0; x < w; x++) H(x, y) = (int)rnd_u(&g, 5);
#define P(x, y, z)                                                                                 \
  v3((float)(x)*scale + offset, (float)(y)*scale + offset, (float)(z)*scale + offset)
  for (int y = 0; y < w; y++)
    for (int x = 0; x < w; x++) {
      int z = H(x, y);
      scene_add_tri(s, P(x, y, z), P(x + 1, y, z), P(x + 1, y + 1, z), NULL, 0);
      scene_add_tri(s, P(x, y, z), P(x + 1, y + 1, z), P(x, y + 1, z), NULL, 0);
      if (z == 0) continue;
      /* Side faces toward lower neighbours (outside the grid counts as 0). */
      int nb[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
      for (int k = 0; k < 4; k++) {
        int zn = H(x + nb[k][0], y + nb[k][1]);
        if (zn >= z) continue;
        int x0 = nb[k][0] == 1 ? x + 1 : x, y0 = nb[k][1] == 1 ? y + 1 : y;
        int x1 = nb[k][0] != 0 ? x0 : x0 + 1, y1 = nb[k][1] != 0 ? y0 : y0 + 1;
        scene_add_tri(s, P(x0, y0, zn), P(x1, y1, zn), P(x1, y1, z), NULL, 0);
        scene_add_tri(s, P(x0, y0, zn), P(x1, y1, z), P(x0, y0, z), NULL, 0);
      }
    }
#undef P
#undef H
  free(h);
}

/* ---- tree structure -------------------------------------------------------- */

struct walk_entry {
  uint32_t node;
  float lo[3], hi[3];
  uint32_t depth;
};

struct tbox {
  float lo[3], hi[3];
};

static struct tbox *tri_boxes(const struct scene *s) {
  struct tbox *b = malloc((s->tri_count + 1) * sizeof *b);
  for (uint32_t p = 0; p < s->tri_count; p++)
    for (int a = 0; a < 3; a++) {
      float x = v3_at(s->tris[p].v[0], a), y = v3_at(s->tris[p].v[1], a),
            z = v3_at(s->tris[p].v[2], a);
      b[p].lo[a] = x < y ? (x < z ? x : z) : (y < z ? y : z);
      b[p].hi[a] = x > y ? (x > z ? x : z) : (y > z ? y : z);
    }
  return b;
}

/* A leaf must hold every triangle whose bounds overlap its box with positive
 * extent, or lie flat in the box (e.g. in one of its faces) along an axis. */
static bool must_hold(const struct tbox *t, const float lo[3], const float hi[3]) {
  for (int a = 0; a < 3; a++) {
    bool overlap = t->lo[a] < hi[a] && t->hi[a] > lo[a];
    bool in_face = t->lo[a] == t->hi[a] && lo[a] <= t->lo[a] && t->lo[a] <= hi[a];
    if (!overlap && !in_face) return false;
  }
  return true;
}

/* With perfect splits a leaf must hold every triangle that meets its box: the
 * box shrunk by a hair (1e-6 of its extent) along every axis the triangle is
 * not flat in, and closed along an axis it is flat in (a triangle lying in a
 * face belongs to the leaves on both sides). Separating-axis test (box axes,
 * triangle normal, the nine edge-by-axis crosses) in double. */
static bool meets_tri(const struct scene_tri *tri, const float lo[3], const float hi[3]) {
  double v[3][3], c[3], h[3];
  for (int a = 0; a < 3; a++) {
    double x0 = v3_at(tri->v[0], a), x1 = v3_at(tri->v[1], a), x2 = v3_at(tri->v[2], a);
    bool flat = x0 == x1 && x1 == x2;
    double e = flat ? 0.0 : 1e-6 * ((double)hi[a] - lo[a]);
    double l = lo[a] + e, u = hi[a] - e;
    if (l > u) return false;
    c[a] = 0.5 * (l + u);
    h[a] = 0.5 * (u - l);
    v[0][a] = x0 - c[a];
    v[1][a] = x1 - c[a];
    v[2][a] = x2 - c[a];
  }
  double axes[13][3];
  int na = 0;
  for (int a = 0; a < 3; a++) {
    double ax[3] = {0, 0, 0};
    ax[a] = 1;
    memcpy(axes[na++], ax, sizeof ax);
  }
  double ed[3][3];
  for (int k = 0; k < 3; k++)
    for (int a = 0; a < 3; a++) ed[k][a] = v[(k + 1) % 3][a] - v[k][a];
  axes[na][0] = ed[0][1] * ed[1][2] - ed[0][2] * ed[1][1];
  axes[na][1] = ed[0][2] * ed[1][0] - ed[0][0] * ed[1][2];
  axes[na][2] = ed[0][0] * ed[1][1] - ed[0][1] * ed[1][0];
  na++;
  for (int k = 0; k < 3; k++)
    for (int a = 0; a < 3; a++) {
      double u[3] = {0, 0, 0};
      u[a] = 1;
      axes[na][0] = ed[k][1] * u[2] - ed[k][2] * u[1];
      axes[na][1] = ed[k][2] * u[0] - ed[k][0] * u[2];
      axes[na][2] = ed[k][0] * u[1] - ed[k][1] * u[0];
      na++;
    }
  for (int i = 0; i < na; i++) {
    const double *n = axes[i];
    double p0 = n[0] * v[0][0] + n[1] * v[0][1] + n[2] * v[0][2];
    double p1 = n[0] * v[1][0] + n[1] * v[1][1] + n[2] * v[1][2];
    double p2 = n[0] * v[2][0] + n[1] * v[2][1] + n[2] * v[2][2];
    double mn = fmin(p0, fmin(p1, p2)), mx = fmax(p0, fmax(p1, p2));
    double r = h[0] * fabs(n[0]) + h[1] * fabs(n[1]) + h[2] * fabs(n[2]);
    if (mn > r || mx < -r) return false;
  }
  return true;
}

static bool touches(const struct tbox *t, const float lo[3], const float hi[3]) {
  for (int a = 0; a < 3; a++)
    if (t->lo[a] > hi[a] || t->hi[a] < lo[a]) return false;
  return true;
}

static int cmp_float(const void *x, const void *y) {
  float a = *(const float *)x, b = *(const float *)y;
  return (a > b) - (a < b);
}

static int pbrt_max_depth(uint32_t n) {
  int lg = 0;
  while (n >> (lg + 1)) lg++;
  return (int)lroundf(8.0f + 1.3f * (float)lg);
}

/* Walk the tree with node boxes; returns the number of splits that differ from
 * every vertex coordinate (with clipping, a clipped bound; without, none). */
static uint32_t check_structure(const char *name, const struct scene *s, const struct kd_tree *kd,
                                int max_depth, bool clip) {
  uint32_t n = s->tri_count;
  struct tbox *tb = tri_boxes(s);
  float *coords[3]; /* sorted vertex coordinates per axis */
  for (int a = 0; a < 3; a++) {
    coords[a] = malloc((3 * (size_t)n + 1) * sizeof *coords[a]);
    for (uint32_t p = 0; p < n; p++)
      for (int k = 0; k < 3; k++) coords[a][3 * p + k] = v3_at(s->tris[p].v[k], a);
    qsort(coords[a], 3 * (size_t)n, sizeof *coords[a], cmp_float);
  }
  uint8_t *seen = calloc(kd->node_count ? kd->node_count : 1, 1);
  uint8_t *in_leaf = calloc(n ? n : 1, 1);
  struct walk_entry *stack = malloc((KD_DEPTH_LIMIT + 2) * sizeof *stack);
  int sp = 0;
  stack[sp++] =
      (struct walk_entry){0, {kd->lo.x, kd->lo.y, kd->lo.z}, {kd->hi.x, kd->hi.y, kd->hi.z}, 0};
  uint32_t nodes = 0, leaves = 0, empty = 0, maxd = 0, maxp = 0, off_bound = 0;
  uint64_t refs = 0;
  int errors = 0;
  while (sp > 0 && errors < 20) {
    struct walk_entry e = stack[--sp];
    if (e.node >= kd->node_count || seen[e.node]) {
      EXPECTF(0, "%s: node %u out of range or reached twice", name, e.node);
      errors++;
      continue;
    }
    seen[e.node] = 1;
    nodes++;
    struct kd_node nd = kd->nodes[e.node];
    EXPECTF(!(nd.w1 & 4u), "%s: node %u has bit 2 of w1 set (it is unused)", name, e.node);
    if (!kd_is_leaf(nd)) {
      int a = kd_axis(nd);
      float sp_v = kd_split(nd);
      EXPECTF(fbits(sp_v) == nd.w0, "%s: node %u split bits %08x", name, e.node, nd.w0);
      if (!(sp_v > e.lo[a] && sp_v < e.hi[a])) {
        EXPECTF(0, "%s: node %u split %.9g outside (%.9g, %.9g)", name, e.node, sp_v, e.lo[a],
                e.hi[a]);
        errors++;
      }
      bool on_bound = bsearch(&sp_v, coords[a], 3 * (size_t)n, sizeof *coords[a], cmp_float);
      off_bound += !on_bound;
      EXPECTF(kd_above(nd) > e.node + 1, "%s: node %u above child %u", name, e.node, kd_above(nd));
      if (sp + 2 > KD_DEPTH_LIMIT + 2) break;
      struct walk_entry b = e, ab = e;
      b.node = e.node + 1;
      b.hi[a] = sp_v;
      b.depth = e.depth + 1;
      ab.node = kd_above(nd);
      ab.lo[a] = sp_v;
      ab.depth = e.depth + 1;
      stack[sp++] = ab;
      stack[sp++] = b;
      continue;
    }
    leaves++;
    uint32_t off = kd_leaf_offset(nd), cnt = kd_leaf_count(nd);
    empty += cnt == 0;
    if (cnt > maxp) maxp = cnt;
    if (e.depth > maxd) maxd = e.depth;
    refs += cnt;
    if ((uint64_t)off + cnt > kd->prim_ref_count) {
      EXPECTF(0, "%s: leaf %u list out of range", name, e.node);
      errors++;
      continue;
    }
    for (uint32_t j = 0; j < cnt; j++) {
      uint32_t p = kd->prims[off + j];
      EXPECTF(p < n && (j == 0 || kd->prims[off + j - 1] < p), "%s: leaf %u bad list", name,
              e.node);
      if (p >= n) continue;
      in_leaf[p] = 1;
      if (!touches(&tb[p], e.lo, e.hi)) {
        EXPECTF(0, "%s: leaf %u holds triangle %u outside its box", name, e.node, p);
        errors++;
      }
    }
    for (uint32_t p = 0; p < n; p++) {
      if (!in_leaf[p] && (clip ? must_hold(&tb[p], e.lo, e.hi) && meets_tri(&s->tris[p], e.lo, e.hi)
                               : must_hold(&tb[p], e.lo, e.hi))) {
        EXPECTF(0, "%s: leaf %u (depth %u) misses triangle %u overlapping it", name, e.node,
                e.depth, p);
        errors++;
      }
    }
    for (uint32_t j = 0; j < cnt; j++)
      if (kd->prims[off + j] < n) in_leaf[kd->prims[off + j]] = 0;
  }
  EXPECTF(nodes == kd->node_count && nodes == kd->stats.nodes, "%s: %u nodes reached, %u stored",
          name, nodes, kd->node_count);
  EXPECTF(leaves == kd->stats.leaves && empty == kd->stats.empty_leaves &&
              maxd == kd->stats.max_depth && maxp == kd->stats.max_leaf_prims &&
              refs == kd->stats.leaf_prim_refs && refs == kd->prim_ref_count,
          "%s: stats mismatch", name);
  EXPECTF((int)maxd <= max_depth, "%s: depth %u > %d", name, maxd, max_depth);
  free(seen);
  free(in_leaf);
  free(stack);
  free(tb);
  for (int a = 0; a < 3; a++) free(coords[a]);
  return off_bound;
}

/* ---- rays against brute force ---------------------------------------------- */

struct ray_result {
  int32_t prim;
  uint32_t t, b1, b2;
  bool any;
};

static void split_values(const struct kd_tree *kd, float **vals, int **axes, uint32_t *count) {
  *vals = malloc((kd->node_count + 1) * sizeof **vals);
  *axes = malloc((kd->node_count + 1) * sizeof **axes);
  *count = 0;
  for (uint32_t i = 0; i < kd->node_count; i++)
    if (!kd_is_leaf(kd->nodes[i])) {
      (*vals)[*count] = kd_split(kd->nodes[i]);
      (*axes)[*count] = kd_axis(kd->nodes[i]);
      (*count)++;
    }
}

static struct ray make_test_ray(struct rng *g, const struct scene *s, const struct kd_tree *kd,
                                const float *svals, const int *saxes, uint32_t nsplit, int i) {
  vec3 lo = kd->lo, hi = kd->hi, ext = v3_sub(hi, lo);
  vec3 mid = v3_scale(v3_add(lo, hi), 0.5f);
  struct ray r;
  memset(&r, 0, sizeof r);
  r.ignore_prim = -1;
  r.tmin = 0.0f;
  r.tmax = INFINITY;
  int ok = i % 5;
  int split_axis = -1;
  vec3 o;
  switch (ok) {
  case 0: /* inside the bounds */ o = rnd_in(g, lo, ext); break;
  case 1: /* anywhere in 3x the bounds */
    o = v3_add(mid, v3_mul(ext, rnd_v3(g, -1.5f, 1.5f)));
    break;
  case 2: /* exactly on a split plane */
    o = rnd_in(g, lo, ext);
    if (nsplit) {
      uint32_t k = rnd_u(g, nsplit);
      split_axis = saxes[k];
      v3_put(&o, split_axis, svals[k]);
    }
    break;
  case 3: { /* at a vertex, moved along one or two axes (lies in the grid's planes) */
    const struct scene_tri *t = &s->tris[rnd_u(g, s->tri_count)];
    o = t->v[rnd_u(g, 3)];
    int a = (int)rnd_u(g, 3);
    v3_put(&o, a, v3_at(o, a) + v3_at(ext, a) * rnd(g, -1.2f, 1.2f));
    if (rng_u32(g) & 1) {
      int b = (a + 1 + (int)rnd_u(g, 2)) % 3;
      v3_put(&o, b, v3_at(o, b) + v3_at(ext, b) * rnd(g, -1.2f, 1.2f));
    }
    break;
  }
  default: /* outside, on a box face plane */
    o = v3_add(mid, v3_mul(ext, rnd_v3(g, -1, 1)));
    bool low = rng_u32(g) & 1; /* drawn before the axis (rnd_v3) */
    v3_put(&o, (int)rnd_u(g, 3), low ? v3_at(lo, (int)(i % 3)) : v3_at(hi, (int)(i % 3)));
    break;
  }
  vec3 d;
  int dk = (i / 5) % 6;
  switch (dk) {
  case 0: d = rnd_v3(g, -1, 1); break;
  case 1: { /* axis-aligned */
    d = v3(0, 0, 0);
    bool up = rng_u32(g) & 1; /* drawn before the axis (rnd_v3) */
    v3_put(&d, (int)rnd_u(g, 3), up ? 1.0f : -1.0f);
    break;
  }
  case 2: /* one zero component; in the split plane when o is on one */
    d = rnd_v3(g, -1, 1);
    v3_put(&d, split_axis >= 0 ? split_axis : (int)rnd_u(g, 3), 0.0f);
    break;
  case 3: { /* at a random point of a random triangle */
    const struct scene_tri *t = &s->tris[rnd_u(g, s->tri_count)];
    float u = rng_f32(g), v = rng_f32(g);
    if (u + v > 1) {
      u = 1 - u;
      v = 1 - v;
    }
    vec3 q = v3_add(t->v[0], v3_add(v3_scale(v3_sub(t->v[1], t->v[0]), u),
                                    v3_scale(v3_sub(t->v[2], t->v[0]), v)));
    d = v3_sub(q, o);
    break;
  }
  case 4: { /* at a vertex or an edge midpoint exactly */
    const struct scene_tri *t = &s->tris[rnd_u(g, s->tri_count)];
    int k = (int)rnd_u(g, 3);
    vec3 q = (rng_u32(g) & 1) ? t->v[k] : v3_scale(v3_add(t->v[k], t->v[(k + 1) % 3]), 0.5f);
    d = v3_sub(q, o);
    break;
  }
  default: { /* unnormalised, wide range of lengths; the length drawn first (rnd_v3) */
    float len = powf(10.0f, rnd(g, -3, 3));
    d = v3_scale(rnd_v3(g, -1, 1), len);
    break;
  }
  }
  if (d.x == 0 && d.y == 0 && d.z == 0) d = v3(0.3f, -0.2f, 1.0f);
  r.o = o;
  r.d = d;
  int tk = (i / 30) % 5;
  if (tk == 1) r.tmin = rnd(g, 0.0f, 1.0f);
  if (tk == 2) r.tmax = rnd(g, 0.1f, 2.0f);
  if (tk == 3) {
    r.tmin = rnd(g, 0.0f, 0.5f);
    r.tmax = r.tmin + rnd(g, 0.0f, 1.0f);
  }
  if (tk == 4) r.ignore_prim = (int32_t)rnd_u(g, s->tri_count);
  return r;
}

static struct ray_result result_of(bool hit, const struct trace_hit *h, bool any) {
  struct ray_result res;
  res.prim = hit ? h->prim : -1;
  res.t = hit ? fbits(h->t) : 0;
  res.b1 = hit ? fbits(h->b1) : 0;
  res.b2 = hit ? fbits(h->b2) : 0;
  res.any = any;
  return res;
}

/* Trace nrays rays with the tree and by brute force; also reruns them with
 * every node flagged as a queue point. Returns the number of hits. */
static int check_rays(const char *name, const struct scene *s, struct kd_tree *kd, int nrays,
                      uint64_t seed) {
  float *svals;
  int *saxes;
  uint32_t nsplit;
  split_values(kd, &svals, &saxes, &nsplit);
  struct trace_ctx tr;
  trace_init(&tr, s, kd, mem_port_native(), NULL);
  struct rng g = rng_make(seed, 4);
  struct ray *rays = malloc((size_t)nrays * sizeof *rays);
  struct ray_result *res = malloc((size_t)nrays * sizeof *res);
  int mism = 0, any_mism = 0, hits = 0;
  for (int i = 0; i < nrays; i++) {
    rays[i] = make_test_ray(&g, s, kd, svals, saxes, nsplit, i);
    struct trace_hit hb, ht;
    bool bb = trace_brute(s, &rays[i], &hb);
    bool bt = trace_closest(&tr, &rays[i], &ht);
    bool ba = trace_any(&tr, &rays[i]);
    struct ray_result rb = result_of(bb, &hb, bb), rt = result_of(bt, &ht, ba);
    res[i] = rt;
    hits += bb;
    if (rb.prim != rt.prim || rb.t != rt.t || rb.b1 != rt.b1 || rb.b2 != rt.b2) {
      if (mism < 5)
        fprintf(stderr,
                "%s ray %d: o (%.9g %.9g %.9g) d (%.9g %.9g %.9g) [%g %g] ign %d: brute %d t %.9g, "
                "tree %d t %.9g\n",
                name, i, rays[i].o.x, rays[i].o.y, rays[i].o.z, rays[i].d.x, rays[i].d.y,
                rays[i].d.z, rays[i].tmin, rays[i].tmax, rays[i].ignore_prim, hb.prim, hb.t,
                ht.prim, ht.t);
      mism++;
    }
    if (ba != bb) any_mism++;
  }
  EXPECTF(mism == 0, "%s: %d of %d rays differ from brute force", name, mism, nrays);
  EXPECTF(any_mism == 0, "%s: trace_any differs from brute force on %d rays", name, any_mism);
  EXPECTF(hits > nrays / 10, "%s: only %d of %d rays hit", name, hits, nrays);

  free(rays);
  free(res);
  free(svals);
  free(saxes);
  return hits;
}

static void run_scene(const char *name, const struct scene *s, const struct kd_build_params *bp,
                      int nrays, uint64_t seed) {
  EXPECTF(s->tri_count > 0, "%s: empty scene", name);
  if (s->tri_count == 0) return;
  struct kd_tree kd;
  kd_build(&kd, s, bp, NULL);
  int md = bp->max_depth < 0 ? pbrt_max_depth(s->tri_count) : bp->max_depth;
  check_structure(name, s, &kd, md, bp->clip);
  check_rays(name, s, &kd, nrays, seed);
  fprintf(stderr, "%s: %u tris, %u nodes, %u leaves (%u empty), depth %u, max leaf %u, refs %llu\n",
          name, s->tri_count, kd.stats.nodes, kd.stats.leaves, kd.stats.empty_leaves,
          kd.stats.max_depth, kd.stats.max_leaf_prims, (unsigned long long)kd.stats.leaf_prim_refs);
  kd_fini(&kd);
}

static void test_small_cases(void) {
  struct kd_build_params bp;
  kd_build_params_default(&bp);
  EXPECT(bp.cost_isect == 80.0f && bp.cost_traversal == 1.0f && bp.empty_bonus == 0.5f &&
         bp.max_prims == 1 && bp.max_depth < 0 && !bp.clip);
  /* Empty scene: one empty leaf; everything misses. */
  struct scene s;
  scene_init(&s);
  struct kd_tree kd;
  kd_build(&kd, &s, &bp, NULL);
  EXPECT(kd.node_count == 1 && kd_is_leaf(kd.nodes[0]) && kd_leaf_count(kd.nodes[0]) == 0);
  EXPECT(kd.stats.nodes == 1 && kd.stats.leaves == 1 && kd.stats.empty_leaves == 1);
  struct trace_ctx tr;
  trace_init(&tr, &s, &kd, mem_port_native(), NULL);
  struct ray r;
  memset(&r, 0, sizeof r);
  r.d = v3(0, 0, 1);
  r.tmax = INFINITY;
  r.ignore_prim = -1;
  struct trace_hit h;
  EXPECT(!trace_closest(&tr, &r, &h) && h.prim == -1 && !trace_any(&tr, &r));
  kd_fini(&kd);
  /* One triangle. */
  scene_add_tri(&s, v3(0, 0, 0), v3(1, 0, 0), v3(0, 1, 0), NULL, 0);
  kd_build(&kd, &s, &bp, NULL);
  EXPECT(kd.node_count == 1 && kd_leaf_count(kd.nodes[0]) == 1);
  trace_init(&tr, &s, &kd, mem_port_native(), NULL);
  r.o = v3(0.25f, 0.25f, -1);
  EXPECT(trace_closest(&tr, &r, &h) && h.prim == 0 && h.t == 1.0f && trace_any(&tr, &r));
  EXPECT(tr.stats.node_visits == 2 && tr.stats.tri_tests == 2);
  kd_fini(&kd);
  scene_fini(&s);
}

/* Scenes whose every coordinate has an odd mantissa: with whole bounds, every
 * split must be a vertex coordinate itself (stored exactly, never stepped to
 * a neighbouring float), and the tree stays exact. */
static void test_odd_mantissas(void) {
  struct kd_build_params bp;
  kd_build_params_default(&bp);
  struct scene s;
  scene_init(&s);
  soup_grid(&s, 31, 1500, true);
  bp.clip = false;
  struct kd_tree kd;
  kd_build(&kd, &s, &bp, NULL);
  uint32_t interior = kd.stats.nodes - kd.stats.leaves;
  uint32_t off = check_structure("odd soup", &s, &kd, pbrt_max_depth(s.tri_count), false);
  EXPECTF(interior > 100 && off == 0, "odd soup: %u of %u splits off the triangle bounds", off,
          interior);
  check_rays("odd soup", &s, &kd, 20000, 32);
  kd_fini(&kd);
  /* Clipped bounds are rounded outwards, odd or not: still exact. */
  bp.clip = true;
  run_scene("odd soup clipped", &s, &bp, 20000, 33);
  scene_fini(&s);
}

/* Triangle tests of n rays from random points of kd's root box in random
 * directions (the same rays for any tree over s with the same root box). */
static uint64_t tests_of(const struct scene *s, const struct kd_tree *kd, int n, uint64_t seed) {
  struct trace_ctx tr;
  trace_init(&tr, s, kd, mem_port_native(), NULL);
  struct rng g = rng_make(seed, 5);
  for (int i = 0; i < n; i++) {
    float o[3], d[3];
    for (int a = 0; a < 3; a++) {
      float lo = v3_at(kd->lo, a), hi = v3_at(kd->hi, a);
      o[a] = lo + (hi - lo) * rng_f32(&g);
      d[a] = 2.0f * rng_f32(&g) - 1.0f;
    }
    struct ray r = testing_make_ray(o[0], o[1], o[2], d[0], d[1], d[2], 0.0f, INFINITY);
    struct trace_hit h;
    trace_closest(&tr, &r, &h);
  }
  return tr.stats.tri_tests;
}

/* Perfect splits against whole bounds on one scene: both exact against brute
 * force, and clipping must cut the triangle tests of the same rays. (Not the
 * references: a clipped tree splits deeper, and on some scenes ends with more
 * references than the whole-bounds tree although its leaves are tighter.) */
static void compare_clip(const char *name, const struct scene *s, int nrays, uint64_t seed) {
  struct kd_build_params bp;
  kd_build_params_default(&bp);
  bp.clip = true;
  run_scene(name, s, &bp, nrays, seed);
  struct kd_tree kc, kw;
  kd_build(&kc, s, &bp, NULL);
  bp.clip = false;
  char wname[96];
  snprintf(wname, sizeof wname, "%s whole bounds", name);
  run_scene(wname, s, &bp, nrays, seed + 1);
  kd_build(&kw, s, &bp, NULL);
  uint64_t tc = tests_of(s, &kc, nrays, seed + 2), tw = tests_of(s, &kw, nrays, seed + 2);
  EXPECTF(tc < tw, "%s: clipping gave %llu triangle tests, whole bounds %llu", name,
          (unsigned long long)tc, (unsigned long long)tw);
  fprintf(stderr,
          "%s: triangle tests clipped %llu, whole %llu; references clipped %llu, whole %llu\n",
          name, (unsigned long long)tc, (unsigned long long)tw,
          (unsigned long long)kc.stats.leaf_prim_refs, (unsigned long long)kw.stats.leaf_prim_refs);
  kd_fini(&kc);
  kd_fini(&kw);
}

static void test_soups(void) {
  struct kd_build_params bp;
  kd_build_params_default(&bp);
  struct scene s;
  scene_init(&s);
  soup_random(&s, 41, 3000);
  compare_clip("random soup", &s, 20000, 42);
  scene_fini(&s);

  scene_init(&s);
  soup_grid(&s, 43, 2000, false);
  run_scene("grid soup", &s, &bp, 20000, 44);
  /* Other parameters: bigger leaves; a shallow tree. */
  struct kd_build_params bp2 = bp;
  bp2.max_prims = 6;
  run_scene("grid soup max_prims 6", &s, &bp2, 5000, 45);
  bp2 = bp;
  bp2.max_depth = 3;
  run_scene("grid soup depth 3", &s, &bp2, 5000, 46);
  scene_fini(&s);

  scene_init(&s);
  voxels(&s, 47, 24, 1.0f, 0.0f);
  run_scene("voxels", &s, &bp, 20000, 48);
  scene_fini(&s);

  scene_init(&s);
  voxels(&s, 49, 16, 0.1f, 1000.0f);
  run_scene("far voxels 0.1", &s, &bp, 10000, 50);
  scene_fini(&s);

  scene_init(&s);
  voxels(&s, 51, 16, 1e-4f, 0.0f);
  run_scene("voxels 1e-4", &s, &bp, 10000, 52);
  scene_fini(&s);
}

static void test_generated(void) {
  struct scene s;
  scene_init(&s);
  gen_sphereflake(&s, 1, 3);
  compare_clip("sphereflake 1", &s, 20000, 61);
  scene_fini(&s);
  scene_init(&s);
  gen_grove(&s, 0.02, 1);
  compare_clip("grove 0.02", &s, 20000, 62);
  scene_fini(&s);
  scene_init(&s);
  gen_room(&s, 0.05, 1);
  compare_clip("room 0.05", &s, 20000, 63);
  scene_fini(&s);
}

int main(void) {
  test_small_cases();
  test_odd_mantissas();
  test_soups();
  test_generated();
  return testing_done("test_kdtree");
}
