/* Scene files: YAML (through sim/cfg) to a struct scene. All reads happen
 * here; every value is range-checked at its source position; unknown keys are
 * errors that list what was expected. */
#include "renderer/scene/scene_file.h"

#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "renderer/bvh.h"
#include "renderer/camera.h"
#include "renderer/scene.h"
#include "renderer/scene/gen.h"
#include "renderer/scene/meshio.h"
#include "sim/cfg.h"
#include "sim/err.h"

/* Limits that keep a typo from asking for a machine-sized allocation. */
#define SCENE_MAX_PIXELS 16384

/* out = "path.key" (or "key" at the top level). */
static void join_path(char *out, size_t cap, const char *path, const char *key) {
  int n = snprintf(out, cap, "%s%s%s", path, path[0] ? "." : "", key);
  if (n < 0 || (size_t)n >= cap) snprintf(out, cap, "%s", key);
}

static vec3 to_vec3(const double v[3]) { return v3((float)v[0], (float)v[1], (float)v[2]); }

static bool opt_vec3(const struct cfg_doc *d, struct cfg_node *m, const char *key, const char *path,
                     double lo, double hi, vec3 *out, struct err *e) {
  struct cfg_node *n = cfg_get(m, key);
  if (!n) return true;
  char p[128];
  join_path(p, sizeof p, path, key);
  double v[3];
  if (!cfg_f64_list(d, n, p, 3, lo, hi, v, e)) return false;
  *out = to_vec3(v);
  return true;
}

static bool req_vec3(const struct cfg_doc *d, struct cfg_node *m, const struct cfg_node *owner,
                     const char *key, const char *path, double lo, double hi, vec3 *out,
                     struct err *e) {
  if (!cfg_get(m, key)) return cfg_fail(d, owner, path, e, "missing required key '%s'", key);
  return opt_vec3(d, m, key, path, lo, hi, out, e);
}

static bool opt_f64(const struct cfg_doc *d, struct cfg_node *m, const char *key, const char *path,
                    double lo, double hi, double *out, struct err *e) {
  struct cfg_node *n = cfg_get(m, key);
  if (!n) return true;
  char p[128];
  join_path(p, sizeof p, path, key);
  return cfg_f64(d, n, p, lo, hi, out, e);
}

static bool opt_u64(const struct cfg_doc *d, struct cfg_node *m, const char *key, const char *path,
                    uint64_t lo, uint64_t hi, uint64_t *out, struct err *e) {
  struct cfg_node *n = cfg_get(m, key);
  if (!n) return true;
  char p[128];
  join_path(p, sizeof p, path, key);
  return cfg_u64(d, n, p, lo, hi, out, e);
}

static bool load_camera(const struct cfg_doc *d, struct cfg_node *n, struct scene *s,
                        struct err *e) {
  if (!cfg_expect_map(d, n, "camera", e)) return false;
  struct scene_camera *c = &s->camera;
  double fov = c->fov_deg;
  if (!req_vec3(d, n, n, "from", "camera", -1e30, 1e30, &c->from, e) ||
      !req_vec3(d, n, n, "at", "camera", -1e30, 1e30, &c->at, e) ||
      !opt_vec3(d, n, "up", "camera", -1e30, 1e30, &c->up, e) ||
      !opt_f64(d, n, "fov_deg", "camera", 0.01, 179.0, &fov, e) ||
      !cfg_check_keys(d, n, "camera", e))
    return false;
  c->fov_deg = (float)fov;
  switch (camera_check(c)) {
  case CAMERA_OK: return true;
  case CAMERA_NO_VIEW:
    return cfg_fail(d, cfg_get(n, "at"), "camera.at", e, "equals camera.from (no view direction)");
  case CAMERA_BAD_UP:
    return cfg_fail(d, cfg_get(n, "up") ? cfg_get(n, "up") : n, "camera.up", e,
                    "zero or parallel to the view direction (as far as 32-bit floats can tell)");
  }
  return false;
}

static bool load_image(const struct cfg_doc *d, struct cfg_node *n, struct scene *s,
                       struct err *e) {
  if (!cfg_expect_map(d, n, "image", e)) return false;
  uint64_t w = s->width, h = s->height;
  if (!opt_u64(d, n, "width", "image", 1, SCENE_MAX_PIXELS, &w, e) ||
      !opt_u64(d, n, "height", "image", 1, SCENE_MAX_PIXELS, &h, e) ||
      !cfg_check_keys(d, n, "image", e))
    return false;
  s->width = (uint32_t)w;
  s->height = (uint32_t)h;
  return true;
}

static bool load_lights(const struct cfg_doc *d, struct cfg_node *n, struct scene *s,
                        struct err *e) {
  if (!cfg_expect_seq(d, n, "lights", e)) return false;
  if (n->count > SCENE_MAX_LIGHTS)
    return cfg_fail(d, n, "lights", e, "too many lights (got %u, expected at most %d)", n->count,
                    SCENE_MAX_LIGHTS);
  for (uint32_t i = 0; i < n->count; i++) {
    struct cfg_node *l = &n->items[i];
    char p[64];
    snprintf(p, sizeof p, "lights[%u]", i);
    if (!cfg_expect_map(d, l, p, e)) return false;
    struct scene_light *L = &s->lights[i];
    L->intensity = v3(1, 1, 1);
    if (!req_vec3(d, l, l, "position", p, -1e30, 1e30, &L->pos, e) ||
        !opt_vec3(d, l, "intensity", p, 0, 1e30, &L->intensity, e) || !cfg_check_keys(d, l, p, e))
      return false;
  }
  s->light_count = n->count;
  return true;
}

static bool load_materials(const struct cfg_doc *d, struct cfg_node *n, struct scene *s,
                           struct err *e) {
  if (!cfg_expect_map(d, n, "materials", e)) return false;
  for (uint32_t i = 0; i < n->count; i++) {
    struct cfg_node *m = &n->items[i];
    m->used = true;
    char p[128];
    snprintf(p, sizeof p, "materials.%s", m->key);
    if (strlen(m->key) >= SCENE_NAME_MAX)
      return err_set(e, d->file, m->key_line, m->key_col,
                     "%s: name too long (expected at most %d characters)", p, SCENE_NAME_MAX - 1);
    if (!cfg_expect_map(d, m, p, e)) return false;
    struct scene_material mat;
    memset(&mat, 0, sizeof mat);
    snprintf(mat.name, sizeof mat.name, "%s", m->key);
    mat.color = v3(0.8f, 0.8f, 0.8f);
    double diffuse = 1.0, mirror = 0.0;
    if (!opt_vec3(d, m, "color", p, 0, 1, &mat.color, e) ||
        !opt_f64(d, m, "diffuse", p, 0, 1, &diffuse, e) ||
        !opt_f64(d, m, "mirror", p, 0, 1, &mirror, e) || !cfg_check_keys(d, m, p, e))
      return false;
    mat.diffuse = (float)diffuse;
    mat.mirror = (float)mirror;
    scene_add_material(s, &mat);
  }
  return true;
}

/* Directory part of path (with trailing slash), "" if none. */
static void dir_of(const char *path, char *out, size_t cap) {
  const char *slash = strrchr(path, '/');
  size_t n = slash ? (size_t)(slash - path + 1) : 0;
  if (n >= cap) n = 0;
  memcpy(out, path, n);
  out[n] = '\0';
}

static const char *const GENERATORS[] = {"sphereflake", "grove", "room", NULL};

uint64_t scene_file_max_triangles(void) {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  if (pages <= 0 || page <= 0) return SCENE_FILE_TRIANGLES_HARD_MAX;
  uint64_t n = (uint64_t)pages * (uint64_t)page / 2 / SCENE_FILE_HOST_BYTES_PER_TRIANGLE;
  return n < SCENE_FILE_TRIANGLES_HARD_MAX ? n : SCENE_FILE_TRIANGLES_HARD_MAX;
}

/* With `count` set, read and check the entry and set *count to exactly the
 * triangles it would add, building nothing; without, build it. */
static bool load_generator(const struct cfg_doc *d, struct cfg_node *g, const char *p,
                           struct scene *s, uint64_t *count, struct err *e) {
  int kind = 0;
  char gp[96];
  snprintf(gp, sizeof gp, "%s.generator", p);
  if (!cfg_enum(d, cfg_get(g, "generator"), gp, GENERATORS, &kind, e)) return false;
  /* Read in the order the keys are listed when one is unknown. */
  uint64_t seed = s->seed, levels = 4, tess = 3;
  double detail = 1.0;
  if (kind == 0 ? !opt_u64(d, g, "detail", p, 0, 6, &levels, e) ||
                      !opt_u64(d, g, "tessellation", p, 1, 64, &tess, e)
                : !opt_f64(d, g, "detail", p, 1e-4, 200.0, &detail, e))
    return false;
  if (!opt_u64(d, g, "seed", p, 0, UINT64_MAX, &seed, e) || !cfg_check_keys(d, g, p, e))
    return false;
  const uint64_t before = s->tri_count;
  if (kind == 0) {
    uint64_t n = gen_sphereflake_tri_count((uint32_t)levels, (uint32_t)tess);
    if (count) *count = n;
    else gen_sphereflake(s, (uint32_t)levels, (uint32_t)tess);
  } else {
    uint64_t n = kind == 1 ? gen_grove_tri_count(detail) : gen_room_tri_count(detail);
    if (count) *count = n;
    else if (kind == 1) gen_grove(s, detail, seed);
    else gen_room(s, detail, seed);
  }
  /* The estimate is exact: what the scene file checked is what was built. */
  if (!count) {
    uint64_t n;
    CHECK(load_generator(d, g, p, s, &n, e));
    CHECK_EQ(s->tri_count - before, n);
  }
  return true;
}

/* Reported the way a mesh's own errors are: at the entry's mesh value, with
 * the mesh's file (and line and column when it has them). */
static bool mesh_fail(const struct cfg_doc *d, struct cfg_node *mn, const char *p,
                      const struct err *me, struct err *e) {
  char mp[96];
  snprintf(mp, sizeof mp, "%s.mesh", p);
  /* Keep the mesh's own position (a PLY header line, an ASCII data line). */
  char at[32] = "";
  if (me->line > 0 && me->col > 0) snprintf(at, sizeof at, ":%d:%d", me->line, me->col);
  else if (me->line > 0) snprintf(at, sizeof at, ":%d", me->line);
  return cfg_fail(d, mn, mp, e, "%s%s: %s", me->file, at, me->msg);
}

/* With `least` set, read and check the entry and set *least to the fewest
 * triangles its file's header promises, reading no data; without, import it,
 * refused if it holds more than `room` triangles. */
static bool load_mesh(const struct cfg_doc *d, struct cfg_node *g, const char *p,
                      const char *scene_path, struct scene *s, uint64_t *least, uint64_t room,
                      struct err *e) {
  struct cfg_node *mn = cfg_get(g, "mesh");
  char file[400], mat_name[SCENE_NAME_MAX] = "default", mp[96];
  snprintf(mp, sizeof mp, "%s.mesh", p);
  if (!cfg_str(d, mn, mp, file, sizeof file, e)) return false;
  struct cfg_node *matn = cfg_get(g, "material");
  snprintf(mp, sizeof mp, "%s.material", p);
  if (matn && !cfg_str(d, matn, mp, mat_name, sizeof mat_name, e)) return false;
  struct meshio_xform xf = {1.0f, v3(0, 0, 0)};
  double scale = 1.0;
  if (!opt_f64(d, g, "scale", p, 1e-30, 1e30, &scale, e) ||
      !opt_vec3(d, g, "translate", p, -1e30, 1e30, &xf.translate, e) || !cfg_check_keys(d, g, p, e))
    return false;
  xf.scale = (float)scale;
  char full[1024];
  if (file[0] == '/') snprintf(full, sizeof full, "%s", file);
  else {
    char dir[600];
    dir_of(scene_path, dir, sizeof dir);
    snprintf(full, sizeof full, "%s%s", dir, file);
  }
  struct err me;
  memset(&me, 0, sizeof me);
  if (least) {
    uint64_t most;
    return meshio_estimate(full, least, &most, &me) || mesh_fail(d, mn, p, &me, e);
  }
  /* Generators may add the material this entry names, so it is looked up now. */
  int mat = scene_find_material(s, mat_name);
  if (mat < 0) {
    if (matn) return cfg_fail(d, matn, mp, e, "no material named '%s' in materials", mat_name);
    mat = (int)scene_material_or_default(s, "default", v3(0.8f, 0.8f, 0.8f), 1.0f, 0.0f);
  }
  return meshio_import(s, full, &xf, (uint32_t)mat, room, &me) || mesh_fail(d, mn, p, &me, e);
}

static bool load_geometry(const struct cfg_doc *d, struct cfg_node *n, const char *scene_path,
                          struct scene *s, struct err *e) {
  if (!cfg_expect_seq(d, n, "geometry", e)) return false;
  if (n->count == 0)
    return cfg_fail(d, n, "geometry", e, "empty list (expected at least one item)");
  /* Pass 0 checks every entry and adds up its triangles (exact for the
   * generators, a PLY header's face count for meshes) against the cap before
   * anything is built; pass 1 builds, and refuses a mesh whose file holds
   * more than the cap leaves room for before adding any of it. */
  const uint64_t cap = scene_file_max_triangles();
  for (int pass = 0; pass < 2; pass++) {
    uint64_t total = 0;
    for (uint32_t i = 0; i < n->count; i++) {
      struct cfg_node *g = &n->items[i];
      char p[64];
      snprintf(p, sizeof p, "geometry[%u]", i);
      if (!cfg_expect_map(d, g, p, e)) return false;
      bool is_gen = cfg_peek(g, "generator") != NULL, is_mesh = cfg_peek(g, "mesh") != NULL;
      if (is_gen == is_mesh)
        return cfg_fail(d, g, p, e, "expected exactly one of 'generator' or 'mesh'");
      uint64_t k = 0, *count = pass == 0 ? &k : NULL;
      if (is_gen ? !load_generator(d, g, p, s, count, e)
                 : !load_mesh(d, g, p, scene_path, s, count, cap - s->tri_count, e))
        return false;
      total += k;
      if (pass == 0 && (k > cap || total > cap))
        return cfg_fail(d, g, p, e,
                        "too many triangles: this entry %s %llu, the scene would "
                        "have %s%llu, expected at most %llu (about %u bytes of host memory a "
                        "triangle, scene and k-d tree, within half of this host's memory; "
                        "docs/inputs.md, Limits)",
                        is_gen ? "builds" : "holds at least", (unsigned long long)k,
                        is_gen ? "" : "at least ", (unsigned long long)total,
                        (unsigned long long)cap, SCENE_FILE_HOST_BYTES_PER_TRIANGLE);
    }
    if (pass == 0) scene_reserve(s, (uint32_t)total);
  }
  if (s->tri_count == 0) return cfg_fail(d, n, "geometry", e, "the scene has no triangles");
  return true;
}

/* kd_tree: {splits: whole | clipped}. How the k-d tree treats a triangle cut
 * by a split plane: whole keeps its full bounds on both sides (PBRT, as the
 * paper); clipped carries only the bounds of the part inside each child. */
static bool load_kd_tree(struct cfg_doc *d, struct cfg_node *n, struct scene *s, struct err *e) {
  if (!cfg_expect_map(d, n, "kd_tree", e)) return false;
  struct cfg_node *v = cfg_get(n, "splits");
  static const char *const splits[] = {"whole", "clipped", NULL};
  int k = 0;
  if (v && !cfg_enum(d, v, "kd_tree.splits", splits, &k, e)) return false;
  s->kd_clip = k == 1;
  return cfg_check_keys(d, n, "kd_tree", e);
}

/* accel: kd | bvh2 | bvh8, the acceleration structure the scene is traced
 * through (bvh.h); its position is kept for messages about it. */
static bool load_accel(struct cfg_doc *d, struct cfg_node *n, struct scene *s, struct err *e) {
  static const char *const names[] = {"kd", "bvh2", "bvh8", NULL};
  _Static_assert(ACCEL_COUNT == 3, "one name a structure");
  int k = 0;
  if (!cfg_enum(d, n, "accel", names, &k, e)) return false;
  s->accel = (uint8_t)k;
  s->accel_line = n->line;
  s->accel_col = n->col;
  return true;
}

bool scene_file_load(struct scene *s, const char *path, struct err *e) {
  scene_init(s);
  struct cfg_doc d;
  if (!cfg_load_file(&d, path, e)) return false;
  bool ok = false;
  struct cfg_node *r = &d.root, *n;
  if (!cfg_expect_map(&d, r, "", e)) goto done;
  if ((n = cfg_get(r, "name")) && !cfg_str(&d, n, "name", s->name, sizeof s->name, e)) goto done;
  if ((n = cfg_get(r, "seed")) && !cfg_u64(&d, n, "seed", 0, UINT64_MAX, &s->seed, e)) goto done;
  if ((n = cfg_get(r, "image")) && !load_image(&d, n, s, e)) goto done;
  if (!(n = cfg_get(r, "camera"))) {
    cfg_fail(&d, r, "", e, "missing required key 'camera'");
    goto done;
  }
  if (!load_camera(&d, n, s, e)) goto done;
  if (!opt_vec3(&d, r, "background", "", 0, 1e30, &s->background, e)) goto done;
  double amb = s->ambient;
  if (!opt_f64(&d, r, "ambient", "", 0, 1, &amb, e)) goto done;
  s->ambient = (float)amb;
  if ((n = cfg_get(r, "lights")) && !load_lights(&d, n, s, e)) goto done;
  if ((n = cfg_get(r, "materials")) && !load_materials(&d, n, s, e)) goto done;
  if ((n = cfg_get(r, "kd_tree")) && !load_kd_tree(&d, n, s, e)) goto done;
  if ((n = cfg_get(r, "accel")) && !load_accel(&d, n, s, e)) goto done;
  if (!(n = cfg_get(r, "geometry"))) {
    cfg_fail(&d, r, "", e, "missing required key 'geometry'");
    goto done;
  }
  /* Check the top level before generating geometry, which can take seconds. */
  if (!cfg_check_keys(&d, r, "", e)) goto done;
  ok = load_geometry(&d, n, path, s, e);
done:
  cfg_free(&d);
  if (!ok) scene_fini(s);
  return ok;
}
