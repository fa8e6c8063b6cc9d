/*
 * The fast paths of a rough interface's per-pair series give the doubles
 * of the plain formulas, bit for bit (the resolution search's probes must
 * compute exactly what the build computes, and the build must not depend
 * on the processor's vector units): the profile g in its vector loops
 * (words/microfacet_profile.c) against the formula sample by sample with
 * fresnel.h's kernels; the grid index read from the exponent against the
 * log2 formula; the shortcut of the negligibility test against i0e; and
 * a series computed in two passes (ll_microfacet_series_if_prepared, then
 * prepared) against the series of a model prepared first.
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <string.h>

#include "numerics/series.h"
#include "words/fresnel.h"
#include "words/microfacet.h"
#include "words/microfacet_pair.h"

/* The profile as one loop over the general formula (the text the vector
 * loops replaced): g with F, and with F = 1. */
static void profile_formula(const ll_microfacet_model *mf, const pair_plan *p,
                            const double *cos_phi, size_t count, double *g, double *no_fresnel)
{
    size_t k;
    for (k = 0; k < count; ++k) {
        double t = -p->sin_prod * cos_phi[k] - p->mu_prod, value, f, unused;
        if (p->reflect) {
            double one_t = fmax(0.0, 1.0 + t);
            double cos_h = p->sign_h * sqrt(fmin(1.0, 0.5 * one_t));
            f = mf->conductor ? ll_fresnel_conductor_kernel(fabs(cos_h), mf->eta_re, mf->eta_im)
                              : ll_fresnel_dielectric_kernel(cos_h, mf->eta_re, &unused);
            value = p->scale * one_t * one_t;
            g[k] = f * value;
        } else {
            double wi_h = 1.0 + p->eta * t, wo_h = t + p->eta;
            double len2 = fmax(1e-300, 1.0 + p->eta * p->eta + 2.0 * p->eta * t);
            if (p->sign_h * wi_h * -p->mu_i > 0.0 && p->sign_h * wo_h * p->mu_o > 0.0) {
                double cos_h = fmax(-1.0, fmin(1.0, p->sign_h * wi_h / sqrt(len2)));
                f = ll_fresnel_dielectric_kernel(cos_h, mf->eta_re, &unused);
                value = p->scale * fabs(wi_h * wo_h);
                g[k] = (1.0 - f) * value;
            } else {
                value = 0.0;
                g[k] = 0.0;
            }
        }
        no_fresnel[k] = value;
    }
}

static void assert_same_doubles(const double *a, const double *b, size_t count)
{
    size_t k;
    for (k = 0; k < count; ++k) {
        uint64_t x, y;
        memcpy(&x, a + k, sizeof x);
        memcpy(&y, b + k, sizeof y);
        if (x != y)
            fail_msg("sample %zu: %.17g against %.17g", k, a[k], b[k]);
    }
}

#define SAMPLES 131

/* Every pair of a set of cosines of a model, at azimuths over the whole
 * circle and counts that leave every remainder of the 4- and 2-wide
 * loops: the profile with both outputs, with g alone and with F = 1
 * alone, against the formula. */
static void check_profiles(double eta_re, double eta_im, int distribution)
{
    static const double mu[] = { -0.999, -0.9, -0.6, -0.3, -0.1, -0.02,
                                 0.02,   0.1,  0.3,  0.6,  0.9,  0.999 };
    size_t n_mu = sizeof mu / sizeof mu[0], a, b, k, count, pairs = 0;
    double cos_phi[SAMPLES], want_g[SAMPLES], want_ref[SAMPLES];
    double g[SAMPLES], ref[SAMPLES];
    ll_microfacet_model *mf;
    assert_int_equal(ll_microfacet_create_distribution(eta_re, eta_im, 0.3, distribution, 8, 8, &mf),
                     LL_OK);
    for (k = 0; k < SAMPLES; ++k)
        cos_phi[k] = cos(LL_PI * (double)k / (SAMPLES - 1));
    for (a = 0; a < n_mu; ++a)
        for (b = 0; b < n_mu; ++b) {
            pair_plan p;
            if (!ll_microfacet_plan_pair(mf, mu[a], mu[b], HUGE_VAL, &p))
                continue;
            ++pairs;
            for (count = 1; count <= SAMPLES; count += count < 12 ? 1 : 17) {
                const double *c = cos_phi + (SAMPLES - count) / 2;
                profile_formula(mf, &p, c, count, want_g, want_ref);
                ll_microfacet_sample_profile(mf, &p, c, count, g, ref);
                assert_same_doubles(g, want_g, count);
                assert_same_doubles(ref, want_ref, count);
                memset(g, 0, sizeof g);
                ll_microfacet_sample_profile(mf, &p, c, count, g, NULL);
                assert_same_doubles(g, want_g, count);
                memset(ref, 0, sizeof ref);
                ll_microfacet_sample_profile(mf, &p, c, count, NULL, ref);
                assert_same_doubles(ref, want_ref, count);
            }
        }
    assert_true(pairs > n_mu); /* (the check saw reflection and, for a
                                * dielectric, refraction) */
    ll_microfacet_destroy(mf);
}

static void profile_loops_give_the_formulas_doubles(void **state)
{
    (void)state;
    check_profiles(1.5, 0.0, LL_DISTRIBUTION_BECKMANN);
    check_profiles(1.0 / 1.5, 0.0, LL_DISTRIBUTION_BECKMANN);
    check_profiles(1.0, 0.0, LL_DISTRIBUTION_BECKMANN); /* (eta 1: no Fresnel) */
    check_profiles(0.18, 3.4, LL_DISTRIBUTION_BECKMANN);
    check_profiles(1.5, 0.0, LL_DISTRIBUTION_GGX);
    check_profiles(1.1, 2.0, LL_DISTRIBUTION_GGX);
}

/* The index by log2, floored, guarded from above (the formula the
 * exponent's reading stands for). */
static size_t grid_index_formula(double b)
{
    size_t k;
    if (b < 1.0 / 16.0)
        return 0;
    k = (size_t)floor(4.0 * (log2(b) - log2(1.0 / 16.0))) + 1;
    while (k > 1 && ll_microfacet_grid_b(k) > b)
        --k;
    return k;
}

static void grid_index_matches_the_log2_formula(void **state)
{
    size_t k;
    int d;
    double b;
    (void)state;
    for (b = 1e-3; b < 1e300; b *= 1.0001)
        assert_int_equal(ll_microfacet_grid_index(b), grid_index_formula(b));
    /* around every grid point up to B = 2^60: 40 ulps and +-1e-9 on each side */
    for (k = 1; k < 4 * 64; ++k) {
        double at = ll_microfacet_grid_b(k), x = at, y = at;
        for (d = 0; d < 40; ++d) {
            x = nextafter(x, 0.0);
            y = nextafter(y, HUGE_VAL);
            assert_int_equal(ll_microfacet_grid_index(x), grid_index_formula(x));
            assert_int_equal(ll_microfacet_grid_index(y), grid_index_formula(y));
        }
        assert_int_equal(ll_microfacet_grid_index(at), k);
        for (d = -100; d <= 100; ++d) {
            x = at * (1.0 + (double)d * 2e-11);
            assert_int_equal(ll_microfacet_grid_index(x), grid_index_formula(x));
        }
    }
    assert_int_equal(ll_microfacet_grid_index(HUGE_VAL / 2), grid_index_formula(HUGE_VAL / 2));
}

/* The plan's negligibility shortcut keeps a pair where e^(A + B) / (2
 * sqrt(1 + 2 pi B)) reaches its bound, trusting i0e(B) >= 1 / sqrt(1 +
 * 2 pi B): that bound, over the B of every pair. */
static void i0e_stays_above_the_plans_bound(void **state)
{
    double b;
    (void)state;
    for (b = 0.0; b < 1e-3; b += 1e-6)
        assert_true(ll_bessel_i0e(b) * sqrt(1.0 + 2.0 * LL_PI * b) >= 1.0);
    for (b = 1e-3; b < 1e9; b *= 1.001)
        assert_true(ll_bessel_i0e(b) * sqrt(1.0 + 2.0 * LL_PI * b) >= 1.0);
}

/* A model asked first for pairs it has no maps for reports them, and
 * once they are prepared gives the series of a model prepared first. */
static void series_if_prepared_reports_and_then_matches(void **state)
{
    static const double mu[] = { -0.95, -0.7, -0.4, -0.15, 0.15, 0.4, 0.7, 0.95 };
    size_t n_mu = sizeof mu / sizeof mu[0], a, b, len, want_len, reported = 0;
    double scratch[MICROFACET_SCRATCH(1)], v, want, ref, want_ref;
    ll_microfacet_model *lazy, *ready;
    int missing;
    (void)state;
    assert_int_equal(ll_microfacet_create(0.2, 3.0, 0.2, 1 << 20, 1, &lazy), LL_OK);
    assert_int_equal(ll_microfacet_create(0.2, 3.0, 0.2, 1 << 20, 1, &ready), LL_OK);
    assert_int_equal(ll_microfacet_prepare(ready, mu, n_mu), LL_OK);
    for (a = 0; a < n_mu; ++a)
        for (b = 0; b < n_mu; ++b) {
            assert_int_equal(ll_microfacet_series(ready, mu[a], mu[b], 1, &want, &want_len,
                                                  &want_ref, scratch),
                             LL_OK);
            assert_int_equal(ll_microfacet_series_if_prepared(lazy, mu[a], mu[b], 1, &v, &len,
                                                              &ref, scratch, &missing),
                             LL_OK);
            if (missing) {
                ++reported;
                assert_int_equal(ll_microfacet_prepare_pairs(lazy, mu + a, mu + b, 1), LL_OK);
                assert_int_equal(ll_microfacet_series_if_prepared(lazy, mu[a], mu[b], 1, &v,
                                                                  &len, &ref, scratch,
                                                                  &missing),
                                 LL_OK);
                assert_false(missing);
            }
            assert_int_equal(len, want_len);
            if (len > 0) {
                assert_memory_equal(&v, &want, sizeof v);
                assert_memory_equal(&ref, &want_ref, sizeof ref);
            }
        }
    assert_true(reported > 0);
    ll_microfacet_destroy(lazy);
    ll_microfacet_destroy(ready);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(profile_loops_give_the_formulas_doubles),
        cmocka_unit_test(grid_index_matches_the_log2_formula),
        cmocka_unit_test(i0e_stays_above_the_plans_bound),
        cmocka_unit_test(series_if_prepared_reports_and_then_matches),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
