/*
 * A rough interface at the probes (search/probe.h), without building it.
 *
 * ll_layer_eval of an interface layer is, per Fourier order, a Catmull-Rom
 * spline over the nodes of the half each direction lies in (4 x 4 node
 * pairs around (mu_o, mu_i)), summed with cos(l phi) (layer/layer.c
 * eval_point), and ll_layer_set_microfacet fills those node pairs with
 * ll_microfacet_series(-mu_o, -mu_i) on m orders (the layer's). So the
 * layer's value at a probe needs only the 16 series of its stencil:
 * O(probes x m) instead of O(n^2 m) for the whole interface, which is what
 * makes the convergence search (twice the resolution, repeatedly)
 * affordable even for the n ~ 1000, m ~ 2000 of alpha = 0.02.
 *
 * With compensate, the energy compensation (ll_microfacet.compensate, a rank-one
 * term of order 0 per block, Jakob et al. 2014, sec. 6.2) is added at the
 * same stencils: it is made from the albedos of every node, so it is
 * computed whole at each resolution (search/interface_probe_compensation.c),
 * O(n^2) order-0 series. Left out, the probes accepted copper, alpha 0.8 at
 * 214 x 45, which was 1.32% off twice that resolution with the term (0.33%
 * without).
 */
#include "search/probe.h"
#include "words/microfacet.h"
#include "numerics/spline.h"

#include "layerlab/ll_quad.h"

#include <math.h>
#include <string.h>

#define TRUE_ORDERS LL_PROBE_TRUE_ORDERS
#define TRUE_MAX_LEN ((size_t)100000)

size_t ll_probe_stencil(const double *half, size_t h, double mu, double node[4], double w[4],
                        size_t index[4])
{
    ptrdiff_t offset = 0;
    double wk[4];
    size_t count = 0;
    int k;
    ll_spline_weights(half, h, fabs(mu), &offset, wk, 1);
    for (k = 0; k < 4; ++k) {
        ptrdiff_t i = offset + k;
        if (wk[k] == 0.0 || i < 0 || i >= (ptrdiff_t)h)
            continue;
        node[count] = mu < 0.0 ? -half[i] : half[i];
        w[count] = wk[k];
        if (index)
            index[count] = (size_t)i;
        ++count;
    }
    return count;
}

void ll_probe_add_series(const double *c, size_t len, const double *phi, size_t n_phi,
                       double weight, double *acc)
{
    size_t k, l;
    for (k = 0; k < n_phi; ++k) {
        double c1 = cos(phi[k]), prev = c1, cur = 1.0, sum = 0.0;
        for (l = 0; l < len; ++l) {
            double next = 2.0 * c1 * cur - prev;
            sum += c[l] * cur;
            prev = cur;
            cur = next;
        }
        acc[k] += weight * sum;
    }
}

ll_status ll_probe_interface_model(double eta_re, double eta_im, double alpha,
                                   ll_microfacet_model **out)
{
    return ll_probe_interface_model_distribution(eta_re, eta_im, alpha,
                                                 LL_DISTRIBUTION_BECKMANN, out);
}

ll_status ll_probe_interface_model_distribution(double eta_re, double eta_im, double alpha,
                                                int distribution, ll_microfacet_model **out)
{
    return ll_microfacet_create_distribution(eta_re, eta_im, alpha, distribution, TRUE_ORDERS,
                                             TRUE_MAX_LEN, out);
}

/* One probe pair's 4 x 4 stencil (signed node cosines and weights). */
typedef struct pair_stencil {
    double no[4], wo[4], ni[4], wi[4];
    size_t io[4], ii[4]; /* node indices into the positive half */
    size_t co, ci;
} pair_stencil;

/* What an evaluation does with the memo's series. */
enum { MEMO_NONE, MEMO_FILL, MEMO_REUSE };

typedef struct eval_job {
    const ll_microfacet_model *mf;
    const ll_probe_set *set;
    const pair_stencil *stencils;
    const ll_probe_compensation *compensation; /* nullable */
    ll_probe_series_memo *memo;                /* nullable */
    int mode;                                  /* MEMO_* */
    size_t m;
    double *values;
    ll_watch *watch;
} eval_job;

/* The terms of a series of len terms (computed with more orders) that a
 * series of m orders keeps: ll_microfacet_series' truncation after the
 * last term that matters, within the first m. */
static size_t kept_terms(const double *c, size_t len, size_t m, double keep)
{
    size_t k = len < m ? len : m, l, last = 0;
    if (k == 0 || !(c[0] > 0.0))
        return 0;
    for (l = 1; l < k; ++l)
        if (fabs(c[l]) >= keep * c[0])
            last = l;
    return last + 1;
}

/* The series of stencil slot `slot` (node cosines mu_o, mu_i as the
 * series takes them): from the memo where it holds them unwidened for
 * orders at least m, else computed (and kept when filling). */
static ll_status slot_series(const eval_job *job, size_t slot, double mu_o, double mu_i,
                             double *series, double *scratch, const double **c, size_t *len)
{
    ll_probe_series_memo *memo = job->memo;
    int widened;
    ll_status s;
    if (job->mode == MEMO_REUSE && !memo->widened[slot] &&
        !ll_microfacet_widened(job->mf, mu_o, mu_i)) {
        *c = memo->series[slot];
        *len = kept_terms(*c, memo->len[slot], job->m, ll_microfacet_keep(job->mf));
        return LL_OK;
    }
    s = ll_microfacet_series_widened(job->mf, mu_o, mu_i, job->m, series, len, NULL, scratch,
                                     &widened);
    *c = series;
    if (s != LL_OK || job->mode != MEMO_FILL)
        return s;
    memo->len[slot] = *len;
    memo->widened[slot] = (unsigned char)(widened != 0);
    if (*len > 0) {
        memo->series[slot] = ll_alloc_array(*len, sizeof(double));
        if (!memo->series[slot])
            return ll_fail(LL_ERROR_OUT_OF_MEMORY, "resolution probes: out of memory");
        memcpy(memo->series[slot], series, *len * sizeof(double));
    }
    return LL_OK;
}

/* The values of probe pair p (on a worker thread: the model is only read). */
static ll_status eval_pair(size_t p, void *ctx)
{
    const eval_job *job = ctx;
    const pair_stencil *st = job->stencils + p;
    /* series, the compensation's series, and the stencil's weighted sum
     * of both */
    double *series = ll_alloc_array(job->m, 3 * sizeof(double));
    double *term = series ? series + job->m : NULL, *sum = series ? series + 2 * job->m : NULL;
    double *scratch = ll_alloc_array(ll_microfacet_scratch_size(job->m), sizeof(double));
    double *acc = job->values + p * job->set->n_phi;
    const ll_probe_pair *pair = job->set->pairs + p;
    int block = LL_BLOCK_OF(pair->mu_o, pair->mu_i);
    size_t a, b, k, l, len, sum_len = 0;
    ll_status s = LL_OK;
    if (!series || !scratch)
        s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "resolution probes: out of memory for %zu orders",
                    job->m);
    else if (ll_watch_poll(job->watch))
        s = ll_fail(LL_ERROR_CANCELLED, "resolution search: cancelled");
    else
        memset(sum, 0, job->m * sizeof(double));
    memset(acc, 0, job->set->n_phi * sizeof(double));
    for (a = 0; a < st->co && s == LL_OK; ++a)
        for (b = 0; b < st->ci && s == LL_OK; ++b) {
            const double *c = NULL;
            /* Depth grows opposite to the normal: the series takes -mu. */
            s = slot_series(job, 16 * p + 4 * a + b, -st->no[a], -st->ni[b], series, scratch, &c,
                            &len);
            /* (The stencil's series summed first and then evaluated at
             * the azimuths: 16 times fewer terms than evaluating each.) */
            for (l = 0; s == LL_OK && l < len; ++l)
                sum[l] += st->wo[a] * st->wi[b] * c[l];
            if (s == LL_OK && len > sum_len)
                sum_len = len;
            if (s == LL_OK) {
                /* The compensation's series (same azimuth convention). */
                len = ll_probe_compensation_series(job->compensation, block, st->io[a],
                                                   st->ii[b], job->m, term);
                for (l = 0; l < len; ++l)
                    sum[l] += st->wo[a] * st->wi[b] * term[l];
                if (len > sum_len)
                    sum_len = len;
            }
        }
    if (s == LL_OK)
        ll_probe_add_series(sum, sum_len, job->set->phi, job->set->n_phi, 1.0, acc);
    for (k = 0; k < job->set->n_phi; ++k)
        acc[k] = acc[k] > 0.0 ? acc[k] : 0.0; /* as ll_layer_eval */
    ll_free(series);
    ll_free(scratch);
    return s;
}

/* Empty the memo's series (its nodes stay). */
static void memo_clear(ll_probe_series_memo *memo)
{
    double *nodes = memo->nodes;
    size_t k, nodes_n = memo->nodes_n;
    if (memo->series)
        for (k = 0; k < memo->slots; ++k)
            ll_free(memo->series[k]);
    ll_free(memo->series);
    ll_free(memo->len);
    ll_free(memo->widened);
    memset(memo, 0, sizeof *memo);
    memo->nodes = nodes;
    memo->nodes_n = nodes_n;
}

void ll_probe_series_memo_free(ll_probe_series_memo *memo)
{
    memo_clear(memo);
    ll_free(memo->nodes);
    memset(memo, 0, sizeof *memo);
}

/* The Gauss-Lobatto nodes of n into nodes (weights: scratch of n): the
 * memo's (nullable) where it holds them, else made and kept there. */
static ll_status lobatto_nodes(ll_probe_series_memo *memo, size_t n, double *nodes,
                               double *weights)
{
    ll_status s;
    if (memo && memo->nodes && memo->nodes_n == n) {
        memcpy(nodes, memo->nodes, n * sizeof(double));
        return LL_OK;
    }
    s = ll_quad_gauss_lobatto(n, nodes, weights, NULL);
    if (s != LL_OK || !memo)
        return s;
    ll_free(memo->nodes);
    memo->nodes_n = 0;
    /* (Kept only if there is memory for it: else made again next time.) */
    memo->nodes = ll_alloc_array(n, sizeof(double));
    if (memo->nodes) {
        memcpy(memo->nodes, nodes, n * sizeof(double));
        memo->nodes_n = n;
    }
    return LL_OK;
}

/* Ready memo for an evaluation at (n, m): MEMO_REUSE when it holds n's
 * series for at least m orders, else emptied and sized for filling. */
static ll_status memo_mode(ll_probe_series_memo *memo, size_t n, size_t m,
                           const ll_probe_set *set, int *mode)
{
    size_t slots;
    *mode = MEMO_NONE;
    if (!memo)
        return LL_OK;
    if (memo->n == n && m <= memo->m) {
        *mode = MEMO_REUSE;
        return LL_OK;
    }
    memo_clear(memo);
    if (!ll_size_mul(16, set->n_pairs, &slots))
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "resolution probes: out of memory");
    memo->series = ll_calloc_array(slots + 1, sizeof *memo->series);
    memo->len = ll_calloc_array(slots + 1, sizeof *memo->len);
    memo->widened = ll_calloc_array(slots + 1, 1);
    if (!memo->series || !memo->len || !memo->widened) {
        memo_clear(memo);
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "resolution probes: out of memory");
    }
    memo->slots = slots;
    *mode = MEMO_FILL;
    return LL_OK;
}

ll_status ll_probe_interface_eval(ll_microfacet_model *mf, const ll_probe_compensation *compensation,
                                  size_t n, size_t m, const ll_probe_set *set, ll_watch *watch,
                                  double *values)
{
    return ll_probe_interface_eval_memo(mf, compensation, NULL, n, m, set, watch, values);
}

ll_status ll_probe_interface_eval_memo(ll_microfacet_model *mf,
                                       const ll_probe_compensation *compensation,
                                       ll_probe_series_memo *memo, size_t n, size_t m,
                                       const ll_probe_set *set, ll_watch *watch, double *values)
{
    double *nodes = ll_alloc_array(n, sizeof(double)), *weights = ll_alloc_array(n, sizeof(double));
    pair_stencil *stencils = ll_alloc_array(set->n_pairs + 1, sizeof *stencils);
    double *mu_o = ll_alloc_array(16 * set->n_pairs + 1, sizeof(double));
    double *mu_i = ll_alloc_array(16 * set->n_pairs + 1, sizeof(double));
    size_t h = n / 2, p, a, b, count = 0;
    eval_job job;
    ll_status s;
    if (!nodes || !weights || !stencils || !mu_o || !mu_i) {
        s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "resolution probes: out of memory for %zu nodes", n);
        goto done;
    }
    /* The widening of a layer of m orders (ll_layer_set_microfacet). */
    ll_microfacet_set_orders(mf, m);
    s = lobatto_nodes(memo, n, nodes, weights);
    for (p = 0; p < set->n_pairs && s == LL_OK; ++p) {
        pair_stencil *st = stencils + p;
        st->co = ll_probe_stencil(nodes + h, h, set->pairs[p].mu_o, st->no, st->wo, st->io);
        st->ci = ll_probe_stencil(nodes + h, h, set->pairs[p].mu_i, st->ni, st->wi, st->ii);
        for (a = 0; a < st->co; ++a)
            for (b = 0; b < st->ci; ++b) {
                mu_o[count] = -st->no[a];
                mu_i[count] = -st->ni[b];
                ++count;
            }
    }
    /* The maps first (they change the model), then the pairs in parallel. */
    if (s == LL_OK)
        s = ll_microfacet_prepare_pairs(mf, mu_o, mu_i, count);
    job.mf = mf;
    job.set = set;
    job.stencils = stencils;
    job.compensation = compensation;
    job.m = m;
    job.values = values;
    job.watch = watch;
    job.memo = memo;
    job.mode = MEMO_NONE;
    if (s == LL_OK)
        s = memo_mode(memo, n, m, set, &job.mode);
    if (s == LL_OK)
        s = ll_parallel_for_watched(set->n_pairs, eval_pair, &job, watch);
    if (job.mode == MEMO_FILL) {
        /* (A fill that failed part way holds a part: empty it.) */
        if (s == LL_OK) {
            memo->n = n;
            memo->m = m;
        } else {
            memo_clear(memo);
        }
    }
done:
    ll_free(nodes);
    ll_free(weights);
    ll_free(stencils);
    ll_free(mu_o);
    ll_free(mu_i);
    return s;
}

/* The true series of a pair into c (*len terms). */
static ll_status true_series(ll_microfacet_model *mf, const ll_probe_pair *pair, double *c,
                             size_t *len, double *scratch)
{
    double mu[2];
    ll_status s;
    mu[0] = -pair->mu_o;
    mu[1] = -pair->mu_i;
    s = ll_microfacet_prepare_pairs(mf, mu, mu + 1, 1);
    return s == LL_OK ? ll_microfacet_series(mf, mu[0], mu[1], TRUE_MAX_LEN, c, len, NULL,
                                             scratch)
                      : s;
}

/* The shortest truncation of c within tolerance of the whole series where
 * it is above floor. */
static size_t needed_length(const double *c, size_t len, const double *phi, size_t n_phi,
                            const double *full, double floor, double tolerance)
{
    double c1[LL_PROBE_MAX_PHI], prev[LL_PROBE_MAX_PHI], cur[LL_PROBE_MAX_PHI],
        sum[LL_PROBE_MAX_PHI];
    size_t k, l, needed = 1;
    for (k = 0; k < n_phi; ++k) {
        c1[k] = cos(phi[k]);
        prev[k] = c1[k];
        cur[k] = 1.0;
        sum[k] = 0.0;
    }
    for (l = 0; l < len; ++l)
        for (k = 0; k < n_phi; ++k) {
            double next = 2.0 * c1[k] * cur[k] - prev[k];
            sum[k] += c[l] * cur[k];
            prev[k] = cur[k];
            cur[k] = next;
            /* l + 1 terms are not enough here: at least l + 2 are needed. */
            if (full[k] > floor && full[k] > 0.0 &&
                fabs(sum[k] - full[k]) > tolerance * full[k])
                needed = l + 2;
        }
    return needed < len ? needed : len;
}

ll_status ll_probe_interface_orders(ll_microfacet_model *mf, double tolerance,
                                    const ll_probe_set *set, size_t *n_orders)
{
    double *c = ll_alloc_array(TRUE_MAX_LEN, sizeof(double));
    double *scratch = ll_alloc_array(ll_microfacet_scratch_size(TRUE_MAX_LEN), sizeof(double));
    double *full = ll_calloc_array(LL_PROBE_VALUES(set) + 1, sizeof(double));
    double *peak = ll_calloc_array(set->n_groups + 1, sizeof(double));
    size_t p, k, len, m = 1, nphi = set->n_phi;
    ll_status s;
    if (!c || !scratch || !full || !peak) {
        s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "resolution probes: out of memory");
        goto done;
    }
    ll_microfacet_set_orders(mf, TRUE_ORDERS);
    s = LL_OK;
    /* The whole series' values, for the peaks of the groups. */
    for (p = 0; p < set->n_pairs && s == LL_OK; ++p) {
        s = true_series(mf, &set->pairs[p], c, &len, scratch);
        if (s != LL_OK)
            break;
        ll_probe_add_series(c, len, set->phi, nphi, 1.0, full + p * nphi);
        for (k = 0; k < nphi; ++k)
            peak[set->pairs[p].group] = fmax(peak[set->pairs[p].group], full[p * nphi + k]);
    }
    for (p = 0; p < set->n_pairs && s == LL_OK; ++p) {
        size_t need;
        s = true_series(mf, &set->pairs[p], c, &len, scratch);
        if (s != LL_OK || len == 0)
            continue;
        need = needed_length(c, len, set->phi, nphi, full + p * nphi,
                             LL_PROBE_FLOOR * peak[set->pairs[p].group], 0.5 * tolerance);
        if (need > m)
            m = need;
    }
    if (s == LL_OK)
        *n_orders = m;
done:
    ll_free(c);
    ll_free(scratch);
    ll_free(full);
    ll_free(peak);
    return s;
}
