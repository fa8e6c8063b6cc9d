/*
 * ll_tables_write_from_bsdf (ll_tables.h): the tables of the `measured`
 * format from an opened opaque, untextured file (a transmissive one goes
 * to bsdf_write_tables_lobes.c), following the producer's
 * steps of docs/formats.md:
 *  1. D and sigma from retro-reflection (bsdf_write_tables_ndf.c), stored
 *     as float tables over (u_phi, u_theta) with two equal rows;
 *  2. per incident elevation, the visible-normal density
 *     max(0, wi.m) D(m) / sigma(wi) times the change of variables
 *     2 pi^2 u_theta sin(theta_m) on the VNDF grid;
 *  3. the sample grid's nodes pushed through the reader's own warp
 *     (reader/tables_warp.c, built from the very floats written), the
 *     incident direction reflected about each normal, f cos there;
 *  4. stored values f cos 4 sigma(wi) / D(m) with D and sigma as the
 *     tables interpolate them, so a reader's product gives f cos back
 *     exactly at the nodes; the luminance of those values, with a floor
 *     of 1e-3 of the slice's largest, as the sampling density.
 * A spectral file shares steps 1-3 (the warp of the RGB source) and takes
 * its values per wavelength (bsdf_write_tables_spectra.c) at the same
 * directions, which step 3 keeps for it.
 *
 * The tables of a textured file's basis are stored as float16 (half):
 * then the VNDF is rounded to float16 before step 3 builds its warp, since
 * a reader builds the warp from the rounded values and the nodes must sit
 * where its warp puts them, and the values and luminance are rounded as
 * they are computed, so that what the tolerance search measures is what
 * the file holds.
 */
#include "layerlab/ll_tables.h"
#include "writer/bsdf_write_tables.h"
#include "writer/bsdf_write_tensor.h"
#include "reader/tables_warp.h"
#include "reader/tables_internal.h"
#include "reader/cie.h"
#include "support/watch.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define FN "ll_tables_write_from_bsdf"
/* The luminance table's floor, relative to its slice's largest value:
 * every slice stays normalisable and every part of the square reachable. */
#define LUMINANCE_FLOOR 1e-3
/* Light transmitted beyond this fraction of the largest reflected a_0
 * makes a file transmissive (a conductor's transmitted blocks are 0). */
#define TRANSMISSION_TOLERANCE 1e-6

typedef struct writer {
    const ll_bsdf *b;
    size_t n_ti, nv, ns;
    float *theta_i, phi_i[1], *ndf, *sigma, *vndf, *lum, *rgb;
    ll_warp2d ndf_w, sigma_w, vndf_w;
    int spectral;
    int half;                /* the grids rounded to float16              */
    double *geom;            /* spectral: [n_ti][ns * ns][wo, scale]      */
    float *wavelengths;      /* spectral: [n_l] as stored                 */
    ll_tables_spectra spectra;
} writer;

/* A spectral file's wavelengths: where the CIE tables that read them back
 * are defined, strictly increasing, and a source to build them from. */
static ll_status check_wavelengths(const ll_tables_options *o)
{
    size_t l;
    if (!o->spectrum)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       FN ": LL_TABLES_SPECTRAL needs a spectrum source (options.spectrum)");
    if (!o->wavelengths || o->n_wavelengths == 0 || o->n_wavelengths > LL_TABLES_MAX_WAVELENGTHS)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       FN ": LL_TABLES_SPECTRAL needs 1..%d wavelengths (%zu given)",
                       LL_TABLES_MAX_WAVELENGTHS, o->wavelengths ? o->n_wavelengths : 0);
    for (l = 0; l < o->n_wavelengths; ++l) {
        double v = o->wavelengths[l];
        if (!(v >= LL_CIE1931_FIRST_NM && v <= LL_CIE1931_LAST_NM))
            return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                           FN ": wavelength %zu = %g nm lies outside the CIE 1931 tables "
                           "(%g..%g nm)",
                           l, v, LL_CIE1931_FIRST_NM, LL_CIE1931_LAST_NM);
        if (l > 0 && !(v > o->wavelengths[l - 1]))
            return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                           FN ": wavelength %zu = %g nm is not above the one before (%g nm)", l,
                           v, o->wavelengths[l - 1]);
    }
    return LL_OK;
}

static ll_status check_options(const ll_tables_options *opts, ll_tables_options *o)
{
    ll_tables_options defaults = LL_TABLES_OPTIONS_INIT;
    ll_status s;
    *o = defaults;
    if (opts && (s = ll_struct_read(o, sizeof *o, opts, FN, "ll_tables_options")) != LL_OK)
        return s;
    if (!o->n_theta_i) o->n_theta_i = 32;
    if (!o->vndf_size) o->vndf_size = 128;
    if (!o->sample_size) o->sample_size = 64;
    if (o->n_theta_i < 2 || o->n_theta_i > 1024 || o->vndf_size < 2 || o->vndf_size > 4096 ||
        o->sample_size < 2 || o->sample_size > 4096)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       FN ": grid sizes n_theta_i = %zu (2..1024), vndf_size = %zu and "
                       "sample_size = %zu (2..4096) out of range",
                       o->n_theta_i, o->vndf_size, o->sample_size);
    if (o->format != LL_TABLES_RGB && o->format != LL_TABLES_SPECTRAL)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       FN ": unknown format %d (LL_TABLES_RGB, LL_TABLES_SPECTRAL)",
                       (int)o->format);
    if (o->format == LL_TABLES_SPECTRAL)
        return check_wavelengths(o);
    return LL_OK;
}

int ll_tables_transmits(const ll_bsdf *b)
{
    size_t n = b->n_nodes, i, o;
    double reflected = 0.0, transmitted = 0.0;
    if (fabs(b->eta - 1.0) > 1e-6)
        return 1;
    for (i = 0; i < n; ++i)
        for (o = 0; o < n; ++o) {
            double a = fabs(b->a0[i * n + o]);
            if (b->nodes[i] * b->nodes[o] > 0.0)
                transmitted = a > transmitted ? a : transmitted;
            else
                reflected = a > reflected ? a : reflected;
        }
    return transmitted > TRANSMISSION_TOLERANCE * reflected;
}

/* The format holds one untextured material; an extended table file (a
 * transmissive material's) has no order-0 series to weigh its lobes by,
 * so it converts from its .bsdf only. */
static ll_status check_source(const ll_bsdf *b)
{
    if (b->measured && b->measured->extended)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       FN ": the file is a transmissive table file (a set of tables per "
                       "lobe); write its tables from the .bsdf it came from");
    if (b->n_bases != 1)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       FN ": the file is textured (%zu basis functions); a table file holds "
                       "one material without parameters",
                       b->n_bases);
    return LL_OK;
}

static ll_status allocate(writer *w)
{
    size_t nd = LL_TABLES_NDF_NODES, v, s;
    if (!ll_size_mul(w->nv, w->nv, &v) || !ll_size_mul(v, w->n_ti, &v) ||
        !ll_size_mul(w->ns, w->ns, &s) || !ll_size_mul(s, w->n_ti, &s))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, FN ": the tables' size overflows");
    w->theta_i = ll_alloc_array(w->n_ti, sizeof(float));
    w->ndf = ll_alloc_array(2 * nd, sizeof(float));
    w->sigma = ll_alloc_array(2 * nd, sizeof(float));
    w->vndf = ll_alloc_array(v, sizeof(float));
    w->lum = ll_alloc_array(s, sizeof(float));
    if (w->spectral) {
        /* The sample directions instead of the RGB values. */
        w->geom = ll_alloc_array(s, 4 * sizeof(double));
        w->wavelengths = ll_alloc_array(w->spectra.n_l, sizeof(float));
    } else {
        w->rgb = ll_alloc_array(s, 3 * sizeof(float));
    }
    if (!w->theta_i || !w->ndf || !w->sigma || !w->vndf || !w->lum ||
        (w->spectral ? !w->geom || !w->wavelengths : !w->rgb))
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, FN ": out of memory (tables)");
    return LL_OK;
}

static void release(writer *w)
{
    ll_free(w->theta_i);
    ll_free(w->ndf);
    ll_free(w->sigma);
    ll_free(w->vndf);
    ll_free(w->lum);
    ll_free(w->rgb);
    ll_free(w->geom);
    ll_free(w->wavelengths);
    ll_tables_spectra_close(&w->spectra);
    ll_warp2d_free(&w->ndf_w);
    ll_warp2d_free(&w->sigma_w);
    ll_warp2d_free(&w->vndf_w);
}

/* Step 1: D and sigma, as float tables and as the warps that interpolate
 * them exactly as a reader will. */
static ll_status ndf_tables(writer *w, double *alpha)
{
    double d[LL_TABLES_NDF_NODES], sigma[LL_TABLES_NDF_NODES];
    ll_status s = ll_tables_derive_ndf(w->b, d, sigma, alpha);
    if (s != LL_OK)
        return s;
    return ll_tables_ndf_warps(d, sigma, w->ndf, w->sigma, &w->ndf_w, &w->sigma_w);
}

/* Step 2 for slice t. */
static void vndf_slice(writer *w, size_t t)
{
    size_t nv = w->nv;
    ll_tables_vndf_slice(&w->ndf_w, &w->sigma_w, (double)w->theta_i[t], nv,
                         w->vndf + t * nv * nv);
}

/* The luminance floor of slice t (every slice normalisable), relative to
 * top, its largest value (< 0: the largest stored). */
static void floor_slice(writer *w, size_t t, double top)
{
    size_t plane = w->ns * w->ns, x;
    float *lum = w->lum + t * plane;
    double floor_v;
    if (top < 0.0)
        for (x = 0, top = 0.0; x < plane; ++x)
            if ((double)lum[x] > top)
                top = (double)lum[x];
    floor_v = top > 0.0 ? LUMINANCE_FLOOR * top : 1.0;
    if (w->half && floor_v < LL_TABLES_HALF_TINY)
        floor_v = LL_TABLES_HALF_TINY;
    for (x = 0; x < plane; ++x)
        if (!((double)lum[x] >= floor_v))
            lum[x] = (float)floor_v;
}

/* The n values v rounded to float16 in place, or an error naming the
 * table if one lies beyond float16's range: the values are f cos
 * 4 sigma / D and densities over the unit square, of order 1
 * (docs/formats.md, "Textured files"), so one near 65504 would be a fault of
 * the source rather than a value to clamp. */
ll_status ll_tables_round_half(float *v, size_t n, const char *table)
{
    size_t i;
    for (i = 0; i < n; ++i) {
        float r = ll_half_round(v[i]);
        if (!(r <= LL_HALF_MAX))
            return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                           FN ": table \"%s\": element %zu = %g is beyond float16's range "
                           "(65504), in which a textured or transmissive file's tables are "
                           "stored",
                           table, i, (double)v[i]);
        v[i] = r;
    }
    return LL_OK;
}

/* ll_tables_round_half where the grids are float16 (w->half). */
static ll_status round_half(const writer *w, float *v, size_t n, const char *table)
{
    return w->half ? ll_tables_round_half(v, n, table) : LL_OK;
}

/* Steps 3 and 4 for slice t; a spectral file keeps each node's direction
 * and factor instead (its values come per wavelength). below (ns * ns)
 * receives which nodes' directions are below the horizon, whose values
 * ll_tables_horizon_fit then sets. */
static ll_status value_slice(writer *w, size_t t, unsigned char *below)
{
    size_t ns = w->ns, x, y, c, plane = ns * ns;
    double th = (double)w->theta_i[t], wi[3] = { sin(th), 0.0, cos(th) };
    double param[2] = { 0.0, th };
    double four_sigma = 4.0 * ll_tables_sigma_at(&w->sigma_w, th);
    float *lum = w->lum + t * plane, *rgb = w->rgb ? w->rgb + t * 3 * plane : NULL;
    double target[3];
    ll_tables_horizon h;
    ll_status s;
    for (y = 0; y < ns; ++y)
        for (x = 0; x < ns; ++x) {
            double sq[2] = { (double)x / (double)(ns - 1), (double)y / (double)(ns - 1) };
            double um[2], pdf, tm, m[3], wo[3], f[3] = { 0.0, 0.0, 0.0 }, scale, y_lum;
            ll_warp2d_sample(&w->vndf_w, sq, param, um, &pdf);
            (void)ll_tables_mirror(wi, um, 0.0, &tm, m, wo);
            below[y * ns + x] = !(wo[2] > 0.0);
            if (w->spectral) {
                double *g = w->geom + (t * plane + y * ns + x) * 4;
                scale = wo[2] * four_sigma / ll_warp2d_eval(&w->ndf_w, um, NULL);
                g[0] = wo[0];
                g[1] = wo[1];
                g[2] = wo[2];
                g[3] = wo[2] > 0.0 && wi[2] > 0.0 && ll_is_finite(scale) ? scale : 0.0;
                continue;
            }
            /* Our renderer convention: wo (viewer) is the format's wi. */
            if (wo[2] > 0.0 && wi[2] > 0.0 &&
                ll_bsdf_eval_dir(w->b, wi, wo, LL_TRANSPORT_RADIANCE, NULL, f) != LL_OK)
                f[0] = f[1] = f[2] = 0.0;
            if (!(wo[2] > 0.0 && wi[2] > 0.0))
                f[0] = f[1] = f[2] = 0.0;
            scale = wo[2] * four_sigma / ll_warp2d_eval(&w->ndf_w, um, NULL);
            if (!ll_is_finite(scale))
                scale = 0.0;
            for (c = 0; c < 3; ++c) {
                double v = f[c] * scale;
                rgb[c * plane + y * ns + x] = (float)(v > 0.0 ? v : 0.0);
                f[c] = v > 0.0 ? v : 0.0;
            }
            y_lum = ll_tables_luminance(f);
            lum[y * ns + x] = (float)y_lum;
        }
    if (w->spectral)
        return LL_OK;
    h.ndf_w = &w->ndf_w;
    h.vndf_w = &w->vndf_w;
    h.sigma = 0.25 * four_sigma;
    h.param[0] = 0.0;
    h.param[1] = th;
    h.fresnel_eta = 0.0;
    h.over_f = 0u;
    if ((s = ll_tables_horizon_target(w->b, th, 0, 0, target)) != LL_OK)
        return s;
    /* The values per channel, and the luminance (what sampling follows)
     * as a plane of its own in the same fit, to the source's luminance
     * albedo (ll_tables_horizon_fit_rgb says why). */
    if ((target[0] > 0.0 || target[1] > 0.0 || target[2] > 0.0) &&
        (s = ll_tables_horizon_fit_rgb(&h, ns, below, target, rgb, lum)) != LL_OK)
        return s;
    floor_slice(w, t, -1.0);
    if ((s = round_half(w, rgb, 3 * plane, "rgb")) != LL_OK)
        return s;
    return round_half(w, lum, plane, "luminance");
}

/* JSON text of a string (quotes and escapes), appended to buf. */
size_t ll_tables_json_string(char *buf, size_t at, size_t cap, const char *s)
{
    if (at < cap) buf[at] = '"';
    ++at;
    for (; *s; ++s) {
        unsigned char ch = (unsigned char)*s;
        char esc[8];
        size_t n, k;
        if (ch == '"' || ch == '\\')
            n = (size_t)snprintf(esc, sizeof esc, "\\%c", ch);
        else if (ch < 0x20)
            n = (size_t)snprintf(esc, sizeof esc, "\\u%04x", ch);
        else {
            esc[0] = (char)ch;
            n = 1;
        }
        for (k = 0; k < n; ++k, ++at)
            if (at < cap) buf[at] = esc[k];
    }
    if (at < cap) buf[at] = '"';
    return at + 1;
}

/* Our metadata field: the grid, the fitted roughness, the source's text. */
static char *metadata_text(const writer *w, double alpha, const char *figures, size_t *size)
{
    size_t cap = 512, at;
    char *buf = NULL;
    const char *src = w->b->metadata ? w->b->metadata : "";
    if (!figures)
        figures = "";
    if (!ll_size_add(cap, w->b->metadata_size, &cap) || !ll_size_mul(cap, 6, &cap) ||
        !ll_size_add(cap, strlen(figures), &cap))
        return NULL;
    buf = ll_malloc(cap);
    if (!buf)
        return NULL;
    /* cap holds the worst case: every source byte escaped as \u00XX. */
    at = (size_t)snprintf(buf, cap,
                          "{\"writer\": \"layerlab %s\", \"theta_i\": %zu, \"vndf\": [%zu, %zu], "
                          "\"sample\": [%zu, %zu], \"ndf_alpha\": %.6g, \"wavelengths\": %zu, "
                          "%s\"bsdf_metadata\": ",
                          ll_version_string(), w->n_ti, w->nv, w->nv, w->ns, w->ns, alpha,
                          w->spectral ? w->spectra.n_l : (size_t)0, figures);
    at = ll_tables_json_string(buf, at, cap, src);
    buf[at++] = '}';
    buf[at] = '\0';
    *size = at;
    return buf;
}

ll_status ll_tables_write_grid(const ll_bsdf *b, const char *path, const ll_tables_options *opts,
                               const char *figures, int half, const ll_monitor *monitor)
{
    ll_tables_options o;
    writer w;
    ll_watch watch;
    double alpha = 0.0;
    char *meta = NULL;
    size_t meta_size = 0, t;
    ll_status s;
    memset(&w, 0, sizeof w);
    if (!b || !path)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, FN ": bsdf or path is NULL");
    if ((s = check_options(opts, &o)) != LL_OK || (s = check_source(b)) != LL_OK)
        return s;
    /* A transmissive file: every lobe, both sides, in an extended file,
     * whose grids are always float16 (a textured file's bases are
     * opaque, so half is never asked for here). */
    if (ll_tables_transmits(b))
        return half ? ll_fail(LL_ERROR_UNSUPPORTED,
                              FN ": a textured file's basis transmits")
                    : ll_tables_write_lobes(b, path, &o, figures, monitor);
    if ((s = ll_watch_begin(&watch, monitor, FN)) != LL_OK)
        return s;
    w.b = b;
    w.spectral = o.format == LL_TABLES_SPECTRAL;
    w.half = half;
    w.spectra.n_l = w.spectral ? o.n_wavelengths : 0;
    w.n_ti = o.n_theta_i;
    w.nv = o.vndf_size;
    w.ns = o.sample_size;
    w.phi_i[0] = 0.0f;
    if ((s = allocate(&w)) != LL_OK)
        goto done;
    /* Incident elevations theta = 90 deg sin(v 90 deg), v uniform: the
     * lobe's shape changes fastest towards grazing, where the slices are
     * interpolated linearly on the sample square. On rough gold (alpha 0.2,
     * 32 slices) this spacing cut the albedo error at 84 degrees from 0.35%
     * (uniform theta) to 0.14%. */
    for (t = 0; t < w.n_ti; ++t)
        w.theta_i[t] = (float)(sin((double)t / (double)(w.n_ti - 1) * (LL_PI / 2)) * (LL_PI / 2));

    ll_watch_stage(&watch, "ndf", 0.0, 0.1, 1);
    if ((s = ndf_tables(&w, &alpha)) != LL_OK || (s = ll_watch_check(&watch, FN)) != LL_OK)
        goto done;
    ll_watch_stage(&watch, "tables", 0.1, w.spectral ? 0.1 : 0.8, 2 * w.n_ti);
    for (t = 0; t < w.n_ti; ++t) {
        vndf_slice(&w, t);
        ll_watch_advance(&watch, 1);
        if ((s = ll_watch_check(&watch, FN)) != LL_OK)
            goto done;
    }
    /* A float16 VNDF is rounded before the warp that places the values is
     * built from it (the file's header says why); allocate() checked the
     * product. */
    if ((s = round_half(&w, w.vndf, w.n_ti * w.nv * w.nv, "vndf")) != LL_OK)
        goto done;
    {
        double phi[1] = { 0.0 }, *theta = ll_alloc_array(w.n_ti, sizeof(double));
        const double *params[2];
        size_t sizes[2];
        if (!theta) {
            s = ll_fail(LL_ERROR_OUT_OF_MEMORY, FN ": out of memory");
            goto done;
        }
        for (t = 0; t < w.n_ti; ++t)
            theta[t] = (double)w.theta_i[t];
        params[0] = phi;
        params[1] = theta;
        sizes[0] = 1;
        sizes[1] = w.n_ti;
        s = ll_warp2d_init(&w.vndf_w, w.nv, w.nv, 2, sizes, params, ll_tables_get_float, w.vndf,
                           1);
        ll_free(theta);
        if (s != LL_OK)
            goto done;
    }
    {
        unsigned char *below = ll_alloc_array(w.ns, w.ns);
        if (!below) {
            s = ll_fail(LL_ERROR_OUT_OF_MEMORY, FN ": out of memory");
            goto done;
        }
        for (t = 0; t < w.n_ti && s == LL_OK; ++t) {
            if ((s = value_slice(&w, t, below)) != LL_OK)
                break;
            ll_watch_advance(&watch, 1);
            s = ll_watch_check(&watch, FN);
        }
        ll_free(below);
        if (s != LL_OK)
            goto done;
    }
    if (w.spectral) {
        ll_watch_stage(&watch, "spectra", 0.2, 0.7, w.spectra.n_l);
        w.spectra.plane = w.ns * w.ns;
        w.spectra.n_ti = w.n_ti;
        w.spectra.wavelengths = o.wavelengths;
        w.spectra.theta_i = w.theta_i;
        w.spectra.geom = w.geom;
        w.spectra.ndf_w = &w.ndf_w;
        w.spectra.vndf_w = &w.vndf_w;
        w.spectra.sigma_w = &w.sigma_w;
        s = ll_tables_spectra_run(&w.spectra, o.spectrum, o.spectrum_user, w.lum, &watch, FN);
        if (s != LL_OK)
            goto done;
        for (t = 0; t < w.n_ti; ++t)
            floor_slice(&w, t, -1.0);
        /* The spectra are rounded as they are written (the textured
         * writer's float16 fields); allocate() checked the product. */
        if ((s = round_half(&w, w.lum, w.n_ti * w.ns * w.ns, "luminance")) != LL_OK)
            goto done;
        for (t = 0; t < w.spectra.n_l; ++t)
            w.wavelengths[t] = (float)o.wavelengths[t];
    }
    meta = metadata_text(&w, alpha, figures, &meta_size);
    if (!meta) {
        s = ll_fail(LL_ERROR_OUT_OF_MEMORY, FN ": out of memory (metadata)");
        goto done;
    }
    ll_watch_stage(&watch, "writing", 0.9, 0.1, 1);
    {
        static const unsigned char jacobian[1] = { 1 };
        const char *desc = o.description ? o.description
                           : w.spectral  ? "layerlab: warped tables of an opaque layered "
                                           "material (spectral)"
                                         : "layerlab: warped tables of an opaque layered "
                                           "material (RGB)";
        size_t nd = LL_TABLES_NDF_NODES;
        ll_tensor_out_field f[11] = {
            { "description", LL_TENSOR_U8, 1, { strlen(desc) }, desc, NULL, NULL },
            { "jacobian", LL_TENSOR_U8, 1, { 1 }, jacobian, NULL, NULL },
            { "theta_i", LL_TENSOR_F32, 1, { w.n_ti }, w.theta_i, NULL, NULL },
            { "phi_i", LL_TENSOR_F32, 1, { 1 }, w.phi_i, NULL, NULL },
            { "ndf", LL_TENSOR_F32, 2, { 2, nd }, w.ndf, NULL, NULL },
            { "sigma", LL_TENSOR_F32, 2, { 2, nd }, w.sigma, NULL, NULL },
            { "vndf", LL_TENSOR_F32, 4, { 1, w.n_ti, w.nv, w.nv }, w.vndf, NULL, NULL },
            { "luminance", LL_TENSOR_F32, 4, { 1, w.n_ti, w.ns, w.ns }, w.lum, NULL, NULL },
            { "rgb", LL_TENSOR_F32, 5, { 1, w.n_ti, 3, w.ns, w.ns }, w.rgb, NULL, NULL },
            { "layerlab_metadata", LL_TENSOR_U8, 1, { meta_size }, meta, NULL, NULL },
            { "wavelengths", LL_TENSOR_F32, 1, { w.spectra.n_l }, w.wavelengths, NULL, NULL },
        };
        if (w.spectral) {
            /* "spectra" in the place of "rgb", filled from the scratch file. */
            ll_tensor_out_field spectra = { "spectra", LL_TENSOR_F32, 5,
                                            { 1, w.n_ti, w.spectra.n_l, w.ns, w.ns }, NULL,
                                            ll_tables_spectra_fill, &w.spectra };
            f[8] = spectra;
        }
        if ((s = ll_watch_finish(&watch, LL_OK, FN)) != LL_OK)
            goto done;
        s = ll_tensor_write(path, FN, f, w.spectral ? 11 : 10);
    }
done:
    ll_free(meta);
    release(&w);
    return s;
}
