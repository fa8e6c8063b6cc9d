/* The speed and memory targets; see targets.h. */
#include "targets.h"
#include "plan.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static size_t add_target(bench_target *targets, size_t count, const char *what, double value,
                         double goal, int at_least, const char *basis)
{
    bench_target *t;
    if (count >= BENCH_MAX_TARGETS || !isfinite(value))
        return count;
    t = &targets[count];
    snprintf(t->what, sizeof t->what, "%s", what);
    snprintf(t->basis, sizeof t->basis, "%s", basis);
    t->value = value;
    t->goal = goal;
    t->at_least = at_least;
    t->met = at_least ? value >= goal : value <= goal;
    return count + 1;
}

static size_t recipe_targets(const bench_store *store, bench_target *targets, size_t count)
{
    size_t r;
    char id[160], what[128];
    for (r = 0; r < BENCH_RECIPE_COUNT; ++r) {
        const bench_recipe_ref *ref = &bench_recipes[r];
        bench_stats wall, rss, owall, orss;
        const char *basis = "original side by side (median)";
        snprintf(id, sizeof id, "recipe.%s.wall", ref->name);
        wall = bench_store_stats(store, id);
        snprintf(id, sizeof id, "recipe.%s.peak_rss", ref->name);
        rss = bench_store_stats(store, id);
        snprintf(id, sizeof id, "original.%s.wall", ref->name);
        owall = bench_store_stats(store, id);
        snprintf(id, sizeof id, "original.%s.peak_rss", ref->name);
        orss = bench_store_stats(store, id);
        if (owall.count == 0) {
            owall.median = ref->original_wall_s;
            orss.median = ref->original_rss_mib;
            basis = "the original's figures (another machine)";
        }
        snprintf(what, sizeof what, "%s: speedup over the original", ref->name);
        count = add_target(targets, count, what, owall.median / wall.median,
                           BENCH_TARGET_SPEEDUP, 1, basis);
        snprintf(what, sizeof what, "%s: peak memory / the original's", ref->name);
        count = add_target(targets, count, what, rss.median / orss.median,
                           BENCH_TARGET_MEMORY_RATIO, 0, basis);
    }
    return count;
}

static size_t adding_targets(const bench_store *store, bench_target *targets, size_t count)
{
    const char *cores_text = bench_store_info_get(store, "machine.cores");
    size_t cores = cores_text ? (size_t)strtoul(cores_text, NULL, 10) : 1, i, k;
    size_t threads[2];
    threads[0] = 1;
    threads[1] = cores;
    for (i = 0; i < BENCH_ADD_SIZE_COUNT; ++i) {
        if (bench_add_sizes[i] < BENCH_TARGET_ADD_MIN_N)
            continue;
        for (k = 0; k < (cores > 1 ? 2u : 1u); ++k) {
            char id[96], what[128];
            snprintf(id, sizeof id, "add.n%zu.t%zu.ratio", bench_add_sizes[i], threads[k]);
            snprintf(what, sizeof what, "ll_layer_add n = %zu, %zu thread(s): / dgemm",
                     bench_add_sizes[i], threads[k]);
            count = add_target(targets, count, what, bench_store_stats(store, id).median,
                               BENCH_TARGET_ADD_RATIO, 1, "dgemm in the same run");
        }
    }
    return count;
}

static size_t eval_targets(const bench_store *store, bench_target *targets, size_t count)
{
    size_t f;
    for (f = 0; f < BENCH_EVAL_FUNCTION_COUNT; ++f) {
        const bench_eval_ref *ref = &bench_eval_functions[f];
        char id[96], what[128], basis[96];
        snprintf(id, sizeof id, "eval.roughgold.%s", ref->function);
        snprintf(what, sizeof what, "ll_bsdf_%s: speedup over pbrt-v3 %s", ref->function,
                 ref->pbrt_name);
        /* Against the fast end of pbrt-v3's range: the strict reading. */
        snprintf(basis, sizeof basis, "pbrt-v3 %.0f ns (quoted, fast end)", ref->pbrt_low_ns);
        count = add_target(targets, count, what,
                           ref->pbrt_low_ns / bench_store_stats(store, id).median,
                           BENCH_TARGET_EVAL_SPEEDUP, 1, basis);
    }
    return count;
}

/* The dust on gold at its own resolution, when it was run. */
static size_t dust_targets(const bench_store *store, bench_target *targets, size_t count)
{
    /* llbuild's figures (the path users take) where measured. */
    bench_stats wall = bench_store_stats(store, "dust.dust-on-gold.llbuild.wall");
    bench_stats rss = bench_store_stats(store, "dust.dust-on-gold.llbuild.peak_rss");
    if (wall.count == 0) {
        wall = bench_store_stats(store, "dust.dust-on-gold.wall");
        rss = bench_store_stats(store, "dust.dust-on-gold.peak_rss");
    }
    if (wall.count == 0)
        return count;
    count = add_target(targets, count, "dust-on-gold (1098, 4194): wall s", wall.median,
                       BENCH_TARGET_DUST_WALL, 0, "this machine");
    count = add_target(targets, count, "dust-on-gold (1098, 4194): peak MiB", rss.median,
                       BENCH_TARGET_DUST_RSS, 0, "this machine");
    return count;
}

size_t bench_compute_targets(const bench_store *store, bench_target *targets)
{
    size_t count = 0;
    memset(targets, 0, BENCH_MAX_TARGETS * sizeof *targets);
    count = recipe_targets(store, targets, count);
    count = adding_targets(store, targets, count);
    count = eval_targets(store, targets, count);
    count = dust_targets(store, targets, count);
    return count;
}
