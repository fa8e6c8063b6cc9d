/*
 * Near normal incidence: the directional albedo of the original's
 * coated-gold-with-scatmedium recipe at mu_i = 1, 0.999, 0.99, 0.9 against
 * references that share no code with the library (tests/reference/):
 *  - the HG medium alone against a discrete-ordinate solution on its own
 *    double-Gauss nodes, the beam a column of its own (no spline);
 *  - the two references against each other (the medium under a smooth
 *    Fresnel boundary, where both apply);
 *  - the whole stack, per channel, against a Monte Carlo run of 3 10^7 paths
 *    per cosine (scripts/normal_incidence_reference.sh; its numbers are
 *    below and a short run here checks that the program in the tree still
 *    gives them), through ll_layer_albedo, the integral of ll_layer_eval
 *    and the integral of the written .bsdf file's ll_bsdf_eval.
 * The original's albedo at mu_i = 1 (R 0.4095, as the issue quotes it) is
 * 16 standard errors below the Monte Carlo; ours must stay within 4.
 */
#include "test_util.h"

#define DO_SLAB_NO_MAIN
#include "reference/do_slab.c"
#define MC_STACK_NO_MAIN
#include "reference/mc_stack.c"

#define N_NODES 196  /* the original recipe's resolution (bench/recipe.c) */
#define N_ORDERS 267
#define N_MU 4

static const double MUS[N_MU] = { 1.0, 0.999, 0.99, 0.9 };

/* Gold's per-channel index as the original recipe computes it. */
static const double GOLD_ETA[3] = { 0.14317534881908534, 0.37309576813050427,
                                    1.4438276243071315 };
static const double GOLD_K[3] = { 3.9826674681176435, 2.3874442318808597, 1.6024561077023662 };
static const double MEDIUM_ALBEDO[3] = { 0.25, 0.0, 0.95 };

/* The precise Monte Carlo (scripts/normal_incidence_reference.sh 3e7: 3 10^7
 * paths per cosine and channel, seed 20261202): R and its standard error.
 * Ours was within 2.4 standard errors of it at each of the 12 points when
 * it was run; the original's R at mu_i = 1 (0.4095) is 16 below, its B
 * (0.2570) 26 below. */
static const double MC_R[3][N_MU] = { { 0.4108204, 0.4106572, 0.4091889, 0.3923559 },
                                      { 0.3122699, 0.3120227, 0.3111174, 0.2980476 },
                                      { 0.2581264, 0.2581478, 0.2578124, 0.2544102 } };
static const double MC_SE[3][N_MU] = { { 8.12e-5, 8.12e-5, 8.12e-5, 8.10e-5 },
                                       { 7.32e-5, 7.32e-5, 7.32e-5, 7.28e-5 },
                                       { 4.23e-5, 4.23e-5, 4.24e-5, 4.33e-5 } };

static ll_layer *medium_slab(size_t n, size_t m, double albedo)
{
    ll_layer *l = ll_test_layer(n, m);
    assert_int_equal(ll_layer_set_henyey_greenstein(l, albedo, 0.5, NULL), LL_OK);
    assert_int_equal(ll_layer_expand(l, 0.5, NULL), LL_OK);
    return l;
}

/* The medium alone: ours (Lobatto nodes, delta-M phase matrices, doubling,
 * the spline between nodes) against discrete ordinates. Measured: within
 * 1.2e-6 in R and 3.5e-6 in T at every cosine, the same offset inside the
 * last intervals as at 0.9; the bound is 2e-5. */
static void test_medium_alone_vs_discrete_ordinates(void **state)
{
    static const double albedos[2] = { 0.25, 0.95 };
    /* Also inside the last two node intervals (0.99981 .. 1, 0.99936 ..
     * 0.99981), where the spline's one-sided end condition applies. */
    static const double mus[6] = { 1.0, 0.9999, 0.9995, 0.999, 0.99, 0.9 };
    int a, j;
    (void)state;
    for (a = 0; a < 2; ++a) {
        ll_layer *l = medium_slab(N_NODES, 1, albedos[a]);
        for (j = 0; j < 6; ++j) {
            double r, t, r_ref, t_ref;
            assert_int_equal(ll_layer_albedo(l, mus[j], &r, &t), LL_OK);
            assert_true(do_slab_albedo(albedos[a], 0.5, 0.5, 1.0, 48, mus[j], &r_ref, &t_ref));
            printf("medium a=%g mu_i=%g: R %.7f / %.7f, T %.7f / %.7f\n", albedos[a], mus[j], r,
                   r_ref, t, t_ref);
            assert_true(fabs(r - r_ref) < 2e-5);
            assert_true(fabs(t - t_ref) < 2e-5);
        }
        ll_layer_destroy(l);
    }
}

/* The Monte Carlo against discrete ordinates where both apply: the medium
 * under a smooth eta = 1.5 boundary, nothing below. 2^20 paths. */
static void test_references_agree(void **state)
{
    stack st = { { 1.5, 0.0, 0.0 }, 0.95, 0.5, 0.5, 0, { 1.0, 0.0, 0.0 }, 0.0 };
    double r, se_r, t, se_t, r_ref, t_ref;
    (void)state;
    assert_true(do_slab_albedo(0.95, 0.5, 0.5, 1.5, 48, 1.0, &r_ref, &t_ref));
    mc_albedo(&st, 1.0, 1 << 20, 5, 0, &r, &se_r, &t, &se_t);
    printf("smooth boundary over the medium, mu_i = 1: R %.6f +- %.6f / %.7f, T %.6f +- %.6f / "
           "%.7f\n", r, se_r, r_ref, t, se_t, t_ref);
    assert_true(se_r > 0.0 && se_r < 5e-4);
    assert_true(fabs(r - r_ref) < 4.5 * se_r);
    assert_true(fabs(t - t_ref) < 4.5 * se_t);
}

static ll_layer *recipe_channel(const ll_layer *coat, int c)
{
    ll_layer *base = ll_test_layer(N_NODES, N_ORDERS), *medium;
    assert_int_equal(ll_test_set_microfacet(base, GOLD_ETA[c], GOLD_K[c], 0.1, 0, 0, NULL), LL_OK);
    medium = medium_slab(N_NODES, N_ORDERS, MEDIUM_ALBEDO[c]);
    assert_int_equal(ll_layer_add_to_top(base, medium), LL_OK);
    ll_layer_destroy(medium);
    assert_int_equal(ll_layer_add_to_top(base, coat), LL_OK);
    return base;
}

/* The reflected fraction by integrating f |mu_o| over the upper hemisphere:
 * Gauss-Legendre in mu_o, the trapezoid rule in phi (exact for the cosine
 * series: more points than orders). */
#define INT_MU 200
#define INT_PHI 300
static void hemisphere_integrals(const ll_layer *const *layers, const ll_bsdf *b, double mu_i,
                                 double *from_layer, double *from_file)
{
    double x[2 * INT_MU], w[2 * INT_MU];
    int a, p, c;
    assert_int_equal(ll_quad_gauss_legendre(2 * INT_MU, x, w, NULL), LL_OK);
    for (c = 0; c < 3; ++c)
        from_layer[c] = from_file[c] = 0.0;
    for (a = INT_MU; a < 2 * INT_MU; ++a) {
        for (p = 0; p < INT_PHI; ++p) {
            double phi = 2.0 * LL_PI * p / INT_PHI, rgb[3], wt = w[a] * x[a] * 2.0 * LL_PI / INT_PHI;
            assert_int_equal(ll_bsdf_eval(b, mu_i, -x[a], phi, NULL, rgb), LL_OK);
            for (c = 0; c < 3; ++c) {
                from_layer[c] += wt * ll_test_layer_eval(layers[c], mu_i, -x[a], phi);
                from_file[c] += wt * rgb[c];
            }
        }
    }
}

static void test_stack_vs_monte_carlo(void **state)
{
    ll_layer *coat = ll_test_layer(N_NODES, N_ORDERS), *channels[3];
    char dir[256], path[300];
    ll_bsdf *b = NULL;
    int c, j;
    (void)state;
    assert_int_equal(ll_test_set_microfacet(coat, 1.5, 0.0, 0.1, 0, 0, NULL), LL_OK);
    for (c = 0; c < 3; ++c)
        channels[c] = recipe_channel(coat, c);
    ll_layer_destroy(coat);
    ll_test_mkdtemp(dir, sizeof dir);
    snprintf(path, sizeof path, "%s/coated-gold-medium.bsdf", dir);
    assert_int_equal(ll_bsdf_write(path, (const ll_layer *const *)channels, 3, NULL, NULL), LL_OK);
    assert_int_equal(ll_bsdf_open(path, NULL, &b), LL_OK);

    for (j = 0; j < N_MU; ++j) {
        double from_layer[3], from_file[3];
        /* The integrals only where the spline in mu_i matters (not at the
         * node mu = 1) and once at the node, to keep the test short. */
        int integrate = j < 2;
        if (integrate)
            hemisphere_integrals((const ll_layer *const *)channels, b, MUS[j], from_layer,
                                 from_file);
        for (c = 0; c < 3; ++c) {
            double r;
            assert_int_equal(ll_layer_albedo(channels[c], MUS[j], &r, NULL), LL_OK);
            printf("stack channel %d mu_i=%g: ll_layer_albedo %.6f", c, MUS[j], r);
            if (integrate)
                printf(", eval integral %.6f, .bsdf integral %.6f", from_layer[c], from_file[c]);
            printf("; Monte Carlo %.6f +- %.6f\n", MC_R[c][j], MC_SE[c][j]);
            assert_true(MC_SE[c][j] > 0.0 && MC_SE[c][j] < 1e-4);
            assert_true(fabs(r - MC_R[c][j]) < 4.0 * MC_SE[c][j]);
            if (integrate) {
                assert_true(fabs(from_layer[c] - r) < 1e-5);
                assert_true(fabs(from_file[c] - r) < 1e-5);
            }
        }
    }
    ll_bsdf_release(b);
    unlink(path);
    rmdir(dir);
    for (c = 0; c < 3; ++c)
        ll_layer_destroy(channels[c]);
}

/* The Monte Carlo program in the tree still gives the stored numbers: a
 * short run of the R and B channels at mu_i = 1 (2^20 paths each). */
static void test_monte_carlo_reproduces(void **state)
{
    int c;
    (void)state;
    for (c = 0; c < 3; c += 2) {
        stack st = { { 1.5, 0.0, 0.1 }, MEDIUM_ALBEDO[c], 0.5, 0.5, 1,
                     { GOLD_ETA[c], GOLD_K[c], 0.1 }, 0.0 };
        double r, se_r, t, se_t;
        mc_albedo(&st, 1.0, 1 << 20, 11, (uint64_t)c, &r, &se_r, &t, &se_t);
        printf("short Monte Carlo channel %d mu_i = 1: %.5f +- %.5f (stored %.6f)\n", c, r, se_r,
               MC_R[c][0]);
        assert_true(fabs(r - MC_R[c][0]) < 4.5 * sqrt(se_r * se_r + MC_SE[c][0] * MC_SE[c][0]));
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_medium_alone_vs_discrete_ordinates),
        cmocka_unit_test(test_references_agree),
        cmocka_unit_test(test_stack_vs_monte_carlo),
        cmocka_unit_test(test_monte_carlo_reproduces),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
