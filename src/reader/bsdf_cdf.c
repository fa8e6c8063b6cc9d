/*
 * The CDF rows of an opened .bsdf file: what a dip means, how it is
 * stored, and the sampling density in mu_o where a row was flattened.
 *
 * A row is the running integral over mu_o of the luminance a_0's
 * Catmull-Rom spline (formats.md, "CDF"). That spline can be negative:
 * the original layerlab's writer (BSDFStorage::fromLayerGeneral) sums the
 * segment integrals as they come, so a row dips wherever a_0 overshoots
 * below 0 next to a zero. Its coated-gold file (198 nodes) dips by 3.1e-4
 * of a row's total at the grazing node after mu = 0, where a_0 = -0.0022
 * sits between 0 and 0.154; at 42 nodes rows dip by up to 6.6e-5 of their
 * total. Such a dip is real mass of the spline, not rounding, and pbrt-v3
 * renders those files. So a decreasing stretch is stored flat (the running
 * maximum), which gives the stretch no probability, and every segment that
 * flattening touched is sampled with the density of the flattened CDF
 * itself (uniform in mu_o over the segment, its mass over its width): the
 * spline of a_0 there no longer integrates to the segment's mass, and the
 * sampler and ll_bsdf_pdf must agree on one density.
 *
 * A dip is accepted only where the file's own a_0 explains it: the entry
 * must be the row's running spline integral to within what computing it
 * with float32 can change (segment_integral derives the bound). A dip no
 * float32 sum of the row's integrals produces is a broken file.
 */
#include "reader/bsdf_internal.h"

#include <float.h>
#include <math.h>

/* Dips of at most this fraction of the row's total (8 float32 ulps of the
 * total) are rounding of the last entry of a sum and are flattened without
 * consulting a_0. */
#define LL_BSDF_CDF_ROUNDING (1.0 / 1048576.0)

/* The spline integral of a_0 over segment j of row values f (stride nb),
 * as the writers compute it (formats.md, "CDF"), and its rounding
 * bound: what a float32 evaluation of that integral over float32 nodes
 * can be off by.
 *
 * The bound: the integral is w ((f0 + f1) / 2 + (d0 - d1) / 12) with
 * d0 = w (f1 - f_-1) / (x1 - x_-1) and d1 likewise; its terms have the
 * magnitude J = w ((|f0| + |f1|) / 2 + (|d0| + |d1|) / 12). Evaluating it
 * in float32 is off by a few float32 epsilons of J, and a running float32
 * sum of n terms by up to n epsilons of each term; the nodes themselves
 * are float32 roundings of the writer's double nodes (each off by eps |x|
 * / 2), which changes the width and the difference quotients by up to
 * eps |x| / w relative: near mu = +-1 segments are ~1e-4 wide, so this
 * term dominates there (1e-4 of the segment at 198 nodes). Hence
 *   E_j = eps J (n + 4 X / w),  X = the largest |x| of the four nodes.
 * On the original's files (38 to 198 file nodes, coated gold with and
 * without a medium, every entry of every row) the entries are within 0.13
 * of the summed bound of the double-precision running integral. */
static void segment_integral(const double *x, const double *f, size_t nb, size_t n, size_t j,
                             double *integral, double *bound)
{
    double f0 = f[j * nb], f1 = f[(j + 1) * nb], w = x[j + 1] - x[j], d0, d1, X, J;
    if (!(w > 0.0)) {
        *integral = 0.0;
        *bound = 0.0;
        return;
    }
    d0 = j > 0 ? w * (f1 - f[(j - 1) * nb]) / (x[j + 1] - x[j - 1]) : f1 - f0;
    d1 = j + 2 < n ? w * (f[(j + 2) * nb] - f0) / (x[j + 2] - x[j]) : f1 - f0;
    *integral = w * ((f0 + f1) * 0.5 + (d0 - d1) * (1.0 / 12.0));
    J = w * ((fabs(f0) + fabs(f1)) * 0.5 + (fabs(d0) + fabs(d1)) * (1.0 / 12.0));
    X = fabs(x[j > 0 ? j - 1 : 0]);
    X = fmax(X, fmax(fabs(x[j]), fabs(x[j + 1])));
    X = fmax(X, fabs(x[j + 2 < n ? j + 2 : n - 1]));
    *bound = (double)FLT_EPSILON * J * ((double)n + 4.0 * X / w);
}

/* Check and flatten one row (raw entries at row[o * nb], a_0 at
 * f[o * nb]); mark the flattened segments in seg (n - 1 entries, 0 or 1).
 * Returns the entry that no float32 sum explains, or n if none; then
 * *reference and *bound say why. */
static size_t settle_row(const ll_bsdf *b, double *row, const double *f, unsigned char *seg,
                         double *reference, double *bound, double *previous)
{
    size_t n = b->n_nodes, nb = b->n_bases, o, j = 0;
    double total = row[(n - 1) * nb], allowed = LL_BSDF_CDF_ROUNDING * total;
    double running = 0.0, sum = 0.0, err = 0.0;
    for (o = 0; o < n; ++o) {
        double v = row[o * nb];
        if (v < running - allowed) {
            /* The row's own integral up to entry o (summed once per row,
             * from where the last check stopped). */
            for (; j < o; ++j) {
                double integral, e;
                segment_integral(b->nodes, f, nb, n, j, &integral, &e);
                sum += integral;
                err += e;
            }
            if (!(fabs(v - sum) <= err)) {
                *reference = sum;
                *bound = err;
                *previous = running;
                return o;
            }
        }
        if (v < running) {
            /* Entry o changes: the segments on both sides of it. */
            seg[o - 1] = 1;
            if (o + 1 < n)
                seg[o] = 1;
            row[o * nb] = running;
        } else {
            running = v;
        }
    }
    return n;
}

ll_status ll_bsdf_cdf_settle(ll_bsdf *b, const char *file)
{
    size_t n = b->n_nodes, nb = b->n_bases, i, k, o, n_seg;
    unsigned char *seg;
    int any = 0;
    /* One flag per segment and incident row (any basis): n (n - 1)
     * bytes, less than the CDF's 4 n^2 bytes in the file. */
    if (!ll_size_mul(n, n - 1, &n_seg))
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_bsdf_open: %s: out of memory", file);
    seg = ll_calloc_array(n_seg, 1);
    if (!seg)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_bsdf_open: %s: out of memory (CDF)", file);
    for (i = 0; i < n; ++i)
        for (k = 0; k < nb; ++k) {
            size_t first = i * n * nb + k;
            double reference = 0.0, bound = 0.0, previous = 0.0;
            o = settle_row(b, b->cdf + first, b->a0 + first, seg + i * (n - 1), &reference,
                           &bound, &previous);
            if (o < n) {
                double v = b->cdf[first + o * nb];
                ll_free(seg);
                return ll_fail(LL_ERROR_FORMAT,
                               "ll_bsdf_open: %s: CDF row %zu (basis %zu) entry %zu = %g falls "
                               "%g below the previous %g, more than the rounding tolerance "
                               "(2^-20 of the row's total %g), and the row's own spline of "
                               "a_0 integrates to %g there: the entry is %g from it, beyond "
                               "the bound %g of a float32 running sum of the row's %zu "
                               "segment integrals; rows must be non-decreasing or dip only "
                               "where a_0's spline does",
                               file, i, k, o, v, previous - v, previous,
                               b->cdf[first + (n - 1) * nb], reference, fabs(v - reference),
                               bound, n - 1);
            }
        }
    for (k = 0; k < n_seg && !any; ++k)
        any = seg[k];
    if (!any) {
        /* Nothing flattened: sampling and pdf never look. */
        ll_free(seg);
        seg = NULL;
    }
    b->cdf_flat = seg;
    return LL_OK;
}

int ll_bsdf_cdf_flattened(const ll_bsdf *b, ptrdiff_t off_i, const double w_i[4], size_t idx)
{
    size_t n = b->n_nodes;
    int a;
    if (!b->cdf_flat || idx + 1 >= n)
        return 0;
    for (a = 0; a < 4; ++a)
        if (w_i[a] != 0.0 && b->cdf_flat[(size_t)(off_i + a) * (n - 1) + idx])
            return 1;
    return 0;
}

int ll_bsdf_cdf_flat_segment(const ll_bsdf *b, ptrdiff_t off_i, const double w_i[4],
                             double mu_o, size_t *idx)
{
    ptrdiff_t off_o;
    double w_o[4];
    size_t k;
    if (!b->cdf_flat || !ll_bsdf_weights(b, mu_o, &off_o, w_o))
        return 0;
    k = (size_t)(off_o + 1);
    /* Strictly inside: at a node the spline density of the neighbouring
     * segment is as right (and is what a sampler landing there used). */
    if (!(b->nodes[k] < mu_o && mu_o < b->nodes[k + 1]))
        return 0;
    *idx = k;
    return ll_bsdf_cdf_flattened(b, off_i, w_i, k);
}

double ll_bsdf_cdf_flat_density(const ll_bsdf *b, ptrdiff_t off_i, const double w_i[4],
                                const float *basis, size_t idx)
{
    size_t n = b->n_nodes;
    double total = ll_bsdf_row_value(b, b->cdf, off_i, w_i, n - 1, basis);
    double mass = ll_bsdf_row_value(b, b->cdf, off_i, w_i, idx + 1, basis) -
                  ll_bsdf_row_value(b, b->cdf, off_i, w_i, idx, basis);
    double width = b->nodes[idx + 1] - b->nodes[idx], density;
    if (!(total > 0.0 && mass > 0.0 && width > 0.0))
        return 0.0;
    density = mass / (width * total);
    return ll_is_finite(density) ? density : 0.0;
}
