/*
 * The benchmark driver (`make bench` -> bench/run.sh -> this program): runs
 * every measuring program in its own process, the requested number of
 * times, collects the samples, prints the table and writes the JSON file.
 *
 * usage: driver --bin DIR --work DIR --testdata DIR --json PATH
 *               [--runs N] [--full 0|1] [--original DIR] [--llbuild PATH]
 *               [--commit TEXT] [--compiler TEXT]
 *
 *   --full 0    (`make bench`) the headline figures: the three recipes, the
 *               dust on gold at (400, 1600) (recipe and llbuild), adding
 *               against dgemm, evaluation and sampling per call
 *   --full 1    (`make bench-full`) also the dust at (400, 800) and at its
 *               own (1098, 4194), the slab against doubling, coated gold at
 *               1, 2, ... threads, batched evaluation and the tolerance's
 *               cost
 *   --bin       where run.sh put the programs recipe, adding, eval and tables
 *   --work      scratch directory for the recipes' .bsdf files
 *   --testdata  the folder of the golden file roughgold_alpha_0.2.bsdf (tests/data)
 *   --original  optional: a directory with one executable per recipe name
 *               (coated-gold, coated-gold-medium, coated-diffuse) that builds
 *               the same material with another implementation, e.g. a
 *               wrapper running the original layerlab's recipe; each is
 *               timed like ours, side by side, and the ratios use it.
 */
#include "bench_util.h"
#include "child.h"
#include "metrics.h"
#include "plan.h"
#include "report.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/utsname.h>
#include <time.h>
#include <unistd.h>

typedef struct config {
    const char *bin_dir, *work_dir, *testdata_dir, *json_path, *original_dir;
    size_t runs, cores;
    int full;            /* the full run (--full 1)                        */
    const char *llbuild; /* tools/llbuild, for the dust as a material      */
    size_t threads[8];   /* scaling: 1, 2, 4, ... and the core count */
    size_t thread_count;
} config;

static void path_join(char *out, size_t size, const char *dir, const char *name)
{
    if ((size_t)snprintf(out, size, "%s/%s", dir, name) >= size)
        bench_die("driver: path %s/%s is too long", dir, name);
}

static void record_load(bench_store *store, const char *when)
{
    double load[3] = { 0, 0, 0 };
    char key[64], text[96];
    if (getloadavg(load, 3) != 3)
        return;
    snprintf(key, sizeof key, "load.%s", when);
    snprintf(text, sizeof text, "%.2f %.2f %.2f", load[0], load[1], load[2]);
    bench_store_info(store, key, text);
}

/* The first "name : value" line of a /proc file whose name matches. */
static void record_proc_field(bench_store *store, const char *path, const char *field,
                              const char *key)
{
    char line[512];
    FILE *f = fopen(path, "r");
    if (!f)
        return;
    while (fgets(line, sizeof line, f)) {
        char *colon = strchr(line, ':');
        if (strncmp(line, field, strlen(field)) == 0 && colon) {
            char *value = colon + 1, *nl = strchr(value, '\n');
            while (*value == ' ' || *value == '\t')
                ++value;
            if (nl)
                *nl = '\0';
            bench_store_info(store, key, value);
            break;
        }
    }
    fclose(f);
}

static void record_machine(const config *cfg, bench_store *store)
{
    struct utsname u;
    char text[256];
    time_t now = time(NULL);
    snprintf(text, sizeof text, "%zu", cfg->cores);
    bench_store_info(store, "machine.cores", text);
    record_proc_field(store, "/proc/cpuinfo", "model name", "machine.cpu");
    record_proc_field(store, "/proc/meminfo", "MemTotal", "machine.memory");
    if (uname(&u) == 0) {
        snprintf(text, sizeof text, "%s %s %s", u.sysname, u.release, u.machine);
        bench_store_info(store, "machine.kernel", text);
    }
    strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", gmtime(&now));
    bench_store_info(store, "date", text);
    snprintf(text, sizeof text, "%zu", cfg->runs);
    bench_store_info(store, "runs", text);
    bench_store_info(store, "layerlab_version", ll_version_string());
}

static void child_failed(bench_store *store, const char *what, const bench_child_result *r)
{
    char message[1200];
    snprintf(message, sizeof message, "%s failed (wait status %d); see its messages above",
             what, r->status);
    fprintf(stderr, "bench: %s\n", message);
    bench_store_error(store, message);
}

/* Whether `file`, what section `section` measures as `label`, is there to
 * read; when not, that is recorded as the section's error (the golden
 * file missing means tests/data is, a recipe's output that its build
 * failed). */
static int input_present(bench_store *store, const char *section, const char *label,
                         const char *file, int golden)
{
    char what[64];
    if (access(file, R_OK) == 0)
        return 1;
    snprintf(what, sizeof what, "%s %s: no file %s", section, label,
             golden ? "(tests/data missing)" : "(the recipe failed)");
    fprintf(stderr, "bench: %s\n", what);
    bench_store_error(store, what);
    return 0;
}

/* Run a measuring program that names its own metrics; a failure is
 * recorded as "SECTION LABEL failed". */
static void run_labelled(bench_store *store, char **argv, const char *section, const char *label)
{
    bench_child_result res;
    char what[64];
    snprintf(what, sizeof what, "%s %s", section, label);
    if (!bench_run_child(argv, NULL, "", store, &res))
        child_failed(store, what, &res);
}

/* The material file of a benchmark, as one info line (its lines joined
 * by "; ") under PREFIXmaterial, and its path under PREFIXmaterial_file. */
static void record_material(bench_store *store, const char *prefix, const char *path)
{
    char key[256], text[1200], line[512];
    size_t len = 0;
    FILE *f = fopen(path, "r");
    snprintf(key, sizeof key, "%smaterial_file", prefix);
    bench_store_info(store, key, path);
    if (!f)
        return;
    text[0] = '\0';
    while (fgets(line, sizeof line, f) && len + 3 < sizeof text) {
        line[strcspn(line, "\n")] = '\0';
        len += (size_t)snprintf(text + len, sizeof text - len, "%s%s", len ? "; " : "", line);
    }
    fclose(f);
    snprintf(key, sizeof key, "%smaterial", prefix);
    bench_store_info(store, key, text);
}

/* A child's wall and CPU seconds (and, with memory, its peak resident
 * size) under PREFIXwall, PREFIXcpu, PREFIXpeak_rss. */
static void store_costs(bench_store *store, const char *prefix, const bench_child_result *res,
                        int memory)
{
    char id[256];
    snprintf(id, sizeof id, "%swall", prefix);
    bench_store_add(store, id, "s", res->wall);
    snprintf(id, sizeof id, "%scpu", prefix);
    bench_store_add(store, id, "s", res->cpu);
    if (memory) {
        snprintf(id, sizeof id, "%speak_rss", prefix);
        bench_store_add(store, id, "MiB", res->peak_rss_mib);
    }
}

/* One run of bench/recipe.c building recipe `name` into out_path
 * (WORK/NAME.bsdf), saying "bench: DOINGNAME, run R of RUNS"; its figures
 * and costs go under SECTION.NAME. 0, recorded as an error, if it failed. */
static int run_recipe(const config *cfg, bench_store *store, char *bin, const char *section,
                      const char *name, const char *doing, size_t run, size_t runs,
                      char *out_path, size_t out_size)
{
    char out_name[128], prefix[160];
    char *argv[5];
    bench_child_result res;
    snprintf(out_name, sizeof out_name, "%s.bsdf", name);
    path_join(out_path, out_size, cfg->work_dir, out_name);
    argv[0] = bin;
    argv[1] = (char *)name;
    argv[2] = out_path;
    argv[3] = "0";
    argv[4] = NULL;
    fprintf(stderr, "bench: %s%s, run %zu of %zu\n", doing, name, run + 1, runs);
    snprintf(prefix, sizeof prefix, "%s.%s.", section, name);
    if (!bench_run_child(argv, NULL, prefix, store, &res)) {
        child_failed(store, name, &res);
        return 0;
    }
    store_costs(store, prefix, &res, 1);
    return 1;
}

/* 1. The three recipes at all threads, interleaved run by run so that a
 * burst of load elsewhere spreads over all of them. */
static void run_recipes(const config *cfg, bench_store *store)
{
    char recipe_bin[1024], out_path[1024], id[160];
    size_t run, r;
    int failed[BENCH_RECIPE_COUNT] = { 0 };

    path_join(recipe_bin, sizeof recipe_bin, cfg->bin_dir, "recipe");
    record_load(store, "recipes");
    for (run = 0; run < cfg->runs; ++run)
        for (r = 0; r < BENCH_RECIPE_COUNT; ++r) {
            const char *name = bench_recipes[r].name;
            struct stat st;
            if (failed[r])
                continue;
            if (!run_recipe(cfg, store, recipe_bin, "recipe", name, "recipe ", run, cfg->runs,
                            out_path, sizeof out_path)) {
                failed[r] = 1;
                continue;
            }
            if (stat(out_path, &st) == 0) {
                snprintf(id, sizeof id, "recipe.%s.output", name);
                bench_store_add(store, id, "MB", (double)st.st_size * 1e-6);
            }
        }
}

/* 1b. The dust on gold, stage by stage, and (full run) the per-order cost
 * of the slab against doubling. The seed's resolution takes minutes: one
 * run, and only in the full run. */
static void run_dust(const config *cfg, bench_store *store)
{
    char recipe_bin[1024], slab_bin[1024], out_path[1024], out_name[128];
    char id[160], sizes[BENCH_SLAB_SIZE_COUNT][16];
    size_t run, r, i;
    char *argv[BENCH_SLAB_SIZE_COUNT + 6];
    bench_child_result res;

    path_join(recipe_bin, sizeof recipe_bin, cfg->bin_dir, "recipe");
    path_join(slab_bin, sizeof slab_bin, cfg->bin_dir, "slab");
    for (r = 0; r < BENCH_DUST_COUNT; ++r) {
        const char *name = bench_dust[r].name;
        size_t runs = bench_dust[r].one_run ? 1 : cfg->runs;
        if (bench_dust[r].full_only && !cfg->full)
            continue;
        for (run = 0; run < runs; ++run)
            if (!run_recipe(cfg, store, recipe_bin, "dust", name, "", run, runs, out_path,
                            sizeof out_path))
                break;
        /* The same stack as a material (WORK/NAME.layers, from run.sh). */
        if (cfg->llbuild) {
            char layers[1024];
            snprintf(out_name, sizeof out_name, "%s.layers", name);
            path_join(layers, sizeof layers, cfg->work_dir, out_name);
            snprintf(id, sizeof id, "dust.%s.llbuild.", name);
            record_material(store, id, layers);
        }
        for (run = 0; cfg->llbuild && run < runs; ++run) {
            char layers[1024];
            snprintf(out_name, sizeof out_name, "%s.layers", name);
            path_join(layers, sizeof layers, cfg->work_dir, out_name);
            snprintf(out_name, sizeof out_name, "%s.llbuild.bsdf", name);
            path_join(out_path, sizeof out_path, cfg->work_dir, out_name);
            argv[0] = (char *)cfg->llbuild;
            argv[1] = "--quiet";
            argv[2] = layers;
            argv[3] = "-o";
            argv[4] = out_path;
            argv[5] = NULL;
            fprintf(stderr, "bench: llbuild %s, run %zu of %zu\n", name, run + 1, runs);
            if (!bench_run_child(argv, NULL, NULL, store, &res)) {
                child_failed(store, layers, &res);
                break;
            }
            snprintf(id, sizeof id, "dust.%s.llbuild.", name);
            store_costs(store, id, &res, 1);
        }
    }
    if (!cfg->full)
        return;
    argv[0] = slab_bin;
    for (i = 0; i < BENCH_SLAB_SIZE_COUNT; ++i) {
        snprintf(sizes[i], sizeof sizes[i], "%zu", bench_slab_sizes[i]);
        argv[i + 1] = sizes[i];
    }
    argv[BENCH_SLAB_SIZE_COUNT + 1] = NULL;
    for (run = 0; run < cfg->runs; ++run) {
        fprintf(stderr, "bench: slab vs doubling per order, run %zu of %zu\n", run + 1,
                cfg->runs);
        if (!bench_run_child(argv, NULL, "", store, &res)) {
            child_failed(store, "slab", &res);
            break;
        }
    }
}

/* One timed run of an executable of the --original directory, if present:
 * adds original.<name>.wall, .cpu and .peak_rss. */
static void run_original_program(const config *cfg, bench_store *store, const char *name,
                                 size_t run)
{
    char path[1024], id[160];
    char *argv[2];
    bench_child_result res;
    path_join(path, sizeof path, cfg->original_dir, name);
    if (access(path, X_OK) != 0)
        return;
    argv[0] = path;
    argv[1] = NULL;
    fprintf(stderr, "bench: original %s, run %zu of %zu\n", name, run + 1, cfg->runs);
    if (!bench_run_child(argv, NULL, NULL, store, &res)) {
        child_failed(store, path, &res);
        return;
    }
    snprintf(id, sizeof id, "original.%s.", name);
    store_costs(store, id, &res, 1);
}

/* The same recipes built by another implementation (--original): for each
 * recipe NAME the executable NAME, and optionally NAME.preamble, which runs
 * only what that recipe does before it builds any layer (for the original:
 * the Python interpreter, imports and the scipy integration of gold's
 * index), so that the comparison can be read with and without it. */
static void run_original(const config *cfg, bench_store *store)
{
    char name[160];
    size_t run, r;
    if (!cfg->original_dir)
        return;
    record_load(store, "original");
    for (run = 0; run < cfg->runs; ++run)
        for (r = 0; r < BENCH_RECIPE_COUNT; ++r) {
            run_original_program(cfg, store, bench_recipes[r].name, run);
            snprintf(name, sizeof name, "%s.preamble", bench_recipes[r].name);
            run_original_program(cfg, store, name, run);
        }
}

/* 4. Coated gold at 1, 2, 4, ... threads: the library's own count
 * (ll_set_thread_count) and OpenMP/OpenBLAS limited to the same. */
static void run_scaling(const config *cfg, bench_store *store)
{
    char recipe_bin[1024], out_path[1024], threads_arg[32], omp_env[64], blas_env[64], id[160];
    char prefix[96];
    size_t run, t;
    path_join(recipe_bin, sizeof recipe_bin, cfg->bin_dir, "recipe");
    path_join(out_path, sizeof out_path, cfg->work_dir, "scaling.bsdf");
    record_load(store, "scaling");
    for (run = 0; run < cfg->runs; ++run)
        for (t = 0; t < cfg->thread_count; ++t) {
            char *argv[5], *env[3];
            bench_child_result res;
            snprintf(threads_arg, sizeof threads_arg, "%zu", cfg->threads[t]);
            snprintf(omp_env, sizeof omp_env, "OMP_NUM_THREADS=%zu", cfg->threads[t]);
            snprintf(blas_env, sizeof blas_env, "OPENBLAS_NUM_THREADS=%zu", cfg->threads[t]);
            argv[0] = recipe_bin;
            argv[1] = "coated-gold";
            argv[2] = out_path;
            argv[3] = threads_arg;
            argv[4] = NULL;
            env[0] = omp_env;
            env[1] = blas_env;
            env[2] = NULL;
            fprintf(stderr, "bench: coated-gold at %zu thread(s), run %zu of %zu\n",
                    cfg->threads[t], run + 1, cfg->runs);
            snprintf(prefix, sizeof prefix, "scaling.coated-gold.t%zu.", cfg->threads[t]);
            if (!bench_run_child(argv, env, prefix, store, &res)) {
                child_failed(store, "scaling", &res);
                return;
            }
            snprintf(id, sizeof id, "scaling.coated-gold.t%zu.", cfg->threads[t]);
            store_costs(store, id, &res, 0);
        }
    remove(out_path);
}

/* 2. Adding throughput against dgemm at 1 thread and at all cores. */
static void run_adding(const config *cfg, bench_store *store)
{
    char bin[1024], runs[32], threads[64], sizes[BENCH_ADD_SIZE_COUNT][32];
    char *argv[4 + BENCH_ADD_SIZE_COUNT];
    bench_child_result res;
    size_t i;
    path_join(bin, sizeof bin, cfg->bin_dir, "adding");
    snprintf(runs, sizeof runs, "%zu", cfg->runs);
    if (cfg->cores > 1)
        snprintf(threads, sizeof threads, "1,%zu", cfg->cores);
    else
        snprintf(threads, sizeof threads, "1");
    argv[0] = bin;
    argv[1] = runs;
    argv[2] = threads;
    for (i = 0; i < BENCH_ADD_SIZE_COUNT; ++i) {
        snprintf(sizes[i], sizeof sizes[i], "%zu", bench_add_sizes[i]);
        argv[3 + i] = sizes[i];
    }
    argv[3 + BENCH_ADD_SIZE_COUNT] = NULL;
    record_load(store, "adding");
    fprintf(stderr, "bench: adding vs dgemm at %s thread(s)\n", threads);
    if (!bench_run_child(argv, NULL, "", store, &res))
        child_failed(store, "adding", &res);
}

/* The files the evaluation sections measure, in order: the golden file
 * (tests/data), then llbuild's outputs of two recipes (work folder). */
static const char *const measured_labels[3] = { "roughgold", "coated-gold", "coated-diffuse" };

/* Run bench/PROGRAM.c as `PROGRAM FILE [TABLE_OUT] LABEL RUNS` on each of
 * the first `count` measured files (TABLE_OUT, when `table_out` is set:
 * LABEL-tables.bsdf in the work folder), saying "bench: DOING LABEL"; the
 * program names its own metrics, and its section is PROGRAM. */
static void run_on_files(const config *cfg, bench_store *store, const char *program,
                         size_t count, int table_out, const char *doing)
{
    char bin[1024], runs[32], file[1024], out[1024], name[64];
    size_t i;
    path_join(bin, sizeof bin, cfg->bin_dir, program);
    snprintf(runs, sizeof runs, "%zu", cfg->runs);
    for (i = 0; i < count; ++i) {
        const char *label = measured_labels[i];
        char *argv[6];
        size_t a = 0;
        if (i == 0) {
            path_join(file, sizeof file, cfg->testdata_dir, "roughgold_alpha_0.2.bsdf");
        } else {
            snprintf(name, sizeof name, "%s.bsdf", label);
            path_join(file, sizeof file, cfg->work_dir, name);
        }
        if (!input_present(store, program, label, file, i == 0))
            continue;
        argv[a++] = bin;
        argv[a++] = file;
        if (table_out) {
            snprintf(name, sizeof name, "%s-tables.bsdf", label);
            path_join(out, sizeof out, cfg->work_dir, name);
            argv[a++] = out;
        }
        argv[a++] = (char *)label;
        argv[a++] = runs;
        argv[a] = NULL;
        fprintf(stderr, "bench: %s %s\n", doing, label);
        run_labelled(store, argv, program, label);
    }
}

/* 3. Evaluation on the golden file and on our coated-gold and
 * coated-diffuse outputs (docs/benchmarks.md has figures for both). */
static void run_eval(const config *cfg, bench_store *store)
{
    record_load(store, "eval");
    run_on_files(cfg, store, "eval", 3, 0, "evaluation on");
}

/* 3a. Table files: written from the golden file and from the coated-gold
 * output with the sizes the default tolerance chooses, then the three calls on the table and on
 * its .bsdf over the same directions (bench/tables.c). */
static void run_tables(const config *cfg, bench_store *store)
{
    record_load(store, "tables");
    run_on_files(cfg, store, "tables", 2, 1, "table file of");
}

/* 3b. The batch calls on the golden file (per element, 1 and all threads). */
static void run_batch(const config *cfg, bench_store *store)
{
    run_on_files(cfg, store, "batch", 1, 0, "batch calls on");
}

/* 6. The cost of the tolerance: each recipe built with the
 * resolution its tolerance chooses, once per tolerance (they take minutes),
 * finest first; then the others against the finest. LL_BENCH_TOLERANCE=0
 * skips it; LL_BENCH_TOLERANCE_RECIPES="coated-gold ..." picks recipes. */
static void run_tolerance(const config *cfg, bench_store *store)
{
    const char *skip = getenv("LL_BENCH_TOLERANCE"), *only = getenv("LL_BENCH_TOLERANCE_RECIPES");
    char bin[1024], out[BENCH_TOLERANCE_COUNT][1024], name[160], prefix[160], tol[32], thr[32];
    size_t r, t;
    if (skip && strcmp(skip, "0") == 0)
        return;
    path_join(bin, sizeof bin, cfg->bin_dir, "tolerance");
    snprintf(thr, sizeof thr, "%zu", cfg->cores);
    record_load(store, "tolerance");
    for (r = 0; r < BENCH_RECIPE_COUNT; ++r) {
        const char *recipe = bench_recipes[r].name;
        int built[BENCH_TOLERANCE_COUNT] = { 0 };
        if (only && !strstr(only, recipe))
            continue;
        for (t = BENCH_TOLERANCE_COUNT; t-- > 0;) {
            char *argv[7];
            bench_child_result res;
            char id[200];
            snprintf(tol, sizeof tol, "%g", bench_tolerances[t]);
            snprintf(name, sizeof name, "tolerance-%s-%s.bsdf", recipe, tol);
            path_join(out[t], sizeof out[t], cfg->work_dir, name);
            argv[0] = bin;
            argv[1] = (char *)"build";
            argv[2] = (char *)recipe;
            argv[3] = tol;
            argv[4] = out[t];
            argv[5] = thr;
            argv[6] = NULL;
            fprintf(stderr, "bench: %s at tolerance %s\n", recipe, tol);
            snprintf(prefix, sizeof prefix, "tolerance.%s.%s.", recipe, tol);
            if (!bench_run_child(argv, NULL, prefix, store, &res)) {
                child_failed(store, prefix, &res);
                continue;
            }
            built[t] = 1;
            snprintf(id, sizeof id, "tolerance.%s.%s.", recipe, tol);
            store_costs(store, id, &res, 1);
        }
        for (t = 0; t + 1 < BENCH_TOLERANCE_COUNT; ++t) {
            char *argv[5];
            bench_child_result res;
            if (!built[t] || !built[BENCH_TOLERANCE_COUNT - 1])
                continue;
            snprintf(tol, sizeof tol, "%g", bench_tolerances[t]);
            argv[0] = bin;
            argv[1] = (char *)"compare";
            argv[2] = out[BENCH_TOLERANCE_COUNT - 1];
            argv[3] = out[t];
            argv[4] = NULL;
            snprintf(prefix, sizeof prefix, "tolerance.%s.%s.", recipe, tol);
            if (!bench_run_child(argv, NULL, prefix, store, &res))
                child_failed(store, prefix, &res);
        }
    }
}

static void parse_args(int argc, char **argv, config *cfg, bench_store *store)
{
    int a;
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    size_t t;
    memset(cfg, 0, sizeof *cfg);
    cfg->runs = 3;
    for (a = 1; a + 1 < argc; a += 2) {
        const char *key = argv[a], *value = argv[a + 1];
        if (strcmp(key, "--bin") == 0)
            cfg->bin_dir = value;
        else if (strcmp(key, "--work") == 0)
            cfg->work_dir = value;
        else if (strcmp(key, "--testdata") == 0)
            cfg->testdata_dir = value;
        else if (strcmp(key, "--json") == 0)
            cfg->json_path = value;
        else if (strcmp(key, "--original") == 0)
            cfg->original_dir = value[0] ? value : NULL;
        else if (strcmp(key, "--llbuild") == 0)
            cfg->llbuild = value[0] ? value : NULL;
        else if (strcmp(key, "--full") == 0)
            cfg->full = strcmp(value, "1") == 0;
        else if (strcmp(key, "--runs") == 0)
            cfg->runs = bench_parse_size(value, "--runs");
        else if (strcmp(key, "--commit") == 0)
            bench_store_info(store, "git_commit", value);
        else if (strcmp(key, "--compiler") == 0)
            bench_store_info(store, "compiler", value);
        else
            bench_die("driver: unknown option %s", key);
    }
    if (a != argc || !cfg->bin_dir || !cfg->work_dir || !cfg->testdata_dir || !cfg->json_path)
        bench_die("usage: %s --bin DIR --work DIR --testdata DIR --json PATH [--runs N] "
                  "[--full 0|1] [--original DIR] [--llbuild PATH] [--commit TEXT] "
                  "[--compiler TEXT]",
                  argv[0]);
    if (cfg->runs < 3)
        bench_die("driver: --runs %zu: every figure is a median of at least 3 runs", cfg->runs);
    cfg->cores = cores > 0 ? (size_t)cores : 1;
    for (t = 1; t < cfg->cores && cfg->thread_count < 7; t *= 2)
        cfg->threads[cfg->thread_count++] = t;
    cfg->threads[cfg->thread_count++] = cfg->cores;
}

int main(int argc, char **argv)
{
    config cfg;
    bench_store store;
    int status;

    bench_store_init(&store);
    parse_args(argc, argv, &cfg, &store);
    record_machine(&cfg, &store);
    bench_store_info(&store, "mode",
                     cfg.full ? "full (make bench-full)" : "headline (make bench)");
    record_load(&store, "start");

    run_recipes(&cfg, &store);
    run_dust(&cfg, &store);
    run_original(&cfg, &store);
    if (cfg.full)
        run_scaling(&cfg, &store);
    run_adding(&cfg, &store);
    run_eval(&cfg, &store);
    run_tables(&cfg, &store);
    if (cfg.full) {
        run_batch(&cfg, &store);
        run_tolerance(&cfg, &store);
    }

    record_load(&store, "end");
    bench_report_table(stdout, &store);
    status = bench_report_json(cfg.json_path, &store);
    if (status == 0)
        printf("\nwrote %s\n", cfg.json_path);
    status = status != 0 || store.error_count != 0;
    bench_store_free(&store);
    return status;
}
