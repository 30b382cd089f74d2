/* Scene files (the YAML under scenes/): camera, image size, lights, materials and
 * geometry (procedural generators or mesh files imported through assimp).
 * The format is documented in scenes/README.md. */
#ifndef RTSIM_RENDERER_SCENE_FILE_H
#define RTSIM_RENDERER_SCENE_FILE_H

#include <stdbool.h>

struct scene;
struct err;

/* Load the scene file at path into s (scene_init is done here). Any problem in
 * the file or in a mesh it names fails with one message at the offending
 * value's file:line:col; s is then empty (scene_fini already done). */
bool scene_file_load(struct scene *s, const char *path, struct err *e);

#endif
