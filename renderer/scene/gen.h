/* Procedural scene generators. Deterministic: the same parameters and seed
 * give bit-identical triangles. Each takes its materials by name through
 * scene_material_or_default, so a scene file can override them. */
#ifndef RTSIM_RENDERER_SCENE_GEN_H
#define RTSIM_RENDERER_SCENE_GEN_H

#include <stdint.h>

struct scene;

/* Standard Procedural Databases "balls" (E. Haines): a sphereflake of `levels`
 * (SPD's size factor: 4 gives 7381 spheres) with its floor square. Each sphere
 * is the 6 faces of a cube projected onto it, each face tess x tess quads of 2
 * triangles (tess 3: 108 triangles a sphere, 797,148 in all, plus 2 for the
 * floor). Materials: "flake" (spheres), "floor". */
void gen_sphereflake(struct scene *s, uint32_t levels, uint32_t tess);
uint64_t gen_sphereflake_tri_count(uint32_t levels, uint32_t tess);

/* A grove of branching trees (trunks, branches, leaves) on a ground plane,
 * seen in depth. detail 1 gives about 164K triangles; triangle count scales
 * roughly linearly with detail. Materials: "bark", "leaf", "ground". */
void gen_grove(struct scene *s, double detail, uint64_t seed);
/* Exactly the triangles gen_grove(s, detail, any seed) adds, without building. */
uint64_t gen_grove_tri_count(double detail);

/* An architectural interior: walls, floor, ceiling, furniture, small objects,
 * mirrors. detail 1 gives about 47K triangles, roughly linear in detail.
 * Materials: "wall", "floor", "ceiling", "wood", "fabric", "metal", "mirror",
 * "ceramic". */
void gen_room(struct scene *s, double detail, uint64_t seed);
/* Exactly the triangles gen_room(s, detail, any seed) adds, without building. */
uint64_t gen_room_tri_count(double detail);

#endif
