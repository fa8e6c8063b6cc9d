/*
 * Which interpolation between the sample positions of a textured .bsdf
 * file's parameter (ll_bsdf_basis_coefficients, src/reader/bsdf_basis.c):
 * linear or Catmull-Rom (the node spline, numerics/spline.c)? Measured, not
 * assumed: textured files whose bases are layers built directly at the
 * sample values, evaluated at in-between values with each interpolation's
 * weights, against an untextured file built directly at that value. The
 * error is |f_interp - f_direct| / f_direct over directions where f_direct
 * exceeds 1% of its peak (max and mean over the directions). A benchmark
 * driver (never part of `make test`): build with
 *   cc -std=c99 -O2 -D_DEFAULT_SOURCE -Iinclude -Isrc bench/basis_interp.c bench/bench_util.c \
 *      build/lib/liblayerlab.a \
 *      -llapacke -lopenblas -fopenmp -lm -lpthread -o build/basis_interp && build/basis_interp /tmp
 */
#include "bench_util.h"
#include "layerlab/ll_bsdf.h"
#include "layerlab/ll_bsdf_write.h"
#include "layerlab/ll_layer.h"
#include "layerlab/ll_quad.h"
#include "numerics/spline.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#define N_SAMPLES 5
static const double alphas[N_SAMPLES] = { 0.05, 0.1, 0.2, 0.3, 0.4 };
static const double between[4] = { 0.075, 0.15, 0.25, 0.35 };

typedef struct material {
    const char *name;
    double eta_re, eta_im;
} material;

static void check(ll_status s, const char *what)
{
    if (s != LL_OK) {
        fprintf(stderr, "%s: %s\n", what, ll_last_error_message());
        exit(1);
    }
}

static ll_layer *build(const material *m, double alpha, size_t n, size_t orders)
{
    double *x = malloc(n * sizeof *x), *w = malloc(n * sizeof *w);
    ll_layer *l = NULL;
    check(ll_quad_gauss_lobatto(n, x, w, NULL), "nodes");
    check(ll_layer_create(x, w, n, orders, &l), "layer");
    check(bench_set_microfacet(l, m->eta_re, m->eta_im, alpha, 1, 0, NULL), "microfacet");
    free(x);
    free(w);
    return l;
}

static ll_bsdf *write_open(const char *path, const ll_layer *const *layers, size_t n_params,
                           const size_t *counts, const double *positions)
{
    ll_bsdf *b = NULL;
    check(ll_bsdf_write_textured(path, layers, 1, n_params, counts, positions, NULL, NULL), "write");
    check(ll_bsdf_open(path, NULL, &b), "open");
    return b;
}

/* Weights of the textured file at alpha: linear (the library's) or
 * Catmull-Rom over the sample positions. */
static void weights(const ll_bsdf *b, double alpha, int catmull_rom, float coeffs[N_SAMPLES])
{
    size_t k;
    if (!catmull_rom) {
        check(ll_bsdf_basis_coefficients(b, &alpha, coeffs), "coefficients");
        return;
    }
    {
        ptrdiff_t off;
        double w[4];
        for (k = 0; k < N_SAMPLES; ++k)
            coeffs[k] = 0.0f;
        if (!ll_spline_weights(alphas, N_SAMPLES, alpha, &off, w, 0))
            exit(1);
        for (k = 0; k < 4; ++k)
            if (off + (ptrdiff_t)k >= 0 && off + (ptrdiff_t)k < N_SAMPLES)
                coeffs[off + (ptrdiff_t)k] = (float)w[k];
    }
}

#define N_MU 12
#define N_PHI 16

static void measure(const material *m, ll_bsdf *textured, size_t n, size_t orders,
                    const char *dir)
{
    size_t t;
    for (t = 0; t < 4; ++t) {
        char path[512];
        ll_layer *l = build(m, between[t], n, orders);
        const ll_layer *one[1];
        ll_bsdf *direct;
        double peak = 0.0, err_max[2] = { 0, 0 }, err_sum[2] = { 0, 0 }, neg[2] = { 0, 0 };
        size_t counted = 0, pass, i, o, p;
        float c[2][N_SAMPLES];
        one[0] = l;
        snprintf(path, sizeof path, "%s/direct.bsdf", dir);
        direct = write_open(path, one, 0, NULL, NULL);
        weights(textured, between[t], 0, c[0]);
        weights(textured, between[t], 1, c[1]);
        /* Two passes: the peak of f_direct, then the errors where f_direct
         * exceeds 1% of it. Reflection (mu_o < 0) and, for dielectrics,
         * transmission (mu_o > 0), light from above. */
        for (pass = 0; pass < 2; ++pass)
            for (i = 0; i < N_MU; ++i)
                for (o = 0; o < 2 * N_MU; ++o)
                    for (p = 0; p < N_PHI; ++p) {
                        double mu_i = (i + 0.5) / N_MU;
                        double mu_o = o < N_MU ? -(o + 0.5) / N_MU : (o - N_MU + 0.5) / N_MU;
                        double phi = LL_PI * (double)p / (N_PHI - 1), fd[3], fi[3];
                        int k;
                        check(ll_bsdf_eval(direct, mu_i, mu_o, phi, NULL, fd), "eval");
                        if (pass == 0) {
                            if (fd[0] > peak)
                                peak = fd[0];
                            continue;
                        }
                        if (!(fd[0] > 0.01 * peak))
                            continue;
                        counted++;
                        for (k = 0; k < 2; ++k) {
                            double e;
                            /* The raw luminance sum, before the clamp at 0,
                             * to see negative lobes. */
                            check(ll_bsdf_eval(textured, mu_i, mu_o, phi, c[k], fi), "eval");
                            e = fabs(fi[0] - fd[0]) / fd[0];
                            if (e > err_max[k])
                                err_max[k] = e;
                            err_sum[k] += e;
                            if (fi[0] <= 0.0)
                                neg[k]++;
                        }
                    }
        printf("%-10s alpha %.3f  linear max %.4f mean %.4f | catmull-rom max %.4f mean %.4f"
               "  (%zu directions; f = 0 clamped: %g / %g)\n",
               m->name, between[t], err_max[0], err_sum[0] / (double)counted, err_max[1],
               err_sum[1] / (double)counted, counted, neg[0], neg[1]);
        ll_bsdf_release(direct);
        ll_layer_destroy(l);
    }
}

int main(int argc, char **argv)
{
    const material mats[2] = { { "conductor", 0.2, 3.0 }, { "dielectric", 1.5, 0.0 } };
    const char *dir = argc > 1 ? argv[1] : "/tmp";
    size_t mi, k, n, orders;
    for (mi = 0; mi < 2; ++mi) {
        ll_layer *l[N_SAMPLES];
        const ll_layer *layers[N_SAMPLES];
        size_t counts[1] = { N_SAMPLES };
        char path[512];
        ll_bsdf *textured;
        /* One resolution for every build: what the sharpest sample needs. */
        check(bench_search_microfacet(alphas[0], mats[mi].eta_re, mats[mi].eta_im, &n, &orders),
              "heuristic");
        printf("%s: %zu nodes, %zu orders\n", mats[mi].name, n, orders);
        for (k = 0; k < N_SAMPLES; ++k) {
            l[k] = build(&mats[mi], alphas[k], n, orders);
            layers[k] = l[k];
        }
        snprintf(path, sizeof path, "%s/textured.bsdf", dir);
        textured = write_open(path, layers, 1, counts, alphas);
        measure(&mats[mi], textured, n, orders, dir);
        ll_bsdf_release(textured);
        for (k = 0; k < N_SAMPLES; ++k)
            ll_layer_destroy(l[k]);
    }
    return 0;
}
