/* PNG previews of rendered images through gnuplot (rgbimage plot of raw 8-bit
 * sRGB), so results/ can carry light pictures beside the EXR files. */
#include "app/preview.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "renderer/image.h"
#include "sim/err.h"
#include "sim/outfile.h"

static unsigned char to_srgb8(float v) {
  if (!(v > 0.0f)) return 0;
  if (v >= 1.0f) return 255;
  float s = v <= 0.0031308f ? 12.92f * v : 1.055f * powf(v, 1.0f / 2.4f) - 0.055f;
  return (unsigned char)lrintf(s * 255.0f);
}

bool preview_write_png(const struct image *im, const char *png, struct err *e) {
  int r = image_channel(im, "R"), g = image_channel(im, "G"), b = image_channel(im, "B");
  CHECK_GE(r, 0);
  CHECK_GE(g, 0);
  CHECK_GE(b, 0);
  /* The raw pixels gnuplot reads: a scratch temporary, never committed. */
  struct outfile raw, out = {0};
  if (!outfile_open(&raw, png, "the preview", e)) return false;
  uint64_t n = (uint64_t)im->width * im->height;
  unsigned char *px = xmalloc(3 * n);
  for (uint64_t i = 0; i < n; i++) {
    px[3 * i + 0] = to_srgb8(im->planes[r][i]);
    px[3 * i + 1] = to_srgb8(im->planes[g][i]);
    px[3 * i + 2] = to_srgb8(im->planes[b][i]);
  }
  bool ok = fwrite(px, 3, n, raw.f) == n && fflush(raw.f) == 0;
  free(px);
  if (!ok) err_set(e, png, 0, 0, "cannot write the preview's temporary file");
  ok = ok && outfile_open_named(&out, png, "the preview", e);
  FILE *gp = ok ? popen("gnuplot >/dev/null 2>&1", "w") : NULL;
  if (ok && !gp) ok = err_set(e, png, 0, 0, "cannot run gnuplot (install gnuplot-nox)");
  if (ok) {
    /* Row 0 of the image is the top; gnuplot's y grows upward, hence flipy. */
    fprintf(gp,
            "set terminal png size %u,%u\nset output '%s'\nset lmargin at screen 0\n"
            "set rmargin at screen 1\nset tmargin at screen 1\nset bmargin at screen 0\n"
            "unset border\nunset tics\nunset key\nset xrange [-0.5:%u-0.5]\n"
            "set yrange [-0.5:%u-0.5]\n"
            "plot '%s' binary array=(%u,%u) flipy format='%%uchar%%uchar%%uchar' with rgbimage\n",
            im->width, im->height, out.tmp, im->width, im->height, raw.tmp, im->width,
            im->height);
    if (pclose(gp) != 0)
      ok = err_set(e, png, 0, 0, "gnuplot could not write the preview (is gnuplot-nox installed?)");
  }
  ok = ok && outfile_commit(&out, e);
  outfile_abort(&out);
  outfile_abort(&raw);
  return ok;
}
