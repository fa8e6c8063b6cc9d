/* Catmull-Rom spline weights (Jakob et al. 2014, appendix; layerlab's
 * evalSplineWeights; pbrt-v3's CatmullRomWeights). */
#include "numerics/spline.h"

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
    double x0, x1, width;

    if (size < 2 || x != x)
        return 0;
    if (!(x >= nodes[0] && x <= nodes[size - 1]) && !extrapolate)
        return 0;

    idx = ll_find_interval(nodes, size, x);
    x0 = nodes[idx];
    x1 = nodes[idx + 1];
    width = x1 - x0;
    ll_spline_basis((x - x0) / width, idx > 0 ? width / (x1 - nodes[idx - 1]) : 0.0,
                    idx + 2 < size ? width / (nodes[idx + 2] - x0) : 0.0, idx > 0,
                    idx + 2 < size, w);
    *offset = (ptrdiff_t)idx - 1;
    return 1;
}
