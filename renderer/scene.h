/* The scene: triangles, materials, point lights, camera, image size. The scene
 * owns its arrays. Triangle index = primitive id = face index in `rtsim export`. */
#ifndef RTSIM_RENDERER_SCENE_H
#define RTSIM_RENDERER_SCENE_H

#include <stdbool.h>
#include <stdint.h>

#include "renderer/vec.h"

#define SCENE_NAME_MAX 64
#define SCENE_MAX_LIGHTS 16

struct scene_material {
  char name[SCENE_NAME_MAX];
  vec3 color;    /* base colour, linear RGB in [0,1] */
  float diffuse; /* weight of the diffuse (Lambert) term, >= 0 */
  float mirror;  /* specular mirror reflectance in [0,1] */
};

struct scene_light {
  vec3 pos;
  vec3 intensity; /* RGB radiant intensity; irradiance falls as 1/d^2 only if falloff */
};

struct scene_camera {
  vec3 from, at, up;
  float fov_deg; /* full vertical field of view, degrees */
};

/* A triangle: three vertices and three shading normals (equal to the geometric
 * normal for flat faces). 76 bytes on the host; the simulated record size is a
 * separate, configurable number. */
struct scene_tri {
  vec3 v[3];
  vec3 n[3];
  uint32_t material;
};

struct scene {
  char name[SCENE_NAME_MAX];
  struct scene_tri *tris;
  uint32_t tri_count, tri_cap;
  struct scene_material *mats;
  uint32_t mat_count, mat_cap;
  uint32_t *mat_slots; /* hash of the names: material id + 1, 0 = empty (mat_slot_cap slots,
                          a power of two, at least twice mat_count) */
  uint32_t mat_slot_cap;
  struct scene_light lights[SCENE_MAX_LIGHTS];
  uint32_t light_count;
  struct scene_camera camera;
  uint32_t width, height; /* default image size in pixels */
  vec3 background;        /* colour of rays that leave the scene */
  float ambient;          /* ambient term weight (times material colour) */
  uint64_t seed;          /* generator seed (also the default render seed) */
  bool kd_clip;           /* kd_tree.splits: clipped (perfect splits) rather than
                             whole (PBRT's and the paper's tree, the default) */

  /* enum accel_kind (bvh.h): the structure traced (the scene file's `accel`,
   * default kd), and where the file set it (line 0: not set). */
  uint8_t accel;
  int accel_line, accel_col;
};

void scene_init(struct scene *s);
void scene_fini(struct scene *s);

/* Material id of `name`, or -1. Constant time (a hash of the names), so a
 * scene of tens of thousands of materials loads in linear time. */
int scene_find_material(const struct scene *s, const char *name);
/* Add a material (name must be new); returns its id. */
uint32_t scene_add_material(struct scene *s, const struct scene_material *m);
/* Id of material `name`; adds `dflt` under that name if the scene has none.
 * Lets the scene file override a generator's built-in materials by name. */
uint32_t scene_material_or_default(struct scene *s, const char *name, vec3 color, float diffuse,
                                   float mirror);

/* Make room for n triangles in all (no-op if there is): a scene whose size is
 * known ahead takes n * 76 bytes, not up to twice that from doubling. */
void scene_reserve(struct scene *s, uint32_t n);

/* Append a triangle. Normals may be NULL: all three become the geometric normal
 * (or +Z for a zero-area triangle). Returns the new primitive id. */
uint32_t scene_add_tri(struct scene *s, vec3 a, vec3 b, vec3 c, const vec3 *normals,
                       uint32_t material);

/* Axis-aligned bounds of all triangles ({0,0,0} both when empty). */
void scene_bounds(const struct scene *s, vec3 *lo, vec3 *hi);

/* FNV-1a 64 over the host bytes of every triangle (vertices, normals,
 * material id), then each material (name, colour, weights), the lights, the
 * camera, the background and the ambient weight: all the loaded scene that
 * shapes a render, but not its name, default image size or seed. Names a
 * scene in stats (scene_hash) and lets tests compare two loads. */
uint64_t scene_hash(const struct scene *s);

#endif
