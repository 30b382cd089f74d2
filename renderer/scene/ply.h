/* A small, strict PLY reader (format 1.0: ascii, binary_little_endian,
 * binary_big_endian): the vertex element's x, y, z (and nx, ny, nz when all
 * three are present) and the face element's index lists, fanned into
 * triangles in file order. Every malformed input is one error; memory is a
 * fixed factor of the file's size. */
#ifndef RTSIM_RENDERER_SCENE_PLY_H
#define RTSIM_RENDERER_SCENE_PLY_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

struct err;

/* What a PLY file holds for rtsim. Owned by the caller: ply_mesh_fini. */
struct ply_mesh {
  uint32_t vertex_count;
  float *pos;    /* 3 * vertex_count: x, y, z, all finite */
  float *normal; /* 3 * vertex_count: nx, ny, nz as stored, or NULL when absent */
  uint32_t tri_count;
  uint32_t *tri; /* 3 * tri_count vertex indices (< vertex_count): face f with
                    indices i0..ik becomes (i0, i1, i2), (i0, i2, i3), ... in
                    face order, so a triangle face is copied as it is */
};

/* True when `path` should be read by this module rather than a general
 * importer: its name ends in ".ply" (any case) or its first three bytes are
 * "ply" (any case). A file that cannot be opened is not claimed (unless named
 * .ply). */
bool ply_claims(const char *path);

/* Parse the len bytes at buf as PLY into *m (zeroed first). `name` is used as
 * the error's file. Header errors carry name:line; ASCII data errors
 * name:line:col; binary data errors say "byte N" (0-based offset in buf) in
 * the message. On failure *m is empty and nothing is left allocated. The
 * header's lines end in "\n" or "\r\n"; the data starts at the byte after the
 * "\n" ending end_header. */
bool ply_read_memory(const unsigned char *buf, size_t len, const char *name, struct ply_mesh *m,
                     struct err *e);

/* Read the file at path whole and parse it as ply_read_memory does. */
bool ply_read_file(const char *path, struct ply_mesh *m, struct err *e);

/* What a PLY header says of the file's size, before its data is read. */
struct ply_counts {
  uint64_t vertices, faces; /* as declared (each face gives at least one triangle) */
  uint64_t tri_max;         /* the most triangles the file's bytes can hold: faces,
                               plus one per index past a face's third that the bytes
                               beyond every element's smallest size could hold */
};

/* Read only the header of the file at path (and its size) and check its
 * declared counts against that size as ply_read_memory does. Errors as
 * ply_read_memory's header errors; the header must end in the first 64 MiB. */
bool ply_read_header_file(const char *path, struct ply_counts *c, struct err *e);

/* Free m's arrays and zero it; accepts a zeroed mesh. */
void ply_mesh_fini(struct ply_mesh *m);

#endif
