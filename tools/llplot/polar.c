/*
 * llplot --polar: reflectance in the plane of incidence for a few incident
 * angles — the classic goniometric view of a BRDF's lobes.
 *
 * For light arriving at zenith angle theta_i (mu_i = cos theta_i > 0 in
 * the layer convention), the curve is f(mu_i, mu_o, phi_d) cos theta_o over
 * the outgoing zenith angle theta_o in [-90, 90] degrees: positive angles
 * are the forward side (phi_d = 0, where the mirror direction lies),
 * negative ones the backward side toward the light (phi_d = pi). Weighted
 * by cos theta_o, the curve is the radiance reflected per unit irradiance
 * (its integral over the hemisphere is the albedo).
 *
 * PNG: the curves in polar coordinates (radius = value) over the upper
 * half plane, one colour per incident angle, with a legend. EXR: the data,
 * one row per incident angle (in the order given) and --size columns,
 * column k at theta_o = -90 + 180 (k + 1/2) / size degrees, RGB.
 */
#include "figure.h"
#include "llplot.h"

#include <math.h>
#include <stdio.h>

/* Reflected f cos theta_o in the plane of incidence (angles in degrees). */
static void plane_value(const llplot_source *s, double theta_i, double theta_o, double rgb[3])
{
    double rad = LLPLOT_PI / 180.0, mu_o = cos(fabs(theta_o) * rad);
    int c;
    llplot_source_eval(s, cos(theta_i * rad), -mu_o, theta_o >= 0.0 ? 0.0 : LLPLOT_PI, rgb);
    for (c = 0; c < 3; ++c)
        rgb[c] *= mu_o;
}

static double select_channel(const double rgb[3], char channel)
{
    return channel == 'R' ? rgb[0] : channel == 'G' ? rgb[1] : channel == 'B' ? rgb[2]
                                                                            : llplot_luminance(rgb);
}

/* Distinct, colour-blind-friendly hues (Okabe and Ito 2008). */
static const double curve_colors[LLPLOT_MAX_ANGLES][3] = {
    { 0.000, 0.447, 0.698 }, { 0.902, 0.624, 0.000 }, { 0.000, 0.620, 0.451 },
    { 0.835, 0.369, 0.000 }, { 0.800, 0.475, 0.655 }, { 0.337, 0.706, 0.914 },
    { 0.941, 0.894, 0.259 }, { 0.000, 0.000, 0.000 },
};

static void polar_point(double cx, double cy, double r, double theta_deg, double *x, double *y)
{
    double t = theta_deg * LLPLOT_PI / 180.0;
    *x = cx + r * sin(t);
    *y = cy - r * cos(t);
}

static void draw_grid(cairo_t *cr, double cx, double cy, double radius, const double *ticks,
                      size_t n_ticks, double step, double r_top)
{
    int deg;
    size_t k;
    cairo_set_line_width(cr, 0.8);
    for (deg = -90; deg <= 90; deg += 15) {
        double x, y;
        polar_point(cx, cy, radius, deg, &x, &y);
        cairo_set_source_rgb(cr, 0.86, 0.86, 0.86);
        cairo_move_to(cr, cx, cy);
        cairo_line_to(cr, x, y);
        cairo_stroke(cr);
        if (deg % 30 == 0) {
            char label[16];
            polar_point(cx, cy, radius + 14, deg, &x, &y);
            snprintf(label, sizeof label, "%d°", deg < 0 ? -deg : deg);
            cairo_set_source_rgb(cr, 0.35, 0.35, 0.35);
            llplot_text(cr, x, y, 11, 0, deg < 0 ? 1.0 : deg > 0 ? 0.0 : 0.5,
                        deg == 0 ? 1.0 : 0.5, label);
        }
    }
    for (k = 0; k < n_ticks; ++k) {
        char label[32];
        double r = radius * ticks[k] / r_top;
        if (ticks[k] <= 0.0)
            continue;
        cairo_set_source_rgb(cr, 0.80, 0.80, 0.80);
        cairo_arc(cr, cx, cy, r, LLPLOT_PI, 2.0 * LLPLOT_PI);
        cairo_stroke(cr);
        llplot_format_tick(ticks[k], step, label, sizeof label);
        cairo_set_source_rgb(cr, 0.35, 0.35, 0.35);
        llplot_text(cr, cx + r, cy + 4, 10, 0, 0.5, 0.0, label);
    }
    cairo_set_source_rgb(cr, 0.3, 0.3, 0.3);
    cairo_set_line_width(cr, 1.0);
    cairo_move_to(cr, cx - radius, cy);
    cairo_line_to(cr, cx + radius, cy);
    cairo_stroke(cr);
}

/* A small arrow just inside the rim pointing at the centre: where the
 * light comes from (the backward side, -theta_i). */
static void draw_light_marker(cairo_t *cr, double cx, double cy, double radius, double theta_i)
{
    double tip_x, tip_y, x0, y0, x1, y1;
    polar_point(cx, cy, radius - 14, -theta_i, &tip_x, &tip_y);
    polar_point(cx, cy, radius - 2, -theta_i - 1.6, &x0, &y0);
    polar_point(cx, cy, radius - 2, -theta_i + 1.6, &x1, &y1);
    cairo_move_to(cr, tip_x, tip_y);
    cairo_line_to(cr, x0, y0);
    cairo_line_to(cr, x1, y1);
    cairo_close_path(cr);
    cairo_fill(cr);
}

#define CURVE_SAMPLES 721 /* every quarter degree */

static int draw_figure(const llplot_options *o, const llplot_source *s)
{
    double values[LLPLOT_MAX_ANGLES][CURVE_SAMPLES];
    double width = (double)(o->size ? o->size : LLPLOT_DEFAULT_POLAR_SIZE);
    double radius = 0.40 * width, cx = 0.5 * width, cy = 96 + radius;
    double height = cy + 84, vmax = 0.0, ticks[16], step, r_top, legend_x, legend_w = 0.0;
    cairo_surface_t *surface;
    cairo_t *cr;
    char text[512];
    size_t a, k, n_ticks;
    int code;

    for (a = 0; a < o->n_angles; ++a)
        for (k = 0; k < CURVE_SAMPLES; ++k) {
            double rgb[3];
            plane_value(s, o->angles_deg[a], -90.0 + 180.0 * (double)k / (CURVE_SAMPLES - 1), rgb);
            values[a][k] = select_channel(rgb, o->channel);
            if (values[a][k] > vmax)
                vmax = values[a][k];
        }
    n_ticks = llplot_nice_ticks(0.0, vmax > 0.0 ? vmax : 1.0, 5, ticks, &step);
    r_top = ticks[n_ticks - 1];
    if (r_top < vmax && n_ticks < 16)
        r_top = ticks[n_ticks++] = r_top + step;

    surface = llplot_canvas_create((int)width, (int)height, &cr);
    if (!surface)
        return LLPLOT_EXIT_IO;
    cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
    llplot_text(cr, width / 2, 14, 19, 1, 0.5, 0.0, o->title ? o->title : s->label);
    snprintf(text, sizeof text, "f · cos θ_{o} in the plane of incidence (%s)",
             o->channel == 'R' ? "red" : o->channel == 'G' ? "green"
                                     : o->channel == 'B' ? "blue" : "luminance");
    cairo_set_source_rgb(cr, 0.3, 0.3, 0.3);
    llplot_text(cr, width / 2, 42, 13, 0, 0.5, 0.0, text);
    draw_grid(cr, cx, cy, radius, ticks, n_ticks, step, r_top);
    cairo_set_source_rgb(cr, 0.45, 0.45, 0.45);
    llplot_text(cr, cx - radius, cy + 22, 11, 0, 0.0, 0.0, "backward (toward the light)");
    llplot_text(cr, cx + radius, cy + 22, 11, 0, 1.0, 0.0, "forward (mirror side)");
    if (!(vmax > 0.0)) {
        cairo_set_source_rgb(cr, 0.4, 0.4, 0.4);
        llplot_text(cr, cx, cy - radius / 2, 15, 0, 0.5, 0.5, "no reflection");
    }

    cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
    for (a = 0; a < o->n_angles; ++a) {
        const double *rgb = curve_colors[a];
        cairo_set_source_rgb(cr, rgb[0], rgb[1], rgb[2]);
        cairo_set_line_width(cr, 2.0);
        for (k = 0; k < CURVE_SAMPLES; ++k) {
            double x, y;
            polar_point(cx, cy, radius * values[a][k] / r_top,
                        -90.0 + 180.0 * (double)k / (CURVE_SAMPLES - 1), &x, &y);
            if (k == 0)
                cairo_move_to(cr, x, y);
            else
                cairo_line_to(cr, x, y);
        }
        cairo_stroke(cr);
        draw_light_marker(cr, cx, cy, radius, o->angles_deg[a]);
    }

    /* Legend: one row under the plot, centred. */
    for (a = 0; a < o->n_angles; ++a) {
        snprintf(text, sizeof text, "θ_{i} = %g°", o->angles_deg[a]);
        legend_w += 28 + llplot_text_width(cr, 12, 0, text) + 18;
    }
    legend_x = 0.5 * (width - legend_w);
    for (a = 0; a < o->n_angles; ++a) {
        const double *rgb = curve_colors[a];
        double y = cy + 56;
        cairo_set_source_rgb(cr, rgb[0], rgb[1], rgb[2]);
        cairo_set_line_width(cr, 3.0);
        cairo_move_to(cr, legend_x, y);
        cairo_line_to(cr, legend_x + 22, y);
        cairo_stroke(cr);
        snprintf(text, sizeof text, "θ_{i} = %g°", o->angles_deg[a]);
        cairo_set_source_rgb(cr, 0.15, 0.15, 0.15);
        legend_x += 28 + llplot_text(cr, legend_x + 28, y, 12, 0, 0.0, 0.5, text) + 18;
    }
    cairo_destroy(cr);
    code = llplot_write_png(o->output, surface);
    cairo_surface_destroy(surface);
    return code;
}

int llplot_polar(const llplot_options *o, const llplot_source *s)
{
    llplot_image img;
    char comments[512];
    size_t n = o->size ? o->size : LLPLOT_DEFAULT_POLAR_SIZE, a, k, c;
    int code;
    if (o->format == LLPLOT_PNG)
        return draw_figure(o, s);
    code = llplot_image_alloc(&img, n, o->n_angles, 3);
    if (code != LLPLOT_EXIT_OK)
        return code;
    img.names[0] = "R";
    img.names[1] = "G";
    img.names[2] = "B";
    for (a = 0; a < o->n_angles; ++a)
        for (k = 0; k < n; ++k) {
            double rgb[3];
            plane_value(s, o->angles_deg[a], -90.0 + 180.0 * ((double)k + 0.5) / (double)n, rgb);
            for (c = 0; c < 3; ++c)
                *llplot_pixel(&img, c, k, a) = (float)rgb[c];
        }
    snprintf(comments, sizeof comments,
             "llplot --polar %s: RGB = f * cos(theta_o) in the plane of incidence; row a: "
             "incident angle a of --angles; column k: theta_o = -90 + 180 (k + 0.5)/%zu deg "
             "(negative: backward side, phi_d = pi)",
             s->label, n);
    code = llplot_write_exr(o->output, &img, comments);
    llplot_image_free(&img);
    return code;
}
