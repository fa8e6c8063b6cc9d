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
#include "calls.h"

#include <stdio.h>

#define DEFAULT_CALLS 1000000

int main(int argc, char **argv)
{
    ll_bsdf *b = NULL;
    bench_calls w;
    size_t runs, calls = DEFAULT_CALLS, run;
    double sum = 0.0;
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
    bench_calls_make(&w, calls, 20140801, NULL);

    /* An untimed pass of each over 1% of the calls warms caches and pages. */
    bench_calls_warm(b, &w, 1, &sum);
    snprintf(id, sizeof id, "eval.%s.", argv[2]);
    for (run = 0; run < runs; ++run)
        bench_calls_measure(b, &w, id, &sum);
    snprintf(id, sizeof id, "eval.%s.checksum", argv[2]);
    snprintf(text, sizeof text, "%.17g", sum);
    bench_info(id, text);
    bench_calls_free(&w);
    ll_bsdf_release(b);
    return 0;
}
