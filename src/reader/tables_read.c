/*
 * Opening a table file of the `measured` format (docs/formats.md)
 * as an ll_bsdf: the container is parsed (tensor_read.c), then every field
 * the evaluation reads is checked -- presence, dtype, rank, the shapes that
 * must agree, every value finite and non-negative, the parameter lists
 * ascending -- before the warps are built from it (style.md rule 10). Each
 * problem is LL_ERROR_FORMAT naming the file and the field; a valid
 * variant this reader does not evaluate (anisotropic files)
 * LL_ERROR_UNSUPPORTED.
 *
 * A spectral file ("spectra" and "wavelengths") is converted to linear
 * sRGB here, once (reader/cie.h: the values as a reflectance lit by D65
 * and seen by the CIE 1931 observer, white-normalised on the file's own
 * wavelengths), so that evaluation and every consumer of the RGB calls
 * work on it unchanged.
 *
 * A textured file's sets (tables_textured.c) may store their three grids
 * (vndf, luminance, rgb or spectra) as float16, read as floats; every
 * other field, and every field of an untextured file, is float32 as the
 * format says (Mitsuba 3's `measured` refuses a file whose fields are
 * not).
 */
#include "reader/tables_internal.h"
#include "reader/tensor.h"
#include "reader/cie.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* Values beyond this are not a reflectance, and would let the products of
 * evaluation overflow (the same bound as the .bsdf reader's coefficients). */
#define LL_MEASURED_MAX_VALUE 1.2676506002282294e30
/* Wavelengths a spectral file may have (one per nm over 1 um and more). */
#define LL_MEASURED_MAX_WAVELENGTHS 4096
#define LL_MEASURED_MAX_WAVELENGTHS_TEXT "4096"

#define FAIL(status, ...) do { s = ll_fail(status, __VA_ARGS__); goto done; } while (0)

static double get_field(const void *ctx, size_t index)
{
    return (double)ll_tensor_value(ctx, index);
}

static double get_double(const void *ctx, size_t index)
{
    return ((const double *)ctx)[index];
}

/* Field name: present, float32 (or float16 if half), of the given rank. */
static ll_status require_as(const ll_tensor_file *t, const char *name, size_t rank, int half,
                            const char *file, const ll_tensor_field **out)
{
    const ll_tensor_field *f = ll_tensor_find(t, name);
    size_t i;
    if (!f)
        return ll_fail(LL_ERROR_FORMAT, "ll_bsdf_open: %s: field \"%s\" is missing", file, name);
    if (f->dtype == LL_TENSOR_F16 && !half)
        return ll_fail(LL_ERROR_FORMAT,
                       "ll_bsdf_open: %s: field \"%s\" is float16, which only the grids of a "
                       "textured file's bases (vndf, luminance, rgb, spectra) and of a "
                       "transmissive file's sets (vndf, luminance, rgb) may be; the format's "
                       "fields are float32",
                       file, name);
    if ((f->dtype != LL_TENSOR_F32 && f->dtype != LL_TENSOR_F16) || f->rank != rank)
        return ll_fail(LL_ERROR_FORMAT,
                       "ll_bsdf_open: %s: field \"%s\" must be float32 of rank %zu "
                       "(dtype code %d, rank %zu)",
                       file, name, rank, f->dtype, f->rank);
    for (i = 0; i < rank; ++i)
        if (f->shape[i] == 0)
            return ll_fail(LL_ERROR_FORMAT, "ll_bsdf_open: %s: field \"%s\" has extent 0",
                           file, name);
    for (i = 0; i < f->count; ++i) {
        float v = ll_tensor_value(f, i);
        if (!(v >= 0.0f) || !((double)v <= LL_MEASURED_MAX_VALUE))
            return ll_fail(LL_ERROR_FORMAT,
                           "ll_bsdf_open: %s: field \"%s\": element %zu = %g is not a finite "
                           "value in [0, 2^100]",
                           file, name, i, (double)v);
    }
    *out = f;
    return LL_OK;
}

static ll_status require(const ll_tensor_file *t, const char *name, size_t rank,
                         const char *file, const ll_tensor_field **out)
{
    return require_as(t, name, rank, 0, file, out);
}

/* A parameter list: strictly ascending. */
static ll_status read_list(const ll_tensor_field *f, const char *file, double lo, double hi,
                           double **out)
{
    size_t i;
    double *v = ll_alloc_array(f->count, sizeof(double));
    if (!v)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_bsdf_open: %s: out of memory", file);
    for (i = 0; i < f->count; ++i) {
        v[i] = ll_tensor_f32(f, i);
        if (!(v[i] >= lo && v[i] <= hi) || (i > 0 && !(v[i] > v[i - 1]))) {
            double bad = v[i];
            ll_free(v);
            return ll_fail(LL_ERROR_FORMAT,
                           "ll_bsdf_open: %s: field \"%s\": element %zu = %g must lie in "
                           "[%g, %g], above the one before",
                           file, f->name, i, bad, lo, hi);
        }
    }
    *out = v;
    return LL_OK;
}

static ll_status shape_error(const char *file, const char *name, const char *what)
{
    return ll_fail(LL_ERROR_FORMAT, "ll_bsdf_open: %s: field \"%s\": %s", file, name, what);
}

/* The warp of field f (its last two axes), with the prefix's parameters. */
static ll_status build(ll_warp2d *wp, const ll_tensor_field *f, size_t n_params,
                      const size_t *sizes, const double *const *params, int sampling,
                      const char *file)
{
    ll_status s = ll_warp2d_init(wp, f->shape[f->rank - 1], f->shape[f->rank - 2], n_params,
                                 sizes, params, get_field, f, sampling);
    if (s == LL_ERROR_FORMAT)
        return ll_fail(s, "ll_bsdf_open: %s: field \"%s\": %s", file, f->name,
                       ll_last_error_message());
    return s;
}

/* The RGB warp of a spectral file, from its converted values (the
 * field f names it in messages). */
static ll_status build_rgb(ll_warp2d *wp, const ll_tensor_field *f, const double *rgb,
                           const size_t *sizes, const double *const *params, const char *file)
{
    ll_status s = ll_warp2d_init(wp, f->shape[4], f->shape[3], 3, sizes, params, get_double,
                                 rgb, 0);
    if (s == LL_ERROR_FORMAT)
        return ll_fail(s, "ll_bsdf_open: %s: field \"%s\": %s", file, f->name,
                       ll_last_error_message());
    return s;
}

/* The metadata the handle reports: our own field, else the description. */
ll_status ll_measured_copy_metadata(ll_bsdf *b, const ll_tensor_file *t, const char *file)
{
    const ll_tensor_field *f = ll_tensor_find(t, "layerlab_metadata");
    if (!f)
        f = ll_tensor_find(t, "description");
    if (f && (f->dtype != LL_TENSOR_U8 || f->rank != 1))
        return ll_fail(LL_ERROR_FORMAT, "ll_bsdf_open: %s: field \"%s\" must be uint8 text",
                       file, f->name);
    b->metadata_size = f ? f->count : 0;
    b->metadata = ll_malloc(b->metadata_size + 1);
    if (!b->metadata)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_bsdf_open: %s: out of memory", file);
    if (f)
        memcpy(b->metadata, f->data, f->count);
    b->metadata[b->metadata_size] = '\0';
    return LL_OK;
}

/* "wavelengths" (read_list checked them: positive, strictly increasing)
 * and "spectra" [n_pi, n_ti, n_l, N, N] into linear sRGB [n_pi, n_ti, 3,
 * N, N]; a component below 0 (a spectrum outside the sRGB gamut) is
 * clipped to 0, as the format's values are. */
static ll_status spectra_to_rgb(const ll_tensor_field *spectra, const double *lambda,
                                const char *file, double **out)
{
    size_t n_l = spectra->shape[2], plane = spectra->shape[3] * spectra->shape[4];
    size_t slices = spectra->shape[0] * spectra->shape[1], count, t, l, q;
    double (*w)[3];
    double *rgb;
    int c;
    if (!ll_size_mul(slices, plane, &count) || !ll_size_mul(count, 3, &count))
        return ll_fail(LL_ERROR_FORMAT, "ll_bsdf_open: %s: field \"spectra\": too large", file);
    w = ll_alloc_array(n_l, sizeof *w);
    rgb = ll_calloc_array(count, sizeof *rgb);
    if (!w || !rgb) {
        ll_free(w);
        ll_free(rgb);
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_bsdf_open: %s: out of memory", file);
    }
    if (!ll_spectral_rgb_weights(lambda, n_l, w)) {
        ll_free(w);
        ll_free(rgb);
        return ll_fail(LL_ERROR_FORMAT,
                       "ll_bsdf_open: %s: field \"wavelengths\": %g..%g nm see no light of "
                       "the CIE 1931 observer (%g..%g nm): the spectra have no colour",
                       file, lambda[0], lambda[n_l - 1], LL_CIE1931_FIRST_NM,
                       LL_CIE1931_LAST_NM);
    }
    for (t = 0; t < slices; ++t)
        for (l = 0; l < n_l; ++l) {
            size_t from = (t * n_l + l) * plane;
            for (q = 0; q < plane; ++q) {
                double v = (double)ll_tensor_value(spectra, from + q);
                for (c = 0; c < 3; ++c)
                    rgb[(t * 3 + (size_t)c) * plane + q] += w[l][c] * v;
            }
        }
    for (q = 0; q < count; ++q)
        if (!(rgb[q] > 0.0))
            rgb[q] = 0.0;
    ll_free(w);
    *out = rgb;
    return LL_OK;
}

/* What every set of a file shares: the incident directions, the
 * wavelengths of a spectral file, the jacobian rule. */
typedef struct shared {
    const char *file;
    int spectral, jacobian, extended;
    int half;                /* the grids may be float16 (a textured or
                                an extended set)                      */
    size_t n_ti, n_pi;
    const ll_tensor_field *lam;
    double *theta_v, *phi_v, *lambda_v;
} shared;

static int warp_eta_ok(double e)
{
    return e == 0.0 || (e >= 1e-3 && e <= 1e3 && e != 1.0);
}

#define NAME_CAP (LL_TENSOR_MAX_NAME + 1)
/* A reflected set's "fresnel_floor" at most: beyond it (F + q) / (1 + q)
 * (q = k D(0) / D(m) >= k at the peak of D, tables_refract.h) is 1 to float
 * precision, and the field would only hide f's own values. */
#define FRESNEL_FLOOR_MAX 1000.0

/* a + b into name, or 0 if the result is longer than a field name may be
 * (a textured file's basis prefix comes from the file's own counts). */
static int join_name(char name[NAME_CAP], const char *a, const char *b)
{
    size_t la = strlen(a), lb = strlen(b);
    if (la + lb > LL_TENSOR_MAX_NAME)
        return 0;
    memcpy(name, a, la);
    memcpy(name + la, b, lb + 1);
    return 1;
}

static ll_status name_error(const char *file, const char *a, const char *b)
{
    return ll_fail(LL_ERROR_FORMAT, "ll_bsdf_open: %s: field name \"%s%s\" is too long", file,
                   a, b);
}

/* require() of the field a + b. */
static ll_status require_named(const ll_tensor_file *t, const char *a, const char *b,
                               size_t rank, const char *file, const ll_tensor_field **out)
{
    char name[NAME_CAP];
    if (!join_name(name, a, b))
        return name_error(file, a, b);
    return require(t, name, rank, file, out);
}

static const ll_tensor_field *find_named(const ll_tensor_file *t, const char *a, const char *b)
{
    char name[NAME_CAP];
    return join_name(name, a, b) ? ll_tensor_find(t, name) : NULL;
}

/* The fields of one set (prefix + "ndf", ...): checked completely, then,
 * if m is not NULL, the warps built into m. An extended file's set also
 * has its "albedo" over the incident elevations. */
static ll_status read_set(const ll_tensor_file *t, const char *base, const char *lobe,
                          const shared *sh, ll_measured *m)
{
    char prefix[NAME_CAP];
    char nn[NAME_CAP], ns[NAME_CAP], nv[NAME_CAP], nl[NAME_CAP], nr[NAME_CAP], na[NAME_CAP];
    char ne[NAME_CAP], nf[NAME_CAP], nt[NAME_CAP], nk[NAME_CAP];
    /* NULL until require sets them: at -O3 the compiler cannot see that
     * every path that reads them went through require's LL_OK. */
    const ll_tensor_field *ndf = NULL, *sigma = NULL, *vndf = NULL, *lum = NULL, *rgb = NULL;
    const ll_tensor_field *alb = NULL, *warp = NULL, *fresnel = NULL, *trans = NULL;
    const ll_tensor_field *floor_k = NULL;
    int transmit = strncmp(lobe, "transmit_", 9) == 0;
    const char *file = sh->file;
    double channels[3] = { 0.0, 1.0, 2.0 }, *converted = NULL;
    size_t n, n_ti = sh->n_ti, n_pi = sh->n_pi;
    ll_status s;
    if (!join_name(prefix, base, lobe))
        return name_error(sh->file, base, lobe);
    if (!join_name(nn, prefix, "ndf") || !join_name(ns, prefix, "sigma") ||
        !join_name(nv, prefix, "vndf") || !join_name(nl, prefix, "luminance") ||
        !join_name(nr, prefix, sh->spectral ? "spectra" : "rgb") ||
        !join_name(na, prefix, "albedo") || !join_name(ne, prefix, "warp_eta") ||
        !join_name(nf, prefix, "fresnel_eta") || !join_name(nt, prefix, "transmittance_eta") ||
        !join_name(nk, prefix, "fresnel_floor"))
        return name_error(sh->file, prefix, "luminance");
    if ((s = require(t, nn, 2, file, &ndf)) != LL_OK ||
        (s = require(t, ns, 2, file, &sigma)) != LL_OK ||
        (s = require_as(t, nv, 4, sh->half, file, &vndf)) != LL_OK ||
        (s = require_as(t, nl, 4, sh->half, file, &lum)) != LL_OK ||
        (s = require_as(t, nr, 5, sh->half, file, &rgb)) != LL_OK ||
        (sh->extended && (s = require(t, na, 1, file, &alb)) != LL_OK) ||
        (sh->extended && transmit && (s = require(t, ne, 1, file, &warp)) != LL_OK) ||
        (sh->extended && !transmit && ll_tensor_find(t, nf) &&
         (s = require(t, nf, 1, file, &fresnel)) != LL_OK) ||
        (sh->extended && transmit && ll_tensor_find(t, nt) &&
         (s = require(t, nt, 1, file, &trans)) != LL_OK) ||
        (sh->extended && !transmit && ll_tensor_find(t, nk) &&
         (s = require(t, nk, 1, file, &floor_k)) != LL_OK))
        return s;
    /* The refraction warp's relative index, or 0: the z-flipped
     * direction's (tables_lobes.c); 1 would have no refraction half
     * vector. require() has checked it finite and >= 0. */
    if (warp && (warp->count != 1 || !warp_eta_ok((double)ll_tensor_f32(warp, 0))))
        return shape_error(file, ne, "must be one value: 0 (the warp of the z-flipped "
                                     "direction) or a relative index in [0.001, 1000] other "
                                     "than 1");
    /* A reflected set's values over the Fresnel reflectance of that
     * relative index (optional: without it the values are f's own). */
    if (fresnel && (fresnel->count != 1 || !warp_eta_ok((double)ll_tensor_f32(fresnel, 0)) ||
                    ll_tensor_f32(fresnel, 0) == 0.0f))
        return shape_error(file, nf, "must be one value: a relative index in [0.001, 1000] "
                                     "other than 1");
    /* Its floor k (optional: values over (F + q) / (1 + q), q = k D(0) /
     * D(m), tables_refract.h), only with
     * fresnel_eta; require() has checked it finite and >= 0. */
    if (floor_k && (!fresnel || floor_k->count != 1 ||
                    !((double)ll_tensor_f32(floor_k, 0) <= FRESNEL_FLOOR_MAX)))
        return shape_error(file, nk, "must be one value in [0, 1000], and only in a set with "
                                     "fresnel_eta");
    /* A refracted set's values over its refraction's transmittance
     * (optional: without it the values are f's own); the refraction is
     * the set's warp, so the index is warp_eta's. */
    if (trans && (trans->count != 1 || warp->count != 1 ||
                  ll_tensor_f32(trans, 0) != ll_tensor_f32(warp, 0) ||
                  ll_tensor_f32(trans, 0) == 0.0f))
        return shape_error(file, nt, "must be one value: the set's warp_eta, a refraction's "
                                     "relative index (not 0)");
    if (ndf->shape[0] < 2 || ndf->shape[1] < 2)
        return shape_error(file, nn, "each extent must be >= 2");
    if (sigma->shape[0] < 2 || sigma->shape[1] < 2)
        return shape_error(file, ns, "each extent must be >= 2");
    if (vndf->shape[0] != n_pi || vndf->shape[1] != n_ti || vndf->shape[2] < 2 ||
        vndf->shape[3] < 2)
        return shape_error(file, nv, "shape must be [phi_i, theta_i, >= 2, >= 2]");
    n = lum->shape[3];
    if (lum->shape[0] != n_pi || lum->shape[1] != n_ti || lum->shape[2] != n || n < 2)
        return shape_error(file, nl, "shape must be [phi_i, theta_i, N, N], N >= 2");
    if (rgb->shape[0] != n_pi || rgb->shape[1] != n_ti ||
        rgb->shape[2] != (sh->spectral ? sh->lam->count : 3) || rgb->shape[3] != n ||
        rgb->shape[4] != n)
        return shape_error(file, nr,
                           sh->spectral ? "shape must be [phi_i, theta_i, n, N, N] with the n "
                                          "of \"wavelengths\" and the N of the luminance"
                                        : "shape must be [phi_i, theta_i, 3, N, N] with the N "
                                          "of the luminance");
    if (alb && alb->count != n_ti)
        return shape_error(file, na, "must have one value per element of \"theta_i\"");
    for (n = 0; n < sigma->count; ++n)
        if (!(ll_tensor_f32(sigma, n) > 0.0f))
            return ll_fail(LL_ERROR_FORMAT,
                           "ll_bsdf_open: %s: field \"%s\": element %zu is 0 (a projected "
                           "area is positive)",
                           file, ns, n);
    if (!m)
        return LL_OK;
    if (sh->spectral && (s = spectra_to_rgb(rgb, sh->lambda_v, file, &converted)) != LL_OK)
        return s;
    m->jacobian = sh->jacobian;
    {
        const double *params[3] = { sh->phi_v, sh->theta_v, channels };
        size_t sizes[3] = { n_pi, n_ti, 3 };
        if ((s = build(&m->ndf, ndf, 0, NULL, NULL, 0, file)) != LL_OK ||
            (s = build(&m->sigma, sigma, 0, NULL, NULL, 0, file)) != LL_OK ||
            (s = build(&m->vndf, vndf, 2, sizes, params, 1, file)) != LL_OK ||
            (s = build(&m->luminance, lum, 2, sizes, params, 1, file)) != LL_OK ||
            (s = sh->spectral ? build_rgb(&m->rgb, rgb, converted, sizes, params, file)
                              : build(&m->rgb, rgb, 3, sizes, params, 0, file)) != LL_OK) {
            ll_free(converted);
            return s;
        }
    }
    ll_free(converted);
    if (alb) {
        m->weight = ll_alloc_array(n_ti, sizeof(double));
        if (!m->weight)
            return ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_bsdf_open: %s: out of memory", file);
        for (n = 0; n < n_ti; ++n)
            m->weight[n] = (double)ll_tensor_f32(alb, n);
    }
    if (warp)
        m->refract_eta = (double)ll_tensor_f32(warp, 0);
    if (fresnel)
        m->fresnel_eta = (double)ll_tensor_f32(fresnel, 0);
    if (floor_k)
        m->fresnel_floor = (double)ll_tensor_f32(floor_k, 0);
    if (trans)
        m->transmittance_eta = (double)ll_tensor_f32(trans, 0);
    return LL_OK;
}

/* An extended file's "layerlab_layout": the names of what it holds,
 * separated by spaces or commas, each at most once: the lobe sets of one
 * material (present[k] for lobe k), or "textured" (*textured: a set per
 * basis, tables_textured.c). One parser for both kinds of file. */
ll_status ll_measured_read_layout(const ll_tensor_field *f, const char *file,
                                  int present[LL_MEASURED_LOBES], int *textured)
{
    size_t at = 0, k, count = 0;
    if (f->dtype != LL_TENSOR_U8 || f->rank != 1)
        return ll_fail(LL_ERROR_FORMAT,
                       "ll_bsdf_open: %s: field \"layerlab_layout\" must be uint8 text", file);
    for (k = 0; k < LL_MEASURED_LOBES; ++k)
        present[k] = 0;
    *textured = 0;
    while (at < f->count) {
        size_t len = 0;
        int found = -1, *seen;
        while (at < f->count && (f->data[at] == ' ' || f->data[at] == ','))
            ++at;
        while (at + len < f->count && f->data[at + len] != ' ' && f->data[at + len] != ',')
            ++len;
        if (len == 0)
            break;
        for (k = 0; k < LL_MEASURED_LOBES; ++k) {
            const char *p = ll_measured_lobe_prefix((int)k);
            if (strlen(p) == len + 1 && memcmp(p, f->data + at, len) == 0)
                found = (int)k;
        }
        if (found < 0 && !(len == 8 && memcmp(f->data + at, "textured", 8) == 0))
            return ll_fail(LL_ERROR_UNSUPPORTED,
                           "ll_bsdf_open: %s: field \"layerlab_layout\": set \"%.*s\" is not "
                           "read by this version (reflect_top, reflect_bottom, transmit_top, "
                           "transmit_bottom, textured)",
                           file, (int)(len > 64 ? 64 : len), (const char *)f->data + at);
        seen = found < 0 ? textured : &present[found];
        if (*seen)
            return ll_fail(LL_ERROR_FORMAT,
                           "ll_bsdf_open: %s: field \"layerlab_layout\": set \"%.*s\" named "
                           "twice",
                           file, (int)len, (const char *)f->data + at);
        *seen = 1;
        ++count;
        at += len;
    }
    if (count == 0)
        return ll_fail(LL_ERROR_FORMAT,
                       "ll_bsdf_open: %s: field \"layerlab_layout\" names no set", file);
    if (*textured && count > 1)
        return ll_fail(LL_ERROR_UNSUPPORTED,
                       "ll_bsdf_open: %s: field \"layerlab_layout\": a textured file of lobe "
                       "sets is not read by this version",
                       file);
    return LL_OK;
}

/* An extended file's "eta": one float32, the index below over above. */
static ll_status read_eta(const ll_tensor_file *t, const char *base, const char *file,
                         double *eta)
{
    const ll_tensor_field *f = find_named(t, base, "eta");
    double v;
    if (!f || f->dtype != LL_TENSOR_F32 || f->count != 1)
        return ll_fail(LL_ERROR_FORMAT,
                       "ll_bsdf_open: %s: field \"%seta\" must be one float32 (an extended "
                       "file's relative index)",
                       file, base);
    v = (double)ll_tensor_f32(f, 0);
    if (!(v >= 1e-3 && v <= 1e3))
        return ll_fail(LL_ERROR_FORMAT,
                       "ll_bsdf_open: %s: field \"%seta\" = %g must lie in [0.001, 1000]", file,
                       base, v);
    *eta = v;
    return LL_OK;
}

ll_status ll_measured_read_set(const ll_tensor_file *t, const char *base, const char *file,
                               ll_measured **out)
{
    const ll_tensor_field *theta, *phi, *jac, *layout;
    shared sh;
    int present[LL_MEASURED_LOBES] = { 1, 0, 0, 0 }, k, textured = 0;
    double eta = 1.0;
    ll_measured *m = NULL;
    ll_status s;
    memset(&sh, 0, sizeof sh);
    sh.file = file;
    /* A set under a prefix is a textured file's basis (tables_textured.c). */
    sh.half = base[0] != '\0';
    /* As Mitsuba: "wavelengths" makes the file spectral (pbrt reads only
     * such files). */
    sh.spectral = find_named(t, base, "wavelengths") != NULL;
    layout = find_named(t, base, "layerlab_layout");
    sh.extended = layout != NULL;
    /* An extended (transmissive) file is ours alone too: its writer
     * stores the grids as float16, earlier ones as float32. */
    sh.half = sh.half || sh.extended;
    /* The layout first: a file this version does not read is said so. */
    if ((layout && (s = ll_measured_read_layout(layout, file, present, &textured)) != LL_OK) ||
        (s = require_named(t, base, "theta_i", 1, file, &theta)) != LL_OK ||
        (s = require_named(t, base, "phi_i", 1, file, &phi)) != LL_OK ||
        (sh.spectral && (s = require_named(t, base, "wavelengths", 1, file, &sh.lam)) != LL_OK) ||
        (layout && (s = read_eta(t, base, file, &eta)) != LL_OK))
        goto done;
    if (textured)
        FAIL(LL_ERROR_UNSUPPORTED,
             "ll_bsdf_open: %s: field \"%slayerlab_layout\": a textured set inside a set is "
             "not read by this version",
             file, base);
    jac = find_named(t, base, "jacobian");
    if (!jac || jac->dtype != LL_TENSOR_U8 || jac->count != 1 || jac->data[0] > 1)
        FAIL(LL_ERROR_FORMAT,
             "ll_bsdf_open: %s: field \"%sjacobian\" must be one uint8 of value 0 or 1", file,
             base);
    sh.jacobian = jac->data[0];
    sh.n_ti = theta->count;
    sh.n_pi = phi->count;
    if (sh.n_pi > 2)
        FAIL(LL_ERROR_UNSUPPORTED,
             "ll_bsdf_open: %s: field \"%sphi_i\": %zu incident azimuths (an anisotropic "
             "table) are not read by this version",
             file, base, sh.n_pi);
    if (sh.spectral && sh.lam->count > LL_MEASURED_MAX_WAVELENGTHS) {
        s = shape_error(file, sh.lam->name, "more than " LL_MEASURED_MAX_WAVELENGTHS_TEXT
                                            " wavelengths");
        goto done;
    }
    /* Every set checked before anything is allocated. */
    for (k = 0; k < LL_MEASURED_LOBES; ++k)
        if (present[k] &&
            (s = read_set(t, base, sh.extended ? ll_measured_lobe_prefix(k) : "", &sh, NULL)) !=
                LL_OK)
            goto done;
    if ((s = read_list(theta, file, 0.0, LL_PI / 2 + 1e-6, &sh.theta_v)) != LL_OK ||
        (s = read_list(phi, file, -2.0 * LL_PI - 1e-6, 2.0 * LL_PI + 1e-6, &sh.phi_v)) != LL_OK ||
        (sh.spectral && (s = read_list(sh.lam, file, 1e-3, 1e6, &sh.lambda_v)) != LL_OK))
        goto done;

    m = ll_calloc(1, sizeof *m);
    if (!m)
        FAIL(LL_ERROR_OUT_OF_MEMORY, "ll_bsdf_open: %s: out of memory", file);
    m->jacobian = sh.jacobian;
    m->n_wavelengths = sh.spectral ? sh.lam->count : 0;
    m->extended = sh.extended;
    m->eta = eta;
    if (!sh.extended) {
        if ((s = read_set(t, base, "", &sh, m)) != LL_OK)
            goto done;
    } else {
        for (k = 0; k < LL_MEASURED_LOBES; ++k) {
            if (!present[k])
                continue;
            if (!(m->lobe[k] = ll_calloc(1, sizeof *m->lobe[k])))
                FAIL(LL_ERROR_OUT_OF_MEMORY, "ll_bsdf_open: %s: out of memory", file);
            if ((s = read_set(t, base, ll_measured_lobe_prefix(k), &sh, m->lobe[k])) != LL_OK)
                goto done;
            if (k == LL_LOBE_TRANSMIT_TOP)
                m->lobe[k]->side_eta = eta;
            else if (k == LL_LOBE_TRANSMIT_BOTTOM)
                m->lobe[k]->side_eta = 1.0 / eta;
        }
    }
done:
    ll_free(sh.theta_v);
    ll_free(sh.phi_v);
    ll_free(sh.lambda_v);
    if (s != LL_OK) {
        ll_measured_free(m);
        return s;
    }
    *out = m;
    return LL_OK;
}

ll_status ll_measured_open(const unsigned char *data, size_t size, const char *file,
                           ll_bsdf **out)
{
    ll_tensor_file t = { 0, NULL };
    const ll_tensor_field *layout;
    int present[LL_MEASURED_LOBES], textured = 0;
    ll_bsdf *b = NULL;
    ll_status s = ll_tensor_parse(data, size, file, &t);
    if (s != LL_OK)
        return s;
    layout = ll_tensor_find(&t, "layerlab_layout");
    if (layout && (s = ll_measured_read_layout(layout, file, present, &textured)) != LL_OK)
        goto done;
    if (textured) {
        s = ll_measured_open_textured(&t, size, file, &b);
        goto done;
    }
    b = ll_calloc(1, sizeof *b);
    if (!b)
        FAIL(LL_ERROR_OUT_OF_MEMORY, "ll_bsdf_open: %s: out of memory", file);
    b->refcount = 1;
    b->n_channels = 3;
    b->n_bases = 1;
    b->file_size = size;
    if ((s = ll_measured_read_set(&t, "", file, &b->measured)) != LL_OK)
        goto done;
    b->eta = b->measured->eta;
    s = ll_measured_copy_metadata(b, &t, file);
done:
    ll_tensor_file_free(&t);
    if (s != LL_OK) {
        ll_bsdf_free(b);
        return s;
    }
    *out = b;
    return LL_OK;
}

void ll_measured_free(ll_measured *m)
{
    int k;
    if (!m)
        return;
    ll_warp2d_free(&m->ndf);
    ll_warp2d_free(&m->sigma);
    ll_warp2d_free(&m->vndf);
    ll_warp2d_free(&m->luminance);
    ll_warp2d_free(&m->rgb);
    for (k = 0; k < LL_MEASURED_LOBES; ++k)
        ll_measured_free(m->lobe[k]);
    ll_free(m->weight);
    ll_free(m);
}
