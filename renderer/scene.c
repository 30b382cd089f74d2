/* Scene storage: growable arrays of triangles and materials. */
#include "renderer/scene.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sim/err.h"

void scene_init(struct scene *s) {
  memset(s, 0, sizeof *s);
  s->width = s->height = 512;
  s->camera.up = v3(0, 0, 1);
  s->camera.fov_deg = 45.0f;
  s->ambient = 0.1f;
}

void scene_fini(struct scene *s) {
  if (!s) return;
  free(s->tris);
  free(s->mats);
  free(s->mat_slots);
  memset(s, 0, sizeof *s);
}

/* FNV-1a of a material name: the slot a lookup starts at. */
static uint32_t name_hash(const char *name) {
  uint32_t h = 2166136261u;
  for (; *name; name++) h = (h ^ (unsigned char)*name) * 16777619u;
  return h;
}

/* The slot holding name, or the empty slot where it would go (linear probing;
 * the table is at most half full, so a probe ends). */
static uint32_t find_slot(const struct scene *s, const char *name) {
  const uint32_t mask = s->mat_slot_cap - 1;
  uint32_t i = name_hash(name) & mask;
  while (s->mat_slots[i] && strcmp(s->mats[s->mat_slots[i] - 1].name, name) != 0)
    i = (i + 1) & mask;
  return i;
}

int scene_find_material(const struct scene *s, const char *name) {
  if (!s->mat_slot_cap) return -1;
  uint32_t id = s->mat_slots[find_slot(s, name)];
  return id ? (int)(id - 1) : -1;
}

uint32_t scene_add_material(struct scene *s, const struct scene_material *m) {
  if (2ull * (s->mat_count + 1) > s->mat_slot_cap) {
    /* Rehash into twice the slots: ids keep their order, only the index moves. */
    free(s->mat_slots);
    s->mat_slot_cap = s->mat_slot_cap ? 2 * s->mat_slot_cap : 16;
    s->mat_slots = xcalloc(s->mat_slot_cap, sizeof *s->mat_slots);
    for (uint32_t i = 0; i < s->mat_count; i++) s->mat_slots[find_slot(s, s->mats[i].name)] = i + 1;
  }
  const uint32_t slot = find_slot(s, m->name);
  CHECK_EQ(s->mat_slots[slot], 0u); /* the name must be new */
  if (s->mat_count == s->mat_cap) {
    s->mat_cap = s->mat_cap ? 2 * s->mat_cap : 8;
    s->mats = xrealloc(s->mats, (unsigned long long)s->mat_cap * sizeof *s->mats);
  }
  s->mats[s->mat_count] = *m;
  s->mat_slots[slot] = s->mat_count + 1;
  return s->mat_count++;
}

uint32_t scene_material_or_default(struct scene *s, const char *name, vec3 color, float diffuse,
                                   float mirror) {
  int id = scene_find_material(s, name);
  if (id >= 0) return (uint32_t)id;
  struct scene_material m;
  memset(&m, 0, sizeof m);
  snprintf(m.name, sizeof m.name, "%s", name);
  m.color = color;
  m.diffuse = diffuse;
  m.mirror = mirror;
  return scene_add_material(s, &m);
}

void scene_reserve(struct scene *s, uint32_t n) {
  if (n <= s->tri_cap) return;
  s->tri_cap = n;
  s->tris = xrealloc(s->tris, (unsigned long long)n * sizeof *s->tris);
}

/* The geometric normal in double precision, for a triangle whose float cross
 * product overflows (finite vertices, but edges of 1e19 or more: a mesh scaled
 * or moved far out). Float's product is kept for every other triangle, so
 * their normals, and every image, stay as they were. */
static vec3 wide_normal(vec3 a, vec3 b, vec3 c) {
  const double ux = (double)b.x - a.x, uy = (double)b.y - a.y, uz = (double)b.z - a.z;
  const double vx = (double)c.x - a.x, vy = (double)c.y - a.y, vz = (double)c.z - a.z;
  const double nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
  const double l = sqrt(nx * nx + ny * ny + nz * nz);
  return l > 0 ? v3((float)(nx / l), (float)(ny / l), (float)(nz / l)) : v3(0, 0, 1);
}

uint32_t scene_add_tri(struct scene *s, vec3 a, vec3 b, vec3 c, const vec3 *normals,
                       uint32_t material) {
  if (s->tri_count == s->tri_cap) {
    s->tri_cap = s->tri_cap ? 2 * s->tri_cap : 1024;
    s->tris = xrealloc(s->tris, (unsigned long long)s->tri_cap * sizeof *s->tris);
  }
  struct scene_tri *t = &s->tris[s->tri_count];
  memset(t, 0, sizeof *t);
  t->v[0] = a;
  t->v[1] = b;
  t->v[2] = c;
  if (normals) {
    for (int i = 0; i < 3; i++) t->n[i] = normals[i];
  } else {
    vec3 n = v3_cross(v3_sub(b, a), v3_sub(c, a));
    float l = v3_len(n);
    if (!isfinite(l)) n = wide_normal(a, b, c);
    else n = l > 0.0f ? v3_scale(n, 1.0f / l) : v3(0, 0, 1);
    t->n[0] = t->n[1] = t->n[2] = n;
  }
  t->material = material;
  return s->tri_count++;
}

void scene_bounds(const struct scene *s, vec3 *lo, vec3 *hi) {
  if (s->tri_count == 0) {
    *lo = *hi = v3(0, 0, 0);
    return;
  }
  vec3 l = s->tris[0].v[0], h = l;
  for (uint32_t i = 0; i < s->tri_count; i++)
    for (int k = 0; k < 3; k++) {
      l = v3_min(l, s->tris[i].v[k]);
      h = v3_max(h, s->tris[i].v[k]);
    }
  *lo = l;
  *hi = h;
}

static uint64_t fnv(uint64_t h, const void *p, size_t n) {
  const unsigned char *b = p;
  for (size_t i = 0; i < n; i++) h = (h ^ b[i]) * 0x100000001b3ull;
  return h;
}

uint64_t scene_hash(const struct scene *s) {
  uint64_t h = 0xcbf29ce484222325ull;
  h = fnv(h, s->tris, (size_t)s->tri_count * sizeof *s->tris);
  for (uint32_t i = 0; i < s->mat_count; i++) {
    const struct scene_material *m = &s->mats[i];
    h = fnv(h, m->name, strlen(m->name));
    h = fnv(h, &m->color, sizeof m->color);
    h = fnv(h, &m->diffuse, sizeof m->diffuse);
    h = fnv(h, &m->mirror, sizeof m->mirror);
  }
  h = fnv(h, s->lights, s->light_count * sizeof s->lights[0]);
  h = fnv(h, &s->camera, sizeof s->camera);
  h = fnv(h, &s->background, sizeof s->background);
  h = fnv(h, &s->ambient, sizeof s->ambient);
  return h;
}
