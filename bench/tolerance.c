/*
 * The cost of the resolution's tolerance: the three recipes of
 * bench/recipe.c written in the material language without a resolution,
 * so that the tolerance chooses it, built at a given tolerance; and the
 * worst difference of such a file from a reference file.
 *
 *     tolerance build NAME TOLERANCE OUT.bsdf THREADS
 *         builds recipe NAME (coated-gold, coated-gold-medium,
 *         coated-diffuse) with ll_build_options.tolerance = TOLERANCE;
 *         reports the chosen resolution (info n_nodes, n_orders), the time
 *         the choice took (metric choose) and the file's size (metric
 *         file, MB). The driver measures the whole process (wall, CPU,
 *         peak memory).
 *     tolerance compare REFERENCE.bsdf FILE.bsdf
 *         the worst |f - ref| / ref (metric error) over reflection at
 *         incident cosines 0.1, 0.15, 0.2 and 5 pseudo-random ones, the
 *         mirror direction, offsets around it and pseudo-random outgoing
 *         cosines, 9 azimuths, every channel, wherever ref is above 1% of
 *         the peak of its incident direction and channel (the tolerance's
 *         own criterion, docs/method.md "Resolution").
 */
#include "bench_util.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* The recipes' materials (as bench/recipe.c builds them call for call). */
static const char *recipe_text(const char *name)
{
    static const char gold[] =
        "dielectric eta=1.5 alpha=0.1\n"
        "conductor eta=0.14317534881908534+3.9826674681176435i,"
        "0.37309576813050427+2.3874442318808597i,1.4438276243071315+1.6024561077023662i "
        "alpha=0.1\n";
    static const char gold_medium[] =
        "dielectric eta=1.5 alpha=0.1\n"
        "medium albedo=0.25,0.0,0.95 g=0.5 tau=0.5\n"
        "conductor eta=0.14317534881908534+3.9826674681176435i,"
        "0.37309576813050427+2.3874442318808597i,1.4438276243071315+1.6024561077023662i "
        "alpha=0.1\n";
    static const char diffuse[] = "dielectric eta=1.5 alpha=0.02\n"
                                  "diffuse albedo=0.5,0.5,0.6\n";
    if (strcmp(name, "coated-gold") == 0)
        return gold;
    if (strcmp(name, "coated-gold-medium") == 0)
        return gold_medium;
    if (strcmp(name, "coated-diffuse") == 0)
        return diffuse;
    bench_die("tolerance: unknown recipe \"%s\"", name);
}

/* The material built, as one info line: its lines joined by "; ", after
 * the tolerance as a `set` line would give it. */
static void report_material(const char *text, double tolerance)
{
    char line[1200];
    size_t i, k;
    k = (size_t)snprintf(line, sizeof line, "set tolerance=%g", tolerance);
    for (i = 0; text[i] && k + 3 < sizeof line; ++i) {
        if (text[i] == '\n') {
            if (text[i + 1]) {
                line[k++] = ';';
                line[k++] = ' ';
            }
        } else {
            if (i == 0) {
                line[k++] = ';';
                line[k++] = ' ';
            }
            line[k++] = text[i];
        }
    }
    line[k] = '\0';
    bench_info("material", line);
}

static void build(const char *name, double tolerance, const char *out, size_t threads)
{
    ll_material *m = NULL;
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    size_t n, k, c;
    double start;
    char text[64];
    struct stat st;
    report_material(recipe_text(name), tolerance);
    bench_check(ll_material_parse(recipe_text(name), name, &m), "ll_material_parse");
    o.tolerance = tolerance;
    o.threads = threads;
    bench_check(ll_set_thread_count(threads), "ll_set_thread_count");
    start = bench_wall_seconds();
    bench_check(ll_material_resolution(m, &o, NULL, &n, &k, &c), "ll_material_resolution");
    bench_metric("choose", "s", bench_wall_seconds() - start);
    snprintf(text, sizeof text, "%zu", n);
    bench_info("n_nodes", text);
    snprintf(text, sizeof text, "%zu", k);
    bench_info("n_orders", text);
    /* Built at what was chosen, so that the process chooses once, as
     * llbuild does (ll_material_build would choose again). */
    o.n_nodes = n;
    o.n_orders = k;
    bench_check(ll_material_build(m, &o, NULL, out), "ll_material_build");
    if (stat(out, &st) == 0)
        bench_metric("file", "MB", (double)st.st_size / 1e6);
    ll_material_destroy(m);
}

static void compare(const char *ref_path, const char *path)
{
    static const double offsets[] = { 0.0, -0.01, 0.01, -0.03, 0.03, -0.1, 0.1 };
    static const double phis[] = { 0.0, 0.01, 0.03, 0.1, 0.2, 0.5, 1.0, 2.0, 3.14159265358979 };
    ll_bsdf *ref = NULL, *file = NULL;
    ll_bsdf_info info = LL_BSDF_INFO_INIT;
    bench_rng rng;
    double worst = 0.0;
    size_t i, c;
    /* Our own files, not untrusted ones: coated-diffuse at 0.2% is 733 MB,
     * above the reader's default limit of 512 MiB (the row was missing). */
    ll_open_options limits = LL_OPEN_OPTIONS_INIT;
    limits.max_bytes = SIZE_MAX;
    bench_check(ll_bsdf_open(ref_path, &limits, &ref), "ll_bsdf_open (reference)");
    bench_check(ll_bsdf_open(path, &limits, &file), "ll_bsdf_open");
    bench_check(ll_bsdf_get_info(ref, &info), "ll_bsdf_get_info");
    bench_rng_seed(&rng, 14);
    for (i = 0; i < 8; ++i) {
        double mu_i = i < 3 ? 0.1 + 0.05 * (double)i : 0.1 + 0.9 * bench_rng_uniform(&rng);
        double mu_o[sizeof offsets / sizeof offsets[0] + 3], peak[3] = { 0, 0, 0 };
        double r[16][9][3], v[16][9][3];
        size_t a, p, count = 0;
        for (a = 0; a < sizeof offsets / sizeof offsets[0]; ++a)
            if (mu_i + offsets[a] >= 0.1 && mu_i + offsets[a] <= 1.0)
                mu_o[count++] = mu_i + offsets[a];
        for (a = 0; a < 3; ++a)
            mu_o[count++] = 0.1 + 0.9 * bench_rng_uniform(&rng);
        for (a = 0; a < count; ++a)
            for (p = 0; p < sizeof phis / sizeof phis[0]; ++p) {
                /* Layer convention: lit from above, reflected up. */
                bench_check(ll_bsdf_eval(ref, mu_i, -mu_o[a], phis[p], NULL, r[a][p]),
                            "ll_bsdf_eval");
                bench_check(ll_bsdf_eval(file, mu_i, -mu_o[a], phis[p], NULL, v[a][p]),
                            "ll_bsdf_eval");
                for (c = 0; c < info.n_channels && c < 3; ++c)
                    peak[c] = fmax(peak[c], r[a][p][c]);
            }
        for (a = 0; a < count; ++a)
            for (p = 0; p < sizeof phis / sizeof phis[0]; ++p)
                for (c = 0; c < info.n_channels && c < 3; ++c)
                    if (r[a][p][c] > 0.01 * peak[c] && r[a][p][c] > 0.0)
                        worst = fmax(worst, fabs(v[a][p][c] - r[a][p][c]) / r[a][p][c]);
    }
    bench_metric("error", "relative", worst);
    ll_bsdf_release(ref);
    ll_bsdf_release(file);
}

int main(int argc, char **argv)
{
    if (argc == 6 && strcmp(argv[1], "build") == 0) {
        build(argv[2], atof(argv[3]), argv[4], bench_parse_size(argv[5], "THREADS"));
        return 0;
    }
    if (argc == 4 && strcmp(argv[1], "compare") == 0) {
        compare(argv[2], argv[3]);
        return 0;
    }
    bench_die("usage: %s build NAME TOLERANCE OUT.bsdf THREADS | compare REFERENCE FILE",
              argv[0]);
}
