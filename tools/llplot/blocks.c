/*
 * llplot --blocks: the four scattering blocks of a layer at one azimuth.
 *
 * A layer's matrices split into four blocks (Jakob et al. 2014, sec. 5;
 * rows outgoing, columns incident, nodes ascending): T^bt (mu_o < 0,
 * mu_i < 0), R^t (mu_o < 0, mu_i > 0), R^b (mu_o > 0, mu_i < 0) and T^tb
 * (mu_o > 0, mu_i > 0). The picture shows the BSDF at phi_d, by default
 * times |mu_i mu_o| — the cosine-weighted kernel, symmetric for a
 * reciprocal material — laid out like the matrix: mu_i runs from -1 (left)
 * to 1 (right) and mu_o from -1 (top) to 1 (bottom).
 *
 * EXR: one 2N x 2N RGB image of the values themselves (pixel (x, y) at
 * mu_i = -1 + (x + 1/2)/N, mu_o = -1 + (y + 1/2)/N). PNG: a 2 x 2 figure,
 * each block colour-mapped on its own scale clipped at its 99th
 * percentile (as the seed's notebook did), with axes and colour bars.
 */
#include "figure.h"
#include "llplot.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

typedef struct blocks_job {
    const llplot_source *source;
    llplot_image *img;
    size_t n;          /* samples per block side */
    double phi_d;
    int weighted;      /* times |mu_i mu_o| */
} blocks_job;

static double sample_mu(size_t k, size_t n) { return -1.0 + ((double)k + 0.5) / (double)n; }

static void blocks_row(size_t y, void *ctx)
{
    const blocks_job *job = ctx;
    double mu_o = sample_mu(y, job->n);
    size_t x, c;
    for (x = 0; x < 2 * job->n; ++x) {
        double mu_i = sample_mu(x, job->n), rgb[3];
        double scale = job->weighted ? fabs(mu_i * mu_o) : 1.0;
        llplot_source_eval(job->source, mu_i, mu_o, job->phi_d, rgb);
        for (c = 0; c < 3; ++c)
            *llplot_pixel(job->img, c, x, y) = (float)(rgb[c] * scale);
    }
}

/* One display channel of block (bx, by) (0 = the negative mu half) as an
 * n x n array. */
static void extract_block(const llplot_image *img, size_t n, size_t bx, size_t by, char channel,
                          float *out)
{
    size_t i, j;
    for (j = 0; j < n; ++j)
        for (i = 0; i < n; ++i) {
            size_t x = bx * n + i, y = by * n + j;
            double rgb[3];
            rgb[0] = *llplot_pixel(img, 0, x, y);
            rgb[1] = *llplot_pixel(img, 1, x, y);
            rgb[2] = *llplot_pixel(img, 2, x, y);
            out[j * n + i] = (float)(channel == 'R'   ? rgb[0]
                                     : channel == 'G' ? rgb[1]
                                     : channel == 'B' ? rgb[2]
                                                      : llplot_luminance(rgb));
        }
}

/* Ticks at -1, -0.5, 0 or 0, 0.5, 1 along one side of a panel. */
static void draw_axis(cairo_t *cr, double x, double y, double d, int vertical, int negative)
{
    static const char *neg[] = { "-1", "-0.5", "0" }, *pos[] = { "0", "0.5", "1" };
    int k;
    cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
    cairo_set_line_width(cr, 0.8);
    for (k = 0; k < 3; ++k) {
        double t = d * (0.5 * k);
        const char *label = negative ? neg[k] : pos[k];
        if (vertical) {
            cairo_move_to(cr, x, y + t);
            cairo_line_to(cr, x - 4, y + t);
            cairo_stroke(cr);
            llplot_text(cr, x - 6, y + t, 11, 0, 1.0, 0.5, label);
        } else {
            cairo_move_to(cr, x + t, y);
            cairo_line_to(cr, x + t, y + 4);
            cairo_stroke(cr);
            llplot_text(cr, x + t, y + 6, 11, 0, 0.5, 0.0, label);
        }
    }
}

static const char *channel_name(char channel)
{
    return channel == 'R' ? "red" : channel == 'G' ? "green" : channel == 'B' ? "blue"
                                                                            : "luminance";
}

static int draw_figure(const llplot_options *o, const llplot_source *s, const llplot_image *img,
                       size_t n)
{
    static const char *titles[2][2] = {
        { "T^{bt}: transmission, bottom to top", "R^{t}: reflection at the top" },
        { "R^{b}: reflection at the bottom", "T^{tb}: transmission, top to bottom" },
    };
    /* Display size of a panel: at least 160 pixels, an integer multiple of
     * the samples so that every sample is a cell of the same size. */
    double d = (double)(n >= 160 ? n : n * ((159 + n) / n));
    double col_x[2], row_y[2], width, height;
    cairo_surface_t *surface;
    cairo_t *cr;
    float *block = malloc(n * n * sizeof(float));
    char text[512];
    size_t bx, by;
    int code;
    if (!block)
        return llplot_fail(LLPLOT_EXIT_IO, "out of memory");
    col_x[0] = 70;
    col_x[1] = col_x[0] + d + 130;
    row_y[0] = 100;
    row_y[1] = row_y[0] + d + 84;
    width = col_x[1] + d + 90;
    height = row_y[1] + d + 60;
    surface = llplot_canvas_create((int)width, (int)height, &cr);
    if (!surface) {
        free(block);
        return LLPLOT_EXIT_IO;
    }
    cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
    snprintf(text, sizeof text, "%s", o->title ? o->title : s->label);
    llplot_text(cr, width / 2, 16, 19, 1, 0.5, 0.0, text);
    snprintf(text, sizeof text, "%s at φ_{d} = %g°, %s; each scale clipped at its 99th percentile",
             o->quantity == LLPLOT_QUANTITY_F ? "f" : "f · |μ_{i} μ_{o}|", o->phi_deg,
             channel_name(o->channel));
    cairo_set_source_rgb(cr, 0.3, 0.3, 0.3);
    llplot_text(cr, width / 2, 46, 13, 0, 0.5, 0.0, text);

    for (by = 0; by < 2; ++by)
        for (bx = 0; bx < 2; ++bx) {
            double x = col_x[bx], y = row_y[by], vmax, peak = 0.0;
            size_t k;
            extract_block(img, n, bx, by, o->channel, block);
            for (k = 0; k < n * n; ++k)
                if (block[k] > peak)
                    peak = block[k];
            /* The seed's scale: the 99th percentile, so that a narrow
             * highlight does not turn the rest of the block black. A block
             * that is zero almost everywhere (percentile 0) uses its peak. */
            vmax = llplot_percentile(block, n * n, 99.0);
            if (!(vmax > 0.0))
                vmax = peak;
            llplot_heatmap(cr, x, y, d, d, block, n, n, n, vmax > 0.0 ? vmax : 1.0);
            cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
            cairo_set_line_width(cr, 1.0);
            cairo_rectangle(cr, x, y, d, d);
            cairo_stroke(cr);
            if (!(peak > 0.0)) {
                cairo_set_source_rgb(cr, 0.85, 0.85, 0.85);
                llplot_text(cr, x + d / 2, y + d / 2, 15, 0, 0.5, 0.5, "zero everywhere");
            }
            cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
            llplot_text(cr, x + d / 2, y - 8, 12, 1, 0.5, 1.0, titles[by][bx]);
            draw_axis(cr, x, y + d, d, 0, bx == 0);
            draw_axis(cr, x, y, d, 1, by == 0);
            cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
            llplot_text(cr, x + d / 2, y + d + 22, 13, 0, 0.5, 0.0, "μ_{i}");
            llplot_text(cr, x - 40, y + d / 2, 13, 0, 1.0, 0.5, "μ_{o}");
            if (peak > 0.0)
                llplot_colorbar(cr, x + d + 12, y, 14, d, vmax, peak > vmax);
        }
    free(block);
    cairo_destroy(cr);
    code = llplot_write_png(o->output, surface);
    cairo_surface_destroy(surface);
    return code;
}

int llplot_blocks(const llplot_options *o, const llplot_source *s)
{
    llplot_image img;
    blocks_job job;
    char comments[512];
    size_t n = o->size ? o->size : LLPLOT_DEFAULT_BLOCK_SIZE;
    int code = llplot_image_alloc(&img, 2 * n, 2 * n, 3);
    if (code != LLPLOT_EXIT_OK)
        return code;
    img.names[0] = "R";
    img.names[1] = "G";
    img.names[2] = "B";
    job.source = s;
    job.img = &img;
    job.n = n;
    job.phi_d = o->phi_deg * LLPLOT_PI / 180.0;
    job.weighted = o->quantity == LLPLOT_QUANTITY_FCOS;
    llplot_parallel_rows(2 * n, o->threads, blocks_row, &job);
    if (o->format == LLPLOT_EXR) {
        snprintf(comments, sizeof comments,
                 "llplot --blocks %s: RGB = %s at phi_d = %g deg; pixel (x, y) has "
                 "mu_i = -1 + (x + 0.5)/%zu, mu_o = -1 + (y + 0.5)/%zu",
                 s->label, job.weighted ? "f * |mu_i mu_o|" : "f", o->phi_deg, n, n);
        code = llplot_write_exr(o->output, &img, comments);
    } else {
        code = draw_figure(o, s, &img, n);
    }
    llplot_image_free(&img);
    return code;
}
