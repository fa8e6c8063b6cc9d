/*
 * The closed-form slab (src/grammar/slab.c) against doubling, the
 * reference: the same matrices, order by order, over thin to very thick
 * slabs, absorbing to conservative media and isotropic to peaked phase
 * functions; and the properties that need no reference (energy, the
 * thick-slab limit).
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <layerlab.h>
#include "grammar/grammar.h"
#include "layer/layer.h"
#include "test_util.h"

typedef struct slab_case {
    size_t n, m;
    double albedo, g, tau;
} slab_case;

/* Largest |a - b| over every entry of every order, in BSDF units (the
 * weights removed as ll_layer_matrix does). */
static double largest_difference(const ll_layer *a, const ll_layer *b)
{
    size_t n = a->n, k, i;
    double *A = malloc(n * n * sizeof *A), *B = malloc(n * n * sizeof *B), worst = 0.0;
    assert_non_null(A);
    assert_non_null(B);
    for (k = 0; k < a->m; ++k) {
        assert_int_equal(ll_layer_matrix(a, k, A), LL_OK);
        assert_int_equal(ll_layer_matrix(b, k, B), LL_OK);
        for (i = 0; i < n * n; ++i)
            worst = fmax(worst, fabs(A[i] - B[i]));
    }
    free(A);
    free(B);
    return worst;
}

/* Largest difference of the albedos (R and T, ll_layer_albedo) at every
 * node: what the energy tests and the cross-checks read. */
static double largest_albedo_difference(const ll_layer *a, const ll_layer *b)
{
    size_t n = a->n, i;
    double *x = malloc(n * sizeof *x), worst = 0.0;
    assert_non_null(x);
    assert_int_equal(ll_layer_get_nodes(a, x, NULL), LL_OK);
    for (i = 0; i < n; ++i) {
        double Ra, Ta, Rb, Tb;
        assert_int_equal(ll_layer_albedo(a, x[i], &Ra, &Ta), LL_OK);
        assert_int_equal(ll_layer_albedo(b, x[i], &Rb, &Tb), LL_OK);
        worst = fmax(worst, fmax(fabs(Ra - Rb), fabs(Ta - Tb)));
    }
    free(x);
    return worst;
}

static void build_pair(const slab_case *c, ll_layer **doubled, ll_layer **slab)
{
    *doubled = ll_test_layer(c->n, c->m);
    *slab = ll_test_layer(c->n, c->m);
    assert_int_equal(ll_layer_set_henyey_greenstein(*doubled, c->albedo, c->g), LL_OK);
    assert_int_equal(ll_layer_set_henyey_greenstein(*slab, c->albedo, c->g), LL_OK);
    assert_int_equal(ll_layer_expand_by(*doubled, c->tau, LL_EXPAND_DOUBLING), LL_OK);
    assert_int_equal(ll_layer_expand_by(*slab, c->tau, LL_EXPAND_SLAB), LL_OK);
}

static void slab_matches_doubling(void **state)
{
    static const slab_case cases[] = {
        { 16, 4, 0.5, 0.0, 1e-3 },   { 16, 4, 0.9, 0.3, 1.0 },
        { 32, 8, 0.99, 0.7, 10.0 },  { 24, 6, 0.8, 0.5, 1000.0 },
        { 32, 8, 0.999999, 0.6, 4.0 }, { 32, 8, 1.0, 0.6, 4.0 },
        { 32, 8, 1.0, 0.0, 1000.0 }, { 64, 32, 0.9, 0.9, 4.0 },
        { 48, 12, 1.0, 0.9, 1e-3 },  { 48, 12, 0.999999, -0.3, 10.0 },
    };
    size_t i;
    (void)state;
    for (i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        ll_layer *doubled, *slab;
        double d;
        build_pair(&cases[i], &doubled, &slab);
        d = largest_difference(doubled, slab);
        printf("n %zu albedo %.6f g %.2f tau %g: max |slab - doubling| = %.3g, albedo %.3g\n", cases[i].n,
               cases[i].albedo, cases[i].g, cases[i].tau, d, largest_albedo_difference(doubled, slab));
        {
            ll_layer *half = ll_test_layer(cases[i].n, cases[i].m);
            assert_int_equal(ll_layer_set_henyey_greenstein(half, cases[i].albedo, cases[i].g), LL_OK);
            assert_int_equal(ll_layer_expand_by(half, cases[i].tau / 2, LL_EXPAND_SLAB), LL_OK);
            assert_int_equal(ll_layer_add(half, half, half, 1), LL_OK);
            printf("   semigroup %.3g\n", largest_difference(half, slab));
            ll_layer_destroy(half);
        }
        ll_layer_destroy(doubled);
        ll_layer_destroy(slab);
    }
}

static void doubling_converges_to_slab(void **state)
{
    size_t steps;
    (void)state;
    for (steps = 15; steps <= 27; steps += 4) {
        ll_layer *thin = ll_test_layer(16, 4), *slab = ll_test_layer(16, 4);
        size_t d;
        assert_int_equal(ll_layer_set_henyey_greenstein(thin, 0.9, 0.5), LL_OK);
        assert_int_equal(ll_layer_set_henyey_greenstein(slab, 0.9, 0.5), LL_OK);
        assert_int_equal(ll_layer_expand_by(thin, ldexp(1.0, -(int)steps), LL_EXPAND_DOUBLING), LL_OK);
        for (d = 0; d < steps; ++d)
            assert_int_equal(ll_layer_add(thin, thin, thin, 1), LL_OK);
        assert_int_equal(ll_layer_expand_by(slab, 1.0, LL_EXPAND_SLAB), LL_OK);
        printf("tau0 2^-%zu: %.3g albedo %.3g\n", steps, largest_difference(thin, slab), largest_albedo_difference(thin, slab));
        ll_layer_destroy(thin);
        ll_layer_destroy(slab);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(slab_matches_doubling),
        cmocka_unit_test(doubling_converges_to_slab),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
