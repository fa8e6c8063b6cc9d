/* Catmull-Rom spline weights (Jakob et al. 2014, appendix; layerlab's
 * evalSplineWeights; pbrt-v3's CatmullRomWeights). */
#include "spline.h"

size_t ll_find_interval(const double *nodes, size_t size, double x)
{
    size_t first = 0, len = size;
    while (len > 0) {
        size_t half = len >> 1, middle = first + half;
        if (nodes[middle] <= x) {
            first = middle + 1;
            len -= half + 1;
        } else {
            len = half;
        }
    }
    if (first == 0)
        return 0;
    return first - 1 > size - 2 ? size - 2 : first - 1;
}

int ll_spline_weights(const double *nodes, size_t size, double x, ptrdiff_t *offset,
                      double w[4], int extrapolate)
{
    size_t idx;
    double x0, x1, width, t, t2, t3, d0, d1;

    if (size < 2 || x != x)
        return 0;
    if (!(x >= nodes[0] && x <= nodes[size - 1]) && !extrapolate)
        return 0;

    idx = ll_find_interval(nodes, size, x);
    x0 = nodes[idx];
    x1 = nodes[idx + 1];
    width = x1 - x0;
    t = (x - x0) / width;
    t2 = t * t;
    t3 = t2 * t;

    /* Hermite basis for the values at x0 and x1 ... */
    w[0] = 0.0;
    w[1] = 2 * t3 - 3 * t2 + 1;
    w[2] = -2 * t3 + 3 * t2;
    w[3] = 0.0;
    *offset = (ptrdiff_t)idx - 1;

    /* ... and for the derivatives, turned into node weights by finite
     * differences (central inside, one-sided at the ends). */
    d0 = t3 - 2 * t2 + t;
    d1 = t3 - t2;
    if (idx > 0) {
        double factor = width / (x1 - nodes[idx - 1]);
        w[2] += d0 * factor;
        w[0] -= d0 * factor;
    } else {
        w[2] += d0;
        w[1] -= d0;
    }
    if (idx + 2 < size) {
        double factor = width / (nodes[idx + 2] - x0);
        w[3] += d1 * factor;
        w[1] -= d1 * factor;
    } else {
        w[2] += d1;
        w[1] -= d1;
    }
    return 1;
}
