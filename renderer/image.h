/* Float images with named channels, written and read through OpenEXR's C API
 * (openexr.h). Planes are stored channel-major: pixels[c][y * width + x]. */
#ifndef RTSIM_RENDERER_IMAGE_H
#define RTSIM_RENDERER_IMAGE_H

#include <stdbool.h>
#include <stdint.h>

struct err;
struct outfile;

#define IMAGE_MAX_CHANNELS 16
#define IMAGE_NAME_MAX 32

struct image {
  uint32_t width, height, channel_count;
  char names[IMAGE_MAX_CHANNELS][IMAGE_NAME_MAX];
  float *planes[IMAGE_MAX_CHANNELS]; /* each width*height floats, owned */
};

/* Allocate a zeroed image with the given channel names (at most
 * IMAGE_MAX_CHANNELS). */
void image_init(struct image *im, uint32_t width, uint32_t height, uint32_t channel_count,
                const char *const *names);
void image_fini(struct image *im);

/* Index of channel `name`, or -1. */
int image_channel(const struct image *im, const char *name);

/* Write as a scanline EXR with ZIP compression; half = true stores 16-bit
 * floats (smaller files), false stores 32-bit floats (exact round trip). The
 * file appears under `path` only when complete (temporary name + rename). On
 * failure fills e (file = path) and returns false. */
bool image_write_exr(const struct image *im, const char *path, bool half, struct err *e);
/* The same into out's temporary (out from outfile_open_named), which the
 * caller commits with the command's other outputs; e names out->path. */
bool image_write_exr_to(const struct image *im, struct outfile *out, bool half, struct err *e);

/* Read any scanline EXR of HALF or FLOAT channels into floats (im is
 * initialised here; image_fini frees it). On failure fills e, returns false. */
bool image_read_exr(struct image *im, const char *path, struct err *e);

#endif
