/*
 * Importance sampling an opened .bsdf file (Jakob et al. 2014, sec. 7.2),
 * mapping u to the same direction as pbrt-v3's FourierBSDF::Sample_f:
 * u[1] picks mu_o by inverting the Catmull-Rom CDF of the interpolated
 * order-0 row (SampleCatmullRom2D), u[0] picks phi from the Fourier series
 * (SampleFourier). Both inversions are Newton-bisection with a maintained
 * bracket and a bounded number of steps.
 */
#include "reader/bsdf_internal.h"
#include "reader/tables_internal.h"

#include <math.h>

/* The series is summed into a stack buffer of this many doubles (51 KiB)
 * when it fits, so that each Newton step reads one series instead of up to
 * 16: all channels when they fit (3 x 2176 orders; our longest file,
 * coated diffuse, has 2103), so that the value at the sample is read from
 * the sum too, else the luminance alone (up to 6528 orders). Longer ones
 * are evaluated chunk by chunk from the stored series, which needs no
 * buffer sized by the file at all. */
#define LL_BSDF_DENSE_VALUES 6528
/* Below this many orders the stored series are in cache after the
 * luminance sum, and one dot product per series for the value at the
 * sample costs less than summing the other channels first (measured on
 * roughgold, whose series are shorter). */
#define LL_BSDF_ALL_CHANNELS_FROM 128
#define LL_BSDF_MU_ITERATIONS 64

/* The segment of the interpolated CDF row (non-decreasing) in which it
 * reaches target: the largest index in [0, n - 2] whose value is below
 * target, or, for target 0, the last one still at 0. pbrt-v3's
 * FindInterval takes the largest index whose value is <= target, which
 * for target = the row's total (u = 1) is the last segment even where the
 * row has long stopped rising, so u = 1 landed in a segment of no mass
 * (e.g. transmission through a conductor) and gave no direction. */
static size_t find_cdf_interval(const ll_bsdf *b, ptrdiff_t off_i, const double w_i[4],
                                const float *basis, double target)
{
    size_t first = 0, len = b->n_nodes;
    while (len > 0) {
        size_t half = len >> 1, middle = first + half;
        double value = ll_bsdf_row_value(b, b->cdf, off_i, w_i, middle, basis);
        if (value < target || value <= 0.0) {
            first = middle + 1;
            len -= half + 1;
        } else {
            len = half;
        }
    }
    if (first == 0)
        return 0;
    return first - 1 > b->n_nodes - 2 ? b->n_nodes - 2 : first - 1;
}

/* The density of the segment's cubic Hermite at t. */
static double segment_density(double f0, double f1, double d0, double d1, double t)
{
    return f0 + t * (d0 + t * (-2.0 * d0 - d1 + 3.0 * (f1 - f0) + t * (d0 + d1 + 2.0 * (f0 - f1))));
}

/* Pick mu_o from u: the CDF row interpolated over the incident weights,
 * then the exact position inside the chosen spline segment by inverting the
 * segment's integral, the quartic
 *   F(t) = int_0^t p(s) ds, p the cubic Hermite of (f0, f1, d0, d1),
 * (pbrt-v3's SampleCatmullRom2D). Writes the density in mu_o, and whether
 * the point was moved off a zero of the density (below), by at least
 * first_step of the segment. */
static int sample_mu(const ll_bsdf *b, ptrdiff_t off_i, const double w_i[4], const float *basis,
                     double u, double first_step, double *mu_o, double *pdf_mu, int *moved)
{
    const double *x = b->nodes;
    size_t n = b->n_nodes, idx;
    double maximum, target, f0, f1, d0, d1, x0, x1, width, r, t, lo = 0.0, hi = 1.0;
    double F = 0.0, f = 0.0, tolerance;
    int it;

    *moved = 0;
    maximum = ll_bsdf_row_value(b, b->cdf, off_i, w_i, n - 1, basis);
    if (!(maximum > 0.0))
        return 0;
    target = u * maximum;
    idx = find_cdf_interval(b, off_i, w_i, basis, target);
    x0 = x[idx];
    x1 = x[idx + 1];
    width = x1 - x0;
    f0 = ll_bsdf_row_value(b, b->a0, off_i, w_i, idx, basis);
    f1 = ll_bsdf_row_value(b, b->a0, off_i, w_i, idx + 1, basis);
    if (!(width > 0.0)) {
        /* Only the interval between the two mu = 0 nodes has no width; a
         * consistent CDF never selects it, an inconsistent one gets x0. */
        *mu_o = x0;
        *pdf_mu = f0 / maximum;
        return 1;
    }
    if (ll_bsdf_cdf_flattened(b, off_i, w_i, idx)) {
        /* A segment where a row was flattened (bsdf_cdf.c): a_0's spline no
         * longer integrates to the segment's mass, so mu_o is uniform over
         * it, the density ll_bsdf_pdf gives there. t stays strictly inside
         * (2^-20 of the segment from its ends), where ll_bsdf_pdf finds the
         * same segment; u = 0 or 1, of probability 0, lands there too. */
        double c0 = ll_bsdf_row_value(b, b->cdf, off_i, w_i, idx, basis);
        double mass = ll_bsdf_row_value(b, b->cdf, off_i, w_i, idx + 1, basis) - c0;
        *pdf_mu = ll_bsdf_cdf_flat_density(b, off_i, w_i, basis, idx);
        if (!(*pdf_mu > 0.0 && mass > 0.0))
            return 0;
        t = (target - c0) / mass;
        if (!(t >= 0x1p-20))
            t = 0x1p-20;
        if (!(t <= 1.0 - 0x1p-20))
            t = 1.0 - 0x1p-20;
        *mu_o = x0 + width * t;
        return 1;
    }
    r = (target - ll_bsdf_row_value(b, b->cdf, off_i, w_i, idx, basis)) / width;
    d0 = idx > 0 ? width * (f1 - ll_bsdf_row_value(b, b->a0, off_i, w_i, idx - 1, basis)) /
                       (x1 - x[idx - 1])
                 : f1 - f0;
    d1 = idx + 2 < n ? width * (ll_bsdf_row_value(b, b->a0, off_i, w_i, idx + 2, basis) - f0) /
                           (x[idx + 2] - x0)
                     : f1 - f0;

    /* Start from the inverse of the linear interpolant's integral (the
     * radicand is clamped: it is negative only through rounding or a
     * negative segment). */
    if (f0 != f1) {
        double radicand = f0 * f0 + 2.0 * r * (f1 - f0);
        t = (f0 - sqrt(radicand > 0.0 ? radicand : 0.0)) / (f0 - f1);
    } else {
        t = r / f0;
    }
    tolerance = 1e-12 * (fabs(f0) + fabs(f1) + fabs(d0) + fabs(d1));
    for (it = 0; it < LL_BSDF_MU_ITERATIONS; ++it) {
        if (!(t >= lo && t <= hi))
            t = 0.5 * (lo + hi);
        /* F and its derivative p in Horner form. */
        F = t * (f0 + t * (0.5 * d0 + t * ((1.0 / 3.0) * (-2.0 * d0 - d1) + f1 - f0 +
                                          t * (0.25 * (d0 + d1) + 0.5 * (f0 - f1)))));
        f = segment_density(f0, f1, d0, d1, t);
        if (fabs(F - r) <= tolerance || hi - lo <= 1e-12 || it + 1 == LL_BSDF_MU_ITERATIONS)
            break;
        if (F - r < 0.0)
            lo = t;
        else
            hi = t;
        t -= (F - r) / f;
    }
    /* u = 0 or 1 (or a u on a flat stretch of the CDF) maps to an end of
     * the mass, where the density is 0 (to rounding): the file pins
     * f |mu_o| to 0 at mu = 0, where reflection ends. Such a u has
     * probability 0, so any direction of positive density is right for it
     * as long as the pdf returned is its own: step inside the segment, from
     * first_step of it in doubling steps, to the first point of a density
     * above rounding. */
    if (!(f > tolerance)) {
        double toward = t < 0.5 ? 1.0 : -1.0, step;
        *moved = 1;
        for (step = first_step; step <= 0.5; step *= 2.0) {
            double at = t + toward * step, density;
            if (!(at >= 0.0 && at <= 1.0))
                break;
            density = segment_density(f0, f1, d0, d1, at);
            if (density > tolerance) {
                t = at;
                f = density;
                break;
            }
        }
    }
    *mu_o = x0 + width * t;
    *pdf_mu = f / maximum;
    return 1;
}

/* The azimuth for u0 at the chosen mu_o, and the direction's pdf and sums
 * (the luminance's and the other channels' series at it); 0 if the density
 * there is not a positive number. */
static int sample_phi(const ll_bsdf *b, ptrdiff_t off_i, const double w_i[4], const float *basis,
                      double u0, double mu_o, double pdf_mu, double *phi_d, double *pdf,
                      double sums[3])
{
    double dense[LL_BSDF_DENSE_VALUES];
    ll_bsdf_series s, d;
    const ll_bsdf_series *luminance = &s, *value = &s;
    double a0;
    size_t stride;

    if (!ll_bsdf_gather_weighted(b, off_i, w_i, mu_o, basis, &s) || s.count == 0)
        return 0;
    stride = (s.max_length + 3) & ~(size_t)3;
    if (stride >= LL_BSDF_ALL_CHANNELS_FROM && b->n_channels * stride <= LL_BSDF_DENSE_VALUES) {
        ll_bsdf_series_densify_channels(&s, b->n_channels, dense, &d);
        luminance = value = &d;
    } else if (stride <= LL_BSDF_DENSE_VALUES) {
        ll_bsdf_series_densify(&s, dense, &d);
        luminance = &d;
    }
    if (!ll_bsdf_series_sample(luminance, b->recip, u0, phi_d))
        return 0;
    /* The value and density at the sampled phi from the series itself (not
     * the Newton iterate's last evaluation), so that they equal what eval
     * and pdf compute for the returned direction: pdf_phi = f / (2 pi a_0)
     * (pbrt-v3's SampleFourier). */
    ll_bsdf_series_eval(value, b->n_channels, cos(*phi_d), sums);
    a0 = ll_bsdf_series_mean(luminance);
    *pdf = pdf_mu * sums[0] / (2.0 * LL_PI * a0);
    /* No direction where the density is not a positive number or where
     * the weight f |mu_o| / pdf would overflow (a density that underflows
     * next to a non-zero value: a file that cancels to nothing there). */
    return *pdf > 0.0 && ll_is_finite(*pdf) && ll_is_finite(sums[0] / *pdf) &&
           ll_is_finite(sums[1] / *pdf) && ll_is_finite(sums[2] / *pdf);
}

int ll_bsdf_sample_core(const ll_bsdf *b, double mu_i, const double u[2], const float *basis,
                        double *mu_o, double *phi_d, double *pdf, double sums[3])
{
    ptrdiff_t off_i;
    double w_i[4], pdf_mu = 0.0, first_step;
    int moved;

    if (b->measured)
        return ll_measured_sample_core(b, mu_i, u, basis, mu_o, phi_d, pdf, sums);
    *mu_o = 0.0;
    *phi_d = 0.0;
    *pdf = 0.0;
    sums[0] = sums[1] = sums[2] = 0.0;
    if (!ll_bsdf_weights(b, mu_i, &off_i, w_i))
        return 0;
    /* A point moved off a zero of the density (sample_mu) is so close to
     * it that the series there may round to nothing: then it moves further
     * in, up to 1/16 of the segment. */
    for (first_step = 0x1p-20; first_step <= 0x1p-4; first_step *= 16.0) {
        if (!sample_mu(b, off_i, w_i, basis, u[1], first_step, mu_o, &pdf_mu, &moved))
            break;
        if (sample_phi(b, off_i, w_i, basis, u[0], *mu_o, pdf_mu, phi_d, pdf, sums))
            return 1;
        if (!moved)
            break;
    }
    *mu_o = 0.0;
    *phi_d = 0.0;
    *pdf = 0.0;
    sums[0] = sums[1] = sums[2] = 0.0;
    return 0;
}

ll_status ll_bsdf_sample(const ll_bsdf *b, double mu_i, const double u[2],
                         const float *basis_coeffs, double *mu_o, double *phi_d, double *pdf,
                         double f_rgb[3])
{
    const float *basis;
    double sums[3];
    ll_status st;
    if (!b || !u || !mu_o || !phi_d || !pdf || !f_rgb)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_bsdf_sample: a required pointer is NULL");
    *mu_o = *phi_d = *pdf = 0.0;
    f_rgb[0] = f_rgb[1] = f_rgb[2] = 0.0;
    if (!ll_is_finite(mu_i) || !(u[0] >= 0.0 && u[0] <= 1.0) || !(u[1] >= 0.0 && u[1] <= 1.0))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_bsdf_sample: mu_i = %g must be finite and u = (%g, %g) in [0, 1]",
                       mu_i, u[0], u[1]);
    st = ll_bsdf_check_basis(b, basis_coeffs, "ll_bsdf_sample", &basis);
    if (st != LL_OK)
        return st;
    if (mu_i > 1.0) mu_i = 1.0;
    if (mu_i < -1.0) mu_i = -1.0;
    /* The stored sums are f |mu_o|: f is them over |mu_o|, as ll_bsdf_eval. */
    if (ll_bsdf_sample_core(b, mu_i, u, basis, mu_o, phi_d, pdf, sums))
        ll_bsdf_to_rgb(b, sums, ll_bsdf_cosine_scale(*mu_o), f_rgb);
    return LL_OK;
}
