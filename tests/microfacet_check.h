/*
 * What tests/test_microfacet.c (Beckmann) and tests/test_microfacet_ggx.c
 * share: the geometry of Walter et al. 2007's closed-form BSDF, written out
 * in vectors independently of microfacet_series.c's reduction to
 * t = wi . wo (each test supplies its own D, G1 and Fresnel term); the
 * check of one pair's Fourier series against direct integration of that
 * closed form; the reciprocity of an interface layer's matrices; and the
 * comparison of two layers order by order. One copy, so that the two
 * distributions are held to the same measure.
 *
 * Header-only (static inline), like test_util.h. Failures are cmocka
 * assertions. Include after <cmocka.h>.
 */
#ifndef LL_TEST_MICROFACET_CHECK_H
#define LL_TEST_MICROFACET_CHECK_H

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include <layerlab.h>
#include "series_check.h"
#include "words/microfacet.h"

/* A small deterministic generator (64-bit LCG, top 53 bits). */
static inline double uniform(uint64_t *state)
{
    *state = *state * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*state >> 11) * (1.0 / 9007199254740992.0);
}

static inline double dot3(const double *a, const double *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* ----------------------------------------------- the closed-form BSDF
 * In the frame of words/microfacet.h: wi points back to the light, wo is
 * the outgoing direction, -mu_i mu_o > 0 is reflection, light with
 * -mu_i > 0 comes from the side of relative index eta. */

typedef struct mf_geometry {
    double wi[3], wo[3], h[3]; /* h: the half vector, on the side of +z */
    double eta;                /* the relative index the light meets */
    double wih, woh;           /* wi . h, wo . h */
    int reflect;
} mf_geometry;

/* The directions and the half vector of the pair at azimuth phi; 0 where
 * the BSDF is 0 whatever the distribution (a conductor's transmission). */
static inline int mf_geometry_set(mf_geometry *g, double mu_o, double mu_i, double eta_re,
                                  double eta_im, double phi)
{
    double si = sqrt(1.0 - mu_i * mu_i), so = sqrt(1.0 - mu_o * mu_o), len, sign;
    int conductor = eta_im != 0.0, k;
    g->reflect = -mu_i * mu_o > 0.0;
    if (conductor && !g->reflect)
        return 0;
    g->wi[0] = -si, g->wi[1] = 0.0, g->wi[2] = -mu_i;
    g->wo[0] = so * cos(phi), g->wo[1] = so * sin(phi), g->wo[2] = mu_o;
    g->eta = (-mu_i > 0.0 || conductor) ? eta_re : 1.0 / eta_re;
    for (k = 0; k < 3; ++k)
        g->h[k] = g->wi[k] + (g->reflect ? 1.0 : g->eta) * g->wo[k];
    len = sqrt(dot3(g->h, g->h));
    sign = g->h[2] > 0.0 ? 1.0 : -1.0;
    for (k = 0; k < 3; ++k)
        g->h[k] *= sign / len;
    g->wih = dot3(g->wi, g->h);
    g->woh = dot3(g->wo, g->h);
    return 1;
}

/* Walter et al. 2007, eq. 20 (reflection) and 21 (transmission), from the
 * Fresnel reflectance f, the distribution d and the shadowing g at h. */
static inline double mf_walter(const mf_geometry *q, double mu_o, double mu_i, double f, double d,
                               double g)
{
    double eta = q->eta, wih = q->wih, woh = q->woh;
    if (q->reflect)
        return f * d * g / (4.0 * fabs(mu_i * mu_o));
    return fabs((1.0 - f) * d * g * eta * eta * wih * woh /
                (mu_i * mu_o * (wih + eta * woh) * (wih + eta * woh)));
}

/* ------------------------------- the series against direct integration */

typedef struct series_case {
    double eta_re, eta_im, alpha;
} series_case;

/* The test's closed form of the case at (mu_o, mu_i, phi). */
typedef double (*mf_closed_form_fn)(const series_case *c, double mu_o, double mu_i, double phi);

/* The reference's resolution and the buffers of series_error. */
struct series_work;
/* A reference of the pair's coefficients other than composite Simpson over
 * the uniform samples: fills w->ref[l], l < len (w->f holds the samples). */
typedef void (*mf_reference_fn)(struct series_work *w, const series_case *c, double mu_o,
                                double mu_i, size_t len);

typedef struct series_work {
    size_t ref_points; /* odd: composite Simpson on [0, pi] */
    size_t max_orders;
    mf_closed_form_fn closed_form;
    mf_reference_fn reference; /* NULL: composite Simpson */
    double *f, *ref, *ours, *scratch;
} series_work;

static inline void series_work_init(series_work *w, size_t ref_points, size_t max_orders,
                                    mf_closed_form_fn closed_form)
{
    w->ref_points = ref_points;
    w->max_orders = max_orders;
    w->closed_form = closed_form;
    w->reference = NULL;
    w->f = malloc(ref_points * sizeof *w->f);
    w->ref = malloc(max_orders * sizeof *w->ref);
    w->ours = malloc(max_orders * sizeof *w->ours);
    w->scratch = malloc(ll_microfacet_scratch_size(max_orders) * sizeof *w->scratch);
    assert_non_null(w->f);
    assert_non_null(w->ref);
    assert_non_null(w->ours);
    assert_non_null(w->scratch);
}

static inline void series_work_free(series_work *w)
{
    free(w->f);
    free(w->ref);
    free(w->ours);
    free(w->scratch);
}

/* The worst error of the pair's series (relative to the BSDF's peak over
 * phi), comparing with coefficients computed by composite Simpson from the
 * closed form (or by w->reference); returns -1 for pairs that scatter
 * negligibly. */
static inline double series_error(series_work *w, ll_microfacet_model *mf, const series_case *c,
                                  double mu_o, double mu_i)
{
    double mu[2], peak = 0.0, h = LL_PI / (double)(w->ref_points - 1);
    size_t len, k;
    mu[0] = mu_o;
    mu[1] = mu_i;
    assert_int_equal(ll_microfacet_prepare(mf, mu, 2), LL_OK);
    assert_int_equal(
        ll_microfacet_series(mf, mu_o, mu_i, w->max_orders, w->ours, &len, NULL, w->scratch),
        LL_OK);
    for (k = 0; k < w->ref_points; ++k) {
        w->f[k] = w->closed_form(c, mu_o, mu_i, (double)k * h);
        peak = fmax(peak, w->f[k]);
    }
    if (len == 0) {
        /* Skipped as negligible: it must be (the peaks that matter here are
         * 0.01 to 1e3). */
        if (peak >= 1e-6)
            print_message("eta %g+%gi alpha %g: mu_o %g mu_i %g: skipped, peak %g\n", c->eta_re,
                          c->eta_im, c->alpha, mu_o, mu_i, peak);
        assert_true(peak < 1e-6);
        return -1.0;
    }
    if (w->reference)
        w->reference(w, c, mu_o, mu_i, len);
    else
        ll_test_cosine_series(w->f, w->ref_points, h, len, w->ref);
    return ll_test_series_error(w->ours, w->ref, len, w->ref_points, h, peak);
}

/* ------------------------------------------------------- reciprocity */

/* With ascending nodes x (x[n-1-j] = -x[j]), f(mu_o, mu_i) of order k is
 * M[row(mu_o) * n + col(mu_i)]. Reflection is symmetric, f(-a, +b) =
 * f(-b, +a); transmission obeys f_bt(-a, -b) = f_tb(+b, +a) / eta^2.
 * Raises *worst_r and *worst_t to the layer's largest departures from
 * these, relative to the largest reflection and transmission entry of the
 * order; M holds n * n. */
static inline void reciprocity_error(const ll_layer *l, size_t n, size_t m, double eta2, double *M,
                                     double *worst_r, double *worst_t)
{
    size_t h = n / 2, k, j, q;
    for (k = 0; k < m; ++k) {
        double scale_r = 0.0, scale_t = 0.0;
        assert_int_equal(ll_layer_matrix(l, k, M), LL_OK);
        for (j = 0; j < n * n; ++j) {
            size_t r = j / n, c = j % n;
            if ((r < h) != (c < h))
                scale_r = fmax(scale_r, fabs(M[j]));
            else
                scale_t = fmax(scale_t, fabs(M[j]));
        }
        for (j = h; j < n; ++j)
            for (q = h; q < n; ++q) {
                size_t a = n - 1 - j, b = n - 1 - q; /* the mirror nodes -x */
                *worst_r = fmax(*worst_r, fabs(M[a * n + q] - M[b * n + j]) / scale_r);
                *worst_r = fmax(*worst_r, fabs(M[j * n + b] - M[q * n + a]) / scale_r);
                if (scale_t > 0.0)
                    *worst_t = fmax(*worst_t, fabs(M[a * n + b] - M[q * n + j] / eta2) / scale_t);
            }
    }
}

/* An interface layer of n nodes and m orders, compensated, resolved
 * internally as the library chooses, of the test's distribution. */
typedef ll_layer *(*mf_interface_fn)(size_t n, size_t m, double eta_re, double eta_im,
                                     double alpha);

/* A dielectric and a conductor (idx: eta_re, eta_im of each) at alpha 0.3
 * made by `make` are reciprocal: to 1e-12 of the largest entry in
 * reflection, 1e-9 in transmission. `name` prefixes the message. */
static inline void check_reciprocity(mf_interface_fn make, const double idx[2][2],
                                     const char *name)
{
    size_t n = 92, m = 61, e;
    double *M = malloc(n * n * sizeof *M), worst_r = 0.0, worst_t = 0.0;
    assert_non_null(M);
    for (e = 0; e < 2; ++e) {
        ll_layer *l = make(n, m, idx[e][0], idx[e][1], 0.3);
        reciprocity_error(l, n, m, idx[e][0] * idx[e][0], M, &worst_r, &worst_t);
        ll_layer_destroy(l);
    }
    print_message("%sreciprocity: reflection %.2e, transmission %.2e of the largest entry\n",
                  name, worst_r, worst_t);
    assert_true(worst_r < 1e-12);
    assert_true(worst_t < 1e-9);
    free(M);
}

/* ------------------------------------------------------------ layers */

/* R + T for light along mu (either side), from the order-0 column. */
static inline double albedo_sum(const ll_layer *l, double mu)
{
    double R, T;
    assert_int_equal(ll_layer_albedo(l, mu, &R, &T), LL_OK);
    return R + T;
}

/* The jump error (ll_microfacet_jump_error) of the transmission albedo of
 * a dielectric interface layer l (index eta, roughness alpha, distribution
 * dist) from each of its nodes, in ascending order: what a compensated
 * GGX layer's R + T differs from 1 by there (0 for Beckmann). */
static inline void jump_errors(const ll_layer *l, double eta, double alpha, int dist,
                               double *out)
{
    size_t n = ll_layer_node_count(l), h = n / 2, j;
    double *x = malloc(n * sizeof *x), *w = malloc(n * sizeof *w);
    double *mu = malloc(h * sizeof *mu), *wt = malloc(h * sizeof *wt);
    double *scratch = malloc(ll_microfacet_scratch_size(1) * sizeof *scratch);
    ll_microfacet_model *mf = NULL;
    assert_true(x && w && mu && wt && scratch);
    assert_int_equal(ll_layer_get_nodes(l, x, w), LL_OK);
    assert_int_equal(ll_microfacet_create_distribution(eta, 0.0, alpha, dist, 200, 1, &mf),
                     LL_OK);
    for (j = 0; j < h; ++j) {
        mu[j] = x[h + j];
        wt[j] = 2.0 * 3.14159265358979323846 * w[h + j] * mu[j];
    }
    for (j = 0; j < h; ++j) {
        out[h + j] = ll_microfacet_jump_error(mf, h, mu, wt, eta, j, 0, scratch);
        out[h - 1 - j] = ll_microfacet_jump_error(mf, h, mu, wt, eta, j, 1, scratch);
    }
    ll_microfacet_destroy(mf);
    free(x);
    free(w);
    free(mu);
    free(wt);
    free(scratch);
}

/* R + T = 1 within 1e-3 for light from every node of l (either side),
 * plus jump[i] from node i (jump_errors(); NULL: none); raises *worst to
 * the largest |R + T - 1 - jump[i]|. */
static inline void assert_conserves_energy(const ll_layer *l, const double *jump, double *worst)
{
    size_t n = ll_layer_node_count(l), i;
    double *x = malloc(n * sizeof *x);
    assert_non_null(x);
    assert_int_equal(ll_layer_get_nodes(l, x, NULL), LL_OK);
    for (i = 0; i < n; ++i) {
        double sum = albedo_sum(l, x[i]) - (jump ? jump[i] : 0.0);
        *worst = fmax(*worst, fabs(sum - 1.0));
        assert_float_equal(sum, 1.0, 1e-3);
    }
    free(x);
}

/* The share of the energy l loses, 1 - (R + T), over light from above,
 * each node weighted by its quadrature weight and mu. */
static inline double energy_lost(const ll_layer *l)
{
    size_t n = ll_layer_node_count(l), i;
    double *x = malloc(n * sizeof *x), *w = malloc(n * sizeof *w), lost = 0.0, total = 0.0;
    assert_non_null(x);
    assert_non_null(w);
    assert_int_equal(ll_layer_get_nodes(l, x, w), LL_OK);
    for (i = 0; i < n; ++i)
        if (x[i] > 0.0) {
            lost += w[i] * x[i] * (1.0 - albedo_sum(l, x[i]));
            total += w[i] * x[i];
        }
    free(x);
    free(w);
    return lost / total;
}

/* The first m orders of two n-node layers are equal to the bit. */
static inline void assert_same_matrices(const ll_layer *one, const ll_layer *two, size_t n,
                                        size_t m)
{
    double *a = malloc(n * n * sizeof *a), *b = malloc(n * n * sizeof *b);
    size_t k;
    assert_non_null(a);
    assert_non_null(b);
    for (k = 0; k < m; ++k) {
        assert_int_equal(ll_layer_matrix(one, k, a), LL_OK);
        assert_int_equal(ll_layer_matrix(two, k, b), LL_OK);
        assert_memory_equal(a, b, n * n * sizeof *a);
    }
    free(a);
    free(b);
}

#endif /* LL_TEST_MICROFACET_CHECK_H */
