/* PNG previews of rendered images, light enough for results/ to carry beside
 * the EXR files. */
#ifndef RTSIM_APP_PREVIEW_H
#define RTSIM_APP_PREVIEW_H

#include <stdbool.h>

struct err;
struct image;

/* Write an sRGB PNG preview of im's R, G, B channels through gnuplot (written
 * whole or not at all: sim/outfile.h). On failure fills e (file = png) and
 * returns false. */
bool preview_write_png(const struct image *im, const char *png, struct err *e);

#endif
