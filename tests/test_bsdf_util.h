/*
 * Helpers shared by the .bsdf tests (test_bsdf_*.c): synthetic layers built
 * through the internal column builder (so the tests need no interface or
 * medium code); the general helpers are in test_util.h.
 */
#ifndef LL_TEST_BSDF_UTIL_H
#define LL_TEST_BSDF_UTIL_H

#include "test_util.h"
#include "layer/layer.h"

#define LL_TEST_GOLDEN LL_SOURCE_DIR "/tests/data/roughgold_alpha_0.2.bsdf"
#define LL_TEST_PI 3.14159265358979323846

/* ll_bsdf_pdf and ll_bsdf_pdf_dir as values, for arguments that must be
 * valid (the call must return LL_OK). */
static inline double ll_test_pdf(const ll_bsdf *b, double mu_i, double mu_o, double phi_d,
                                 const float *basis_coeffs)
{
    double pdf = -1.0;
    assert_int_equal(ll_bsdf_pdf(b, mu_i, mu_o, phi_d, basis_coeffs, &pdf), LL_OK);
    return pdf;
}

static inline double ll_test_pdf_dir(const ll_bsdf *b, const double wo[3], const double wi[3],
                                     const float *basis_coeffs)
{
    double pdf = -1.0;
    assert_int_equal(ll_bsdf_pdf_dir(b, wo, wi, basis_coeffs, &pdf), LL_OK);
    return pdf;
}

/* f_k(mu_o, mu_i): the BSDF's order-k coefficient (without weights) for
 * outgoing mu_o and incident mu_i, in the layer convention. */
typedef double (*ll_test_bsdf_fn)(size_t k, double mu_o, double mu_i, const void *ctx);

/* Set every order of l to fn, folding the surface weights into the columns
 * as the words do (method.md, "Discretisation"). */
static inline void ll_test_fill(ll_layer *l, ll_test_bsdf_fn fn, const void *ctx)
{
    size_t n = l->n, m = l->m, k, row, col;
    ll_order_builder **builders = calloc(m, sizeof *builders);
    double *column = malloc(n * sizeof *column);
    assert_non_null(builders);
    assert_non_null(column);
    for (k = 0; k < m; ++k) {
        assert_int_equal(ll_order_builder_create(n, &builders[k]), LL_OK);
        for (col = 0; col < n; ++col) {
            for (row = 0; row < n; ++row)
                column[row] = fn(k, l->nodes[row], l->nodes[col], ctx) *
                              ll_layer_surface_factor(l, col, k);
            assert_int_equal(ll_order_builder_set_column(builders[k], col, column, 0.0), LL_OK);
        }
    }
    assert_int_equal(ll_layer_set_from_builders(l, builders), LL_OK);
    free(builders);
    free(column);
}

/* A BSDF whose file representation is exact between nodes too: f_k is
 * constant in mu_o and proportional to |mu_i|, so the stored f |mu_o| is
 * bilinear in |mu_o|, |mu_i| and vanishes at the mu = 0 nodes, which both
 * Catmull-Rom interpolants reproduce exactly. scale[0] scales reflection
 * from above, scale[1] transmission downward, scale[2] reflection from
 * below, scale[3] transmission upward. */
typedef struct ll_test_smooth {
    double scale[4];
    double decay;      /* coefficient k is decay^k (k >= 1)  */
} ll_test_smooth;

static inline double ll_test_smooth_fn(size_t k, double mu_o, double mu_i, const void *ctx)
{
    const ll_test_smooth *p = ctx;
    int block = mu_i > 0.0 ? (mu_o < 0.0 ? 0 : 1) : (mu_o > 0.0 ? 2 : 3);
    /* f = sum_k c_k cos(k phi) with c_0 = 1: non-negative for decay <= 1/2. */
    double c = k == 0 ? 1.0 : pow(p->decay, (double)k);
    return p->scale[block] * c * fabs(mu_i) / LL_TEST_PI;
}

/* A rough, lobe-shaped BSDF (not reproduced exactly between nodes): used
 * at the nodes themselves, where the file must match the layer exactly. */
static inline double ll_test_lobe_fn(size_t k, double mu_o, double mu_i, const void *ctx)
{
    double sharp = *(const double *)ctx;
    double spec = exp(-sharp * (mu_o + mu_i) * (mu_o + mu_i)); /* near mu_o = -mu_i */
    double phase = 0.3 + 0.2 * sin(7.0 * mu_o + 3.0 * mu_i);
    return (1.0 + spec * 4.0) * phase * exp(-0.15 * (double)k * (1.0 + fabs(mu_o))) / LL_TEST_PI;
}

static inline double ll_test_luminance(const double rgb[3])
{
    return 0.212671 * rgb[0] + 0.715160 * rgb[1] + 0.072169 * rgb[2];
}

#endif /* LL_TEST_BSDF_UTIL_H */
