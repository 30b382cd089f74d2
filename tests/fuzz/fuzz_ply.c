/* libFuzzer entry point for the PLY reader: any bytes must give a mesh whose
 * indices are in range and whose coordinates are finite, or one error; never
 * a crash, a hang or unbounded memory. Built with -DRTSIM_FUZZ=ON and run by
 * .ci/fuzz on corpus/ply with ply.dict (docs/testing.md, Fuzzing). */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "renderer/scene/ply.h"
#include "sim/err.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  struct ply_mesh m;
  struct err e;
  memset(&e, 0, sizeof e);
  if (ply_read_memory(data, size, "fuzz.ply", &m, &e)) {
    CHECK(!e.set);
    for (uint64_t i = 0; i < 3ull * m.tri_count; i++) CHECK_LT(m.tri[i], m.vertex_count);
    for (uint64_t i = 0; i < 3ull * m.vertex_count; i++) CHECK(isfinite(m.pos[i]));
  } else {
    CHECK(e.set && e.msg[0] != '\0' && strchr(e.msg, '\n') == NULL);
    CHECK(m.pos == NULL && m.tri == NULL && m.normal == NULL);
  }
  ply_mesh_fini(&m);
  return 0;
}
