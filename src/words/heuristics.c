/*
 * The instant fits of a resolution: how many zenith-cosine nodes n and
 * Fourier orders m a Henyey-Greenstein medium or a rough interface needs,
 * by the fits of the original layerlab (parameterHeuristicHG and
 * parameterHeuristicMicrofacet, from convergence studies of Jakob et al.
 * 2014), extended to every index of refraction. They are the public
 * ll_heuristic_* and the first guess of n of the tolerance searches
 * (search/resolution.c), which measure the convergence on probe
 * directions: the fits do not see the narrow azimuthal lobes of grazing
 * pairs (eta 1.5, alpha 0.5: 37 orders gave 2.5 instead of 4.76 at
 * mu = 0.1 in the mirror direction).
 */
#include "support/support.h"
#include "words/heuristics.h"

#include "layerlab/ll_layer.h"
#include "layerlab/ll_quad.h"

#include <math.h>

/* ll_layer_create accepts at most this many nodes. */
#define MAX_NODES ((double)(UINT32_MAX / 2))

/* Round a fitted resolution up to an even node count >= 2 and an order
 * count >= 1, refusing what no layer can hold. */
static ll_status store_resolution(const char *fn, double n, double m, size_t *n_nodes,
                                  size_t *n_orders)
{
    double ni = ceil(n), mi = ceil(m);
    if (!(ni <= MAX_NODES) || !(mi <= MAX_NODES))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: the material needs %g nodes and %g orders, more than a layer can "
                       "hold (%g)",
                       fn, ni, mi, MAX_NODES);
    if (ni < 2.0)
        ni = 2.0;
    if (mi < 1.0)
        mi = 1.0;
    *n_nodes = (size_t)ni + ((size_t)ni % 2);
    *n_orders = (size_t)mi;
    return LL_OK;
}

ll_status ll_fit_henyey_greenstein(double g, size_t *n_nodes, size_t *n_orders)
{
    double a;
    if (!n_nodes || !n_orders)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_heuristic_henyey_greenstein: n_nodes or n_orders is NULL");
    if (!(g > -1.0 && g < 1.0))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_heuristic_henyey_greenstein: g = %g is outside (-1, 1)", g);
    /* Both grow like the width of the forward peak, 1 / (1 - |g|). */
    a = 1.0 / (1.0 - fabs(g));
    return store_resolution("ll_heuristic_henyey_greenstein", 8.6 * a - 0.2, 5.4 * a - 1.3,
                            n_nodes, n_orders);
}

/* The paper's fits: resolution = max(A + B ln(alpha)^4 alpha,
 * C + D alpha^-1.2) for n (columns 1-4) and m (columns 5-8), row 0 for
 * conductors (any eta), rows 1-4 for dielectrics of the given eta. */
static const double fit_table[5][9] = {
    /* eta    A_n      B_n     C_n      D_n      A_m      B_m      C_m      D_m    */
    { 0.0, 35.275,  14.136, 29.287,  1.8765,  39.814,  88.992, -98.998, 39.261 },
    { 1.1, 256.47, -73.180, 99.807,  37.383, 110.782,  57.576,  94.725, 14.001 },
    { 1.3, 100.264, 28.187, 64.425,  14.850,  45.809,  17.785,  -7.8543, 12.892 },
    { 1.5, 74.176,  27.470, 42.454,   9.6437, 31.700,  44.896, -45.016, 19.643 },
    { 1.7, 80.098,  17.016, 50.656,   7.2798, 46.549,  58.592, -73.585, 25.473 },
};

static double fit_value(const double *c, double alpha)
{
    double l = log(alpha), l2 = l * l;
    return fmax(c[0] + c[1] * l2 * l2 * alpha, c[2] + c[3] * pow(alpha, -1.2));
}

static void fit_eval(int row, double alpha, double *n, double *m)
{
    *n = fit_value(fit_table[row] + 1, alpha);
    *m = fit_value(fit_table[row] + 5, alpha);
}

/* Angular width of the refracted lobe relative to the facet tilt: a facet
 * tilted by d deflects the ray refracted from outside by d (1 - 1/eta) and
 * the one refracted from inside by d (eta - 1); the narrower one,
 * (eta - 1) / eta, sets the resolution. The fits bear this out: at
 * alpha = 0.1 the node counts of eta = 1.1, 1.3, 1.5, 1.7 (692, 300, 196,
 * 166) scale like 1 / width within 10%. */
static double refracted_width(double eta) { return (eta - 1.0) / eta; }

/* Below this eta the refracted lobe is narrower than any practical
 * resolution; the heuristic keeps this eta's value (about twice the node
 * count of eta = 1.1) and the series construction broadens the lobe,
 * conserving its energy, to what the resolution can hold. */
#define NARROWEST_ETA 1.05

ll_status ll_fit_microfacet(double alpha, double eta_re, double eta_im, size_t *n_nodes,
                            size_t *n_orders)
{
    static const char fn[] = "ll_heuristic_microfacet";
    double n, m, eta;
    int row;
    if (!n_nodes || !n_orders)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: n_nodes or n_orders is NULL", fn);
    if (!(alpha >= LL_MICROFACET_MIN_ALPHA) || !ll_is_finite(alpha))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: alpha = %g; the smallest roughness supported is "
                       "LL_MICROFACET_MIN_ALPHA = %g",
                       fn, alpha, LL_MICROFACET_MIN_ALPHA);
    if (!(eta_im >= 0.0) || !ll_is_finite(eta_im) || !ll_is_finite(eta_re) ||
        !(eta_im > 0.0 ? eta_re >= 0.0 : eta_re > 0.0))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: eta = %g + %g i is not a valid index (need eta_im >= 0, and "
                       "eta_re > 0 for a dielectric, >= 0 for a conductor)",
                       fn, eta_re, eta_im);
    /* The fits stop changing beyond alpha = 1 (the original clamps too). */
    alpha = fmin(alpha, 1.0);
    if (eta_im > 0.0) {
        fit_eval(0, alpha, &n, &m);
        return store_resolution(fn, n, m, n_nodes, n_orders);
    }
    /* A dielectric looks the same from both sides: eta and 1/eta. */
    eta = eta_re < 1.0 ? 1.0 / eta_re : eta_re;
    if (eta == 1.0) {
        /* Index-matched: no interface at all (ll_layer_set_microfacet makes
         * the layer clear), so it asks for nothing. */
        *n_nodes = 2;
        *n_orders = 1;
        return LL_OK;
    }
    if (eta <= fit_table[1][0]) {
        double scale = refracted_width(fmax(eta, NARROWEST_ETA)) / refracted_width(fit_table[1][0]);
        fit_eval(1, alpha * scale, &n, &m);
    } else if (eta >= fit_table[4][0]) {
        /* Denser media widen the refracted lobe; the reflected lobe, which
         * does not depend on eta, is then the narrowest one and the last fit
         * already resolves it. */
        fit_eval(4, alpha, &n, &m);
    } else {
        /* Linear interpolation between the two neighbouring fits. */
        double n0, m0, n1, m1, t;
        for (row = 1; row < 4 && eta > fit_table[row + 1][0]; ++row)
            ;
        fit_eval(row, alpha, &n0, &m0);
        fit_eval(row + 1, alpha, &n1, &m1);
        t = (eta - fit_table[row][0]) / (fit_table[row + 1][0] - fit_table[row][0]);
        n = n0 + t * (n1 - n0);
        m = m0 + t * (m1 - m0);
    }
    return store_resolution(fn, n, m, n_nodes, n_orders);
}

ll_status ll_heuristic_microfacet(double alpha, double eta_re, double eta_im, size_t *n_nodes,
                                  size_t *n_orders)
{
    return ll_fit_microfacet(alpha, eta_re, eta_im, n_nodes, n_orders);
}

ll_status ll_heuristic_henyey_greenstein(double g, size_t *n_nodes, size_t *n_orders)
{
    return ll_fit_henyey_greenstein(g, n_nodes, n_orders);
}
