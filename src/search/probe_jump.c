/*
 * GGX's transmission jump at the probes (search/probe.h).
 *
 * GGX's D does not vanish for horizontal microfacets, so a dielectric's
 * transmitted f drops from a finite value to 0 where the refraction half
 * vector turns horizontal: |mu_i| = eta |mu_o|, eta the relative index
 * ahead of the light, the same line at every azimuth (docs/method.md).
 * The layer holds f per order on a Catmull-Rom spline over fixed nodes,
 * and where a probe's stencil has nodes on both sides of that line the
 * spline smears the jump over the node interval: the error there falls
 * only like 1/n, and a search comparing such values would grow n without
 * end. Such values are left out (NaN) of the comparison: the tolerance
 * covers what a spline over nodes represents, and not the smear within
 * one node interval of the jump. (At eta 1.5 the probes lie mostly clear
 * of the line: from above it is 0.33 or more in mu from the refracted
 * centre, beyond the groups' offsets; from below it lies beyond
 * |mu_o| = 1 wherever a refracted direction exists. Of the 514 probe
 * pairs, 2 straddle at 100 nodes. Nearer 1 the line comes closer: at eta
 * 1.1 and normal incidence it is 0.09 from the centre.)
 */
#include "search/probe.h"

#include "layerlab/ll_quad.h"

#include <math.h>

/* Whether the stencil's nodes (positive half, count of them) lie on both
 * sides of the line |mu_i| = eta |mu_o|: the smallest and largest
 * |mu_i| - eta |mu_o| over its node pairs have opposite signs. */
static int straddles(const double *no, size_t co, const double *ni, size_t ci, double eta)
{
    double o_lo = HUGE_VAL, o_hi = 0.0, i_lo = HUGE_VAL, i_hi = 0.0;
    size_t k;
    if (co == 0 || ci == 0)
        return 0;
    for (k = 0; k < co; ++k) {
        o_lo = fmin(o_lo, fabs(no[k]));
        o_hi = fmax(o_hi, fabs(no[k]));
    }
    for (k = 0; k < ci; ++k) {
        i_lo = fmin(i_lo, fabs(ni[k]));
        i_hi = fmax(i_hi, fabs(ni[k]));
    }
    return i_hi - eta * o_lo > 0.0 && i_lo - eta * o_hi < 0.0;
}

int ll_probe_jump_straddles(const double *half, size_t h, double eta, double mu_o, double mu_i)
{
    double no[4], wo[4], ni[4], wi[4];
    size_t co, ci;
    /* Transmission only (mu_o, mu_i of one sign): reflection has no jump. */
    if (!((mu_o > 0.0 && mu_i > 0.0) || (mu_o < 0.0 && mu_i < 0.0)))
        return 0;
    co = ll_probe_stencil(half, h, mu_o, no, wo, NULL);
    ci = ll_probe_stencil(half, h, mu_i, ni, wi, NULL);
    /* mu_i > 0 arrives from above, where the index ahead is eta. */
    return straddles(no, co, ni, ci, mu_i > 0.0 ? eta : 1.0 / eta);
}

ll_status ll_probe_mark_jump(const ll_probe_set *set, size_t n, double eta, double *values)
{
    double *rule = ll_alloc_array(n, 2 * sizeof(double));
    ll_status s = rule ? ll_quad_gauss_lobatto(n, rule, rule + n, NULL)
                       : ll_fail(LL_ERROR_OUT_OF_MEMORY,
                                 "resolution probes: out of memory for %zu nodes", n);
    if (s == LL_OK)
        ll_probe_mark_jump_nodes(set, n, rule, eta, values);
    ll_free(rule);
    return s;
}

void ll_probe_mark_jump_nodes(const ll_probe_set *set, size_t n, const double *nodes, double eta,
                              double *values)
{
    size_t h = n / 2, p, k;
    for (p = 0; p < set->n_pairs; ++p)
        if (ll_probe_jump_straddles(nodes + h, h, eta, set->pairs[p].mu_o, set->pairs[p].mu_i))
            for (k = 0; k < set->n_phi; ++k)
                values[p * set->n_phi + k] = NAN;
}
