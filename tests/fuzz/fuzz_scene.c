/* libFuzzer target: scene files (renderer/scene/scene_file.c through sim/cfg.c).
 * The input is a YAML file in tests/data/scenes/ of the scratch folder (its
 * meshes resolve as in the repository). Scenes are parsed and checked in
 * full, but built only when small: large generators and meshes outside the
 * test data stand in as one triangle (fuzz_util.c). Any bytes must give a
 * scene whose triangles name its materials, whose vertices and normals are
 * finite and whose camera frame is finite, or one error on one line. */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "renderer/camera.h"
#include "renderer/scene.h"
#include "renderer/scene/scene_file.h"
#include "sim/err.h"
#include "tests/fuzz/fuzz_util.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static bool finite3(vec3 v) { return isfinite(v.x) && isfinite(v.y) && isfinite(v.z); }

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  const char *path = fuzz_file("tests/data/scenes/fuzz.yaml", data, size);
  static struct scene s;
  struct err e;
  memset(&e, 0, sizeof e);
  if (!scene_file_load(&s, path, &e)) {
    fuzz_check_err(&e);
    CHECK(s.tris == NULL && s.tri_count == 0);
    return 0;
  }
  CHECK(!e.set);
  CHECK_GT(s.tri_count, 0);
  CHECK(s.width >= 1 && s.height >= 1);
  for (uint32_t i = 0; i < s.tri_count; i++) {
    const struct scene_tri *t = &s.tris[i];
    CHECK_LT(t->material, s.mat_count);
    for (int k = 0; k < 3; k++) CHECK(finite3(t->v[k]) && finite3(t->n[k]));
  }
  struct camera_frame cf;
  camera_frame_init(&cf, &s.camera, s.width, s.height);
  CHECK(finite3(cf.origin) && finite3(cf.forward) && finite3(cf.right) && finite3(cf.up));
  scene_fini(&s);
  return 0;
}
