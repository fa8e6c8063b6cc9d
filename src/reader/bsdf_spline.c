/*
 * Catmull-Rom spline weights on a .bsdf file's nodes, prepared at open.
 *
 * The weights are those of ll_spline_weights (spline.c; pbrt-v3's
 * CatmullRomWeights): the cubic Hermite basis with end derivatives from
 * difference quotients, central inside the node range and one-sided at its
 * ends. Every evaluation needs them twice and sampling once more, so the
 * per-interval constants (reciprocal width, derivative factors) are
 * computed once here and the interval is found from a bucket table: no
 * division and no binary search per call. tests/test_bsdf_golden.c checks
 * the result against ll_spline_weights.
 */
#include "reader/bsdf_internal.h"
#include "numerics/spline.h"

void ll_bsdf_spline_prepare(ll_bsdf *b)
{
    const double *x = b->nodes;
    size_t n = b->n_nodes, k;
    double lo = x[0], span = x[n - 1] - x[0];
    for (k = 0; k + 1 < n; ++k) {
        ll_bsdf_interval *iv = &b->intervals[k];
        double width = x[k + 1] - x[k];
        iv->x0 = x[k];
        /* The zero-width interval between the two mu = 0 nodes is never
         * selected (the search takes the last node <= mu). */
        iv->inv_width = width > 0.0 ? 1.0 / width : 0.0;
        iv->f0 = k > 0 ? width / (x[k + 1] - x[k - 1]) : 0.0;
        iv->f1 = k + 2 < n ? width / (x[k + 2] - x[k]) : 0.0;
    }
    b->bucket_scale = (double)b->n_buckets / span;
    for (k = 0; k < b->n_buckets; ++k)
        b->bucket_first[k] =
            (uint32_t)ll_find_interval(x, n, lo + span * (double)k / (double)b->n_buckets);
}

int ll_bsdf_weights(const ll_bsdf *b, double mu, ptrdiff_t *offset, double w[4])
{
    const double *x = b->nodes;
    const ll_bsdf_interval *iv;
    size_t n = b->n_nodes, k;
    if (!(mu >= x[0] && mu <= x[n - 1]))
        return 0;
    k = (size_t)((mu - x[0]) * b->bucket_scale);
    if (k >= b->n_buckets)
        k = b->n_buckets - 1;
    k = b->bucket_first[k];
    /* The interval is the last node <= mu, at most n - 2 (ll_find_interval);
     * the bucket's start is at most a rounding away, a few nodes at most. */
    while (k > 0 && x[k] > mu)
        --k;
    while (k + 2 < n && x[k + 1] <= mu)
        ++k;
    iv = &b->intervals[k];
    ll_spline_basis((mu - iv->x0) * iv->inv_width, iv->f0, iv->f1, k > 0, k + 2 < n, w);
    *offset = (ptrdiff_t)k - 1;
    return 1;
}
