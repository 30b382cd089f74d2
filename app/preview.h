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

/* Write a heat map PNG of im's channel `channel` (which must exist) through
 * gnuplot: a linear colour scale from 0 to top (0: the channel's largest
 * value) with a colour bar labelled `units`, under a title of two lines
 * (the second followed by the largest pixel's value); pixels above top take
 * the top colour. Written whole or not at all. On failure fills e. */
bool preview_write_heat_png(const struct image *im, const char *channel, const char *title,
                            const char *subtitle, const char *units, double top, const char *png,
                            struct err *e);

#endif
