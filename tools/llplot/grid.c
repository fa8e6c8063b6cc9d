/*
 * llplot --grid: a textured .bsdf file as a grid of small spheres, one per
 * sample of its first two parameters (parameter 0 across the columns, from
 * its smallest sample at the left; parameter 1 down the rows, smallest at
 * the top; a file with one parameter gives one row), every other parameter
 * at the fixed point (--param, else the middle of its range). Each sphere is
 * --sphere's picture (same lighting, sampler and seed) at the basis weights
 * of its sample point, which are exactly that basis's.
 *
 * PNG: the spheres (--size pixels each, default 128; --spp default 16) on a
 * dark figure with the values as column and row labels (cairo text) and a
 * title. EXR: the spheres' linear RGBA side by side, cell (i, j) at pixels
 * [i size, (i + 1) size) x [j size, (j + 1) size), without labels (the
 * parameters and their values are in the comments attribute).
 */
#include "figure.h"
#include "llplot.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Figure layout (pixels). */
#define GRID_GAP 6
#define GRID_TITLE 30
#define GRID_COLUMN_LABELS 22
#define GRID_MARGIN 12

typedef struct grid_layout {
    size_t cols, rows, cell;
    double left, top;          /* where cell (0, 0) starts */
    int width, height;
} grid_layout;

static void row_label(const llplot_axes *a, size_t j, char *buf, size_t size)
{
    char v[32];
    llplot_format_value(a->positions[1][j], v, sizeof v);
    snprintf(buf, size, "%s = %s", a->names[1], v);
}

static void column_label(const llplot_axes *a, size_t i, char *buf, size_t size)
{
    char v[32];
    llplot_format_value(a->positions[0][i], v, sizeof v);
    /* The name once, above the first column; values alone after it. */
    if (i == 0)
        snprintf(buf, size, "%s = %s", a->names[0], v);
    else
        snprintf(buf, size, "%s", v);
}

static int layout_figure(const llplot_axes *a, grid_layout *g)
{
    cairo_surface_t *probe = cairo_image_surface_create(CAIRO_FORMAT_RGB24, 1, 1);
    cairo_t *cr = cairo_create(probe);
    double label_width = 0.0, width, height;
    size_t j;
    char text[160];
    for (j = 0; a->n > 1 && j < g->rows; ++j) {
        double w;
        row_label(a, j, text, sizeof text);
        w = llplot_text_width(cr, 12, 0, text);
        label_width = w > label_width ? w : label_width;
    }
    cairo_destroy(cr);
    cairo_surface_destroy(probe);
    g->left = GRID_MARGIN + (label_width > 0.0 ? label_width + 10.0 : 0.0);
    g->top = GRID_TITLE + GRID_COLUMN_LABELS;
    width = g->left + (double)g->cols * (double)(g->cell + GRID_GAP) + GRID_MARGIN;
    height = g->top + (double)g->rows * (double)(g->cell + GRID_GAP) + GRID_MARGIN;
    if (width > 32767.0 || height > 32767.0)
        return llplot_fail(LLPLOT_EXIT_INPUT,
                           "a grid of %zu x %zu spheres of %zu pixels does not fit a PNG figure; "
                           "lower --size",
                           g->cols, g->rows, g->cell);
    g->width = (int)width;
    g->height = (int)height;
    return LLPLOT_EXIT_OK;
}

static void draw_labels(cairo_t *cr, const llplot_options *o, const llplot_source *s,
                        const llplot_axes *a, const grid_layout *g)
{
    char text[320];
    size_t i, j;
    cairo_set_source_rgb(cr, 0.92, 0.92, 0.92);
    llplot_text(cr, 0.5 * g->width, 8, 14, 1, 0.5, 0.0, o->title ? o->title : s->label);
    for (i = 0; i < g->cols; ++i) {
        double x = g->left + (double)i * (double)(g->cell + GRID_GAP) + 0.5 * (double)g->cell;
        column_label(a, i, text, sizeof text);
        llplot_text(cr, x, g->top - 4, 12, 0, 0.5, 1.0, text);
    }
    for (j = 0; a->n > 1 && j < g->rows; ++j) {
        double y = g->top + (double)j * (double)(g->cell + GRID_GAP) + 0.5 * (double)g->cell;
        row_label(a, j, text, sizeof text);
        llplot_text(cr, g->left - 8, y, 12, 0, 1.0, 0.5, text);
    }
}

/* The comments of the EXR mosaic: the layout and each axis's values. */
static void exr_comments(const llplot_source *s, const llplot_axes *a, const grid_layout *g,
                         size_t spp, char *buf, size_t size)
{
    size_t at, k, i;
    at = (size_t)snprintf(buf, size,
                          "llplot --grid %s: linear RGB radiance premultiplied by A (coverage), "
                          "%zu x %zu spheres of %zu pixels, %zu samples per pixel; columns: %s",
                          s->label, g->cols, g->rows, g->cell, spp, a->names[0]);
    for (k = 0; k < (a->n > 1 ? 2u : 1u); ++k) {
        if (k == 1 && at < size)
            at += (size_t)snprintf(buf + at, size - at, "; rows: %s", a->names[1]);
        for (i = 0; i < a->counts[k] && at < size; ++i) {
            char v[32];
            llplot_format_value(a->positions[k][i], v, sizeof v);
            at += (size_t)snprintf(buf + at, size - at, "%s%s", i ? ", " : " = ", v);
        }
    }
}

int llplot_grid(const llplot_options *o, const llplot_source *s)
{
    llplot_axes a;
    grid_layout g;
    llplot_image mosaic, cell;
    cairo_surface_t *surface = NULL;
    cairo_t *cr = NULL;
    float *coeffs = NULL;
    size_t spp = o->spp ? o->spp : LLPLOT_DEFAULT_GRID_SPP, i, j, c, x, y;
    char comments[2048];
    int code = llplot_axes_open(o, s, "--grid", &a);
    if (code != LLPLOT_EXIT_OK)
        return code;
    memset(&mosaic, 0, sizeof mosaic);
    memset(&g, 0, sizeof g);
    g.cell = o->size ? o->size : LLPLOT_DEFAULT_GRID_CELL;
    g.cols = a.counts[0];
    g.rows = a.n > 1 ? a.counts[1] : 1;
    coeffs = malloc(a.n_bases * sizeof(float));
    if (!coeffs) {
        code = llplot_fail(LLPLOT_EXIT_IO, "out of memory");
        goto done;
    }
    if (o->format == LLPLOT_PNG) {
        code = layout_figure(&a, &g);
        if (code == LLPLOT_EXIT_OK) {
            surface = llplot_canvas_create(g.width, g.height, &cr);
            code = surface ? LLPLOT_EXIT_OK : LLPLOT_EXIT_IO;
        }
        if (code != LLPLOT_EXIT_OK)
            goto done;
        cairo_set_source_rgb(cr, 0.16, 0.16, 0.17);
        cairo_paint(cr);
        cairo_surface_flush(surface);
    } else {
        code = g.rows > (size_t)-1 / g.cell || g.cols > (size_t)-1 / g.cell
                   ? llplot_fail(LLPLOT_EXIT_INPUT, "the grid is too large")
                   : llplot_image_alloc(&mosaic, g.cols * g.cell, g.rows * g.cell, 4);
        if (code != LLPLOT_EXIT_OK)
            goto done;
        mosaic.names[0] = "R";
        mosaic.names[1] = "G";
        mosaic.names[2] = "B";
        mosaic.names[3] = "A";
    }
    for (j = 0; j < g.rows && code == LLPLOT_EXIT_OK; ++j)
        for (i = 0; i < g.cols && code == LLPLOT_EXIT_OK; ++i) {
            a.point[0] = a.positions[0][i];
            if (a.n > 1)
                a.point[1] = a.positions[1][j];
            code = llplot_axes_weights(s, a.point, coeffs);
            if (code == LLPLOT_EXIT_OK)
                code = llplot_sphere_image(o, s, g.cell, spp, coeffs, 0, &cell);
            if (code != LLPLOT_EXIT_OK)
                break;
            if (surface) {
                llplot_sphere_paint(o, &cell, cairo_image_surface_get_data(surface),
                                    cairo_image_surface_get_stride(surface),
                                    (size_t)g.left + i * (g.cell + GRID_GAP),
                                    (size_t)g.top + j * (g.cell + GRID_GAP));
            } else {
                for (c = 0; c < 4; ++c)
                    for (y = 0; y < g.cell; ++y)
                        for (x = 0; x < g.cell; ++x)
                            *llplot_pixel(&mosaic, c, i * g.cell + x, j * g.cell + y) =
                                *llplot_pixel(&cell, c, x, y);
            }
            llplot_image_free(&cell);
        }
    if (code != LLPLOT_EXIT_OK)
        goto done;
    if (surface) {
        cairo_surface_mark_dirty(surface);
        draw_labels(cr, o, s, &a, &g);
        code = llplot_write_png(o->output, surface);
    } else {
        exr_comments(s, &a, &g, spp, comments, sizeof comments);
        code = llplot_write_exr(o->output, &mosaic, comments);
    }
done:
    if (cr)
        cairo_destroy(cr);
    if (surface)
        cairo_surface_destroy(surface);
    llplot_image_free(&mosaic);
    free(coeffs);
    llplot_axes_close(&a);
    return code;
}
