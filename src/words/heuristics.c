/*
 * Resolution: how many zenith-cosine nodes n and Fourier orders m a
 * Henyey-Greenstein medium or a rough interface needs. The heuristics are
 * the fits of the original layerlab (parameterHeuristicHG and
 * parameterHeuristicMicrofacet, from convergence studies of Jakob et al.
 * 2014), extended to every index of refraction; the resolution searches
 * measure the convergence on probe directions (words/probe.h) to a stated
 * tolerance, the fits their first guess of n only: the fits do not see the
 * narrow azimuthal lobes of grazing pairs (eta 1.5, alpha 0.5: 37 orders
 * gave 2.5 instead of 4.76 at mu = 0.1 in the mirror direction).
 */
#include "support/support.h"
#include "words/probe.h"

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

/* ------------------------------------------------ chosen by a tolerance */

/* Fewer nodes than this are never chosen: the quadrature itself is then
 * off by more than 1% in an albedo (src/material/material_resolution.c,
 * LL_MATERIAL_MIN_NODES: 8 nodes are 1.5% off, 10 below 1%). */
#define SEARCH_MIN_NODES 10
/* The largest nodes or orders the search tries (a build accepts up to
 * LL_MATERIAL_MAX_RESOLUTION = 100000). */
#define SEARCH_LIMIT 100000

/* Above this first guess of the nodes (alpha below about 0.02 for eta 1.1,
 * 0.007 for eta 1.5, 0.002 for conductors) the search is not run and the
 * fit is the answer, unverified: the probes' quadrature alone is O(n^2)
 * at 2n and the series of such smooth interfaces have thousands of terms,
 * minutes per search, for layers beyond most memory budgets anyway
 * (8000 nodes x 8000 orders: 1 TB dense). */
#define UNVERIFIED_NODES 8000

static ll_status read_goal(const char *fn, double *tolerance, double *mu_min)
{
    if (*tolerance == 0.0)
        *tolerance = LL_DEFAULT_TOLERANCE;
    if (*mu_min == 0.0)
        *mu_min = LL_DEFAULT_MU_MIN;
    if (!(*tolerance >= LL_MIN_TOLERANCE && *tolerance < 1.0))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: tolerance = %g; expected a relative error in [%g, 1) (or 0 for the "
                       "default %g): the azimuthal series themselves are accurate to a few "
                       "1e-4 of their peak",
                       fn, *tolerance, LL_MIN_TOLERANCE, LL_DEFAULT_TOLERANCE);
    if (!(*mu_min > 0.0 && *mu_min <= 1.0))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: mu_min = %g; expected a cosine in (0, 1] (or 0 for the default %g)",
                       fn, *mu_min, LL_DEFAULT_MU_MIN);
    return LL_OK;
}

/* The compensations made so far, one per node count (the search asks
 * for each n at several m; the term depends on n alone). */
#define MAX_COMPENSATIONS 64

typedef struct interface_ctx {
    ll_microfacet_model *mf;
    ll_microfacet_model *mf0; /* the compensation's: order 0 only */
    double eta_re, eta_im;
    int compensate;
    const ll_probe_set *set;
    ll_probe_compensation made[MAX_COMPENSATIONS];
    size_t n_made;
} interface_ctx;

static ll_status compensation_for(interface_ctx *c, size_t n, ll_watch *watch,
                                  const ll_probe_compensation **out)
{
    size_t k;
    ll_status s;
    for (k = 0; k < c->n_made; ++k)
        if (c->made[k].h == n / 2) {
            *out = &c->made[k];
            return LL_OK;
        }
    if (c->n_made == MAX_COMPENSATIONS) {
        /* Forget the oldest (the search has moved past it). */
        ll_probe_compensation_free(&c->made[0]);
        for (k = 1; k < MAX_COMPENSATIONS; ++k)
            c->made[k - 1] = c->made[k];
        --c->n_made;
    }
    s = ll_probe_compensation_make(c->mf0, c->eta_re, c->eta_im, n, watch, &c->made[c->n_made]);
    if (s != LL_OK)
        return s;
    *out = &c->made[c->n_made++];
    return LL_OK;
}

static ll_status interface_eval(void *ctx, size_t n, size_t m, ll_watch *watch, double *values)
{
    interface_ctx *c = ctx;
    const ll_probe_compensation *compensation = NULL;
    ll_status s = c->compensate ? compensation_for(c, n, watch, &compensation) : LL_OK;
    return s == LL_OK
               ? ll_probe_interface_eval(c->mf, compensation, n, m, c->set, watch, values)
               : s;
}

ll_status ll_resolution_search_microfacet(const ll_microfacet *microfacet, double tolerance,
                                          double mu_min, const ll_monitor *monitor,
                                          size_t *n_nodes, size_t *n_orders, double *error)
{
    static const char fn[] = "ll_resolution_search_microfacet";
    ll_microfacet in;
    ll_watch watch;
    ll_status s = ll_microfacet_read(microfacet, &in, fn);
    if (s == LL_OK)
        s = ll_watch_begin(&watch, monitor, fn);
    if (s != LL_OK)
        return s;
    ll_watch_stage(&watch, "resolution", 0.0, 1.0, LL_PROBE_SEARCH_UNITS);
    s = ll_search_microfacet_distribution(in.alpha, in.eta_re, in.eta_im, in.distribution,
                                          in.compensate != 0, tolerance, mu_min, &watch,
                                          n_nodes, n_orders, error);
    return ll_watch_finish(&watch, s, fn);
}

ll_status ll_search_microfacet(double alpha, double eta_re, double eta_im, int compensate,
                               double tolerance, double mu_min, ll_watch *watch,
                               size_t *n_nodes, size_t *n_orders, double *error)
{
    return ll_search_microfacet_distribution(alpha, eta_re, eta_im, LL_DISTRIBUTION_BECKMANN,
                                             compensate, tolerance, mu_min, watch, n_nodes,
                                             n_orders, error);
}

ll_status ll_search_microfacet_distribution(double alpha, double eta_re, double eta_im,
                                            int distribution, int compensate, double tolerance,
                                            double mu_min, ll_watch *watch, size_t *n_nodes,
                                            size_t *n_orders, double *error)
{
    static const char fn[] = "ll_resolution_search_microfacet";
    ll_probe_set set;
    interface_ctx ctx;
    size_t n, m;
    double e = 0.0;
    ll_status s = n_nodes && n_orders
                      ? read_goal(fn, &tolerance, &mu_min)
                      : ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: n_nodes or n_orders is NULL", fn);
    if (s == LL_OK)
        s = ll_fit_microfacet(alpha, eta_re, eta_im, &n, &m);
    if (s != LL_OK)
        return s;
    if (eta_im == 0.0 && eta_re == 1.0) {
        /* No interface: nothing to resolve. */
        *n_nodes = n;
        *n_orders = m;
        if (error)
            *error = 0.0;
        return LL_OK;
    }
    if (n > UNVERIFIED_NODES) {
        /* Too smooth to probe affordably: the fit, unverified. */
        *n_nodes = n;
        *n_orders = m;
        if (error)
            *error = HUGE_VAL;
        return LL_OK;
    }
    s = ll_probe_interface(eta_re, eta_im, mu_min, &set);
    if (s != LL_OK)
        return s;
    ctx.mf = NULL;
    ctx.mf0 = NULL;
    ctx.n_made = 0;
    ctx.eta_re = eta_re;
    ctx.eta_im = eta_im;
    ctx.compensate = compensate;
    ctx.set = &set;
    /* n: the fit's guess; m: what the probes' own series need. */
    s = ll_probe_interface_model_distribution(eta_re, eta_im, alpha, distribution, &ctx.mf);
    if (s == LL_OK && compensate)
        s = ll_probe_compensation_model_distribution(eta_re, eta_im, alpha, distribution,
                                                     &ctx.mf0);
    if (s == LL_OK)
        s = ll_probe_interface_orders(ctx.mf, tolerance, &set, &m);
    if (s == LL_OK)
        s = ll_probe_search(&set, interface_eval, &ctx, watch, tolerance, SEARCH_MIN_NODES,
                            SEARCH_LIMIT, fn, &n, &m, &e);
    while (ctx.n_made > 0)
        ll_probe_compensation_free(&ctx.made[--ctx.n_made]);
    ll_microfacet_destroy(ctx.mf);
    ll_microfacet_destroy(ctx.mf0);
    ll_probe_free(&set);
    if (s != LL_OK)
        return s;
    *n_nodes = n;
    *n_orders = m;
    if (error)
        *error = e;
    return LL_OK;
}

ll_status ll_heuristic_microfacet(double alpha, double eta_re, double eta_im, size_t *n_nodes,
                                  size_t *n_orders)
{
    return ll_fit_microfacet(alpha, eta_re, eta_im, n_nodes, n_orders);
}

/* The largest |g| whose resolution is searched (see below). */
#define HG_SEARCHED 0.95
/* The most nodes or orders a medium's search tries: ten times the 344 x 181
 * that g = 0.95 needs; its probes hold one n x n phase matrix per thread
 * (128 MB each at 4000). */
#define HG_SEARCH_LIMIT 4000

typedef struct medium_ctx {
    double g;
    const ll_probe_set *set;
} medium_ctx;

/* A monitor for a layer call inside a search: it answers the search's
 * watch (on the calling thread, the watch's owner: polling reports the
 * search's progress and sees its cancel). */
static int poll_watch(void *user, double fraction, const char *stage)
{
    (void)fraction;
    (void)stage;
    return ll_watch_poll(user);
}

/* The phase function's layer (ll_layer_set_henyey_greenstein on the
 * Gauss-Lobatto nodes of n) at the probes: the single-scattering lobe,
 * which is the sharpest part of a slab (the doubling only smooths it). */
static ll_status medium_eval(void *ctx, size_t n, size_t m, ll_watch *watch, double *values)
{
    const medium_ctx *c = ctx;
    ll_monitor monitor = LL_MONITOR_INIT;
    monitor.progress = poll_watch;
    monitor.user = watch;
    return ll_probe_medium_eval(LL_MEDIUM_HG, c->g, 0, n, m, c->set, watch ? &monitor : NULL,
                                values);
}

ll_status ll_resolution_search_henyey_greenstein(double g, double tolerance, double mu_min,
                                                 const ll_monitor *monitor, size_t *n_nodes,
                                                 size_t *n_orders, double *error)
{
    static const char fn[] = "ll_resolution_search_henyey_greenstein";
    ll_watch watch;
    ll_status s = ll_watch_begin(&watch, monitor, fn);
    if (s != LL_OK)
        return s;
    ll_watch_stage(&watch, "resolution", 0.0, 1.0, LL_PROBE_SEARCH_UNITS);
    s = ll_search_henyey_greenstein(g, tolerance, mu_min, &watch, n_nodes, n_orders, error);
    return ll_watch_finish(&watch, s, fn);
}

ll_status ll_search_henyey_greenstein(double g, double tolerance, double mu_min,
                                      ll_watch *watch, size_t *n_nodes, size_t *n_orders,
                                      double *error)
{
    static const char fn[] = "ll_resolution_search_henyey_greenstein";
    ll_probe_set set;
    medium_ctx ctx;
    size_t n, m;
    double e = 0.0;
    ll_status s = n_nodes && n_orders
                      ? read_goal(fn, &tolerance, &mu_min)
                      : ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: n_nodes or n_orders is NULL", fn);
    if (s == LL_OK)
        s = ll_fit_henyey_greenstein(g, &n, &m);
    if (s == LL_OK)
        s = ll_probe_medium(mu_min, &set);
    if (s != LL_OK)
        return s;
    ctx.g = g;
    ctx.set = &set;
    /* The fit is the first guess of both. Beyond |g| = 0.95 the fit is the
     * answer, unverified: each evaluation there makes phase matrices of
     * O(n^2 m) work at 2n, 2m (n = 2 x 860, m = 2 x 539 at |g| = 0.99), and
     * already g = -0.95 takes 86 s of CPU (426 x 261). */
    if (fabs(g) > HG_SEARCHED) {
        ll_probe_free(&set);
        *n_nodes = n;
        *n_orders = m;
        if (error)
            *error = HUGE_VAL;
        return LL_OK;
    }
    s = ll_probe_search(&set, medium_eval, &ctx, watch, tolerance, SEARCH_MIN_NODES,
                        HG_SEARCH_LIMIT, fn, &n, &m, &e);
    ll_probe_free(&set);
    if (s != LL_OK)
        return s;
    *n_nodes = n;
    *n_orders = m;
    if (error)
        *error = e;
    return LL_OK;
}

ll_status ll_heuristic_henyey_greenstein(double g, size_t *n_nodes, size_t *n_orders)
{
    return ll_fit_henyey_greenstein(g, n_nodes, n_orders);
}
