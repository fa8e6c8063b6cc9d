/*
 * The inner loops (bsdf_kernels.c) in both versions: the portable one,
 * which every machine can run, and the AVX2/FMA one chosen at run time on
 * processors that have it, give the same results up to rounding. The rest
 * of the suite runs whichever this processor selects; this test is what
 * covers the other.
 */
#include "test_bsdf_util.h"
#include "reader/bsdf_internal.h"

static ll_bsdf *open_golden(void)
{
    ll_bsdf *b = NULL;
    assert_int_equal(ll_bsdf_open(LL_TEST_GOLDEN, NULL, &b), LL_OK);
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

/* The recurrence over as many orders as our longest file has and more
 * (2103; here 2400), both versions, against cos(k phi) and sin(k phi) in
 * long double, and the resulting series error against a long-double sum.
 * The recurrence's error grows with k (each step adds a rounding, which
 * the recurrence carries on with a gain that is largest near phi = 0 and
 * pi, where its characteristic roots meet), so the angles include those
 * ends. Measured worst: 5.4e-11 per term at phi = 1e-3 (sine), most of it
 * the rounding of the given cos(phi) carried k times; the bound 2e-10 per
 * term, and 1e-10 of the sum of |a_k| for the series, is 1e4 times below
 * the 1e-6 that results may move. */
#define LONG_ORDERS 2400
static void harmonics_long_accuracy(void **state)
{
    static const double phis[] = { 0.0, 1e-7, 1e-3, 0.05, 0.3, 1.0, 1.5707963267948966,
                                   2.5, 3.14, 3.141592653589793 };
    static double x[LONG_ORDERS];
    size_t k, j;
    int vector;
    (void)state;
    for (vector = 0; vector <= ll_bsdf_kernels_vector(); ++vector)
        for (k = 0; k < sizeof phis / sizeof phis[0]; ++k) {
            int sine;
            for (sine = 0; sine < 2; ++sine) {
                ll_harmonics h;
                long double sum = 0.0L, exact_sum = 0.0L, worst = 0.0L, total = 0.0L;
                ll_bsdf_harmonics_start(&h, cos(phis[k]), sin(phis[k]), sine);
                ll_bsdf_harmonics_next(vector, &h, LONG_ORDERS, x);
                for (j = 0; j < LONG_ORDERS; ++j) {
                    long double angle = (long double)j * (long double)phis[k];
                    long double exact = sine ? sinl(angle) : cosl(angle);
                    long double err = fabsl((long double)x[j] - exact);
                    /* coefficients of a decaying lobe, all positive */
                    long double a = 1.0L / (1.0L + 1e-3L * (long double)j);
                    if (err > worst)
                        worst = err;
                    sum += a * (long double)x[j];
                    total += a;
                    exact_sum += a * exact;
                }
                if (worst > 2e-10L || fabsl(sum - exact_sum) > 1e-10L * total)
                    fail_msg("phi %g %s vector %d: worst term error %Lg, series error %Lg",
                             phis[k], sine ? "sin" : "cos", vector, worst,
                             fabsl(sum - exact_sum));
            }
        }
}

/* Four series summed in one pass, portable against vector, against one
 * series at a time; and the all-channel sum of a gathered series read
 * back through ll_bsdf_series_eval against the stored series themselves. */
static void densify_agrees(void **state)
{
    ll_bsdf *b = open_golden();
    int vector = ll_bsdf_kernels_vector();
    uint64_t rng = 11;
    size_t n;
    (void)state;
    for (n = 0; n < 2000; ++n) {
        static double dense[3 * 1024], p4[1024], v4[1024], one[1024];
        ll_bsdf_series s, d;
        double mu_i = ll_test_uniform(&rng), mu_o = -ll_test_uniform(&rng);
        double cos_phi = cos(LL_TEST_PI * ll_test_uniform(&rng)), ref[3], got[3];
        double scale = 0.0;
        size_t j, m, c;
        assert_true(ll_bsdf_gather(b, mu_i, mu_o, ll_bsdf_unit_basis, &s));
        if (s.count < 4 || s.max_length > 1000)
            continue;
        m = s.length[0];
        for (j = 1; j < 4; ++j)
            if (s.length[j] < m)
                m = s.length[j];
        memset(p4, 0, sizeof p4);
        memset(v4, 0, sizeof v4);
        memset(one, 0, sizeof one);
        {
            const float *a[4];
            double w[4];
            for (j = 0; j < 4; ++j) {
                a[j] = s.coeff[j];
                w[j] = s.weight[j];
                scale += fabs(w[j]);
                ll_bsdf_add_scaled(0, one, a[j], w[j], m);
            }
            ll_bsdf_add_scaled4(0, p4, a, w, m, NULL, 0);
            ll_bsdf_add_scaled4(vector, v4, a, w, m, s.coeff[4], 256);
        }
        for (j = 0; j < m; ++j) {
            assert_true(fabs(p4[j] - v4[j]) <= 1e-14 * (1.0 + scale));
            assert_true(fabs(p4[j] - one[j]) <= 1e-14 * (1.0 + scale));
        }
        ll_bsdf_series_eval(&s, 3, cos_phi, ref);
        ll_bsdf_series_densify_channels(&s, 3, dense, &d);
        ll_bsdf_series_eval(&d, 3, cos_phi, got);
        {
            /* the summed series' dot product, portable against vector */
            ll_harmonics h;
            static double cosines[1024];
            ll_bsdf_harmonics_start(&h, cos_phi, 0.0, 0);
            ll_bsdf_harmonics_next(0, &h, d.dense_stride, cosines);
            for (c = 0; c < 3; ++c) {
                double a = ll_bsdf_dot_dense(0, d.dense + c * d.dense_stride, cosines,
                                             d.dense_stride);
                double v = ll_bsdf_dot_dense(vector, d.dense + c * d.dense_stride, cosines,
                                             d.dense_stride);
                double size = 0.0;
                for (j = 0; j < d.dense_stride; ++j)
                    size += fabs(d.dense[c * d.dense_stride + j]);
                /* rounding of a sum of dense_stride terms: against their size */
                if (fabs(a - v) > 1e-14 * size || fabs(a - ref[c]) > 1e-13 * size)
                    fail_msg("channel %zu: dot %.17g portable, %.17g vector, %.17g series (size %g)",
                             c, a, v, ref[c], size);
            }
        }
        for (c = 0; c < 3; ++c)
            if (!ll_test_close(got[c], ref[c], 1e-12, 1e-15))
                fail_msg("channel %zu: %.17g summed first, %.17g series by series", c, got[c],
                         ref[c]);
        assert_true(ll_bsdf_series_mean(&d) == d.dense[0]);
    }
    ll_bsdf_release(b);
}

/* The evaluation of a long spline-weighted series (16 stored series of
 * up to 4000 orders, longer than any file of ours: coated diffuse has
 * 2103) against a long-double sum of the same float coefficients with
 * cosl(k phi) of the angle the given cosine stands for: the whole-buffer
 * path (<= 2176 orders) and the chunked one (longer) through
 * ll_bsdf_series_eval, and chunk by chunk with each kernel version. Each
 * series stops at its own length (they differ by 37 orders). Measured
 * worst (x86-64 with AVX2, both versions): 1.9e-13 of sum |w a| (mostly
 * the recurrence's error carried over 4000 orders, harmonics_long_accuracy);
 * bound 1e-11, far below the 1e-6 that results may move and below the
 * coefficients' own float rounding (6e-8 of each). LL_TEST_VERBOSE=1
 * prints the worst. */
#define SERIES_ORDERS 4000
static void long_series_against_long_double(void **state)
{
    static float store[LL_BSDF_SERIES_MAX][3 * SERIES_ORDERS + 4];
    static const double phis[] = { 0.0, 1e-6, 0.01, 0.2, 0.7853981, 1.5707963267948966,
                                   2.0, 3.0, 3.14159 };
    /* products of two Catmull-Rom weight rows, some negative */
    static const double w1[4] = { -0.0625, 0.5625, 0.5625, -0.0625 };
    static const double w2[4] = { -0.032, 0.224, 0.864, -0.056 };
    static const uint32_t lengths[2] = { 2103, SERIES_ORDERS };
    uint64_t rng = 17;
    long double worst = 0.0L;
    size_t p, k, c, lk, ph;
    int vector;
    (void)state;
    for (lk = 0; lk < 2; ++lk)
        for (vector = 0; vector <= ll_bsdf_kernels_vector(); ++vector)
            for (ph = 0; ph < sizeof phis / sizeof phis[0]; ++ph) {
                ll_bsdf_series s;
                double cos_phi = cos(phis[ph]), got[3], whole[3];
                long double angle = acosl((long double)cos_phi);
                memset(&s, 0, sizeof s);
                s.count = LL_BSDF_SERIES_MAX;
                s.n_bases = 1;
                s.basis = ll_bsdf_unit_basis;
                s.n_active = 1;
                s.all_bases = 1;
                s.max_length = 0;
                for (p = 0; p < s.count; ++p) {
                    /* lengths differ, so that the sums stop at each one's own */
                    uint32_t len = lengths[lk] - (uint32_t)(37 * p);
                    for (c = 0; c < 3; ++c)
                        for (k = 0; k < len; ++k) {
                            double decay = exp(-(double)k / (0.3 * (double)len));
                            store[p][c * len + k] =
                                (float)((ll_test_uniform(&rng) - 0.3) * decay);
                        }
                    s.coeff[p] = store[p];
                    s.length[p] = len;
                    s.weight[p] = w1[p / 4] * w2[p % 4];
                    if (len > s.max_length)
                        s.max_length = len;
                }
                /* chunk by chunk with the chosen kernels, and the processor's
                 * own path through ll_bsdf_series_eval */
                {
                    ll_harmonics h;
                    double cosines[64];
                    size_t k0;
                    got[0] = got[1] = got[2] = 0.0;
                    ll_bsdf_harmonics_start(&h, cos_phi, 0.0, 0);
                    for (k0 = 0; k0 < s.max_length; k0 += 64) {
                        size_t count = s.max_length - k0 < 64 ? s.max_length - k0 : 64;
                        ll_bsdf_harmonics_next(vector, &h, 64, cosines);
                        ll_bsdf_dot_chunk(vector, &s, 3, k0, count, cosines, got);
                    }
                    ll_bsdf_series_eval(&s, 3, cos_phi, whole);
                }
                for (c = 0; c < 3; ++c) {
                    long double exact = 0.0L, size = 0.0L, e1, e2;
                    for (p = 0; p < s.count; ++p)
                        for (k = 0; k < s.length[p]; ++k) {
                            long double a = (long double)s.weight[p] *
                                            (long double)s.coeff[p][c * s.length[p] + k];
                            exact += a * cosl((long double)k * angle);
                            size += fabsl(a);
                        }
                    e1 = fabsl((long double)got[c] - exact) / size;
                    e2 = fabsl((long double)whole[c] - exact) / size;
                    if (e1 > worst)
                        worst = e1;
                    if (e2 > worst)
                        worst = e2;
                    if (e1 > 1e-11L || e2 > 1e-11L)
                        fail_msg("%u orders, vector %d, phi %g, channel %zu: %.17g chunked, "
                                 "%.17g whole, long double %.17Lg (errors %.3Lg, %.3Lg of the "
                                 "size %.3Lg)",
                                 (unsigned)lengths[lk], vector, phis[ph], c, got[c], whole[c],
                                 exact, e1, e2, size);
                }
            }
    if (getenv("LL_TEST_VERBOSE"))
        print_message("long series: worst error %.3Lg of sum |w a|\n", worst);
}

/* The recurrence over 4096 orders at angles next to j pi / 16 (j = 0 ..
 * 16, offsets +-10^-12 .. 10^-1), where the step's cosine 2 cos(4 phi) is
 * near +-2 and the recurrence is at its worst, both kernel versions. The
 * reference is the angle the given cosine stands for (acosl of it: the
 * rounding of cos(phi) is the caller's, not the recurrence's) for the
 * cosines, the given phi for the sines (which start from sin(phi)).
 * Measured worst: 3.1e-10 (phi = pi/2 - 1e-4, both versions); bound 5e-10
 * per term, far below the 1e-6 that results may move. */
#define SWEEP_ORDERS 4096
static void harmonics_sweep_accuracy(void **state)
{
    static double x[SWEEP_ORDERS];
    long double worst = 0.0L;
    int vector, j, e, side, sine;
    size_t k;
    (void)state;
    for (vector = 0; vector <= ll_bsdf_kernels_vector(); ++vector)
        for (j = 0; j <= 16; ++j)
            for (e = -12; e <= -1; ++e)
                for (side = -1; side <= 1; side += 2) {
                    double phi = LL_TEST_PI * j / 16.0 + side * pow(10.0, e);
                    if (phi < 0.0 || phi > LL_TEST_PI)
                        continue;
                    for (sine = 0; sine < 2; ++sine) {
                        ll_harmonics h;
                        long double angle =
                            sine ? (long double)phi : acosl((long double)cos(phi));
                        ll_bsdf_harmonics_start(&h, cos(phi), sin(phi), sine);
                        ll_bsdf_harmonics_next(vector, &h, SWEEP_ORDERS, x);
                        for (k = 0; k < SWEEP_ORDERS; ++k) {
                            long double a = (long double)k * angle;
                            long double err = fabsl((long double)x[k] - (sine ? sinl(a) : cosl(a)));
                            if (err > worst)
                                worst = err;
                            if (err > 5e-10L)
                                fail_msg("phi %.17g %s vector %d, order %zu: error %Lg", phi,
                                         sine ? "sin" : "cos", vector, k, err);
                        }
                    }
                }
    if (getenv("LL_TEST_VERBOSE"))
        print_message("harmonics sweep: worst error %.3Lg per term\n", worst);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(harmonics_agree),
        cmocka_unit_test(dot_and_integral_agree),
        cmocka_unit_test(harmonics_long_accuracy),
        cmocka_unit_test(harmonics_sweep_accuracy),
        cmocka_unit_test(densify_agrees),
        cmocka_unit_test(long_series_against_long_double),
    };
    return cmocka_run_group_tests_name("bsdf_kernels", tests, NULL, NULL);
}
