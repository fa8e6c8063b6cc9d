/*
 * The resolution of a measured BRDF by the tolerance (search/probe.h): the
 * projected lobe at (n, m) against (2n, 2m) on the probes of an opaque
 * surface, searched by ll_probe_search as the interfaces are.
 *
 * As for an interface (interface_probe.c), the layer's value at a probe is
 * the Catmull-Rom spline over the 4 x 4 node pairs around it of the series
 * ll_merl_set_layer puts there (ll_merl_pair_series, the same code), so no
 * layer is built: the series of the distinct stencil node pairs only
 * (neighbouring probes share most of them), each 4m lookups and a DCT of
 * 4m x m multiply-adds, against (n/2)^2 of them for a whole layer.
 */
#include "search/probe.h"

#include "layerlab/ll_quad.h"

#include <math.h>
#include <string.h>

/* The nodes never fewer than a build's minimum. */
#define MERL_SEARCH_MIN_NODES 10

typedef struct merl_probe_ctx {
    const ll_merl *merl;
    const double *weights;
    const ll_probe_set *set;
} merl_probe_ctx;

/* The distinct node pairs (incident index, outgoing index on the half) and
 * the values of their series at the probes' azimuths. */
typedef struct pair_job {
    const ll_merl *merl;
    const double *weights;
    const double *half;
    const ll_probe_set *set;
    const size_t *in, *out; /* per distinct pair */
    size_t m, N;
    const double *cos_table;
    double *at_phi; /* distinct pairs x n_phi */
    ll_watch *watch;
} pair_job;

static ll_status pair_values(size_t u, void *ctx)
{
    const pair_job *job = ctx;
    double *f = ll_alloc_array(job->N, sizeof(double)), *a = ll_alloc_array(job->m, sizeof(double));
    double *acc = job->at_phi + u * job->set->n_phi;
    ll_status s = LL_OK;
    if (!f || !a) {
        s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "measured resolution: out of memory for %zu orders",
                    job->m);
        goto done;
    }
    if (ll_watch_poll(job->watch)) {
        s = ll_fail(LL_ERROR_CANCELLED, "measured resolution: cancelled");
        goto done;
    }
    ll_merl_pair_series(job->merl, job->weights, job->half[job->in[u]], job->half[job->out[u]],
                        job->m, job->N, job->cos_table, f, a);
    memset(acc, 0, job->set->n_phi * sizeof(double));
    ll_probe_add_series(a, job->m, job->set->phi, job->set->n_phi, 1.0, acc);
done:
    ll_free(f);
    ll_free(a);
    return s;
}

ll_status ll_merl_probe_eval(const ll_merl *merl, const double weights[3], size_t n, size_t m,
                             const ll_probe_set *set, ll_watch *watch, double *values)
{
    size_t h = n / 2, p, a, b, k, count = 0, pairs_max;
    double *nodes = ll_alloc_array(n, sizeof(double)), *qw = ll_alloc_array(n, sizeof(double));
    size_t *slot = NULL, *in = NULL, *out = NULL;
    double *cos_table = NULL;
    pair_job job;
    ll_status s;

    memset(&job, 0, sizeof job);
    /* slot[i * h + o]: the distinct pair's index + 1, 0 when unused. */
    if (!nodes || !qw || !ll_size_mul(h, h, &pairs_max) ||
        !(slot = ll_calloc_array(pairs_max + 1, sizeof(size_t))) ||
        !(in = ll_alloc_array(16 * set->n_pairs + 1, sizeof(size_t))) ||
        !(out = ll_alloc_array(16 * set->n_pairs + 1, sizeof(size_t)))) {
        s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "measured resolution: out of memory for %zu nodes", n);
        goto done;
    }
    s = ll_quad_gauss_lobatto(n, nodes, qw, NULL);
    if (s == LL_OK)
        s = ll_merl_cos_table(m, &job.N, &cos_table);
    for (p = 0; p < set->n_pairs && s == LL_OK; ++p) {
        double no[4], wo[4], ni[4], wi[4];
        size_t io[4], ii[4];
        size_t co = ll_probe_stencil(nodes + h, h, fabs(set->pairs[p].mu_o), no, wo, io);
        size_t ci = ll_probe_stencil(nodes + h, h, set->pairs[p].mu_i, ni, wi, ii);
        for (a = 0; a < co; ++a)
            for (b = 0; b < ci; ++b)
                if (!slot[ii[b] * h + io[a]]) {
                    in[count] = ii[b];
                    out[count] = io[a];
                    slot[ii[b] * h + io[a]] = ++count;
                }
    }
    if (s == LL_OK && !(job.at_phi = ll_alloc_array(count + 1, set->n_phi * sizeof(double))))
        s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "measured resolution: out of memory");
    job.merl = merl;
    job.weights = weights;
    job.half = nodes + h;
    job.set = set;
    job.in = in;
    job.out = out;
    job.m = m;
    job.cos_table = cos_table;
    job.watch = watch;
    if (s == LL_OK)
        s = ll_parallel_for_watched(count, pair_values, &job, watch);
    /* The spline sum of each probe, as ll_layer_eval: reflection from
     * above only (mu_i > 0, mu_o < 0), nothing elsewhere. */
    for (p = 0; p < set->n_pairs && s == LL_OK; ++p) {
        double no[4], wo[4], ni[4], wi[4], *acc = values + p * set->n_phi;
        size_t io[4], ii[4], co, ci;
        memset(acc, 0, set->n_phi * sizeof(double));
        if (!(set->pairs[p].mu_i > 0.0 && set->pairs[p].mu_o < 0.0))
            continue;
        co = ll_probe_stencil(nodes + h, h, fabs(set->pairs[p].mu_o), no, wo, io);
        ci = ll_probe_stencil(nodes + h, h, set->pairs[p].mu_i, ni, wi, ii);
        for (a = 0; a < co; ++a)
            for (b = 0; b < ci; ++b) {
                const double *v = job.at_phi + (slot[ii[b] * h + io[a]] - 1) * set->n_phi;
                for (k = 0; k < set->n_phi; ++k)
                    acc[k] += wo[a] * wi[b] * v[k];
            }
        for (k = 0; k < set->n_phi; ++k)
            acc[k] = acc[k] > 0.0 ? acc[k] : 0.0; /* as ll_layer_eval */
    }
done:
    ll_free(nodes);
    ll_free(qw);
    ll_free(slot);
    ll_free(in);
    ll_free(out);
    ll_free(cos_table);
    ll_free(job.at_phi);
    return s;
}

static ll_status merl_eval(void *ctx, size_t n, size_t m, ll_watch *watch, double *values)
{
    const merl_probe_ctx *c = ctx;
    return ll_merl_probe_eval(c->merl, c->weights, n, m, c->set, watch, values);
}

ll_status ll_merl_resolution(const ll_merl *merl, const double weights[3], double tolerance,
                             double mu_min, ll_watch *watch, size_t *n_nodes, size_t *n_orders,
                             double *error)
{
    /* The table's own resolution bounds the search: the reader looks its
     * cells up nearest-neighbour (MERL's reader), so the converged layer
     * is a staircase whose steps no (n, m) brings within a tolerance
     * smaller than the steps themselves (a Beckmann lobe of alpha 0.2 in
     * a table of the database's size steps by about 20% per theta_half
     * cell on its flank, and the search had not met 1% at 800 x 1440,
     * after 52 s). Twice the table's cells, about two nodes per theta
     * cell and two orders per phi_diff step, resolve every cell; beyond,
     * only the cells' edges sharpen. */
    size_t n_cap = 2 * (merl->res_theta_h > merl->res_theta_d ? merl->res_theta_h
                                                               : merl->res_theta_d);
    size_t m_cap = merl->res_phi_d, n = *n_nodes, m = *n_orders;
    ll_probe_set set;
    merl_probe_ctx ctx;
    double e = HUGE_VAL;
    ll_status s;
    n_cap = n_cap < MERL_SEARCH_MIN_NODES ? MERL_SEARCH_MIN_NODES : n_cap + n_cap % 2;
    n = n < n_cap ? n : n_cap;
    m = m < m_cap ? m : m_cap;
    s = ll_probe_opaque(mu_min, &set);
    if (s != LL_OK)
        return s;
    ctx.merl = merl;
    ctx.weights = weights;
    ctx.set = &set;
    s = ll_probe_search(&set, merl_eval, &ctx, watch, tolerance, MERL_SEARCH_MIN_NODES,
                        2 * (n_cap > m_cap ? n_cap : m_cap), "measured", &n, &m, &e);
    ll_probe_free(&set);
    if (s == LL_ERROR_INVALID_ARGUMENT) {
        /* Not met below twice the cap: the table's resolution, its error
         * unverified (as ll_resolution_search_microfacet's beyond what it can
         * probe). */
        n = n_cap;
        m = m_cap;
        e = HUGE_VAL;
        s = LL_OK;
    }
    if (s != LL_OK)
        return s;
    *n_nodes = n;
    *n_orders = m;
    if (error)
        *error = e;
    return LL_OK;
}
