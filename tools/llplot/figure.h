/*
 * llplot — drawing helpers over cairo: text with sub- and superscripts,
 * the colour map and its colour bar, axis ticks, percentiles and the
 * atomic PNG writer. Only the figure files include cairo.
 */
#ifndef LLPLOT_FIGURE_H
#define LLPLOT_FIGURE_H

#include <cairo.h>
#include <stddef.h>

#define LLPLOT_FONT "DejaVu Sans"

/* A white canvas of width x height pixels; *cr draws on it. Returns NULL
 * (and prints why) when cairo cannot allocate it. */
cairo_surface_t *llplot_canvas_create(int width, int height, cairo_t **cr);

/* Draw text at (x, y) with the anchor (ax, ay) of its box placed there:
 * ax 0/0.5/1 = left/centre/right, ay 0/0.5/1 = top/middle/bottom of the
 * font's ascent..descent. `_{..}` and `^{..}` (or `_x`, `^x` for one
 * character) set sub- and superscripts. Returns the drawn width. */
double llplot_text(cairo_t *cr, double x, double y, double size, int bold, double ax,
                   double ay, const char *text);

/* The width text would take, without drawing it. */
double llplot_text_width(cairo_t *cr, double size, int bold, const char *text);

/* The sequential colour map: t in [0, 1] (clamped) to display sRGB. */
void llplot_colormap(double t, double rgb[3]);

/* Draw values (nx x ny, row-major from the top row, rows row_stride floats
 * apart) as a colour-mapped image of nx x ny pixels at (x, y), scaled to
 * w x h; values are divided by vmax and clipped to [0, 1]. */
void llplot_heatmap(cairo_t *cr, double x, double y, double w, double h, const float *values,
                    size_t nx, size_t ny, size_t row_stride, double vmax);

/* A vertical colour bar for [0, vmax] with ticks on its right; `clipped`
 * marks the top as a lower bound (values above vmax share its colour). */
void llplot_colorbar(cairo_t *cr, double x, double y, double w, double h, double vmax,
                     int clipped);

/* Up to max_ticks "nice" (1, 2, 5 x 10^k) values covering [lo, hi];
 * returns the count and writes the step. */
size_t llplot_nice_ticks(double lo, double hi, size_t max_ticks, double *ticks, double *step);

/* Format a tick value with as many decimals as the step needs. */
void llplot_format_tick(double value, double step, char *buf, size_t size);

/* The p-th percentile (0..100) of n values, linear interpolation between
 * order statistics (numpy's default). Sorts a copy; 0 for n == 0 or when
 * the copy cannot be allocated. */
double llplot_percentile(const float *values, size_t n, double p);

/* Release cairo's process-wide caches (fonts above all) once every cairo
 * object is gone, so that leak checkers (ASan in the test suite) see only
 * real leaks. */
void llplot_figure_release_caches(void);

/* Encode surface as PNG into path atomically. Returns an exit code. */
int llplot_write_png(const char *path, cairo_surface_t *surface);

#endif /* LLPLOT_FIGURE_H */
