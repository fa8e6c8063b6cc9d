/*
 * The directional albedo of an opened .bsdf file, at the file's own
 * accuracy: the order-0 coefficient of the stored f |mu_o| (which is the
 * azimuthal mean, so 2 pi a_0 integrated over mu_o is the albedo),
 * interpolated in mu_i with the file's spline weights and integrated over
 * mu_o segment by segment with the cubic Hermite the sampler inverts
 * (bsdf_sample.c, sample_mu), so that the luminance albedo is the
 * normalisation of ll_bsdf_pdf and the mean of the sample weights.
 */
#include "reader/bsdf_internal.h"
#include "support/support.h"

#include <math.h>

/* a_0 of each stored channel (Y[, R, B]) at outgoing node o, interpolated
 * over the incident weights and weighted by the bases. */
static void node_a0(const ll_bsdf *b, ptrdiff_t off_i, const double w_i[4], size_t o,
                    const float *basis, double out[3])
{
    size_t n = b->n_nodes, nb = b->n_bases, c, k;
    int a;
    out[0] = out[1] = out[2] = 0.0;
    for (a = 0; a < 4; ++a) {
        const ll_bsdf_pair *pr;
        if (w_i[a] == 0.0)
            continue;
        pr = &b->pairs[(size_t)(off_i + a) * n + o];
        if (!pr->length)
            continue;
        for (c = 0; c < b->n_channels; ++c)
            for (k = 0; k < nb; ++k)
                if (basis[k] != 0.0f)
                    out[c] += w_i[a] * (double)basis[k] *
                              (double)b->coeffs[pr->offset + (c * nb + k) * pr->length];
    }
}

/* The integral over mu_o of each channel's a_0, split at mu_o = 0:
 * below[c] over mu_o < 0, above[c] over mu_o > 0. Each segment is the
 * sampler's cubic Hermite, whose integral over [x0, x1] is
 * (x1 - x0) ((f0 + f1) / 2 + (d0 - d1) / 12) with its derivatives scaled
 * to the segment. Allocation-free: a window of four nodes slides along. */
static void integrate(const ll_bsdf *b, ptrdiff_t off_i, const double w_i[4],
                      const float *basis, double below[3], double above[3])
{
    const double *x = b->nodes;
    size_t n = b->n_nodes, idx, c;
    double f[4][3]; /* nodes idx - 1 .. idx + 2 */
    for (c = 0; c < 3; ++c)
        below[c] = above[c] = 0.0;
    if (n < 2)
        return;
    node_a0(b, off_i, w_i, 0, basis, f[1]);
    node_a0(b, off_i, w_i, 1, basis, f[2]);
    for (idx = 0; idx + 1 < n; ++idx) {
        double width = x[idx + 1] - x[idx];
        if (idx + 2 < n)
            node_a0(b, off_i, w_i, idx + 2, basis, f[3]);
        if (width > 0.0) {
            for (c = 0; c < b->n_channels; ++c) {
                double f0 = f[1][c], f1 = f[2][c], d0, d1, part;
                d0 = idx > 0 ? width * (f1 - f[0][c]) / (x[idx + 1] - x[idx - 1]) : f1 - f0;
                d1 = idx + 2 < n ? width * (f[3][c] - f0) / (x[idx + 2] - x[idx]) : f1 - f0;
                part = width * (0.5 * (f0 + f1) + (d0 - d1) / 12.0);
                if (x[idx + 1] <= 0.0)
                    below[c] += part;
                else
                    above[c] += part;
            }
        }
        for (c = 0; c < 3; ++c) {
            f[0][c] = f[1][c];
            f[1][c] = f[2][c];
            f[2][c] = f[3][c];
        }
    }
}

ll_status ll_bsdf_albedo(const ll_bsdf *b, double mu_i, const float *basis_coeffs,
                         double rgb_reflected[3], double rgb_transmitted[3])
{
    const float *basis;
    ptrdiff_t off_i;
    double w_i[4], below[3], above[3];
    ll_status s;
    int c;
    for (c = 0; c < 3; ++c) {
        if (rgb_reflected)
            rgb_reflected[c] = 0.0;
        if (rgb_transmitted)
            rgb_transmitted[c] = 0.0;
    }
    if (!b)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_bsdf_albedo: bsdf is NULL");
    if (!ll_is_finite(mu_i))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_bsdf_albedo: mu_i = %g must be finite",
                       mu_i);
    s = ll_bsdf_check_basis(b, basis_coeffs, "ll_bsdf_albedo", &basis);
    if (s != LL_OK)
        return s;
    if (b->measured)
        return ll_fail(LL_ERROR_UNSUPPORTED,
                       "ll_bsdf_albedo: a table file (the `measured` format) has no order-0 "
                       "series to integrate; estimate its albedo from ll_bsdf_sample weights");
    mu_i = mu_i > 1.0 ? 1.0 : (mu_i < -1.0 ? -1.0 : mu_i);
    if (!ll_bsdf_weights(b, mu_i, &off_i, w_i))
        return LL_OK;
    integrate(b, off_i, w_i, basis, below, above);
    for (c = 0; c < 3; ++c) {
        below[c] *= 2.0 * LL_PI;
        above[c] *= 2.0 * LL_PI;
    }
    /* Light from above (mu_i > 0) is reflected to mu_o < 0. */
    if (rgb_reflected)
        ll_bsdf_to_rgb(b, mu_i >= 0.0 ? below : above, 1.0, rgb_reflected);
    if (rgb_transmitted)
        ll_bsdf_to_rgb(b, mu_i >= 0.0 ? above : below, 1.0, rgb_transmitted);
    return LL_OK;
}
