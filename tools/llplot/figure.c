/*
 * llplot — drawing helpers over cairo (text, colour map, colour bar,
 * ticks) and the PNG writer. Text uses cairo's "toy" font API, which is
 * enough for labels and keeps the tool on cairo alone.
 */
#include "figure.h"
#include "llplot.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

cairo_surface_t *llplot_canvas_create(int width, int height, cairo_t **cr)
{
    cairo_surface_t *surface = cairo_image_surface_create(CAIRO_FORMAT_RGB24, width, height);
    *cr = NULL;
    if (cairo_surface_status(surface) != CAIRO_STATUS_SUCCESS) {
        llplot_fail(LLPLOT_EXIT_IO, "cannot create a %d x %d canvas: %s", width, height,
                    cairo_status_to_string(cairo_surface_status(surface)));
        cairo_surface_destroy(surface);
        return NULL;
    }
    *cr = cairo_create(surface);
    cairo_set_source_rgb(*cr, 1.0, 1.0, 1.0);
    cairo_paint(*cr);
    return surface;
}

/* ------------------------------------------------------------------ text */

/* Sub- and superscripts: smaller, and moved by a fraction of the base size. */
#define SCRIPT_SCALE 0.68
#define SUB_SHIFT 0.22
#define SUP_SHIFT -0.38

/* Walk the marked-up text segment by segment, measuring and (when draw is
 * set) drawing each at the pen position; returns the total advance. Only
 * `_{..}` and `^{..}` with braces are markup, so file names with '_' in a
 * title print as they are. */
static double text_run(cairo_t *cr, double x, double baseline, double size, int bold, int draw,
                       const char *text)
{
    char buf[512];
    const char *p = text;
    double pen = x;
    cairo_select_font_face(cr, LLPLOT_FONT, CAIRO_FONT_SLANT_NORMAL,
                           bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
    while (*p) {
        size_t len = 0;
        double seg_size = size, shift = 0.0;
        cairo_text_extents_t ext;
        if ((p[0] == '_' || p[0] == '^') && p[1] == '{') {
            shift = (p[0] == '_' ? SUB_SHIFT : SUP_SHIFT) * size;
            seg_size = SCRIPT_SCALE * size;
            p += 2;
            while (*p && *p != '}' && len < sizeof buf - 1)
                buf[len++] = *p++;
            if (*p == '}')
                ++p;
        } else {
            while (*p && len < sizeof buf - 1 &&
                   !((p[0] == '_' || p[0] == '^') && p[1] == '{'))
                buf[len++] = *p++;
        }
        buf[len] = '\0';
        cairo_set_font_size(cr, seg_size);
        cairo_text_extents(cr, buf, &ext);
        if (draw) {
            cairo_move_to(cr, pen, baseline + shift);
            cairo_show_text(cr, buf);
        }
        pen += ext.x_advance;
    }
    /* show_text leaves a current point behind; drop it so that the next
     * path (an arc, say) does not start with a line from the text. */
    if (draw)
        cairo_new_path(cr);
    return pen - x;
}

double llplot_text_width(cairo_t *cr, double size, int bold, const char *text)
{
    return text_run(cr, 0.0, 0.0, size, bold, 0, text);
}

double llplot_text(cairo_t *cr, double x, double y, double size, int bold, double ax,
                   double ay, const char *text)
{
    cairo_font_extents_t fe;
    double width = llplot_text_width(cr, size, bold, text);
    double baseline;
    cairo_set_font_size(cr, size);
    cairo_font_extents(cr, &fe);
    baseline = y - ay * (fe.ascent + fe.descent) + fe.ascent;
    return text_run(cr, x - ax * width, baseline, size, bold, 1, text);
}

/* ------------------------------------------------------------ colour map */

/* A sequential map from near-black through purple, red and orange to pale
 * yellow, its lightness increasing monotonically so that the order of
 * values reads correctly in grey too. Control points in display sRGB. */
static const double colormap_points[][4] = {
    { 0.00, 0.015, 0.015, 0.060 }, { 0.18, 0.200, 0.050, 0.420 },
    { 0.40, 0.560, 0.120, 0.480 }, { 0.60, 0.870, 0.300, 0.260 },
    { 0.80, 0.985, 0.620, 0.150 }, { 1.00, 0.990, 0.990, 0.720 },
};

void llplot_colormap(double t, double rgb[3])
{
    size_t k, n = sizeof colormap_points / sizeof colormap_points[0];
    if (!(t > 0.0))
        t = 0.0;
    if (t > 1.0)
        t = 1.0;
    for (k = 1; k < n - 1 && t > colormap_points[k][0]; ++k)
        ;
    {
        const double *a = colormap_points[k - 1], *b = colormap_points[k];
        double s = (t - a[0]) / (b[0] - a[0]);
        int c;
        for (c = 0; c < 3; ++c)
            rgb[c] = a[c + 1] + s * (b[c + 1] - a[c + 1]);
    }
}

static uint32_t pack_rgb(const double rgb[3])
{
    uint32_t v = 0;
    int c;
    for (c = 0; c < 3; ++c) {
        double x = rgb[c] * 255.0 + 0.5;
        uint32_t q = x <= 0.0 ? 0u : x >= 255.0 ? 255u : (uint32_t)x;
        v = (v << 8) | q;
    }
    return v;
}

/* Paint a surface of the given pixel size into the box (x, y, w, h) with
 * nearest-neighbour filtering, so that each data value stays one crisp cell. */
static void paint_scaled(cairo_t *cr, cairo_surface_t *img, double x, double y, double w,
                         double h, size_t nx, size_t ny)
{
    cairo_save(cr);
    cairo_translate(cr, x, y);
    cairo_scale(cr, w / (double)nx, h / (double)ny);
    cairo_set_source_surface(cr, img, 0, 0);
    cairo_pattern_set_filter(cairo_get_source(cr), CAIRO_FILTER_NEAREST);
    cairo_rectangle(cr, 0, 0, (double)nx, (double)ny);
    cairo_fill(cr);
    cairo_restore(cr);
}

void llplot_heatmap(cairo_t *cr, double x, double y, double w, double h, const float *values,
                    size_t nx, size_t ny, size_t row_stride, double vmax)
{
    cairo_surface_t *img = cairo_image_surface_create(CAIRO_FORMAT_RGB24, (int)nx, (int)ny);
    unsigned char *data;
    int stride;
    size_t i, j;
    if (cairo_surface_status(img) != CAIRO_STATUS_SUCCESS) {
        cairo_surface_destroy(img);
        return;
    }
    cairo_surface_flush(img);
    data = cairo_image_surface_get_data(img);
    stride = cairo_image_surface_get_stride(img);
    for (j = 0; j < ny; ++j) {
        uint32_t *row = (uint32_t *)(void *)(data + (size_t)stride * j);
        for (i = 0; i < nx; ++i) {
            double rgb[3];
            llplot_colormap(vmax > 0.0 ? values[j * row_stride + i] / vmax : 0.0, rgb);
            row[i] = pack_rgb(rgb);
        }
    }
    cairo_surface_mark_dirty(img);
    paint_scaled(cr, img, x, y, w, h, nx, ny);
    cairo_surface_destroy(img);
}

/* ------------------------------------------------------------------ ticks */

size_t llplot_nice_ticks(double lo, double hi, size_t max_ticks, double *ticks, double *step)
{
    static const double mantissas[] = { 1.0, 2.0, 2.5, 5.0, 10.0 };
    double span = hi - lo, raw, magnitude, s = 1.0, t;
    size_t k, n = 0;
    if (!(span > 0.0) || max_ticks < 2) {
        ticks[0] = lo;
        *step = 1.0;
        return 1;
    }
    raw = span / (double)(max_ticks - 1);
    magnitude = pow(10.0, floor(log10(raw)));
    for (k = 0; k < sizeof mantissas / sizeof mantissas[0]; ++k) {
        s = mantissas[k] * magnitude;
        if (s >= raw * (1.0 - 1e-9))
            break;
    }
    for (t = ceil(lo / s - 1e-9) * s; t <= hi * (1.0 + 1e-9) + 1e-12 && n < max_ticks; t += s)
        ticks[n++] = fabs(t) < s * 1e-9 ? 0.0 : t;
    *step = s;
    return n;
}

void llplot_format_tick(double value, double step, char *buf, size_t size)
{
    double a = fabs(value);
    if (value == 0.0) {
        snprintf(buf, size, "0");
    } else if (step >= 1e-3 && a < 1e5) {
        int decimals = step >= 1.0 ? 0 : (int)ceil(-log10(step) - 1e-9);
        /* Steps such as 0.25 need one more decimal than their magnitude. */
        if (fabs(step * pow(10.0, decimals) - floor(step * pow(10.0, decimals) + 0.5)) > 1e-6)
            ++decimals;
        snprintf(buf, size, "%.*f", decimals, value);
    } else {
        snprintf(buf, size, "%.2g", value);
    }
}

/* ------------------------------------------------------------ colour bar */

void llplot_colorbar(cairo_t *cr, double x, double y, double w, double h, double vmax,
                     int clipped)
{
    enum { STEPS = 256 };
    float ramp[STEPS];
    double ticks[16], step;
    size_t k, n;
    /* The ramp runs top (vmax) to bottom (0). */
    for (k = 0; k < STEPS; ++k)
        ramp[k] = (float)(1.0 - ((double)k + 0.5) / STEPS);
    llplot_heatmap(cr, x, y, w, h, ramp, 1, STEPS, 1, 1.0);
    if (clipped) {
        /* Matplotlib's "extend" marker: values beyond the top share its colour. */
        double rgb[3];
        llplot_colormap(1.0, rgb);
        cairo_set_source_rgb(cr, rgb[0], rgb[1], rgb[2]);
        cairo_move_to(cr, x, y);
        cairo_line_to(cr, x + w / 2, y - w);
        cairo_line_to(cr, x + w, y);
        cairo_close_path(cr);
        cairo_fill_preserve(cr);
        cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
        cairo_set_line_width(cr, 0.8);
        cairo_stroke(cr);
    }
    cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
    cairo_set_line_width(cr, 0.8);
    cairo_rectangle(cr, x, y, w, h);
    cairo_stroke(cr);
    if (!(vmax > 0.0))
        vmax = 1.0;
    n = llplot_nice_ticks(0.0, vmax, 6, ticks, &step);
    for (k = 0; k < n; ++k) {
        char label[32];
        double ty = y + h * (1.0 - ticks[k] / vmax);
        cairo_move_to(cr, x + w, ty);
        cairo_line_to(cr, x + w + 4, ty);
        cairo_stroke(cr);
        llplot_format_tick(ticks[k], step, label, sizeof label);
        llplot_text(cr, x + w + 6, ty, 11, 0, 0.0, 0.5, label);
    }
}

/* ------------------------------------------------------------ percentile */

static int compare_floats(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

double llplot_percentile(const float *values, size_t n, double p)
{
    float *copy;
    double pos, frac, result;
    size_t lo;
    if (n == 0 || n > ((size_t)-1) / sizeof(float))
        return 0.0;
    copy = malloc(n * sizeof(float));
    if (!copy)
        return 0.0;
    memcpy(copy, values, n * sizeof(float));
    qsort(copy, n, sizeof(float), compare_floats);
    pos = p / 100.0 * (double)(n - 1);
    lo = (size_t)floor(pos);
    if (lo >= n - 1) {
        result = copy[n - 1];
    } else {
        frac = pos - (double)lo;
        result = copy[lo] + frac * (copy[lo + 1] - copy[lo]);
    }
    free(copy);
    return result;
}

void llplot_figure_release_caches(void) { cairo_debug_reset_static_data(); }

/* ------------------------------------------------------------------- PNG */

static cairo_status_t write_to_file(void *closure, const unsigned char *data, unsigned int length)
{
    return fwrite(data, 1, length, (FILE *)closure) == length ? CAIRO_STATUS_SUCCESS
                                                             : CAIRO_STATUS_WRITE_ERROR;
}

int llplot_write_png(const char *path, cairo_surface_t *surface)
{
    llplot_output out;
    FILE *f;
    cairo_status_t st;
    int code = llplot_output_begin(path, &out);
    if (code != LLPLOT_EXIT_OK)
        return code;
    f = fopen(out.temp_path, "wb");
    if (!f) {
        code = llplot_fail(LLPLOT_EXIT_IO, "%s: cannot write: %s", path, strerror(errno));
        goto fail;
    }
    st = cairo_surface_write_to_png_stream(surface, write_to_file, f);
    if (st != CAIRO_STATUS_SUCCESS || fflush(f) != 0 || fsync(fileno(f)) != 0) {
        code = llplot_fail(LLPLOT_EXIT_IO, "%s: cannot write: %s", path,
                           st != CAIRO_STATUS_SUCCESS ? cairo_status_to_string(st)
                                                      : strerror(errno));
        fclose(f);
        goto fail;
    }
    if (fclose(f) != 0) {
        code = llplot_fail(LLPLOT_EXIT_IO, "%s: cannot write: %s", path, strerror(errno));
        goto fail;
    }
    return llplot_output_commit(&out);
fail:
    llplot_output_abort(&out);
    return code;
}
