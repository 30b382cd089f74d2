/* rtsim export: the scene's triangles as PLY, face i = primitive i. */
#include "app/app.h"

#include <stdio.h>
#include <string.h>

#include "app/opts.h"
#include "renderer/scene/meshio.h"
#include "renderer/scene/scene_file.h"
#include "sim/err.h"

static const char HELP[] =
    "usage: rtsim export SCENE.yaml -o SCENE.ply\n"
    "\n"
    "Write the scene's triangles as a binary little-endian PLY file: three unshared\n"
    "vertices per face, face i is primitive i (the 'prim' of 'rtsim hits'), so any\n"
    "other ray tracer can load exactly this geometry.\n"
    "\n"
    "example:\n"
    "  rtsim export scenes/small/room.yaml -o build/room.ply\n"
    "\n"
    "options:\n"
    "  -o, --output FILE   PLY file to write (required)\n"
    "  -h, --help          this text\n";

int cmd_export(int argc, char **argv) {
  const char *out = NULL;
  const struct opts_spec spec[] = {OPTS_STR("output", 'o', &out), OPTS_END};
  struct opts_args args;
  int rc = opts_parse("export", HELP, spec, argc, argv, &args);
  if (rc != OPTS_GO) return rc;
  const char *scene_path = opts_one_scene(&args);
  if (!scene_path) return APP_EXIT_USAGE;
  if (!out) return app_usage_error("export", "missing -o SCENE.ply");
  struct scene s;
  struct err e;
  memset(&e, 0, sizeof e);
  if (!scene_file_load(&s, scene_path, &e)) return app_report(&e);
  bool ok = meshio_export_ply(&s, out, &e);
  if (ok) printf("triangles: %u\noutput: %s\n", s.tri_count, out);
  scene_fini(&s);
  return ok ? 0 : app_report(&e);
}
