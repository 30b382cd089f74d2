/* PNG previews of rendered images through gnuplot (rgbimage plot of raw 8-bit
 * sRGB), so results/ can carry light pictures beside the EXR files. */
#include "app/preview.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "app/gnuplot.h"
#include "app/plot_axis.h"
#include "renderer/image.h"
#include "sim/err.h"
#include "sim/outfile.h"

static unsigned char to_srgb8(float v) {
  if (!(v > 0.0f)) return 0;
  if (v >= 1.0f) return 255;
  float s = v <= 0.0031308f ? 12.92f * v : 1.055f * powf(v, 1.0f / 2.4f) - 0.055f;
  return (unsigned char)lrintf(s * 255.0f);
}

bool preview_write_png(const struct image *im, struct outfile *out, struct err *e) {
  const char *png = out->path;
  int r = image_channel(im, "R"), g = image_channel(im, "G"), b = image_channel(im, "B");
  CHECK_GE(r, 0);
  CHECK_GE(g, 0);
  CHECK_GE(b, 0);
  /* The raw pixels gnuplot reads: a scratch temporary, never committed. */
  struct outfile raw;
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
  struct gnuplot gnu;
  FILE *gp = ok && gnuplot_open(&gnu, true) ? gnu.in : NULL;
  if (ok && !gp) ok = err_set(e, png, 0, 0, "cannot run gnuplot (install gnuplot-nox)");
  if (ok) {
    /* Row 0 of the image is the top; gnuplot's y grows upward, hence flipy. */
    fprintf(gp,
            "set terminal png size %u,%u\nset output '%s'\nset lmargin at screen 0\n"
            "set rmargin at screen 1\nset tmargin at screen 1\nset bmargin at screen 0\n"
            "unset border\nunset tics\nunset key\nset xrange [-0.5:%u-0.5]\n"
            "set yrange [-0.5:%u-0.5]\n"
            "plot '%s' binary array=(%u,%u) flipy format='%%uchar%%uchar%%uchar' with rgbimage\n",
            im->width, im->height, out->tmp, im->width, im->height, raw.tmp, im->width, im->height);
    if (!gnuplot_close(&gnu))
      ok = err_set(e, png, 0, 0, "gnuplot could not write the preview (is gnuplot-nox installed?)");
  }
  outfile_abort(&raw);
  return ok;
}

bool preview_write_heat_png(const struct image *im, const char *channel, const char *title,
                            const char *subtitle, const char *units, double top,
                            struct outfile *out, struct err *e) {
  const char *png = out->path;
  const int ch = image_channel(im, channel);
  CHECK_GE(ch, 0);
  const uint64_t n = (uint64_t)im->width * im->height;
  double max = 0;
  for (uint64_t i = 0; i < n; i++)
    if (im->planes[ch][i] > max) max = im->planes[ch][i];
  if (!(top > 0)) top = max > 0 ? max : 1;
  char clip[64] = "";
  if (max > top) snprintf(clip, sizeof clip, " (top colour: %.6g or more)", top);
  /* The title's two lines inside gnuplot's double quotes: no quote or
   * backslash of a scene name may end them. */
  char t1[256], t2[256];
  snprintf(t1, sizeof t1, "%s", title);
  snprintf(t2, sizeof t2, "%s", subtitle);
  for (char *q = t1; *q; q++)
    if (*q == '"' || *q == '\\') *q = '\'';
  for (char *q = t2; *q; q++)
    if (*q == '"' || *q == '\\') *q = '\'';
  struct outfile raw;
  if (!outfile_open(&raw, png, "the heat map", e)) return false;
  bool ok = fwrite(im->planes[ch], sizeof(float), n, raw.f) == n && fflush(raw.f) == 0;
  if (!ok) err_set(e, png, 0, 0, "cannot write the heat map's temporary file");
  struct gnuplot gnu;
  FILE *gp = ok && gnuplot_open(&gnu, true) ? gnu.in : NULL;
  if (ok && !gp) ok = err_set(e, png, 0, 0, "cannot run gnuplot (install gnuplot-nox)");
  if (ok) {
    /* Small images are drawn enlarged (whole pixels), beside the colour bar. */
    const uint32_t big = im->width > im->height ? im->width : im->height;
    const uint32_t scale = big >= 512 ? 1 : 512 / big;
    /* The colour bar's ticks: our labels (40k, not gnuplot's 40.0k), and the
     * bar's label set off past the widest, so the two never overlap. */
    struct plot_axis cb;
    plot_axis_nice(&cb, 0, top, false, 10, false, true);
    char ticks[2048] = "", l[64];
    size_t tl = 0, widest = 0;
    for (unsigned i = 0; i < cb.nticks && cb.ticks[i] <= top * (1 + 1e-9); i++) {
      plot_fmt_tick(cb.ticks[i], "", l, sizeof l);
      widest = strlen(l) > widest ? strlen(l) : widest;
      tl += (size_t)snprintf(ticks + tl, tl < sizeof ticks ? sizeof ticks - tl : 0, "%s'%s' %.17g",
                             i ? ", " : "", l, cb.ticks[i]);
    }
    /* Viridis (matplotlib's): perceptually even, readable in grey and by
     * most colour-blind readers. */
    fprintf(gp,
            "set terminal pngcairo size %u,%u noenhanced font ',11'\nset output '%s'\n"
            "set title \"%s\\n%s; largest pixel %.0f%s\"\nset size ratio -1\nunset key\n"
            "unset xtics\nunset ytics\nset border 0\nset xrange [-0.5:%u-0.5]\n"
            "set yrange [-0.5:%u-0.5]\nset cbrange [0:%.17g]\nset cbtics (%s)\n"
            "set cblabel '%s' offset %.1f,0\n"
            "set palette defined (0 '#440154', 1 '#3b528b', 2 '#21908d', 3 '#5dc963', "
            "4 '#fde725')\n"
            "plot '%s' binary array=(%u,%u) flipy format='%%float' using ($1 > %.17g ? %.17g : "
            "$1) with image\n",
            im->width * scale + 260, im->height * scale + 90, out->tmp, t1, t2, max, clip,
            im->width, im->height, top, ticks, units, widest > 3 ? (widest - 3) * 0.8 + 0.5 : 0.5,
            raw.tmp, im->width, im->height, top, top);
    if (!gnuplot_close(&gnu))
      ok = err_set(e, png, 0, 0, "gnuplot could not draw the heat map (is gnuplot-nox installed?)");
  }
  outfile_abort(&raw);
  return ok;
}
