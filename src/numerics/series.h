/*
 * The modified Bessel function I_0 and the length of the cosine series of
 * exp(B cos phi) (numerics only).
 */
#ifndef LL_SERIES_H
#define LL_SERIES_H

#include <stddef.h>
#include "support/support.h"

/* I_0(x) exp(-|x|), the exponentially scaled modified Bessel function of
 * the first kind of order 0; relative error below 1e-14 for every x. */
LL_INTERNAL double ll_bessel_i0e(double x);

/* The number of terms after which the cosine series of exp(B cos phi),
 * B >= 0, has decayed below relerr times its first term: the smallest n
 * with prod_{i<n} 1 / (1 + i / B) < relerr (the original layerlab's
 * estimate of I_n(B) / I_0(B)); 1 for B = 0. */
LL_INTERNAL size_t ll_expcos_length(double B, double relerr);

#endif /* LL_SERIES_H */
