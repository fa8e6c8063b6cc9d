/*
 * The textured build against separate builds: an
 * 8 x 8 coated-gold grid, coat alpha x gold alpha from 0.05 to 0.4, at the
 * coated-gold recipe's resolution (196 nodes, 267 orders, RGB), built as one
 * textured file by one `llbuild` run, and the same 64 materials built by 64
 * separate `llbuild` runs: wall, CPU and peak resident memory of each
 * process (wait4), the file sizes; then ns per ll_bsdf_eval_dir and
 * ll_bsdf_sample_dir on the grid file at random parameter values (the
 * weights from ll_bsdf_basis_coefficients, computed per call as a renderer
 * does per shading point) against the untextured files of the sharpest
 * and the smoothest corner of the grid.
 *
 * usage: textured LLBUILD WORKDIR [SEPARATE_RUNS]
 *   SEPARATE_RUNS: how many of the 64 separate builds to run (default 64);
 *   fewer are spread over the grid (every coat and gold value as evenly as
 *   possible) and the total is extrapolated by 64 / runs, which the report
 *   says.
 * Run by bench/run.sh --full (`make bench-full`); prints a table and `metric` lines.
 */
#include "bench_util.h"
#include "child.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define SIDE 8
#define NODES 196
#define ORDERS 267
#define CALLS 200000

static double grid_alpha(size_t i) { return 0.05 + 0.35 * (double)i / (SIDE - 1); }

static void write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    if (!f || fputs(text, f) < 0 || fclose(f) != 0)
        bench_die("textured: cannot write %s", path);
}

static double file_mib(const char *path)
{
    struct stat st;
    if (stat(path, &st) != 0)
        bench_die("textured: %s is missing", path);
    return (double)st.st_size / 1048576.0;
}

static void run_llbuild(char *llbuild, char *in, char *out, bench_child_result *r)
{
    char quiet[] = "--quiet", dash_o[] = "-o";
    char *argv[6];
    argv[0] = llbuild;
    argv[1] = quiet;
    argv[2] = in;
    argv[3] = dash_o;
    argv[4] = out;
    argv[5] = NULL;
    if (!bench_run_child(argv, NULL, NULL, NULL, r))
        bench_die("textured: llbuild %s failed (status %d)", in, r->status);
}

/* ns per call of eval_dir and sample_dir at random directions and, for a
 * textured file, random parameter values (weights computed per call). */
static void time_calls(const ll_bsdf *b, int textured, double *eval_ns, double *sample_ns)
{
    bench_rng rng;
    float coeffs[SIDE * SIDE];
    double sum = 0.0, t0;
    long k;
    int pass;
    for (pass = 0; pass < 2; ++pass) {
        bench_rng_seed(&rng, 5);
        t0 = bench_wall_seconds();
        for (k = 0; k < CALLS; ++k) {
            double params[2], wo[3], wi[3], f[3], pdf, u[2], mu = bench_rng_uniform(&rng);
            params[0] = 0.05 + 0.35 * bench_rng_uniform(&rng);
            params[1] = 0.05 + 0.35 * bench_rng_uniform(&rng);
            wo[0] = sqrt(1.0 - mu * mu);
            wo[1] = 0.0;
            wo[2] = mu;
            u[0] = bench_rng_uniform(&rng);
            u[1] = bench_rng_uniform(&rng);
            if (textured)
                bench_check(ll_bsdf_basis_coefficients(b, params, coeffs), "coefficients");
            if (pass == 0) {
                double phi = 2.0 * 3.14159265358979 * u[0], m2 = u[1];
                wi[0] = sqrt(1.0 - m2 * m2) * cos(phi);
                wi[1] = sqrt(1.0 - m2 * m2) * sin(phi);
                wi[2] = m2;
                bench_check(ll_bsdf_eval_dir(b, wo, wi, LL_TRANSPORT_RADIANCE,
                                             textured ? coeffs : NULL, f),
                            "eval_dir");
            } else {
                bench_check(ll_bsdf_sample_dir(b, wo, u, LL_TRANSPORT_RADIANCE,
                                               textured ? coeffs : NULL, wi, &pdf, f),
                            "sample_dir");
            }
            sum += f[0];
        }
        if (pass == 0)
            *eval_ns = (bench_wall_seconds() - t0) / CALLS * 1e9;
        else
            *sample_ns = (bench_wall_seconds() - t0) / CALLS * 1e9;
    }
    if (sum < 0.0)
        printf("(never)\n");
}

int main(int argc, char **argv)
{
    char path[1024], out[1024], text[512], info[256];
    char *llbuild;
    const char *work;
    size_t runs = SIDE * SIDE, k, done = 0;
    bench_child_result grid, one;
    double sep_wall = 0.0, sep_cpu = 0.0, sep_rss = 0.0, sep_mib = 0.0, grid_mib, scale;
    double ev_grid = 0.0, sa_grid = 0.0, ev_one = 0.0, sa_one = 0.0, ev_smooth = 0.0,
           sa_smooth = 0.0;
    ll_bsdf *b;
    ll_open_options open_opts = LL_OPEN_OPTIONS_INIT;

    if (argc < 3 || argc > 4)
        bench_die("usage: textured LLBUILD WORKDIR [SEPARATE_RUNS]");
    llbuild = argv[1];
    work = argv[2];
    if (argc == 4)
        runs = bench_parse_size(argv[3], "SEPARATE_RUNS");
    if (runs < 1 || runs > SIDE * SIDE)
        bench_die("textured: SEPARATE_RUNS must be 1 to %d", SIDE * SIDE);

    snprintf(path, sizeof path, "%s/grid.layers", work);
    snprintf(text, sizeof text,
             "set nodes=%d orders=%d\n"
             "dielectric name=coat eta=1.5 alpha=[0.05..0.4:%d]\n"
             "conductor name=gold eta=Au alpha=[0.05..0.4:%d]\n",
             NODES, ORDERS, SIDE, SIDE);
    write_text(path, text);
    snprintf(out, sizeof out, "%s/grid.bsdf", work);
    run_llbuild(llbuild, path, out, &grid);
    grid_mib = file_mib(out);

    /* The separate builds: run k builds coat k % 8 and gold (k + 3 (k / 8)) % 8,
     * which over 64 runs is every pair once, and over any 8 consecutive runs
     * every coat and every gold value once (a subset is spread evenly). */
    for (k = 0; k < runs; ++k) {
        size_t coat = k % SIDE, gold = (k + 3 * (k / SIDE)) % SIDE;
        bench_child_result r;
        snprintf(path, sizeof path, "%s/one.layers", work);
        snprintf(text, sizeof text,
                 "set nodes=%d orders=%d\ndielectric eta=1.5 alpha=%.17g\n"
                 "conductor eta=Au alpha=%.17g\n",
                 NODES, ORDERS, grid_alpha(coat), grid_alpha(gold));
        write_text(path, text);
        snprintf(out, sizeof out, "%s/one.bsdf", work);
        run_llbuild(llbuild, path, out, &r);
        sep_wall += r.wall;
        sep_cpu += r.cpu;
        sep_mib += file_mib(out);
        if (r.peak_rss_mib > sep_rss)
            sep_rss = r.peak_rss_mib;
        if (done++ == 0)
            one = r;
    }
    scale = (double)(SIDE * SIDE) / (double)runs;

    printf("\ntextured 8 x 8 coated-gold grid (coat alpha x gold alpha 0.05..0.4, %d nodes x "
           "%d orders, RGB)\n",
           NODES, ORDERS);
    printf("  %-34s %9s %9s %10s %10s\n", "", "wall s", "CPU s", "peak MiB", "file MiB");
    printf("  %-34s %9.2f %9.2f %10.1f %10.1f\n", "one llbuild, textured file", grid.wall,
           grid.cpu, grid.peak_rss_mib, grid_mib);
    snprintf(info, sizeof info, "64 llbuild runs%s", runs == SIDE * SIDE ? "" : " (extrapolated)");
    printf("  %-34s %9.2f %9.2f %10.1f %10.1f\n", info, sep_wall * scale, sep_cpu * scale,
           sep_rss, sep_mib * scale);
    printf("  %-34s %9.2f %9.2f %10.1f\n", "the first of them", one.wall, one.cpu,
           one.peak_rss_mib);
    if (runs != SIDE * SIDE)
        printf("  (%zu of the 64 separate builds were run, spread over the grid; their sums "
               "are scaled by %.2f)\n",
               runs, scale);
    printf("  grid / 64 runs: wall %.2f (target <= 0.5); peak RSS grid / one build %.2f "
           "(target <= 2; the largest of the separate builds)\n",
           grid.wall / (sep_wall * scale), grid.peak_rss_mib / sep_rss);
    bench_metric("textured.grid.wall", "s", grid.wall);
    bench_metric("textured.grid.cpu", "s", grid.cpu);
    bench_metric("textured.grid.peak_rss", "MiB", grid.peak_rss_mib);
    bench_metric("textured.grid.file", "MiB", grid_mib);
    bench_metric("textured.separate.wall", "s", sep_wall * scale);
    bench_metric("textured.separate.cpu", "s", sep_cpu * scale);
    bench_metric("textured.separate.peak_rss", "MiB", sep_rss);
    bench_metric("textured.separate.file", "MiB", sep_mib * scale);
    bench_metric("textured.one.peak_rss", "MiB", one.peak_rss_mib);

    /* Evaluation: the grid file (beyond the reader's default 512 MiB limit
     * at this resolution, so opened with the limit lifted) against the last
     * separate file. */
    open_opts.max_bytes = SIZE_MAX;
    snprintf(out, sizeof out, "%s/grid.bsdf", work);
    bench_check(ll_bsdf_open(out, &open_opts, &b), "open grid");
    time_calls(b, 1, &ev_grid, &sa_grid);
    ll_bsdf_release(b);
    /* Untextured files of the sharpest and the smoothest corner: every
     * series of the grid file is as long as the longest over its bases
     * (the sharpest's), and 4 bases are weighted at an interior point. */
    for (k = 0; k < 2; ++k) {
        bench_child_result r;
        double a = k == 0 ? grid_alpha(0) : grid_alpha(SIDE - 1);
        snprintf(path, sizeof path, "%s/corner.layers", work);
        snprintf(text, sizeof text,
                 "set nodes=%d orders=%d\ndielectric eta=1.5 alpha=%.17g\n"
                 "conductor eta=Au alpha=%.17g\n",
                 NODES, ORDERS, a, a);
        write_text(path, text);
        snprintf(out, sizeof out, "%s/corner.bsdf", work);
        run_llbuild(llbuild, path, out, &r);
        bench_check(ll_bsdf_open(out, NULL, &b), "open corner");
        time_calls(b, 0, k == 0 ? &ev_one : &ev_smooth, k == 0 ? &sa_one : &sa_smooth);
        ll_bsdf_release(b);
    }
    printf("  ns per call (random directions)    eval_dir  sample_dir\n");
    printf("  %-34s %9.0f %10.0f\n", "grid file, random parameters", ev_grid, sa_grid);
    printf("  %-34s %9.0f %10.0f\n", "untextured, alpha 0.05 / 0.05", ev_one, sa_one);
    printf("  %-34s %9.0f %10.0f\n", "untextured, alpha 0.4 / 0.4", ev_smooth, sa_smooth);

    bench_metric("textured.grid.eval_dir", "ns", ev_grid);
    bench_metric("textured.grid.sample_dir", "ns", sa_grid);
    bench_metric("textured.sharp.eval_dir", "ns", ev_one);
    bench_metric("textured.sharp.sample_dir", "ns", sa_one);
    bench_metric("textured.smooth.eval_dir", "ns", ev_smooth);
    bench_metric("textured.smooth.sample_dir", "ns", sa_smooth);
    return 0;
}
