/*
 * GGX coats, as pbrt-v4's layered materials have them (coatedconductor,
 * coateddiffuse), against the Monte Carlo reference that shares no code
 * with the library (tests/reference/mc_stack.c, -D ggx): a GGX dielectric
 * of index 1.5 without the energy compensation over a Lambertian base of
 * albedo 0.5, and over gold (GGX), at alpha 0.1 and 0.3. The directional
 * albedo of our adding (ll_layer_albedo) must be within 4 standard errors
 * of the walk (plus 2e-4 for the discretisation) at mu_i = 1, 0.7, 0.5.
 *
 * A point value: f of the GGX coat (alpha 0.1) over the Lambertian base
 * with light and view along the same direction (mu 0.8), where pbrt-v4's
 * coateddiffuse and ours differ (shims/pbrt-v4/README.md), against the
 * walk's light leaving within 3 degrees of that direction (mc_stack -o).
 *
 * A third check reads the reference against itself: with the
 * height-correlated G2 of pbrt-v4 in place of the separable G1 G1 that the
 * library (and Mitsuba) use, the albedo can only grow (G2 >= G1 G1), and
 * by little at these roughnesses; the size is stated in
 * shims/pbrt-v4/README.md, where pbrt-v4's own materials are compared.
 */
#include "test_util.h"

#define MC_STACK_NO_MAIN
#include "reference/mc_stack.c"

#define N_NODES 300
#define N_MU 3
#define PATHS (1 << 20)

static const double MUS[N_MU] = { 1.0, 0.7, 0.5 };
/* Gold's index at 550 nm (data/ior/Au.eta.spd, Au.k.spd) relative to the coat. */
static const double GOLD_ETA = 0.35041 / 1.5, GOLD_K = 2.71406 / 1.5;

/* Our stack: the coat over the base, order 0 only (the albedo needs no more). */
static ll_layer *our_stack(double alpha, int diffuse_base)
{
    ll_layer *base = ll_test_layer(N_NODES, 1), *coat = ll_test_layer(N_NODES, 1);
    if (diffuse_base)
        assert_int_equal(ll_layer_set_diffuse(base, 0.5, NULL), LL_OK);
    else
        assert_int_equal(ll_test_set_microfacet_dist(base, GOLD_ETA, GOLD_K, alpha,
                                                     LL_MICROFACET_GGX, 0, 0, NULL), LL_OK);
    assert_int_equal(ll_test_set_microfacet_dist(coat, 1.5, 0.0, alpha, LL_MICROFACET_GGX, 0, 0,
                                                 NULL), LL_OK);
    assert_int_equal(ll_layer_add_to_top(base, coat), LL_OK);
    ll_layer_destroy(coat);
    return base;
}

static stack reference_stack(double alpha, int diffuse_base)
{
    stack st = { { 1.5, 0.0, alpha }, 0.0, 0.0, 0.0, diffuse_base ? 2 : 1,
                 { GOLD_ETA, GOLD_K, alpha }, 0.5 };
    return st;
}

static void test_adding_matches_the_walk(void **state)
{
    int diffuse_base, a, j;
    const double alphas[2] = { 0.1, 0.3 };
    (void)state;
    use_ggx = 1;
    use_correlated = 0;
    for (diffuse_base = 0; diffuse_base < 2; ++diffuse_base) {
        for (a = 0; a < 2; ++a) {
            ll_layer *ours = our_stack(alphas[a], diffuse_base);
            stack st = reference_stack(alphas[a], diffuse_base);
            for (j = 0; j < N_MU; ++j) {
                double r, t, mc, se, mc_t, se_t;
                assert_int_equal(ll_layer_albedo(ours, MUS[j], &r, &t), LL_OK);
                mc_albedo(&st, MUS[j], PATHS, 7, (uint64_t)(10 * a + j), &mc, &se, &mc_t, &se_t);
                printf("GGX coat %.1f over %s, mu_i %.1f: ours %.5f, walk %.5f +- %.5f\n",
                       alphas[a], diffuse_base ? "diffuse 0.5" : "gold", MUS[j], r, mc, se);
                assert_true(fabs(r - mc) < 4.0 * se + 2e-4);
            }
            ll_layer_destroy(ours);
        }
    }
}

static void test_retro_reflection_point_value(void **state)
{
    const double mu = 0.8, half = 3.0 * LL_PI / 180.0;
    ll_layer *full = ll_test_layer(N_NODES, 200), *coat = ll_test_layer(N_NODES, 200);
    stack st = reference_stack(0.1, 1);
    double ours, mc, se, t, se_t, solid;
    (void)state;
    assert_int_equal(ll_layer_set_diffuse(full, 0.5, NULL), LL_OK);
    assert_int_equal(ll_test_set_microfacet_dist(coat, 1.5, 0.0, 0.1, LL_MICROFACET_GGX, 0, 0,
                                                 NULL), LL_OK);
    assert_int_equal(ll_layer_add_to_top(full, coat), LL_OK);
    /* Retro-reflection: the outgoing azimuth opposite the mirror's. */
    ours = ll_test_layer_eval(full, mu, -mu, LL_PI);
    use_ggx = 1;
    use_correlated = 0;
    use_cone = 1;
    cone_axis = v3(sqrt(1.0 - mu * mu), 0.0, mu);
    cone_cos = cos(half);
    mc_albedo(&st, mu, 1 << 22, 13, 0, &mc, &se, &t, &se_t);
    use_cone = 0;
    solid = 2.0 * LL_PI * (1.0 - cone_cos) * mu;
    mc /= solid;
    se /= solid;
    printf("GGX coat 0.1 over diffuse 0.5, retro-reflection at mu 0.8: ours %.5f, walk %.5f "
           "+- %.5f\n", ours, mc, se);
    /* 4 standard errors and 0.5% for the cone's curvature. */
    assert_true(fabs(ours - mc) < 4.0 * se + 5e-3 * mc);
    ll_layer_destroy(coat);
    ll_layer_destroy(full);
}

static void test_correlated_shadowing_only_adds(void **state)
{
    int j;
    (void)state;
    use_ggx = 1;
    for (j = 0; j < N_MU; ++j) {
        stack st = reference_stack(0.3, 1);
        double sep, se_sep, cor, se_cor, t, se_t;
        use_correlated = 0;
        mc_albedo(&st, MUS[j], PATHS, 9, (uint64_t)j, &sep, &se_sep, &t, &se_t);
        use_correlated = 1;
        mc_albedo(&st, MUS[j], PATHS, 9, (uint64_t)j, &cor, &se_cor, &t, &se_t);
        printf("GGX coat 0.3 over diffuse 0.5, mu_i %.1f: separable %.5f, correlated %.5f\n",
               MUS[j], sep, cor);
        /* The same random numbers: every path's weight grows or stays. */
        assert_true(cor >= sep);
        assert_true(cor - sep < 0.02 * sep);
    }
    use_correlated = 0;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_adding_matches_the_walk),
        cmocka_unit_test(test_retro_reflection_point_value),
        cmocka_unit_test(test_correlated_shadowing_only_adds),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
