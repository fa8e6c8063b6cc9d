/*
 * The per-call workload of the evaluation benchmarks (bench/eval.c,
 * bench/tables.c, bench/batch.c): direction pairs and sample points drawn
 * once, before timing, from a fixed seed, and the timed loops of
 * ll_bsdf_eval_dir, ll_bsdf_pdf_dir and ll_bsdf_sample_dir over them. One
 * copy, so that the scalar figures of a .bsdf and of a table file, and the
 * batch figures, are measured the same way.
 */
#ifndef BENCH_CALLS_H
#define BENCH_CALLS_H

#include "bench_util.h"

typedef struct bench_calls {
    size_t calls;
    double *wo, *wi, *u; /* [3 calls], [3 calls], [2 calls] */
} bench_calls;

/* A direction uniformly distributed over the upper hemisphere. */
void bench_uniform_hemisphere(bench_rng *rng, double w[3]);

/* wi of call k for the viewer wo; NULL in bench_calls_make: uniform over
 * the upper hemisphere, like wo. */
typedef void (*bench_light_fn)(bench_rng *rng, const double wo[3], size_t k, double wi[3]);

/* Draw `calls` calls from `seed`: for each, wo uniform over the upper
 * hemisphere, then wi (by `light`), then u uniform in [0, 1)^2. */
void bench_calls_make(bench_calls *w, size_t calls, uint64_t seed, bench_light_fn light);
void bench_calls_free(bench_calls *w);

/* The timers below measure wall seconds, or after
 * bench_calls_use_cpu_time(1) the process's CPU seconds (for a program
 * that makes its calls on one thread: on a shared machine the steadier
 * figure). bench_calls_seconds: that clock. */
void bench_calls_use_cpu_time(int on);
double bench_calls_seconds(void);

/* Each timer makes w->calls calls of its function on one handle and
 * returns the seconds they took; it adds their results to *sum,
 * which the program prints, so that the work is observable. */
double bench_time_eval(const ll_bsdf *b, const bench_calls *w, double *sum);
double bench_time_pdf(const ll_bsdf *b, const bench_calls *w, double *sum);
double bench_time_sample(const ll_bsdf *b, const bench_calls *w, double *sum);

/* An untimed pass of each timer over 1% of the calls (at least one), to
 * warm caches and pages; pdf only when `pdf` is set. */
void bench_calls_warm(const ll_bsdf *b, const bench_calls *w, int pdf, double *sum);

/* One run of the three timers as the metrics PREFIXeval_dir,
 * PREFIXpdf_dir and PREFIXsample_dir, in nanoseconds per call. */
void bench_calls_measure(const ll_bsdf *b, const bench_calls *w, const char *prefix,
                         double *sum);

#endif /* BENCH_CALLS_H */
