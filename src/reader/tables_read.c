/*
 * Opening a table file of the `measured` format (docs/measured-format.md)
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
 */
#include "reader/tables_internal.h"
#include "reader/tensor.h"
#include "reader/cie.h"

#include <math.h>
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
    return (double)ll_tensor_f32(ctx, index);
}

static double get_double(const void *ctx, size_t index)
{
    return ((const double *)ctx)[index];
}

/* Field name: present, float32, of the given rank. */
static ll_status require(const ll_tensor_file *t, const char *name, size_t rank,
                         const char *file, const ll_tensor_field **out)
{
    const ll_tensor_field *f = ll_tensor_find(t, name);
    size_t i;
    if (!f)
        return ll_fail(LL_ERROR_FORMAT, "ll_bsdf_open: %s: field \"%s\" is missing", file, name);
    if (f->dtype != LL_TENSOR_F32 || f->rank != rank)
        return ll_fail(LL_ERROR_FORMAT,
                       "ll_bsdf_open: %s: field \"%s\" must be float32 of rank %zu "
                       "(dtype code %d, rank %zu)",
                       file, name, rank, f->dtype, f->rank);
    for (i = 0; i < rank; ++i)
        if (f->shape[i] == 0)
            return ll_fail(LL_ERROR_FORMAT, "ll_bsdf_open: %s: field \"%s\" has extent 0",
                           file, name);
    for (i = 0; i < f->count; ++i) {
        float v = ll_tensor_f32(f, i);
        if (!(v >= 0.0f) || !((double)v <= LL_MEASURED_MAX_VALUE))
            return ll_fail(LL_ERROR_FORMAT,
                           "ll_bsdf_open: %s: field \"%s\": element %zu = %g is not a finite "
                           "value in [0, 2^100]",
                           file, name, i, (double)v);
    }
    *out = f;
    return LL_OK;
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
                double v = (double)ll_tensor_f32(spectra, from + q);
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

/* prefix + base into buf (a field name of the container's length), or 0
 * if it does not fit. */
static int field_name(const char *prefix, const char *base, char buf[LL_TENSOR_MAX_NAME + 1])
{
    size_t a = strlen(prefix), c = strlen(base);
    if (a + c > LL_TENSOR_MAX_NAME)
        return 0;
    memcpy(buf, prefix, a);
    memcpy(buf + a, base, c + 1);
    return 1;
}

/* require() of the field prefix + base. */
static ll_status require_set(const ll_tensor_file *t, const char *prefix, const char *base,
                             size_t rank, const char *file, const ll_tensor_field **out)
{
    char name[LL_TENSOR_MAX_NAME + 1];
    if (!field_name(prefix, base, name))
        return ll_fail(LL_ERROR_FORMAT, "ll_bsdf_open: %s: field name \"%s%s\" is too long",
                       file, prefix, base);
    return require(t, name, rank, file, out);
}

static const ll_tensor_field *find_set(const ll_tensor_file *t, const char *prefix,
                                       const char *base)
{
    char name[LL_TENSOR_MAX_NAME + 1];
    return field_name(prefix, base, name) ? ll_tensor_find(t, name) : NULL;
}

ll_status ll_measured_read_set(const ll_tensor_file *t, const char *prefix, const char *file,
                               ll_measured **out)
{
    const ll_tensor_field *theta, *phi, *ndf, *sigma, *vndf, *lum, *rgb, *jac, *lam = NULL;
    double *theta_v = NULL, *phi_v = NULL, channels[3] = { 0.0, 1.0, 2.0 };
    double *lambda_v = NULL, *converted = NULL;
    int spectral;
    ll_measured *m = NULL;
    size_t n_ti, n_pi, n;
    ll_status s;
    /* As Mitsuba: "wavelengths" makes the file spectral (pbrt reads only
     * such files). */
    spectral = find_set(t, prefix, "wavelengths") != NULL;
    if ((s = require_set(t, prefix, "theta_i", 1, file, &theta)) != LL_OK ||
        (s = require_set(t, prefix, "phi_i", 1, file, &phi)) != LL_OK ||
        (s = require_set(t, prefix, "ndf", 2, file, &ndf)) != LL_OK ||
        (s = require_set(t, prefix, "sigma", 2, file, &sigma)) != LL_OK ||
        (s = require_set(t, prefix, "vndf", 4, file, &vndf)) != LL_OK ||
        (s = require_set(t, prefix, "luminance", 4, file, &lum)) != LL_OK ||
        (s = require_set(t, prefix, spectral ? "spectra" : "rgb", 5, file, &rgb)) != LL_OK ||
        (spectral && (s = require_set(t, prefix, "wavelengths", 1, file, &lam)) != LL_OK))
        goto done;
    jac = find_set(t, prefix, "jacobian");
    if (!jac || jac->dtype != LL_TENSOR_U8 || jac->count != 1 || jac->data[0] > 1)
        FAIL(LL_ERROR_FORMAT,
             "ll_bsdf_open: %s: field \"%sjacobian\" must be one uint8 of value 0 or 1", file,
             prefix);
    n_ti = theta->count;
    n_pi = phi->count;
    if (n_pi > 2)
        FAIL(LL_ERROR_UNSUPPORTED,
             "ll_bsdf_open: %s: field \"%s\": %zu incident azimuths (an anisotropic table) "
             "are not read by this version",
             file, phi->name, n_pi);
    if (ndf->shape[0] < 2 || ndf->shape[1] < 2)
        FAIL(LL_ERROR_FORMAT, "ll_bsdf_open: %s: field \"%s\": each extent must be >= 2", file,
             ndf->name);
    if (sigma->shape[0] < 2 || sigma->shape[1] < 2)
        FAIL(LL_ERROR_FORMAT, "ll_bsdf_open: %s: field \"%s\": each extent must be >= 2",
             file, sigma->name);
    if (vndf->shape[0] != n_pi || vndf->shape[1] != n_ti || vndf->shape[2] < 2 ||
        vndf->shape[3] < 2) {
        s = shape_error(file, vndf->name, "shape must be [phi_i, theta_i, >= 2, >= 2]");
        goto done;
    }
    n = lum->shape[3];
    if (lum->shape[0] != n_pi || lum->shape[1] != n_ti || lum->shape[2] != n || n < 2) {
        s = shape_error(file, lum->name, "shape must be [phi_i, theta_i, N, N], N >= 2");
        goto done;
    }
    if (spectral && lam->count > LL_MEASURED_MAX_WAVELENGTHS) {
        s = shape_error(file, lam->name, "more than " LL_MEASURED_MAX_WAVELENGTHS_TEXT
                                         " wavelengths");
        goto done;
    }
    if (rgb->shape[0] != n_pi || rgb->shape[1] != n_ti ||
        rgb->shape[2] != (spectral ? lam->count : 3) || rgb->shape[3] != n ||
        rgb->shape[4] != n) {
        s = spectral ? shape_error(file, rgb->name,
                                   "shape must be [phi_i, theta_i, n, N, N] with the n of "
                                   "\"wavelengths\" and the N of \"luminance\"")
                     : shape_error(file, rgb->name,
                                   "shape must be [phi_i, theta_i, 3, N, N] with the N of "
                                   "\"luminance\"");
        goto done;
    }
    if ((s = read_list(theta, file, 0.0, LL_PI / 2 + 1e-6, &theta_v)) != LL_OK ||
        (s = read_list(phi, file, -2.0 * LL_PI - 1e-6, 2.0 * LL_PI + 1e-6, &phi_v)) != LL_OK ||
        (spectral && (s = read_list(lam, file, 1e-3, 1e6, &lambda_v)) != LL_OK))
        goto done;
    if (spectral && (s = spectra_to_rgb(rgb, lambda_v, file, &converted)) != LL_OK)
        goto done;
    for (n = 0; n < sigma->count; ++n)
        if (!(ll_tensor_f32(sigma, n) > 0.0f))
            FAIL(LL_ERROR_FORMAT,
                 "ll_bsdf_open: %s: field \"%s\": element %zu is 0 (a projected area is "
                 "positive)",
                 file, sigma->name, n);

    m = ll_calloc(1, sizeof *m);
    if (!m)
        FAIL(LL_ERROR_OUT_OF_MEMORY, "ll_bsdf_open: %s: out of memory", file);
    m->jacobian = jac->data[0];
    m->n_wavelengths = spectral ? lam->count : 0;
    {
        const double *params[3] = { phi_v, theta_v, channels };
        size_t sizes[3] = { n_pi, n_ti, 3 };
        if ((s = build(&m->ndf, ndf, 0, NULL, NULL, 0, file)) != LL_OK ||
            (s = build(&m->sigma, sigma, 0, NULL, NULL, 0, file)) != LL_OK ||
            (s = build(&m->vndf, vndf, 2, sizes, params, 1, file)) != LL_OK ||
            (s = build(&m->luminance, lum, 2, sizes, params, 1, file)) != LL_OK ||
            (s = spectral ? build_rgb(&m->rgb, rgb, converted, sizes, params, file)
                          : build(&m->rgb, rgb, 3, sizes, params, 0, file)) != LL_OK)
            goto done;
    }
done:
    ll_free(theta_v);
    ll_free(phi_v);
    ll_free(lambda_v);
    ll_free(converted);
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
    ll_bsdf *b = NULL;
    ll_status s = ll_tensor_parse(data, size, file, &t);
    if (s != LL_OK)
        return s;
    /* An extended file (textured, ...) names its sets in this field and
     * has no plain table fields. */
    if (ll_tensor_find(&t, "layerlab_layout")) {
        s = ll_measured_open_extended(&t, size, file, &b);
        goto done;
    }
    b = ll_calloc(1, sizeof *b);
    if (!b)
        FAIL(LL_ERROR_OUT_OF_MEMORY, "ll_bsdf_open: %s: out of memory", file);
    b->refcount = 1;
    b->n_channels = 3;
    b->n_bases = 1;
    b->eta = 1.0;
    b->file_size = size;
    if ((s = ll_measured_read_set(&t, "", file, &b->measured)) != LL_OK)
        goto done;
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
    if (!m)
        return;
    ll_warp2d_free(&m->ndf);
    ll_warp2d_free(&m->sigma);
    ll_warp2d_free(&m->vndf);
    ll_warp2d_free(&m->luminance);
    ll_warp2d_free(&m->rgb);
    ll_free(m);
}
