/* Catmull-Rom spline weights on non-uniform nodes (numerics; no layer code). */
#ifndef LL_SPLINE_H
#define LL_SPLINE_H

#include <stddef.h>
#include "support/support.h"

/* Weights of the four nodes offset .. offset+3 whose combination
 * sum w[k] f(nodes[offset + k]) interpolates f at x with a cubic Hermite
 * spline whose derivatives are central differences (one-sided at the ends),
 * the interpolant of Jakob et al. 2014 and pbrt-v3's CatmullRomWeights.
 * nodes ascending, size >= 2. Weights of nodes outside [0, size) are 0.
 * Returns 0 (and no weights) if x is outside [nodes[0], nodes[size-1]] or
 * NaN, unless extrapolate is set (then the end interval is extended). */
LL_INTERNAL int ll_spline_weights(const double *nodes, size_t size, double x,
                                  ptrdiff_t *offset, double w[4], int extrapolate);

/* The weights for position t in [0, 1] of an interval whose derivative
 * factors are f0 = width / (x1 - x_{-1}) and f1 = width / (x2 - x0);
 * has_left / has_right say whether those outer nodes exist (else one-sided
 * differences). Shared by ll_spline_weights and the .bsdf evaluator, which
 * prepares f0 and f1 once per interval. */
static inline void ll_spline_basis(double t, double f0, double f1, int has_left,
                                   int has_right, double w[4])
{
    double t2 = t * t, t3 = t2 * t, d0 = t3 - 2 * t2 + t, d1 = t3 - t2;
    /* Hermite basis for the values at x0 and x1 ... */
    w[0] = 0.0;
    w[1] = 2 * t3 - 3 * t2 + 1;
    w[2] = -2 * t3 + 3 * t2;
    w[3] = 0.0;
    /* ... and for the derivatives, turned into node weights by finite
     * differences (central inside, one-sided at the ends). */
    if (has_left) {
        w[2] += d0 * f0;
        w[0] -= d0 * f0;
    } else {
        w[2] += d0;
        w[1] -= d0;
    }
    if (has_right) {
        w[3] += d1 * f1;
        w[1] -= d1 * f1;
    } else {
        w[2] += d1;
        w[1] -= d1;
    }
}

/* The index i of the interval [nodes[i], nodes[i+1]] holding x, clamped to
 * [0, size - 2] (binary search). */
LL_INTERNAL size_t ll_find_interval(const double *nodes, size_t size, double x);

#endif
