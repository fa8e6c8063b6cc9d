/*
 * The closed-form slab (src/grammar/slab.c) against doubling, per Fourier
 * order, on one thread: the figures behind the cost model of slab.c
 * (ll_slab_order_cost, ll_doubling_order_cost), which picks between them.
 *
 * usage: slab N...        e.g. slab 100 400 1098
 *
 * The layer: the seed's dust (Henyey-Greenstein g = 0.9, albedo 0.9) of
 * optical thickness 4, one Fourier order (order 0, full in every block), n
 * Gauss-Lobatto nodes. Each method is timed over whole ll_layer_expand
 * calls (phase matrices rebuilt outside the clock), at least
 * MIN_SAMPLE_SECONDS per sample. Reported per n:
 *     slab.N.doubling   seconds per order by doubling (k doublings)
 *     slab.N.slab       seconds per order by the closed form
 *     slab.N.speedup    doubling / slab
 *     slab.N.doubling_step_h3, slab.N.slab_h3
 *                       the same divided by k h^3 and h^3: the constants
 *                       of the cost model
 * Links the static library: the method choice is internal.
 */
#include "bench_util.h"

#include "grammar/grammar.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#define MIN_SAMPLE_SECONDS 0.5

static double time_method(const double *x, const double *w, size_t n, ll_expand_method method)
{
    double spent = 0.0;
    size_t calls = 0;
    while (spent < MIN_SAMPLE_SECONDS || calls == 0) {
        ll_layer *l = NULL;
        double t0;
        bench_check(ll_layer_create(x, w, n, 1, &l), "ll_layer_create");
        bench_check(ll_layer_set_henyey_greenstein(l, 0.9, 0.9, NULL), "ll_layer_set_henyey_greenstein");
        t0 = bench_wall_seconds();
        bench_check(ll_layer_expand_by(l, 4.0, method), "ll_layer_expand_by");
        spent += bench_wall_seconds() - t0;
        ++calls;
        ll_layer_destroy(l);
    }
    return spent / (double)calls;
}

int main(int argc, char **argv)
{
    int a;
    char id[96];
    if (argc < 2)
        bench_die("usage: %s N...", argv[0]);
    bench_check(ll_set_thread_count(1), "ll_set_thread_count");
    for (a = 1; a < argc; ++a) {
        size_t n = bench_parse_size(argv[a], "N"), h = n / 2, k, i;
        double *x = bench_alloc(n, sizeof(double)), *w = bench_alloc(n, sizeof(double));
        double min_mu = 1.0, tau0, doubling, slab, h3 = (double)h * (double)h * (double)h;
        bench_check(ll_quad_gauss_lobatto(n, x, w, NULL), "ll_quad_gauss_lobatto");
        for (i = 0; i < n; ++i)
            min_mu = fmin(min_mu, fabs(x[i]));
        ll_expand_schedule(4.0, min_mu, &tau0, &k);
        doubling = time_method(x, w, n, LL_EXPAND_DOUBLING);
        slab = time_method(x, w, n, LL_EXPAND_SLAB);
        snprintf(id, sizeof id, "slab.%zu.doubling", n);
        bench_metric(id, "s", doubling);
        snprintf(id, sizeof id, "slab.%zu.slab", n);
        bench_metric(id, "s", slab);
        snprintf(id, sizeof id, "slab.%zu.speedup", n);
        bench_metric(id, "x", doubling / slab);
        snprintf(id, sizeof id, "slab.%zu.doubling_step_h3", n);
        bench_metric(id, "ns", 1e9 * doubling / ((double)k * h3));
        snprintf(id, sizeof id, "slab.%zu.slab_h3", n);
        bench_metric(id, "ns", 1e9 * slab / h3);
        snprintf(id, sizeof id, "%zu", k);
        bench_info("doublings", id);
        free(x);
        free(w);
    }
    return 0;
}
