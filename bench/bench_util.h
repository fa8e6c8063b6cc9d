/*
 * Helpers shared by the benchmark programs in bench/: clocks, a seeded
 * random-number generator, failure handling and the one-line protocol in
 * which the measuring programs report to the driver (bench/driver.c).
 *
 * Protocol (stdout, one record a line):
 *     metric <id> <unit> <value>     one sample of a figure
 *     info <key> <text...>           a fact about the run (versions, sizes)
 * The driver collects the samples of each id over all runs and reports
 * their median, minimum and maximum.
 *
 * Benchmark programs are programs, not library code: on a failure they
 * print the library's message and exit.
 */
#ifndef BENCH_UTIL_H
#define BENCH_UTIL_H

#include <stddef.h>
#include <stdint.h>

#ifndef LL_EXPERIMENTAL
#define LL_EXPERIMENTAL /* ll_material_estimate, ll_layer_pack */
#endif
#include <layerlab.h>

/* Seconds on a monotonic wall clock. */
double bench_wall_seconds(void);
/* CPU seconds used by the whole process (all threads). */
double bench_cpu_seconds(void);

/* Print one metric sample / one info record (and flush, so that a crash
 * later keeps what was measured). */
void bench_metric(const char *id, const char *unit, double value);
void bench_info(const char *key, const char *text);

/* Exit with the library's message when status is not LL_OK. */
void bench_check(ll_status status, const char *what);
/* Exit with a message (printf-style). */
void bench_die(const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 1, 2), noreturn))
#endif
    ;

/* malloc that exits on failure. */
void *bench_alloc(size_t count, size_t size);

/* A small deterministic generator (PCG32, O'Neill 2014): the same seed
 * gives the same sequence on every machine. */
typedef struct bench_rng {
    uint64_t state, inc;
} bench_rng;

void bench_rng_seed(bench_rng *rng, uint64_t seed);
/* Uniform in [0, 1) with 53 random bits. */
double bench_rng_uniform(bench_rng *rng);

/* Parse a non-negative integer argument or exit naming it. */
size_t bench_parse_size(const char *text, const char *what);

/* ll_layer_set_microfacet of a Beckmann interface given by its numbers. */
ll_status bench_set_microfacet(ll_layer *layer, double eta_re, double eta_im, double alpha,
                               int compensate, size_t n_orders_internal,
                               const ll_monitor *monitor);
/* ll_resolution_search_microfacet of a compensated Beckmann interface at
 * the default tolerance (what a build chooses). */
ll_status bench_search_microfacet(double alpha, double eta_re, double eta_im, size_t *n_nodes,
                                  size_t *n_orders);

#endif /* BENCH_UTIL_H */
