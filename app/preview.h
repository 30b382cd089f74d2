/* PNG previews of rendered images, light enough for results/ to carry beside
 * the EXR files. */
#ifndef RTSIM_APP_PREVIEW_H
#define RTSIM_APP_PREVIEW_H

#include <stdbool.h>

struct err;
struct image;
struct outfile;

/* Each draws into out's temporary (out from outfile_open_named; the caller
 * commits it with the command's other outputs, or aborts). On failure fills
 * e (file = out->path) and returns false. */

/* An sRGB PNG preview of im's R, G, B channels through gnuplot. */
bool preview_write_png(const struct image *im, struct outfile *out, struct err *e);

/* A heat map PNG of im's channel `channel` (which must exist) through
 * gnuplot: a linear colour scale from 0 to top (0: the channel's largest
 * value) with a colour bar labelled `units`, under a title of two lines
 * (the second followed by the largest pixel's value); pixels above top take
 * the top colour. */
bool preview_write_heat_png(const struct image *im, const char *channel, const char *title,
                            const char *subtitle, const char *units, double top,
                            struct outfile *out, struct err *e);

#endif
