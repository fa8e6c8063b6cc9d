/*
 * GGX (Trowbridge-Reitz) rough interfaces: the per-pair Fourier series
 * against direct integration of the closed-form BSDF (random pairs,
 * grazing pairs, the kinks of total internal reflection and of the end of
 * refraction; alpha 0.02 to 1; gold-like conductor, dielectric from both
 * sides), single scattering against an independent integration over the
 * half vectors (a white furnace: F = 1), reciprocity and the eta^2 relation
 * of transmission, and the energy compensation.
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
#include "microfacet_check.h"
#include "words/microfacet.h"
#include "words/microfacet_ggx.h"
#include "search/probe.h"
#include "words/heuristics.h"

#define GOLD_RE 0.2
#define GOLD_IM 3.5

/* The public Fresnel reflectances as values (0 on failure). */
static double fresnel_conductor(double cos_i, double eta_re, double eta_im)
{
    double r = 0.0;
    return ll_fresnel_conductor(cos_i, eta_re, eta_im, &r) == LL_OK ? r : 0.0;
}

static double fresnel_dielectric(double cos_i, double eta, double *cos_t)
{
    double r = 0.0;
    return ll_fresnel_dielectric(cos_i, eta, &r, cos_t) == LL_OK ? r : 0.0;
}

/* ----------------------------------------------- the closed-form BSDF
 * Written out in vectors (microfacet_check.h), independently of
 * microfacet_ggx.c too: Walter et al. 2007 with GGX's D and exact Smith
 * G1. */

static double ggx_d(const double *m, double alpha)
{
    double c2 = m[2] * m[2], t2 = (1.0 - c2) / c2, a2 = alpha * alpha;
    double q = a2 + t2;
    return a2 / (LL_PI * c2 * c2 * q * q);
}

static double ggx_g1(const double *v, const double *m, double alpha)
{
    double t2 = (1.0 - v[2] * v[2]) / (v[2] * v[2]);
    if (dot3(v, m) * v[2] <= 0.0)
        return 0.0;
    return 2.0 / (1.0 + sqrt(1.0 + alpha * alpha * t2));
}

static double closed_form(const series_case *c, double mu_o, double mu_i, double phi)
{
    mf_geometry q;
    double f, g;
    if (!mf_geometry_set(&q, mu_o, mu_i, c->eta_re, c->eta_im, phi))
        return 0.0;
    f = c->eta_im != 0.0 ? fresnel_conductor(fabs(q.wih), c->eta_re, c->eta_im)
                         : fresnel_dielectric(q.wih, c->eta_re, NULL);
    g = ggx_g1(q.wi, q.h, c->alpha) * ggx_g1(q.wo, q.h, c->alpha);
    return mf_walter(&q, mu_o, mu_i, f, ggx_d(q.h, c->alpha), g);
}

/* ------------------------------- the series against direct integration */

/* beta of the pair (words/microfacet_ggx.h): B / (1 + X_0) from the
 * half-vector geometry, tan^2(theta_h) = (lateral^2 + 2 k si so (1 - cos
 * phi)) / h_z^2 with H = wi + k wo. */
static double peak_sharpness(const series_case *c, double mu_o, double mu_i)
{
    int reflect = -mu_i * mu_o > 0.0;
    double eta = (-mu_i > 0.0 || c->eta_im != 0.0) ? c->eta_re : 1.0 / c->eta_re;
    double k = reflect ? 1.0 : eta, h_z = k * mu_o - mu_i;
    double si = sqrt(1.0 - mu_i * mu_i), so = sqrt(1.0 - mu_o * mu_o);
    double x0 = (si - k * so) * (si - k * so) / (c->alpha * c->alpha * h_z * h_z);
    return 2.0 * k * si * so / (c->alpha * c->alpha * h_z * h_z) / (1.0 + x0);
}

#define REF_POINTS 16001 /* samples of [0, pi]: 20+ points per lobe width */
#define MAX_ORDERS 800
#define MAX_BETA 5000.0

/* ------------------------------------------------- the reference's kinks
 * f is not smooth where total internal reflection starts (Fresnel's square
 * root at the critical azimuth) and where refraction ends (G1 falls to 0).
 * Composite Simpson on a uniform grid over such a point errs like h^1.5
 * times the square root's coefficient in every cosine coefficient alike,
 * and those errors add up in the series at the kink: at grazing pairs at
 * alpha 1 (f flat up to the critical azimuth, where it falls by half
 * within 0.05) to 4e-4 of the peak with 16001 points, of a series that is
 * within 1.1e-4. So the reference integrates each piece between the kinks
 * in x, phi = a + (b - a)(3 x^2 - 2 x^3), whose derivative vanishes at both
 * ends and turns a square root there into a smooth function of x. */

/* Which side of the kinks phi lies on, f being the closed form there: f = 0
 * (no refraction, or a facet seen from behind), and total internal
 * reflection at the half vector (the index the light meets below 1, sin^2
 * beyond it). */
static int kink_side(const series_case *c, double mu_o, double mu_i, double phi, double f)
{
    mf_geometry q;
    int side = f == 0.0;
    if (c->eta_im == 0.0 && mf_geometry_set(&q, mu_o, mu_i, c->eta_re, c->eta_im, phi) &&
        q.reflect && q.eta < 1.0 && 1.0 - q.wih * q.wih > q.eta * q.eta)
        side += 2;
    return side;
}

/* Adds (2 - [l = 0]) / pi times the integral of f cos(l phi) over [a, b],
 * l < len, by composite Simpson in x (above) on the odd number of samples
 * that spacing h of [a, b] takes. */
static void add_piece(const series_work *w, const series_case *c, double mu_o, double mu_i,
                      double a, double b, double h, size_t len)
{
    size_t points, k, l;
    double hx;
    if (!(b > a))
        return; /* two kinks a rounding apart: no piece between them */
    points = 2 * (size_t)ceil(0.5 * (b - a) / h) + 1;
    hx = 1.0 / (double)(points - 1);
    for (k = 0; k < points; ++k) {
        double x = (double)k * hx, phi = a + (b - a) * x * x * (3.0 - 2.0 * x);
        double jac = (b - a) * 6.0 * x * (1.0 - x), c1 = cos(phi), prev = c1, cur = 1.0;
        double wk = (k == 0 || k == points - 1 ? 1.0 : k % 2 ? 4.0 : 2.0) * hx / 3.0 * jac *
                    closed_form(c, mu_o, mu_i, phi) / LL_PI;
        for (l = 0; l < len; ++l) {
            double next = 2.0 * c1 * cur - prev;
            w->ref[l] += (l == 0 ? wk : 2.0 * wk) * cur;
            prev = cur;
            cur = next;
        }
    }
}

/* The reference's coefficients, l < len, from f at the uniform samples
 * w->f, which locate the kinks to a sample (bisection then to rounding);
 * the pieces share the samples' spacing. */
static void kinked_cosine_series(series_work *w, const series_case *c, double mu_o, double mu_i,
                                 size_t len)
{
    double h = LL_PI / (double)(w->ref_points - 1), a = 0.0;
    size_t k;
    int before = kink_side(c, mu_o, mu_i, 0.0, w->f[0]);
    memset(w->ref, 0, len * sizeof *w->ref);
    for (k = 1; k < w->ref_points; ++k) {
        double lo = (double)(k - 1) * h, hi = (double)k * h;
        int after = kink_side(c, mu_o, mu_i, hi, w->f[k]), it;
        if (after == before)
            continue;
        for (it = 0; it < 60; ++it) {
            double mid = 0.5 * (lo + hi);
            if (kink_side(c, mu_o, mu_i, mid, closed_form(c, mu_o, mu_i, mid)) == before)
                lo = mid;
            else
                hi = mid;
        }
        add_piece(w, c, mu_o, mu_i, a, hi, h, len);
        a = hi;
        before = after;
    }
    add_piece(w, c, mu_o, mu_i, a, LL_PI, h, len);
}

/* Fixed pairs: with a kink (critical azimuth of total internal reflection,
 * end of refraction) inside [0, pi], grazing on one or both sides, and near
 * normal incidence. The last two reflect from the denser side of eta 1.5
 * and of 1/1.5, grazing on both: at alpha 1, f is flat up to the critical
 * azimuth and falls by half within 0.05 after it, which a reference
 * without the kinks' pieces misses by 4e-4 of the peak. */
static void kink_pairs(double *pairs, size_t *count)
{
    static const double fixed[][2] = {
        { -0.6608, 0.8136 }, { -0.7047, 0.7621 }, { -0.5338, 0.8532 }, { 0.6154, 0.8381 },
        { -0.0112, 0.1051 }, { -0.2323, 0.5485 }, { 0.3, -0.4 },       { 0.8, -0.2 },
        { -0.9, -0.3 },      { 0.5, 0.5 },        { 0.05, 0.9 },       { -0.03, 0.04 },
        { 0.02, -0.03 },     { -0.05, -0.02 },    { 0.015, 0.99 },     { -0.999, 0.02 },
        { -0.0618, 0.0229 }, { 0.0586, -0.0237 },
    };
    size_t k;
    for (k = 0; k < sizeof fixed / sizeof fixed[0]; ++k) {
        pairs[2 * k] = fixed[k][0];
        pairs[2 * k + 1] = fixed[k][1];
    }
    *count = k;
}

/* Pairs per alpha and index: 40 (6 of them random grazing ones), or with
 * LL_GGX_WIDE set (not 0) the wider sample of 1000 (330 grazing), which
 * takes minutes. */
static size_t sample_pairs(size_t *grazing)
{
    const char *v = getenv("LL_GGX_WIDE");
    int wide = v && *v && strcmp(v, "0") != 0;
    *grazing = wide ? 330 : 6;
    return wide ? 1000 : 40;
}

static void series_matches_direct_integration(void **state)
{
    static const double alphas[] = { 0.02, 0.05, 0.1, 0.3, 0.6, 1.0 };
    static const double idx[][2] = { { 1.5, 0.0 }, { 1.0 / 1.5, 0.0 }, { GOLD_RE, GOLD_IM } };
    series_work work;
    double worst = 0.0, worst_case[3] = { 0 };
    double fixed[64];
    double beta_max = fmin(MAX_BETA, ll_ggx_max_beta(MAX_ORDERS, LL_MICROFACET_RELERR));
    uint64_t rng = 12345;
    size_t ai, ei, p, tested = 0, n_fixed, n_grazing, n_pairs = sample_pairs(&n_grazing);
    (void)state;
    series_work_init(&work, REF_POINTS, MAX_ORDERS, closed_form);
    work.reference = kinked_cosine_series;
    kink_pairs(fixed, &n_fixed);
    for (ai = 0; ai < sizeof alphas / sizeof alphas[0]; ++ai)
        for (ei = 0; ei < 3; ++ei) {
            series_case c;
            ll_microfacet_model *mf;
            c.eta_re = idx[ei][0];
            c.eta_im = idx[ei][1];
            c.alpha = alphas[ai];
            assert_int_equal(ll_microfacet_create_distribution(c.eta_re, c.eta_im, c.alpha,
                                                               LL_DISTRIBUTION_GGX, MAX_ORDERS,
                                                               MAX_ORDERS, &mf),
                             LL_OK);
            for (p = 0; p < n_pairs; ++p) {
                double mu_o, mu_i, e;
                if (p < n_fixed) {
                    mu_o = fixed[2 * p];
                    mu_i = fixed[2 * p + 1];
                } else if (p < n_fixed + n_grazing) { /* grazing pairs */
                    mu_o = (uniform(&rng) < 0.5 ? -1.0 : 1.0) * (0.01 + 0.1 * uniform(&rng));
                    mu_i = (uniform(&rng) < 0.5 ? -1.0 : 1.0) * (0.01 + 0.1 * uniform(&rng));
                } else {
                    mu_o = 2.0 * uniform(&rng) - 1.0;
                    mu_i = 2.0 * uniform(&rng) - 1.0;
                }
                /* Only lobes that the series holds without widening (and the
                 * reference resolves). */
                if (fabs(mu_o) < 0.01 || fabs(mu_i) < 0.01 ||
                    peak_sharpness(&c, mu_o, mu_i) > beta_max)
                    continue;
                e = series_error(&work, mf, &c, mu_o, mu_i);
                if (e < 0.0)
                    continue;
                if (e > 2e-4)
                    print_message("eta %g+%gi alpha %g: mu_o %g mu_i %g: error %.3g of the "
                                  "peak\n",
                                  c.eta_re, c.eta_im, c.alpha, mu_o, mu_i, e);
                assert_true(e <= 2e-4);
                worst = fmax(worst, e);
                worst_case[ei] = fmax(worst_case[ei], e);
                ++tested;
            }
            ll_microfacet_destroy(mf);
        }
    print_message("GGX series vs integration: %zu pairs, worst error %.2e of the peak "
                  "(eta 1.5 %.2e, 1/1.5 %.2e, gold %.2e)\n",
                  tested, worst, worst_case[0], worst_case[1], worst_case[2]);
    assert_true(tested > 400);
    series_work_free(&work);
}

/* --------------------------------------------------- the white furnace */

/* The single-scattering albedo of a white (F = 1) GGX mirror lit from
 * direction mu, integrated over the half vectors m independently of the
 * series: with tan^2 theta_m = alpha^2 xi / (1 - xi), D cos theta_m
 * d omega_m = d xi d phi_m / 2 pi, and f cos theta_o d omega_o = D G
 * (wi . m) / cos theta_i d omega_m. Midpoint rule. */
static double furnace_reference(double mu, double alpha)
{
    const size_t n_xi = 4000, n_phi = 720;
    double wi[3], sum = 0.0;
    size_t a, b;
    wi[0] = -sqrt(1.0 - mu * mu);
    wi[1] = 0.0;
    wi[2] = mu;
    for (a = 0; a < n_xi; ++a) {
        double xi = ((double)a + 0.5) / (double)n_xi;
        double t = alpha * sqrt(xi / (1.0 - xi)), ct = 1.0 / sqrt(1.0 + t * t), st = t * ct;
        for (b = 0; b < n_phi; ++b) {
            double phi = 2.0 * LL_PI * ((double)b + 0.5) / (double)n_phi, m[3], wo[3], c;
            int k;
            m[0] = st * cos(phi);
            m[1] = st * sin(phi);
            m[2] = ct;
            c = dot3(wi, m);
            if (c <= 0.0)
                continue;
            for (k = 0; k < 3; ++k)
                wo[k] = 2.0 * c * m[k] - wi[k];
            if (wo[2] <= 0.0)
                continue;
            sum += ggx_g1(wi, m, alpha) * ggx_g1(wo, m, alpha) * c / (mu * ct);
        }
    }
    return sum / (double)(n_xi * n_phi);
}

static void white_furnace_matches_integration_over_half_vectors(void **state)
{
    static const double alphas[] = { 0.1, 0.3, 0.6, 1.0 };
    static const double mus[] = { 0.95, 0.7, 0.4, 0.2 };
    const size_t n_mu = 512, max_len = 4;
    double *x = malloc(n_mu * sizeof *x), *w = malloc(n_mu * sizeof *w), worst = 0.0;
    double *scratch = malloc(ll_microfacet_scratch_size(max_len) * sizeof *scratch);
    double out[4];
    size_t a, i, k;
    (void)state;
    assert_non_null(x);
    assert_non_null(w);
    assert_non_null(scratch);
    assert_int_equal(ll_quad_gauss_legendre(n_mu, x, w, NULL), LL_OK);
    for (a = 0; a < sizeof alphas / sizeof alphas[0]; ++a) {
        ll_microfacet_model *mf;
        /* A conductor (reflection only); ref0 is its F = 1 reflection. */
        assert_int_equal(ll_microfacet_create_distribution(GOLD_RE, GOLD_IM, alphas[a],
                                                           LL_DISTRIBUTION_GGX, 20000, max_len,
                                                           &mf),
                         LL_OK);
        for (i = 0; i < sizeof mus / sizeof mus[0]; ++i) {
            double albedo = 0.0, expected = furnace_reference(mus[i], alphas[a]);
            for (k = 0; k < n_mu; ++k) {
                double mu_o = 0.5 * (x[k] + 1.0), ref0, mu[2];
                size_t len;
                mu[0] = mu_o;
                mu[1] = -mus[i];
                assert_int_equal(ll_microfacet_prepare(mf, mu, 2), LL_OK);
                assert_int_equal(ll_microfacet_series(mf, mu_o, -mus[i], max_len, out, &len,
                                                      &ref0, scratch),
                                 LL_OK);
                albedo += 0.5 * w[k] * 2.0 * LL_PI * mu_o * ref0;
            }
            print_message("alpha %.1f mu %.2f: white albedo %.6f, over half vectors %.6f\n",
                          alphas[a], mus[i], albedo, expected);
            worst = fmax(worst, fabs(albedo - expected));
            assert_float_equal(albedo, expected, 1e-3);
        }
        ll_microfacet_destroy(mf);
    }
    print_message("white furnace: within %.2e of the integration over half vectors\n", worst);
    free(x);
    free(w);
    free(scratch);
}

/* ------------------------------------------------------------ layers */

static ll_layer *ggx_layer(size_t n, size_t m, double eta_re, double eta_im, double alpha,
                           int compensate, size_t n_orders_internal)
{
    ll_layer *l = ll_test_layer(n, m);
    assert_int_equal(ll_test_set_microfacet_dist(l, eta_re, eta_im, alpha,
                                                          LL_DISTRIBUTION_GGX, compensate,
                                                          n_orders_internal, NULL),
                     LL_OK);
    return l;
}

static ll_layer *ggx_interface(size_t n, size_t m, double eta_re, double eta_im, double alpha)
{
    return ggx_layer(n, m, eta_re, eta_im, alpha, 1, 0);
}

/* Reflection is symmetric and transmission obeys the eta^2 relation
 * (check_reciprocity, microfacet_check.h). */
static void interface_is_reciprocal(void **state)
{
    static const double idx[2][2] = { { 1.5, 0.0 }, { GOLD_RE, GOLD_IM } };
    (void)state;
    check_reciprocity(ggx_interface, idx, "GGX ");
}

/* A non-absorbing GGX dielectric: with the compensation, R + T = 1 for
 * every incident node (both sides), plus the node's jump error (the
 * compensation makes up the loss of the albedo whose transmission jump is
 * integrated exactly, words/microfacet.h); without it, shadowing loses energy,
 * more the rougher the surface (and more than Beckmann at the same alpha:
 * GGX's tails hold more steep facets). Order 0 holds all of the energy, so
 * the layers keep one order, resolved internally with the Beckmann fit's
 * orders. */
static void dielectric_conserves_energy(void **state)
{
    static const double alphas[] = { 0.05, 0.1, 0.3, 0.5, 0.8 };
    double loss[5], loss_beckmann[5], worst = 0.0, *jump;
    size_t a;
    (void)state;
    for (a = 0; a < 5; ++a) {
        size_t n, m;
        ll_layer *on, *off, *beckmann;
        assert_int_equal(ll_fit_microfacet(alphas[a], 1.5, 0.0, &n, &m), LL_OK);
        on = ggx_layer(n, 1, 1.5, 0.0, alphas[a], 1, m);
        off = ggx_layer(n, 1, 1.5, 0.0, alphas[a], 0, m);
        beckmann = ll_test_layer(n, 1);
        assert_int_equal(ll_test_set_microfacet(beckmann, 1.5, 0.0, alphas[a], 0, m, NULL), LL_OK);
        jump = malloc(n * sizeof *jump);
        assert_non_null(jump);
        jump_errors(on, 1.5, alphas[a], LL_MICROFACET_GGX, jump);
        assert_conserves_energy(on, jump, &worst);
        free(jump);
        loss[a] = energy_lost(off);
        loss_beckmann[a] = energy_lost(beckmann);
        ll_layer_destroy(on);
        ll_layer_destroy(off);
        ll_layer_destroy(beckmann);
    }
    print_message("GGX R + T = 1 + jump error within %.2e; lost without compensation (GGX / Beckmann):", worst);
    for (a = 0; a < 5; ++a)
        print_message(" %.4f/%.4f", loss[a], loss_beckmann[a]);
    print_message("\n");
    for (a = 1; a < 5; ++a)
        assert_true(loss[a] > loss[a - 1]);
    for (a = 0; a < 5; ++a)
        assert_true(loss[a] > loss_beckmann[a]);
}

/* A rough GGX conductor's compensation restores what a white mirror of the
 * same roughness loses to shadowing: the compensated albedo of a conductor
 * whose index reflects almost everything stays within 1% of its Fresnel
 * average's reach, and rises over the uncompensated one. At alpha = 0.02
 * it reflects what a mirror does (mu >= 0.2). */
static void conductor_compensation_and_smooth_limit(void **state)
{
    size_t n, m, i;
    double worst = 0.0, gain = 0.0;
    ll_layer *smooth, *on, *off;
    double *x;
    (void)state;
    assert_int_equal(ll_fit_microfacet(0.02, GOLD_RE, GOLD_IM, &n, &m), LL_OK);
    x = malloc(n * sizeof *x);
    assert_non_null(x);
    smooth = ggx_layer(n, 1, GOLD_RE, GOLD_IM, 0.02, 1, m);
    assert_int_equal(ll_layer_get_nodes(smooth, x, NULL), LL_OK);
    for (i = n / 2; i < n; ++i) {
        double R, T, F = fresnel_conductor(x[i], GOLD_RE, GOLD_IM);
        if (x[i] < 0.2)
            continue;
        assert_int_equal(ll_layer_albedo(smooth, x[i], &R, &T), LL_OK);
        assert_float_equal(T, 0.0, 0.0);
        worst = fmax(worst, fabs(R - F) / F);
        assert_float_equal(R, F, 0.01 * F);
    }
    ll_layer_destroy(smooth);
    free(x);
    assert_int_equal(ll_fit_microfacet(0.5, GOLD_RE, GOLD_IM, &n, &m), LL_OK);
    x = malloc(n * sizeof *x);
    assert_non_null(x);
    on = ggx_layer(n, 1, GOLD_RE, GOLD_IM, 0.5, 1, m);
    off = ggx_layer(n, 1, GOLD_RE, GOLD_IM, 0.5, 0, m);
    assert_int_equal(ll_layer_get_nodes(on, x, NULL), LL_OK);
    for (i = n / 2; i < n; ++i) {
        double r_on, r_off;
        assert_int_equal(ll_layer_albedo(on, x[i], &r_on, NULL), LL_OK);
        assert_int_equal(ll_layer_albedo(off, x[i], &r_off, NULL), LL_OK);
        assert_true(r_on >= r_off);
        assert_true(r_on <= 1.0);
        gain = fmax(gain, r_on - r_off);
    }
    print_message("GGX gold: alpha 0.02 within %.2e of Fresnel (mu >= 0.2); alpha 0.5 "
                  "compensation adds up to %.4f\n",
                  worst, gain);
    assert_true(gain > 0.01);
    ll_layer_destroy(on);
    ll_layer_destroy(off);
    free(x);
}

static void beckmann_is_unchanged_and_unknown_distribution_rejected(void **state)
{
    size_t n = 40, m = 20;
    ll_layer *one = ll_test_layer(n, m), *two = ll_test_layer(n, m);
    (void)state;
    assert_int_equal(ll_test_set_microfacet(one, 1.5, 0.0, 0.3, 1, 0, NULL), LL_OK);
    assert_int_equal(ll_test_set_microfacet_dist(two, 1.5, 0.0, 0.3,
                                                          LL_DISTRIBUTION_BECKMANN, 1, 0, NULL),
                     LL_OK);
    assert_same_matrices(one, two, n, m);
    assert_int_equal(ll_test_set_microfacet_dist(two, 1.5, 0.0, 0.3, 2, 1, 0, NULL),
                     LL_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(ll_last_error_message(), "distribution"));
    ll_layer_destroy(one);
    ll_layer_destroy(two);
}

static void shadowing_is_exact_smith(void **state)
{
    (void)state;
    /* G1 = 2 / (1 + sqrt(1 + alpha^2 tan^2)): 1 at normal incidence, and
     * alpha tan = sqrt(3) gives 2 / 3. */
    assert_float_equal(ll_ggx_smith_g1(0.0, 0.3), 1.0, 0.0);
    assert_float_equal(ll_ggx_smith_g1(sqrt(3.0) / 0.5, 0.5), 2.0 / 3.0, 1e-15);
    /* The peak's mean: (1 + beta) / (1 + 2 beta)^1.5 (beta = 4: 5 / 27). */
    assert_float_equal(ll_ggx_peak_mean(4.0), 5.0 / 27.0, 1e-15);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(shadowing_is_exact_smith),
        cmocka_unit_test(series_matches_direct_integration),
        cmocka_unit_test(white_furnace_matches_integration_over_half_vectors),
        cmocka_unit_test(interface_is_reciprocal),
        cmocka_unit_test(dielectric_conserves_energy),
        cmocka_unit_test(conductor_compensation_and_smooth_limit),
        cmocka_unit_test(beckmann_is_unchanged_and_unknown_distribution_rejected),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
