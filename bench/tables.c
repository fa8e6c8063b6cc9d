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
 * uniform in [0, 1)^2. Times are CPU seconds (every call on one thread).
 * Metrics: tables.LABEL.{eval,pdf,sample}_dir and
 * tables.LABEL.bsdf_{eval,pdf,sample}_dir ("cold": every call reads new,
 * scattered nodes of the tables); on the table also
 * tables.LABEL.hot_{eval,pdf,sample}_dir, the first HOT_CALLS calls made
 * over and over until as many calls are made (their nodes stay in cache:
 * the cost of the code itself), and tables.LABEL.batch_{eval,pdf,sample}_dir,
 * ns per element of ll_bsdf_eval_dir_batch, ll_bsdf_pdf_dir_batch and
 * ll_bsdf_sample_dir_batch over all the calls on one thread
 * (LAYERLAB_BATCH_THREADS=1).
 */
#define LL_EXPERIMENTAL /* ll_tables_write_from_bsdf */
#include "calls.h"

#include <layerlab/ll_tables.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define DEFAULT_CALLS 1000000
#define HOT_CALLS 64
#define HOT_REPEAT 256

/* wi of call k for the viewer wo (bench_light_fn): for odd k the
 * reflection of wo about a normal m near the pole, for even k a uniform
 * direction (above the surface either way, as wo). */
static void light_for(bench_rng *rng, const double wo[3], size_t k, double wi[3])
{
    double m[3], len, d;
    if (!(k & 1u)) {
        bench_uniform_hemisphere(rng, wi);
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

/* The hot figures: w's first HOT_CALLS calls (fewer if w has fewer)
 * repeated HOT_REPEAT times in one workload, timed over and over until at
 * least w->calls calls are made, per call (one clock reading per
 * HOT_CALLS * HOT_REPEAT calls). */
static void measure_hot(const ll_bsdf *b, const bench_calls *w, const char *prefix,
                        double *sum)
{
    bench_calls hot;
    double t[3] = { 0.0, 0.0, 0.0 };
    size_t n = w->calls < HOT_CALLS ? w->calls : HOT_CALLS, made, k;
    char id[192];
    hot.calls = n * HOT_REPEAT;
    hot.wo = bench_alloc(hot.calls, 3 * sizeof(double));
    hot.wi = bench_alloc(hot.calls, 3 * sizeof(double));
    hot.u = bench_alloc(hot.calls, 2 * sizeof(double));
    for (k = 0; k < hot.calls; ++k) {
        memcpy(hot.wo + 3 * k, w->wo + 3 * (k % n), 3 * sizeof(double));
        memcpy(hot.wi + 3 * k, w->wi + 3 * (k % n), 3 * sizeof(double));
        memcpy(hot.u + 2 * k, w->u + 2 * (k % n), 2 * sizeof(double));
    }
    for (made = 0; made < w->calls; made += hot.calls) {
        t[0] += bench_time_eval(b, &hot, sum);
        t[1] += bench_time_pdf(b, &hot, sum);
        t[2] += bench_time_sample(b, &hot, sum);
    }
    snprintf(id, sizeof id, "%shot_eval_dir", prefix);
    bench_metric(id, "ns", t[0] * 1e9 / (double)made);
    snprintf(id, sizeof id, "%shot_pdf_dir", prefix);
    bench_metric(id, "ns", t[1] * 1e9 / (double)made);
    snprintf(id, sizeof id, "%shot_sample_dir", prefix);
    bench_metric(id, "ns", t[2] * 1e9 / (double)made);
    bench_calls_free(&hot);
}

/* The batch figures: all of w's calls in one batch call of each kind. */
static void measure_batch(const ll_bsdf *b, const bench_calls *w, const char *prefix,
                          double *sum, double *out, double *pdf, double *wi)
{
    double start;
    char id[192];
    start = bench_calls_seconds();
    bench_check(ll_bsdf_eval_dir_batch(b, w->calls, w->wo, w->wi, LL_TRANSPORT_RADIANCE, NULL,
                                       0, out),
                "ll_bsdf_eval_dir_batch");
    snprintf(id, sizeof id, "%sbatch_eval_dir", prefix);
    bench_metric(id, "ns", (bench_calls_seconds() - start) * 1e9 / (double)w->calls);
    *sum += out[0];
    start = bench_calls_seconds();
    bench_check(ll_bsdf_pdf_dir_batch(b, w->calls, w->wo, w->wi, NULL, 0, pdf),
                "ll_bsdf_pdf_dir_batch");
    snprintf(id, sizeof id, "%sbatch_pdf_dir", prefix);
    bench_metric(id, "ns", (bench_calls_seconds() - start) * 1e9 / (double)w->calls);
    *sum += pdf[0];
    start = bench_calls_seconds();
    bench_check(ll_bsdf_sample_dir_batch(b, w->calls, w->wo, w->u, LL_TRANSPORT_RADIANCE, NULL,
                                         0, wi, pdf, out),
                "ll_bsdf_sample_dir_batch");
    snprintf(id, sizeof id, "%sbatch_sample_dir", prefix);
    bench_metric(id, "ns", (bench_calls_seconds() - start) * 1e9 / (double)w->calls);
    *sum += out[0] + pdf[0];
}

int main(int argc, char **argv)
{
    ll_bsdf *source = NULL, *table = NULL;
    ll_bsdf_info info = LL_BSDF_INFO_INIT;
    bench_calls w;
    size_t runs, calls = DEFAULT_CALLS, run;
    double sum = 0.0, start, *out, *pdf, *wi;
    char text[64], prefix[2][128];

    if (argc != 5 && argc != 6)
        bench_die("usage: %s SOURCE.bsdf TABLE_OUT LABEL RUNS [CALLS]", argv[0]);
    runs = bench_parse_size(argv[4], "RUNS");
    if (argc == 6)
        calls = bench_parse_size(argv[5], "CALLS");
    if (calls == 0)
        bench_die("tables: CALLS must be positive");
    bench_check(ll_set_thread_count(1), "ll_set_thread_count");
    /* Every call on this one thread: CPU time, which a shared machine's
     * other work does not lengthen as it does the wall time. */
    bench_calls_use_cpu_time(1);
    /* The batch calls on one thread, as the scalar ones. */
    if (setenv("LAYERLAB_BATCH_THREADS", "1", 1) != 0)
        bench_die("tables: setenv failed");
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
    bench_calls_make(&w, calls, 29, light_for);
    out = bench_alloc(calls, 3 * sizeof(double));
    wi = bench_alloc(calls, 3 * sizeof(double));
    pdf = bench_alloc(calls, sizeof(double));
    /* An untimed pass of each over 1% of the calls warms caches and pages. */
    bench_calls_warm(table, &w, 1, &sum);
    bench_calls_warm(source, &w, 0, &sum);
    snprintf(prefix[0], sizeof prefix[0], "tables.%s.", argv[3]);
    snprintf(prefix[1], sizeof prefix[1], "tables.%s.bsdf_", argv[3]);
    for (run = 0; run < runs; ++run) {
        bench_calls_measure(table, &w, prefix[0], &sum);
        measure_hot(table, &w, prefix[0], &sum);
        measure_batch(table, &w, prefix[0], &sum, out, pdf, wi);
        bench_calls_measure(source, &w, prefix[1], &sum);
    }
    snprintf(text, sizeof text, "%g", sum);
    bench_info("checksum", text);
    ll_bsdf_release(table);
    ll_bsdf_release(source);
    bench_calls_free(&w);
    free(out);
    free(wi);
    free(pdf);
    return 0;
}
