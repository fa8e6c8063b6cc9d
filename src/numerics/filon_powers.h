/*
 * The power moments of Filon's piecewise quadratic on 5, 9 or 17 samples
 * by fixed weights (numerics only).
 */
#ifndef LL_FILON_POWERS_H
#define LL_FILON_POWERS_H

#include <stddef.h>
#include "numerics/filon.h"

/* For the piecewise quadratic q through n_samples equidistant samples g
 * over [c - half_width, c + half_width] (Filon's, filon.h), the Taylor
 * form's coefficients in u = phi - c:
 *   even[i] = (-1)^i M_2i / (2i)!,  odd[i] = (-1)^i M_(2i+1) / (2i+1)!,
 * M_k = integral q u^k du, for every power k < LL_FILON_POWERS (even[0 ..
 * 13], odd[0 .. 12]). Returns 0 (and leaves them) where
 * ll_filon_power_tabled(n_samples) is 0. */
LL_INTERNAL int ll_filon_power_sums(const double *g, size_t n_samples, double half_width,
                                    double *even, double *odd);

/* Whether the weights of n_samples samples are tabulated: 5, 9 and 17
 * (GGX's pieces, which take every fourth, second or every one of 17, and
 * the grading's pieces of 5). */
LL_INTERNAL int ll_filon_power_tabled(size_t n_samples);

#endif /* LL_FILON_POWERS_H */
