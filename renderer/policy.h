/* Ray scheduling policies (the paper's sections 2 and 3), each its own module
 * behind this one interface. A policy decides only the order in which rays are
 * traced and where they wait in memory; tracing and shading are the shared
 * kernels, so every policy produces the same hits and the same image, bit for
 * bit (the framebuffer sums in fixed point). */
#ifndef RTSIM_RENDERER_POLICY_H
#define RTSIM_RENDERER_POLICY_H

#include <stdbool.h>
#include <stdint.h>

#include "renderer/render.h"

struct tracer;
struct shade_ctx;
struct framebuffer;
struct camera_frame;
struct ray;

enum policy_kind { POLICY_RECURSIVE = 0, POLICY_PACKET = 1, POLICY_DYNAMIC = 2, POLICY_COUNT = 3 };

struct policy_params {
  uint32_t packet_dim;   /* packet: packets are packet_dim x packet_dim pixels (8) */
  uint64_t cache_bytes;  /* dynamic: the cache size the schedule is made for */
  /* dynamic: what the cache holds besides geometry (section 2.2), each capped
   * by a share of cache_bytes: k-d nodes up to 1/dyn_node_share (4: the paper's
   * 1 MB of 4 MB), the queue table (8 bytes a queue point) up to
   * 1/dyn_table_share (16: 256 KB of 4 MB), a ray buffer of
   * dyn_ray_buffer_bytes (4096: 64 rays) up to 1/dyn_ray_share (16). The rest
   * is g_max, the geometry a queue point's subtree may hold (qpoint.h). */
  uint32_t dyn_node_share, dyn_table_share, dyn_ray_share;
  uint64_t dyn_ray_buffer_bytes;
  /* dynamic: primary rays admitted at a time, each batch traced through all
   * its generations before the next is admitted; this bounds the rays active at
   * once (the paper's continuum between recursive and fully deferred tracing).
   * 0 (default): every primary ray at once, as the paper's section 2 reads. */
  uint64_t dyn_batch_rays;
};

void policy_params_default(struct policy_params *p);

/* What a policy runs with. The tracer carries the memory port and layout
 * (where rays, queues and the framebuffer live in the simulated image). */
struct policy_env {
  struct tracer *tr;
  const struct shade_ctx *sc;
  struct framebuffer *fb; /* its size is the image size */
  struct render_stats *st;
  render_progress_fn progress;
  void *progress_ctx;
};

/* Render the whole image with policy k. Checks ray conservation at the end. */
void policy_run(enum policy_kind k, const struct policy_env *env, const struct policy_params *p);

/* Pixel (x, y)'s primary ray. Every policy reads it from the camera's ray
 * array in the memory image (one 64-byte load; trace_layout.camera_base), as a
 * ray-generation stage would have left it: the same input traffic for all
 * policies, and the 64 bytes per primary ray the paper's baselines carry. */
void policy_primary(const struct policy_env *env, const struct camera_frame *cf, uint32_t x,
                    uint32_t y, struct ray *r);

/* "recursive", "packet", "dynamic". */
const char *policy_name(enum policy_kind k);
/* Parse a name; false if unknown. */
bool policy_parse(const char *name, enum policy_kind *k);

/* The modules (policy_recursive.c, policy_packet.c, policy_dynamic.c). */
void policy_recursive_run(const struct policy_env *env, const struct policy_params *p);
void policy_packet_run(const struct policy_env *env, const struct policy_params *p);
void policy_dynamic_run(const struct policy_env *env, const struct policy_params *p);

#endif
