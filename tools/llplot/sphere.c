/*
 * llplot --sphere: a sphere of the material under the studio lighting of
 * scene.h, seen by an orthographic camera, rendered by Monte Carlo
 * integration of the reflected radiance
 *     L_o(wo) = integral f(wo, wi) L_env(wi) cos(theta_i) dwi
 *               + f(wo, l) E_key cos(theta_l).
 * The environment integral is importance-sampled with ll_bsdf_sample_dir
 * (pbrt-v3's FourierBSDF::Sample_f): its weight f cos / pdf is nearly
 * constant (within 0.5% for the rough gold test file), so the noise left is
 * that of the sky within the lobe. The delta key light is evaluated exactly.
 * Light that a transmissive stack lets into the sphere is followed through
 * it (the sphere is filled with what lies below the stack) until it leaves.
 *
 * Each pixel has its own random stream derived from (seed, pixel index), so
 * pictures are reproducible and independent of the thread count. The two
 * numbers that drive the BSDF sampler come from the first two dimensions
 * of the Sobol sequence (a (0,2)-sequence: every power-of-two prefix is
 * stratified in all elementary intervals), randomised per pixel by a
 * digital XOR shift; the position inside the pixel is uniformly random,
 * which anti-aliases the silhouette. A 3 x 3 reconstruction filter then
 * shares samples between neighbouring pixels.
 *
 * EXR: linear RGBA (premultiplied; A is the sphere's pixel coverage, the
 * background is transparent). PNG: exposure, a filmic tone curve and the
 * sRGB transfer function, over a neutral backdrop.
 */
#include "figure.h"
#include "llplot.h"
#include "scene.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct sphere_job {
    const llplot_source *source;
    llplot_image *img;
    size_t size, spp;
    uint64_t seed;
    double key_dir[3], key_e[3];
    const float *column_coeffs; /* --vary: n_bases weights per column, or NULL */
    size_t n_bases;
} sphere_job;

/* SplitMix64 (Steele, Lea and Flood 2014): a fast generator whose output
 * is well mixed even for consecutive seeds, used per pixel. */
static uint64_t splitmix64(uint64_t *state)
{
    uint64_t z = (*state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

static double uniform01(uint64_t *state)
{
    return (double)(splitmix64(state) >> 11) * (1.0 / 9007199254740992.0);
}

/* Sobol dimension 1 is the base-2 radical inverse; dimension 2 uses the
 * direction numbers v_{k+1} = v_k xor (v_k >> 1), v_1 = 2^31. */
static uint32_t sobol_dim1(uint32_t i)
{
    i = (i << 16) | (i >> 16);
    i = ((i & 0x00ff00ffu) << 8) | ((i & 0xff00ff00u) >> 8);
    i = ((i & 0x0f0f0f0fu) << 4) | ((i & 0xf0f0f0f0u) >> 4);
    i = ((i & 0x33333333u) << 2) | ((i & 0xccccccccu) >> 2);
    i = ((i & 0x55555555u) << 1) | ((i & 0xaaaaaaaau) >> 1);
    return i;
}

static uint32_t sobol_dim2(uint32_t i)
{
    uint32_t v = 1u << 31, r = 0;
    for (; i; i >>= 1, v ^= v >> 1)
        if (i & 1u)
            r ^= v;
    return r;
}

/* Never 1.0: the sampler expects u in [0, 1). */
static double to_unit(uint32_t bits) { return (double)bits * (1.0 / 4294967296.0); }

/* An orthonormal frame (t, b, n) around the unit normal n (Duff et al.,
 * "Building an Orthonormal Basis, Revisited", JCGT 2017), free of the
 * singularity of cross-product constructions. */
static void frame_from_normal(const double n[3], double t[3], double b[3])
{
    double sign = n[2] >= 0.0 ? 1.0 : -1.0;
    double a = -1.0 / (sign + n[2]);
    double c = n[0] * n[1] * a;
    t[0] = 1.0 + sign * n[0] * n[0] * a;
    t[1] = sign * c;
    t[2] = -sign * n[0];
    b[0] = c;
    b[1] = sign + n[1] * n[1] * a;
    b[2] = -n[1];
}

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* The shading frame at a point of the unit sphere: tangents t, b, the
 * outward normal n, and the position p (equal to n on a unit sphere). */
typedef struct shading_frame {
    double t[3], b[3], n[3];
} shading_frame;

static void shading_frame_at(const double p[3], shading_frame *f)
{
    int c;
    for (c = 0; c < 3; ++c)
        f->n[c] = p[c];
    frame_from_normal(f->n, f->t, f->b);
}

static void to_local(const shading_frame *f, const double w[3], double out[3])
{
    out[0] = dot3(w, f->t);
    out[1] = dot3(w, f->b);
    out[2] = dot3(w, f->n);
}

static void to_world(const shading_frame *f, const double w[3], double out[3])
{
    int c;
    for (c = 0; c < 3; ++c)
        out[c] = f->t[c] * w[0] + f->b[c] * w[1] + f->n[c] * w[2];
}

/* Bounces inside the sphere before a path is abandoned (total internal
 * reflection in a glass ball can keep light in for long; what is left
 * after this many bounces is a fraction of a percent). */
#define MAX_BOUNCES 8

/* Environment light reflected toward the camera, one path importance-
 * sampled by the BSDF: each bounce multiplies the throughput by f cos / pdf.
 * A direction above the surface leaves to the sky. One below it enters the
 * sphere, which is filled with whatever lies under the stack (air for a
 * coated sheet, glass for a frosted-glass interface): the path crosses the
 * sphere in a straight line and meets the stack again from below at the far
 * side, where the BSDF's bottom half (R^b, T^bt) takes over. Opaque stacks
 * never get there. The first bounce uses the stratified numbers u, later
 * ones the pixel's random stream. */
static void shade_environment(const sphere_job *job, const float *basis, const double hit[3],
                              const double u[2], uint64_t *state, double out[3])
{
    const llplot_source *s = job->source;
    double p[3], d[3], throughput[3] = { 1.0, 1.0, 1.0 }, v[2];
    int c, bounce;
    out[0] = out[1] = out[2] = 0.0;
    for (c = 0; c < 3; ++c)
        p[c] = hit[c];
    /* The camera looks along -z. */
    d[0] = 0.0;
    d[1] = 0.0;
    d[2] = -1.0;
    v[0] = u[0];
    v[1] = u[1];
    for (bounce = 0; bounce < MAX_BOUNCES; ++bounce) {
        shading_frame f;
        double wo[3], back[3], wi[3], w[3], fr[3], pdf = 0.0, env[3], t;
        shading_frame_at(p, &f);
        for (c = 0; c < 3; ++c)
            back[c] = -d[c];
        to_local(&f, back, wo);
        if (ll_bsdf_sample_dir(s->bsdf, wo, v, LL_TRANSPORT_RADIANCE, basis, wi, &pdf, fr) !=
                LL_OK ||
            !(pdf > 0.0))
            return;
        for (c = 0; c < 3; ++c)
            throughput[c] *= fr[c] * fabs(wi[2]) / pdf;
        to_world(&f, wi, w);
        if (wi[2] > 0.0) {
            llplot_env_radiance(w, env);
            for (c = 0; c < 3; ++c)
                out[c] = throughput[c] * env[c];
            return;
        }
        if (!(throughput[0] > 0.0 || throughput[1] > 0.0 || throughput[2] > 0.0))
            return;
        /* Inside: the chord from p (|p| = 1) along w ends at p + t w with
         * t = -2 p.w (positive, since w points inward). */
        t = -2.0 * dot3(p, w);
        for (c = 0; c < 3; ++c) {
            p[c] += t * w[c];
            d[c] = w[c];
        }
        t = sqrt(dot3(p, p));
        for (c = 0; c < 3; ++c)
            p[c] /= t;
        v[0] = uniform01(state);
        v[1] = uniform01(state);
    }
}

/* Reflected key light: a delta direction, evaluated exactly. It is seen
 * in reflection only (not through a transmissive sphere). */
static void shade_key(const sphere_job *job, const float *basis, const double hit[3],
                      double out[3])
{
    const llplot_source *s = job->source;
    const double camera[3] = { 0.0, 0.0, 1.0 };
    double l[3], wo[3], f[3];
    shading_frame frame;
    int c;
    out[0] = out[1] = out[2] = 0.0;
    shading_frame_at(hit, &frame);
    to_local(&frame, job->key_dir, l);
    to_local(&frame, camera, wo);
    if (l[2] > 0.0 &&
        ll_bsdf_eval_dir(s->bsdf, wo, l, LL_TRANSPORT_RADIANCE, basis, f) == LL_OK)
        for (c = 0; c < 3; ++c)
            out[c] = f[c] * l[2] * job->key_e[c];
}

/* The key light varies smoothly over a pixel and costs a BSDF evaluation,
 * so only every KEY_STRIDE-th sample position evaluates it (about a fifth
 * of the time saved); the environment gets every sample. */
#define KEY_STRIDE 4

static int finite3(const double v[3])
{
    return isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]);
}

static void sphere_row(size_t y, void *ctx)
{
    const sphere_job *job = ctx;
    double half = 0.5 * (double)job->size, radius = LLPLOT_SPHERE_RADIUS * half;
    size_t x, i, c;
    for (x = 0; x < job->size; ++x) {
        uint64_t state = job->seed ^ (0xD1B54A32D192ED03ull * (uint64_t)(y * job->size + x + 1));
        uint32_t shift0 = (uint32_t)splitmix64(&state), shift1 = (uint32_t)splitmix64(&state);
        double env_sum[3] = { 0.0, 0.0, 0.0 }, key_sum[3] = { 0.0, 0.0, 0.0 };
        double covered = 0.0, key_positions = 0.0;
        const float *basis = job->column_coeffs ? job->column_coeffs + x * job->n_bases
                                                : job->source->basis_coeffs;
        for (i = 0; i < job->spp; ++i) {
            double px = (double)x + uniform01(&state), py = (double)y + uniform01(&state);
            double sx = (px - half) / radius, sy = (half - py) / radius, u[2], L[3], hit[3];
            int key = i % KEY_STRIDE == 0;
            /* Positions off the sphere count, as zero, toward both
             * averages: the pixel value is premultiplied by coverage. */
            key_positions += key;
            if (sx * sx + sy * sy >= 1.0)
                continue;
            covered += 1.0;
            hit[0] = sx;
            hit[1] = sy;
            hit[2] = sqrt(1.0 - sx * sx - sy * sy);
            u[0] = to_unit(sobol_dim1((uint32_t)i) ^ shift0);
            u[1] = to_unit(sobol_dim2((uint32_t)i) ^ shift1);
            /* A failed or degenerate sample counts as black rather than
             * poisoning the pixel. */
            shade_environment(job, basis, hit, u, &state, L);
            if (finite3(L))
                for (c = 0; c < 3; ++c)
                    env_sum[c] += L[c];
            if (key) {
                shade_key(job, basis, hit, L);
                if (finite3(L))
                    for (c = 0; c < 3; ++c)
                        key_sum[c] += L[c];
            }
        }
        for (c = 0; c < 3; ++c)
            *llplot_pixel(job->img, c, x, y) =
                (float)(env_sum[c] / (double)job->spp + key_sum[c] / key_positions);
        *llplot_pixel(job->img, 3, x, y) = (float)(covered / (double)job->spp);
    }
}

/* ---------------------------------------------------------------- PNG */

/* Narkowicz's fit of the ACES filmic curve: a gentle shoulder keeps
 * highlights from clipping flat. */
static double tone_curve(double x)
{
    double y = x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14);
    return y < 0.0 ? 0.0 : y > 1.0 ? 1.0 : y;
}

static double srgb_encode(double x)
{
    return x <= 0.0031308 ? 12.92 * x : 1.055 * pow(x, 1.0 / 2.4) - 0.055;
}

/* The backdrop behind the sphere (display values): a dark neutral gradient
 * that lets both bright metals and dark diffuse materials stand out. */
static void backdrop(double v, double rgb[3])
{
    rgb[0] = 0.34 - 0.16 * v;
    rgb[1] = 0.35 - 0.16 * v;
    rgb[2] = 0.37 - 0.16 * v;
}

void llplot_sphere_paint(const llplot_options *o, const llplot_image *img, unsigned char *data,
                         int stride, size_t x0, size_t y0)
{
    double gain = pow(2.0, o->exposure);
    size_t x, y, c;
    for (y = 0; y < img->height; ++y) {
        uint32_t *row = (uint32_t *)(void *)(data + (size_t)stride * (y0 + y)) + x0;
        double back[3];
        backdrop((double)y / (double)img->height, back);
        for (x = 0; x < img->width; ++x) {
            double alpha = *llplot_pixel(img, 3, x, y);
            uint32_t packed = 0;
            for (c = 0; c < 3; ++c) {
                /* Tone-map the sphere's own radiance (unpremultiplied), then
                 * blend with the backdrop by coverage in display space. */
                double L = alpha > 0.0 ? *llplot_pixel(img, c, x, y) / alpha : 0.0;
                double v = alpha * srgb_encode(tone_curve(gain * L)) + (1.0 - alpha) * back[c];
                uint32_t q = (uint32_t)(v * 255.0 + 0.5);
                packed = (packed << 8) | (q > 255u ? 255u : q);
            }
            row[x] = packed;
        }
    }
}

/* title: --title, else the input's file name (PNG figures have titles,
 * docs/material-language.md, "`llplot`"); vary: the caption of --vary
 * ("NAME: LO (left) to HI (right)"), or NULL. */
static int write_png(const llplot_options *o, const llplot_image *img, const char *title,
                     const char *vary)
{
    cairo_t *cr;
    cairo_surface_t *surface = llplot_canvas_create((int)img->width, (int)img->height, &cr);
    int code;
    if (!surface)
        return LLPLOT_EXIT_IO;
    cairo_surface_flush(surface);
    llplot_sphere_paint(o, img, cairo_image_surface_get_data(surface),
                        cairo_image_surface_get_stride(surface), 0, 0);
    cairo_surface_mark_dirty(surface);
    cairo_set_source_rgb(cr, 0.92, 0.92, 0.92);
    if (title && *title)
        llplot_text(cr, 0.5 * (double)img->width, (double)img->height - 8, 13, 0, 0.5, 1.0,
                    title);
    if (vary)
        llplot_text(cr, 0.5 * (double)img->width, 8, 13, 0, 0.5, 0.0, vary);
    cairo_destroy(cr);
    code = llplot_write_png(o->output, surface);
    cairo_surface_destroy(surface);
    return code;
}

/* The pixel reconstruction filter: a 3 x 3 binomial kernel (1 2 1) x (1 2 1)
 * / 16, a truncated Gaussian of standard deviation 0.7 pixel, as renderers
 * use (pbrt's default is a Gaussian of radius 1.5). Each pixel then draws on
 * the samples of its neighbours too, which cuts the noise by a factor of
 * about 2.7 for a slight softening. Applied to premultiplied RGBA, so the
 * silhouette blends correctly; edges of the image repeat their border. */
static int reconstruction_filter(llplot_image *img)
{
    static const float k[3] = { 0.25f, 0.5f, 0.25f };
    size_t w = img->width, h = img->height, c, x, y;
    float *row = malloc(w * sizeof(float)), *col = malloc(h * sizeof(float));
    if (!row || !col) {
        free(row);
        free(col);
        return llplot_fail(LLPLOT_EXIT_IO, "out of memory");
    }
    for (c = 0; c < img->channels; ++c) {
        for (y = 0; y < h; ++y) {
            for (x = 0; x < w; ++x) {
                size_t xl = x > 0 ? x - 1 : 0, xr = x + 1 < w ? x + 1 : x;
                row[x] = k[0] * *llplot_pixel(img, c, xl, y) + k[1] * *llplot_pixel(img, c, x, y) +
                         k[2] * *llplot_pixel(img, c, xr, y);
            }
            memcpy(llplot_pixel(img, c, 0, y), row, w * sizeof(float));
        }
        for (x = 0; x < w; ++x) {
            for (y = 0; y < h; ++y) {
                size_t yu = y > 0 ? y - 1 : 0, yd = y + 1 < h ? y + 1 : y;
                col[y] = k[0] * *llplot_pixel(img, c, x, yu) + k[1] * *llplot_pixel(img, c, x, y) +
                         k[2] * *llplot_pixel(img, c, x, yd);
            }
            for (y = 0; y < h; ++y)
                *llplot_pixel(img, c, x, y) = col[y];
        }
    }
    free(row);
    free(col);
    return LLPLOT_EXIT_OK;
}

int llplot_sphere_image(const llplot_options *o, const llplot_source *s, size_t size, size_t spp,
                        const float *column_coeffs, size_t n_bases, llplot_image *img)
{
    sphere_job job;
    int code;
    job.size = size;
    job.spp = spp;
    code = llplot_image_alloc(img, job.size, job.size, 4);
    if (code != LLPLOT_EXIT_OK)
        return code;
    img->names[0] = "R";
    img->names[1] = "G";
    img->names[2] = "B";
    img->names[3] = "A";
    job.source = s;
    job.img = img;
    job.seed = o->seed;
    job.column_coeffs = column_coeffs;
    job.n_bases = n_bases;
    llplot_key_direction(job.key_dir);
    llplot_key_irradiance(job.key_e);
    llplot_parallel_rows(job.size, o->threads, sphere_row, &job);
    code = reconstruction_filter(img);
    if (code != LLPLOT_EXIT_OK)
        llplot_image_free(img);
    return code;
}

/* --vary NAME: the weights of each pixel column, NAME running linearly from
 * its smallest sample at the sphere's left edge to its largest at the right
 * edge (pixel centres; columns beyond the sphere are clamped), the other
 * parameters at the fixed point; *caption says so. */
static int vary_weights(const llplot_options *o, const llplot_source *s, size_t size,
                        float **coeffs, size_t *n_bases, char *caption, size_t caption_size)
{
    llplot_axes a;
    size_t p, x, total;
    double half = 0.5 * (double)size, radius = LLPLOT_SPHERE_RADIUS * half, lo, hi;
    char lo_text[32], hi_text[32];
    int code = llplot_axes_open(o, s, "--vary", &a);
    if (code != LLPLOT_EXIT_OK)
        return code;
    code = llplot_axes_find(&a, o->vary, strlen(o->vary), "--vary", o->input, &p);
    if (code == LLPLOT_EXIT_OK && (a.n_bases == 0 || size > (size_t)-1 / a.n_bases ||
                                   size * a.n_bases > (size_t)-1 / sizeof(float)))
        code = llplot_fail(LLPLOT_EXIT_INPUT, "%s: %zu bases x %zu columns are too many",
                           o->input, a.n_bases, size);
    if (code != LLPLOT_EXIT_OK) {
        llplot_axes_close(&a);
        return code;
    }
    total = size * a.n_bases;
    *coeffs = malloc(total * sizeof(float));
    if (!*coeffs) {
        llplot_axes_close(&a);
        return llplot_fail(LLPLOT_EXIT_IO, "out of memory");
    }
    lo = a.positions[p][0];
    hi = a.positions[p][a.counts[p] - 1];
    for (x = 0; x < size && code == LLPLOT_EXIT_OK; ++x) {
        double t = 0.5 * (((double)x + 0.5 - half) / radius + 1.0);
        t = t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t;
        a.point[p] = lo + (hi - lo) * t;
        code = llplot_axes_weights(s, a.point, *coeffs + x * a.n_bases);
    }
    llplot_format_value(lo, lo_text, sizeof lo_text);
    llplot_format_value(hi, hi_text, sizeof hi_text);
    snprintf(caption, caption_size, "%s: %s (left) to %s (right)", o->vary, lo_text, hi_text);
    *n_bases = a.n_bases;
    llplot_axes_close(&a);
    if (code != LLPLOT_EXIT_OK) {
        free(*coeffs);
        *coeffs = NULL;
    }
    return code;
}

int llplot_sphere(const llplot_options *o, const llplot_source *s)
{
    llplot_image img;
    char comments[768], caption[320] = "";
    float *column_coeffs = NULL;
    size_t n_bases = 0;
    size_t size = o->size ? o->size : LLPLOT_DEFAULT_SPHERE_SIZE;
    size_t spp = o->spp ? o->spp : LLPLOT_DEFAULT_SPP;
    int code = LLPLOT_EXIT_OK;
    if (o->vary)
        code = vary_weights(o, s, size, &column_coeffs, &n_bases, caption, sizeof caption);
    if (code == LLPLOT_EXIT_OK)
        code = llplot_sphere_image(o, s, size, spp, column_coeffs, n_bases, &img);
    free(column_coeffs);
    if (code != LLPLOT_EXIT_OK)
        return code;
    if (o->format == LLPLOT_EXR) {
        snprintf(comments, sizeof comments,
                 "llplot --sphere %s: linear RGB radiance, premultiplied by A (coverage); "
                 "%zu samples per pixel, seed %llu; lighting as in tools/llplot/scene.h%s%s",
                 s->label, spp, (unsigned long long)o->seed, o->vary ? "; varied: " : "",
                 caption);
        code = llplot_write_exr(o->output, &img, comments);
    } else {
        code = write_png(o, &img, o->title ? o->title : s->label, o->vary ? caption : NULL);
    }
    llplot_image_free(&img);
    return code;
}
