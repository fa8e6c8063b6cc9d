/*
 * The resolution searches of the public API and of the words: the smallest
 * (n, m) whose layer agrees on the probe directions (search/probe.h) with
 * twice the resolution within a stated tolerance, for a rough interface
 * and a Henyey-Greenstein medium. The instant fits (words/heuristics.c)
 * are their first guess.
 */
#include "support/support.h"
#include "search/probe.h"
#include "words/heuristics.h"
#include "words/microfacet.h"

#include "layerlab/ll_layer.h"

#include <math.h>
#include <string.h>

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
/* The node counts whose probe series are kept (search/probe.h,
 * ll_probe_series_memo): a few MB each; the search's shrinking visits
 * n and 2n at a few order counts each, about four node counts at once. */
#define MAX_MEMOS 6

typedef struct interface_ctx {
    ll_microfacet_model *mf;
    ll_microfacet_model *mf0; /* the compensation's: order 0 only */
    double eta_re, eta_im;
    int compensate;
    /* A GGX dielectric: the probes whose stencils straddle its
     * transmission jump are left out (search/probe_jump.c). */
    int jump;
    const ll_probe_set *set;
    ll_probe_compensation made[MAX_COMPENSATIONS];
    size_t n_made;
    ll_probe_series_memo memo[MAX_MEMOS];
    size_t n_memos;
} interface_ctx;

/* The memo of node count n's series: the one kept, else a new one (the
 * oldest forgotten when all are taken: the search has moved past it). */
static ll_probe_series_memo *memo_for(interface_ctx *c, size_t n)
{
    ll_probe_series_memo spare;
    size_t k;
    for (k = 0; k < c->n_memos; ++k)
        if (c->memo[k].n == n)
            return &c->memo[k];
    if (c->n_memos < MAX_MEMOS) {
        memset(&c->memo[c->n_memos], 0, sizeof c->memo[0]);
        return &c->memo[c->n_memos++];
    }
    ll_probe_series_memo_free(&c->memo[0]);
    spare = c->memo[0];
    for (k = 1; k < MAX_MEMOS; ++k)
        c->memo[k - 1] = c->memo[k];
    c->memo[MAX_MEMOS - 1] = spare;
    return &c->memo[MAX_MEMOS - 1];
}

static ll_status compensation_for(interface_ctx *c, size_t n, const double *nodes,
                                  const double *weights, ll_watch *watch,
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
    s = ll_probe_compensation_make_rule(c->mf0, c->eta_re, c->eta_im, n, nodes, weights, watch,
                                        &c->made[c->n_made]);
    if (s != LL_OK)
        return s;
    *out = &c->made[c->n_made++];
    return LL_OK;
}

static ll_status interface_eval(void *ctx, size_t n, size_t m, ll_watch *watch, double *values)
{
    interface_ctx *c = ctx;
    const ll_probe_compensation *compensation = NULL;
    ll_probe_series_memo *memo = memo_for(c, n);
    const double *nodes, *weights;
    /* (One Gauss-Lobatto rule of n for the compensation, the probes'
     * stencils and the jump's marks.) */
    ll_status s = ll_probe_series_memo_rule(memo, n, &nodes, &weights);
    if (s == LL_OK && c->compensate)
        s = compensation_for(c, n, nodes, weights, watch, &compensation);
    if (s == LL_OK)
        s = ll_probe_interface_eval_memo(c->mf, compensation, memo, n, m, c->set, watch, values);
    if (s == LL_OK && c->jump)
        ll_probe_mark_jump_nodes(c->set, n, nodes, c->eta_re, values);
    return s;
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
    size_t n = 0, m = 0;
    ll_status s = ll_search_microfacet_from(alpha, eta_re, eta_im, distribution, compensate,
                                            tolerance, mu_min, watch, n_nodes ? &n : NULL,
                                            n_orders ? &m : NULL, error);
    if (s == LL_OK) {
        *n_nodes = n;
        *n_orders = m;
    }
    return s;
}

ll_status ll_search_microfacet_from(double alpha, double eta_re, double eta_im, int distribution,
                                    int compensate, double tolerance, double mu_min,
                                    ll_watch *watch, size_t *n_nodes, size_t *n_orders,
                                    double *error)
{
    static const char fn[] = "ll_resolution_search_microfacet";
    ll_probe_set set;
    interface_ctx ctx;
    size_t n, m, start_n, start_m;
    double e = 0.0;
    ll_status s = n_nodes && n_orders
                      ? read_goal(fn, &tolerance, &mu_min)
                      : ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: n_nodes or n_orders is NULL", fn);
    if (s != LL_OK)
        return s;
    start_n = *n_nodes;
    start_m = *n_orders;
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
    ctx.n_memos = 0;
    ctx.eta_re = eta_re;
    ctx.eta_im = eta_im;
    ctx.compensate = compensate;
    ctx.jump = distribution == LL_DISTRIBUTION_GGX && eta_im == 0.0;
    ctx.set = &set;
    /* n: the fit's guess; m: what the probes' own series need; or the
     * start, where one is given. */
    s = ll_probe_interface_model_distribution(eta_re, eta_im, alpha, distribution, &ctx.mf);
    if (s == LL_OK && compensate)
        s = ll_probe_compensation_model_distribution(eta_re, eta_im, alpha, distribution,
                                                     &ctx.mf0);
    if (s == LL_OK)
        s = ll_probe_interface_orders(ctx.mf, tolerance, &set, &m);
    if (s == LL_OK) {
        if (start_n)
            n = start_n;
        if (start_m)
            m = start_m;
        s = ll_probe_search(&set, interface_eval, &ctx, watch, tolerance, SEARCH_MIN_NODES,
                            SEARCH_LIMIT, fn, &n, &m, &e);
    }
    while (ctx.n_made > 0)
        ll_probe_compensation_free(&ctx.made[--ctx.n_made]);
    while (ctx.n_memos > 0)
        ll_probe_series_memo_free(&ctx.memo[--ctx.n_memos]);
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
     * O(n^2 m) work at 2n, 2m, where n and m grow without bound as |g|
     * approaches 1 (docs/method.md, "Resolution", has the cost at g = -0.95). */
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
