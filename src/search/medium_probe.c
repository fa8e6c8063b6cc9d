/*
 * A medium's phase function at the probes (search/probe.h), without keeping
 * its layer: ll_layer_set_medium_finished hands each order's phase matrix
 * over as it is made, and only the 4 x 4 spline stencils of ll_layer_eval
 * (layer/layer.c eval_point) at the probes are read from it; the orders
 * are summed with cos(l phi) afterwards, in order (the same for any thread
 * count). One n x n matrix per thread instead of the layer's n^2 m: the
 * search compares with twice the resolution, and at g = 0.95 a whole layer
 * there is 1376 x 724, 11 GB (a search that grew further filled a 23 GB
 * machine). tests/test_convergence.c checks it against ll_layer_eval.
 *
 * The search leaves out the delta-M forward term f I (words/media.c: the
 * moments beyond the kept K are exactly forward scattering, f = chi_K): a
 * delta, not a lobe, which ll_layer_eval shows near mu_o = mu_i as f over
 * the node's weight, and which changes with n and K without converging.
 * With g = -0.9 the true forward lobe is tiny (at mu = 1, 0.0022) and
 * f / w there was 0.6% of it at 300 x 150 and 8.4% at 2232 x 530: the
 * search never met the tolerance. */
#include "search/probe.h"
#include "words/media.h"

#include "layerlab/ll_quad.h"

#include <math.h>
#include <string.h>

typedef struct probe_stencil {
    size_t row[4], col[4]; /* the layer's internal node indices */
    double wo[4], scale[4];
    size_t co, ci;
} probe_stencil;

typedef struct medium_probe {
    const ll_probe_set *set;
    const probe_stencil *at;
    size_t n;
    int with_forward;
    double *per_order; /* m x pairs: order l's stencil sum at each pair */
} medium_probe;

/* The stencil of mu in the layer's order (ll_layer_create: index j and
 * j + h are -x_j and x_j). */
static size_t layer_stencil(const double *half, size_t h, double mu, size_t index[4],
                            double w[4])
{
    double node[4];
    size_t count = ll_probe_stencil(half, h, mu, node, w, index), k;
    for (k = 0; k < count; ++k)
        index[k] += mu < 0.0 ? 0 : h;
    return count;
}

static ll_status probe_order(void *user, size_t l, double *P, double forward, ll_order **out)
{
    const medium_probe *job = user;
    size_t p, a, b, n = job->n;
    for (p = 0; p < job->set->n_pairs; ++p) {
        const probe_stencil *st = job->at + p;
        double sum = 0.0;
        for (b = 0; b < st->ci; ++b)
            for (a = 0; a < st->co; ++a) {
                /* Beyond the kept moments an order is forward * I. */
                double diagonal = st->row[a] == st->col[b] ? forward : 0.0;
                double v = P ? P[st->col[b] * n + st->row[a]] : diagonal;
                if (!job->with_forward)
                    v -= diagonal;
                sum += st->wo[a] * st->scale[b] * v;
            }
        job->per_order[l * job->set->n_pairs + p] = sum;
    }
    *out = NULL; /* kept by nobody */
    return LL_OK;
}

ll_status ll_probe_medium_eval(ll_medium_kind kind, double shape, int with_forward, size_t n,
                               size_t m, const ll_probe_set *set, const ll_monitor *monitor,
                               double *values)
{
    size_t h = n / 2, p, k, l, per_order_count;
    double *rule = ll_alloc_array(n, 2 * sizeof(double));
    probe_stencil *at = ll_alloc_array(set->n_pairs + 1, sizeof *at);
    ll_layer *layer = NULL;
    medium_probe job;
    ll_medium_finish finish;
    ll_status s = LL_OK;

    job.per_order = NULL;
    if (!rule || !at || !ll_size_mul(m, set->n_pairs, &per_order_count) ||
        !(job.per_order = ll_calloc_array(per_order_count + 1, sizeof(double)))) {
        s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "resolution probes: out of memory for %zu orders",
                    m);
        goto done;
    }
    s = ll_quad_gauss_lobatto(n, rule, rule + n, NULL);
    if (s == LL_OK)
        s = ll_layer_create(rule, rule + n, n, m, &layer);
    if (s != LL_OK)
        goto done;
    for (p = 0; p < set->n_pairs; ++p) {
        probe_stencil *st = at + p;
        double wi[4];
        st->co = layer_stencil(rule + h, h, set->pairs[p].mu_o, st->row, st->wo);
        st->ci = layer_stencil(rule + h, h, set->pairs[p].mu_i, st->col, wi);
        /* ll_layer_eval's column scale: the incident node's weight out. */
        for (k = 0; k < st->ci; ++k)
            st->scale[k] =
                wi[k] / (fabs(layer->nodes[st->col[k]]) * layer->weights[st->col[k]]);
    }
    job.set = set;
    job.at = at;
    job.n = n;
    job.with_forward = with_forward;
    finish.order = probe_order;
    finish.user = &job;
    s = ll_layer_set_medium_finished(layer, kind, 1.0, shape, &finish, monitor);
    for (p = 0; p < set->n_pairs && s == LL_OK; ++p)
        for (k = 0; k < set->n_phi; ++k) {
            double c1 = cos(set->phi[k]), prev = c1, cur = 1.0, sum = 0.0;
            for (l = 0; l < m; ++l) {
                double next = 2.0 * c1 * cur - prev;
                sum += job.per_order[l * set->n_pairs + p] * cur * (l == 0 ? 0.5 : 1.0);
                prev = cur;
                cur = next;
            }
            sum *= LL_INV_PI;
            values[p * set->n_phi + k] = sum > 0.0 ? sum : 0.0; /* as ll_layer_eval */
        }
done:
    ll_layer_destroy(layer);
    ll_free(rule);
    ll_free(at);
    ll_free(job.per_order);
    return s;
}
