/*
 * Fresnel reflectance (ll_fresnel_*): closed-form special cases, an
 * independent complex-amplitude implementation, and hemispherical averages
 * against composite Simpson integration and published fits.
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <complex.h>
#include <math.h>
#include <string.h>

#include <layerlab.h>

/* The unpolarised reflectance from the complex amplitudes of Born and Wolf
 * (section 1.5.2 and 14.2): cos_t = sqrt(1 - sin_i^2 / eta^2), principal
 * branch, which gives the evanescent wave under total internal reflection
 * and the damped one in a conductor. Written independently of the library's
 * real-arithmetic forms (Moeller's for conductors). */
static double fresnel_complex(double cos_i, double complex eta)
{
    double complex ct = csqrt(1.0 - (1.0 - cos_i * cos_i) / (eta * eta));
    double complex rs = (cos_i - eta * ct) / (cos_i + eta * ct);
    double complex rp = (eta * cos_i - ct) / (eta * cos_i + ct);
    double a = cabs(rs), b = cabs(rp);
    return 0.5 * (a * a + b * b);
}

/* The reflectances as values; each call must succeed. */
static double dielectric(double cos_i, double eta, double *cos_t)
{
    double r = -1.0;
    assert_int_equal(ll_fresnel_dielectric(cos_i, eta, &r, cos_t), LL_OK);
    return r;
}

static double conductor(double cos_i, double eta_re, double eta_im)
{
    double r = -1.0;
    assert_int_equal(ll_fresnel_conductor(cos_i, eta_re, eta_im, &r), LL_OK);
    return r;
}

static double dielectric_average(double eta)
{
    double r = -1.0;
    assert_int_equal(ll_fresnel_dielectric_average(eta, &r), LL_OK);
    return r;
}

static double conductor_average(double eta_re, double eta_im)
{
    double r = -1.0;
    assert_int_equal(ll_fresnel_conductor_average(eta_re, eta_im, &r), LL_OK);
    return r;
}

static void normal_incidence_and_snell(void **state)
{
    double ct, eta = 1.5, r0 = (eta - 1.0) / (eta + 1.0);
    (void)state;
    assert_float_equal(dielectric(1.0, eta, &ct), r0 * r0, 1e-15);
    assert_float_equal(ct, -1.0, 1e-15);
    /* From the other side the reflectance at normal incidence is the same. */
    assert_float_equal(dielectric(-1.0, eta, &ct), r0 * r0, 1e-15);
    assert_float_equal(ct, 1.0, 1e-15);
    /* Snell: sin_t = sin_i / eta, leaving into the other side. */
    dielectric(0.6, eta, &ct);
    assert_float_equal(ct, -sqrt(1.0 - 0.64 / (eta * eta)), 1e-15);
    dielectric(-0.9, eta, &ct);
    assert_float_equal(ct, sqrt(1.0 - 0.19 * eta * eta), 1e-15);
    /* Index-matched: nothing reflects, the ray goes straight on. */
    assert_float_equal(dielectric(0.3, 1.0, &ct), 0.0, 0.0);
    assert_float_equal(ct, -0.3, 0.0);
    /* Grazing incidence reflects everything. */
    assert_float_equal(dielectric(0.0, eta, NULL), 1.0, 1e-15);
}

static void total_internal_reflection(void **state)
{
    double ct, eta = 1.5, cos_crit = sqrt(1.0 - 1.0 / (eta * eta));
    (void)state;
    /* Inside the denser medium, beyond the critical angle. */
    assert_float_equal(dielectric(-0.5 * cos_crit, eta, &ct), 1.0, 0.0);
    assert_float_equal(ct, 0.0, 0.0);
    /* The same boundary given from the dense side (eta < 1, cos > 0). */
    assert_float_equal(dielectric(0.5 * cos_crit, 1.0 / eta, &ct), 1.0, 0.0);
    /* Just inside the critical angle it is still below 1, and rises
     * continuously (like a square root) to it. */
    {
        double f = dielectric(-(cos_crit + 1e-6), eta, NULL);
        double g = dielectric(-(cos_crit + 1e-10), eta, NULL);
        assert_true(f < g && g < 1.0);
        assert_true(f > 0.98 && g > 0.9998);
    }
}

static void dielectric_matches_complex_amplitudes(void **state)
{
    static const double etas[] = { 1.0001, 1.33, 1.5, 2.4, 0.75, 1.0 / 1.5 };
    size_t e;
    int k;
    (void)state;
    for (e = 0; e < sizeof etas / sizeof etas[0]; ++e)
        for (k = -50; k <= 50; ++k) {
            double c = k / 50.0;
            /* cos_i < 0: from the other side, relative index 1/eta. */
            double complex rel = c >= 0.0 ? etas[e] : 1.0 / etas[e];
            if (k == 0)
                continue;
            assert_float_equal(dielectric(c, etas[e], NULL),
                               fresnel_complex(fabs(c), rel), 1e-13);
        }
}

static void conductor_matches_complex_amplitudes(void **state)
{
    /* Gold's RGB index of tests/data, aluminium near 550 nm, a weak
     * absorber, and the mirror eta = i (which reflects everything). */
    static const double idx[][2] = { { 0.14355224039215753, 3.9839744793223466 },
                                     { 0.3774377780596837, 2.384954234733302 },
                                     { 1.4382481043262747, 1.6043381450132959 },
                                     { 0.96, 6.69 },
                                     { 1.5, 0.01 },
                                     { 0.0, 1.0 } };
    size_t e;
    int k;
    (void)state;
    for (e = 0; e < sizeof idx / sizeof idx[0]; ++e)
        for (k = 0; k <= 100; ++k) {
            double c = k / 100.0;
            assert_float_equal(conductor(c, idx[e][0], idx[e][1]),
                               fresnel_complex(c, idx[e][0] + I * idx[e][1]), 1e-12);
        }
    for (k = 0; k <= 10; ++k)
        assert_float_equal(conductor(k / 10.0, 0.0, 1.0), 1.0, 1e-15);
}

static void conductor_without_absorption_is_a_dielectric(void **state)
{
    int k;
    (void)state;
    for (k = 0; k <= 20; ++k) {
        double c = k / 20.0;
        assert_float_equal(conductor(c, 1.5, 0.0), dielectric(c, 1.5, NULL),
                           1e-14);
        /* eta < 1: total internal reflection, as the dielectric. */
        assert_float_equal(conductor(c, 0.7, 0.0), dielectric(c, 0.7, NULL),
                           1e-14);
    }
}

/* 2 * integral_a^b F mu dmu by composite Simpson with n (even) intervals. */
static double simpson_flux(double a, double b, int n, double eta_re, double eta_im)
{
    double h = (b - a) / n, sum = 0.0;
    int k;
    for (k = 0; k <= n; ++k) {
        double mu = a + k * h;
        double f = fresnel_complex(mu, eta_re + I * eta_im);
        sum += (k == 0 || k == n ? 1.0 : k % 2 ? 4.0 : 2.0) * f * mu;
    }
    return 2.0 * sum * h / 3.0;
}

static void averages_match_integration(void **state)
{
    static const double etas[] = { 1.1, 1.33, 1.5, 2.0, 4.0 };
    size_t e;
    (void)state;
    for (e = 0; e < sizeof etas / sizeof etas[0]; ++e) {
        double eta = etas[e], inv = 1.0 / eta, mu_c = sqrt(1.0 - inv * inv);
        /* Outside: smooth on [0, 1]. Inside: total reflection below mu_c,
         * a square-root kink there, so Simpson only above it (2e5 intervals:
         * the kink costs ~1e-9). */
        double outside = simpson_flux(0.0, 1.0, 20000, eta, 0.0);
        double inside = mu_c * mu_c + simpson_flux(mu_c, 1.0, 200000, inv, 0.0);
        assert_float_equal(dielectric_average(eta), outside, 1e-9);
        assert_float_equal(dielectric_average(inv), inside, 1e-8);
        /* Detailed balance across the boundary. */
        assert_float_equal(1.0 - dielectric_average(eta),
                           eta * eta * (1.0 - dielectric_average(inv)), 1e-13);
    }
    assert_float_equal(dielectric_average(1.0), 0.0, 0.0);
    assert_float_equal(conductor_average(0.14355224039215753, 3.9839744793223466),
                       simpson_flux(0.0, 1.0, 20000, 0.14355224039215753, 3.9839744793223466),
                       1e-10);
    assert_float_equal(conductor_average(0.96, 6.69),
                       simpson_flux(0.0, 1.0, 20000, 0.96, 6.69), 1e-10);
    assert_float_equal(conductor_average(0.0, 1.0), 1.0, 1e-13);
    assert_float_equal(conductor_average(1.5, 0.0), dielectric_average(1.5),
                       1e-15);
}

/* The fits the original layerlab uses instead of integrating: d'Eon and
 * Irving 2011 for eta > 1, Egan and Hilgeman 1973 for eta < 1. Where they
 * are meant to be good (eta 1.2-2.5, 1/eta 1.2-1.8) they agree with the
 * integral to 0.1% (measured: at most 7.3e-4 and 1.04e-3 relative). */
static void averages_match_published_fits(void **state)
{
    static const double etas[] = { 1.2, 1.33, 1.5, 1.8, 2.5 };
    size_t e;
    (void)state;
    for (e = 0; e < sizeof etas / sizeof etas[0]; ++e) {
        double eta = etas[e], x = 1.0 / eta;
        double deon = 0.919317 - 3.4793 * x + 6.75335 * x * x - 7.80989 * x * x * x +
                      4.98554 * x * x * x * x - 1.36881 * x * x * x * x * x;
        double egan = -1.4399 * x * x + 0.7099 * x + 0.6681 + 0.0636 / x;
        double outside = dielectric_average(eta);
        double inside = dielectric_average(x);
        assert_true(fabs(outside - deon) <= 1e-3 * outside);
        if (eta <= 1.8)
            assert_true(fabs(inside - egan) <= 1.2e-3 * inside);
    }
    /* The often quoted value for glass. */
    assert_float_equal(dielectric_average(1.5), 0.0918, 1e-4);
}

/* Failure is a status and a message, with the outputs 0 (never NaN). */
static void invalid_arguments_fail_with_zero(void **state)
{
    double r = -1.0, ct = -1.0;
    (void)state;
    assert_int_equal(ll_fresnel_dielectric(1.5, 1.5, &r, &ct), LL_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(ll_last_error_message(), "ll_fresnel_dielectric"));
    assert_true(r == 0.0 && ct == 0.0);
    r = -1.0;
    assert_int_equal(ll_fresnel_dielectric(0.5, 0.0, &r, NULL), LL_ERROR_INVALID_ARGUMENT);
    assert_true(r == 0.0);
    assert_int_equal(ll_fresnel_dielectric(NAN, 1.5, &r, NULL), LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_fresnel_dielectric(0.5, INFINITY, &r, NULL), LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_fresnel_dielectric(0.5, 1.5, NULL, NULL), LL_ERROR_INVALID_ARGUMENT);
    r = -1.0;
    assert_int_equal(ll_fresnel_conductor(-0.1, 1.0, 1.0, &r), LL_ERROR_INVALID_ARGUMENT);
    assert_true(r == 0.0);
    assert_int_equal(ll_fresnel_conductor(0.5, -1.0, 1.0, &r), LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_fresnel_conductor(0.5, 1.0, -1.0, &r), LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_fresnel_conductor(0.5, 0.0, 0.0, &r), LL_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(ll_last_error_message(), "eta must not be 0"));
    assert_int_equal(ll_fresnel_conductor(0.5, 1.0, 1.0, NULL), LL_ERROR_INVALID_ARGUMENT);
    r = -1.0;
    assert_int_equal(ll_fresnel_dielectric_average(-1.0, &r), LL_ERROR_INVALID_ARGUMENT);
    assert_true(r == 0.0);
    r = -1.0;
    assert_int_equal(ll_fresnel_conductor_average(NAN, 1.0, &r), LL_ERROR_INVALID_ARGUMENT);
    assert_true(r == 0.0);
    assert_int_equal(ll_fresnel_dielectric_average(1.5, NULL), LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_fresnel_conductor_average(1.0, 1.0, NULL), LL_ERROR_INVALID_ARGUMENT);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(normal_incidence_and_snell),
        cmocka_unit_test(total_internal_reflection),
        cmocka_unit_test(dielectric_matches_complex_amplitudes),
        cmocka_unit_test(conductor_matches_complex_amplitudes),
        cmocka_unit_test(conductor_without_absorption_is_a_dielectric),
        cmocka_unit_test(averages_match_integration),
        cmocka_unit_test(averages_match_published_fits),
        cmocka_unit_test(invalid_arguments_fail_with_zero),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
