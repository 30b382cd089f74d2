/* Scene files (the YAML under scenes/): camera, image size, lights, materials and
 * geometry (procedural generators or mesh files imported through assimp).
 * The format is documented in scenes/README.md. */
#ifndef RTSIM_RENDERER_SCENE_SCENE_FILE_H
#define RTSIM_RENDERER_SCENE_SCENE_FILE_H

#include <stdbool.h>

struct scene;
struct err;

#include <stdint.h>

/* The most triangles a scene may have: half of the host's physical memory
 * at SCENE_FILE_HOST_BYTES_PER_TRIANGLE (the measured peak of loading a scene
 * and building its k-d tree, docs/inputs.md, Limits), and never more than
 * SCENE_FILE_TRIANGLES_HARD_MAX. Every scene file entry's triangles are
 * counted against it before anything is built. */
#define SCENE_FILE_HOST_BYTES_PER_TRIANGLE 600u
#define SCENE_FILE_TRIANGLES_HARD_MAX 100000000ull
uint64_t scene_file_max_triangles(void);

/* Load the scene file at path into s (scene_init is done here). Any problem in
 * the file or in a mesh it names fails with one message at the offending
 * value's file:line:col; s is then empty (scene_fini already done). */
bool scene_file_load(struct scene *s, const char *path, struct err *e);

#endif
