/*
 * I_0 (exponentially scaled) and the series length of exp(B cos phi),
 * whose cosine coefficients are 2 I_k(B) (Abramowitz and Stegun 9.6.34).
 */
#include "numerics/series.h"

#include <math.h>

/* Below this x the power series of I_0 is summed; above it the asymptotic
 * expansion, whose smallest term there is about e^(-2x) < 1e-17. */
#define I0E_ASYMPTOTIC_FROM 20.0

double ll_bessel_i0e(double x)
{
    double ax = fabs(x), sum, term;
    int k;
    if (ax < I0E_ASYMPTOTIC_FROM) {
        /* I_0(x) = sum_k (x^2 / 4)^k / (k!)^2: positive terms, no
         * cancellation; at most ~60 terms for x < 20. */
        double q = 0.25 * ax * ax;
        sum = term = 1.0;
        for (k = 1; term > 1e-17 * sum; ++k) {
            term *= q / ((double)k * (double)k);
            sum += term;
        }
        return sum * exp(-ax);
    }
    /* I_0(x) e^-x ~ (2 pi x)^(-1/2) sum_k ((2k-1)!!)^2 / (k! (8x)^k)
     * (Abramowitz and Stegun 9.7.1), summed while the terms decrease. */
    sum = term = 1.0;
    for (k = 1; k < 64; ++k) {
        double next = term * (2.0 * k - 1.0) * (2.0 * k - 1.0) / (8.0 * k * ax);
        if (!(next < term) || next < 1e-17 * sum)
            break;
        term = next;
        sum += term;
    }
    return sum / sqrt(2.0 * LL_PI * ax);
}

size_t ll_expcos_length(double B, double relerr)
{
    double prod = 1.0, inv_b;
    size_t i;
    if (!(B > 0.0))
        return 1;
    inv_b = 1.0 / B;
    for (i = 0;; ++i) {
        prod /= 1.0 + (double)i * inv_b;
        if (prod < relerr)
            return i + 1;
    }
}
