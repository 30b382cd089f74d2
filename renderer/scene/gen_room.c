/* Room: an architectural interior, 8 x 6 x 3 units (x 0..8, y 0..6, z up 0..3),
 * closed by inward-facing walls, floor and ceiling, with a window in the back
 * wall (y = 6), a door on the left wall (x = 0), a wall mirror on the right
 * wall (x = 8), furniture and many small objects. Like the paper's room, little
 * of it is visible from any one viewpoint.
 * Scaling: furniture is always built; "clutter" (cups, plates, vases, bowls,
 * balls, books) fills a fixed list of slots. Below detail 1 slots are thinned
 * in proportion to detail; above it tessellation alone grows. Which slots are filled depends on
 * detail, never on the seed, so the seed changes sizes and positions but not the triangle count. */
#include "renderer/scene/gen.h"

#include <math.h>
#include <stdbool.h>

#include "renderer/rng.h"
#include "renderer/scene.h"
#include "renderer/scene/gen_util.h"
#include "sim/err.h"

#define ROOM_X 8.0
#define ROOM_Y 6.0
#define ROOM_Z 3.0
/* Walls, floor and ceiling reach this far past the room's corners so that each
 * corner line lies inside a face, not on an edge shared with a T-junction:
 * a ray aimed at the corner cannot slip out between two planes. */
#define ROOM_OVERHANG 0.05
/* Clutter tessellation at detail 1, tuned so detail 1 gives about 47K
 * triangles: sides of cups, plates, vases and bowls; profile steps of vases
 * and bowls; quads per cube-face edge of balls. */
#define ROOM_LATHE_SIDES 36
#define ROOM_VASE_STEPS 14
#define ROOM_BOWL_STEPS 8
#define ROOM_BALL_TESS 8

struct room_ctx {
  struct scene *s;
  struct rng rng;
  double keep;        /* fraction of clutter slots filled, (0, 1] */
  double tess_scale;  /* multiplies clutter tessellation levels given at detail 1 */
  double fixed_scale; /* the same for furniture and fixtures, always built */
  uint64_t slot;      /* clutter slots met so far */
  uint32_t wall, floor_mat, ceiling, wood, fabric, metal, mirror, ceramic;
};

static double room_unif(struct room_ctx *c, double lo, double hi) {
  return lo + (hi - lo) * (double)rng_f32(&c->rng);
}

static uint32_t room_res_scaled(double base, double scale, uint32_t min) {
  double v = floor(base * scale + 0.5);
  return v < (double)min ? min : v > 256.0 ? 256u : (uint32_t)v;
}

/* Tessellation level of clutter, `base` at detail 1, clamped to [min, 256]. */
static uint32_t room_res(const struct room_ctx *c, double base, uint32_t min) {
  return room_res_scaled(base, c->tess_scale, min);
}

/* Tessellation level of furniture and fixtures (never thinned). */
static uint32_t room_res_fixed(const struct room_ctx *c, double base, uint32_t min) {
  return room_res_scaled(base, c->fixed_scale, min);
}

/* Whether the next clutter slot is filled. A golden-ratio sequence on the slot
 * index thins slots evenly over the whole room and independently of the seed. */
static bool room_slot_kept(uint64_t slot, double keep) {
  return fmod((double)slot * 0.6180339887498949, 1.0) < keep;
}

static bool room_keep(struct room_ctx *c) { return room_slot_kept(c->slot++, c->keep); }

static void room_box(struct room_ctx *c, double x0, double y0, double z0, double x1, double y1,
                     double z1, uint32_t mat) {
  gen_box_aa(c->s, gen_d3_make(x0, y0, z0), gen_d3_make(x1, y1, z1), mat);
}

/* Box with half extents (hx, hy, hz) centred at local (x, y, z) of frame f. */
static void room_box_in(struct room_ctx *c, const struct gen_frame *f, double x, double y, double z,
                        double hx, double hy, double hz, uint32_t mat) {
  struct gen_frame g = *f;
  g.o = gen_frame_point(f, x, y, z);
  gen_box(c->s, &g, hx, hy, hz, mat);
}

static void room_lathe_at(struct room_ctx *c, gen_d3 base, const double *r, const double *z,
                          uint32_t n, uint32_t sides, uint32_t mat) {
  struct gen_frame f = gen_frame_at(base);
  gen_lathe(c->s, &f, r, z, n, sides, mat);
}

/* ---- clutter: small objects of revolution, balls and books ---- */

static void room_cup(struct room_ctx *c, gen_d3 base, double rad, double h, uint32_t mat) {
  double t = 0.006;
  double r[6] = {0, rad, rad * 1.08, rad * 1.08 - t, rad - t, 0};
  double z[6] = {0, 0, h, h, t, t};
  room_lathe_at(c, base, r, z, 6, room_res(c, ROOM_LATHE_SIDES, 6), mat);
}

static void room_plate(struct room_ctx *c, gen_d3 base, double rad) {
  double r[6] = {0, rad * 0.6, rad, rad * 0.96, rad * 0.55, 0};
  double z[6] = {0, 0, 0.02, 0.022, 0.007, 0.007};
  room_lathe_at(c, base, r, z, 6, room_res(c, ROOM_LATHE_SIDES, 6), c->ceramic);
}

#define ROOM_MAX_PROFILE 80

/* A vase: outer silhouette sampled k+1 times from foot to lip, a lip, and a
 * shallow inner well. style picks the silhouette. */
static void room_vase(struct room_ctx *c, gen_d3 base, double rad, double h, int style,
                      uint32_t mat) {
  uint32_t k = room_res(c, ROOM_VASE_STEPS, 3);
  if (k > ROOM_MAX_PROFILE - 6) k = ROOM_MAX_PROFILE - 6;
  double r[ROOM_MAX_PROFILE], z[ROOM_MAX_PROFILE];
  uint32_t n = 0;
  r[n] = 0;
  z[n++] = 0;
  for (uint32_t i = 0; i <= k; i++) {
    double t = (double)i / k, sh;
    switch (style % 3) {
    case 0: /* round belly, narrow neck, flared lip */
      sh = 0.4 + 0.6 * sin(GEN_PI * fmin(t * 1.1, 1.0)) + 0.3 * t * t * t * t;
      break;
    case 1: /* tall and slightly tapered */ sh = 0.75 + 0.25 * cos(GEN_PI * t); break;
    default: /* amphora: widest high up */ sh = 0.45 + 0.55 * sin(GEN_PI * t * 0.8); break;
    }
    r[n] = rad * sh;
    z[n++] = h * t;
  }
  double lip = r[n - 1];
  r[n] = lip * 0.8;
  z[n++] = h;
  r[n] = lip * 0.8;
  z[n++] = h * 0.8;
  r[n] = 0;
  z[n++] = h * 0.8;
  room_lathe_at(c, base, r, z, n, room_res(c, ROOM_LATHE_SIDES, 6), mat);
}

/* A bowl on a small foot: outer and inner arcs of k steps each. */
static void room_bowl(struct room_ctx *c, gen_d3 base, double rad, uint32_t mat) {
  uint32_t k = room_res(c, ROOM_BOWL_STEPS, 2);
  if (k > (ROOM_MAX_PROFILE - 4) / 2 - 1) k = (ROOM_MAX_PROFILE - 4) / 2 - 1;
  double r[ROOM_MAX_PROFILE], z[ROOM_MAX_PROFILE];
  const double t = 0.008, a0 = 0.35, h = rad * 0.75;
  uint32_t n = 0;
  r[n] = 0;
  z[n++] = 0;
  for (uint32_t i = 0; i <= k; i++) { /* outer arc, foot to rim */
    double a = a0 + (0.5 * GEN_PI - a0) * (double)i / k;
    r[n] = rad * sin(a);
    z[n++] = h * (cos(a0) - cos(a)) / cos(a0);
  }
  for (uint32_t i = 0; i <= k; i++) { /* inner arc, rim down to the well */
    double a = 0.5 * GEN_PI - (0.5 * GEN_PI - a0) * (double)i / k;
    r[n] = (rad - t) * sin(a);
    z[n++] = t + (h - t) * (cos(a0) - cos(a)) / cos(a0);
  }
  r[n] = 0;
  z[n++] = t;
  room_lathe_at(c, base, r, z, n, room_res(c, ROOM_LATHE_SIDES, 6), mat);
}

static void room_ball(struct room_ctx *c, gen_d3 centre, double rad, uint32_t mat) {
  gen_sphere(c->s, centre, rad, room_res(c, ROOM_BALL_TESS, 2), mat);
}

/* A bowl of fruit-like balls on a surface at height z. Each piece is a slot. */
static void room_fruit_bowl(struct room_ctx *c, double x, double y, double z, double rad) {
  double ball_r[5];
  for (int i = 0; i < 5; i++) ball_r[i] = room_unif(c, 0.032, 0.042) * rad / 0.12;
  if (room_keep(c)) room_bowl(c, gen_d3_make(x, y, z), rad, c->ceramic);
  for (int i = 0; i < 5; i++) {
    /* Four around, one on top; they rest on the inner wall, roughly. */
    double a = i * 0.5 * GEN_PI + 0.3;
    double d = i < 4 ? rad * 0.42 : 0.0, zz = z + (i < 4 ? rad * 0.45 : rad * 0.75);
    if (room_keep(c))
      room_ball(c, gen_d3_make(x + d * cos(a), y + d * sin(a), zz), ball_r[i],
                i % 2 ? c->fabric : c->ceramic);
  }
}

/* A stack of `count` books lying flat, centred at (x, y) on height z. */
static void room_book_stack(struct room_ctx *c, double x, double y, double z, int count,
                            double max_w, double max_d) {
  for (int i = 0; i < count; i++) {
    double w = room_unif(c, 0.75, 1.0) * max_w, d = room_unif(c, 0.75, 1.0) * max_d;
    double th = room_unif(c, 0.025, 0.045), dx = room_unif(c, -0.02, 0.02);
    uint32_t mat = room_unif(c, 0, 1) < 0.5 ? c->fabric : c->wood;
    if (room_keep(c))
      room_box(c, x + dx - w / 2, y - d / 2, z, x + dx + w / 2, y + d / 2, z + th, mat);
    z += th;
  }
}

/* ---- bookcase rows ---- */

/* The bookcase's shelves, bottom up, in room_shelf_row's letters. */
#define ROOM_SHELVES 5
static const char *const room_shelf_rows[ROOM_SHELVES] = {
    "BBBBBBBBBBBBBBBBBBBBBBBBV", "BBBBBBBBBBBBBBOOBBBBBBBBBBC",
    "VBBBBBBBBBBBBBBBBSV",       "BBBBBBBBBBBBBBBBBBOCWBBBBBB",
    "CVBBBBBBBBBBBBOV",
};

enum room_item { ROOM_BOOK, ROOM_VASE, ROOM_BALL, ROOM_CUP, ROOM_STACK, ROOM_BOWL };

#define ROOM_ROW_MAX 48

/* Fill a shelf row x0..x1 (depth y0..y1, back at y1, floor z, clear height
 * hmax) with the items of `pattern` (B book, V vase, O ball, C cup, S stack,
 * W bowl), squeezed to fit and spaced evenly between non-book neighbours. */
static void room_shelf_row(struct room_ctx *c, double x0, double x1, double y0, double y1, double z,
                           double hmax, const char *pattern) {
  enum room_item kind[ROOM_ROW_MAX];
  double w[ROOM_ROW_MAX], a[ROOM_ROW_MAX], b[ROOM_ROW_MAX];
  int n = 0;
  double sum = 0;
  for (const char *p = pattern; *p && n < ROOM_ROW_MAX; p++) {
    switch (*p) {
    case 'B':
      kind[n] = ROOM_BOOK;
      w[n] = room_unif(c, 0.025, 0.05);
      break;
    case 'V':
      kind[n] = ROOM_VASE;
      w[n] = 2 * room_unif(c, 0.05, 0.08);
      break;
    case 'O':
      kind[n] = ROOM_BALL;
      w[n] = 2 * room_unif(c, 0.04, 0.07);
      break;
    case 'C':
      kind[n] = ROOM_CUP;
      w[n] = 2 * 0.045;
      break;
    case 'S':
      kind[n] = ROOM_STACK;
      w[n] = room_unif(c, 0.2, 0.26);
      break;
    case 'W':
      kind[n] = ROOM_BOWL;
      w[n] = 2 * 0.09;
      break;
    default: continue;
    }
    a[n] = room_unif(c, 0, 1);
    b[n] = room_unif(c, 0, 1);
    sum += w[n++];
  }
  double avail = x1 - x0, scale = sum > avail * 0.95 ? avail * 0.95 / sum : 1.0;
  int breaks = 0;
  for (int i = 0; i <= n; i++)
    if (i == 0 || i == n || kind[i - 1] != ROOM_BOOK || kind[i] != ROOM_BOOK) breaks++;
  double gap = (avail - sum * scale) / breaks, x = x0, yc = 0.5 * (y0 + y1);
  for (int i = 0; i < n; i++) {
    if (i == 0 || kind[i - 1] != ROOM_BOOK || kind[i] != ROOM_BOOK) x += gap;
    double wi = w[i] * scale, xc = x + wi / 2;
    switch (kind[i]) {
    case ROOM_BOOK: {
      double h = fmin(hmax * 0.92, (0.6 + 0.35 * a[i]) * hmax), d = (0.6 + 0.3 * b[i]) * (y1 - y0);
      uint32_t mat = a[i] < 0.2 ? c->ceramic : b[i] < 0.55 ? c->fabric : c->wood;
      /* Books stand a hair apart so neighbouring boxes never share a face. */
      if (room_keep(c)) room_box(c, x + 0.001, y1 - d, z, x + wi - 0.001, y1, z + h, mat);
      break;
    }
    case ROOM_VASE:
      if (room_keep(c))
        room_vase(c, gen_d3_make(xc, yc, z), wi / 2, fmin(hmax * 0.9, (0.5 + 0.4 * a[i]) * hmax),
                  (int)(b[i] * 3), c->ceramic);
      break;
    case ROOM_BALL:
      if (room_keep(c)) room_ball(c, gen_d3_make(xc, yc, z + wi / 2), wi / 2, c->fabric);
      break;
    case ROOM_CUP:
      if (room_keep(c)) room_cup(c, gen_d3_make(xc, yc, z), wi / 2 / 1.08, 0.09, c->ceramic);
      break;
    case ROOM_STACK: room_book_stack(c, xc, yc, z, 4, wi, (y1 - y0) * 0.8); break;
    case ROOM_BOWL:
      if (room_keep(c)) room_bowl(c, gen_d3_make(xc, yc, z), wi / 2, c->ceramic);
      break;
    }
    x += wi;
  }
}

/* ---- architecture ---- */

/* A wall plane on breakpoints us x vs along unit axes du, dv from o (du x dv
 * is the front), leaving out cell (hole_i, hole_j) (-1: none). Vertices are
 * shared by construction: each comes from one (i, j). */
static void room_wall(struct room_ctx *c, gen_d3 o, gen_d3 du, gen_d3 dv, const double *us, int nu,
                      const double *vs, int nv, int hole_i, int hole_j, uint32_t mat) {
  for (int j = 0; j + 1 < nv; j++)
    for (int i = 0; i + 1 < nu; i++) {
      if (i == hole_i && j == hole_j) continue;
      gen_d3 p[4];
      for (int k = 0; k < 4; k++) {
        int ci = i + (k == 1 || k == 2), cj = j + (k >= 2);
        p[k] = gen_d3_add(o, gen_d3_add(gen_d3_scale(du, us[ci]), gen_d3_scale(dv, vs[cj])));
      }
      gen_quad(c->s, p[0], p[1], p[2], p[3], mat);
    }
}

static void room_shell(struct room_ctx *c) {
  const double e = ROOM_OVERHANG, X = ROOM_X, Y = ROOM_Y, Z = ROOM_Z;
  gen_d3 ex = gen_d3_make(1, 0, 0), ey = gen_d3_make(0, 1, 0), ez = gen_d3_make(0, 0, 1);
  /* Floor (faces +z) and ceiling (faces -z), split so no triangle is huge. */
  gen_grid(c->s, gen_d3_make(-e, -e, 0), gen_d3_make(X + 2 * e, 0, 0), gen_d3_make(0, Y + 2 * e, 0),
           8, 6, c->floor_mat);
  gen_grid(c->s, gen_d3_make(-e, -e, Z), gen_d3_make(0, Y + 2 * e, 0), gen_d3_make(X + 2 * e, 0, 0),
           4, 4, c->ceiling);
  double zs[4] = {-e, 1.0, 2.2, Z + e};
  double xs_front[5] = {-e, 2.0, 4.0, 6.0, X + e};
  double ys[4] = {-e, 2.0, 4.0, Y + e};
  /* Front wall y = 0 (faces +y), left x = 0 (+x), right x = 8 (-x). */
  room_wall(c, gen_d3_make(0, 0, 0), ez, ex, zs, 4, xs_front, 5, -1, -1, c->wall);
  room_wall(c, gen_d3_make(0, 0, 0), ey, ez, ys, 4, zs, 4, -1, -1, c->wall);
  room_wall(c, gen_d3_make(X, 0, 0), ez, ey, zs, 4, ys, 4, -1, -1, c->wall);
  /* Back wall y = 6 (faces -y) with the window opening x 4.6..6.6, z 1..2.2. */
  double xs_back[6] = {-e, 1.5, 3.0, 4.6, 6.6, X + e};
  room_wall(c, gen_d3_make(0, Y, 0), ex, ez, xs_back, 6, zs, 4, 3, 1, c->wall);

  /* Baseboards. */
  room_box(c, 0, 0, 0, X, 0.015, 0.08, c->wood);
  room_box(c, 0, Y - 0.015, 0, X, Y, 0.08, c->wood);
  room_box(c, 0, 0.015, 0, 0.015, Y - 0.015, 0.08, c->wood);
  room_box(c, X - 0.015, 0.015, 0, X, Y - 0.015, 0.08, c->wood);

  /* Window frame, sill, mullion and transom; the opening shows the sky. */
  room_box(c, 4.5, 5.82, 0.95, 6.7, 6.06, 1.0, c->wood);
  room_box(c, 4.5, 5.9, 2.2, 6.7, 6.06, 2.28, c->wood);
  room_box(c, 4.52, 5.9, 1.0, 4.6, 6.06, 2.2, c->wood);
  room_box(c, 6.6, 5.9, 1.0, 6.68, 6.06, 2.2, c->wood);
  room_box(c, 5.58, 5.95, 1.0, 5.62, 6.01, 2.2, c->wood);
  room_box(c, 4.6, 5.95, 1.58, 5.58, 6.01, 1.62, c->wood);
  room_box(c, 5.62, 5.95, 1.58, 6.6, 6.01, 1.62, c->wood);

  /* Door on the left wall: panel, jambs, head, knob. */
  room_box(c, 0, 1.0, 0, 0.04, 1.9, 2.05, c->wood);
  room_box(c, 0, 0.92, 0, 0.07, 1.0, 2.13, c->wood);
  room_box(c, 0, 1.9, 0, 0.07, 1.98, 2.13, c->wood);
  room_box(c, 0, 1.0, 2.05, 0.07, 1.9, 2.13, c->wood);
  struct gen_frame stem = gen_frame_along(gen_d3_make(0.04, 1.8, 1.0), ex);
  gen_cylinder(c->s, &stem, 0.01, 0.01, 0.05, room_res_fixed(c, 8, 4), c->metal);
  gen_sphere(c->s, gen_d3_make(0.115, 1.8, 1.0), 0.03, room_res_fixed(c, 4, 2), c->metal);

  /* Wall mirror above the sofa, framed in metal. */
  gen_quad(c->s, gen_d3_make(X - 0.012, 2.0, 1.1), gen_d3_make(X - 0.012, 4.0, 1.1),
           gen_d3_make(X - 0.012, 4.0, 2.3), gen_d3_make(X - 0.012, 2.0, 2.3), c->mirror);
  room_box(c, X - 0.03, 1.95, 1.05, X, 4.05, 1.1, c->metal);
  room_box(c, X - 0.03, 1.95, 2.3, X, 4.05, 2.35, c->metal);
  room_box(c, X - 0.03, 1.95, 1.1, X, 2.0, 2.3, c->metal);
  room_box(c, X - 0.03, 4.0, 1.1, X, 4.05, 2.3, c->metal);
}

/* ---- furniture ---- */

static void room_legs(struct room_ctx *c, double x0, double y0, double x1, double y1, double r,
                      double h, uint32_t mat) {
  uint32_t sides = room_res_fixed(c, 16, 6);
  for (int i = 0; i < 4; i++) {
    struct gen_frame f = gen_frame_at(gen_d3_make(i & 1 ? x1 : x0, i & 2 ? y1 : y0, 0));
    gen_cylinder(c->s, &f, r, r, h, sides, mat);
  }
}

/* A chair at (x, y) facing direction angle `a` (its local +y, toward the table). */
static void room_chair(struct room_ctx *c, double x, double y, double a) {
  struct gen_frame f = gen_frame_at(gen_d3_make(x, y, 0));
  f.u = gen_d3_make(cos(a), sin(a), 0);
  f.v = gen_d3_make(-sin(a), cos(a), 0);
  const double s = 0.2, leg = 0.018;
  for (int i = 0; i < 4; i++)
    room_box_in(c, &f, i & 1 ? s - leg : -s + leg, i & 2 ? s - leg : -s + leg, 0.22, leg, leg, 0.22,
                c->wood);
  room_box_in(c, &f, 0, 0, 0.46, s + 0.01, s + 0.01, 0.02, c->wood);
  room_box_in(c, &f, 0, 0, 0.49, s - 0.02, s - 0.03, 0.01, c->fabric);
  for (int i = 0; i < 2; i++) /* back posts, rail and two slats behind the seat */
    room_box_in(c, &f, i ? s - leg : -s + leg, -s + leg, 0.73, leg, leg, 0.25, c->wood);
  room_box_in(c, &f, 0, -s + leg, 0.93, s - 2 * leg, 0.014, 0.04, c->wood);
  for (int i = 0; i < 2; i++)
    room_box_in(c, &f, i ? 0.06 : -0.06, -s + leg, 0.69, 0.022, 0.01, 0.2, c->wood);
}

static void room_table(struct room_ctx *c) {
  room_box(c, 2.7, 2.3, 0.72, 4.5, 3.3, 0.77, c->wood);
  room_legs(c, 2.8, 2.4, 4.4, 3.2, 0.035, 0.72, c->wood);
  /* Rug under the table. */
  room_box(c, 2.1, 1.5, 0, 5.1, 4.1, 0.008, c->fabric);
  double jitter[6][3];
  for (int i = 0; i < 6; i++) {
    jitter[i][0] = room_unif(c, -0.06, 0.06);
    jitter[i][1] = room_unif(c, -0.04, 0.1);
    jitter[i][2] = room_unif(c, -0.15, 0.15);
  }
  /* Chairs pulled out a little, each a bit askew. */
  room_chair(c, 3.15 + jitter[0][0], 1.95 - jitter[0][1], 0 + jitter[0][2]);
  room_chair(c, 4.05 + jitter[1][0], 1.95 - jitter[1][1], 0 + jitter[1][2]);
  room_chair(c, 3.15 + jitter[2][0], 3.65 + jitter[2][1], GEN_PI + jitter[2][2]);
  room_chair(c, 4.05 + jitter[3][0], 3.65 + jitter[3][1], GEN_PI + jitter[3][2]);
  room_chair(c, 2.35 - jitter[4][1], 2.8 + jitter[4][0], -0.5 * GEN_PI + jitter[4][2]);
  room_chair(c, 4.85 + jitter[5][1], 2.8 + jitter[5][0], 0.5 * GEN_PI + jitter[5][2]);
}

/* Place settings, fruit, a vase and a small mirror ball on the table. */
static void room_table_clutter(struct room_ctx *c) {
  const double top = 0.77;
  static const double settings[6][4] = {/* plate x, y, cup dx, dy */
                                        {3.15, 2.52, 0.17, -0.08}, {4.05, 2.52, 0.17, -0.08},
                                        {3.15, 3.08, -0.17, 0.08}, {4.05, 3.08, -0.17, 0.08},
                                        {2.92, 2.8, -0.06, 0.19},  {4.28, 2.8, 0.06, -0.19}};
  for (int i = 0; i < 6; i++) {
    double dx = room_unif(c, -0.02, 0.02), dy = room_unif(c, -0.02, 0.02);
    double h = room_unif(c, 0.08, 0.1);
    if (room_keep(c))
      room_plate(c, gen_d3_make(settings[i][0] + dx, settings[i][1] + dy, top), 0.11);
    if (room_keep(c))
      room_cup(c,
               gen_d3_make(settings[i][0] + settings[i][2] + dx,
                           settings[i][1] + settings[i][3] + dy, top),
               0.035, h, c->ceramic);
  }
  room_fruit_bowl(c, 3.35, 2.8, top, 0.13);
  double vh = room_unif(c, 0.3, 0.4);
  if (room_keep(c)) room_vase(c, gen_d3_make(3.9, 2.8, top), 0.08, vh, 0, c->ceramic);
  /* Mirror ball on a short metal stand: a mirror surface near the middle of
   * the view. Always built. */
  struct gen_frame f = gen_frame_at(gen_d3_make(3.65, 2.8, top));
  gen_cylinder(c->s, &f, 0.04, 0.02, 0.05, room_res_fixed(c, 16, 6), c->metal);
  gen_sphere(c->s, gen_d3_make(3.65, 2.8, top + 0.05 + 0.09), 0.09, room_res_fixed(c, 10, 3),
             c->mirror);
}

static void room_bookcase(struct room_ctx *c) {
  const double x0 = 0.4, x1 = 3.0, y0 = 5.6, y1 = 5.99, b = 0.025;
  room_box(c, x0, y0, 0, x0 + b, y1, 2.2, c->wood);
  room_box(c, x1 - b, y0, 0, x1, y1, 2.2, c->wood);
  room_box(c, x0 + b, y1 - 0.02, 0, x1 - b, y1, 2.2, c->wood);
  room_box(c, x0 + b, y0, 0, x1 - b, y1 - 0.02, 0.08, c->wood);
  room_box(c, x0 + b, y0, 2.2 - b, x1 - b, y1 - 0.02, 2.2, c->wood);
  for (int i = 0; i < ROOM_SHELVES; i++) {
    double z = 0.08 + 0.44 * i;
    if (i > 0) room_box(c, x0 + b, y0, z - b, x1 - b, y1 - 0.02, z, c->wood);
    double top = i < 4 ? z + 0.44 - b : 2.2 - b;
    room_shelf_row(c, x0 + b, x1 - b, y0 + 0.01, y1 - 0.02, z, top - z - 0.01, room_shelf_rows[i]);
  }
}

static void room_sofa(struct room_ctx *c) {
  const double x0 = 7.05, x1 = 7.97, y0 = 1.8, y1 = 4.2;
  room_box(c, x0, y0 + 0.15, 0.08, x1, y1 - 0.15, 0.3, c->fabric);        /* base */
  room_box(c, x1 - 0.22, y0 + 0.15, 0.3, x1, y1 - 0.15, 0.85, c->fabric); /* back */
  room_box(c, x0, y0, 0.08, x1, y0 + 0.15, 0.6, c->fabric);               /* arms */
  room_box(c, x0, y1 - 0.15, 0.08, x1, y1, 0.6, c->fabric);
  for (int i = 0; i < 3; i++) { /* seat and back cushions */
    double ya = y0 + 0.15 + 0.7 * i + 0.005, yb = ya + 0.69;
    room_box(c, x0 + 0.02, ya, 0.3, x1 - 0.22, yb, 0.45, c->fabric);
    room_box(c, x1 - 0.35, ya, 0.45, x1 - 0.22, yb, 0.8, c->fabric);
  }
  for (int i = 0; i < 4; i++) /* short feet */
    room_box(c, i & 1 ? x1 - 0.08 : x0 + 0.03, i & 2 ? y1 - 0.08 : y0 + 0.03, 0,
             i & 1 ? x1 - 0.03 : x0 + 0.08, i & 2 ? y1 - 0.03 : y0 + 0.08, 0.08, c->wood);
}

static void room_coffee_table(struct room_ctx *c) {
  const double top = 0.42;
  room_box(c, 5.9, 2.4, 0.38, 6.7, 3.6, top, c->wood);
  room_legs(c, 5.96, 2.46, 6.64, 3.54, 0.025, 0.38, c->metal);
  room_fruit_bowl(c, 6.3, 2.75, top, 0.12);
  double vh = room_unif(c, 0.25, 0.35);
  if (room_keep(c)) room_vase(c, gen_d3_make(6.45, 3.3, top), 0.07, vh, 2, c->ceramic);
  room_book_stack(c, 6.05, 3.25, top, 3, 0.22, 0.16);
}

/* Sideboard against the front wall: wooden body, metal doors. */
static void room_sideboard(struct room_ctx *c) {
  const double x0 = 3.0, x1 = 5.2, top = 0.85;
  room_box(c, x0, 0.02, 0.08, x1, 0.5, top, c->wood);
  room_box(c, x0 + 0.05, 0.05, 0, x1 - 0.05, 0.47, 0.08, c->wood);
  room_box(c, x0 + 0.03, 0.5, 0.11, 0.5 * (x0 + x1) - 0.005, 0.52, top - 0.03, c->metal);
  room_box(c, 0.5 * (x0 + x1) + 0.005, 0.5, 0.11, x1 - 0.03, 0.52, top - 0.03, c->metal);
  double vh[3];
  for (int i = 0; i < 3; i++) vh[i] = room_unif(c, 0.22, 0.45);
  for (int i = 0; i < 3; i++)
    if (room_keep(c))
      room_vase(c, gen_d3_make(x0 + 0.25 + 0.45 * i, 0.26, top), 0.06 + 0.015 * i, vh[i], i,
                c->ceramic);
  room_fruit_bowl(c, x1 - 0.6, 0.26, top, 0.12);
  for (int i = 0; i < 3; i++)
    if (room_keep(c))
      room_cup(c, gen_d3_make(x1 - 0.3 + 0.09 * (i % 2), 0.18 + 0.1 * i, top), 0.033, 0.085,
               c->ceramic);
}

/* Lamps, the big mirror ball on its pedestal and a floor vase. */
static void room_fixtures(struct room_ctx *c) {
  uint32_t sides = room_res_fixed(c, 24, 8);
  /* Ceiling lamp over the table: cord and a bell-shaped shade, open below. */
  struct gen_frame cord = gen_frame_at(gen_d3_make(3.6, 2.8, 2.49));
  gen_cylinder(c->s, &cord, 0.008, 0.008, ROOM_Z - 2.49, room_res_fixed(c, 8, 4), c->metal);
  double sr[7] = {0.25, 0.06, 0, 0, 0.055, 0.235, 0.25};
  double sz[7] = {0, 0.2, 0.2, 0.185, 0.185, 0, 0};
  room_lathe_at(c, gen_d3_make(3.6, 2.8, 2.3), sr, sz, 7, sides, c->ceramic);

  /* Floor lamp beside the sofa: base, pole, open conical shade. */
  struct gen_frame lamp = gen_frame_at(gen_d3_make(7.45, 0.7, 0));
  gen_cylinder(c->s, &lamp, 0.15, 0.14, 0.03, sides, c->metal);
  gen_cylinder(c->s, &lamp, 0.015, 0.015, 1.5, room_res_fixed(c, 8, 4), c->metal);
  double lr[5] = {0.22, 0.14, 0.13, 0.21, 0.22}, lz[5] = {0, 0.3, 0.3, 0, 0};
  room_lathe_at(c, gen_d3_make(7.45, 0.7, 1.45), lr, lz, 5, sides, c->fabric);

  /* Large mirror ball on a ceramic pedestal in the back right corner. */
  struct gen_frame ped = gen_frame_at(gen_d3_make(7.35, 5.35, 0));
  gen_cylinder(c->s, &ped, 0.2, 0.16, 0.3, sides, c->ceramic);
  gen_sphere(c->s, gen_d3_make(7.35, 5.35, 0.3 + 0.4), 0.4, room_res_fixed(c, 16, 4), c->mirror);

  /* Tall floor vase by the left wall. */
  double vh = room_unif(c, 0.7, 0.9);
  if (room_keep(c)) room_vase(c, gen_d3_make(0.45, 4.9, 0), 0.16, vh, 1, c->ceramic);
}

/* Below detail 1, thin the clutter slots (linear in detail) and keep each
 * object's shape; above 1 the room is full and tessellation grows instead
 * (levels are per edge, so triangles go as their square). Furniture is
 * always there, coarsened with detail down to a minimum shape. */
static void room_scales(struct room_ctx *c, double detail) {
  c->keep = detail >= 1.0 ? 1.0 : detail;
  c->tess_scale = detail >= 1.0 ? sqrt(detail) : 1.0;
  c->fixed_scale = sqrt(detail);
}

/* Every clutter slot in the order gen_room meets them, in room_shelf_row's
 * letters plus P (plate); S stands for a stack of 4 books (4 slots). Before
 * the shelves come none; after them the coffee table (fruit bowl: a bowl and
 * 5 balls; vase; 3 books), the sideboard (3 vases, fruit bowl, 3 cups), the
 * floor vase, and the table (6 plates with cups, fruit bowl, vase). */
static const char *const room_clutter_after_shelves = "WOOOOOVBBB"
                                                      "VVVWOOOOOCCC"
                                                      "V"
                                                      "PCPCPCPCPCPCWOOOOOV";

/* Triangles of one clutter item of kind `letter` at c's scales: lathe
 * profiles from room_cup, room_plate, room_vase and room_bowl (every radius
 * but the ends' is positive, so gen_lathe_tri_count gives sides per end
 * segment and 2 * sides per other), spheres from room_ball, boxes of 12. */
static uint64_t room_item_tri_count(const struct room_ctx *c, char letter) {
  uint64_t sides = room_res(c, ROOM_LATHE_SIDES, 6);
  uint64_t vase_k = room_res(c, ROOM_VASE_STEPS, 3), bowl_k = room_res(c, ROOM_BOWL_STEPS, 2);
  if (vase_k > ROOM_MAX_PROFILE - 6) vase_k = ROOM_MAX_PROFILE - 6;
  if (bowl_k > (ROOM_MAX_PROFILE - 4) / 2 - 1) bowl_k = (ROOM_MAX_PROFILE - 4) / 2 - 1;
  uint64_t ball = room_res(c, ROOM_BALL_TESS, 2);
  switch (letter) {
  case 'B': return 12;
  case 'C':
  case 'P': return 8 * sides;                /* 6-point profiles */
  case 'V': return (2 * vase_k + 6) * sides; /* k + 5 points */
  case 'W': return (4 * bowl_k + 4) * sides; /* 2k + 4 points */
  case 'O': return gen_sphere_tri_count((uint32_t)ball);
  default: CHECK(false); return 0;
  }
}

static uint64_t room_clutter_tri_count(const struct room_ctx *c) {
  uint64_t tris = 0, slot = 0;
  for (int i = 0; i <= ROOM_SHELVES; i++) {
    const char *p = i < ROOM_SHELVES ? room_shelf_rows[i] : room_clutter_after_shelves;
    for (; *p; p++)
      for (int k = 0; k < (*p == 'S' ? 4 : 1); k++)
        if (room_slot_kept(slot++, c->keep)) tris += room_item_tri_count(c, *p == 'S' ? 'B' : *p);
  }
  return tris;
}

/* Furniture and fixtures, always built: 115 boxes (shell 19, table and
 * chairs 68, bookcase 9, sofa 14, coffee table 1, sideboard 4), 218
 * triangles of floor, ceiling, walls and mirror, cylinders of 4 * sides
 * (room_res_fixed(8): door knob, lamp cord and pole; (16): 8 table legs and
 * the ball stand; (24): lamp base and pedestal), two 8 * sides lamp shades
 * (24), and three spheres (door knob 4, big mirror ball 16, table ball 10). */
static uint64_t room_fixed_tri_count(const struct room_ctx *c) {
  uint64_t s8 = room_res_fixed(c, 8, 4), s16 = room_res_fixed(c, 16, 6);
  uint64_t s24 = room_res_fixed(c, 24, 8);
  return 115 * 12 + 218 + 3 * 4 * s8 + 9 * 4 * s16 + (2 * 4 + 2 * 8) * s24 +
         gen_sphere_tri_count(room_res_fixed(c, 4, 2)) +
         gen_sphere_tri_count(room_res_fixed(c, 16, 4)) +
         gen_sphere_tri_count(room_res_fixed(c, 10, 3));
}

uint64_t gen_room_tri_count(double detail) {
  struct room_ctx c;
  room_scales(&c, detail);
  return room_fixed_tri_count(&c) + room_clutter_tri_count(&c);
}

void gen_room(struct scene *s, double detail, uint64_t seed) {
  CHECK_GT(detail, 0.0);
  struct room_ctx c;
  c.s = s;
  c.rng = rng_make(seed, 0x726f6f6dull);
  c.slot = 0;
  room_scales(&c, detail);
  c.wall = scene_material_or_default(s, "wall", v3(0.8f, 0.78f, 0.72f), 1.0f, 0.0f);
  c.floor_mat = scene_material_or_default(s, "floor", v3(0.55f, 0.4f, 0.3f), 0.9f, 0.1f);
  c.ceiling = scene_material_or_default(s, "ceiling", v3(0.9f, 0.9f, 0.9f), 1.0f, 0.0f);
  c.wood = scene_material_or_default(s, "wood", v3(0.5f, 0.33f, 0.2f), 0.9f, 0.0f);
  c.fabric = scene_material_or_default(s, "fabric", v3(0.3f, 0.35f, 0.6f), 1.0f, 0.0f);
  c.metal = scene_material_or_default(s, "metal", v3(0.7f, 0.7f, 0.75f), 0.3f, 0.6f);
  c.mirror = scene_material_or_default(s, "mirror", v3(0.95f, 0.95f, 0.95f), 0.05f, 0.9f);
  c.ceramic = scene_material_or_default(s, "ceramic", v3(0.85f, 0.85f, 0.8f), 0.8f, 0.1f);

  room_shell(&c);
  room_table(&c);
  room_bookcase(&c);
  room_sofa(&c);
  room_coffee_table(&c);
  room_sideboard(&c);
  room_fixtures(&c);
  room_table_clutter(&c);
}
