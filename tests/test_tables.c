/*
 * Table files of the `measured` format (ll_tables.h, docs/formats.md):
 * written from the rough-gold .bsdf, read back through ll_bsdf_open, and
 * compared with the .bsdf they came from (albedo per channel and relative
 * errors of f where f cos matters: the error targets of the tables), the
 * reader's own consistency (sampled pdf and f equal the evaluated ones, the
 * stored values exact at the grid nodes), and refusals (textured,
 * transmissive).
 */
#include "test_bsdf_util.h"
#include "tables_figures.h"

static char path[600];

static ll_bsdf *open_file(const char *p)
{
    ll_bsdf *b = NULL;
    assert_int_equal(ll_bsdf_open(p, NULL, &b), LL_OK);
    return b;
}

/* The table of the golden file, written once for the program, at the
 * grid 32 x 128^2 x 64^2 (given, so nothing is measured: the sizes chosen
 * by a tolerance are checked in the slow tier, test_tables_tolerance.c). */
static ll_bsdf *table(void)
{
    static int written;
    if (!written) {
        ll_bsdf *src = open_file(LL_TEST_GOLDEN);
        ll_tables_options o = LL_TABLES_OPTIONS_INIT;
        o.n_theta_i = 32;
        o.vndf_size = 128;
        o.sample_size = 64;
        snprintf(path, sizeof path, "%s/gold.bsdf", ll_test_dir());
        assert_int_equal(ll_tables_write_from_bsdf(src, path, &o, NULL), LL_OK);
        ll_bsdf_release(src);
        written = 1;
    }
    return open_file(path);
}

static void test_info(void **state)
{
    ll_bsdf *t = table(), *f = open_file(LL_TEST_GOLDEN);
    ll_bsdf_info it = LL_BSDF_INFO_INIT, fi = LL_BSDF_INFO_INIT;
    struct stat st;
    (void)state;
    assert_int_equal(ll_bsdf_get_info(t, &it), LL_OK);
    assert_int_equal(ll_bsdf_get_info(f, &fi), LL_OK);
    assert_int_equal(it.format, LL_BSDF_FORMAT_TABLES);
    assert_int_equal(fi.format, LL_BSDF_FORMAT_FOURIER);
    assert_int_equal(it.n_channels, 3);
    assert_int_equal(it.n_nodes, 0);
    assert_non_null(strstr(it.metadata, "\"theta_i\": 32"));
    assert_null(ll_bsdf_nodes(t));
    assert_int_equal(stat(path, &st), 0);
    printf("table %lld bytes, .bsdf %zu bytes; %.120s\n", (long long)st.st_size, fi.file_size,
           strstr(it.metadata, "\"theta_i\""));
    ll_bsdf_release(t);
    ll_bsdf_release(f);
}

/* Albedo per channel for light seen along wo (cos theta = mu), by the
 * file's own sampler, stratified (tables_figures.h); every sample must
 * succeed. */
static void albedo(const ll_bsdf *b, double mu, double out[3])
{
    assert_true(tf_albedo(b, mu, out));
}

static void test_albedo(void **state)
{
    static const double mus[4] = { 1.0, 0.7, 0.3, 0.1 };
    ll_bsdf *t = table(), *f = open_file(LL_TEST_GOLDEN);
    int k, c;
    (void)state;
    for (k = 0; k < 4; ++k) {
        double at[3], af[3];
        albedo(t, mus[k], at);
        albedo(f, mus[k], af);
        printf("albedo cos %.1f: table/bsdf R %.5f G %.5f B %.5f (bsdf G %.4f)\n", mus[k],
               at[0] / af[0], at[1] / af[1], at[2] / af[2], af[1]);
        for (c = 0; c < 3; ++c)
            assert_true(fabs(at[c] / af[c] - 1.0) <= 0.003);
    }
    ll_bsdf_release(t);
    ll_bsdf_release(f);
}

/* Relative errors of f where f cos is above 1% of its maximum, both
 * elevations <= 80 degrees, half of the pairs near the mirror direction
 * (tables_figures.h); every evaluation must succeed. */
static void test_f_errors(void **state)
{
    ll_bsdf *t = table(), *f = open_file(LL_TEST_GOLDEN);
    tf_figures fig;
    (void)state;
    memset(&fig, 0, sizeof fig);
    assert_true(tf_f_errors(f, t, &fig, ll_test_uniform));
    printf("f errors over %zu channel values: median %.4f%% 95th %.3f%% 99th %.3f%%\n",
           fig.n_values, 100 * fig.p50, 100 * fig.p95, 100 * fig.p99);
    assert_true(fig.p50 <= 0.002);
    assert_true(fig.p95 <= 0.02);
    assert_true(fig.p99 <= 0.05);
    ll_bsdf_release(t);
    ll_bsdf_release(f);
}

/* Sampling reports the pdf and f that evaluation gives at its direction. */
static void test_sample_consistency(void **state)
{
    ll_bsdf *t = table();
    uint64_t rng = 5;
    int k, c, hits = 0;
    (void)state;
    for (k = 0; k < 5000; ++k) {
        double wo[3], u[2] = { ll_test_uniform(&rng), ll_test_uniform(&rng) }, wi[3], pdf, f[3];
        double pdf_e, f_e[3];
        tf_direction(acos(ll_test_uniform(&rng)), 2.0 * LL_TEST_PI * ll_test_uniform(&rng), wo);
        assert_int_equal(ll_bsdf_sample_dir(t, wo, u, LL_TRANSPORT_RADIANCE, NULL, wi, &pdf, f),
                         LL_OK);
        if (!(pdf > 0.0))
            continue;
        ++hits;
        assert_true(fabs(wi[0] * wi[0] + wi[1] * wi[1] + wi[2] * wi[2] - 1.0) < 1e-12);
        assert_int_equal(ll_bsdf_pdf_dir(t, wo, wi, NULL, &pdf_e), LL_OK);
        assert_int_equal(ll_bsdf_eval_dir(t, wo, wi, LL_TRANSPORT_RADIANCE, NULL, f_e), LL_OK);
        assert_true(ll_test_close(pdf, pdf_e, 1e-6, 1e-9));
        for (c = 0; c < 3; ++c)
            assert_true(ll_test_close(f[c], f_e[c], 1e-6, 1e-9));
    }
    assert_true(hits > 4500);
    ll_bsdf_release(t);
}

/* The pdf integrates to (at most) 1 over the hemisphere, and to 1 where
 * the whole lobe lies above the horizon. */
static void test_pdf_integral(void **state)
{
    ll_bsdf *t = table();
    const int n = 400;
    double wo[3], sum = 0.0;
    int i, j;
    (void)state;
    tf_direction(0.3, 0.0, wo);
    for (i = 0; i < n; ++i)
        for (j = 0; j < 2 * n; ++j) {
            /* Uniform in cos theta and phi: d omega = dcos dphi. */
            double ct = (i + 0.5) / n, phi = (j + 0.5) / (2 * n) * 2.0 * LL_TEST_PI, wi[3], pdf;
            wi[0] = sqrt(1.0 - ct * ct) * cos(phi);
            wi[1] = sqrt(1.0 - ct * ct) * sin(phi);
            wi[2] = ct;
            assert_int_equal(ll_bsdf_pdf_dir(t, wo, wi, NULL, &pdf), LL_OK);
            sum += pdf * (1.0 / n) * (LL_TEST_PI / n);
        }
    printf("pdf integral at 0.3 rad: %.5f\n", sum);
    assert_true(fabs(sum - 1.0) < 0.01);
    ll_bsdf_release(t);
}

/* The layer convention on a table: the same values as the renderer one. */
static void test_layer_convention(void **state)
{
    ll_bsdf *t = table();
    double mu_i = 0.8, mu_o = -0.6, phi = 0.3, f[3], g[3], pdf, pdf_d;
    double wo[3] = { sqrt(1 - mu_i * mu_i), 0.0, mu_i };
    double wi[3] = { -sqrt(1 - mu_o * mu_o) * cos(phi), -sqrt(1 - mu_o * mu_o) * sin(phi), -mu_o };
    int c;
    (void)state;
    assert_int_equal(ll_bsdf_eval(t, mu_i, mu_o, phi, NULL, f), LL_OK);
    assert_int_equal(ll_bsdf_eval_dir(t, wo, wi, LL_TRANSPORT_RADIANCE, NULL, g), LL_OK);
    assert_int_equal(ll_bsdf_pdf(t, mu_i, mu_o, phi, NULL, &pdf), LL_OK);
    assert_int_equal(ll_bsdf_pdf_dir(t, wo, wi, NULL, &pdf_d), LL_OK);
    for (c = 0; c < 3; ++c)
        assert_true(f[c] > 0.0 && ll_test_close(f[c], g[c], 1e-9, 0.0));
    assert_true(pdf > 0.0 && ll_test_close(pdf, pdf_d, 1e-9, 0.0));
    /* Transmission and light from below: nothing. */
    assert_int_equal(ll_bsdf_eval(t, mu_i, 0.5, phi, NULL, f), LL_OK);
    assert_true(f[0] == 0.0 && f[1] == 0.0 && f[2] == 0.0);
    assert_int_equal(ll_bsdf_eval(t, -mu_i, mu_o, phi, NULL, f), LL_OK);
    assert_true(f[0] == 0.0 && f[1] == 0.0 && f[2] == 0.0);
    ll_bsdf_release(t);
}

/* The batches give what the scalar calls give on a table, element by
 * element. */
static void test_batches(void **state)
{
    enum { COUNT = 3000 };
    ll_bsdf *t = table();
    static double wo[3 * COUNT], wi[3 * COUNT], u[2 * COUNT], rgb[3 * COUNT], pdf[COUNT];
    static double wi_s[3 * COUNT], pdf_s[COUNT], rgb_s[3 * COUNT];
    uint64_t rng = 31;
    size_t k;
    int c;
    (void)state;
    for (k = 0; k < COUNT; ++k) {
        double a = acos(ll_test_uniform(&rng)), b = 2.0 * LL_TEST_PI * ll_test_uniform(&rng);
        tf_direction(a, b, wo + 3 * k);
        a = acos(ll_test_uniform(&rng));
        b = 2.0 * LL_TEST_PI * ll_test_uniform(&rng);
        tf_direction(a, b, wi + 3 * k);
        u[2 * k] = ll_test_uniform(&rng);
        u[2 * k + 1] = ll_test_uniform(&rng);
    }
    assert_int_equal(
        ll_bsdf_eval_dir_batch(t, COUNT, wo, wi, LL_TRANSPORT_RADIANCE, NULL, 0, rgb), LL_OK);
    assert_int_equal(ll_bsdf_pdf_dir_batch(t, COUNT, wo, wi, NULL, 0, pdf), LL_OK);
    for (k = 0; k < COUNT; ++k) {
        double f[3], p;
        assert_int_equal(
            ll_bsdf_eval_dir(t, wo + 3 * k, wi + 3 * k, LL_TRANSPORT_RADIANCE, NULL, f), LL_OK);
        assert_int_equal(ll_bsdf_pdf_dir(t, wo + 3 * k, wi + 3 * k, NULL, &p), LL_OK);
        for (c = 0; c < 3; ++c)
            assert_true(f[c] == rgb[3 * k + c]);
        assert_true(p == pdf[k]);
    }
    assert_int_equal(ll_bsdf_sample_dir_batch(t, COUNT, wo, u, LL_TRANSPORT_RADIANCE, NULL, 0,
                                              wi_s, pdf_s, rgb_s),
                     LL_OK);
    for (k = 0; k < COUNT; ++k) {
        double w[3], p, f[3];
        assert_int_equal(ll_bsdf_sample_dir(t, wo + 3 * k, u + 2 * k, LL_TRANSPORT_RADIANCE, NULL,
                                            w, &p, f),
                         LL_OK);
        assert_true(p == pdf_s[k]);
        for (c = 0; c < 3; ++c)
            assert_true(w[c] == wi_s[3 * k + c] && f[c] == rgb_s[3 * k + c]);
    }
    ll_bsdf_release(t);
}

/* Sizes given are the sizes written, and nothing is measured. */
static void test_explicit_grid(void **state)
{
    ll_bsdf *f = open_file(LL_TEST_GOLDEN), *t;
    ll_bsdf_info it = LL_BSDF_INFO_INIT;
    ll_tables_options o = LL_TABLES_OPTIONS_INIT;
    char out[600];
    (void)state;
    snprintf(out, sizeof out, "%s/explicit.bsdf", ll_test_dir());
    o.n_theta_i = 8;
    o.vndf_size = 16;
    o.sample_size = 12;
    assert_int_equal(ll_tables_write_from_bsdf(f, out, &o, NULL), LL_OK);
    t = open_file(out);
    assert_int_equal(ll_bsdf_get_info(t, &it), LL_OK);
    assert_non_null(strstr(it.metadata, "\"theta_i\": 8, \"vndf\": [16, 16], \"sample\": [12, 12]"));
    assert_null(strstr(it.metadata, "\"figures\""));
    ll_bsdf_release(t);
    /* A tolerance out of range, when a size is left to it. */
    o.sample_size = 0;
    o.tolerance = 2.0;
    assert_int_equal(ll_tables_write_from_bsdf(f, out, &o, NULL), LL_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(ll_last_error_message(), "tolerance"));
    ll_bsdf_release(f);
}

static void test_refusals(void **state)
{
    ll_bsdf *f = open_file(LL_TEST_GOLDEN);
    char out[600];
    ll_tables_options o = LL_TABLES_OPTIONS_INIT;
    (void)state;
    snprintf(out, sizeof out, "%s/refused.bsdf", ll_test_dir());
    assert_int_equal(ll_tables_write_from_bsdf(NULL, out, NULL, NULL), LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_tables_write_from_bsdf(f, NULL, NULL, NULL), LL_ERROR_INVALID_ARGUMENT);
    o.sample_size = 1;
    assert_int_equal(ll_tables_write_from_bsdf(f, out, &o, NULL), LL_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(ll_last_error_message(), "sample_size"));
    assert_int_equal(access(out, F_OK), -1);
    ll_bsdf_release(f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_info),
        cmocka_unit_test(test_albedo),
        cmocka_unit_test(test_f_errors),
        cmocka_unit_test(test_sample_consistency),
        cmocka_unit_test(test_pdf_integral),
        cmocka_unit_test(test_layer_convention),
        cmocka_unit_test(test_batches),
        cmocka_unit_test(test_explicit_grid),
        cmocka_unit_test(test_refusals),
    };
    return cmocka_run_group_tests(tests, ll_test_dir_setup, ll_test_dir_teardown);
}
