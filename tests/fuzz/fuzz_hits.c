/* libFuzzer target: rtsim hits' ray CSV (app/cmd_hits.c), read and traced
 * as `rtsim hits SCENE < rays.csv` does (app_hits_answer) against a small
 * sphereflake (10 spheres, 482 triangles) loaded once; hits go to /dev/null.
 * Any bytes must give 0 (every row answered) or 2 (one message); never a
 * crash or a hang in the reader or in the traversal of whatever ray it
 * accepts. */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "app/app.h"
#include "renderer/trace.h"
#include "sim/err.h"
#include "sim/mem.h"
#include "tests/fuzz/fuzz_util.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static const char SCENE[] = "camera: {from: [0, -8, 3], at: [0, 0, 0]}\n"
                            "geometry:\n"
                            "  - {generator: sphereflake, detail: 1, tessellation: 2}\n";

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  static struct app_world w;
  static struct trace_ctx tr;
  static FILE *out;
  if (!out) {
    CHECK(
        app_world_load(&w, fuzz_file("hits-scene.yaml", (const uint8_t *)SCENE, sizeof SCENE - 1)));
    struct trace_layout layout;
    trace_layout_default(&layout);
    trace_init(&tr, &w.scene, &w.kd, mem_port_native(), &layout);
    CHECK((out = fopen("/dev/null", "w")) != NULL);
  }
  /* fmemopen wants a non-empty buffer: an empty input is one byte read. */
  static char empty[1];
  FILE *in = size ? fmemopen((void *)data, size, "r") : fmemopen(empty, 1, "r");
  CHECK(in != NULL);
  if (!size) fgetc(in);
  int rc = app_hits_answer(&tr, in, out);
  fclose(in);
  CHECK(rc == 0 || rc == 2);
  return 0;
}
