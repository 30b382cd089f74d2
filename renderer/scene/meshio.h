/* Mesh files in and out: import of PLY through rtsim's own strict reader
 * (renderer/scene/ply.h) and of any other format assimp reads (OBJ, glTF, ...)
 * through its C API, and export of the scene's triangles as a PLY file whose
 * faces are in primitive-id order, so any other ray tracer loads exactly our
 * geometry. */
#ifndef RTSIM_RENDERER_SCENE_MESHIO_H
#define RTSIM_RENDERER_SCENE_MESHIO_H

#include <stdbool.h>
#include <stdint.h>

#include "renderer/vec.h"

struct scene;
struct err;

/* Placement applied to imported vertices: p' = p * scale + translate. */
struct meshio_xform {
  float scale;
  vec3 translate;
};

/* Append every triangle of the mesh file at `path` (all meshes of the file,
 * node transforms applied, polygons triangulated, points and lines dropped)
 * with material id `material`. Vertex normals from the file are used when
 * present. Fails (e->file = path) if the file cannot be read, holds no
 * triangle or more than `max_tris`; the scene is left unchanged then. */
bool meshio_import(struct scene *s, const char *path, const struct meshio_xform *xf,
                   uint32_t material, uint64_t max_tris, struct err *e);

/* Bounds on the triangles meshio_import would add from `path`, reading at
 * most a header: a PLY's face count and the most its size can hold (its
 * header is checked); for other formats nothing is known before import
 * (0 and UINT64_MAX). Fails (e->file = path) on a PLY header error. */
bool meshio_estimate(const char *path, uint64_t *least, uint64_t *most, struct err *e);

/* Write s's triangles as binary little-endian PLY: 3 vertices per face, not
 * shared, face i = primitive i. Temporary name + rename. */
bool meshio_export_ply(const struct scene *s, const char *path, struct err *e);

#endif
