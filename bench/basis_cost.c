/*
 * What a textured file costs per call: ns per ll_bsdf_eval_dir (and
 * ll_bsdf_sample_dir) on a file of
 * 64 bases (two parameters sampled 8 x 8, weights from
 * ll_bsdf_basis_coefficients at an interior point: 4 non-zero) against the
 * untextured file of one of its layers, same directions. A benchmark driver
 * (never part of `make test`; the numbers are for the report):
 *   cc -std=c99 -O2 -D_DEFAULT_SOURCE -Iinclude bench/basis_cost.c bench/bench_util.c -Lbuild/lib \
 *      -Wl,-rpath,$PWD/build/lib -llayerlab -lm -o build/basis_cost && build/basis_cost /tmp
 */
#define _POSIX_C_SOURCE 200809L
#include "bench_util.h"
#include "layerlab/ll_bsdf.h"
#include "layerlab/ll_bsdf_write.h"
#include "layerlab/ll_layer.h"
#include "layerlab/ll_quad.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#define SIDE 8
#define CALLS 200000

/* The next four numbers of the generator, uniform in [0, 1). */
static void draw4(unsigned long long *rng, double u[4])
{
    int j;
    for (j = 0; j < 4; ++j) {
        *rng = *rng * 6364136223846793005ULL + 1442695040888963407ULL;
        u[j] = (double)(*rng >> 11) / 9007199254740992.0;
    }
}

/* The direction of cos theta 0.05 + 0.95 u_z and azimuth 2 pi u_phi. */
static void direction(double u_z, double u_phi, double w[3])
{
    w[2] = 0.05 + 0.95 * u_z;
    w[0] = sqrt(1 - w[2] * w[2]) * cos(6.283185307 * u_phi);
    w[1] = sqrt(1 - w[2] * w[2]) * sin(6.283185307 * u_phi);
}

/* ns per sample_dir over CALLS pseudo-random (wo, u), best of 3 runs. */
static double time_sample(const ll_bsdf *b, const float *coeffs, double *checksum)
{
    double best = 1e30;
    int run;
    for (run = 0; run < 3; ++run) {
        unsigned long long rng = 777;
        double t0 = bench_wall_seconds(), sum = 0.0, t;
        int k;
        for (k = 0; k < CALLS / 4; ++k) {
            double u[4], wo[3], wi[3], rgb[3], pdf;
            draw4(&rng, u);
            direction(u[0], u[1], wo);
            bench_check(ll_bsdf_sample_dir(b, wo, u + 2, LL_TRANSPORT_RADIANCE, coeffs, wi, &pdf, rgb),
                  "sample");
            sum += pdf;
        }
        t = (bench_wall_seconds() - t0) / (CALLS / 4) * 1e9;
        if (t < best)
            best = t;
        *checksum = sum;
    }
    return best;
}

/* ns per eval_dir over CALLS pseudo-random direction pairs (same seed for
 * every file), best of 3 runs. */
static double time_eval(const ll_bsdf *b, const float *coeffs, double *checksum)
{
    double best = 1e30;
    int run;
    for (run = 0; run < 3; ++run) {
        unsigned long long rng = 12345;
        double t0 = bench_wall_seconds(), sum = 0.0, t;
        int k;
        for (k = 0; k < CALLS; ++k) {
            double u[4], wo[3], wi[3], rgb[3];
            draw4(&rng, u);
            direction(u[0], u[1], wo);
            direction(u[2], u[3], wi);
            bench_check(ll_bsdf_eval_dir(b, wo, wi, LL_TRANSPORT_RADIANCE, coeffs, rgb), "eval");
            sum += rgb[0];
        }
        t = (bench_wall_seconds() - t0) / CALLS * 1e9;
        if (t < best)
            best = t;
        *checksum = sum;
    }
    return best;
}

int main(int argc, char **argv)
{
    const char *dir = argc > 1 ? argv[1] : "/tmp";
    ll_layer *l[SIDE];
    const ll_layer *layers[SIDE * SIDE];
    size_t counts[2] = { SIDE, SIDE }, n = 0, orders = 0, k;
    double positions[2 * SIDE], x[64], w[64], params[2] = { 0.33, 0.5 }, sum1, sum64;
    float coeffs[SIDE * SIDE], *nonzero = coeffs;
    char path[512];
    ll_bsdf *b64 = NULL, *b1 = NULL;
    size_t active = 0;
    bench_check(bench_search_microfacet(0.2, 0.2, 3.0, &n, &orders), "heuristic");
    if (n > 64)
        n = 64;
    bench_check(ll_quad_gauss_lobatto(n, x, w, NULL), "nodes");
    for (k = 0; k < SIDE; ++k) {
        bench_check(ll_layer_create(x, w, n, orders, &l[k]), "layer");
        bench_check(bench_set_microfacet(l[k], 0.2, 3.0, 0.2 + 0.05 * (double)k, 1, 0, NULL), "fill");
        positions[k] = 0.2 + 0.05 * (double)k;
        positions[SIDE + k] = (double)k / (SIDE - 1);
    }
    /* Parameter 1 repeats the row of parameter 0 (the cost does not depend
     * on what the bases hold). */
    for (k = 0; k < SIDE * SIDE; ++k)
        layers[k] = l[k % SIDE];
    snprintf(path, sizeof path, "%s/basis64.bsdf", dir);
    bench_check(ll_bsdf_write_textured(path, layers, 1, 2, counts, positions, NULL, NULL), "write");
    bench_check(ll_bsdf_open(path, NULL, &b64), "open");
    snprintf(path, sizeof path, "%s/basis1.bsdf", dir);
    bench_check(ll_bsdf_write(path, layers, 1, NULL, NULL), "write");
    bench_check(ll_bsdf_open(path, NULL, &b1), "open");
    bench_check(ll_bsdf_basis_coefficients(b64, params, coeffs), "coefficients");
    for (k = 0; k < SIDE * SIDE; ++k)
        active += coeffs[k] != 0.0f;
    (void)nonzero;
    printf("%zu nodes, %zu orders; 64-basis file: %zu non-zero weights\n", n, orders, active);
    printf("1 basis:   %.0f ns per eval_dir\n", time_eval(b1, NULL, &sum1));
    printf("64 bases:  %.0f ns per eval_dir\n", time_eval(b64, coeffs, &sum64));
    printf("checksums %.6g %.6g\n", sum1, sum64);
    printf("1 basis:   %.0f ns per sample_dir\n", time_sample(b1, NULL, &sum1));
    printf("64 bases:  %.0f ns per sample_dir\n", time_sample(b64, coeffs, &sum64));
    printf("checksums %.9g %.9g\n", sum1, sum64);
    ll_bsdf_release(b1);
    ll_bsdf_release(b64);
    for (k = 0; k < SIDE; ++k)
        ll_layer_destroy(l[k]);
    return 0;
}
