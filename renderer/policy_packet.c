/* The packet policy: the paper's "ray packet tracer using 8x8 packets tiled
 * over the image plane". Tiles go in scanline order; a tile's primary rays
 * (row-major) are traced as one packet, and the rays their hits spawn are
 * grouped the way a packet tracer groups them: one child packet per kind of
 * child (a shadow packet per light, the specular packet, a diffuse packet per
 * cell of the 3x3 hemisphere grid), each holding that child of every ray of
 * the parent. Packets are processed depth-first on an explicit stack of packet
 * buffers in the memory image (children pushed so shadow packets go first,
 * then specular, then diffuse: the recursive policy's order at packet grain).
 * A ray written to a buffer is a 64-byte store, read back before tracing a
 * 64-byte load.
 *
 * Per-pixel cost channels: each ray's own share of the packet's work (nodes it
 * was active in, triangles tested against it) goes to its pixel, so they read
 * like the recursive policy's. tr->stats.node_visits counts packet node visits
 * (one fetch serves the packet); tri_tests counts ray/triangle tests. */
#include <stdlib.h>
#include <string.h>

#include "renderer/camera.h"
#include "renderer/framebuffer.h"
#include "renderer/policy.h"
#include "renderer/rng.h"
#include "renderer/scene.h"
#include "renderer/shade.h"
#include "renderer/trace.h"
#include "sim/err.h"

#define PACKET_MAX TRACE_PACKET_MAX
/* Child packets of one parent packet: shadow (one per light), specular,
 * diffuse (one per grid cell); the group index is also the trace order. */
#define GROUP_SPECULAR SCENE_MAX_LIGHTS
#define GROUP_DIFFUSE (GROUP_SPECULAR + 1)
#define GROUP_COUNT (GROUP_DIFFUSE + SHADE_DIFFUSE_GRID * SHADE_DIFFUSE_GRID)
_Static_assert(GROUP_COUNT <= 64, "groups of one parent fit a 64-bit set");
/* Depth-first bound, as the recursive policy's: each of up to
 * SHADE_MAX_DEPTH + 1 levels holds the child packets of one packet. */
#define PACKET_STACK ((SHADE_MAX_DEPTH + 2) * GROUP_COUNT)

struct packet {
  uint32_t n;
  struct ray r[PACKET_MAX];
};

/* Which child packet a ray spawned by parent belongs to; *used collects the
 * groups the parent's children took (one child a group, so no packet overflows).
 * Shading gives a diffuse ray's grid cell only through its path key (hash of
 * the parent's path, type and cell): recover the cell by matching that key. */
static uint32_t child_group(const struct ray *parent, const struct ray *c, uint64_t *used) {
  uint32_t g = 0;
  switch (c->type) {
  case RAY_SHADOW: g = c->light; break;
  case RAY_SPECULAR: g = GROUP_SPECULAR; break;
  case RAY_DIFFUSE:
    g = GROUP_COUNT;
    for (uint32_t slot = 0; slot < SHADE_DIFFUSE_GRID * SHADE_DIFFUSE_GRID; slot++) {
      uint64_t key = rng_hash2(parent->path, ((uint64_t)RAY_DIFFUSE << 32) | slot);
      /* A 32-bit key collision between two cells takes the next free match. */
      if ((uint32_t)key == c->path && !(*used & (1ull << (GROUP_DIFFUSE + slot)))) {
        g = GROUP_DIFFUSE + slot;
        break;
      }
    }
    break;
  default: CHECK(!"unexpected child ray type");
  }
  CHECK(g < GROUP_COUNT && !(*used & (1ull << g)));
  *used |= 1ull << g;
  return g;
}

/* Simulated address of ray i of the packet buffer at stack slot k. */
static uint64_t buf_addr(uint64_t base, uint32_t k, uint32_t i) {
  return base + ((uint64_t)k * PACKET_MAX + i) * sizeof(struct ray);
}

void policy_packet_run(const struct policy_env *env, const struct policy_params *p) {
  struct tracer *tr = env->tr;
  const struct shade_ctx *sc = env->sc;
  struct framebuffer *fb = env->fb;
  struct render_stats *st = env->st;
  const struct mem_port *mem = &tr->mem;
  const uint64_t base = tr->layout.ray_base;
  const uint32_t w = fb->width, h = fb->height, dim = p->packet_dim;
  CHECK(dim >= 1 && dim * dim <= PACKET_MAX);
  const uint32_t tiles_x = (w + dim - 1) / dim, tiles_y = (h + dim - 1) / dim;
  const uint64_t ntiles = (uint64_t)tiles_x * tiles_y;
  struct camera_frame cf;
  camera_frame_init(&cf, &sc->scene->camera, w, h);

  struct packet *stack = xmalloc(PACKET_STACK * sizeof *stack);
  struct packet *group = xmalloc(GROUP_COUNT * sizeof *group);
  struct packet *cur = xmalloc(sizeof *cur);
  struct trace_packet *pk = trace_packet_create();
  struct trace_packet_cost cost;
  struct hit hits[PACKET_MAX];
  bool occ[PACKET_MAX];
  struct ray spawn[SHADE_MAX_SPAWN];

  for (uint64_t k = 0; k < ntiles; k++) {
    const uint32_t x0 = (uint32_t)(k % tiles_x) * dim, y0 = (uint32_t)(k / tiles_x) * dim;
    const uint32_t x1 = x0 + dim < w ? x0 + dim : w, y1 = y0 + dim < h ? y0 + dim : h;
    uint32_t top = 0;
    struct packet *pr = &stack[top];
    pr->n = 0;
    for (uint32_t y = y0; y < y1; y++)
      for (uint32_t x = x0; x < x1; x++) {
        policy_primary(env, &cf, x, y, &pr->r[pr->n]);
        mem_store(mem, buf_addr(base, top, pr->n), sizeof(struct ray), TRACE_CLASS_RAY);
        pr->n++;
      }
    top++;
    st->spawned += pr->n;
    while (top > 0) {
      top--;
      /* Read the packet back; its buffer is free for its children from here. */
      const uint32_t n = stack[top].n;
      cur->n = n;
      for (uint32_t i = 0; i < n; i++) {
        mem_load(mem, buf_addr(base, top, i), sizeof(struct ray), TRACE_CLASS_RAY);
        cur->r[i] = stack[top].r[i];
      }
      const uint8_t type = cur->r[0].type;
      st->rays[type] += n;
      st->terminated += n;
      if (type == RAY_SHADOW) {
        trace_packet_any(tr, pk, cur->r, n, occ, &cost);
        for (uint32_t i = 0; i < n; i++) shade_shadow(&cur->r[i], occ[i], fb, mem);
      } else {
        trace_packet_closest(tr, pk, cur->r, n, hits, &cost);
        for (uint32_t g = 0; g < GROUP_COUNT; g++) group[g].n = 0;
        for (uint32_t i = 0; i < n; i++) {
          uint32_t ns = shade_hit(sc, &cur->r[i], &hits[i], fb, mem, spawn);
          uint64_t used = 0;
          for (uint32_t j = 0; j < ns; j++) {
            struct packet *gp = &group[child_group(&cur->r[i], &spawn[j], &used)];
            CHECK(gp->n < PACKET_MAX);
            gp->r[gp->n++] = spawn[j];
          }
          st->spawned += ns;
        }
        /* Push in reverse so the shadow packets (light order) are traced first. */
        for (uint32_t g = GROUP_COUNT; g-- > 0;) {
          if (group[g].n == 0) continue;
          CHECK(top < PACKET_STACK);
          struct packet *dst = &stack[top];
          dst->n = group[g].n;
          for (uint32_t i = 0; i < dst->n; i++) {
            mem_store(mem, buf_addr(base, top, i), sizeof(struct ray), TRACE_CLASS_RAY);
            dst->r[i] = group[g].r[i];
          }
          top++;
        }
        uint64_t slots = (uint64_t)top * PACKET_MAX;
        if (slots > st->ray_slots_max) st->ray_slots_max = slots;
      }
      for (uint32_t i = 0; i < n; i++) {
        fb->cost_nodes[cur->r[i].pixel] += cost.nodes[i];
        fb->cost_tris[cur->r[i].pixel] += cost.tris[i];
      }
    }
    if (env->progress && (k & 63) == 63) env->progress(env->progress_ctx, k + 1, ntiles);
  }
  if (env->progress) env->progress(env->progress_ctx, ntiles, ntiles);
  trace_packet_destroy(pk);
  free(cur);
  free(group);
  free(stack);
}
