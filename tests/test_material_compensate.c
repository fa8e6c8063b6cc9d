/*
 * The material language's compensate=0 (docs/material-language.md): a
 * dielectric or conductor built with it is the interface of
 * ll_layer_set_microfacet without energy compensation, exactly; without the
 * key (or with compensate=1) it is the compensated one; other values and
 * other words are refused by name.
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
#include "test_util.h"

/* The first channel's layer of a one-word material at a small resolution. */
static ll_layer *build_word(const char *text)
{
    ll_material *m = NULL;
    ll_build_options opts = LL_BUILD_OPTIONS_INIT;
    ll_layer *layers[3] = { NULL, NULL, NULL };
    size_t channels = 0, c;
    opts.n_nodes = 24;
    opts.n_orders = 12;
    opts.threads = 1;
    if (ll_material_parse(text, "<test>", &m) != LL_OK)
        fail_msg("%s: %s", text, ll_last_error_message());
    if (ll_material_build_layers(m, &opts, NULL, layers, &channels, NULL) != LL_OK)
        fail_msg("%s: %s", text, ll_last_error_message());
    for (c = 1; c < channels; ++c)
        ll_layer_destroy(layers[c]);
    ll_material_destroy(m);
    return layers[0];
}

/* The same interface made directly, on the same nodes. */
static ll_layer *direct(const ll_layer *like, double eta_re, double eta_im, double alpha,
                        int conserve)
{
    ll_layer *l = ll_test_layer_like(like);
    assert_int_equal(ll_test_set_microfacet(l, eta_re, eta_im, alpha, conserve, 0, NULL), LL_OK);
    return l;
}

/* Largest |a - b| over a grid of direction pairs, and the largest |a|. */
static double max_difference(const ll_layer *a, const ll_layer *b, double *peak)
{
    double worst = 0.0;
    int i, o, p;
    *peak = 0.0;
    for (i = 0; i < 9; ++i)
        for (o = 0; o < 9; ++o)
            for (p = 0; p < 3; ++p) {
                double mu_i = 0.1 + 0.1125 * i, mu_o = -(0.1 + 0.1125 * o) * (o % 2 ? 1 : -1);
                double fa = ll_test_layer_eval(a, mu_i, mu_o, 1.3 * p);
                double fb = ll_test_layer_eval(b, mu_i, mu_o, 1.3 * p);
                worst = fmax(worst, fabs(fa - fb));
                *peak = fmax(*peak, fabs(fa));
            }
    return worst;
}

static void check_word(const char *plain, const char *off, const char *on, double eta_re,
                       double eta_im, double alpha)
{
    ll_layer *l_off = build_word(off), *l_on = build_word(on), *l_plain = build_word(plain);
    ll_layer *d_off = direct(l_off, eta_re, eta_im, alpha, 0);
    ll_layer *d_on = direct(l_off, eta_re, eta_im, alpha, 1);
    double peak, diff;
    assert_true(max_difference(l_off, d_off, &peak) == 0.0);
    assert_true(max_difference(l_on, d_on, &peak) == 0.0);
    assert_true(max_difference(l_plain, d_on, &peak) == 0.0);
    /* At alpha 0.6 the compensation is visible: the check can tell. */
    diff = max_difference(l_off, l_on, &peak);
    assert_true(diff > 1e-3 * peak);
    ll_layer_destroy(l_off);
    ll_layer_destroy(l_on);
    ll_layer_destroy(l_plain);
    ll_layer_destroy(d_off);
    ll_layer_destroy(d_on);
}

static void dielectric_without_compensation(void **state)
{
    (void)state;
    check_word("dielectric eta=1.5 alpha=0.6", "dielectric eta=1.5 alpha=0.6 compensate=0",
               "dielectric eta=1.5 alpha=0.6 compensate=1", 1.5, 0.0, 0.6);
}

static void conductor_without_compensation(void **state)
{
    (void)state;
    check_word("conductor eta=0.2+3.9i alpha=0.6",
               "conductor eta=0.2+3.9i alpha=0.6 compensate=0",
               "conductor eta=0.2+3.9i alpha=0.6 compensate=1", 0.2, 3.9, 0.6);
}

static void refused(const char *text, const char *expect)
{
    ll_material *m = NULL;
    assert_int_not_equal(ll_material_parse(text, "<test>", &m), LL_OK);
    assert_null(m);
    if (!strstr(ll_last_error_message(), expect))
        fail_msg("%s: message '%s' lacks '%s'", text, ll_last_error_message(), expect);
}

static void bad_values_are_refused(void **state)
{
    (void)state;
    refused("conductor eta=0.2+3.9i alpha=0.2 compensate=2", "compensate is 1");
    refused("dielectric eta=1.5 alpha=0.2 compensate=0,1,0", "compensate is 1");
    refused("medium albedo=0.5 tau=1 compensate=0", "no parameter 'compensate'");
    refused("diffuse albedo=0.5 compensate=0", "no parameter 'compensate'");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(dielectric_without_compensation),
        cmocka_unit_test(conductor_without_compensation),
        cmocka_unit_test(bad_values_are_refused),
    };
    return cmocka_run_group_tests_name("material_compensate", tests, NULL, NULL);
}
