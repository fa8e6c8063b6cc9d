/*
 * The basis weights of a textured .bsdf file for one point of parameter
 * space (ll_bsdf_basis_coefficients; formats.md, "Weights for a point
 * of parameter space").
 *
 * A textured file stores one BSDF per point of a grid over its parameters
 * (basis index over parameter 0 fastest); a point between grid points is
 * the weighted sum of the stored BSDFs. The weights are the tensor product
 * of 1-D piecewise-linear ("hat") weights over each parameter's sample
 * positions. Linear and not Catmull-Rom (the node spline of the cosines,
 * numerics/spline.c), after measuring both (bench/basis_interp.c, numbers
 * in docs/formats.md): on a rough conductor and a dielectric textured
 * over alpha, Catmull-Rom's mean error is 25-50% lower but its maximum is
 * higher in 2 of 8 cases and, above all, its negative weights can make f
 * and the combined CDF rows negative or decreasing between samples, which
 * the sampler does not handle; linear weights, all >= 0 and summing to 1,
 * keep f a convex combination of non-negative BSDFs that the per-basis
 * CDFs sample exactly.
 * At most two weights per parameter are non-zero, so evaluation touches at
 * most 2^P bases (bsdf_eval.c skips the zero ones).
 */
#include "reader/bsdf_internal.h"

/* The hat weight of sample position j of a parameter at x (x already inside
 * [pos[0], pos[count - 1]]): 1 at pos[j], falling linearly to 0 at the
 * neighbouring positions (which the reader checked are strictly
 * increasing). */
static double hat_weight(const float *pos, size_t count, size_t j, double x)
{
    double here = pos[j];
    if (x == here)
        return 1.0;
    if (x < here)
        return j > 0 && x > (double)pos[j - 1]
                   ? (x - (double)pos[j - 1]) / (here - (double)pos[j - 1])
                   : 0.0;
    return j + 1 < count && x < (double)pos[j + 1]
               ? ((double)pos[j + 1] - x) / ((double)pos[j + 1] - here)
               : 0.0;
}

/* x clamped to the parameter's sampled range. */
static double clamp_to_range(const float *pos, size_t count, double x)
{
    if (x < (double)pos[0])
        return pos[0];
    if (x > (double)pos[count - 1])
        return pos[count - 1];
    return x;
}

ll_status ll_bsdf_basis_coefficients(const ll_bsdf *b, const double *params, float *coeffs)
{
    size_t basis, p;
    if (!b || !coeffs)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_bsdf_basis_coefficients: bsdf or coeffs is NULL");
    if (b->n_parameters == 0) {
        /* Untextured: one basis, the stored BSDF itself (params unused). */
        coeffs[0] = 1.0f;
        return LL_OK;
    }
    if (!params)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_bsdf_basis_coefficients: the file is textured (%zu parameters); "
                       "params must give their values",
                       b->n_parameters);
    for (p = 0; p < b->n_parameters; ++p)
        if (!ll_is_finite(params[p]))
            return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                           "ll_bsdf_basis_coefficients: params[%zu] = %g is not finite", p,
                           params[p]);
    /* Basis index = sum_p j_p * stride_p with parameter 0 fastest (the
     * format's order); each weight is the product of its parameters' hat
     * weights, decoded from the index. n_bases * n_parameters steps, no
     * buffer sized by the file. */
    for (basis = 0; basis < b->n_bases; ++basis) {
        size_t rest = basis;
        double w = 1.0;
        for (p = 0; p < b->n_parameters && w != 0.0; ++p) {
            size_t count = b->param_counts[p];
            const float *pos = b->param_positions + b->param_first[p];
            size_t j = rest % count;
            rest /= count;
            w *= count == 1 ? 1.0 : hat_weight(pos, count, j, clamp_to_range(pos, count, params[p]));
        }
        coeffs[basis] = (float)w;
    }
    return LL_OK;
}
