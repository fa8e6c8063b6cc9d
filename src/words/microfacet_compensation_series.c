/*
 * The azimuthal spread of the energy-compensation terms
 * (words/microfacet.h, ll_microfacet_compensation_series): what light a
 * rough metal scatters more than once leaves mostly toward the mirror side
 * (the random walk of tests/reference/ms_walk.c: Beckmann alpha 0.5,
 * theta_i = theta_o = 60 degrees, 5e-8 / 9e-5 / 0.355 at 0 / 90 / 180
 * degrees from the incident azimuth), so order 0's term is spread over
 * the orders by a density of mean 1, which keeps its energy.
 */
#include "words/microfacet.h"

#include <math.h>

/* The series ends where its terms fall below this share of order 0 or
 * below SERIES_ABSOLUTE (the BSDF's units: a white Lambertian is 1 / pi):
 * a smooth metal's small term would otherwise fill every order's
 * reflection columns whole. */
#define SERIES_FLOOR 1e-5
/* The concentration's ceiling (about 0.1 radians wide; the walk's peaks at
 * alpha 0.3 and above stay below it): a layer of 64 orders or more holds
 * the whole term, so the resolution search's comparison of m against 2m
 * orders does not see it change. */
#define KAPPA_MAX 100.0
#define SERIES_ABSOLUTE 1e-8

/* I_k(kappa) / I_0(kappa), k = 1 .. len - 1, in ratio[k] (ratio[0] = 1),
 * len <= m the first k where the ratio falls below cut (at least 1). The
 * length is bounded first: I_k / I_0 ~ exp(-k^2 / 2 kappa) at large
 * kappa and falls faster at small kappa, so at k = sqrt(2 (kappa + 1)
 * ln(100 / cut)) + 4 it is below cut (checked against scipy's ive for
 * kappa 1e-3 .. 4000). Then the backward recurrence r_k = I_k / I_{k-1} =
 * 1 / (2k / kappa + r_{k+1}) from far enough above that bound that the
 * start does not matter, and the products of the r_k: no Bessel function
 * itself is formed, so no overflow at large kappa, and the cost is the
 * series' length, not m. */
static size_t bessel_ratios(double kappa, size_t m, double cut, double *ratio)
{
    size_t k, start, len;
    double r = 0.0, p = 1.0, bound;
    ratio[0] = 1.0;
    if (!(kappa > 0.0) || m < 2)
        return 1;
    bound = sqrt(2.0 * (kappa + 1.0) * log(100.0 / cut)) + 4.0;
    len = bound < (double)m ? (size_t)bound : m;
    if (len < 2)
        return 1;
    start = len + 16 + (size_t)(4.0 * sqrt(kappa));
    for (k = start; k >= len; --k)
        r = 1.0 / (2.0 * (double)k / kappa + r);
    for (k = len - 1; k >= 1; --k) {
        r = 1.0 / (2.0 * (double)k / kappa + r);
        ratio[k] = r;
    }
    for (k = 1; k < len; ++k) {
        p *= ratio[k];
        ratio[k] = p;
        if (p < cut)
            return k;
    }
    return len;
}

size_t ll_microfacet_compensation_series(const ll_microfacet_compensation *c, int q, size_t i,
                                         size_t j, size_t m, double *out)
{
    double value, kappa, limit, s_i, s_j, sum, weight;
    size_t k, len;
    if (m == 0 || c->scale[q] == 0.0)
        return 0;
    value = c->scale[q] * c->u[q][i] * c->v[q][j];
    out[0] = value;
    if (!c->mu || m == 1 || !(c->spread > 0.0) || !(c->peaked > 0.0) || value == 0.0)
        return 1;
    s_i = sqrt(fmax(0.0, 1.0 - c->mu[i] * c->mu[i]));
    s_j = sqrt(fmax(0.0, 1.0 - c->mu[j] * c->mu[j]));
    sum = c->mu[i] + c->mu[j];
    kappa = sum > 0.0 ? c->spread * s_i * s_j / pow(sum, c->power) : 0.0;
    limit = fmin(KAPPA_MAX, (double)m * (double)m / 40.0);
    kappa = fmin(kappa, limit);
    weight = 2.0 * c->peaked * fabs(value);
    len = bessel_ratios(kappa, m, fmax(SERIES_FLOOR, SERIES_ABSOLUTE / weight), out);
    out[0] = value;
    /* vM(phi) = 1 + 2 sum_k (I_k / I_0) cos(k phi). */
    for (k = 1; k < len; ++k)
        out[k] *= 2.0 * c->peaked * value;
    return len;
}
