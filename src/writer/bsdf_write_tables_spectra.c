/*
 * The values of a spectral table file (bsdf_write_tables.h): the warp is
 * one for all wavelengths, so the directions of the sample nodes and their
 * jacobian factors are computed once (bsdf_write_tables.c); here each
 * wavelength's file is opened through the caller's source, evaluated at
 * those directions and released before the next, and its values go to a
 * scratch file in wavelength-major order (the order they are made in).
 * The file's order is [theta_i][wavelength][N][N], so writing reads them
 * back block by block: memory holds one block, never the whole field.
 */
#include "writer/bsdf_write_tables.h"
#include "reader/cie.h"

#include <math.h>
#include <string.h>

/* The luminance weights of the wavelengths: Y of ll_spectral_rgb_weights
 * (the luminance of the linear sRGB it gives), uniform if it sees none. */
static ll_status luminance_weights(const ll_tables_spectra *sp, double *y, const char *fn)
{
    double (*w)[3] = ll_alloc_array(sp->n_l, sizeof *w);
    size_t l;
    if (!w)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", fn);
    if (ll_spectral_rgb_weights(sp->wavelengths, sp->n_l, w)) {
        for (l = 0; l < sp->n_l; ++l)
            y[l] = 0.212671 * w[l][0] + 0.715160 * w[l][1] + 0.072169 * w[l][2];
    } else {
        for (l = 0; l < sp->n_l; ++l)
            y[l] = 1.0 / (double)sp->n_l;
    }
    ll_free(w);
    return LL_OK;
}

/* Slice t of one wavelength's values (plane floats) with its nodes
 * beyond the horizon fitted to b's albedo, as the RGB file's
 * (bsdf_write_tables_horizon.c); below is scratch of plane bytes. */
static ll_status fit_slice(const ll_tables_spectra *sp, const ll_bsdf *b, size_t t,
                           float *values, unsigned char *below)
{
    ll_tables_horizon h;
    double th = (double)sp->theta_i[t], rgb[3], target;
    size_t q, ns = (size_t)(sqrt((double)sp->plane) + 0.5);
    ll_status s;
    /* The values are the luminance of the wavelength's file (its one
     * channel), and so is the target. */
    if ((s = ll_tables_horizon_target(b, th, 0, 0, rgb)) != LL_OK)
        return s;
    target = ll_tables_luminance(rgb);
    if (!(target > 0.0))
        return LL_OK;
    for (q = 0; q < sp->plane; ++q)
        below[q] = !(sp->geom[(t * sp->plane + q) * 4 + 2] > 0.0);
    h.ndf_w = sp->ndf_w;
    h.vndf_w = sp->vndf_w;
    h.sigma = ll_tables_sigma_at(sp->sigma_w, th);
    h.param[0] = 0.0;
    h.param[1] = th;
    h.fresnel_eta = 0.0;
    h.over_f = 0u;
    return ll_tables_horizon_fit(&h, ns, below, 1, &target, &values);
}

/* One wavelength's values at every node of every slice, into block
 * (n_ti * plane floats). */
static ll_status evaluate(const ll_tables_spectra *sp, const ll_bsdf *b, float *block,
                          unsigned char *below, const char *fn, double lambda)
{
    size_t t, q;
    ll_status s;
    for (t = 0; t < sp->n_ti; ++t) {
        double th = (double)sp->theta_i[t], wi[3] = { sin(th), 0.0, cos(th) };
        for (q = 0; q < sp->plane; ++q) {
            const double *g = sp->geom + (t * sp->plane + q) * 4;
            double f[3] = { 0.0, 0.0, 0.0 }, v = 0.0;
            if (g[3] > 0.0) {
                /* Our renderer convention: wo (viewer) is the format's wi. */
                s = ll_bsdf_eval_dir(b, wi, g, LL_TRANSPORT_RADIANCE, NULL, f);
                if (s != LL_OK)
                    return ll_fail(s, "%s: the file of %g nm: %s", fn, lambda,
                                   ll_last_error_message());
                v = (0.212671 * f[0] + 0.715160 * f[1] + 0.072169 * f[2]) * g[3];
            }
            block[t * sp->plane + q] = (float)(v > 0.0 && ll_is_finite(v) ? v : 0.0);
        }
        if ((s = fit_slice(sp, b, t, block + t * sp->plane, below)) != LL_OK)
            return s;
    }
    return LL_OK;
}

ll_status ll_tables_spectra_run(ll_tables_spectra *sp, ll_tables_spectrum_fn source,
                                void *user, float *lum, ll_watch *watch, const char *fn)
{
    size_t count, l, i;
    double *y = NULL;
    float *block = NULL;
    unsigned char *below = NULL;
    ll_status s = LL_OK;
    if (!ll_size_mul(sp->n_ti, sp->plane, &count))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: the tables' size overflows", fn);
    y = ll_alloc_array(sp->n_l, sizeof *y);
    block = ll_alloc_array(count, sizeof *block);
    below = ll_alloc_array(sp->plane, 1);
    if (!y || !block || !below) {
        s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory (spectra)", fn);
        goto done;
    }
    if ((s = luminance_weights(sp, y, fn)) != LL_OK)
        goto done;
    sp->scratch = tmpfile();
    if (!sp->scratch) {
        s = ll_fail(LL_ERROR_IO, "%s: cannot create a scratch file for the spectra", fn);
        goto done;
    }
    memset(lum, 0, count * sizeof *lum);
    for (l = 0; l < sp->n_l; ++l) {
        ll_bsdf *b = NULL;
        s = source(user, l, sp->wavelengths[l], &b);
        if (s == LL_OK && !b)
            s = ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: the spectrum source gave no file for "
                        "%g nm", fn, sp->wavelengths[l]);
        if (s == LL_OK)
            s = evaluate(sp, b, block, below, fn, sp->wavelengths[l]);
        ll_bsdf_release(b);
        if (s != LL_OK)
            goto done;
        for (i = 0; i < count; ++i)
            lum[i] = (float)((double)lum[i] + y[l] * (double)block[i]);
        if (fwrite(block, sizeof *block, count, sp->scratch) != count) {
            s = ll_fail(LL_ERROR_IO, "%s: writing the spectra's scratch file failed", fn);
            goto done;
        }
        ll_watch_advance(watch, 1);
        if ((s = ll_watch_check(watch, fn)) != LL_OK)
            goto done;
    }
    if (fflush(sp->scratch) != 0)
        s = ll_fail(LL_ERROR_IO, "%s: writing the spectra's scratch file failed", fn);
done:
    ll_free(y);
    ll_free(block);
    ll_free(below);
    return s;
}

ll_status ll_tables_spectra_fill(void *ctx, size_t block, float *out)
{
    const ll_tables_spectra *sp = ctx;
    size_t t = block / sp->n_l, l = block % sp->n_l;
    /* Offsets in floats; the whole scratch file's size was checked. */
    long long at = ((long long)l * (long long)sp->n_ti + (long long)t) * (long long)sp->plane *
                   (long long)sizeof(float);
    if (fseeko(sp->scratch, (off_t)at, SEEK_SET) != 0 ||
        fread(out, sizeof *out, sp->plane, sp->scratch) != sp->plane)
        return ll_fail(LL_ERROR_IO, "reading the spectra's scratch file failed");
    return LL_OK;
}

void ll_tables_spectra_close(ll_tables_spectra *sp)
{
    if (sp->scratch)
        fclose(sp->scratch);
    sp->scratch = NULL;
}
