/* The table that `make bench` prints; see report.h. */
#include "plan.h"
#include "report.h"
#include "targets.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A figure with about three significant digits, without exponents. */
static void format_value(char *out, size_t size, double x)
{
    double a = fabs(x);
    if (!isfinite(x))
        snprintf(out, size, "-");
    else if (a >= 100.0)
        snprintf(out, size, "%.0f", x);
    else if (a >= 10.0)
        snprintf(out, size, "%.1f", x);
    else if (a >= 1.0)
        snprintf(out, size, "%.2f", x);
    else
        snprintf(out, size, "%.3f", x);
}

/* "median [min..max]" of a series, or "-" if it was not measured. */
static const char *format_stats(char *out, size_t size, bench_stats st)
{
    char med[32], lo[32], hi[32];
    if (st.count == 0) {
        snprintf(out, size, "-");
        return out;
    }
    format_value(med, sizeof med, st.median);
    format_value(lo, sizeof lo, st.min);
    format_value(hi, sizeof hi, st.max);
    snprintf(out, size, "%s [%s..%s]", med, lo, hi);
    return out;
}

/* Stats of the series whose id is formatted from fmt (printf-style). */
static bench_stats stats_of(const bench_store *s, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

static bench_stats stats_of(const bench_store *s, const char *fmt, ...)
{
    char id[192];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(id, sizeof id, fmt, ap);
    va_end(ap);
    return bench_store_stats(s, id);
}

static const char *info_or(const bench_store *s, const char *key, const char *fallback)
{
    const char *text = bench_store_info_get(s, key);
    return text ? text : fallback;
}

static void print_header(FILE *out, const bench_store *s)
{
    fprintf(out, "\nlayerlab benchmarks (layerlab %s, commit %s, %s)\n",
            info_or(s, "layerlab_version", "?"), info_or(s, "git_commit", "?"),
            info_or(s, "date", "?"));
    fprintf(out, "machine: %s cores, %s, %s memory, %s\n", info_or(s, "machine.cores", "?"),
            info_or(s, "machine.cpu", "?"), info_or(s, "machine.memory", "?"),
            info_or(s, "machine.kernel", "?"));
    fprintf(out, "OpenBLAS: %s\n", info_or(s, "openblas_config", "?"));
    fprintf(out, "load average (1/5/15 min): start %s, end %s\n", info_or(s, "load.start", "?"),
            info_or(s, "load.end", "?"));
    fprintf(out, "every figure: median [min..max] of %s runs\n", info_or(s, "runs", "?"));
    fprintf(out, "run: %s\n", info_or(s, "mode", "?"));
}

/* What a benchmark built (the material, its file), from the info key
 * PREFIX.NAME.SUFFIX (one line), labelled. */
static void print_material(FILE *out, const bench_store *s, const char *label,
                           const char *prefix, const char *name, const char *suffix)
{
    char key[200];
    const char *text;
    snprintf(key, sizeof key, "%s.%s.%s", prefix, name, suffix);
    text = bench_store_info_get(s, key);
    if (text)
        fprintf(out, "%-20s %s: %s\n", "", label, text);
}

static void print_recipes(FILE *out, const bench_store *s)
{
    size_t r, k;
    char a[128], b[128], c[128], d[128];
    fprintf(out, "\n1. Recipes of the original at its resolutions (whole process, all cores)\n");
    fprintf(out, "%-20s %-24s %-24s %-24s %-20s\n", "recipe", "wall s", "CPU s", "peak MiB",
            "output MB");
    for (r = 0; r < BENCH_RECIPE_COUNT; ++r) {
        const char *name = bench_recipes[r].name;
        bench_stats ow = stats_of(s, "original.%s.wall", name);
        bench_stats pre = stats_of(s, "original.%s.preamble.wall", name);
        fprintf(out, "%-20s %-24s %-24s %-24s %-20s\n", name,
                format_stats(a, sizeof a, stats_of(s, "recipe.%s.wall", name)),
                format_stats(b, sizeof b, stats_of(s, "recipe.%s.cpu", name)),
                format_stats(c, sizeof c, stats_of(s, "recipe.%s.peak_rss", name)),
                format_stats(d, sizeof d, stats_of(s, "recipe.%s.output", name)));
        print_material(out, s, "material", "recipe", name, "material");
        fprintf(out, "%-20s stages, wall s:", "");
        for (k = 0; k < BENCH_STAGE_COUNT; ++k) {
            char id[160];
            snprintf(id, sizeof id, "recipe.%s.stage.%s", name, bench_stages[k]);
            format_value(a, sizeof a, bench_store_stats(s, id).median);
            fprintf(out, " %s %s", bench_stages[k], a);
        }
        fputc('\n', out);
        /* llbuild --dry-run's estimate of the same stack (one value). */
        {
            char id[160];
            snprintf(id, sizeof id, "recipe.%s.estimate.wall", name);
            format_value(a, sizeof a, bench_store_stats(s, id).median);
            fprintf(out, "%-20s estimate: wall %s s", "", a);
            snprintf(id, sizeof id, "recipe.%s.estimate.cpu", name);
            format_value(a, sizeof a, bench_store_stats(s, id).median);
            snprintf(id, sizeof id, "recipe.%s.estimate.peak_rss", name);
            format_value(b, sizeof b, bench_store_stats(s, id).median);
            fprintf(out, ", CPU %s s, peak %s MiB (measured: the line above)\n", a, b);
        }
        if (ow.count) {
            bench_stats oc = stats_of(s, "original.%s.cpu", name);
            bench_stats ours_w = stats_of(s, "recipe.%s.wall", name);
            bench_stats ours_c = stats_of(s, "recipe.%s.cpu", name);
            fprintf(out, "%-20s original, side by side: wall %s", "",
                    format_stats(a, sizeof a, ow));
            fprintf(out, "  CPU %s", format_stats(b, sizeof b, oc));
            fprintf(out, "  peak MiB %s\n",
                    format_stats(c, sizeof c, stats_of(s, "original.%s.peak_rss", name)));
            format_value(a, sizeof a, ow.median / ours_w.median);
            format_value(b, sizeof b, oc.median / ours_c.median);
            fprintf(out, "%-20s   speedup: wall %sx, CPU %sx", "", a, b);
            if (pre.count) {
                format_value(a, sizeof a, (ow.median - pre.median) / ours_w.median);
                format_value(c, sizeof c, pre.median);
                fprintf(out, ", wall without its preamble (%s s: interpreter, imports, IOR) "
                             "%sx", c, a);
            }
            fputc('\n', out);
        } else {
            format_value(a, sizeof a, bench_recipes[r].original_wall_s);
            format_value(b, sizeof b, bench_recipes[r].original_rss_mib);
            fprintf(out, "%-20s original (its figures, another machine): wall %s s, "
                         "peak %s MiB\n", "", a, b);
        }
    }
}

/* The dust on gold, per stage, next to the figures before; and (full run)
 * the slab against doubling per order. */
static void print_dust(FILE *out, const bench_store *s)
{
    size_t r, k, i;
    char a[128], b[128], c[128];
    fprintf(out, "\n1b. Dust on gold (HG g 0.9, tau 4, albedo 0.9 over gold alpha 0.02, "
                 "gold's RGB index as in 1.; whole process, all cores)\n");
    fprintf(out, "%-20s %-24s %-24s %-24s\n", "recipe", "wall s", "CPU s", "peak MiB");
    for (r = 0; r < BENCH_DUST_COUNT; ++r) {
        const char *name = bench_dust[r].name;
        bench_stats w = stats_of(s, "dust.%s.wall", name);
        if (w.count == 0) {
            fprintf(out, "%-20s %s\n", name,
                    bench_dust[r].full_only ? "not run (make bench-full runs it)"
                                            : "not measured");
            continue;
        }
        fprintf(out, "%-20s %-24s %-24s %-24s\n", name, format_stats(a, sizeof a, w),
                format_stats(b, sizeof b, stats_of(s, "dust.%s.cpu", name)),
                format_stats(c, sizeof c, stats_of(s, "dust.%s.peak_rss", name)));
        print_material(out, s, "material", "dust", name, "material");
        fprintf(out, "%-20s stages, CPU s:", "");
        for (k = 0; k < BENCH_STAGE_COUNT; ++k) {
            format_value(a, sizeof a,
                         stats_of(s, "dust.%s.stage_cpu.%s", name, bench_stages[k]).median);
            fprintf(out, " %s %s", bench_stages[k], a);
        }
        fputc('\n', out);
        if (stats_of(s, "dust.%s.llbuild.wall", name).count) {
            fprintf(out, "%-20s llbuild, the same stack as a material: wall %s", "",
                    format_stats(a, sizeof a, stats_of(s, "dust.%s.llbuild.wall", name)));
            fprintf(out, "  CPU %s",
                    format_stats(b, sizeof b, stats_of(s, "dust.%s.llbuild.cpu", name)));
            fprintf(out, "  peak MiB %s\n",
                    format_stats(c, sizeof c, stats_of(s, "dust.%s.llbuild.peak_rss", name)));
            print_material(out, s, "llbuild's file", "dust", name, "llbuild.material_file");
            print_material(out, s, "llbuild's material", "dust", name, "llbuild.material");
        }
        if (bench_dust[r].before_wall_s > 0.0) {
            format_value(a, sizeof a, bench_dust[r].before_wall_s);
            format_value(b, sizeof b, bench_dust[r].before_cpu_s);
            format_value(c, sizeof c, bench_dust[r].before_rss_mib);
            fprintf(out, "%-20s before (%s): wall %s s, CPU %s s, peak %s MiB\n", "",
                    bench_dust[r].before_source, a, b, c);
        }
    }
    if (stats_of(s, "slab.%zu.slab", bench_slab_sizes[0]).count == 0)
        return;
    fprintf(out, "\n1c. One order (order 0, HG g 0.9, tau 4), 1 thread: doubling vs the "
                 "closed-form slab, s\n");
    fprintf(out, "%-6s %-24s %-24s %-24s\n", "n", "doubling", "slab", "speedup");
    for (i = 0; i < BENCH_SLAB_SIZE_COUNT; ++i) {
        size_t n = bench_slab_sizes[i];
        char d[128];
        fprintf(out, "%-6zu %-24s %-24s %-24s\n", n,
                format_stats(a, sizeof a, stats_of(s, "slab.%zu.doubling", n)),
                format_stats(b, sizeof b, stats_of(s, "slab.%zu.slab", n)),
                format_stats(d, sizeof d, stats_of(s, "slab.%zu.speedup", n)));
    }
}

static void print_adding(FILE *out, const bench_store *s)
{
    const char *cores_text = bench_store_info_get(s, "machine.cores");
    size_t cores = cores_text ? (size_t)strtoul(cores_text, NULL, 10) : 1, i, k;
    size_t threads[2];
    char a[128], b[128], c[128], d[128];
    threads[0] = 1;
    threads[1] = cores;
    fprintf(out, "\n2. Adding: ll_layer_add on full layers vs OpenBLAS dgemm (GFLOP/s; "
                 "adding counted as 8/3 n^3 per order, dgemm on the h = n/2 blocks)\n");
    fprintf(out, "%-6s %-8s %-24s %-24s %-24s %-24s\n", "n", "threads", "ll_layer_add",
            "dgemm h x h", "ratio", "dgemm n x n");
    for (i = 0; i < BENCH_ADD_SIZE_COUNT; ++i)
        for (k = 0; k < (cores > 1 ? 2u : 1u); ++k) {
            size_t n = bench_add_sizes[i], t = threads[k];
            char id[96];
            bench_stats st[4];
            const char *suffix[4] = { "add", "dgemm_h", "ratio", "dgemm_n" };
            int j;
            for (j = 0; j < 4; ++j) {
                snprintf(id, sizeof id, "add.n%zu.t%zu.%s", n, t, suffix[j]);
                st[j] = bench_store_stats(s, id);
            }
            fprintf(out, "%-6zu %-8zu %-24s %-24s %-24s %-24s\n", n, t,
                    format_stats(a, sizeof a, st[0]), format_stats(b, sizeof b, st[1]),
                    format_stats(c, sizeof c, st[2]), format_stats(d, sizeof d, st[3]));
        }
}

/* Earlier figures of the evaluation kernels, printed under each file's
 * row as "before (commit)", so that a run shows what the kernels gained:
 * the results of commit f61ccd6 (median of 3 on 2 cores) for roughgold and
 * coated-diffuse, and a figure taken before the kernels were rewritten for
 * coated-gold, which that run did not measure (no pdf figure: 0 prints as
 * "-"); then commit cfeba3b, measured side by side with 2b5271c in one run
 * (5 alternating rounds of 2 x 10^5 calls, median, on a busy 2-core
 * machine; docs/benchmarks.md, "Evaluation per call"). Order: eval_dir,
 * pdf_dir, sample_dir (bench_eval_functions). */
static const struct {
    const char *label, *source;
    double ns[3];
} previous_eval[] = {
    { "roughgold", "f61ccd6", { 521.2, 389.7, 1945.9 } },
    { "roughgold", "cfeba3b", { 678.0, 536.0, 2420.0 } },
    { "coated-gold", "old kernels", { 2300.0, 0.0, 6200.0 } },
    { "coated-gold", "cfeba3b", { 1454.0, 979.0, 4228.0 } },
    { "coated-diffuse", "f61ccd6", { 11839.3, 5218.5, 47432.9 } },
    { "coated-diffuse", "cfeba3b", { 8418.0, 5463.0, 25510.0 } },
};

static void print_eval(FILE *out, const bench_store *s)
{
    const char *labels[3] = { "roughgold", "coated-gold", "coated-diffuse" };
    size_t i, f, k;
    char a[128];
    fprintf(out, "\n3. Evaluation, ns per call (1 thread, 10^6 random directions, fixed seed)\n");
    fprintf(out, "%-20s", "file");
    for (f = 0; f < BENCH_EVAL_FUNCTION_COUNT; ++f)
        fprintf(out, " ll_bsdf_%-16s", bench_eval_functions[f].function);
    fputc('\n', out);
    for (i = 0; i < 3; ++i) {
        char before[48];
        fprintf(out, "%-20s", labels[i]);
        for (f = 0; f < BENCH_EVAL_FUNCTION_COUNT; ++f) {
            char id[96];
            snprintf(id, sizeof id, "eval.%s.%s", labels[i], bench_eval_functions[f].function);
            fprintf(out, " %-24s", format_stats(a, sizeof a, bench_store_stats(s, id)));
        }
        fputc('\n', out);
        for (k = 0; k < sizeof previous_eval / sizeof previous_eval[0]; ++k) {
            if (strcmp(previous_eval[k].label, labels[i]) != 0)
                continue;
            snprintf(before, sizeof before, "  before (%s)", previous_eval[k].source);
            fprintf(out, "%-20s", before);
            for (f = 0; f < BENCH_EVAL_FUNCTION_COUNT && f < 3; ++f) {
                if (previous_eval[k].ns[f] > 0.0)
                    fprintf(out, " %-24.0f", previous_eval[k].ns[f]);
                else
                    fprintf(out, " %-24s", "-");
            }
            fputc('\n', out);
        }
    }
    fprintf(out, "%-20s", "pbrt-v3 (quoted)");
    for (f = 0; f < BENCH_EVAL_FUNCTION_COUNT; ++f) {
        char range[48];
        snprintf(range, sizeof range, "%.0f-%.0f (%s)", bench_eval_functions[f].pbrt_low_ns,
                 bench_eval_functions[f].pbrt_high_ns, bench_eval_functions[f].pbrt_name);
        fprintf(out, " %-24s", range);
    }
    fputc('\n', out);
}

static void print_scaling(FILE *out, const bench_store *s)
{
    size_t t;
    double one = stats_of(s, "scaling.coated-gold.t%zu.wall", (size_t)1).median;
    char a[128], b[128], c[32];
    fprintf(out, "\n4. Scaling: coated-gold (library, OpenMP and OpenBLAS limited to the "
                 "thread count)\n");
    if (stats_of(s, "scaling.coated-gold.t%zu.wall", (size_t)1).count == 0) {
        fprintf(out, "not run (make bench-full runs it)\n");
        return;
    }
    fprintf(out, "%-8s %-24s %-24s %-10s\n", "threads", "wall s", "CPU s", "speedup");
    for (t = 1; t <= 4096; ++t) {
        bench_stats w = stats_of(s, "scaling.coated-gold.t%zu.wall", t);
        if (w.count == 0)
            continue;
        format_value(c, sizeof c, one / w.median);
        fprintf(out, "%-8zu %-24s %-24s %-10s\n", t, format_stats(a, sizeof a, w),
                format_stats(b, sizeof b, stats_of(s, "scaling.coated-gold.t%zu.cpu", t)),
                c);
    }
}

static void print_targets(FILE *out, const bench_store *s)
{
    bench_target targets[BENCH_MAX_TARGETS];
    size_t count = bench_compute_targets(s, targets), i;
    char v[32], g[32];
    fprintf(out, "\nTargets\n");
    for (i = 0; i < count; ++i) {
        format_value(v, sizeof v, targets[i].value);
        format_value(g, sizeof g, targets[i].goal);
        fprintf(out, "  [%s] %-52s %8s (goal %s %s; vs %s)\n", targets[i].met ? " met " : "NOT met",
                targets[i].what, v, targets[i].at_least ? ">=" : "<=", g, targets[i].basis);
    }
    for (i = 0; i < s->error_count; ++i)
        fprintf(out, "  error: %s\n", s->errors[i]);
}

static void print_tolerance(FILE *out, const bench_store *s)
{
    size_t r, t;
    char a[64], b[64], c[64], d[64], e[64];
    fprintf(out, "\n6. The tolerance's cost: the recipes at the resolution it chooses "
                 "(one run each; error: worst relative difference from the %g build where "
                 "it is above 1%% of its peak, reflection at mu 0.1 .. 1)\n",
            bench_tolerances[BENCH_TOLERANCE_COUNT - 1]);
    for (r = 0, t = 0; r < BENCH_RECIPE_COUNT; ++r) {
        char key[160];
        snprintf(key, sizeof key, "tolerance.%s.%g.material", bench_recipes[r].name,
                 bench_tolerances[0]);
        if (bench_store_info_get(s, key)) {
            fprintf(out, "%-20s material: %s\n", bench_recipes[r].name,
                    bench_store_info_get(s, key));
            ++t;
        }
    }
    if (t == 0) {
        fprintf(out, "not run (make bench-full runs it)\n");
        return;
    }
    fprintf(out, "%-20s %-9s %-14s %-9s %-9s %-9s %-9s %-9s\n", "recipe", "tolerance",
            "nodes x orders", "choose s", "wall s", "peak MiB", "file MB", "error");
    for (r = 0; r < BENCH_RECIPE_COUNT; ++r)
        for (t = 0; t < BENCH_TOLERANCE_COUNT; ++t) {
            const char *name = bench_recipes[r].name;
            char key[160], res[64];
            double tol = bench_tolerances[t];
            bench_stats wall = stats_of(s, "tolerance.%s.%g.wall", name, tol);
            if (wall.count == 0)
                continue;
            snprintf(key, sizeof key, "tolerance.%s.%g.n_nodes", name, tol);
            snprintf(res, sizeof res, "%s x ", info_or(s, key, "?"));
            snprintf(key, sizeof key, "tolerance.%s.%g.n_orders", name, tol);
            snprintf(res + strlen(res), sizeof res - strlen(res), "%s", info_or(s, key, "?"));
            format_value(a, sizeof a, stats_of(s, "tolerance.%s.%g.choose", name, tol).median);
            format_value(b, sizeof b, wall.median);
            format_value(c, sizeof c, stats_of(s, "tolerance.%s.%g.peak_rss", name, tol).median);
            format_value(d, sizeof d, stats_of(s, "tolerance.%s.%g.file", name, tol).median);
            format_value(e, sizeof e, stats_of(s, "tolerance.%s.%g.error", name, tol).median);
            fprintf(out, "%-20s %-9g %-14s %-9s %-9s %-9s %-9s %-9s\n", name, tol, res, a, b,
                    c, d, e);
        }
}

void bench_report_table(FILE *out, const bench_store *store)
{
    print_header(out, store);
    print_recipes(out, store);
    print_dust(out, store);
    print_adding(out, store);
    print_eval(out, store);
    print_scaling(out, store);
    print_tolerance(out, store);
    print_targets(out, store);
}
