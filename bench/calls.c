/* The per-call workload and its timers (calls.h). */
#include "calls.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

/* The timers' clock: wall seconds unless bench_calls_use_cpu_time. */
static int use_cpu_time;

void bench_calls_use_cpu_time(int on) { use_cpu_time = on; }

double bench_calls_seconds(void)
{
    return use_cpu_time ? bench_cpu_seconds() : bench_wall_seconds();
}

void bench_uniform_hemisphere(bench_rng *rng, double w[3])
{
    double z = bench_rng_uniform(rng), r = sqrt(fmax(0.0, 1.0 - z * z));
    double phi = 2.0 * 3.14159265358979323846 * bench_rng_uniform(rng);
    w[0] = r * cos(phi);
    w[1] = r * sin(phi);
    w[2] = z;
}

void bench_calls_make(bench_calls *w, size_t calls, uint64_t seed, bench_light_fn light)
{
    bench_rng rng;
    size_t k;
    bench_rng_seed(&rng, seed);
    w->calls = calls;
    w->wo = bench_alloc(calls, 3 * sizeof(double));
    w->wi = bench_alloc(calls, 3 * sizeof(double));
    w->u = bench_alloc(calls, 2 * sizeof(double));
    for (k = 0; k < calls; ++k) {
        bench_uniform_hemisphere(&rng, w->wo + 3 * k);
        if (light)
            light(&rng, w->wo + 3 * k, k, w->wi + 3 * k);
        else
            bench_uniform_hemisphere(&rng, w->wi + 3 * k);
        w->u[2 * k] = bench_rng_uniform(&rng);
        w->u[2 * k + 1] = bench_rng_uniform(&rng);
    }
}

void bench_calls_free(bench_calls *w)
{
    free(w->wo);
    free(w->wi);
    free(w->u);
}

double bench_time_eval(const ll_bsdf *b, const bench_calls *w, double *sum)
{
    double rgb[3], start = bench_calls_seconds(), acc = 0.0;
    size_t k;
    for (k = 0; k < w->calls; ++k) {
        bench_check(ll_bsdf_eval_dir(b, w->wo + 3 * k, w->wi + 3 * k, LL_TRANSPORT_RADIANCE,
                                     NULL, rgb),
                    "ll_bsdf_eval_dir");
        acc += rgb[0] + rgb[1] + rgb[2];
    }
    start = bench_calls_seconds() - start;
    *sum += acc;
    return start;
}

double bench_time_pdf(const ll_bsdf *b, const bench_calls *w, double *sum)
{
    double start = bench_calls_seconds(), acc = 0.0;
    size_t k;
    for (k = 0; k < w->calls; ++k) {
        double pdf;
        bench_check(ll_bsdf_pdf_dir(b, w->wo + 3 * k, w->wi + 3 * k, NULL, &pdf),
                    "ll_bsdf_pdf_dir");
        acc += pdf;
    }
    start = bench_calls_seconds() - start;
    *sum += acc;
    return start;
}

double bench_time_sample(const ll_bsdf *b, const bench_calls *w, double *sum)
{
    double wi[3], pdf, rgb[3], start = bench_calls_seconds(), acc = 0.0;
    size_t k;
    for (k = 0; k < w->calls; ++k) {
        bench_check(ll_bsdf_sample_dir(b, w->wo + 3 * k, w->u + 2 * k, LL_TRANSPORT_RADIANCE,
                                       NULL, wi, &pdf, rgb),
                    "ll_bsdf_sample_dir");
        acc += pdf + wi[2] + rgb[1];
    }
    start = bench_calls_seconds() - start;
    *sum += acc;
    return start;
}

void bench_calls_warm(const ll_bsdf *b, const bench_calls *w, int pdf, double *sum)
{
    bench_calls warm = *w;
    warm.calls = w->calls / 100 ? w->calls / 100 : 1;
    (void)bench_time_eval(b, &warm, sum);
    if (pdf)
        (void)bench_time_pdf(b, &warm, sum);
    (void)bench_time_sample(b, &warm, sum);
}

void bench_calls_measure(const ll_bsdf *b, const bench_calls *w, const char *prefix, double *sum)
{
    double scale = 1e9 / (double)w->calls;
    char id[192];
    snprintf(id, sizeof id, "%seval_dir", prefix);
    bench_metric(id, "ns", bench_time_eval(b, w, sum) * scale);
    snprintf(id, sizeof id, "%spdf_dir", prefix);
    bench_metric(id, "ns", bench_time_pdf(b, w, sum) * scale);
    snprintf(id, sizeof id, "%ssample_dir", prefix);
    bench_metric(id, "ns", bench_time_sample(b, w, sum) * scale);
}
