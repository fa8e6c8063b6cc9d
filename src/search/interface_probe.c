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
#include "search/probe_pairs.h"
#include "words/microfacet.h"
#include "numerics/spline.h"

#include "layerlab/ll_quad.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>


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
    return ll_microfacet_create_distribution(eta_re, eta_im, alpha, distribution,
                                             LL_PROBE_TRUE_ORDERS, LL_PROBE_TRUE_MAX_LEN, out);
}

/* What an evaluation does with the memo's series. */
enum { MEMO_NONE, MEMO_FILL, MEMO_REUSE };

typedef struct eval_job {
    const ll_microfacet_model *mf;
    const ll_probe_set *set;
    const ll_probe_pair_stencil *stencils;
    const ll_probe_compensation *compensation; /* nullable */
    ll_probe_series_memo *memo;                /* nullable */
    int mode;                                  /* MEMO_* */
    size_t m;
    ll_probe_node_pairs *pairs;
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

/* The series of distinct node pair d (on a worker thread: the model is
 * only read): from the memo where it holds it unwidened for orders at
 * least m, else computed (and kept there when filling). */
static ll_status pair_series(size_t d, void *ctx)
{
    const eval_job *job = ctx;
    ll_probe_series_memo *memo = job->memo;
    ll_probe_node_pairs *np = job->pairs;
    double mu_o = np->mu_o[d], mu_i = np->mu_i[d], *series, *scratch, *kept = NULL;
    size_t len = 0;
    int widened = 0;
    ll_status s;
    if (ll_watch_poll(job->watch))
        return ll_fail(LL_ERROR_CANCELLED, "resolution search: cancelled");
    if (job->mode == MEMO_REUSE && !memo->widened[d] &&
        !ll_microfacet_widened(job->mf, mu_o, mu_i)) {
        np->c[d] = memo->series[d];
        np->len[d] = kept_terms(memo->series[d], memo->len[d], job->m,
                                ll_microfacet_keep(job->mf));
        return LL_OK;
    }
    series = ll_alloc_array(job->m, sizeof(double));
    scratch = ll_alloc_array(ll_microfacet_scratch_size(job->m), sizeof(double));
    if (!series || !scratch)
        s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "resolution probes: out of memory for %zu orders",
                    job->m);
    else
        s = ll_microfacet_series_widened(job->mf, mu_o, mu_i, job->m, series, &len, NULL,
                                         scratch, &widened);
    if (s == LL_OK && len > 0) {
        kept = ll_alloc_array(len, sizeof(double));
        if (!kept)
            s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "resolution probes: out of memory");
        else
            memcpy(kept, series, len * sizeof(double));
    }
    ll_free(series);
    ll_free(scratch);
    if (s != LL_OK)
        return s;
    np->c[d] = kept;
    np->len[d] = len;
    if (job->mode == MEMO_FILL) {
        memo->series[d] = kept;
        memo->len[d] = len;
        memo->widened[d] = (unsigned char)(widened != 0);
    } else {
        np->fresh[d] = kept;
    }
    return LL_OK;
}

/* The values of probe pair p from its stencil's series (on a worker
 * thread). */
static ll_status eval_pair(size_t p, void *ctx)
{
    const eval_job *job = ctx;
    const ll_probe_pair_stencil *st = job->stencils + p;
    const ll_probe_node_pairs *np = job->pairs;
    /* the compensation's series, and the stencil's weighted sum of both */
    double *term = ll_alloc_array(job->m, 2 * sizeof(double));
    double *sum = term ? term + job->m : NULL;
    double *acc = job->values + p * job->set->n_phi;
    const ll_probe_pair *pair = job->set->pairs + p;
    int block = LL_BLOCK_OF(pair->mu_o, pair->mu_i);
    size_t a, b, k, l, len, sum_len = 0;
    ll_status s = LL_OK;
    if (!term)
        s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "resolution probes: out of memory for %zu orders",
                    job->m);
    else if (ll_watch_poll(job->watch))
        s = ll_fail(LL_ERROR_CANCELLED, "resolution search: cancelled");
    else
        memset(sum, 0, job->m * sizeof(double));
    memset(acc, 0, job->set->n_phi * sizeof(double));
    for (a = 0; a < st->co && s == LL_OK; ++a)
        for (b = 0; b < st->ci; ++b) {
            size_t d = np->of_slot[16 * p + 4 * a + b];
            const double *c = np->c[d];
            /* (The stencil's series summed first and then evaluated at
             * the azimuths: 16 times fewer terms than evaluating each.) */
            len = np->len[d];
            for (l = 0; l < len; ++l)
                sum[l] += st->wo[a] * st->wi[b] * c[l];
            if (len > sum_len)
                sum_len = len;
            /* The compensation's series (same azimuth convention). */
            len = ll_probe_compensation_series(job->compensation, block, st->io[a], st->ii[b],
                                               job->m, term);
            for (l = 0; l < len; ++l)
                sum[l] += st->wo[a] * st->wi[b] * term[l];
            if (len > sum_len)
                sum_len = len;
        }
    if (s == LL_OK)
        ll_probe_add_series(sum, sum_len, job->set->phi, job->set->n_phi, 1.0, acc);
    for (k = 0; k < job->set->n_phi; ++k)
        acc[k] = acc[k] > 0.0 ? acc[k] : 0.0; /* as ll_layer_eval */
    ll_free(term);
    return s;
}

/* Empty the memo's series (its rule stays). */
static void memo_clear(ll_probe_series_memo *memo)
{
    double *rule = memo->rule;
    size_t k, rule_n = memo->rule_n;
    if (memo->series)
        for (k = 0; k < memo->slots; ++k)
            ll_free(memo->series[k]);
    ll_free(memo->series);
    ll_free(memo->len);
    ll_free(memo->widened);
    memset(memo, 0, sizeof *memo);
    memo->rule = rule;
    memo->rule_n = rule_n;
}

void ll_probe_series_memo_free(ll_probe_series_memo *memo)
{
    memo_clear(memo);
    ll_free(memo->rule);
    memset(memo, 0, sizeof *memo);
}

ll_status ll_probe_series_memo_rule(ll_probe_series_memo *memo, size_t n, const double **nodes,
                                    const double **weights)
{
    ll_status s = LL_OK;
    if (!memo->rule || memo->rule_n != n) {
        ll_free(memo->rule);
        memo->rule_n = 0;
        memo->rule = ll_alloc_array(n, 2 * sizeof(double));
        s = memo->rule ? ll_quad_gauss_lobatto(n, memo->rule, memo->rule + n, NULL)
                       : ll_fail(LL_ERROR_OUT_OF_MEMORY,
                                 "resolution probes: out of memory for %zu nodes", n);
        if (s != LL_OK) {
            ll_free(memo->rule);
            memo->rule = NULL;
            return s;
        }
        memo->rule_n = n;
    }
    *nodes = memo->rule;
    *weights = memo->rule + n;
    return s;
}

/* Ready memo for an evaluation at (n, m) of count distinct node pairs:
 * MEMO_REUSE when it holds n's series for at least m orders, else emptied
 * and sized for filling. */
static ll_status memo_mode(ll_probe_series_memo *memo, size_t n, size_t m, size_t count,
                           int *mode)
{
    *mode = MEMO_NONE;
    if (!memo)
        return LL_OK;
    if (memo->n == n && m <= memo->m && memo->slots == count) {
        *mode = MEMO_REUSE;
        return LL_OK;
    }
    memo_clear(memo);
    memo->series = ll_calloc_array(count + 1, sizeof *memo->series);
    memo->len = ll_calloc_array(count + 1, sizeof *memo->len);
    memo->widened = ll_calloc_array(count + 1, 1);
    if (!memo->series || !memo->len || !memo->widened) {
        memo_clear(memo);
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "resolution probes: out of memory");
    }
    memo->slots = count;
    *mode = MEMO_FILL;
    return LL_OK;
}

ll_status ll_probe_interface_eval(ll_microfacet_model *mf,
                                  const ll_probe_compensation *compensation,
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
    ll_probe_series_memo own;
    const double *nodes, *weights;
    ll_probe_pair_stencil *stencils = ll_alloc_array(set->n_pairs + 1, sizeof *stencils);
    size_t h = n / 2, p;
    ll_probe_node_pairs np;
    eval_job job;
    ll_status s;
    memset(&np, 0, sizeof np);
    memset(&own, 0, sizeof own);
    if (!stencils) {
        s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "resolution probes: out of memory for %zu nodes", n);
        goto done;
    }
    /* The widening of a layer of m orders (ll_layer_set_microfacet). */
    ll_microfacet_set_orders(mf, m);
    /* (Without a memo, the rule of this evaluation alone.) */
    s = ll_probe_series_memo_rule(memo ? memo : &own, n, &nodes, &weights);
    for (p = 0; p < set->n_pairs && s == LL_OK; ++p) {
        ll_probe_pair_stencil *st = stencils + p;
        st->co = ll_probe_stencil(nodes + h, h, set->pairs[p].mu_o, st->no, st->wo, st->io);
        st->ci = ll_probe_stencil(nodes + h, h, set->pairs[p].mu_i, st->ni, st->wi, st->ii);
    }
    if (s == LL_OK)
        s = ll_probe_node_pairs_make(set, stencils, &np);
    /* The maps first (they change the model), then the series of the node
     * pairs and the probes' sums of them, each in parallel. */
    if (s == LL_OK)
        s = ll_microfacet_prepare_pairs(mf, np.mu_o, np.mu_i, np.count);
    job.mf = mf;
    job.set = set;
    job.stencils = stencils;
    job.compensation = compensation;
    job.m = m;
    job.pairs = &np;
    job.values = values;
    job.watch = watch;
    job.memo = memo;
    job.mode = MEMO_NONE;
    if (s == LL_OK)
        s = memo_mode(memo, n, m, np.count, &job.mode);
    if (s == LL_OK)
        s = ll_parallel_for_watched(np.count, pair_series, &job, watch);
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
    ll_probe_node_pairs_free(&np);
    ll_probe_series_memo_free(&own);
    ll_free(stencils);
    return s;
}
