/* Helpers shared by the benchmark programs; see bench_util.h. */
#include "bench_util.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

static double timespec_seconds(clockid_t clock)
{
    struct timespec ts;
    if (clock_gettime(clock, &ts) != 0)
        bench_die("clock_gettime failed");
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

double bench_wall_seconds(void) { return timespec_seconds(CLOCK_MONOTONIC); }

double bench_cpu_seconds(void) { return timespec_seconds(CLOCK_PROCESS_CPUTIME_ID); }

void bench_metric(const char *id, const char *unit, double value)
{
    printf("metric %s %s %.9g\n", id, unit, value);
    fflush(stdout);
}

void bench_info(const char *key, const char *text)
{
    const char *p;
    printf("info %s ", key);
    /* One record per line: a newline inside the text would split it. */
    for (p = text; *p; ++p)
        putchar(*p == '\n' || *p == '\r' ? ' ' : *p);
    putchar('\n');
    fflush(stdout);
}

void bench_die(const char *fmt, ...)
{
    va_list ap;
    fflush(stdout);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
    exit(1);
}

void bench_check(ll_status status, const char *what)
{
    if (status != LL_OK)
        bench_die("%s failed: %s (%s)", what, ll_status_string(status),
                  ll_last_error_message());
}

void *bench_alloc(size_t count, size_t size)
{
    void *p;
    size_t bytes;
    if (size != 0 && count > (size_t)-1 / size)
        bench_die("allocation of %zu x %zu bytes overflows", count, size);
    bytes = count * size;
    p = malloc(bytes ? bytes : 1);
    if (!p)
        bench_die("out of memory (%zu x %zu bytes)", count, size);
    return p;
}

static uint32_t rng_next(bench_rng *rng)
{
    uint64_t old = rng->state;
    uint32_t xorshifted, rot;
    rng->state = old * 6364136223846793005ULL + rng->inc;
    xorshifted = (uint32_t)(((old >> 18u) ^ old) >> 27u);
    rot = (uint32_t)(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((32u - rot) & 31u));
}

void bench_rng_seed(bench_rng *rng, uint64_t seed)
{
    rng->state = 0;
    rng->inc = (seed << 1u) | 1u;
    (void)rng_next(rng);
    rng->state += 0x853c49e6748fea9bULL;
    (void)rng_next(rng);
}

double bench_rng_uniform(bench_rng *rng)
{
    uint64_t hi = rng_next(rng) >> 5, lo = rng_next(rng) >> 6; /* 27 + 26 bits */
    return ((double)hi * 67108864.0 + (double)lo) * (1.0 / 9007199254740992.0);
}

size_t bench_parse_size(const char *text, const char *what)
{
    char *end;
    unsigned long long v;
    errno = 0;
    v = strtoull(text, &end, 10);
    if (errno != 0 || end == text || *end != '\0' || text[0] == '-')
        bench_die("%s: \"%s\" is not a non-negative integer", what, text);
    return (size_t)v;
}

ll_status bench_set_microfacet(ll_layer *layer, double eta_re, double eta_im, double alpha,
                               int compensate, size_t n_orders_internal,
                               const ll_monitor *monitor)
{
    ll_microfacet mf = LL_MICROFACET_INIT;
    mf.eta_re = eta_re;
    mf.eta_im = eta_im;
    mf.alpha = alpha;
    mf.compensate = compensate;
    mf.n_orders_internal = n_orders_internal;
    return ll_layer_set_microfacet(layer, &mf, monitor);
}

ll_status bench_search_microfacet(double alpha, double eta_re, double eta_im, size_t *n_nodes,
                                  size_t *n_orders)
{
    ll_microfacet mf = LL_MICROFACET_INIT;
    mf.eta_re = eta_re;
    mf.eta_im = eta_im;
    mf.alpha = alpha;
    return ll_resolution_search_microfacet(&mf, 0.0, 0.0, NULL, n_nodes, n_orders, NULL);
}
