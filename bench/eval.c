/*
 * Evaluation speed of an opened .bsdf file in the renderer convention:
 * nanoseconds per call of ll_bsdf_eval_dir, ll_bsdf_pdf_dir and
 * ll_bsdf_sample_dir on one thread.
 *
 * usage: eval FILE.bsdf LABEL RUNS [CALLS]      (CALLS default 10^6)
 *
 * The directions are drawn once, before timing, from a fixed seed: wo and
 * wi uniformly distributed over the upper hemisphere (the side a renderer
 * sees an opaque layered material from), u uniform in [0, 1)^2. Each run
 * makes CALLS calls of each function over the same arrays, so the figures
 * include what a renderer pays per call (argument checks, the frame
 * conversion, the spline and Fourier work) and nothing of the generator.
 */
#include "bench_util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#define DEFAULT_CALLS 1000000

static void uniform_hemisphere(bench_rng *rng, double w[3])
{
    double z = bench_rng_uniform(rng), r = sqrt(fmax(0.0, 1.0 - z * z));
    double phi = 2.0 * 3.14159265358979323846 * bench_rng_uniform(rng);
    w[0] = r * cos(phi);
    w[1] = r * sin(phi);
    w[2] = z;
}

typedef struct workload {
    size_t calls;
    double *wo, *wi, *u; /* [3 calls], [3 calls], [2 calls] */
} workload;

static void workload_make(workload *w, size_t calls)
{
    bench_rng rng;
    size_t k;
    bench_rng_seed(&rng, 20140801);
    w->calls = calls;
    w->wo = bench_alloc(calls, 3 * sizeof(double));
    w->wi = bench_alloc(calls, 3 * sizeof(double));
    w->u = bench_alloc(calls, 2 * sizeof(double));
    for (k = 0; k < calls; ++k) {
        uniform_hemisphere(&rng, w->wo + 3 * k);
        uniform_hemisphere(&rng, w->wi + 3 * k);
        w->u[2 * k] = bench_rng_uniform(&rng);
        w->u[2 * k + 1] = bench_rng_uniform(&rng);
    }
}

static void workload_free(workload *w)
{
    free(w->wo);
    free(w->wi);
    free(w->u);
}

/* Each timer returns seconds and adds its results to *sum, which is
 * printed, so that the work is observable. */
static double time_eval(const ll_bsdf *b, const workload *w, double *sum)
{
    double rgb[3], start = bench_wall_seconds(), acc = 0.0;
    size_t k;
    for (k = 0; k < w->calls; ++k) {
        bench_check(ll_bsdf_eval_dir(b, w->wo + 3 * k, w->wi + 3 * k, LL_TRANSPORT_RADIANCE,
                                     NULL, rgb),
                    "ll_bsdf_eval_dir");
        acc += rgb[0] + rgb[1] + rgb[2];
    }
    start = bench_wall_seconds() - start;
    *sum += acc;
    return start;
}

static double time_pdf(const ll_bsdf *b, const workload *w, double *sum)
{
    double start = bench_wall_seconds(), acc = 0.0;
    size_t k;
    for (k = 0; k < w->calls; ++k) {
        double pdf;
        bench_check(ll_bsdf_pdf_dir(b, w->wo + 3 * k, w->wi + 3 * k, NULL, &pdf),
                    "ll_bsdf_pdf_dir");
        acc += pdf;
    }
    start = bench_wall_seconds() - start;
    *sum += acc;
    return start;
}

static double time_sample(const ll_bsdf *b, const workload *w, double *sum)
{
    double wi[3], pdf, rgb[3], start = bench_wall_seconds(), acc = 0.0;
    size_t k;
    for (k = 0; k < w->calls; ++k) {
        bench_check(ll_bsdf_sample_dir(b, w->wo + 3 * k, w->u + 2 * k, LL_TRANSPORT_RADIANCE,
                                       NULL, wi, &pdf, rgb),
                    "ll_bsdf_sample_dir");
        acc += pdf + wi[2] + rgb[1];
    }
    start = bench_wall_seconds() - start;
    *sum += acc;
    return start;
}

int main(int argc, char **argv)
{
    ll_bsdf *b = NULL;
    workload w;
    size_t runs, calls = DEFAULT_CALLS, run;
    double sum = 0.0, scale;
    char id[128], text[64];

    if (argc != 4 && argc != 5)
        bench_die("usage: %s FILE.bsdf LABEL RUNS [CALLS]", argv[0]);
    runs = bench_parse_size(argv[3], "RUNS");
    if (argc == 5)
        calls = bench_parse_size(argv[4], "CALLS");
    if (calls == 0)
        bench_die("eval: CALLS must be positive");
    bench_check(ll_set_thread_count(1), "ll_set_thread_count");
    bench_check(ll_bsdf_open(argv[1], NULL, &b), "ll_bsdf_open");
    workload_make(&w, calls);
    scale = 1e9 / (double)calls;

    /* An untimed pass of each over 1% of the calls warms caches and pages. */
    {
        workload warm = w;
        warm.calls = calls / 100 ? calls / 100 : 1;
        (void)time_eval(b, &warm, &sum);
        (void)time_pdf(b, &warm, &sum);
        (void)time_sample(b, &warm, &sum);
    }
    for (run = 0; run < runs; ++run) {
        snprintf(id, sizeof id, "eval.%s.eval_dir", argv[2]);
        bench_metric(id, "ns", time_eval(b, &w, &sum) * scale);
        snprintf(id, sizeof id, "eval.%s.pdf_dir", argv[2]);
        bench_metric(id, "ns", time_pdf(b, &w, &sum) * scale);
        snprintf(id, sizeof id, "eval.%s.sample_dir", argv[2]);
        bench_metric(id, "ns", time_sample(b, &w, &sum) * scale);
    }
    snprintf(id, sizeof id, "eval.%s.checksum", argv[2]);
    snprintf(text, sizeof text, "%.17g", sum);
    bench_info(id, text);
    workload_free(&w);
    ll_bsdf_release(b);
    return 0;
}
