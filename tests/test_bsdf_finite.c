/*
 * Every file that opens gives finite eval/pdf/sample results whatever the
 * directions, and every file the original layerlab wrote opens:
 *  - the golden file with its two mu = 0 nodes moved apart (no pair at 0):
 *    f = stored f |mu_o| / |mu_o| returned +inf at mu_o = 5e-324;
 *  - coefficients beyond what evaluation can scale without overflow are
 *    refused at open;
 *  - CDF rows with dips at rounding level, as the original's running float32
 *    sums of spline integrals have them (its coated-gold files carry 47),
 *    open, and sampling treats them as flat (pdf of a sample = ll_bsdf_pdf
 *    there); a large dip, a negative total or a non-zero start are refused.
 */
#include "test_bsdf_util.h"
#include "reader/bsdf_format.h"

#include <float.h>

/* The golden file's layout (as in test_bsdf_corrupt.c). */
enum {
    G_NODES = 64,
    G_N = 58,
    G_CDF = G_NODES + 4 * G_N,
    G_TABLE = G_CDF + 4 * G_N * G_N,
    G_COEFFS = G_TABLE + 8 * G_N * G_N
};

static unsigned char *g_gold;
static size_t g_size;

static int setup(void **state)
{
    (void)state;
    g_gold = ll_test_read_file(LL_TEST_GOLDEN, &g_size);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    free(g_gold);
    return 0;
}

static unsigned char *copy_gold(void)
{
    unsigned char *d = malloc(g_size);
    assert_non_null(d);
    memcpy(d, g_gold, g_size);
    return d;
}

static float node(const unsigned char *d, size_t k) { return ll_le_get_f32(d + G_NODES + 4 * k); }
static float cdf(const unsigned char *d, size_t row, size_t o)
{
    return ll_le_get_f32(d + G_CDF + 4 * (row * G_N + o));
}
static void set_cdf(unsigned char *d, size_t row, size_t o, float v)
{
    ll_le_put_f32(d + G_CDF + 4 * (row * G_N + o), v);
}

static void check_rgb(const double rgb[3], const char *what, double a, double b)
{
    if (!(isfinite(rgb[0]) && isfinite(rgb[1]) && isfinite(rgb[2]) && rgb[0] >= 0.0 &&
          rgb[1] >= 0.0 && rgb[2] >= 0.0))
        fail_msg("%s(%g, %g) = (%g, %g, %g)", what, a, b, rgb[0], rgb[1], rgb[2]);
}

/* eval, pdf and sample at every pair of a list of cosines that includes
 * the smallest ones, in both conventions: all finite and non-negative. */
static void check_finite_everywhere(const ll_bsdf *b)
{
    static const double mus[] = { -1.0, -0.5, -1e-3, -1e-9, -1e-300, -5e-324, 0.0,
                                  5e-324, 1e-300, 1e-160, 1e-9, 1e-6, 2e-6, 1e-3, 0.5, 1.0 };
    size_t n = sizeof mus / sizeof mus[0], i, o, k;
    for (i = 0; i < n; ++i)
        for (o = 0; o < n; ++o) {
            double rgb[3], p, wo[3], wi[3], mu_s, phi_s, w[3], u[2];
            assert_int_equal(ll_bsdf_eval(b, mus[i], mus[o], 0.3, NULL, rgb), LL_OK);
            check_rgb(rgb, "eval", mus[i], mus[o]);
            p = ll_test_pdf(b, mus[i], mus[o], 0.3, NULL);
            if (!(isfinite(p) && p >= 0.0))
                fail_msg("pdf(%g, %g) = %g", mus[i], mus[o], p);
            wo[0] = sqrt(1.0 - mus[i] * mus[i]);
            wo[1] = 0.0;
            wo[2] = mus[i];
            wi[0] = -sqrt(1.0 - mus[o] * mus[o]);
            wi[1] = 0.0;
            wi[2] = mus[o];
            assert_int_equal(ll_bsdf_eval_dir(b, wo, wi, LL_TRANSPORT_RADIANCE, NULL, rgb),
                             LL_OK);
            check_rgb(rgb, "eval_dir", mus[i], mus[o]);
            for (k = 0; k < 8; ++k) {
                u[0] = (double)k / 7.0;
                u[1] = (double)((k * 5) % 8) / 7.0;
                assert_int_equal(ll_bsdf_sample(b, mus[i], u, NULL, &mu_s, &phi_s, &p, w),
                                 LL_OK);
                check_rgb(w, "sample f", mus[i], u[1]);
                assert_int_equal(ll_bsdf_sample_dir(b, wo, u, LL_TRANSPORT_RADIANCE, NULL, wi,
                                                    &p, rgb),
                                 LL_OK);
                check_rgb(rgb, "sample_dir f", mus[i], u[1]);
                assert_true(isfinite(p) && p >= 0.0);
            }
        }
}

static void moved_zero_nodes(void **state)
{
    unsigned char *d = copy_gold();
    ll_bsdf *b = NULL;
    double rgb[3];
    size_t z;
    (void)state;
    /* The pair of mu = 0 nodes, moved halfway to their neighbours: the
     * file now interpolates across 0 with no node there. */
    for (z = 1; z + 2 < G_N && !(node(d, z) == 0.0f && node(d, z + 1) == 0.0f); ++z)
        ;
    assert_true(z + 2 < G_N);
    ll_le_put_f32(d + G_NODES + 4 * z, 0.5f * node(d, z - 1));
    ll_le_put_f32(d + G_NODES + 4 * (z + 1), 0.5f * node(d, z + 2));
    if (ll_bsdf_open_memory(d, g_size, NULL, &b) != LL_OK)
        fail_msg("%s", ll_last_error_message());
    /* The value the issue reported as +inf. */
    assert_int_equal(ll_bsdf_eval(b, 0.5, 5e-324, 0.0, NULL, rgb), LL_OK);
    check_rgb(rgb, "eval", 0.5, 5e-324);
    assert_int_equal(ll_bsdf_eval(b, 0.5, -5e-324, 0.0, NULL, rgb), LL_OK);
    check_rgb(rgb, "eval", 0.5, -5e-324);
    check_finite_everywhere(b);
    ll_bsdf_release(b);
    free(d);
}

static void golden_finite_and_unchanged_away_from_grazing(void **state)
{
    ll_bsdf *b = NULL;
    double rgb[3], rgb2[3];
    (void)state;
    assert_int_equal(ll_bsdf_open_memory(g_gold, g_size, NULL, &b), LL_OK);
    check_finite_everywhere(b);
    /* Below LL_BSDF_MU_FLOOR = 1e-6 the division uses the floor: the valid
     * file's f there is continuous with f at 1e-6 times |mu_o| / 1e-6. */
    assert_int_equal(ll_bsdf_eval(b, 0.7, -1e-6, 0.0, NULL, rgb), LL_OK);
    assert_int_equal(ll_bsdf_eval(b, 0.7, -2e-6, 0.0, NULL, rgb2), LL_OK);
    assert_true(rgb[0] > 0.0 && fabs(rgb[0] - rgb2[0]) <= 1e-3 * rgb2[0]);
    ll_bsdf_release(b);
}

static void huge_coefficients_refused(void **state)
{
    unsigned char *d = copy_gold();
    ll_bsdf *b = NULL;
    (void)state;
    ll_le_put_f32(d + G_COEFFS + 4 * 100, FLT_MAX);
    assert_int_equal(ll_bsdf_open_memory(d, g_size, NULL, &b), LL_ERROR_FORMAT);
    assert_null(b);
    assert_non_null(strstr(ll_last_error_message(), "coefficient 100"));
    /* 1e30 is still a (strange) number that evaluates finitely. */
    ll_le_put_f32(d + G_COEFFS + 4 * 100, -1e30f);
    if (ll_bsdf_open_memory(d, g_size, NULL, &b) != LL_OK)
        fail_msg("%s", ll_last_error_message());
    check_finite_everywhere(b);
    ll_bsdf_release(b);
    free(d);
}

/* The original's CDF: each entry the float32 running sum of the previous
 * entry and a spline integral; where a_0 is ~0 next to a lobe, the
 * integral is a tiny negative number or rounds the sum down by an ulp.
 * This puts such dips into rows of the golden file: 47 entries a few ulps
 * (or, from 0, 2^-22 of the total) below the previous one. */
static size_t add_rounding_dips(unsigned char *d)
{
    size_t dips = 0, row, o;
    for (row = 0; row < G_N && dips < 47; row += 3) {
        float total = cdf(d, row, G_N - 1);
        if (!(total > 0.0f))
            continue;
        for (o = 1; o + 1 < G_N && dips < 47; o += 9) {
            float prev = cdf(d, row, o - 1);
            float dip = prev > 0.0f ? nextafterf(nextafterf(prev, 0.0f), 0.0f)
                                    : -total * (1.0f / 4194304.0f);
            set_cdf(d, row, o, dip);
            ++dips;
        }
    }
    return dips;
}

static void rounding_dips_open_and_sample_consistently(void **state)
{
    unsigned char *d = copy_gold();
    ll_bsdf *b = NULL;
    size_t i, k, samples = 0;
    (void)state;
    assert_int_equal(add_rounding_dips(d), 47);
    /* What the reader said of the original's coated-gold files before. */
    if (ll_bsdf_open_memory(d, g_size, NULL, &b) != LL_OK)
        fail_msg("%s", ll_last_error_message());
    check_finite_everywhere(b);
    /* Sampling: the density and f of every sample are what ll_bsdf_pdf
     * and ll_bsdf_eval give for the sampled direction. */
    for (i = 0; i < 41; ++i) {
        double mu_i = -1.0 + 2.0 * (double)i / 40.0;
        for (k = 0; k < 64; ++k) {
            double u[2], mu_o, phi, pdf, w[3], f[3], p;
            u[0] = ((double)k + 0.5) / 64.0;
            u[1] = fmod(0.618033988749895 * (double)(k + 1), 1.0);
            assert_int_equal(ll_bsdf_sample(b, mu_i, u, NULL, &mu_o, &phi, &pdf, w), LL_OK);
            if (pdf == 0.0)
                continue;
            p = ll_test_pdf(b, mu_i, mu_o, phi, NULL);
            if (!(fabs(p - pdf) <= 1e-6 * pdf))
                fail_msg("mu_i %g u (%g, %g): sample pdf %.9g, ll_bsdf_pdf %.9g", mu_i, u[0],
                         u[1], pdf, p);
            assert_int_equal(ll_bsdf_eval(b, mu_i, mu_o, phi, NULL, f), LL_OK);
            if (!(fabs(w[1] - f[1]) <= 1e-6 * w[1] + 1e-12))
                fail_msg("sampled f %g, eval f %g", w[1], f[1]);
            ++samples;
        }
    }
    assert_true(samples > 1000);
    ll_bsdf_release(b);
    free(d);
}

static void expect_cdf_refused(unsigned char *d, const char *needle)
{
    ll_bsdf *b = NULL;
    assert_int_equal(ll_bsdf_open_memory(d, g_size, NULL, &b), LL_ERROR_FORMAT);
    assert_null(b);
    if (!strstr(ll_last_error_message(), needle))
        fail_msg("\"%s\" does not say \"%s\"", ll_last_error_message(), needle);
}

static void real_breakage_refused(void **state)
{
    unsigned char *d = copy_gold();
    size_t row, o = 0;
    float total = 0.0f;
    char where[64];
    (void)state;
    /* A row with light, and an entry inside its rise. */
    for (row = 0; row < G_N && o == 0; ++row) {
        total = cdf(d, row, G_N - 1);
        for (o = 1; total > 0.0f && o + 1 < G_N; ++o)
            if (cdf(d, row, o - 1) > 0.25f * total)
                break;
        if (!(total > 0.0f) || o + 1 >= G_N)
            o = 0;
    }
    --row;
    assert_true(o > 0);
    snprintf(where, sizeof where, "CDF row %zu (basis 0) entry %zu", row, o);
    /* A dip of 1e-3 of the total: not rounding. */
    set_cdf(d, row, o, cdf(d, row, o - 1) - 1e-3f * total);
    expect_cdf_refused(d, "more than the rounding tolerance");
    /* Just beyond the tolerance (2^-20 of the total) is refused too... */
    memcpy(d, g_gold, g_size);
    set_cdf(d, row, o, cdf(d, row, o - 1) - total * (2.0f / 1048576.0f));
    expect_cdf_refused(d, where);
    /* ... a negative total, */
    memcpy(d, g_gold, g_size);
    set_cdf(d, row, G_N - 1, -1e-3f);
    expect_cdf_refused(d, "total");
    /* ... a row that does not start at 0, */
    memcpy(d, g_gold, g_size);
    set_cdf(d, row, 0, 1e-9f);
    expect_cdf_refused(d, "rows must start at 0");
    /* ... and a NaN. */
    memcpy(d, g_gold, g_size);
    set_cdf(d, row, o, NAN);
    expect_cdf_refused(d, "finite");
    free(d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(moved_zero_nodes),
        cmocka_unit_test(golden_finite_and_unchanged_away_from_grazing),
        cmocka_unit_test(huge_coefficients_refused),
        cmocka_unit_test(rounding_dips_open_and_sample_consistently),
        cmocka_unit_test(real_breakage_refused),
    };
    return cmocka_run_group_tests_name("bsdf_finite", tests, setup, teardown);
}
