/*
 * Per-element cost of the batch calls (ll_bsdf_eval_dir_batch,
 * ll_bsdf_pdf_dir_batch, ll_bsdf_sample_dir_batch) in nanoseconds, with one
 * thread and with every processor (LAYERLAB_BATCH_THREADS), on the same
 * directions as bench/eval.c draws them (wo, wi uniform over the upper
 * hemisphere, u uniform), cut into batches of BATCH elements as a wavefront
 * renderer would pass them. Compare with eval.c's scalar figures: the
 * difference is the batch overhead (one thread) and the threading gain.
 *
 * usage: batch FILE.bsdf LABEL RUNS [CALLS [BATCH]]   (10^6 and 65536)
 */
#include "calls.h"

#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

/* eval.c's calls (the same seed), cut into batches, and the outputs. */
typedef struct workload {
    bench_calls in;
    size_t batch;
    double *rgb, *pdf, *wi_out;
} workload;

static void workload_make(workload *w, size_t calls, size_t batch)
{
    bench_calls_make(&w->in, calls, 20140801, NULL);
    w->batch = batch;
    w->rgb = bench_alloc(calls, 3 * sizeof(double));
    w->pdf = bench_alloc(calls, sizeof(double));
    w->wi_out = bench_alloc(calls, 3 * sizeof(double));
}

/* One timed pass of function f (0 eval, 1 pdf, 2 sample) over all calls in
 * batches; adds the outputs to *sum so that the work is observable. */
static double time_pass(const ll_bsdf *b, const workload *w, int f, double *sum)
{
    double start = bench_wall_seconds(), acc = 0.0;
    size_t k, n;
    for (k = 0; k < w->in.calls; k += n) {
        n = w->in.calls - k < w->batch ? w->in.calls - k : w->batch;
        if (f == 0)
            bench_check(ll_bsdf_eval_dir_batch(b, n, w->in.wo + 3 * k, w->in.wi + 3 * k,
                                               LL_TRANSPORT_RADIANCE, NULL, 0, w->rgb + 3 * k),
                        "ll_bsdf_eval_dir_batch");
        else if (f == 1)
            bench_check(ll_bsdf_pdf_dir_batch(b, n, w->in.wo + 3 * k, w->in.wi + 3 * k, NULL, 0,
                                              w->pdf + k),
                        "ll_bsdf_pdf_dir_batch");
        else
            bench_check(ll_bsdf_sample_dir_batch(b, n, w->in.wo + 3 * k, w->in.u + 2 * k,
                                                 LL_TRANSPORT_RADIANCE, NULL, 0,
                                                 w->wi_out + 3 * k, w->pdf + k, w->rgb + 3 * k),
                        "ll_bsdf_sample_dir_batch");
    }
    start = bench_wall_seconds() - start;
    for (k = 0; k < w->in.calls; ++k)
        acc += f == 1 ? w->pdf[k] : w->rgb[3 * k] + w->rgb[3 * k + 1] + w->rgb[3 * k + 2];
    *sum += acc;
    return start;
}

int main(int argc, char **argv)
{
    static const char *names[3] = { "eval_dir_batch", "pdf_dir_batch", "sample_dir_batch" };
    ll_bsdf *b = NULL;
    workload w;
    size_t runs, calls = 1000000, batch = 65536, run;
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    double sum = 0.0;
    char id[160], text[64], threads[2][24];
    int f, t;

    if (argc < 4 || argc > 6)
        bench_die("usage: %s FILE.bsdf LABEL RUNS [CALLS [BATCH]]", argv[0]);
    runs = bench_parse_size(argv[3], "RUNS");
    if (argc >= 5)
        calls = bench_parse_size(argv[4], "CALLS");
    if (argc == 6)
        batch = bench_parse_size(argv[5], "BATCH");
    if (calls == 0 || batch == 0)
        bench_die("batch: CALLS and BATCH must be positive");
    snprintf(threads[0], sizeof threads[0], "1");
    snprintf(threads[1], sizeof threads[1], "%ld", cores > 0 ? cores : 1);
    bench_check(ll_bsdf_open(argv[1], NULL, &b), "ll_bsdf_open");
    workload_make(&w, calls, batch);
    for (t = 0; t < 2; ++t) {
        if (setenv("LAYERLAB_BATCH_THREADS", threads[t], 1) != 0)
            bench_die("batch: setenv failed");
        for (f = 0; f < 3; ++f)
            (void)time_pass(b, &w, f, &sum); /* warm-up */
        for (run = 0; run < runs; ++run)
            for (f = 0; f < 3; ++f) {
                snprintf(id, sizeof id, "batch.%s.%s.threads%s", argv[2], names[f], threads[t]);
                bench_metric(id, "ns", time_pass(b, &w, f, &sum) * 1e9 / (double)calls);
            }
    }
    snprintf(id, sizeof id, "batch.%s.checksum", argv[2]);
    snprintf(text, sizeof text, "%.17g", sum);
    bench_info(id, text);
    ll_bsdf_release(b);
    return 0;
}
