/* Whitted-style shading with the paper's ray types, in linear form. */
#include "renderer/shade.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "renderer/framebuffer.h"
#include "renderer/rng.h"
#include "renderer/scene.h"
#include "renderer/trace.h"

static const char *const RAY_NAMES[RAY_TYPE_COUNT] = {"primary", "shadow", "specular", "diffuse"};

static vec3 tri_normal(const struct scene_tri *t) {
  return v3_norm(v3_cross(v3_sub(t->v[1], t->v[0]), v3_sub(t->v[2], t->v[0])));
}

/* Child ray in the same pixel and path tree. */
static void child_of(const struct ray *r, struct ray *c, uint8_t type, uint32_t slot) {
  c->pixel = r->pixel;
  c->path = (uint32_t)rng_hash2(r->path, ((uint64_t)type << 32) | slot);
  c->depth = r->depth;
  c->type = type;
  c->light = 0;
  c->flags = 0;
  c->hit_prim = -1;
  c->tmin = 0.0f;
  c->tmax = INFINITY;
}

/* An orthonormal basis around n (Duff et al. 2017). */
static void basis(vec3 n, vec3 *t, vec3 *b) {
  float sign = copysignf(1.0f, n.z);
  float a = -1.0f / (sign + n.z);
  float bb = n.x * n.y * a;
  *t = v3(1.0f + sign * n.x * n.x * a, sign * bb, -sign * n.x);
  *b = v3(bb, sign + n.y * n.y * a, -n.y);
}

uint32_t shade_hit(const struct shade_ctx *c, const struct ray *r, const struct trace_hit *h,
                   struct framebuffer *fb, const struct mem_port *mem, struct ray *out) {
  const struct scene *s = c->scene;
  if (h->prim < 0) {
    fb_add(fb, r->pixel, v3_mul(r->w, s->background), mem);
    return 0;
  }
  mem_compute(mem, c->shade_cycles);
  const struct scene_tri *t = &s->tris[h->prim];
  const struct scene_material *m = &s->mats[t->material];
  vec3 err;
  vec3 p = trace_hit_point(s, h, &err);
  float b0 = 1.0f - h->b1 - h->b2;
  vec3 ng = tri_normal(t);
  vec3 ns = v3_norm(
      v3_add(v3_add(v3_scale(t->n[0], b0), v3_scale(t->n[1], h->b1)), v3_scale(t->n[2], h->b2)));
  /* Face the normals toward the incoming ray. */
  if (v3_dot(ng, r->d) > 0.0f) ng = v3_scale(ng, -1.0f);
  if (v3_dot(ns, ng) < 0.0f) ns = v3_scale(ns, -1.0f);
  vec3 albedo = v3_mul(r->w, m->color);
  uint32_t n = 0;

  fb_add(fb, r->pixel, v3_scale(albedo, s->ambient), mem);

  /* Direct light: a shadow ray per light, or the unshadowed term. */
  for (uint32_t i = 0; i < s->light_count && m->diffuse > 0.0f; i++) {
    vec3 L = v3_sub(s->lights[i].pos, p);
    float dist = v3_len(L);
    if (!(dist > 0.0f)) continue;
    vec3 l = v3_scale(L, 1.0f / dist);
    float cosl = v3_dot(ns, l);
    if (cosl <= 0.0f || v3_dot(ng, l) <= 0.0f) continue;
    vec3 contrib = v3_scale(v3_mul(albedo, s->lights[i].intensity), m->diffuse * cosl);
    if (!(c->ray_mask & RAY_MASK(RAY_SHADOW))) {
      fb_add(fb, r->pixel, contrib, mem);
      continue;
    }
    struct ray *sr = &out[n++];
    child_of(r, sr, RAY_SHADOW, i);
    sr->o = trace_offset_origin(p, err, ng, l);
    sr->d = l;
    sr->tmax = v3_len(v3_sub(s->lights[i].pos, sr->o));
    sr->w = contrib;
    sr->ignore_prim = h->prim;
    sr->light = (uint8_t)i;
  }
  if (r->depth >= SHADE_MAX_DEPTH) return n;

  /* Specular reflection about the shading normal (geometric if that dips under). */
  if ((c->ray_mask & RAY_MASK(RAY_SPECULAR)) && m->mirror > 0.0f) {
    vec3 d = v3_norm(r->d);
    vec3 refl = v3_sub(d, v3_scale(ns, 2.0f * v3_dot(d, ns)));
    if (v3_dot(refl, ng) <= 0.0f) refl = v3_sub(d, v3_scale(ng, 2.0f * v3_dot(d, ng)));
    struct ray *sr = &out[n++];
    child_of(r, sr, RAY_SPECULAR, 0);
    sr->depth = (uint8_t)(r->depth + 1);
    sr->o = trace_offset_origin(p, err, ng, refl);
    sr->d = refl;
    sr->w = v3_scale(r->w, m->mirror);
    sr->ignore_prim = h->prim;
  }

  /* Diffuse: a 3x3 stratified, cosine-weighted round. The estimate of the
   * Lambert term is albedo x mean radiance; no 1/0.1 reweighting of the rare
   * second round (the paper's sampling models cost, not an exact integral). */
  if ((c->ray_mask & RAY_MASK(RAY_DIFFUSE)) && m->diffuse > 0.0f) {
    struct rng g = rng_make(c->seed, r->path);
    bool round = r->type != RAY_DIFFUSE || rng_f32(&g) < SHADE_DIFFUSE_CONTINUE;
    if (round) {
      vec3 tb, bb;
      basis(ns, &tb, &bb);
      const int grid = SHADE_DIFFUSE_GRID;
      vec3 w = v3_scale(albedo, m->diffuse / (float)(grid * grid));
      for (int j = 0; j < grid; j++)
        for (int i = 0; i < grid; i++) {
          float u1 = ((float)i + rng_f32(&g)) / (float)grid;
          float u2 = ((float)j + rng_f32(&g)) / (float)grid;
          float rad = sqrtf(u1), phi = 2.0f * 3.14159265358979f * u2;
          float x = rad * cosf(phi), y = rad * sinf(phi), z = sqrtf(fmaxf(0.0f, 1.0f - u1));
          vec3 d = v3_add(v3_add(v3_scale(tb, x), v3_scale(bb, y)), v3_scale(ns, z));
          if (v3_dot(d, ng) <= 0.0f) continue; /* under the true surface: no light */
          struct ray *dr = &out[n++];
          child_of(r, dr, RAY_DIFFUSE, (uint32_t)(j * grid + i));
          dr->depth = (uint8_t)(r->depth + 1);
          dr->o = trace_offset_origin(p, err, ng, d);
          dr->d = v3_norm(d);
          dr->w = w;
          dr->ignore_prim = h->prim;
        }
    }
  }
  return n;
}

void shade_shadow(const struct ray *r, bool occluded, struct framebuffer *fb,
                  const struct mem_port *mem) {
  if (!occluded) fb_add(fb, r->pixel, r->w, mem);
}

bool shade_parse_rays(const char *list, uint32_t *mask) {
  uint32_t m = RAY_MASK(RAY_PRIMARY);
  const char *p = list;
  /* Every item a name: "" and "primary," are refused, not read as primary. */
  for (;;) {
    const char *q = strchr(p, ',');
    size_t len = q ? (size_t)(q - p) : strlen(p);
    int found = -1;
    for (int t = 0; t < RAY_TYPE_COUNT; t++)
      if (strlen(RAY_NAMES[t]) == len && strncmp(p, RAY_NAMES[t], len) == 0) found = t;
    if (found < 0) return false;
    m |= RAY_MASK(found);
    if (!q) break;
    p = q + 1;
  }
  *mask = m;
  return true;
}

void shade_rays_name(uint32_t mask, char *buf, unsigned cap) {
  buf[0] = '\0';
  size_t len = 0;
  for (int t = 0; t < RAY_TYPE_COUNT; t++)
    if (mask & RAY_MASK(t)) {
      snprintf(buf + len, cap - len, "%s%s", len ? "," : "", RAY_NAMES[t]);
      len = strlen(buf);
    }
}
