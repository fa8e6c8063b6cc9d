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
#define SERIES_FLOOR 1e-12
#define SERIES_ABSOLUTE 1e-8

/* I_k(kappa) / I_0(kappa), k = 1 .. m - 1, in ratio[k] (ratio[0] = 1),
 * by the backward recurrence of r_k = I_k / I_{k-1} = 1 / (2k / kappa +
 * r_{k+1}) from far enough above m that the start does not matter (the
 * r_k fall like kappa / 2k there), and the products of the r_k: no Bessel
 * function itself is formed, so no overflow at large kappa. Returns how
 * many ratios are above SERIES_FLOOR (at least 1). */
static size_t bessel_ratios(double kappa, size_t m, double *ratio)
{
    size_t k, start = m + 32 + (size_t)kappa, len = 1;
    double r = 0.0, p = 1.0;
    ratio[0] = 1.0;
    if (!(kappa > 0.0) || m < 2)
        return 1;
    for (k = start; k >= m; --k)
        r = 1.0 / (2.0 * (double)k / kappa + r);
    /* r is r_m now; going down, r_k is kept in ratio[k] first. */
    for (k = m - 1; k >= 1; --k) {
        r = 1.0 / (2.0 * (double)k / kappa + r);
        ratio[k] = r;
    }
    for (k = 1; k < m; ++k) {
        p *= ratio[k];
        ratio[k] = p;
        if (p > SERIES_FLOOR)
            len = k + 1;
    }
    return len;
}

size_t ll_microfacet_compensation_series(const ll_microfacet_compensation *c, int q, size_t i,
                                         size_t j, size_t m, double *out)
{
    double value, kappa, limit, s_i, s_j, sum;
    size_t k, len;
    if (m == 0 || c->scale[q] == 0.0)
        return 0;
    value = c->scale[q] * c->u[q][i] * c->v[q][j];
    out[0] = value;
    if (!c->mu || m == 1 || !(c->spread > 0.0) || value == 0.0)
        return 1;
    s_i = sqrt(fmax(0.0, 1.0 - c->mu[i] * c->mu[i]));
    s_j = sqrt(fmax(0.0, 1.0 - c->mu[j] * c->mu[j]));
    sum = c->mu[i] + c->mu[j];
    kappa = sum > 0.0 ? c->spread * s_i * s_j / pow(sum, c->power) : 0.0;
    limit = (double)m * (double)m / 40.0;
    kappa = fmin(kappa, limit);
    len = bessel_ratios(kappa, m, out);
    out[0] = value;
    /* vM(phi) = 1 + 2 sum_k (I_k / I_0) cos(k phi). */
    for (k = 1; k < len; ++k) {
        out[k] *= 2.0 * c->peaked * value;
        if (!(out[k] > SERIES_ABSOLUTE))
            return k;
    }
    return len;
}
