/* Scene files: the committed scenes load with the paper's triangle counts,
 * meshes are placed as asked, and scene materials override generator ones. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "renderer/scene.h"
#include "renderer/scene/scene_file.h"
#include "sim/err.h"
#include "testing.h"

static int load(struct scene *s, const char *path) {
  struct err e;
  memset(&e, 0, sizeof e);
  int ok = scene_file_load(s, path, &e);
  EXPECTF(ok, "%s: %s:%d:%d %s", path, e.file, e.line, e.col, e.msg);
  return ok;
}

int main(void) {
  static const struct {
    const char *file;
    uint32_t lo, hi; /* accepted triangle count range */
  } scenes[] = {
      {"/scenes/sphereflake.yaml", 797150, 797150}, /* 7381 x 108 + 2 */
      {"/scenes/grove.yaml", 164000 * 95 / 100, 164000 * 105 / 100},
      {"/scenes/room.yaml", 47000 * 95 / 100, 47000 * 105 / 100},
      {"/scenes/small/sphereflake.yaml", 9830, 9830}, /* 91 x 108 + 2 */
      {"/scenes/small/grove.yaml", 1000, 10000},
      {"/scenes/small/room.yaml", 1000, 10000},
  };
  char path[1024];
  for (size_t i = 0; i < sizeof scenes / sizeof scenes[0]; i++) {
    struct scene s;
    snprintf(path, sizeof path, "%s%s", RTSIM_SOURCE_DIR, scenes[i].file);
    if (!load(&s, path)) continue;
    EXPECTF(s.tri_count >= scenes[i].lo && s.tri_count <= scenes[i].hi, "%s: %u triangles",
            scenes[i].file, s.tri_count);
    EXPECTF(s.light_count == 3, "%s: %u lights (the paper's scenes have three)", scenes[i].file,
            s.light_count);
    EXPECT(s.width > 0 && s.height > 0 && s.camera.fov_deg > 0);
    scene_fini(&s);
  }

  /* Two loads are identical (generators are deterministic). */
  struct scene a, b;
  snprintf(path, sizeof path, "%s/scenes/small/grove.yaml", RTSIM_SOURCE_DIR);
  if (load(&a, path) && load(&b, path)) EXPECT(scene_hash(&a) == scene_hash(&b));
  scene_fini(&a);
  scene_fini(&b);

  /* A mesh item: tri.obj is (0,0,0) (1,0,0) (0,1,0); scale 2. */
  struct scene s;
  if (load(&s, RTSIM_TEST_DATA "/scenes/good_mesh.yaml")) {
    EXPECT(s.tri_count == 1);
    const struct scene_tri *t = &s.tris[0];
    EXPECT(t->v[0].x == 0 && t->v[1].x == 2 && t->v[2].y == 2 && t->v[2].x == 0);
    EXPECT(s.mats[t->material].color.x > 0);
    scene_fini(&s);
  }

  /* The same triangle scaled by 2.18e20 (a fuzzer's find): its vertices are
   * finite, but float's cross product of its edges overflows; its normal is
   * still the unit +Z, not NaN. Moved far out instead, the same. */
  static const char *const far[] = {"scale: 218446744073709551615", "scale: 1e19",
                                    "translate: [-1e30, 1e30, 0]\n    scale: 1e30"};
  for (size_t i = 0; i < sizeof far / sizeof far[0]; i++) {
    const char *big = RTSIM_TMP "/scene_far_mesh.yaml";
    if (!testing_writef(big,
                        "camera: {from: [0, -2, 1], at: [0, 0, 0]}\ngeometry:\n  - mesh: "
                        "%s/scenes/tri.obj\n    %s\n",
                        RTSIM_TEST_DATA, far[i]))
      break;
    if (!load(&s, big)) continue;
    EXPECTF(s.tri_count == 1, "%s: %u triangles", far[i], s.tri_count);
    for (int k = 0; k < 3; k++) {
      vec3 n = s.tris[0].n[k];
      EXPECTF(n.x == 0 && n.y == 0 && n.z == 1, "%s: normal %d is (%g, %g, %g), want +Z", far[i], k,
              (double)n.x, (double)n.y, (double)n.z);
    }
    scene_fini(&s);
  }

  /* Materials in the file override the generator's defaults by name. */
  snprintf(path, sizeof path, "%s/scenes/sphereflake.yaml", RTSIM_SOURCE_DIR);
  if (load(&s, path)) {
    int flake = scene_find_material(&s, "flake");
    EXPECT(flake >= 0 && s.mats[flake].mirror == 0.5f && s.mats[flake].diffuse == 0.5f);
    EXPECT(fabsf(s.mats[flake].color.y - 0.9f) < 1e-6f);
    scene_fini(&s);
  }

  /* 49,000 materials, and a mesh that names the last: each name finds its
   * own id (the lookup is a hash, so this loads in linear time), an unknown
   * name none. */
  const char *many = RTSIM_TMP "/scene_many_materials.yaml";
  FILE *f = fopen(many, "w");
  EXPECT(f != NULL);
  if (f) {
    fputs("camera: {from: [0, -5, 1], at: [0, 0, 0]}\nmaterials:\n", f);
    for (int i = 0; i < 49000; i++) fprintf(f, " m%d: {}\n", i);
    fprintf(f, "geometry:\n  - mesh: %s/scenes/tri.obj\n    material: m48999\n", RTSIM_TEST_DATA);
    fclose(f);
    if (load(&s, many)) {
      EXPECT(s.mat_count == 49000 && s.tri_count == 1 && s.tris[0].material == 48999);
      char name[32];
      int wrong = 0;
      for (int i = 0; i < 49000; i++) {
        snprintf(name, sizeof name, "m%d", i);
        wrong += scene_find_material(&s, name) != i;
      }
      EXPECTF(wrong == 0, "%d of 49000 names found the wrong material", wrong);
      EXPECT(scene_find_material(&s, "m49000") == -1 && scene_find_material(&s, "") == -1);
      scene_fini(&s);
    }
    remove(many);
  }
  return testing_done("test_scene_file");
}
