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
 * A work item is a tile: workers take the next one from the job's shared
 * counter, each with its own packet buffers in its own ray region.
 *
 * Per-pixel cost channels: each ray's own share of the packet's work (nodes it
 * was active in, triangles tested against it) goes to its pixel, so they read
 * like the recursive policy's. tr->stats.node_visits counts packet node visits
 * (one fetch serves the packet); tri_tests counts ray/triangle tests. */
#include "renderer/policy/policy_impl.h"

#include <stdlib.h>
#include <string.h>

#include "renderer/camera.h"
#include "renderer/framebuffer.h"
#include "renderer/policy/policy.h"
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
  CHECK_LT(g, GROUP_COUNT);
  CHECK(!(*used & (1ull << g)));
  *used |= 1ull << g;
  return g;
}

/* Simulated address of ray i of the packet buffer at stack slot k. */
static uint64_t buf_addr(uint64_t base, uint32_t k, uint32_t i) {
  return base + ((uint64_t)k * PACKET_MAX + i) * sizeof(struct ray);
}

/* A worker's own: the host copies of its packet buffers, the packet query's
 * scratch, and the results of one packet (kept off the C stack, so that the
 * worker fits a small coroutine stack). */
struct pkt_scratch {
  struct packet stack[PACKET_STACK];
  struct packet group[GROUP_COUNT];
  struct packet cur;
  struct trace_packet *pk;
  struct trace_packet_cost cost;
  struct trace_hit hits[PACKET_MAX];
  bool occ[PACKET_MAX];
  struct ray spawn[SHADE_MAX_SPAWN];
  uint32_t pixels[PACKET_MAX]; /* the packet's rays' (trace_attribute) */
};

static void pkt_create(struct policy_job *job) {
  const uint32_t w = job->setup.fb->width, h = job->setup.fb->height, dim = job->params.packet_dim;
  CHECK_GE(dim, 1);
  CHECK_LE(dim * dim, PACKET_MAX);
  job->total = (uint64_t)((w + dim - 1) / dim) * ((h + dim - 1) / dim);
  job->progress_every = 64;
  job->shared = NULL;
}

static void pkt_destroy(struct policy_job *job) { (void)job; }

static void pkt_scratch_free(void *scratch) {
  struct pkt_scratch *x = scratch;
  if (!x) return;
  trace_packet_destroy(x->pk);
  free(x);
}

static bool pkt_step(struct policy_job *job, struct policy_worker *wk) {
  uint64_t k;
  if (policy_job_claim(job, 1, &k) == 0) return false;
  struct mem_port own;
  const enum policy_item how = policy_item_begin(job, wk, k, &own);
  if (how == POLICY_ITEM_SKIP) {
    policy_job_done(job, 1);
    return true;
  }
  const bool detail = how == POLICY_ITEM_DETAIL;
  if (!wk->scratch) {
    struct pkt_scratch *n = xmalloc(sizeof *n);
    n->pk = trace_packet_create();
    wk->scratch = n;
  }
  struct pkt_scratch *x = wk->scratch;
  struct packet *stack = x->stack, *group = x->group, *cur = &x->cur;
  struct trace_ctx *tr = &wk->tr;
  const struct shade_ctx *sc = job->setup.sc;
  struct framebuffer *fb = job->setup.fb;
  struct render_stats *st = &wk->st;
  const struct mem_port *mem = &tr->mem;
  const uint64_t base = tr->layout.ray_base;
  const uint32_t w = fb->width, h = fb->height, dim = job->params.packet_dim;
  const uint32_t tiles_x = (w + dim - 1) / dim;

  const uint32_t x0 = (uint32_t)(k % tiles_x) * dim, y0 = (uint32_t)(k / tiles_x) * dim;
  const uint32_t x1 = x0 + dim < w ? x0 + dim : w, y1 = y0 + dim < h ? y0 + dim : h;
  uint32_t top = 0;
  struct packet *pr = &stack[top];
  pr->n = 0;
  for (uint32_t y = y0; y < y1; y++)
    for (uint32_t xx = x0; xx < x1; xx++) {
      const uint32_t pix = y * w + xx;
      trace_attribute(tr, &pix, 1);
      policy_primary(job, wk, xx, y, &pr->r[pr->n]);
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
      trace_attribute(tr, &stack[top].r[i].pixel, 1);
      mem_load(mem, buf_addr(base, top, i), sizeof(struct ray), TRACE_CLASS_RAY);
      cur->r[i] = stack[top].r[i];
      x->pixels[i] = cur->r[i].pixel;
    }
    /* The traversal is the packet's: its cost is split among its rays. */
    trace_attribute(tr, x->pixels, n);
    const uint8_t type = cur->r[0].type;
    st->rays[type] += n;
    st->terminated += n;
    if (type == RAY_SHADOW) {
      trace_packet_any(tr, x->pk, cur->r, n, x->occ, &x->cost);
      for (uint32_t i = 0; i < n; i++) {
        trace_attribute(tr, &cur->r[i].pixel, 1);
        shade_shadow(&cur->r[i], x->occ[i], fb, mem);
      }
    } else {
      trace_packet_closest(tr, x->pk, cur->r, n, x->hits, &x->cost);
      for (uint32_t g = 0; g < GROUP_COUNT; g++) group[g].n = 0;
      for (uint32_t i = 0; i < n; i++) {
        trace_attribute(tr, &cur->r[i].pixel, 1);
        uint32_t ns = shade_hit(sc, &cur->r[i], &x->hits[i], fb, mem, x->spawn);
        uint64_t used = 0;
        for (uint32_t j = 0; j < ns; j++) {
          struct packet *gp = &group[child_group(&cur->r[i], &x->spawn[j], &used)];
          CHECK_LT(gp->n, PACKET_MAX);
          gp->r[gp->n++] = x->spawn[j];
        }
        st->spawned += ns;
      }
      /* Push in reverse so the shadow packets (light order) are traced first. */
      for (uint32_t g = GROUP_COUNT; g-- > 0;) {
        if (group[g].n == 0) continue;
        CHECK_LT(top, PACKET_STACK);
        struct packet *dst = &stack[top];
        dst->n = group[g].n;
        for (uint32_t i = 0; i < dst->n; i++) {
          trace_attribute(tr, &group[g].r[i].pixel, 1);
          mem_store(mem, buf_addr(base, top, i), sizeof(struct ray), TRACE_CLASS_RAY);
          dst->r[i] = group[g].r[i];
        }
        top++;
      }
      uint64_t slots = (uint64_t)top * PACKET_MAX;
      if (slots > st->ray_slots_max) st->ray_slots_max = slots;
    }
    for (uint32_t i = 0; i < n; i++) {
      fb->cost_nodes[cur->r[i].pixel] += x->cost.nodes[i];
      fb->cost_tris[cur->r[i].pixel] += x->cost.tris[i];
    }
  }
  policy_item_end(job, wk, k, &own, detail);
  policy_job_done(job, 1);
  return true;
}

const struct policy_module policy_packet_module = {
    .region_bytes = (uint64_t)PACKET_STACK * PACKET_MAX * sizeof(struct ray),
    .max_workers = 0, /* as many as the ray regions allow */
    .create = pkt_create,
    .destroy = pkt_destroy,
    .step = pkt_step,
    .scratch_free = pkt_scratch_free,
};
