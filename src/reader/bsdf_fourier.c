/*
 * The azimuthal Fourier series of a .bsdf file (Jakob et al. 2014, sec. 7):
 * evaluating f(phi) = sum_k a_k cos(k phi) and sampling phi from it.
 *
 * A series here is the spline-weighted sum of up to 16 stored series
 * (ll_bsdf_series). Rather than adding them into a buffer as long as the
 * longest series in the file (a length that comes from the file), orders are
 * processed in fixed-size chunks: the harmonics cos(k phi) of a chunk come
 * from a Chebyshev recurrence (below) and each stored series is dotted
 * with them (bsdf_kernels.c), weighted by its spline weight. Stack use is
 * constant, the work one multiply-add per stored coefficient.
 */
#include "reader/bsdf_internal.h"

#include <math.h>

#define LL_BSDF_CHUNK 64
/* Series up to this many orders are evaluated with all their cosines in a
 * stack buffer (17 KiB; our longest file, coated diffuse, has 2103 orders);
 * longer ones chunk by chunk. */
#define LL_BSDF_WHOLE_ORDERS 2176
/* Newton-bisection on [0, pi] ends within this many steps: bisection alone
 * halves pi below 1e-12 in 42 of them. */
#define LL_BSDF_PHI_ITERATIONS 64

void ll_bsdf_harmonics_start(ll_harmonics *h, double cos_phi, double sin_phi, int sine)
{
    /* x_1 .. x_4 by the three-term recurrence; cos is even and sin odd,
     * so x_{-j} = +-x_j. */
    double c2 = 2.0 * cos_phi, x1 = sine ? sin_phi : cos_phi, x0 = sine ? 0.0 : 1.0;
    double x2 = c2 * x1 - x0, x3 = c2 * x2 - x1, x4 = c2 * x3 - x2, sign = sine ? -1.0 : 1.0;
    double cos2 = c2 * cos_phi - 1.0;
    h->cur[0] = x0;
    h->cur[1] = x1;
    h->cur[2] = x2;
    h->cur[3] = x3;
    h->prev[0] = sign * x4;
    h->prev[1] = sign * x3;
    h->prev[2] = sign * x2;
    h->prev[3] = sign * x1;
    h->twice_cos4 = 2.0 * (2.0 * cos2 * cos2 - 1.0);
}

/* The chunk length rounded up to the recurrence's group of four (the
 * chunk buffers have room: LL_BSDF_CHUNK is a multiple of 4). */
static size_t group_of_four(size_t count) { return (count + 3) & ~(size_t)3; }

void ll_bsdf_series_eval(const ll_bsdf_series *s, size_t n_channels, double cos_phi,
                         double out[3])
{
    double cosines[LL_BSDF_WHOLE_ORDERS];
    int vector = ll_bsdf_kernels_vector();
    ll_harmonics h;
    size_t k0;
    out[0] = out[1] = out[2] = 0.0;
    ll_bsdf_harmonics_start(&h, cos_phi, 0.0, 0); /* the sine is not needed for cosines */
    if (s->dense && n_channels <= s->dense_channels &&
        s->dense_stride <= LL_BSDF_WHOLE_ORDERS) {
        /* Summed already (sampling): one dot product per channel. */
        size_t c;
        ll_bsdf_harmonics_next(vector, &h, s->dense_stride, cosines);
        for (c = 0; c < n_channels; ++c)
            out[c] = ll_bsdf_dot_dense(vector, s->dense + c * s->dense_stride, cosines,
                                       s->dense_stride);
        return;
    }
    if (group_of_four(s->max_length) <= LL_BSDF_WHOLE_ORDERS) {
        /* All cosines first, then each stored series in one pass: each
         * series is then one sequential stream (its channels are adjacent),
         * which the hardware prefetcher follows, where a chunk at a time
         * would interleave 16 x 3 streams that it cannot all track. On a
         * long series (coated diffuse, 2103 orders) the coefficients come
         * from memory, so this is what the call's time is. */
        ll_bsdf_prefetch_series(s, n_channels);
        ll_bsdf_harmonics_next(vector, &h, group_of_four(s->max_length), cosines);
        ll_bsdf_dot_chunk(vector, s, n_channels, 0, s->max_length, cosines, out);
        return;
    }
    for (k0 = 0; k0 < s->max_length; k0 += LL_BSDF_CHUNK) {
        size_t count = s->max_length - k0 < LL_BSDF_CHUNK ? s->max_length - k0 : LL_BSDF_CHUNK;
        ll_bsdf_harmonics_next(vector, &h, group_of_four(count), cosines);
        ll_bsdf_dot_chunk(vector, s, n_channels, k0, count, cosines, out);
    }
}

/* Coefficient k of the luminance series. */
static double series_coefficient(const ll_bsdf_series *s, size_t k)
{
    size_t p, q, basis;
    double sum = 0.0;
    if (k >= s->max_length)
        return 0.0;
    if (s->dense)
        return s->dense[k];
    for (p = 0; p < s->count; ++p)
        if (k < s->length[p])
            for (q = 0; q < s->n_active; ++q) {
                basis = ll_bsdf_active_basis(s, q);
                sum += s->weight[p] * (double)s->basis[basis] *
                       (double)s->coeff[p][basis * s->length[p] + k];
            }
    return sum;
}

double ll_bsdf_series_mean(const ll_bsdf_series *s) { return series_coefficient(s, 0); }

void ll_bsdf_series_densify(const ll_bsdf_series *s, double *dense, ll_bsdf_series *d)
{
    ll_bsdf_series_densify_channels(s, 1, dense, d);
}

void ll_bsdf_series_densify_channels(const ll_bsdf_series *s, size_t n_channels, double *dense,
                                     ll_bsdf_series *d)
{
    int vector = ll_bsdf_kernels_vector();
    size_t p, j, basis, c, k, nb = s->n_bases, stride = group_of_four(s->max_length);
    ll_bsdf_prefetch_series(s, n_channels);
    for (k = 0; k < n_channels * stride; ++k)
        dense[k] = 0.0;
    /* Four series at a time (a row of the 4 x 4 stencil, whose blocks are
     * adjacent in the file) over their common length, then each one's
     * rest; channels in storage order. While a row is read, the next one's
     * block (when it is one block) is asked for at the same pace, a third
     * per channel pass, so that its memory latencies overlap this row's
     * reading (bsdf_kernels.c, dot_chunk_avx2, for the measurement). */
    p = 0;
    if (nb == 1)
        for (; p + 4 <= s->count; p += 4) {
            size_t m = s->length[p], q, next_bytes = 0;
            const char *next = NULL;
            double w[4];
            if (n_channels == 3 && s->prefetch_rows && s->max_length >= 64 &&
                p + 4 < s->count) {
                size_t last = p + 7 < s->count ? p + 7 : s->count - 1, values = 0;
                for (q = p + 4; q <= last; ++q)
                    values += 3 * (size_t)s->length[q];
                /* one block: the last series ends where the sum of the
                 * lengths says (all point into b->coeffs, so the
                 * difference is defined) */
                if (s->coeff[last] >= s->coeff[p + 4] &&
                    (size_t)(s->coeff[last] - s->coeff[p + 4]) + 3 * (size_t)s->length[last] ==
                        values) {
                    next = (const char *)(const void *)s->coeff[p + 4];
                    next_bytes = values * sizeof(float);
                }
            }
            for (q = 1; q < 4; ++q)
                if (s->length[p + q] < m)
                    m = s->length[p + q];
            for (q = 0; q < 4; ++q)
                w[q] = s->weight[p + q] * (double)s->basis[0];
            for (c = 0; c < n_channels; ++c) {
                const float *a[4];
                for (q = 0; q < 4; ++q)
                    a[q] = s->coeff[p + q] + c * s->length[p + q];
                ll_bsdf_add_scaled4(vector, dense + c * stride, a, w, m,
                                    next ? next + c * (next_bytes / 3) : NULL, next_bytes / 3);
                for (q = 0; q < 4; ++q)
                    if (s->length[p + q] > m && w[q] != 0.0)
                        ll_bsdf_add_scaled(vector, dense + c * stride + m, a[q] + m, w[q],
                                           s->length[p + q] - m);
            }
        }
    for (; p < s->count; ++p)
        for (c = 0; c < n_channels; ++c)
            for (j = 0; j < s->n_active; ++j) {
                double w;
                basis = ll_bsdf_active_basis(s, j);
                w = s->weight[p] * (double)s->basis[basis];
                if (w != 0.0)
                    ll_bsdf_add_scaled(vector, dense + c * stride,
                                       s->coeff[p] + (c * nb + basis) * s->length[p], w,
                                       s->length[p]);
            }
    *d = *s;
    d->dense = dense;
    d->dense_channels = n_channels;
    d->dense_stride = stride;
}

/* The luminance series and its integral at phi in [0, pi]:
 *   f(phi) = sum_k a_k cos(k phi),
 *   F(phi) = a_0 phi + sum_{k>=1} a_k sin(k phi) / k  (= integral_0^phi f).
 * One pass: the integral's chunk holds phi for k = 0 and sin(k phi) / k
 * beyond. */
static void series_integral(const ll_bsdf_series *s, const double *recip, int vector,
                            double phi, double cos_phi, double sin_phi, double *F, double *f)
{
    double cosines[LL_BSDF_CHUNK], sines[LL_BSDF_CHUNK];
    ll_harmonics hc, hs;
    size_t k0, j;
    *F = *f = 0.0;
    ll_bsdf_harmonics_start(&hc, cos_phi, sin_phi, 0);
    ll_bsdf_harmonics_start(&hs, cos_phi, sin_phi, 1);
    if (s->dense) {
        /* One fused pass; recip[0] = 0, so order 0 adds its a_0 phi here. */
        ll_bsdf_integral_dense(vector, s->dense, recip, group_of_four(s->max_length), &hc, &hs,
                               F, f);
        *F += s->dense[0] * phi;
        return;
    }
    for (k0 = 0; k0 < s->max_length; k0 += LL_BSDF_CHUNK) {
        size_t count = s->max_length - k0 < LL_BSDF_CHUNK ? s->max_length - k0 : LL_BSDF_CHUNK;
        ll_bsdf_harmonics_next(vector, &hc, group_of_four(count), cosines);
        ll_bsdf_harmonics_next(vector, &hs, group_of_four(count), sines);
        for (j = 0; j < count; ++j)
            sines[j] *= recip[k0 + j];
        if (k0 == 0)
            sines[0] = phi;
        {
            double out_f[3] = { 0.0, 0.0, 0.0 }, out_F[3] = { 0.0, 0.0, 0.0 };
            ll_bsdf_dot_chunk(vector, s, 1, k0, count, cosines, out_f);
            ll_bsdf_dot_chunk(vector, s, 1, k0, count, sines, out_F);
            *f += out_f[0];
            *F += out_F[0];
        }
    }
}

/* cos and sin of phi + d from those of phi, for |d| <= 1/5: Taylor series
 * of cos d and sin d to the 10th/11th order (remainder below 1e-17), then
 * the angle-addition formulas. A Newton step near convergence is small, and
 * this costs a fraction of a libm sincos. */
static void rotate(double *c, double *s, double d)
{
    double d2 = d * d;
    double cd = 1.0 - d2 / 2.0 * (1.0 - d2 / 12.0 * (1.0 - d2 / 30.0 * (1.0 - d2 / 56.0 *
                                                                      (1.0 - d2 / 90.0))));
    double sd = d * (1.0 - d2 / 6.0 * (1.0 - d2 / 20.0 * (1.0 - d2 / 42.0 * (1.0 - d2 / 72.0 *
                                                                          (1.0 - d2 / 110.0)))));
    double c1 = *c * cd - *s * sd, s1 = *s * cd + *c * sd;
    *c = c1;
    *s = s1;
}

/* A first guess for the phi with F(phi) = u F(pi): the exact inverse for
 * the wrapped Cauchy (Poisson kernel) series a_k = 2 a_0 r^k that shares
 * a_0 and a_1 with the series,
 *     F(phi) / F(pi) = (2 / pi) atan((1 + r) / (1 - r) tan(phi / 2)).
 * Lobes peaked at phi = 0 (r > 0) or pi (r < 0) start near their answer,
 * which halves the Newton steps that pbrt-v3's start at pi / 2 needs. */
static double initial_phi(const ll_bsdf_series *s, double a0, double u)
{
    double r = series_coefficient(s, 1) / (2.0 * a0), phi;
    if (!(r < 0.99))
        r = 0.99;
    if (!(r > -0.99))
        r = -0.99;
    phi = 2.0 * atan((1.0 - r) / (1.0 + r) * tan(0.5 * LL_PI * u));
    return (phi > 0.0 && phi < LL_PI) ? phi : 0.5 * LL_PI;
}

int ll_bsdf_series_sample(const ll_bsdf_series *s, const double *recip, double u,
                          double *phi_out)
{
    double a0 = ll_bsdf_series_mean(s), lo = 0.0, hi = LL_PI, phi, F, f, target, c, sn;
    int flip, it, vector = ll_bsdf_kernels_vector();

    if (!(a0 > 0.0) || !ll_is_finite(a0))
        return 0;
    /* pbrt-v3's SampleFourier: the series is even in phi, so u picks a half
     * (u >= 1/2 the mirrored one) and is stretched back to [0, 1]. */
    flip = u >= 0.5;
    u = flip ? 2.0 - 2.0 * u : 2.0 * u;
    if (u < 0.0) u = 0.0;
    if (u > 1.0) u = 1.0;
    target = u * a0 * LL_PI;
    phi = initial_phi(s, a0, u);
    c = cos(phi);
    sn = sin(phi);

    /* Newton-bisection for F(phi) = target: F(0) = 0 <= target <= F(pi) =
     * a0 pi, so [lo, hi] always brackets a root; a Newton step that leaves
     * the bracket (or divides by f = 0) is replaced by bisection, and the
     * number of steps is bounded, so the loop ends whatever the series. A
     * Newton step below 1e-9 is taken without another evaluation: the
     * convergence is quadratic, its error is far below that. */
    for (it = 0; it < LL_BSDF_PHI_ITERATIONS; ++it) {
        double step;
        series_integral(s, recip, vector, phi, c, sn, &F, &f);
        F -= target;
        if (F > 0.0)
            hi = phi;
        else
            lo = phi;
        if (F == 0.0 || hi - lo <= 1e-12)
            break;
        step = phi - F / f;
        if (step > lo && step < hi) {
            int done = fabs(step - phi) <= 1e-9;
            if (fabs(step - phi) <= 0.2) {
                rotate(&c, &sn, step - phi);
            } else {
                c = cos(step);
                sn = sin(step);
            }
            phi = step;
            if (done)
                break;
        } else {
            phi = 0.5 * (lo + hi);
            c = cos(phi);
            sn = sin(phi);
        }
    }
    if (flip)
        phi = 2.0 * LL_PI - phi;
    *phi_out = phi >= 2.0 * LL_PI ? 0.0 : phi;
    return 1;
}
