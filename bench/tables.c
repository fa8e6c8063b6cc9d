/*
 * Per-call cost of table files (the `measured` format) against the .bsdf
 * they are made from: nanoseconds per call of ll_bsdf_eval_dir,
 * ll_bsdf_pdf_dir and ll_bsdf_sample_dir on one thread, on both handles,
 * over the same directions.
 *
 * usage: tables SOURCE.bsdf TABLE_OUT LABEL RUNS [CALLS]   (CALLS default 10^6)
 *
 * The table is written from SOURCE with the sizes the default tolerance
 * chooses (ll_tables_write_from_bsdf) to TABLE_OUT, then opened with ll_bsdf_open
 * as a renderer would. The directions are drawn once, before timing, from
 * a fixed seed: wo uniform over the upper hemisphere (the viewer; a table
 * file reflects only, and reflection has wo and wi on the same side in the
 * renderer convention of ll_bsdf.h), wi half uniform over the upper
 * hemisphere and half the mirror direction of wo turned
 * by a normal within about 0.2 radians of the pole (inside a glossy lobe,
 * where a renderer's evaluations of a glossy material concentrate), u
 * uniform in [0, 1)^2. Metrics: tables.LABEL.{eval,pdf,sample}_dir and
 * tables.LABEL.bsdf_{eval,pdf,sample}_dir.
 */
#define LL_EXPERIMENTAL /* ll_tables_write_from_bsdf */
#include "bench_util.h"

#include <layerlab/ll_tables.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#define DEFAULT_CALLS 1000000
#define PI 3.14159265358979323846

typedef struct workload {
    size_t calls;
    double *wo, *wi, *u; /* [3 calls], [3 calls], [2 calls] */
} workload;

static void uniform_hemisphere(bench_rng *rng, double w[3])
{
    double z = bench_rng_uniform(rng), r = sqrt(fmax(0.0, 1.0 - z * z));
    double phi = 2.0 * PI * bench_rng_uniform(rng);
    w[0] = r * cos(phi);
    w[1] = r * sin(phi);
    w[2] = z;
}

/* wi for the viewer wo: the reflection of wo about a normal m near the
 * pole, or a uniform direction (above the surface either way, as wo). */
static void light_for(bench_rng *rng, const double wo[3], int near_mirror, double wi[3])
{
    double m[3], len, d;
    if (!near_mirror) {
        uniform_hemisphere(rng, wi);
        return;
    }
    m[0] = 0.2 * (2.0 * bench_rng_uniform(rng) - 1.0);
    m[1] = 0.2 * (2.0 * bench_rng_uniform(rng) - 1.0);
    m[2] = 1.0;
    len = sqrt(m[0] * m[0] + m[1] * m[1] + 1.0);
    m[0] /= len;
    m[1] /= len;
    m[2] /= len;
    d = wo[0] * m[0] + wo[1] * m[1] + wo[2] * m[2];
    wi[0] = 2.0 * d * m[0] - wo[0];
    wi[1] = 2.0 * d * m[1] - wo[1];
    wi[2] = 2.0 * d * m[2] - wo[2];
}

static void workload_make(workload *w, size_t calls)
{
    bench_rng rng;
    size_t k;
    bench_rng_seed(&rng, 29);
    w->calls = calls;
    w->wo = bench_alloc(3 * calls, sizeof(double));
    w->wi = bench_alloc(3 * calls, sizeof(double));
    w->u = bench_alloc(2 * calls, sizeof(double));
    for (k = 0; k < calls; ++k) {
        uniform_hemisphere(&rng, w->wo + 3 * k);
        light_for(&rng, w->wo + 3 * k, (int)(k & 1u), w->wi + 3 * k);
        w->u[2 * k] = bench_rng_uniform(&rng);
        w->u[2 * k + 1] = bench_rng_uniform(&rng);
    }
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
    *sum += acc;
    return bench_wall_seconds() - start;
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
    *sum += acc;
    return bench_wall_seconds() - start;
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
    *sum += acc;
    return bench_wall_seconds() - start;
}

/* One run of the three calls on b, as metrics tables.LABEL.PREFIX*_dir. */
static void measure(const ll_bsdf *b, const workload *w, const char *label, const char *prefix,
                    double *sum)
{
    double scale = 1e9 / (double)w->calls;
    char id[160];
    snprintf(id, sizeof id, "tables.%s.%seval_dir", label, prefix);
    bench_metric(id, "ns", time_eval(b, w, sum) * scale);
    snprintf(id, sizeof id, "tables.%s.%spdf_dir", label, prefix);
    bench_metric(id, "ns", time_pdf(b, w, sum) * scale);
    snprintf(id, sizeof id, "tables.%s.%ssample_dir", label, prefix);
    bench_metric(id, "ns", time_sample(b, w, sum) * scale);
}

int main(int argc, char **argv)
{
    ll_bsdf *source = NULL, *table = NULL;
    ll_bsdf_info info = LL_BSDF_INFO_INIT;
    workload w, warm;
    size_t runs, calls = DEFAULT_CALLS, run;
    double sum = 0.0, start;
    char text[64];

    if (argc != 5 && argc != 6)
        bench_die("usage: %s SOURCE.bsdf TABLE_OUT LABEL RUNS [CALLS]", argv[0]);
    runs = bench_parse_size(argv[4], "RUNS");
    if (argc == 6)
        calls = bench_parse_size(argv[5], "CALLS");
    if (calls == 0)
        bench_die("tables: CALLS must be positive");
    bench_check(ll_set_thread_count(1), "ll_set_thread_count");
    bench_check(ll_bsdf_open(argv[1], NULL, &source), "ll_bsdf_open (source)");
    start = bench_wall_seconds();
    bench_check(ll_tables_write_from_bsdf(source, argv[2], NULL, NULL),
                "ll_tables_write_from_bsdf");
    snprintf(text, sizeof text, "%.2f s", bench_wall_seconds() - start);
    bench_info("tables write (sizes by the default tolerance, one thread)", text);
    bench_check(ll_bsdf_open(argv[2], NULL, &table), "ll_bsdf_open (table)");
    bench_check(ll_bsdf_get_info(table, &info), "ll_bsdf_get_info");
    snprintf(text, sizeof text, "%zu bytes", info.file_size);
    bench_info("table file", text);
    workload_make(&w, calls);
    /* An untimed pass of each over 1% of the calls warms caches and pages. */
    warm = w;
    warm.calls = calls / 100 ? calls / 100 : 1;
    (void)time_eval(table, &warm, &sum);
    (void)time_pdf(table, &warm, &sum);
    (void)time_sample(table, &warm, &sum);
    (void)time_eval(source, &warm, &sum);
    (void)time_sample(source, &warm, &sum);
    for (run = 0; run < runs; ++run) {
        measure(table, &w, argv[3], "", &sum);
        measure(source, &w, argv[3], "bsdf_", &sum);
    }
    snprintf(text, sizeof text, "%g", sum);
    bench_info("checksum", text);
    ll_bsdf_release(table);
    ll_bsdf_release(source);
    free(w.wo);
    free(w.wi);
    free(w.u);
    return 0;
}
