/*
 * How far a table file (the `measured` format) is from the file it was
 * written from, per channel, in the figures its tolerance is stated in
 * (ll_tables.h, docs/formats.md):
 *  - albedo: the integral of f cos over the reflected hemisphere for a
 *    viewer at elevations 0..85 degrees, each file by its own sampler,
 *    stratified (the weights f cos / pdf are nearly constant for both
 *    representations, so 256^2 strata resolve 1e-4);
 *  - f: relative errors of f where f cos is above 1% of its largest value
 *    over the pairs (per channel), both elevations <= 80 degrees, half of
 *    the pairs near the mirror direction; their median, 95th and 99th
 *    percentiles.
 * Public API only, so that it measures what a renderer reads. The
 * albedo and the f errors are also what test_tables.c holds its table of
 * the golden file to. Header-only (static inline).
 */
#ifndef LL_TEST_TABLES_FIGURES_H
#define LL_TEST_TABLES_FIGURES_H

#include <layerlab.h>

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define TF_PI 3.14159265358979323846
#define TF_ANGLES 10
#define TF_PAIRS 60000

static const double tf_angles_deg[TF_ANGLES] = { 0, 10, 20, 30, 40, 50, 60, 70, 80, 85 };

typedef struct tf_figures {
    double albedo_ratio[TF_ANGLES][3]; /* table / source, per channel   */
    double worst_albedo;               /* max |ratio - 1|               */
    double p50, p95, p99;              /* relative f errors, all channels */
    size_t n_values;
    int failed;                        /* a call did not return LL_OK   */
} tf_figures;

static inline double tf_uniform(uint64_t *s)
{
    *s = *s * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*s >> 11) * (1.0 / 9007199254740992.0);
}

/* A direction at elevation theta, azimuth phi. */
static inline void tf_direction(double theta, double phi, double w[3])
{
    w[0] = sin(theta) * cos(phi);
    w[1] = sin(theta) * sin(phi);
    w[2] = cos(theta);
}

/* Albedo per channel for light seen along wo (cos theta = mu); 0 if a
 * call failed. */
static inline int tf_albedo_weighted(const ll_bsdf *b, double mu, const float *basis,
                                     double out[3])
{
    const int n = 256;
    double wo[3] = { sqrt(1.0 - mu * mu), 0.0, mu };
    int i, j, c;
    out[0] = out[1] = out[2] = 0.0;
    for (i = 0; i < n; ++i)
        for (j = 0; j < n; ++j) {
            double u[2] = { (i + 0.5) / n, (j + 0.5) / n }, wi[3], pdf, f[3];
            if (ll_bsdf_sample_dir(b, wo, u, LL_TRANSPORT_RADIANCE, basis, wi, &pdf, f) != LL_OK)
                return 0;
            if (pdf > 0.0)
                for (c = 0; c < 3; ++c)
                    out[c] += f[c] * fabs(wi[2]) / pdf;
        }
    for (c = 0; c < 3; ++c)
        out[c] /= (double)n * n;
    return 1;
}

static inline int tf_albedo(const ll_bsdf *b, double mu, double out[3])
{
    return tf_albedo_weighted(b, mu, NULL, out);
}

static inline int tf_compare(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* fig's relative f errors (p50, p95, p99, n_values), with the pairs drawn
 * by `uniform` from a fixed seed; 0 if a call failed or no value counted. */
static inline int tf_f_errors_weighted(const ll_bsdf *src, const ll_bsdf *table,
                                       const float *basis, tf_figures *fig,
                                       double (*uniform)(uint64_t *))
{
    const double lim = 80.0 * TF_PI / 180.0;
    double(*wo)[3] = malloc(TF_PAIRS * sizeof *wo), (*wi)[3] = malloc(TF_PAIRS * sizeof *wi);
    double(*ref)[3] = malloc(TF_PAIRS * sizeof *ref), (*got)[3] = malloc(TF_PAIRS * sizeof *got);
    double *err = malloc(3 * TF_PAIRS * sizeof *err), top[3] = { 0.0, 0.0, 0.0 };
    uint64_t rng = 2024;
    size_t k, n = 0;
    int c, ok = wo && wi && ref && got && err;
    for (k = 0; ok && k < TF_PAIRS; ++k) {
        double tv = acos(1.0 - uniform(&rng) * (1.0 - cos(lim)));
        tf_direction(tv, 0.0, wo[k]);
        do {
            if (k % 2 == 0) {
                double tl = acos(1.0 - uniform(&rng) * (1.0 - cos(lim)));
                tf_direction(tl, 2.0 * TF_PI * uniform(&rng), wi[k]);
            } else {
                /* Near the mirror direction: offsets of up to 0.4 radians
                 * (about 2 alpha for the golden file). */
                double dt = 0.4 * (2.0 * uniform(&rng) - 1.0);
                double dp = 0.4 * (2.0 * uniform(&rng) - 1.0) / (sin(tv) + 0.2);
                tf_direction(fabs(tv + dt), TF_PI + dp, wi[k]);
            }
        } while (acos(wi[k][2]) > lim);
        ok = ll_bsdf_eval_dir(src, wo[k], wi[k], LL_TRANSPORT_RADIANCE, basis, ref[k]) ==
                 LL_OK &&
             ll_bsdf_eval_dir(table, wo[k], wi[k], LL_TRANSPORT_RADIANCE, basis, got[k]) == LL_OK;
        for (c = 0; c < 3; ++c)
            if (ref[k][c] * wi[k][2] > top[c])
                top[c] = ref[k][c] * wi[k][2];
    }
    for (k = 0; ok && k < TF_PAIRS; ++k)
        for (c = 0; c < 3; ++c)
            if (ref[k][c] * wi[k][2] > 0.01 * top[c])
                err[n++] = fabs(got[k][c] / ref[k][c] - 1.0);
    if (ok && n > 0) {
        qsort(err, n, sizeof *err, tf_compare);
        fig->p50 = err[n / 2];
        fig->p95 = err[(size_t)(0.95 * (double)n)];
        fig->p99 = err[(size_t)(0.99 * (double)n)];
    }
    fig->n_values = n;
    free(wo);
    free(wi);
    free(ref);
    free(got);
    free(err);
    return ok && n > 0;
}

static inline int tf_f_errors(const ll_bsdf *src, const ll_bsdf *table, tf_figures *fig,
                              double (*uniform)(uint64_t *))
{
    return tf_f_errors_weighted(src, table, NULL, fig, uniform);
}

/* All the figures of table against src, both evaluated with the basis
 * weights basis (NULL: an untextured pair); fig->failed if a call failed. */
static inline void tf_measure_weighted(const ll_bsdf *src, const ll_bsdf *table,
                                       const float *basis, tf_figures *fig)
{
    int k, c;
    memset(fig, 0, sizeof *fig);
    for (k = 0; k < TF_ANGLES; ++k) {
        double mu = cos(tf_angles_deg[k] * TF_PI / 180.0), at[3], as[3];
        if (!tf_albedo_weighted(table, mu, basis, at) || !tf_albedo_weighted(src, mu, basis, as)) {
            fig->failed = 1;
            return;
        }
        for (c = 0; c < 3; ++c) {
            double r = at[c] / as[c];
            fig->albedo_ratio[k][c] = r;
            if (!(fabs(r - 1.0) <= fig->worst_albedo))
                fig->worst_albedo = fabs(r - 1.0);
        }
    }
    if (!tf_f_errors_weighted(src, table, basis, fig, tf_uniform))
        fig->failed = 1;
}

static inline void tf_measure(const ll_bsdf *src, const ll_bsdf *table, tf_figures *fig)
{
    tf_measure_weighted(src, table, NULL, fig);
}

static inline void tf_print(const char *label, const tf_figures *fig)
{
    int k;
    printf("%s: albedo table/source by viewer elevation (R G B):\n", label);
    for (k = 0; k < TF_ANGLES; ++k)
        printf("  %2.0f deg  %.5f %.5f %.5f\n", tf_angles_deg[k], fig->albedo_ratio[k][0],
               fig->albedo_ratio[k][1], fig->albedo_ratio[k][2]);
    printf("%s: worst albedo error %.3f%%; f errors over %zu channel values: median %.4f%% "
           "95th %.3f%% 99th %.3f%%\n",
           label, 100 * fig->worst_albedo, fig->n_values, 100 * fig->p50, 100 * fig->p95,
           100 * fig->p99);
}

#endif /* LL_TEST_TABLES_FIGURES_H */
