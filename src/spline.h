/* Catmull-Rom spline weights on non-uniform nodes (numerics; no layer code). */
#ifndef LL_SPLINE_H
#define LL_SPLINE_H

#include <stddef.h>
#include "support.h"

/* Weights of the four nodes offset .. offset+3 whose combination
 * sum w[k] f(nodes[offset + k]) interpolates f at x with a cubic Hermite
 * spline whose derivatives are central differences (one-sided at the ends),
 * the interpolant of Jakob et al. 2014 and pbrt-v3's CatmullRomWeights.
 * nodes ascending, size >= 2. Weights of nodes outside [0, size) are 0.
 * Returns 0 (and no weights) if x is outside [nodes[0], nodes[size-1]] or
 * NaN, unless extrapolate is set (then the end interval is extended). */
LL_INTERNAL int ll_spline_weights(const double *nodes, size_t size, double x,
                                  ptrdiff_t *offset, double w[4], int extrapolate);

/* The index i of the interval [nodes[i], nodes[i+1]] holding x, clamped to
 * [0, size - 2] (binary search). */
LL_INTERNAL size_t ll_find_interval(const double *nodes, size_t size, double x);

#endif
