/*
 * Throughput of the adding step (ll_layer_add) against OpenBLAS dgemm on
 * the same machine, in the same process, on the same matrix size.
 *
 * usage: adding RUNS THREADS N...
 *     e.g. adding 3 1,2 200 500 1000
 *
 * Flop count. Per Fourier order the adding equations (Jakob et al. 2014,
 * section 5; method.md) work on h x h blocks, h = n / 2. For each of the
 * two directions the dense formulation with a shared factor is
 *     G = I - Ra Rb              gemm            2 h^3
 *     LU(G)                      getrf         2/3 h^3
 *     Z = Tb G^-1                two trsm        2 h^3
 *     P = Ra Tb'                 gemm            2 h^3
 *     [T | R'] = Z [Ta | P]      gemm (2h cols)  4 h^3
 * i.e. 32/3 h^3, and 64/3 h^3 = 8/3 n^3 for one order (the O(n^2) work of
 * expanding and compressing the blocks is not counted). This is also the
 * count of the arithmetic src/grammar/adding.c performs on full blocks; a cheaper
 * formulation would give a *lower* GFLOP/s for the same time, so nothing
 * is flattered by it.
 *
 * The layers: a Henyey-Greenstein slab (g = 0.5) of optical thickness 1e-6
 * (no doubling step), whose four blocks are full in every order used, so
 * that none of the zero-block shortcuts of adding applies (checked below).
 *
 * dgemm reference: C = A B with h x h operands (the size the adding works
 * on), 2 h^3 flops; also n x n for information. At more than one thread
 * two references are measured and the higher taken: one dgemm threaded by
 * OpenBLAS, and one single-threaded dgemm per thread running concurrently
 * (how adding itself uses the cores: one order per thread).
 */
#include "bench_util.h"

#include <cblas.h>
#include <lapacke.h>
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* At least this long per timed sample, so that small sizes are measured
 * over many calls. */
#define MIN_SAMPLE_SECONDS 0.25

/* Check that every block of every order holds a non-zero value. */
static void check_full(const ll_layer *layer, size_t n, size_t m)
{
    double *mat = bench_alloc(n * n, sizeof(double));
    size_t h = n / 2, l, r, c;
    for (l = 0; l < m; ++l) {
        int nonzero[2][2] = { { 0, 0 }, { 0, 0 } };
        bench_check(ll_layer_matrix(layer, l, mat), "ll_layer_matrix");
        for (r = 0; r < n; ++r)
            for (c = 0; c < n; ++c)
                if (mat[r * n + c] != 0.0)
                    nonzero[r >= h][c >= h] = 1;
        if (!nonzero[0][0] || !nonzero[0][1] || !nonzero[1][0] || !nonzero[1][1])
            bench_die("adding: order %zu of the n = %zu test layer has a zero block", l, n);
    }
    free(mat);
}

static ll_layer *make_slab(size_t n, size_t m)
{
    double *nodes = bench_alloc(n, sizeof(double)), *weights = bench_alloc(n, sizeof(double));
    ll_layer *layer = NULL;
    bench_check(ll_quad_gauss_legendre(n, nodes, weights, NULL), "ll_quad_gauss_legendre");
    bench_check(ll_layer_create(nodes, weights, n, m, &layer), "ll_layer_create");
    bench_check(ll_layer_set_henyey_greenstein(layer, 0.9, 0.5, NULL), "ll_layer_set_henyey_greenstein");
    bench_check(ll_layer_expand(layer, 1e-6, NULL), "ll_layer_expand");
    free(nodes);
    free(weights);
    return layer;
}

/* Seconds per ll_layer_add call, averaged over one sample of calls. */
static double time_add(const ll_layer *top, const ll_layer *bottom, ll_layer *out)
{
    size_t calls = 0;
    double start = bench_wall_seconds(), elapsed;
    do {
        bench_check(ll_layer_add(top, bottom, out, 0, NULL), "ll_layer_add");
        ++calls;
        elapsed = bench_wall_seconds() - start;
    } while (elapsed < MIN_SAMPLE_SECONDS);
    return elapsed / (double)calls;
}

static void fill_random(double *x, size_t count, bench_rng *rng)
{
    size_t i;
    for (i = 0; i < count; ++i)
        x[i] = bench_rng_uniform(rng) - 0.5;
}

typedef struct gemm_operands {
    double *a, *b, *c;
} gemm_operands;

static void gemm_alloc(gemm_operands *g, size_t size, bench_rng *rng)
{
    g->a = bench_alloc(size * size, sizeof(double));
    g->b = bench_alloc(size * size, sizeof(double));
    g->c = bench_alloc(size * size, sizeof(double));
    fill_random(g->a, size * size, rng);
    fill_random(g->b, size * size, rng);
    memset(g->c, 0, size * size * sizeof(double));
}

static void gemm_free(gemm_operands *g)
{
    free(g->a);
    free(g->b);
    free(g->c);
}

static void gemm_once(const gemm_operands *g, size_t size)
{
    blasint s = (blasint)size;
    cblas_dgemm(CblasColMajor, CblasNoTrans, CblasNoTrans, s, s, s, 1.0, g->a, s, g->b, s, 0.0,
                g->c, s);
}

/* GFLOP/s of one dgemm threaded by OpenBLAS over `threads` threads. */
static double gemm_threaded_gflops(size_t size, size_t threads, bench_rng *rng)
{
    gemm_operands g;
    size_t calls = 0;
    double start, elapsed;
    gemm_alloc(&g, size, rng);
    openblas_set_num_threads((int)threads);
    gemm_once(&g, size); /* warm up: thread pool, pages */
    start = bench_wall_seconds();
    do {
        gemm_once(&g, size);
        ++calls;
        elapsed = bench_wall_seconds() - start;
    } while (elapsed < MIN_SAMPLE_SECONDS);
    gemm_free(&g);
    return 2.0 * pow((double)size, 3.0) * (double)calls / elapsed * 1e-9;
}

/* GFLOP/s of `threads` single-threaded dgemm running side by side (each on
 * its own operands, the same number of calls each). */
static double gemm_concurrent_gflops(size_t size, size_t threads, bench_rng *rng)
{
    gemm_operands *g = bench_alloc(threads, sizeof *g);
    size_t t, calls = 1;
    double elapsed;
    for (t = 0; t < threads; ++t)
        gemm_alloc(&g[t], size, rng);
    /* Calibrate the call count on one thread, then time all threads. */
    for (;;) {
        double start = bench_wall_seconds();
        for (t = 0; t < calls; ++t)
            gemm_once(&g[0], size);
        elapsed = bench_wall_seconds() - start;
        if (elapsed >= 0.05 || calls > ((size_t)1 << 24))
            break;
        calls *= 2;
    }
    calls = (size_t)ceil((double)calls * MIN_SAMPLE_SECONDS / (elapsed > 0 ? elapsed : 1e-9));
    {
        double start = bench_wall_seconds();
        long long tt;
#pragma omp parallel for num_threads((int)threads) schedule(static, 1)
        for (tt = 0; tt < (long long)threads; ++tt) {
            size_t k;
            /* OpenBLAS's OpenMP build runs single-threaded inside a
             * parallel region. */
            for (k = 0; k < calls; ++k)
                gemm_once(&g[tt], size);
        }
        elapsed = bench_wall_seconds() - start;
    }
    for (t = 0; t < threads; ++t)
        gemm_free(&g[t]);
    free(g);
    return 2.0 * pow((double)size, 3.0) * (double)(calls * threads) / elapsed * 1e-9;
}

/* GFLOP/s of the non-gemm part of one half of an adding step on one
 * thread: LU of an h x h gain matrix (2/3 h^3) and the two right-sided
 * triangular solves of Z = Tb G^-1 (2 h^3), a quarter of the step's flops,
 * on a diagonally dominant random G as adding factors (I - R R). Beside
 * dgemm's rate this says how much of the gap to dgemm is LAPACK's. */
static double lu_solve_gflops(size_t h, bench_rng *rng)
{
    double *g0 = bench_alloc(h * h, sizeof(double)), *g = bench_alloc(h * h, sizeof(double));
    double *b0 = bench_alloc(h * h, sizeof(double)), *b = bench_alloc(h * h, sizeof(double));
    lapack_int *piv = bench_alloc(h, sizeof(lapack_int));
    size_t calls = 0, i;
    blasint s = (blasint)h;
    double start, elapsed;
    fill_random(g0, h * h, rng);
    fill_random(b0, h * h, rng);
    for (i = 0; i < h; ++i)
        g0[i * h + i] += (double)h;
    openblas_set_num_threads(1);
    start = bench_wall_seconds();
    do {
        memcpy(g, g0, h * h * sizeof(double));
        memcpy(b, b0, h * h * sizeof(double));
        if (LAPACKE_dgetrf_work(LAPACK_COL_MAJOR, s, s, g, s, piv) != 0)
            bench_die("adding: dgetrf failed on a diagonally dominant matrix");
        cblas_dtrsm(CblasColMajor, CblasRight, CblasUpper, CblasNoTrans, CblasNonUnit, s, s,
                    1.0, g, s, b, s);
        cblas_dtrsm(CblasColMajor, CblasRight, CblasLower, CblasNoTrans, CblasUnit, s, s, 1.0,
                    g, s, b, s);
        ++calls;
        elapsed = bench_wall_seconds() - start;
    } while (elapsed < MIN_SAMPLE_SECONDS);
    free(g0);
    free(g);
    free(b0);
    free(b);
    free(piv);
    return 8.0 / 3.0 * pow((double)h, 3.0) * (double)calls / elapsed * 1e-9;
}

static void bench_size(size_t n, size_t runs, const size_t *threads, size_t n_threads,
                       bench_rng *rng)
{
    size_t max_threads = 1, m, t, run;
    ll_layer *top, *bottom, *out = NULL;
    double flops;
    char id[96];

    for (t = 0; t < n_threads; ++t)
        if (threads[t] > max_threads)
            max_threads = threads[t];
    /* Enough orders that every thread gets several (dynamic schedule). */
    m = 4 * max_threads < 8 ? 8 : 4 * max_threads;
    flops = 8.0 / 3.0 * pow((double)n, 3.0) * (double)m;

    bench_check(ll_set_thread_count(max_threads), "ll_set_thread_count");
    top = make_slab(n, m);
    check_full(top, n, m);
    bench_check(ll_layer_clone(top, &bottom), "ll_layer_clone");
    bench_check(ll_layer_clone(top, &out), "ll_layer_clone");
    {
        char key[64];
        snprintf(key, sizeof key, "adding_layers.n%zu", n);
        snprintf(id, sizeof id, "m=%zu orders, %.6g flops per ll_layer_add", m, flops);
        bench_info(key, id);
    }

    for (t = 0; t < n_threads; ++t) {
        size_t th = threads[t];
        bench_check(ll_set_thread_count(th), "ll_set_thread_count");
        (void)time_add(top, bottom, out); /* warm up */
        for (run = 0; run < runs; ++run) {
            double add_gflops = flops / time_add(top, bottom, out) * 1e-9;
            double gemm_h = gemm_threaded_gflops(n / 2, th, rng);
            double gemm_n = gemm_threaded_gflops(n, th, rng);
            if (th > 1) {
                double conc_h = gemm_concurrent_gflops(n / 2, th, rng);
                double conc_n = gemm_concurrent_gflops(n, th, rng);
                snprintf(id, sizeof id, "add.n%zu.t%zu.dgemm_h_threaded", n, th);
                bench_metric(id, "GFLOP/s", gemm_h);
                snprintf(id, sizeof id, "add.n%zu.t%zu.dgemm_h_concurrent", n, th);
                bench_metric(id, "GFLOP/s", conc_h);
                gemm_h = fmax(gemm_h, conc_h);
                gemm_n = fmax(gemm_n, conc_n);
            }
            snprintf(id, sizeof id, "add.n%zu.t%zu.add", n, th);
            bench_metric(id, "GFLOP/s", add_gflops);
            snprintf(id, sizeof id, "add.n%zu.t%zu.dgemm_h", n, th);
            bench_metric(id, "GFLOP/s", gemm_h);
            snprintf(id, sizeof id, "add.n%zu.t%zu.dgemm_n", n, th);
            bench_metric(id, "GFLOP/s", gemm_n);
            snprintf(id, sizeof id, "add.n%zu.t%zu.ratio", n, th);
            bench_metric(id, "x", add_gflops / gemm_h);
            if (th == 1) {
                /* (The two copies per sample are not counted: a lower bound.) */
                double lu = lu_solve_gflops(n / 2, rng);
                snprintf(id, sizeof id, "add.n%zu.t1.lu_solve", n);
                bench_metric(id, "GFLOP/s", lu);
                snprintf(id, sizeof id, "add.n%zu.t1.lu_solve_ratio", n);
                bench_metric(id, "x", lu / gemm_h);
            }
        }
    }
    ll_layer_destroy(top);
    ll_layer_destroy(bottom);
    ll_layer_destroy(out);
}

/* "1,2,4" -> counts; exits on a malformed list. */
static size_t parse_list(const char *text, size_t *out, size_t capacity)
{
    size_t count = 0;
    char buf[256], *tok, *save = NULL;
    if (strlen(text) >= sizeof buf)
        bench_die("adding: thread list \"%s\" is too long", text);
    strcpy(buf, text);
    for (tok = strtok_r(buf, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
        if (count == capacity)
            bench_die("adding: more than %zu thread counts", capacity);
        out[count] = bench_parse_size(tok, "thread count");
        if (out[count] == 0)
            bench_die("adding: thread count 0 (give explicit counts)");
        ++count;
    }
    if (count == 0)
        bench_die("adding: empty thread list");
    return count;
}

int main(int argc, char **argv)
{
    size_t threads[16], n_threads, runs;
    bench_rng rng;
    int a;

    if (argc < 4)
        bench_die("usage: %s RUNS THREADS(1,2,..) N...", argv[0]);
    runs = bench_parse_size(argv[1], "RUNS");
    n_threads = parse_list(argv[2], threads, sizeof threads / sizeof threads[0]);
    bench_info("openblas_config", openblas_get_config());
    bench_info("openblas_core", openblas_get_corename());
    bench_rng_seed(&rng, 7);
    for (a = 3; a < argc; ++a) {
        size_t n = bench_parse_size(argv[a], "N");
        if (n < 4 || n % 2)
            bench_die("adding: n = %zu must be even and >= 4", n);
        bench_size(n, runs, threads, n_threads, &rng);
    }
    return 0;
}
