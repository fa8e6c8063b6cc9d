/*
 * The resolution search's kept series (search/probe.h, ll_probe_series_memo):
 * an evaluation that reads a node count's series from an evaluation at more
 * orders gives the values of one that computes them, bit for bit, where
 * lobes are widened too (down to one order), for Beckmann and GGX
 * dielectrics from both sides and conductors; and a memo filled at fewer
 * orders is refilled, not read, for more.
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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(kept_series_are_the_computed_ones),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
