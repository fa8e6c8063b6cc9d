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
    assert_int_equal(ll_layer_set_henyey_greenstein(*doubled, c->albedo, c->g, NULL), LL_OK);
    assert_int_equal(ll_layer_set_henyey_greenstein(*slab, c->albedo, c->g, NULL), LL_OK);
    assert_int_equal(ll_layer_expand_by(*doubled, c->tau, LL_EXPAND_DOUBLING), LL_OK);
    assert_int_equal(ll_layer_expand_by(*slab, c->tau, LL_EXPAND_SLAB), LL_OK);
}

/*
 * Doubling starts from a first-order thin layer (tau0 <= 2^-15), so it
 * carries an error of order tau0 (tau0 tau A^2 / 2 for the transport
 * matrix A): the albedos of the two methods differ by up to 3.1e-5 over
 * these cases (measured), the slab being the limit doubling converges to
 * (doubling_converges_to_slab). What must hold exactly is the slab's own
 * algebra: two slabs of tau / 2 added are the slab of tau (to rounding),
 * for absorbing to conservative media and thin to very thick slabs.
 */
static void slab_matches_doubling(void **state)
{
    static const slab_case cases[] = {
        { 16, 4, 0.5, 0.0, 1e-3 },     { 16, 4, 0.9, 0.3, 1.0 },
        { 32, 8, 0.99, 0.7, 10.0 },    { 24, 6, 0.8, 0.5, 1000.0 },
        { 32, 8, 0.999999, 0.6, 4.0 }, { 32, 8, 1.0, 0.6, 4.0 },
        { 32, 8, 1.0, 0.0, 1000.0 },   { 64, 32, 0.9, 0.9, 4.0 },
        { 48, 12, 1.0, 0.9, 1e-3 },    { 48, 12, 0.999999, -0.3, 10.0 },
    };
    size_t i;
    (void)state;
    for (i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        const slab_case *c = &cases[i];
        ll_layer *doubled, *slab, *half = ll_test_layer(c->n, c->m);
        double albedo, semigroup;
        build_pair(c, &doubled, &slab);
        albedo = largest_albedo_difference(doubled, slab);
        assert_int_equal(ll_layer_set_henyey_greenstein(half, c->albedo, c->g, NULL), LL_OK);
        assert_int_equal(ll_layer_expand_by(half, c->tau / 2, LL_EXPAND_SLAB), LL_OK);
        assert_int_equal(ll_layer_add(half, half, half, 1, NULL), LL_OK);
        semigroup = largest_difference(half, slab);
        if (!(albedo < 5e-5) || !(semigroup < 1e-9))
            fail_msg("n %zu albedo %g g %g tau %g: albedos differ from doubling's by %.3g, "
                     "slab(tau/2) + slab(tau/2) from slab(tau) by %.3g",
                     c->n, c->albedo, c->g, c->tau, albedo, semigroup);
        ll_layer_destroy(doubled);
        ll_layer_destroy(slab);
        ll_layer_destroy(half);
    }
}

/* Doubling by hand from thinner first layers (a thin layer of 2^-k, then
 * k additions to itself): its distance to the slab falls like tau0 (first
 * order: measured 1.15e-5, 7.2e-7, 4.5e-8, 5.6e-9 for k = 15, 19, 23, 27). */
static void doubling_converges_to_slab(void **state)
{
    size_t steps;
    double previous = 0.0;
    (void)state;
    for (steps = 15; steps <= 27; steps += 4) {
        ll_layer *thin = ll_test_layer(16, 4), *slab = ll_test_layer(16, 4);
        size_t d;
        double diff;
        assert_int_equal(ll_layer_set_henyey_greenstein(thin, 0.9, 0.5, NULL), LL_OK);
        assert_int_equal(ll_layer_set_henyey_greenstein(slab, 0.9, 0.5, NULL), LL_OK);
        assert_int_equal(
            ll_layer_expand_by(thin, ldexp(1.0, -(int)steps), LL_EXPAND_DOUBLING), LL_OK);
        for (d = 0; d < steps; ++d)
            assert_int_equal(ll_layer_add(thin, thin, thin, 1, NULL), LL_OK);
        assert_int_equal(ll_layer_expand_by(slab, 1.0, LL_EXPAND_SLAB), LL_OK);
        diff = largest_albedo_difference(thin, slab);
        if (steps > 15 && !(diff < previous / 8.0))
            fail_msg("tau0 = 2^-%zu: doubling is %.3g from the slab, 2^-%zu was %.3g", steps,
                     diff, steps - 4, previous);
        previous = diff;
        ll_layer_destroy(thin);
        ll_layer_destroy(slab);
    }
    assert_true(previous < 1e-8);
}

static void assert_energy_conserved(const ll_layer *l, double tol)
{
    size_t n = l->n, i;
    double *x = malloc(n * sizeof *x);
    assert_non_null(x);
    assert_int_equal(ll_layer_get_nodes(l, x, NULL), LL_OK);
    for (i = 0; i < n; ++i) {
        double R, T;
        assert_int_equal(ll_layer_albedo(l, x[i], &R, &T), LL_OK);
        if (!(fabs(R + T - 1.0) <= tol))
            fail_msg("mu_i = %g: R + T = %.15f", x[i], R + T);
    }
    free(x);
}

/* Conservative media (order 0 has the eigenvalue k = 0) from thin to very
 * thick: energy to rounding, no overflow at tau = 1000, and the thick slab
 * follows the Milne law T (tau + 2 q0) = const (van de Hulst 1980). */
static void conservative_slabs_keep_energy(void **state)
{
    static const double taus[] = { 1e-3, 1.0, 10.0, 100.0, 1000.0 };
    double T[5];
    size_t i;
    (void)state;
    for (i = 0; i < 5; ++i) {
        ll_layer *l = ll_test_layer(32, 4);
        assert_int_equal(ll_layer_set_henyey_greenstein(l, 1.0, 0.6, NULL), LL_OK);
        assert_int_equal(ll_layer_expand_by(l, taus[i], LL_EXPAND_SLAB), LL_OK);
        assert_energy_conserved(l, 1e-9);
        assert_int_equal(ll_layer_albedo(l, 1.0, NULL, &T[i]), LL_OK);
        ll_layer_destroy(l);
    }
    /* q0 for g = 0.6 in similarity: (tau + 2 q0) (1 - g) scales out. */
    assert_float_equal(T[4] * (1000.0 * 0.4 + 1.4209), T[3] * (100.0 * 0.4 + 1.4209), 2e-4);
    /* A nearly conservative slab lies next to the conservative one. */
    {
        ll_layer *a = ll_test_layer(32, 4), *b = ll_test_layer(32, 4);
        assert_int_equal(ll_layer_set_henyey_greenstein(a, 1.0, 0.6, NULL), LL_OK);
        assert_int_equal(ll_layer_set_henyey_greenstein(b, 0.999999, 0.6, NULL), LL_OK);
        assert_int_equal(ll_layer_expand_by(a, 10.0, LL_EXPAND_SLAB), LL_OK);
        assert_int_equal(ll_layer_expand_by(b, 10.0, LL_EXPAND_SLAB), LL_OK);
        assert_true(largest_albedo_difference(a, b) < 1e-4);
        ll_layer_destroy(a);
        ll_layer_destroy(b);
    }
}

/* The slab is computed per order with single-threaded LAPACK: the same bits
 * for any thread count. */
static void slab_does_not_depend_on_thread_count(void **state)
{
    ll_layer *l[3];
    size_t t;
    (void)state;
    for (t = 0; t < 3; ++t) {
        assert_int_equal(ll_set_thread_count(t + 1), LL_OK);
        l[t] = ll_test_layer(40, 24);
        assert_int_equal(ll_layer_set_henyey_greenstein(l[t], 0.95, 0.8, NULL), LL_OK);
        assert_int_equal(ll_layer_expand_by(l[t], 3.0, LL_EXPAND_SLAB), LL_OK);
    }
    assert_int_equal(ll_set_thread_count(0), LL_OK);
    assert_true(largest_difference(l[0], l[1]) == 0.0);
    assert_true(largest_difference(l[0], l[2]) == 0.0);
    for (t = 0; t < 3; ++t)
        ll_layer_destroy(l[t]);
}

/* ll_layer_expand picks by the cost model: a slab that needs doublings
 * goes by the closed form, so it equals the forced slab bit for bit. */
static void expand_uses_the_cheaper_method(void **state)
{
    ll_layer *a = ll_test_layer(64, 8), *b = ll_test_layer(64, 8);
    (void)state;
    assert_int_equal(ll_layer_set_henyey_greenstein(a, 0.9, 0.5, NULL), LL_OK);
    assert_int_equal(ll_layer_set_henyey_greenstein(b, 0.9, 0.5, NULL), LL_OK);
    assert_int_equal(ll_layer_expand(a, 2.0, NULL), LL_OK);
    assert_int_equal(ll_layer_expand_by(b, 2.0, LL_EXPAND_SLAB), LL_OK);
    assert_true(largest_difference(a, b) == 0.0);
    ll_layer_destroy(a);
    ll_layer_destroy(b);
}

/* The one-pass medium (phase matrix straight into the slab, slab_medium.c)
 * is the two-step one with the slab, bit for bit, for each phase function;
 * where the cost model keeps doubling it declines and leaves the layer. */
static void one_pass_medium_is_the_two_steps(void **state)
{
    static const struct { ll_medium_kind kind; double shape; } phases[] = {
        { LL_MEDIUM_HG, 0.85 }, { LL_MEDIUM_VMF, 12.0 }, { LL_MEDIUM_ISOTROPIC, 0.0 } };
    size_t i;
    (void)state;
    for (i = 0; i < 3; ++i) {
        ll_layer *one = ll_test_layer(48, 64), *two = ll_test_layer(48, 64);
        int done = 0;
        assert_int_equal(ll_layer_set_medium_slab(one, phases[i].kind, 0.97, phases[i].shape,
                                                  2.5, NULL, &done), LL_OK);
        assert_true(done);
        assert_int_equal(ll_layer_set_medium_finished(two, phases[i].kind, 0.97,
                                                      phases[i].shape, NULL, NULL), LL_OK);
        assert_int_equal(ll_layer_expand_by(two, 2.5, LL_EXPAND_SLAB), LL_OK);
        assert_true(largest_difference(one, two) == 0.0);
        ll_layer_destroy(one);
        ll_layer_destroy(two);
    }
    {
        ll_layer *l = ll_test_layer(16, 2);
        int done = 1;
        assert_int_equal(ll_layer_set_medium_slab(l, LL_MEDIUM_HG, 0.9, 0.5, 1e-4, NULL, &done),
                         LL_OK);
        assert_false(done);
        ll_layer_destroy(l);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(slab_matches_doubling),
        cmocka_unit_test(doubling_converges_to_slab),
        cmocka_unit_test(conservative_slabs_keep_energy),
        cmocka_unit_test(slab_does_not_depend_on_thread_count),
        cmocka_unit_test(expand_uses_the_cheaper_method),
        cmocka_unit_test(one_pass_medium_is_the_two_steps),
    };
    return cmocka_run_group_tests_name("slab", tests, NULL, NULL);
}
