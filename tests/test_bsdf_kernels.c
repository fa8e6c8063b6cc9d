/*
 * The inner loops (bsdf_kernels.c) in both versions: the portable one,
 * which every machine can run, and the AVX2/FMA one chosen at run time on
 * processors that have it, give the same results up to rounding. The rest
 * of the suite runs whichever this processor selects; this test is what
 * covers the other.
 */
#include "test_bsdf_util.h"
#include "storage/bsdf_internal.h"

static ll_bsdf *open_golden(void)
{
    ll_bsdf *b = NULL;
    assert_int_equal(ll_bsdf_open(LL_TEST_GOLDEN, &b), LL_OK);
    return b;
}

static void harmonics_agree(void **state)
{
    static const double phis[] = { 0.0, 0.3, 1.0, 1.5707963267948966, 2.5, 3.14159265358979 };
    size_t k, j;
    (void)state;
    for (k = 0; k < sizeof phis / sizeof phis[0]; ++k) {
        ll_harmonics a, b;
        double x[64], y[64], c = cos(phis[k]), s = sin(phis[k]);
        int sine;
        for (sine = 0; sine < 2; ++sine) {
            ll_bsdf_harmonics_start(&a, c, s, sine);
            ll_bsdf_harmonics_start(&b, c, s, sine);
            ll_bsdf_harmonics_next(0, &a, 64, x);
            ll_bsdf_harmonics_next(ll_bsdf_kernels_vector(), &b, 64, y);
            for (j = 0; j < 64; ++j) {
                double exact = sine ? sin((double)j * phis[k]) : cos((double)j * phis[k]);
                assert_true(fabs(x[j] - exact) < 1e-12);
                assert_true(fabs(y[j] - exact) < 1e-12);
            }
        }
    }
}

/* Dot products of gathered series (1 and 3 channels, both chunk positions)
 * and the fused integral of a dense series, portable against vector. */
static void dot_and_integral_agree(void **state)
{
    ll_bsdf *b = open_golden();
    int vector = ll_bsdf_kernels_vector();
    uint64_t rng = 3;
    size_t n;
    (void)state;
    for (n = 0; n < 3000; ++n) {
        ll_bsdf_series s;
        double mu_i = ll_test_uniform(&rng), mu_o = -ll_test_uniform(&rng), h[64];
        double p1[3] = { 0, 0, 0 }, v1[3] = { 0, 0, 0 }, p3[3] = { 0, 0, 0 };
        double v3[3] = { 0, 0, 0 }, scale = 0.0;
        ll_harmonics hc, hsn;
        double phi = LL_TEST_PI * ll_test_uniform(&rng);
        size_t j, k0, c;
        int ok = ll_bsdf_gather(b, mu_i, mu_o, ll_bsdf_unit_basis, &s);
        assert_true(ok);
        if (s.count == 0)
            continue;
        for (k0 = 0; k0 < s.max_length; k0 += 64) {
            size_t count = s.max_length - k0 < 64 ? s.max_length - k0 : 64;
            for (j = 0; j < 64; ++j)
                h[j] = cos((double)(k0 + j) * phi);
            ll_bsdf_dot_chunk(0, &s, 1, k0, count, h, p1);
            ll_bsdf_dot_chunk(vector, &s, 1, k0, count, h, v1);
            ll_bsdf_dot_chunk(0, &s, 3, k0, count, h, p3);
            ll_bsdf_dot_chunk(vector, &s, 3, k0, count, h, v3);
        }
        for (j = 0; j < s.count; ++j)
            scale += fabs(s.weight[j]) * (double)s.length[j];
        assert_true(fabs(p1[0] - v1[0]) <= 1e-13 * (1.0 + scale));
        assert_true(fabs(p1[0] - p3[0]) <= 1e-13 * (1.0 + scale));
        for (c = 0; c < 3; ++c)
            assert_true(fabs(p3[c] - v3[c]) <= 1e-13 * (1.0 + scale));
        /* Dense series: summed both ways, then the fused F and f. */
        {
            double dp[1024], dv[1024], F1, f1, F2, f2;
            ll_bsdf_series d1, d2;
            if (s.max_length > 1000)
                continue;
            memset(dp, 0, sizeof dp);
            memset(dv, 0, sizeof dv);
            for (j = 0; j < s.count; ++j) {
                ll_bsdf_add_scaled(0, dp, s.coeff[j], s.weight[j], s.length[j]);
                ll_bsdf_add_scaled(vector, dv, s.coeff[j], s.weight[j], s.length[j]);
            }
            for (j = 0; j < s.max_length; ++j)
                assert_true(fabs(dp[j] - dv[j]) <= 1e-14 * (1.0 + scale));
            ll_bsdf_series_densify(&s, dp, &d1);
            d2 = d1;
            ll_bsdf_harmonics_start(&hc, cos(phi), sin(phi), 0);
            ll_bsdf_harmonics_start(&hsn, cos(phi), sin(phi), 1);
            k0 = (s.max_length + 3) & ~(size_t)3;
            ll_bsdf_integral_dense(0, d1.dense, b->recip, k0, &hc, &hsn, &F1, &f1);
            ll_bsdf_integral_dense(vector, d2.dense, b->recip, k0, &hc, &hsn, &F2, &f2);
            assert_true(fabs(F1 - F2) <= 1e-13 * (1.0 + scale));
            assert_true(fabs(f1 - f2) <= 1e-13 * (1.0 + scale));
            /* and f is the series: against the 1-channel dot above */
            assert_true(fabs(f1 - p1[0]) <= 1e-12 * (1.0 + scale));
        }
    }
    ll_bsdf_release(b);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(harmonics_agree),
        cmocka_unit_test(dot_and_integral_agree),
    };
    return cmocka_run_group_tests_name("bsdf_kernels", tests, NULL, NULL);
}
