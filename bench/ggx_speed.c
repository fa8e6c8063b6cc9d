/*
 * The build of a GGX interface against the Beckmann one at the same
 * resolution: ll_layer_set_microfacet of each, one thread, CPU seconds
 * (the best of RUNS), by alpha, for a dielectric of eta 1.5 and for gold.
 * Both get the same (n, m): the nodes given, and the orders that the
 * tolerance search chooses for GGX at that alpha (docs/method.md's
 * resolution table), which Beckmann's shorter series leave partly empty.
 * The ratio GGX / Beckmann is the figure (docs/benchmarks.md).
 *
 * usage: ggx_speed [NODES [RUNS [CASE [DIST]]]]
 *   (default 100 nodes, 3 runs, every case, both distributions). CASE, a
 *   row of the table from 1, and DIST, ggx or beckmann, build that alone
 *   (its seconds in its own column, the other 0): one build to count the
 *   instructions of, e.g. under valgrind --tool=callgrind.
 */
#include "bench_util.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Gold's index in the red channel (bench/recipe.c's), mono. */
#define GOLD_RE 0.14317534881908534
#define GOLD_IM 3.9826674681176435

typedef struct speed_case {
    const char *material;
    double eta_re, eta_im, alpha;
    size_t orders; /* GGX's choice at the default tolerance */
} speed_case;

static const speed_case cases[] = {
    { "eta 1.5", 1.5, 0.0, 0.05, 1179 }, { "eta 1.5", 1.5, 0.0, 0.1, 589 },
    { "eta 1.5", 1.5, 0.0, 0.2, 272 },   { "eta 1.5", 1.5, 0.0, 0.3, 192 },
    { "eta 1.5", 1.5, 0.0, 0.5, 108 },   { "eta 1.5", 1.5, 0.0, 0.8, 74 },
    { "gold", GOLD_RE, GOLD_IM, 0.05, 1179 }, { "gold", GOLD_RE, GOLD_IM, 0.1, 587 },
    { "gold", GOLD_RE, GOLD_IM, 0.2, 322 },   { "gold", GOLD_RE, GOLD_IM, 0.3, 221 },
    { "gold", GOLD_RE, GOLD_IM, 0.5, 139 },   { "gold", GOLD_RE, GOLD_IM, 0.8, 101 },
};

/* The best CPU seconds of runs builds of one interface. */
static double build_seconds(const speed_case *c, int distribution, size_t n, size_t runs)
{
    double *nodes = bench_alloc(n, sizeof *nodes), *weights = bench_alloc(n, sizeof *weights);
    double best = -1.0;
    size_t r;
    bench_check(ll_quad_gauss_lobatto(n, nodes, weights, NULL), "ll_quad_gauss_lobatto");
    for (r = 0; r < runs; ++r) {
        ll_microfacet mf = LL_MICROFACET_INIT;
        ll_layer *layer = NULL;
        double start;
        mf.eta_re = c->eta_re;
        mf.eta_im = c->eta_im;
        mf.alpha = c->alpha;
        mf.distribution = distribution;
        bench_check(ll_layer_create(nodes, weights, n, c->orders, &layer), "ll_layer_create");
        start = bench_cpu_seconds();
        bench_check(ll_layer_set_microfacet(layer, &mf, NULL), "ll_layer_set_microfacet");
        start = bench_cpu_seconds() - start;
        if (best < 0.0 || start < best)
            best = start;
        ll_layer_destroy(layer);
    }
    free(nodes);
    free(weights);
    return best;
}

int main(int argc, char **argv)
{
    size_t n = argc > 1 ? bench_parse_size(argv[1], "NODES") : 100;
    size_t runs = argc > 2 ? bench_parse_size(argv[2], "RUNS") : 3, i;
    size_t n_cases = sizeof cases / sizeof cases[0];
    size_t only = argc > 3 ? bench_parse_size(argv[3], "CASE") : 0;
    int beckmann_too = argc <= 4 || strcmp(argv[4], "beckmann") == 0;
    int ggx_too = argc <= 4 || strcmp(argv[4], "ggx") == 0;
    if (n < 4 || n % 2 || runs < 1 || only > n_cases || !(beckmann_too || ggx_too))
        bench_die("usage: %s [NODES (even, >= 4) [RUNS (>= 1) [CASE (1 .. %zu) "
                  "[ggx|beckmann]]]]",
                  argv[0], n_cases);
    bench_check(ll_set_thread_count(1), "ll_set_thread_count");
    printf("GGX against Beckmann at the same (n, m): CPU seconds of ll_layer_set_microfacet,\n"
           "one thread, best of %zu, n = %zu, m = GGX's chosen orders\n\n", runs, n);
    printf("| material | alpha | m | Beckmann s | GGX s | GGX / Beckmann |\n");
    printf("|---|---|---|---|---|---|\n");
    for (i = 0; i < n_cases; ++i) {
        const speed_case *c = &cases[i];
        double beckmann, ggx;
        if (only && i + 1 != only)
            continue;
        beckmann = beckmann_too ? build_seconds(c, LL_MICROFACET_BECKMANN, n, runs) : 0.0;
        ggx = ggx_too ? build_seconds(c, LL_MICROFACET_GGX, n, runs) : 0.0;
        printf("| %s | %g | %zu | %.3f | %.3f | %.2f |\n", c->material, c->alpha, c->orders,
               beckmann, ggx, beckmann > 0.0 ? ggx / beckmann : 0.0);
        fflush(stdout);
    }
    return 0;
}
