/* rtsim plot's gnuplot script: a figure (app/plot_figure.h) drawn as panels in
 * a grid on one canvas, with one title, one legend and one caption over them.
 * Ranges, ticks and the layout are computed here, not left to gnuplot, so the
 * panels share them; the data go inline. Pure text: nothing runs gnuplot. */
#ifndef RTSIM_APP_PLOT_SCRIPT_H
#define RTSIM_APP_PLOT_SCRIPT_H

#include <stddef.h>
#include <stdio.h>

struct plot_figure;

/* The script of f from after `set output` to its end, into a new buffer
 * (*body, *len; the caller frees *body), and the canvas it needs in pixels
 * (*width x *height) for the `set terminal` line. */
void plot_script_write(const struct plot_figure *f, char **body, size_t *len, unsigned *width,
                       unsigned *height);

/* s as a gnuplot single-quoted string (line breaks dropped). */
void plot_script_str(FILE *out, const char *s);

#endif
