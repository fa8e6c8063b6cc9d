/*
 * Cosine moments of sampled functions by Filon quadrature (numerics only).
 */
#ifndef LL_FILON_H
#define LL_FILON_H

#include <stddef.h>
#include "support/support.h"

/* Filon's rule (L. N. G. Filon 1928) for b_l = integral_a^b g(phi)
 * cos(l phi) dphi, l < n_moments: g is replaced by the piecewise quadratic
 * through n_samples (odd, >= 3) equidistant samples g_k = g(a + k h'),
 * h' = (b - a) / (n_samples - 1), and each panel is integrated exactly, so
 * the rule stays exact however fast cos(l phi) oscillates (the orders with
 * l (b - a) / 2 <= 3 of a piece with many of them by the Taylor series of
 * cos(l phi) about its centre, truncated below 1e-15 of the integral of
 * |g|: the value of an order never depends on how many are asked for).
 *
 * Adds b_l to moments[l] for l < n_moments; scratch holds 7 n_moments
 * doubles. */
LL_INTERNAL void ll_filon_moments(const double *g, size_t n_samples, double a, double b,
                                  size_t n_moments, double *moments, double *scratch);

/* The same for the orders l = first .. first + n_moments - 1, added to
 * moments[l - first] (a series extended by its next orders). */
LL_INTERNAL void ll_filon_moments_from(const double *g, size_t n_samples, double a, double b,
                                       size_t first, size_t n_moments, double *moments,
                                       double *scratch);

/* The Taylor form's sums of one piece's samples (the panels summed once
 * per power of u), kept between calls of ll_filon_moments_kept for the
 * next blocks of orders of the same samples. powers = 0: none yet. */
#define LL_FILON_POWERS 27
typedef struct ll_filon_kept {
    size_t powers;
    double even[LL_FILON_POWERS / 2 + 1], odd[LL_FILON_POWERS / 2 + 1];
} ll_filon_kept;

/* ll_filon_moments_from with the sums kept in (or taken from) kept: the
 * moments are the same bit for bit as without. */
LL_INTERNAL void ll_filon_moments_kept(const double *g, size_t n_samples, double a, double b,
                                       size_t first, size_t n_moments, double *moments,
                                       double *scratch, ll_filon_kept *kept);

#endif /* LL_FILON_H */
