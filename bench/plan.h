/*
 * What the benchmark measures, shared by the driver (which runs it) and
 * the report (which lays it out), and the reference figures: the original
 * layerlab's and pbrt-v3's, measured on another 2-core machine.
 */
#ifndef BENCH_PLAN_H
#define BENCH_PLAN_H

#include <stddef.h>

#define BENCH_RECIPE_COUNT 3
#define BENCH_ADD_SIZE_COUNT 3
#define BENCH_STAGE_COUNT 6
#define BENCH_EVAL_FUNCTION_COUNT 3

typedef struct bench_recipe_ref {
    const char *name;
    double original_wall_s;   /* the original layerlab: whole process, median of 3 */
    double original_rss_mib;  /* its peak resident memory                                  */
} bench_recipe_ref;

static const bench_recipe_ref bench_recipes[BENCH_RECIPE_COUNT] = {
    { "coated-gold", 2.87, 186.0 },
    { "coated-gold-medium", 3.86, 185.0 },
    { "coated-diffuse", 28.3, 2.38 * 1024.0 },
};

static const size_t bench_add_sizes[BENCH_ADD_SIZE_COUNT] = { 200, 500, 1000 };

/* Stage names as the recipe program reports them (bench/recipe.c). */
static const char *const bench_stages[BENCH_STAGE_COUNT] = {
    "setup", "interfaces", "media", "expanding", "adding", "writing"
};

typedef struct bench_eval_ref {
    const char *function;     /* metric suffix                          */
    const char *pbrt_name;    /* pbrt-v3 FourierBSDF method             */
    double pbrt_low_ns, pbrt_high_ns; /* on roughgold_alpha_0.2 */
} bench_eval_ref;

static const bench_eval_ref bench_eval_functions[BENCH_EVAL_FUNCTION_COUNT] = {
    { "eval_dir", "f", 400.0, 600.0 },
    { "pdf_dir", "Pdf", 170.0, 270.0 },
    { "sample_dir", "Sample_f", 1200.0, 1800.0 },
};

/* The tolerances of the resolution whose cost is measured; the
 * finest is the others' reference. */
#define BENCH_TOLERANCE_COUNT 3
static const double bench_tolerances[BENCH_TOLERANCE_COUNT] = { 0.05, 0.01, 0.002 };
/* The seed's dust on gold (bench/recipe.c): at (400, 1600), the seed's
 * ratio of orders to nodes, in every run; at (400, 800), the resolution
 * the figures before the slab solver, the straight-through orders and the
 * reused workspaces were taken at, and at the seed's own (1098, 4194), one
 * run (minutes), only in the full run (bench/run.sh --full). 0: no figure
 * before (the (400, 800) one was measured on a busy 2-core machine, so
 * its wall time is only indicative; its CPU time holds). */
#define BENCH_DUST_COUNT 3
typedef struct bench_dust_ref {
    const char *name;
    int full_only;            /* only in the full run                        */
    int one_run;              /* one run, not --runs                         */
    double before_wall_s, before_cpu_s, before_rss_mib;
    const char *before_source;
} bench_dust_ref;

static const bench_dust_ref bench_dust[BENCH_DUST_COUNT] = {
    { "dust-on-gold-400x1600", 0, 0, 0.0, 0.0, 0.0, "" },
    { "dust-on-gold-400", 1, 0, 142.0, 20.7, 492.0, "be5d0ca, this recipe, busy machine" },
    { "dust-on-gold", 1, 1, 429.0, 732.0 + 78.0, 4.8 * 1024.0, "earlier figure" },
};
/* Per-order cost of the slab against doubling (bench/slab.c), these n. */
#define BENCH_SLAB_SIZE_COUNT 3
static const size_t bench_slab_sizes[BENCH_SLAB_SIZE_COUNT] = { 100, 400, 1098 };
#define BENCH_TARGET_DUST_WALL 60.0          /* s, dust-on-gold (1098, 4194)  */
#define BENCH_TARGET_DUST_RSS (2.0 * 1024.0) /* MiB                           */

/* The speed and memory targets. */
#define BENCH_TARGET_SPEEDUP 5.0       /* recipes: at least 5x faster than the original   */
#define BENCH_TARGET_MEMORY_RATIO 0.5  /* ... with at most half its peak memory           */
#define BENCH_TARGET_ADD_RATIO 0.5     /* ll_layer_add >= half of dgemm for n >= 500      */
#define BENCH_TARGET_ADD_MIN_N 500
#define BENCH_TARGET_EVAL_SPEEDUP 1.5  /* eval/pdf/sample >= 1.5x faster than pbrt-v3     */

#endif /* BENCH_PLAN_H */
