/*
 * The reference that the microfacet tests measure an azimuthal Fourier
 * series against: the cosine coefficients of f sampled at `points`
 * (odd) azimuths k h, k < points, over [0, pi], by Simpson's rule, and the
 * largest difference of two series of the same length over every tenth of
 * those azimuths, relative to the peak. Equal lengths on both sides make the
 * difference the method's, not the truncation's.
 */
#ifndef LL_TEST_SERIES_CHECK_H
#define LL_TEST_SERIES_CHECK_H

#include <math.h>
#include <stddef.h>
#include <string.h>

/* ref_l = (2 - [l = 0]) / pi integral_0^pi f cos(l phi) dphi, l < len, with
 * the cosines by their recurrence. */
static inline void ll_test_cosine_series(const double *f, size_t points, double h, size_t len,
                                         double *ref)
{
    size_t k, l;
    memset(ref, 0, len * sizeof *ref);
    for (k = 0; k < points; ++k) {
        double w = (k == 0 || k == points - 1 ? 1.0 : k % 2 ? 4.0 : 2.0) * h / 3.0 * f[k];
        double c1 = cos((double)k * h), prev = c1, cur = 1.0;
        for (l = 0; l < len; ++l) {
            double next = 2.0 * c1 * cur - prev;
            ref[l] += w * cur;
            prev = cur;
            cur = next;
        }
    }
    for (l = 0; l < len; ++l)
        ref[l] *= (l == 0 ? 1.0 : 2.0) / 3.14159265358979323846;
}

/* max over k = 0, 10, 20, ... < points of |sum_l (ours_l - ref_l) cos(l k h)|
 * / peak. */
static inline double ll_test_series_error(const double *ours, const double *ref, size_t len,
                                          size_t points, double h, double peak)
{
    double worst = 0.0;
    size_t k, l;
    for (k = 0; k < points; k += 10) {
        double c1 = cos((double)k * h), prev = c1, cur = 1.0, diff = 0.0;
        for (l = 0; l < len; ++l) {
            double next = 2.0 * c1 * cur - prev;
            diff += (ours[l] - ref[l]) * cur;
            prev = cur;
            cur = next;
        }
        worst = fmax(worst, fabs(diff) / peak);
    }
    return worst;
}

#endif /* LL_TEST_SERIES_CHECK_H */
