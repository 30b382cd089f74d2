/* Pinhole camera and primary-ray order (Hilbert curve over the image). */
#ifndef RTSIM_RENDERER_CAMERA_H
#define RTSIM_RENDERER_CAMERA_H

#include <stdint.h>

#include "renderer/vec.h"

struct scene_camera;
struct ray;

struct camera_frame {
  vec3 origin, forward, right,
      up; /* right and up scaled by the half-extent of the image plane at distance 1 */
  uint32_t width, height;
};

/* What makes a camera unusable: no view direction (at equals from), or an up
 * that is zero or parallel to the view (as far as floats can tell: the frame
 * built from it would be rounding noise). Scale-free: any finite nonzero from
 * - at and up, however small or large, are judged by their directions alone. */
enum camera_fault { CAMERA_OK, CAMERA_NO_VIEW, CAMERA_BAD_UP };
enum camera_fault camera_check(const struct scene_camera *c);

/* The frame of a camera camera_check accepts. */
void camera_frame_init(struct camera_frame *cf, const struct scene_camera *c, uint32_t width,
                       uint32_t height);

/* The primary ray through the centre of pixel (x, y); row 0 is the top. */
void camera_primary(const struct camera_frame *cf, uint32_t x, uint32_t y, uint64_t seed,
                    struct ray *r);

/* Fill order[0 .. width*height-1] with pixel ids (y*width + x) along a Hilbert
 * curve over the smallest power-of-two square covering the image, skipping
 * positions outside it. */
void camera_hilbert_order(uint32_t width, uint32_t height, uint32_t *order);

#endif
