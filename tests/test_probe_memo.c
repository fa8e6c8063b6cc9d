/*
 * The resolution search's kept series (search/probe.h, ll_probe_series_memo):
 * an evaluation that reads a node count's series from an evaluation at more
 * orders gives the values of one that computes them, bit for bit, where
 * lobes are widened too (down to one order), for Beckmann and GGX
 * dielectrics from both sides and conductors; and a memo filled at fewer
 * orders is refilled, not read, for more. And the series of a node pair
 * that several probes' stencils share, computed once, is what each of
 * their stencil slots would have computed for itself.
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdlib.h>
#include <string.h>

#include <layerlab.h>
#include "search/probe.h"
#include "words/microfacet.h"
#include "layerlab/ll_quad.h"

static void memo_matches(double eta_re, double eta_im, double alpha, int distribution,
                         size_t n)
{
    /* Down from the most orders (read from the memo), then up (refilled). */
    static const size_t orders[] = { 400, 300, 120, 50, 10, 3, 1, 500, 200 };
    ll_probe_set set;
    ll_probe_series_memo memo;
    ll_microfacet_model *mf = NULL;
    double *kept, *fresh;
    size_t k;
    memset(&memo, 0, sizeof memo);
    assert_int_equal(ll_probe_interface(eta_re, eta_im, 0.1, &set), LL_OK);
    assert_int_equal(ll_probe_interface_model_distribution(eta_re, eta_im, alpha, distribution,
                                                           &mf),
                     LL_OK);
    kept = malloc(LL_PROBE_VALUES(&set) * sizeof *kept);
    fresh = malloc(LL_PROBE_VALUES(&set) * sizeof *fresh);
    assert_non_null(kept);
    assert_non_null(fresh);
    for (k = 0; k < sizeof orders / sizeof orders[0]; ++k) {
        assert_int_equal(ll_probe_interface_eval_memo(mf, NULL, &memo, n, orders[k], &set, NULL,
                                                      kept),
                         LL_OK);
        assert_int_equal(memo.n, n);
        assert_true(memo.m >= orders[k]);
        assert_int_equal(ll_probe_interface_eval(mf, NULL, n, orders[k], &set, NULL, fresh),
                         LL_OK);
        assert_memory_equal(kept, fresh, LL_PROBE_VALUES(&set) * sizeof *kept);
    }
    assert_int_equal(memo.m, 500);
    /* Another node count refills it. */
    assert_int_equal(ll_probe_interface_eval_memo(mf, NULL, &memo, n + 2, 40, &set, NULL, kept),
                     LL_OK);
    assert_int_equal(memo.n, n + 2);
    assert_int_equal(memo.m, 40);
    ll_probe_series_memo_free(&memo);
    ll_microfacet_destroy(mf);
    ll_probe_free(&set);
    free(kept);
    free(fresh);
}

static void kept_series_are_the_computed_ones(void **state)
{
    (void)state;
    memo_matches(1.5, 0.0, 0.1, LL_DISTRIBUTION_BECKMANN, 120);
    memo_matches(1.5, 0.0, 0.5, LL_DISTRIBUTION_BECKMANN, 60);
    memo_matches(1.0 / 1.5, 0.0, 0.05, LL_DISTRIBUTION_BECKMANN, 160);
    memo_matches(0.2, 3.5, 0.1, LL_DISTRIBUTION_BECKMANN, 100);
    memo_matches(1.5, 0.0, 0.2, LL_DISTRIBUTION_GGX, 100);
    memo_matches(0.2, 3.0, 0.3, LL_DISTRIBUTION_GGX, 80);
}

/* The evaluation against each probe's 4 x 4 stencil summed slot by slot
 * from series computed for that slot alone (interface_probe.c's sum,
 * without compensation): bit for bit, so a slot that read another node
 * pair's series, or one computed at other orders, would show. */
static void slots_match(double eta_re, double eta_im, double alpha, size_t n, size_t m)
{
    ll_probe_set set;
    ll_microfacet_model *mf = NULL;
    double *values, *direct, *nodes, *weights, *series, *scratch, *sum;
    size_t h = n / 2, p, a, b, k, l;
    assert_int_equal(ll_probe_interface(eta_re, eta_im, 0.1, &set), LL_OK);
    assert_int_equal(ll_probe_interface_model(eta_re, eta_im, alpha, &mf), LL_OK);
    values = malloc(LL_PROBE_VALUES(&set) * sizeof *values);
    direct = calloc(LL_PROBE_VALUES(&set), sizeof *direct);
    nodes = malloc(n * sizeof *nodes);
    weights = malloc(n * sizeof *weights);
    series = malloc(m * sizeof *series);
    sum = malloc(m * sizeof *sum);
    scratch = malloc(ll_microfacet_scratch_size(m) * sizeof *scratch);
    assert_true(values && direct && nodes && weights && series && sum && scratch);
    /* (This also prepares the model for every stencil's node pairs.) */
    assert_int_equal(ll_probe_interface_eval(mf, NULL, n, m, &set, NULL, values), LL_OK);
    assert_int_equal(ll_quad_gauss_lobatto(n, nodes, weights, NULL), LL_OK);
    for (p = 0; p < set.n_pairs; ++p) {
        double no[4], wo[4], ni[4], wi[4], *acc = direct + p * set.n_phi;
        size_t co = ll_probe_stencil(nodes + h, h, set.pairs[p].mu_o, no, wo, NULL);
        size_t ci = ll_probe_stencil(nodes + h, h, set.pairs[p].mu_i, ni, wi, NULL);
        size_t len, sum_len = 0;
        memset(sum, 0, m * sizeof *sum);
        for (a = 0; a < co; ++a)
            for (b = 0; b < ci; ++b) {
                assert_int_equal(ll_microfacet_series(mf, -no[a], -ni[b], m, series, &len,
                                                      NULL, scratch),
                                 LL_OK);
                for (l = 0; l < len; ++l)
                    sum[l] += wo[a] * wi[b] * series[l];
                if (len > sum_len)
                    sum_len = len;
            }
        ll_probe_add_series(sum, sum_len, set.phi, set.n_phi, 1.0, acc);
        for (k = 0; k < set.n_phi; ++k)
            acc[k] = acc[k] > 0.0 ? acc[k] : 0.0;
    }
    assert_memory_equal(values, direct, LL_PROBE_VALUES(&set) * sizeof *values);
    ll_microfacet_destroy(mf);
    ll_probe_free(&set);
    free(values);
    free(direct);
    free(nodes);
    free(weights);
    free(series);
    free(sum);
    free(scratch);
}

static void shared_node_pairs_are_each_slots_series(void **state)
{
    (void)state;
    /* Dielectric from above and below (four blocks), a conductor (one);
     * widened lobes at the fewest orders. */
    slots_match(1.5, 0.0, 0.15, 138, 120);
    slots_match(1.5, 0.0, 0.1, 196, 8);
    slots_match(1.0 / 1.5, 0.0, 0.3, 60, 40);
    slots_match(0.2, 3.5, 0.1, 100, 90);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(kept_series_are_the_computed_ones),
        cmocka_unit_test(shared_node_pairs_are_each_slots_series),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
