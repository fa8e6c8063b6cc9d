/*
 * An interface computes the series of one entry of each reciprocal pair
 * and mirrors the other (words/microfacet_columns.c): the layer equals
 * the one whose every entry has its own series, to rounding, in every
 * entry of every order (Beckmann and GGX, dielectric from either side and
 * a conductor, compensated or not); its bits do not depend on the thread
 * count; nodes that are not exact mirrors (ll_layer_create allows 1e-12)
 * take the build of every pair. And the builders' mirror itself
 * (ll_order_builder_mirror) on a small order whose entries are known.
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "test_util.h"
#include "words/microfacet_columns.h"

#define GOLD_RE 0.14317534881908534
#define GOLD_IM 3.9826674681176435

static ll_layer *layer_on(size_t n, size_t m, const double *shift)
{
    double *x = malloc(n * sizeof *x), *w = malloc(n * sizeof *w);
    ll_layer *l = NULL;
    size_t k;
    assert_non_null(x);
    assert_non_null(w);
    assert_int_equal(ll_quad_gauss_lobatto(n, x, w, NULL), LL_OK);
    for (k = 0; shift && k < n; ++k)
        x[k] *= 1.0 + shift[k];
    assert_int_equal(ll_layer_create(x, w, n, m, &l), LL_OK);
    free(x);
    free(w);
    return l;
}

static ll_status build(ll_layer *l, double eta_re, double eta_im, double alpha,
                       int distribution, int compensate, int every_pair)
{
    ll_microfacet mf = LL_MICROFACET_INIT;
    mf.eta_re = eta_re;
    mf.eta_im = eta_im;
    mf.alpha = alpha;
    mf.distribution = distribution;
    mf.compensate = compensate;
    return ll_microfacet_set_layer(l, &mf, NULL, every_pair);
}

/* The largest difference of two layers' entries, per order, over the
 * largest entry of that order; orders must be empty in both or neither. */
static double worst_difference(const ll_layer *a, const ll_layer *b)
{
    size_t n = a->n, k, o, i;
    double worst = 0.0;
    for (k = 0; k < a->m; ++k) {
        double big = 0.0, diff = 0.0;
        assert_true((a->orders[k] == NULL) == (b->orders[k] == NULL));
        if (!a->orders[k])
            continue;
        for (i = 0; i < n; ++i)
            for (o = 0; o < n; ++o) {
                double x = ll_order_get(a->orders[k], o, i), y = ll_order_get(b->orders[k], o, i);
                big = fmax(big, fmax(fabs(x), fabs(y)));
                diff = fmax(diff, fabs(x - y));
            }
        assert_true(big > 0.0);
        worst = fmax(worst, diff / big);
    }
    return worst;
}

/* Are two layers the same bits (orders stored alike, values equal)? */
static int same_bits(const ll_layer *a, const ll_layer *b)
{
    size_t k;
    for (k = 0; k < a->m; ++k) {
        const ll_order *x = a->orders[k], *y = b->orders[k];
        if ((x == NULL) != (y == NULL))
            return 0;
        if (!x)
            continue;
        if (memcmp(x->seg, y->seg, (2 * x->n + 1) * sizeof *x->seg) != 0 ||
            memcmp(x->val, y->val, x->seg[2 * x->n].off * sizeof *x->val) != 0)
            return 0;
    }
    return 1;
}

static void reciprocal_build_equals_every_pair(void **state)
{
    static const double index[3][2] = { { 1.5, 0.0 }, { 1.0 / 1.5, 0.0 }, { GOLD_RE, GOLD_IM } };
    static const double alphas[2] = { 0.05, 0.3 };
    int dist, e, a, comp;
    (void)state;
    for (dist = 0; dist < 2; ++dist)
        for (e = 0; e < 3; ++e)
            for (a = 0; a < 2; ++a)
                for (comp = 0; comp < 2; ++comp) {
                    ll_layer *once = layer_on(40, 240, NULL), *every = layer_on(40, 240, NULL);
                    double worst;
                    size_t k, stored_once = 0, stored_every = 0;
                    assert_int_equal(build(once, index[e][0], index[e][1], alphas[a], dist,
                                           comp, 0),
                                     LL_OK);
                    assert_int_equal(build(every, index[e][0], index[e][1], alphas[a], dist,
                                           comp, 1),
                                     LL_OK);
                    worst = worst_difference(once, every);
                    /* The same truncation: the same entries stored. */
                    for (k = 0; k < once->m; ++k) {
                        stored_once += ll_order_stored(once->orders[k]);
                        stored_every += ll_order_stored(every->orders[k]);
                    }
                    if (worst > 1e-12 || stored_once != stored_every)
                        print_message("%s eta %g%s alpha %g compensate %d: %.3g, stored %zu "
                                      "against %zu\n",
                                      dist ? "GGX" : "Beckmann", index[e][0],
                                      index[e][1] > 0.0 ? " (gold)" : "", alphas[a], comp, worst,
                                      stored_once, stored_every);
                    assert_true(worst <= 1e-12);
                    assert_true(stored_once == stored_every);
                    ll_layer_destroy(once);
                    ll_layer_destroy(every);
                }
}

static void reciprocal_build_is_the_same_for_any_thread_count(void **state)
{
    size_t threads = ll_get_thread_count();
    ll_layer *one = layer_on(60, 300, NULL), *three = layer_on(60, 300, NULL);
    (void)state;
    assert_int_equal(ll_set_thread_count(1), LL_OK);
    assert_int_equal(build(one, 1.5, 0.0, 0.1, LL_MICROFACET_GGX, 1, 0), LL_OK);
    assert_int_equal(ll_set_thread_count(3), LL_OK);
    assert_int_equal(build(three, 1.5, 0.0, 0.1, LL_MICROFACET_GGX, 1, 0), LL_OK);
    assert_int_equal(ll_set_thread_count(threads), LL_OK);
    assert_true(same_bits(one, three));
    ll_layer_destroy(one);
    ll_layer_destroy(three);
}

/* Nodes symmetric to 1e-13 only: a pair's mirror is another pair of
 * cosines, so every pair gets its own series (the same bits as
 * every_pair), while exact mirrors do not (a different rounding). */
static void inexact_mirrors_compute_every_pair(void **state)
{
    double shift[40];
    size_t k;
    ll_layer *once, *every;
    (void)state;
    for (k = 0; k < 40; ++k)
        shift[k] = k % 3 == 1 ? 1e-13 : 0.0;
    once = layer_on(40, 120, shift);
    every = layer_on(40, 120, shift);
    assert_int_equal(build(once, 1.5, 0.0, 0.2, LL_MICROFACET_BECKMANN, 1, 0), LL_OK);
    assert_int_equal(build(every, 1.5, 0.0, 0.2, LL_MICROFACET_BECKMANN, 1, 1), LL_OK);
    assert_true(same_bits(once, every));
    ll_layer_destroy(once);
    ll_layer_destroy(every);
    once = layer_on(40, 120, NULL);
    every = layer_on(40, 120, NULL);
    assert_int_equal(build(once, 1.5, 0.0, 0.2, LL_MICROFACET_BECKMANN, 1, 0), LL_OK);
    assert_int_equal(build(every, 1.5, 0.0, 0.2, LL_MICROFACET_BECKMANN, 1, 1), LL_OK);
    assert_false(same_bits(once, every));
    ll_layer_destroy(once);
    ll_layer_destroy(every);
}

/* A 6-node order with one entry of each pair set (a fixed point among
 * them, and a run with a zero inside), mirrored with scales that tell
 * rows and columns apart: every entry as the rule says, the zero not
 * mirrored, and each run from its first to its last non-zero entry. */
static void builder_mirror_writes_each_pair_once(void **state)
{
    enum { N = 6, H = 3 };
    double set[N][N], want[N][N], column[N], row_scale[N], col_scale[N];
    ll_order_builder *b = NULL;
    ll_order *o = NULL;
    void *scratch;
    size_t r, c, half, stored = 0;
    (void)state;
    memset(set, 0, sizeof set);
    /* [col][row]: T^tb (3, 3), (3, 5) and (5, 5) with a zero at (4, 5),
     * R^t (2, 3) and its fixed point (1, 4), R^b (5, 1), T^bt (0, 2). */
    set[3][3] = 1.0;
    set[5][3] = 2.0;
    set[5][5] = 7.0;
    set[4][1] = 3.0;
    set[3][2] = 4.0;
    set[1][5] = 5.0;
    set[2][0] = 6.0;
    for (r = 0; r < N; ++r) {
        row_scale[r] = 1.0 + (double)r;
        col_scale[r] = 1.0 / (2.0 + (double)r);
    }
    memcpy(want, set, sizeof want);
    for (c = 0; c < N; ++c)
        for (r = 0; r < N; ++r) {
            size_t mr = (c + H) % N, mc = (r + H) % N; /* (M(c), M(r)) */
            if (set[c][r] != 0.0 && r != mr) {
                assert_true(set[mc][mr] == 0.0); /* (one of each pair) */
                want[mc][mr] = set[c][r] * row_scale[mr] * col_scale[mc];
            }
        }
    assert_int_equal(ll_order_builder_create(N, &b), LL_OK);
    for (c = 0; c < N; ++c)
        assert_int_equal(ll_order_builder_set_column(b, c, set[c], 0.0), LL_OK);
    scratch = malloc(ll_order_builder_mirror_bytes(N));
    assert_non_null(scratch);
    memset(scratch, 0x5a, ll_order_builder_mirror_bytes(N)); /* (contents unused) */
    assert_int_equal(ll_order_builder_mirror(b, row_scale, col_scale, scratch), LL_OK);
    free(scratch);
    for (c = 0; c < N; ++c) {
        ll_order_builder_get_column(b, c, column);
        for (r = 0; r < N; ++r)
            assert_true(column[r] == want[c][r]);
        for (half = 0; half < 2; ++half) {
            size_t lo = H, hi = 0;
            for (r = 0; r < H; ++r)
                if (want[c][half * H + r] != 0.0) {
                    lo = r < lo ? r : lo;
                    hi = r + 1;
                }
            stored += lo < hi ? hi - lo : 0;
        }
    }
    assert_int_equal(ll_order_builder_finish(b, &o), LL_OK);
    assert_non_null(o);
    assert_int_equal(ll_order_stored(o), stored);
    ll_order_release(o);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(builder_mirror_writes_each_pair_once),
        cmocka_unit_test(reciprocal_build_equals_every_pair),
        cmocka_unit_test(reciprocal_build_is_the_same_for_any_thread_count),
        cmocka_unit_test(inexact_mirrors_compute_every_pair),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
