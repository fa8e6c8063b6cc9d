/*
 * GGX interfaces in the material language: dist=ggx builds the GGX layer
 * (dielectric, conductor, a swept alpha), dist=beckmann and the default
 * build what they always did, and the resolution search evaluates the GGX
 * model when the word is GGX.
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
#include "words/microfacet.h"
#include "search/probe.h"

#define GOLD_RE 0.2
#define GOLD_IM 3.5

static ll_material *parse(const char *text)
{
    ll_material *m = NULL;
    if (ll_material_parse(text, "t", &m) != LL_OK)
        fail_msg("%s", ll_last_error_message());
    return m;
}

/* One channel at a fixed resolution. */
static ll_layer *build_one(const char *text, size_t nodes, size_t orders)
{
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    ll_layer *layers[3] = { NULL, NULL, NULL };
    ll_material *m = parse(text);
    size_t n = 0;
    o.n_nodes = nodes;
    o.n_orders = orders;
    o.n_channels = 1;
    if (ll_material_build_layers(m, &o, NULL, layers, &n, NULL) != LL_OK)
        fail_msg("build: %s", ll_last_error_message());
    assert_int_equal(n, 1);
    ll_material_destroy(m);
    return layers[0];
}

/* The interface made directly on the nodes of `like`. */
static ll_layer *direct(const ll_layer *like, double eta_re, double eta_im, double alpha,
                        int distribution)
{
    ll_layer *l = ll_test_layer_like(like);
    assert_int_equal(ll_test_set_microfacet_dist(l, eta_re, eta_im, alpha, distribution,
                                                          1, 0, NULL),
                     LL_OK);
    return l;
}

/* Largest |a - b| over every order, relative to the largest |b|. */
static double difference(const ll_layer *a, const ll_layer *b)
{
    size_t n = ll_layer_node_count(a), m = ll_layer_order_count(a), k, j;
    double *A = malloc(n * n * sizeof *A), *B = malloc(n * n * sizeof *B), diff = 0.0,
           scale = 0.0;
    assert_non_null(A);
    assert_non_null(B);
    assert_int_equal(ll_layer_node_count(b), n);
    assert_int_equal(ll_layer_order_count(b), m);
    for (k = 0; k < m; ++k) {
        assert_int_equal(ll_layer_matrix(a, k, A), LL_OK);
        assert_int_equal(ll_layer_matrix(b, k, B), LL_OK);
        for (j = 0; j < n * n; ++j) {
            diff = fmax(diff, fabs(A[j] - B[j]));
            scale = fmax(scale, fabs(B[j]));
        }
    }
    free(A);
    free(B);
    return scale > 0.0 ? diff / scale : diff;
}

static void ggx_words_build_the_ggx_interface(void **state)
{
    ll_layer *built, *ggx, *beckmann;
    (void)state;
    built = build_one("dielectric eta=1.5 alpha=0.3 dist=ggx\n", 60, 40);
    ggx = direct(built, 1.5, 0.0, 0.3, LL_DISTRIBUTION_GGX);
    beckmann = direct(built, 1.5, 0.0, 0.3, LL_DISTRIBUTION_BECKMANN);
    assert_true(difference(built, ggx) == 0.0);
    assert_true(difference(built, beckmann) > 0.01);
    ll_layer_destroy(built);
    ll_layer_destroy(ggx);
    ll_layer_destroy(beckmann);

    built = build_one("conductor eta=0.2+3.5i alpha=0.2 dist=ggx\n", 40, 60);
    ggx = direct(built, 0.2, 3.5, 0.2, LL_DISTRIBUTION_GGX);
    assert_true(difference(built, ggx) == 0.0);
    ll_layer_destroy(built);
    ll_layer_destroy(ggx);
}

static void default_and_beckmann_build_as_before(void **state)
{
    ll_layer *plain, *named, *beckmann;
    (void)state;
    plain = build_one("dielectric eta=1.5 alpha=0.3\n", 60, 40);
    named = build_one("dielectric eta=1.5 alpha=0.3 dist=beckmann\n", 60, 40);
    beckmann = direct(plain, 1.5, 0.0, 0.3, LL_DISTRIBUTION_BECKMANN);
    assert_true(difference(plain, named) == 0.0);
    assert_true(difference(plain, beckmann) == 0.0);
    ll_layer_destroy(plain);
    ll_layer_destroy(named);
    ll_layer_destroy(beckmann);
}

/* A swept GGX alpha: each basis is the GGX interface of its alpha. */
static void swept_alpha_builds_ggx(void **state)
{
    static const double alphas[] = { 0.2, 0.4 };
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    ll_material *m = parse("dielectric eta=1.5 alpha=[0.2 0.4] dist=ggx\n");
    ll_material_builder *b = NULL;
    size_t basis;
    (void)state;
    o.n_nodes = 50;
    o.n_orders = 30;
    o.n_channels = 1;
    assert_int_equal(ll_material_builder_create(m, &o, NULL, &b), LL_OK);
    for (basis = 0; basis < 2; ++basis) {
        ll_layer *layers[3] = { NULL, NULL, NULL }, *ggx;
        size_t n = 0;
        assert_int_equal(ll_material_builder_build_basis(b, basis, layers, &n, NULL), LL_OK);
        assert_int_equal(n, 1);
        ggx = direct(layers[0], 1.5, 0.0, alphas[basis], LL_DISTRIBUTION_GGX);
        assert_true(difference(layers[0], ggx) == 0.0);
        ll_layer_destroy(layers[0]);
        ll_layer_destroy(ggx);
    }
    ll_material_builder_destroy(b);
    ll_material_destroy(m);
}

/* The search of a GGX word verifies the GGX interface: at the resolution
 * it chooses, the GGX model at the probes is within the tolerance of the
 * GGX model at twice that resolution, which the Beckmann resolution is not
 * (GGX's tails need more). Beckmann's search is the one it always was. */
static double probe_error(ll_microfacet_model *mf, ll_microfacet_model *mf0, const ll_probe_set *set,
                          size_t n, size_t m)
{
    double *lo = malloc(LL_PROBE_VALUES(set) * sizeof *lo);
    double *hi = malloc(LL_PROBE_VALUES(set) * sizeof *hi), e;
    ll_probe_compensation c_lo, c_hi;
    assert_non_null(lo);
    assert_non_null(hi);
    assert_int_equal(ll_probe_compensation_make(mf0, GOLD_RE, GOLD_IM, n, NULL, &c_lo), LL_OK);
    assert_int_equal(ll_probe_compensation_make(mf0, GOLD_RE, GOLD_IM, 2 * n, NULL, &c_hi),
                     LL_OK);
    assert_int_equal(ll_probe_interface_eval(mf, &c_lo, n, m, set, NULL, lo), LL_OK);
    assert_int_equal(ll_probe_interface_eval(mf, &c_hi, 2 * n, 2 * m, set, NULL, hi), LL_OK);
    e = ll_probe_error(set, lo, hi);
    ll_probe_compensation_free(&c_lo);
    ll_probe_compensation_free(&c_hi);
    free(lo);
    free(hi);
    return e;
}

static void search_resolves_the_ggx_interface(void **state)
{
    const double alpha = 0.3, tolerance = 0.01, mu_min = 0.1;
    size_t n, m, n_b, m_b, n0, m0;
    double error, error_b, e0, at_own, at_beckmann;
    ll_probe_set set;
    ll_microfacet_model *mf, *mf0;
    (void)state;
    assert_int_equal(ll_search_microfacet_distribution(alpha, GOLD_RE, GOLD_IM,
                                                       LL_DISTRIBUTION_GGX, 1, tolerance,
                                                       mu_min, NULL, &n, &m, &error),
                     LL_OK);
    assert_int_equal(ll_search_microfacet_distribution(alpha, GOLD_RE, GOLD_IM,
                                                       LL_DISTRIBUTION_BECKMANN, 1, tolerance,
                                                       mu_min, NULL, &n_b, &m_b, &error_b),
                     LL_OK);
    assert_int_equal(ll_search_microfacet(alpha, GOLD_RE, GOLD_IM, 1, tolerance, mu_min, NULL,
                                          &n0, &m0, &e0),
                     LL_OK);
    assert_int_equal(n0, n_b);
    assert_int_equal(m0, m_b);
    assert_true(error <= tolerance);

    assert_int_equal(ll_probe_interface(GOLD_RE, GOLD_IM, mu_min, &set), LL_OK);
    assert_int_equal(ll_probe_interface_model_distribution(GOLD_RE, GOLD_IM, alpha,
                                                           LL_DISTRIBUTION_GGX, &mf),
                     LL_OK);
    assert_int_equal(ll_probe_compensation_model_distribution(GOLD_RE, GOLD_IM, alpha,
                                                              LL_DISTRIBUTION_GGX, &mf0),
                     LL_OK);
    at_own = probe_error(mf, mf0, &set, n, m);
    at_beckmann = probe_error(mf, mf0, &set, n_b, m_b);
    print_message("gold alpha %.1f: GGX chooses %zu x %zu (error %.4f, %.4f again), Beckmann "
                  "%zu x %zu (%.4f), where GGX errs by %.4f\n",
                  alpha, n, m, error, at_own, n_b, m_b, error_b, at_beckmann);
    assert_float_equal(at_own, error, 1e-12);
    assert_true(at_beckmann > tolerance);
    ll_microfacet_destroy(mf);
    ll_microfacet_destroy(mf0);
    ll_probe_free(&set);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(ggx_words_build_the_ggx_interface),
        cmocka_unit_test(default_and_beckmann_build_as_before),
        cmocka_unit_test(swept_alpha_builds_ggx),
        cmocka_unit_test(search_resolves_the_ggx_interface),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
