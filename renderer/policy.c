/* Policy dispatch, names and defaults. */
#include "renderer/policy.h"

#include <string.h>

#include "renderer/camera.h"
#include "renderer/framebuffer.h"
#include "renderer/shade.h"
#include "renderer/trace.h"
#include "sim/err.h"

static const char *const NAMES[POLICY_COUNT] = {"recursive", "packet", "dynamic"};

void policy_params_default(struct policy_params *p) {
  memset(p, 0, sizeof *p);
  p->packet_dim = 8;
  p->cache_bytes = 512u * 1024u;
  p->dyn_node_share = 4;
  p->dyn_table_share = 16;
  p->dyn_ray_share = 16;
  p->dyn_ray_buffer_bytes = 4096;
  p->dyn_batch_rays = 0;
}

void policy_primary(const struct policy_env *env, const struct camera_frame *cf, uint32_t x,
                    uint32_t y, struct ray *r) {
  const struct tracer *tr = env->tr;
  uint64_t pix = (uint64_t)y * env->fb->width + x;
  mem_load(&tr->mem, tr->layout.camera_base + pix * sizeof *r, sizeof *r, TRACE_CLASS_RAY);
  camera_primary(cf, x, y, env->sc->seed, r);
}

const char *policy_name(enum policy_kind k) { return (unsigned)k < POLICY_COUNT ? NAMES[k] : "?"; }

bool policy_parse(const char *name, enum policy_kind *k) {
  for (int i = 0; i < POLICY_COUNT; i++)
    if (strcmp(name, NAMES[i]) == 0) {
      *k = (enum policy_kind)i;
      return true;
    }
  return false;
}

uint64_t render_stats_total(const struct render_stats *st) {
  uint64_t n = 0;
  for (int t = 0; t < RAY_TYPE_COUNT; t++) n += st->rays[t];
  return n;
}

void policy_run(enum policy_kind k, const struct policy_env *env, const struct policy_params *p) {
  switch (k) {
  case POLICY_RECURSIVE: policy_recursive_run(env, p); break;
  case POLICY_PACKET: policy_packet_run(env, p); break;
  case POLICY_DYNAMIC: policy_dynamic_run(env, p); break;
  default: CHECK(!"unknown policy");
  }
  CHECK(env->st->spawned == env->st->terminated);
}
