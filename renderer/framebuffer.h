/* The framebuffer: per-pixel radiance accumulated in 64-bit fixed point
 * (2^-32 units), so that the sum of a pixel's contributions is the same bits in
 * any order: scheduling policies change the order of work, never the picture.
 * Also per-pixel cost counters (k-d node visits, triangle tests). */
#ifndef RTSIM_RENDERER_FRAMEBUFFER_H
#define RTSIM_RENDERER_FRAMEBUFFER_H

#include <stdint.h>

#include "renderer/vec.h"
#include "sim/mem.h"

struct image;

/* Simulated bytes a pixel occupies in the memory image (3 x 32-bit colour +
 * padding): each contribution is a load and a store of this record. */
#define FB_PIXEL_BYTES 16u

struct framebuffer {
  uint32_t width, height;
  int64_t *acc;         /* 3 per pixel */
  uint32_t *cost_nodes; /* k-d node visits of all rays of the pixel */
  uint32_t *cost_tris;  /* triangle tests of all rays of the pixel */
  uint64_t base_addr;   /* simulated address of pixel 0 */
};

void fb_init(struct framebuffer *fb, uint32_t width, uint32_t height, uint64_t base_addr);
void fb_fini(struct framebuffer *fb);

/* Add colour c (components >= 0) to pixel; one load + store through mem. */
void fb_add(struct framebuffer *fb, uint32_t pixel, vec3 c, const struct mem_port *mem);

/* Image with channels R, G, B, cost.nodes, cost.tris (im initialised here). */
void fb_to_image(const struct framebuffer *fb, struct image *im);

#endif
