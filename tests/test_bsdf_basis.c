/*
 * ll_bsdf_basis_coefficients (src/reader/bsdf_basis.c): the weights of a
 * textured file's bases for a point of parameter space, and what a file
 * evaluated with them gives: the untextured file of the same layer at a
 * sample point, the documented interpolation error between samples, a
 * non-negative f and consistent sampling there.
 */
#include "test_bsdf_util.h"
#include "words/heuristics.h" /* ll_fit_microfacet: the original's resolution */

#define N_ALPHA 5
static const double g_alphas[N_ALPHA] = { 0.05, 0.1, 0.2, 0.3, 0.4 };

/* A rough conductor (eta 0.2 + 3i) textured over alpha at g_alphas, at the
 * resolution of its sharpest sample (the measurement of formats.md,
 * "Weights for a point of parameter space"), and its layers for direct builds. */
static ll_layer *g_layers[N_ALPHA];
static ll_bsdf *g_conductor;
static size_t g_n, g_orders;
/* A synthetic file of two parameters (3 x 4 positions, 12 bases). */
static ll_bsdf *g_grid;
static const double g_grid_positions[7] = { -1.0, 0.5, 2.0, 0.0, 1.0, 3.0, 10.0 };

static void path_in_dir(char *path, size_t size, const char *name)
{
    snprintf(path, size, "%s/%s", ll_test_dir(), name);
}

/* error_goal: the series truncation (ll_bsdf_write_options); < 0 the default. */
static ll_bsdf *write_open_ex(const char *name, const ll_layer *const *layers, size_t n_params,
                              const size_t *counts, const double *positions, double error_goal)
{
    char path[600];
    ll_bsdf *b = NULL;
    ll_bsdf_write_options opts = LL_BSDF_WRITE_OPTIONS_INIT;
    if (error_goal >= 0.0)
        opts.error_goal = error_goal;
    path_in_dir(path, sizeof path, name);
    if (ll_bsdf_write_textured(path, layers, 1, n_params, counts, positions, &opts, NULL) != LL_OK)
        fail_msg("write %s: %s", name, ll_last_error_message());
    if (ll_bsdf_open(path, NULL, &b) != LL_OK)
        fail_msg("open %s: %s", name, ll_last_error_message());
    return b;
}

static ll_bsdf *write_open(const char *name, const ll_layer *const *layers, size_t n_params,
                           const size_t *counts, const double *positions)
{
    return write_open_ex(name, layers, n_params, counts, positions, -1.0);
}

static ll_layer *conductor_layer(double alpha)
{
    ll_layer *l = ll_test_layer(g_n, g_orders);
    assert_int_equal(ll_test_set_microfacet(l, 0.2, 3.0, alpha, 1, 0, NULL), LL_OK);
    return l;
}

static int setup(void **state)
{
    size_t counts[1] = { N_ALPHA }, grid_counts[2] = { 3, 4 }, k;
    const ll_layer *layers[12];
    ll_layer *synthetic[12];
    ll_test_smooth p[12];
    ll_test_dir_setup(state);
    assert_int_equal(ll_fit_microfacet(g_alphas[0], 0.2, 3.0, &g_n, &g_orders), LL_OK);
    for (k = 0; k < N_ALPHA; ++k) {
        g_layers[k] = conductor_layer(g_alphas[k]);
        layers[k] = g_layers[k];
    }
    g_conductor = write_open("conductor.bsdf", layers, 1, counts, g_alphas);
    for (k = 0; k < 12; ++k) {
        p[k].scale[0] = 0.2 + 0.05 * (double)k;
        p[k].scale[1] = 0.02 * (double)k;
        p[k].scale[2] = 0.5;
        p[k].scale[3] = 0.1;
        p[k].decay = 0.1 + 0.02 * (double)k;
        synthetic[k] = ll_test_layer(8, 3);
        ll_test_fill(synthetic[k], ll_test_smooth_fn, &p[k]);
        layers[k] = synthetic[k];
    }
    g_grid = write_open("grid.bsdf", layers, 2, grid_counts, g_grid_positions);
    for (k = 0; k < 12; ++k)
        ll_layer_destroy(synthetic[k]);
    return 0;
}

static int teardown(void **state)
{
    size_t k;
    ll_bsdf_release(g_conductor);
    ll_bsdf_release(g_grid);
    for (k = 0; k < N_ALPHA; ++k)
        ll_layer_destroy(g_layers[k]);
    return ll_test_dir_teardown(state);
}

/* Weights are >= 0, sum to 1, and at most 2 per parameter are non-zero;
 * at a grid point exactly one is 1. */
static void weights_sum_to_one(void **state)
{
    uint64_t rng = 7;
    float c[12];
    int k;
    (void)state;
    for (k = 0; k < 1000; ++k) {
        double params[2], sum = 0.0;
        size_t j, nonzero = 0;
        params[0] = -1.0 + 3.0 * ll_test_uniform(&rng);
        params[1] = 10.0 * ll_test_uniform(&rng);
        assert_int_equal(ll_bsdf_basis_coefficients(g_grid, params, c), LL_OK);
        for (j = 0; j < 12; ++j) {
            assert_true(c[j] >= 0.0f);
            sum += c[j];
            nonzero += c[j] != 0.0f;
        }
        if (fabs(sum - 1.0) > 1e-6)
            fail_msg("params (%g, %g): weights sum to %.9g", params[0], params[1], sum);
        assert_true(nonzero >= 1 && nonzero <= 4);
    }
    {
        /* Grid point (0.5, 3.0): index 1 + 3 * 2 = 7 (parameter 0 fastest). */
        const double params[2] = { 0.5, 3.0 };
        size_t j;
        assert_int_equal(ll_bsdf_basis_coefficients(g_grid, params, c), LL_OK);
        for (j = 0; j < 12; ++j)
            assert_true(c[j] == (j == 7 ? 1.0f : 0.0f));
    }
    {
        /* Halfway along parameter 0 between positions 0 and 1 (-1 and 0.5),
         * a quarter along parameter 1 between 1 and 3 (index 2 and 3). */
        const double params[2] = { -0.25, 1.5 };
        assert_int_equal(ll_bsdf_basis_coefficients(g_grid, params, c), LL_OK);
        assert_true(fabs(c[0 + 3 * 1] - 0.375) < 1e-7 && fabs(c[1 + 3 * 1] - 0.375) < 1e-7);
        assert_true(fabs(c[0 + 3 * 2] - 0.125) < 1e-7 && fabs(c[1 + 3 * 2] - 0.125) < 1e-7);
    }
}

/* Outside a parameter's range the weights are those of its nearest end. */
static void clamped_outside_range(void **state)
{
    const double inside[4][2] = { { -1.0, 0.0 }, { 2.0, 10.0 }, { -1.0, 2.0 }, { 1.0, 10.0 } };
    const double outside[4][2] = { { -5.0, -3.0 }, { 7.0, 1e30 }, { -1e30, 2.0 }, { 1.0, 11.0 } };
    float a[12], b[12];
    int k;
    size_t j;
    (void)state;
    for (k = 0; k < 4; ++k) {
        assert_int_equal(ll_bsdf_basis_coefficients(g_grid, inside[k], a), LL_OK);
        assert_int_equal(ll_bsdf_basis_coefficients(g_grid, outside[k], b), LL_OK);
        for (j = 0; j < 12; ++j)
            assert_true(a[j] == b[j]);
    }
}

/* NULL params: fine for an untextured file (weight 1), an error naming the
 * problem for a textured one; non-finite values and NULL pointers too. */
static void null_and_invalid_arguments(void **state)
{
    const ll_layer *one[1];
    ll_bsdf *plain;
    float c[12] = { 5.0f };
    const double nan_params[2] = { NAN, 1.0 };
    (void)state;
    one[0] = g_layers[2];
    plain = write_open("plain.bsdf", one, 0, NULL, NULL);
    assert_int_equal(ll_bsdf_basis_coefficients(plain, NULL, c), LL_OK);
    assert_true(c[0] == 1.0f);
    assert_int_equal(ll_bsdf_basis_coefficients(g_grid, NULL, c), LL_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(ll_last_error_message(), "textured (2 parameters)"));
    assert_non_null(strstr(ll_last_error_message(), "params"));
    assert_int_equal(ll_bsdf_basis_coefficients(g_grid, nan_params, c),
                     LL_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(ll_last_error_message(), "params[0]"));
    assert_int_equal(ll_bsdf_basis_coefficients(NULL, nan_params, c), LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_bsdf_basis_coefficients(g_grid, nan_params + 1, NULL),
                     LL_ERROR_INVALID_ARGUMENT);
    ll_bsdf_release(plain);
}

/* Directions of the comparisons: light from above, reflection. */
#define N_MU 12
#define N_PHI 16
static double grid_mu_i(size_t i) { return ((double)i + 0.5) / N_MU; }
static double grid_mu_o(size_t o) { return -((double)o + 0.5) / N_MU; }
static double grid_phi(size_t p) { return LL_TEST_PI * (double)p / (N_PHI - 1); }

/* Relative error of the textured file at alpha against a direct build, where
 * the direct f exceeds 1% of its peak: max and mean. Also checks f >= 0. */
static void interpolation_error(const ll_bsdf *textured, double alpha, const ll_bsdf *direct,
                                double *max_err, double *mean_err)
{
    float c[N_ALPHA];
    double peak = 0.0, sum = 0.0;
    size_t i, o, p, counted = 0;
    int pass;
    assert_int_equal(ll_bsdf_basis_coefficients(textured, &alpha, c), LL_OK);
    *max_err = 0.0;
    for (pass = 0; pass < 2; ++pass)
        for (i = 0; i < N_MU; ++i)
            for (o = 0; o < N_MU; ++o)
                for (p = 0; p < N_PHI; ++p) {
                    double fd[3], fi[3], e;
                    assert_int_equal(ll_bsdf_eval(direct, grid_mu_i(i), grid_mu_o(o),
                                                  grid_phi(p), NULL, fd),
                                     LL_OK);
                    if (pass == 0) {
                        peak = fd[0] > peak ? fd[0] : peak;
                        continue;
                    }
                    assert_int_equal(ll_bsdf_eval(textured, grid_mu_i(i), grid_mu_o(o),
                                                  grid_phi(p), c, fi),
                                     LL_OK);
                    assert_true(fi[0] >= 0.0 && fi[1] >= 0.0 && fi[2] >= 0.0);
                    if (!(fd[0] > 0.01 * peak))
                        continue;
                    e = fabs(fi[0] - fd[0]) / fd[0];
                    *max_err = e > *max_err ? e : *max_err;
                    sum += e;
                    counted++;
                }
    assert_true(counted > 0);
    *mean_err = sum / (double)counted;
}

/* At each sample position the textured file is the untextured file of that
 * sample's layer, to float rounding. Both keep every order (error_goal 0):
 * the default truncation keeps a pair's longest series over the bases, so
 * a textured file holds a few more orders than a basis alone would. */
static void sample_points_match_direct_builds(void **state)
{
    const size_t counts[1] = { N_ALPHA };
    const ll_layer *layers[N_ALPHA];
    ll_bsdf *textured;
    size_t k;
    (void)state;
    for (k = 0; k < N_ALPHA; ++k)
        layers[k] = g_layers[k];
    textured = write_open_ex("full.bsdf", layers, 1, counts, g_alphas, 0.0);
    for (k = 0; k < N_ALPHA; ++k) {
        const ll_layer *one[1];
        ll_bsdf *direct;
        double max_err, mean_err;
        char name[32];
        one[0] = g_layers[k];
        snprintf(name, sizeof name, "direct%zu.bsdf", k);
        direct = write_open_ex(name, one, 0, NULL, NULL, 0.0);
        interpolation_error(textured, g_alphas[k], direct, &max_err, &mean_err);
        if (max_err > 1e-6)
            fail_msg("alpha %g: relative difference %g from the direct build", g_alphas[k],
                     max_err);
        ll_bsdf_release(direct);
    }
    ll_bsdf_release(textured);
}

/* Between samples: within the errors documented in ll_bsdf.h and
 * formats.md for this grid (measured max 0.90 / mean 0.27 at 0.15,
 * max 0.18 / mean 0.042 at 0.35; bench/basis_interp.c). */
static void between_samples_within_documented_error(void **state)
{
    const double alpha[2] = { 0.15, 0.35 }, max_bound[2] = { 1.0, 0.2 },
                 mean_bound[2] = { 0.3, 0.05 };
    int k;
    (void)state;
    for (k = 0; k < 2; ++k) {
        ll_layer *l = conductor_layer(alpha[k]);
        const ll_layer *one[1];
        ll_bsdf *direct;
        double max_err, mean_err;
        one[0] = l;
        direct = write_open("between.bsdf", one, 0, NULL, NULL);
        interpolation_error(g_conductor, alpha[k], direct, &max_err, &mean_err);
        if (max_err > max_bound[k] || mean_err > mean_bound[k])
            fail_msg("alpha %g: relative error max %g mean %g (bounds %g, %g)", alpha[k],
                     max_err, mean_err, max_bound[k], mean_bound[k]);
        print_message("alpha %g: relative error max %g mean %g\n", alpha[k], max_err, mean_err);
        /* ... and not trivially: the interpolation does differ there. */
        assert_true(max_err > 1e-3);
        ll_bsdf_release(direct);
        ll_layer_destroy(l);
    }
}

/* Sampling at interpolated weights: the returned pdf is ll_bsdf_pdf of the
 * returned direction and the returned f its ll_bsdf_eval, also in the renderer
 * convention. */
static void sampling_consistent_between_samples(void **state)
{
    uint64_t rng = 31;
    const double alpha = 0.17;
    float c[N_ALPHA];
    long k, zero = 0;
    (void)state;
    assert_int_equal(ll_bsdf_basis_coefficients(g_conductor, &alpha, c), LL_OK);
    for (k = 0; k < 2000; ++k) {
        double mu_i = 0.05 + 0.95 * ll_test_uniform(&rng), u[2], mu_o, phi, pdf, w[3], f[3], p;
        double wo[3], wi[3], pdf_dir, f_dir[3], f_eval[3];
        u[0] = ll_test_uniform(&rng);
        u[1] = ll_test_uniform(&rng);
        assert_int_equal(ll_bsdf_sample(g_conductor, mu_i, u, c, &mu_o, &phi, &pdf, w), LL_OK);
        if (pdf == 0.0) {
            ++zero;
            assert_true(w[0] == 0.0);
            continue;
        }
        p = ll_test_pdf(g_conductor, mu_i, mu_o, phi, c);
        if (!ll_test_close(pdf, p, 1e-5, 1e-9))
            fail_msg("sample %ld: pdf %.9g, pdf() %.9g", k, pdf, p);
        assert_int_equal(ll_bsdf_eval(g_conductor, mu_i, mu_o, phi, c, f), LL_OK);
        assert_true(f[0] >= 0.0);
        if (!ll_test_close(w[0], f[0], 1e-5, 1e-9))
            fail_msg("sample %ld: sampled f %.9g, eval f %.9g", k, w[0], f[0]);
        wo[0] = sqrt(1.0 - mu_i * mu_i);
        wo[1] = 0.0;
        wo[2] = mu_i;
        assert_int_equal(ll_bsdf_sample_dir(g_conductor, wo, u, LL_TRANSPORT_RADIANCE, c, wi,
                                            &pdf_dir, f_dir),
                         LL_OK);
        if (pdf_dir == 0.0)
            continue;
        if (!ll_test_close(pdf_dir, ll_test_pdf_dir(g_conductor, wo, wi, c), 1e-5, 1e-9))
            fail_msg("sample %ld: pdf_dir %.9g, pdf_dir() %.9g", k, pdf_dir,
                     ll_test_pdf_dir(g_conductor, wo, wi, c));
        assert_int_equal(ll_bsdf_eval_dir(g_conductor, wo, wi, LL_TRANSPORT_RADIANCE, c, f_eval),
                         LL_OK);
        if (!ll_test_close(f_dir[0], f_eval[0], 1e-5, 1e-9))
            fail_msg("sample %ld: f %.9g, eval_dir %.9g", k, f_dir[0], f_eval[0]);
    }
    assert_true(zero < 20);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(weights_sum_to_one),
        cmocka_unit_test(clamped_outside_range),
        cmocka_unit_test(null_and_invalid_arguments),
        cmocka_unit_test(sample_points_match_direct_builds),
        cmocka_unit_test(between_samples_within_documented_error),
        cmocka_unit_test(sampling_consistent_between_samples),
    };
    return cmocka_run_group_tests_name("bsdf_basis", tests, setup, teardown);
}
