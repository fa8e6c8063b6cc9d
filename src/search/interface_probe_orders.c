/*
 * The Fourier orders a rough interface's lobes need at the probes
 * (ll_probe_interface_orders, search/probe.h): the search's first m.
 *
 * Each probe pair's true series (no widening) is computed once. What the
 * pair needs depends on its group's peak, which only all the pairs
 * together give; so each pair keeps, per azimuth, the terms that azimuth
 * would need were it above the floor (a few numbers, not the series), and
 * the floor picks among them once the peaks are known.
 */
#include "search/probe.h"
#include "words/microfacet.h"

#include <math.h>

/* Prepare the maps of every probe pair's true series, in one batch (one
 * pass over the model's grid, not one per pair). */
static ll_status prepare_all(ll_microfacet_model *mf, const ll_probe_set *set)
{
    double *mu = ll_alloc_array(set->n_pairs + 1, 2 * sizeof(double));
    size_t p;
    ll_status s;
    if (!mu)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "resolution probes: out of memory");
    /* Depth grows opposite to the normal: the series takes -mu. */
    for (p = 0; p < set->n_pairs; ++p) {
        mu[p] = -set->pairs[p].mu_o;
        mu[set->n_pairs + p] = -set->pairs[p].mu_i;
    }
    s = ll_microfacet_prepare_pairs(mf, mu, mu + set->n_pairs, set->n_pairs);
    ll_free(mu);
    return s;
}

/* Per azimuth k, the terms the truncation of c needs to stay within
 * tolerance of the whole series full[k] there: 1 + the last l + 1 at
 * which l + 1 terms are not enough (at least 1, at most len). */
static void needed_terms(const double *c, size_t len, const double *phi, size_t n_phi,
                         const double *full, double tolerance, size_t *need)
{
    double c1[LL_PROBE_MAX_PHI], prev[LL_PROBE_MAX_PHI], cur[LL_PROBE_MAX_PHI],
        sum[LL_PROBE_MAX_PHI];
    size_t k, l;
    for (k = 0; k < n_phi; ++k) {
        c1[k] = cos(phi[k]);
        prev[k] = c1[k];
        cur[k] = 1.0;
        sum[k] = 0.0;
        need[k] = 1;
    }
    for (l = 0; l < len; ++l)
        for (k = 0; k < n_phi; ++k) {
            double next = 2.0 * c1[k] * cur[k] - prev[k];
            sum[k] += c[l] * cur[k];
            prev[k] = cur[k];
            cur[k] = next;
            /* l + 1 terms are not enough here: at least l + 2 are needed. */
            if (fabs(sum[k] - full[k]) > tolerance * full[k])
                need[k] = l + 2;
        }
    for (k = 0; k < n_phi; ++k)
        if (need[k] > len)
            need[k] = len;
}

ll_status ll_probe_interface_orders(ll_microfacet_model *mf, double tolerance,
                                    const ll_probe_set *set, size_t *n_orders)
{
    size_t nphi = set->n_phi, values = LL_PROBE_VALUES(set);
    double *c = ll_alloc_array(LL_PROBE_TRUE_MAX_LEN, sizeof(double));
    double *scratch = ll_alloc_array(ll_microfacet_scratch_size(LL_PROBE_TRUE_MAX_LEN),
                                     sizeof(double));
    double *full = ll_calloc_array(values + 1, sizeof(double));
    double *peak = ll_calloc_array(set->n_groups + 1, sizeof(double));
    size_t *need = ll_calloc_array(values + 1, sizeof(size_t));
    size_t p, k, len, m = 1;
    ll_status s;
    if (!c || !scratch || !full || !peak || !need) {
        s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "resolution probes: out of memory");
        goto done;
    }
    ll_microfacet_set_orders(mf, LL_PROBE_TRUE_ORDERS);
    s = prepare_all(mf, set);
    for (p = 0; p < set->n_pairs && s == LL_OK; ++p) {
        s = ll_microfacet_series(mf, -set->pairs[p].mu_o, -set->pairs[p].mu_i,
                                 LL_PROBE_TRUE_MAX_LEN, c, &len, NULL, scratch);
        if (s != LL_OK || len == 0)
            continue; /* (a pair without a lobe needs nothing: need stays 0) */
        /* The whole series' values, for the peaks of the groups. */
        ll_probe_add_series(c, len, set->phi, nphi, 1.0, full + p * nphi);
        for (k = 0; k < nphi; ++k)
            peak[set->pairs[p].group] = fmax(peak[set->pairs[p].group], full[p * nphi + k]);
        needed_terms(c, len, set->phi, nphi, full + p * nphi, 0.5 * tolerance,
                     need + p * nphi);
    }
    /* The most any azimuth above its group's floor needs. */
    for (p = 0; p < set->n_pairs && s == LL_OK; ++p) {
        double floor = LL_PROBE_FLOOR * peak[set->pairs[p].group];
        for (k = 0; k < nphi; ++k)
            if (full[p * nphi + k] > floor && full[p * nphi + k] > 0.0 &&
                need[p * nphi + k] > m)
                m = need[p * nphi + k];
    }
    if (s == LL_OK)
        *n_orders = m;
done:
    ll_free(c);
    ll_free(scratch);
    ll_free(full);
    ll_free(peak);
    ll_free(need);
    return s;
}
