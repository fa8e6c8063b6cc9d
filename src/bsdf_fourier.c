/*
 * The azimuthal Fourier series of a .bsdf file (Jakob et al. 2014, sec. 7):
 * evaluating f(phi) = sum_k a_k cos(k phi) and sampling phi from it.
 *
 * A series here is the spline-weighted sum of up to 16 stored series
 * (ll_bsdf_series). Rather than adding them into a buffer as long as the
 * longest series in the file (whose length comes from the file), the cosines
 * cos(k phi) are generated in fixed-size chunks by the Chebyshev recurrence
 * cos((k+1) phi) = 2 cos(phi) cos(k phi) - cos((k-1) phi) and each stored
 * series is dotted with the chunk. Stack use is constant and the work is the
 * same as summing first: one multiply-add per stored coefficient.
 */
#include "bsdf_internal.h"

#include <math.h>

#define LL_BSDF_CHUNK 64
/* Newton-bisection on [0, pi] ends within this many steps: bisection alone
 * halves pi below 1e-12 in 42 of them. */
#define LL_BSDF_PHI_ITERATIONS 64

/* Fill c[j] = cos((k0 + j) phi) for j < count and advance the recurrence
 * state (cos of the previous and the current order). */
static void cos_chunk(double cos_phi, size_t count, double *prev, double *cur, double *c)
{
    size_t j;
    double p = *prev, q = *cur;
    for (j = 0; j < count; ++j) {
        double next = 2.0 * cos_phi * q - p;
        c[j] = q;
        p = q;
        q = next;
    }
    *prev = p;
    *cur = q;
}

static double dot(const float *a, const double *c, size_t count)
{
    size_t j;
    double sum = 0.0;
    for (j = 0; j < count; ++j)
        sum += (double)a[j] * c[j];
    return sum;
}

/* out[c] += sum over the entries and bases of weight * <series from k0, chunk>. */
static void add_chunk(const ll_bsdf_series *s, size_t n_channels, size_t k0, size_t count,
                      const double *chunk, double *out)
{
    size_t p, c, basis, nb = s->n_bases;
    for (p = 0; p < s->count; ++p) {
        size_t len = s->length[p], m;
        if (len <= k0)
            continue;
        m = len - k0 < count ? len - k0 : count;
        for (c = 0; c < n_channels; ++c)
            for (basis = 0; basis < nb; ++basis) {
                double w = s->weight[p] * (double)s->basis[basis];
                if (w != 0.0)
                    out[c] += w * dot(s->coeff[p] + (c * nb + basis) * len + k0, chunk, m);
            }
    }
}

void ll_bsdf_series_eval(const ll_bsdf_series *s, size_t n_channels, double cos_phi,
                         double out[3])
{
    double chunk[LL_BSDF_CHUNK], prev = cos_phi, cur = 1.0; /* cos(-phi), cos(0) */
    size_t k0;
    out[0] = out[1] = out[2] = 0.0;
    for (k0 = 0; k0 < s->max_length; k0 += LL_BSDF_CHUNK) {
        size_t count = s->max_length - k0 < LL_BSDF_CHUNK ? s->max_length - k0 : LL_BSDF_CHUNK;
        cos_chunk(cos_phi, count, &prev, &cur, chunk);
        add_chunk(s, n_channels, k0, count, chunk, out);
    }
}

/* The luminance series and its integral at phi in [0, pi]:
 *   f(phi) = sum_k a_k cos(k phi),
 *   F(phi) = a_0 phi + sum_{k>=1} a_k sin(k phi) / k  (= integral_0^phi f).
 * Both come from one pass: the integral uses a chunk holding phi for k = 0
 * and sin(k phi) / k beyond (sines by the same recurrence as the cosines). */
static void series_integral(const ll_bsdf_series *s, const double *recip, double phi,
                            double *F, double *f)
{
    double cosines[LL_BSDF_CHUNK], sines[LL_BSDF_CHUNK];
    double cos_phi = cos(phi), sin_phi = sin(phi);
    double c_prev = cos_phi, c_cur = 1.0, s_prev = -sin_phi, s_cur = 0.0;
    double sum_f[3] = { 0.0, 0.0, 0.0 }, sum_F[3] = { 0.0, 0.0, 0.0 };
    size_t k0, j;
    for (k0 = 0; k0 < s->max_length; k0 += LL_BSDF_CHUNK) {
        size_t count = s->max_length - k0 < LL_BSDF_CHUNK ? s->max_length - k0 : LL_BSDF_CHUNK;
        cos_chunk(cos_phi, count, &c_prev, &c_cur, cosines);
        for (j = 0; j < count; ++j) {
            double next = 2.0 * cos_phi * s_cur - s_prev;
            sines[j] = (k0 + j) ? s_cur * recip[k0 + j] : phi;
            s_prev = s_cur;
            s_cur = next;
        }
        add_chunk(s, 1, k0, count, cosines, sum_f);
        add_chunk(s, 1, k0, count, sines, sum_F);
    }
    *F = sum_F[0];
    *f = sum_f[0];
}

/* a_0 of the luminance series: its mean over phi. */
static double series_mean(const ll_bsdf_series *s)
{
    double one = 1.0, out[3] = { 0.0, 0.0, 0.0 };
    add_chunk(s, 1, 0, 1, &one, out);
    return out[0];
}

double ll_bsdf_series_sample(const ll_bsdf_series *s, const double *recip, double u,
                             double *phi_out, double *pdf_phi)
{
    double a0 = series_mean(s), lo = 0.0, hi = LL_PI, phi = 0.5 * LL_PI, F = 0.0, f = 0.0;
    double target, tolerance;
    int flip, it;

    *phi_out = 0.0;
    *pdf_phi = 0.0;
    if (!(a0 > 0.0))
        return 0.0;
    /* pbrt-v3's SampleFourier: the series is even in phi, so u picks a half
     * (u >= 1/2 the mirrored one) and is stretched back to [0, 1]. */
    flip = u >= 0.5;
    u = flip ? 2.0 - 2.0 * u : 2.0 * u;
    if (u < 0.0) u = 0.0;
    if (u > 1.0) u = 1.0;
    target = u * a0 * LL_PI;
    tolerance = 1e-12 * a0 * LL_PI;

    /* Newton-bisection for F(phi) = target: F(0) = 0 <= target <= F(pi) =
     * a0 pi, so [lo, hi] always brackets a root; a Newton step that leaves
     * the bracket (or divides by f = 0) is replaced by bisection, and the
     * iteration count is bounded, so the loop ends whatever the series. */
    for (it = 0; it < LL_BSDF_PHI_ITERATIONS; ++it) {
        double step;
        series_integral(s, recip, phi, &F, &f);
        F -= target;
        if (F > 0.0)
            hi = phi;
        else
            lo = phi;
        if (fabs(F) <= tolerance || hi - lo <= 1e-12 || it + 1 == LL_BSDF_PHI_ITERATIONS)
            break;
        step = phi - F / f;
        phi = (step > lo && step < hi) ? step : 0.5 * (lo + hi);
    }
    if (flip)
        phi = 2.0 * LL_PI - phi;
    *phi_out = phi;
    *pdf_phi = f / (2.0 * LL_PI * a0);
    return f;
}
