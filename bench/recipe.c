/*
 * The three recipes of the original layerlab (recipes/coated-gold.py,
 * recipes/coated-gold-with-scatmedium.py, recipes/coated-diffuse.py),
 * rebuilt call for call on the C API at the original's resolutions, with
 * the time of each stage measured:
 *
 *     setup       quadrature and layer creation
 *     interfaces  ll_layer_set_microfacet / ll_layer_set_diffuse
 *     media       ll_layer_set_henyey_greenstein (the phase matrices)
 *     expanding   ll_layer_expand (doubling to the optical thickness)
 *     adding      ll_layer_add_to_top
 *     writing     ll_bsdf_write
 *
 * and, beside the measurements, what ll_material_estimate (llbuild
 * --dry-run) predicts for the same stack written in the material language
 * (estimate.wall, estimate.cpu, estimate.peak_rss), so that the report
 * shows the estimate against the measured process.
 *
 * usage: recipe NAME OUT.bsdf THREADS     (THREADS 0 = all processors)
 * The driver runs each recipe in its own process and reads the whole
 * process's wall time, CPU time and peak memory from wait4().
 */
#include "bench_util.h"
#include "time_model.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum {
    STAGE_SETUP,
    STAGE_INTERFACES,
    STAGE_MEDIA,
    STAGE_EXPANDING,
    STAGE_ADDING,
    STAGE_WRITING,
    STAGE_COUNT
};

static const char *const stage_names[STAGE_COUNT] = { "setup",     "interfaces", "media",
                                                      "expanding", "adding",     "writing" };

typedef enum { BASE_GOLD, BASE_DIFFUSE } base_kind;

/* An HG medium: albedo per channel, asymmetry, optical thickness. */
typedef struct medium_recipe {
    double albedo[3], g, tau;
} medium_recipe;

typedef struct recipe {
    const char *name;
    size_t n_nodes, n_orders; /* the original's parameterHeuristicMicrofacet results */
    double coat_alpha;        /* Beckmann roughness of the eta = 1.5 coating; 0: none */
    base_kind base;
    const medium_recipe *medium; /* HG medium between coating and base (nullable)   */
    double base_alpha;           /* the gold's roughness                            */
} recipe;

static const medium_recipe original_medium = { { 0.25, 0.0, 0.95 }, 0.5, 0.5 };
/* The seed's dust on gold: an index-matched HG medium, so no
 * coating above it, over smooth gold. */
static const medium_recipe dust = { { 0.9, 0.9, 0.9 }, 0.9, 4.0 };

/* Resolutions as the original recipes compute them (n = max over the two
 * interfaces, m = the coating's), at which the original's figures in
 * plan.h were taken; the dust on gold at the seed's own resolution (1098,
 * 4194) and at two reduced ones: (400, 1600), the seed's ratio of orders
 * to nodes, and (400, 800). */
static const recipe recipes[] = {
    { "coated-gold", 196, 267, 0.1, BASE_GOLD, NULL, 0.1 },
    { "coated-gold-medium", 196, 267, 0.1, BASE_GOLD, &original_medium, 0.1 },
    { "coated-diffuse", 1098, 2103, 0.02, BASE_DIFFUSE, NULL, 0.1 },
    { "dust-on-gold-400x1600", 400, 1600, 0.0, BASE_GOLD, &dust, 0.02 },
    { "dust-on-gold-400", 400, 800, 0.0, BASE_GOLD, &dust, 0.02 },
    { "dust-on-gold", 1098, 4194, 0.0, BASE_GOLD, &dust, 0.02 },
};

/* Gold's complex index per channel (R, G, B) exactly as the original
 * recipes compute it: utils/cie.py get_rgb(utils/materials.py gold), i.e.
 * the spectrum averaged against the CIE 1931 matching functions and
 * converted to linear sRGB (evaluated with scipy 1.17). */
static const double gold_eta[3] = { 0.14317534881908534, 0.37309576813050427,
                                    1.4438276243071315 };
static const double gold_k[3] = { 3.9826674681176435, 2.3874442318808597, 1.6024561077023662 };

static const double diffuse_albedo[3] = { 0.5, 0.5, 0.6 };
static const double coat_eta = 1.5;

typedef struct stage_clock {
    double wall[STAGE_COUNT], cpu[STAGE_COUNT];
    int current;
    double wall_start, cpu_start;
} stage_clock;

static void stage_begin(stage_clock *c, int stage)
{
    c->current = stage;
    c->wall_start = bench_wall_seconds();
    c->cpu_start = bench_cpu_seconds();
}

static void stage_end(stage_clock *c)
{
    c->wall[c->current] += bench_wall_seconds() - c->wall_start;
    c->cpu[c->current] += bench_cpu_seconds() - c->cpu_start;
}

static ll_layer *new_layer(const recipe *r, const double *nodes, const double *weights,
                           stage_clock *clk)
{
    ll_layer *layer = NULL;
    stage_begin(clk, STAGE_SETUP);
    bench_check(ll_layer_create(nodes, weights, r->n_nodes, r->n_orders, &layer),
                "ll_layer_create");
    stage_end(clk);
    return layer;
}

static void run_recipe(const recipe *r, const char *out_path, stage_clock *clk)
{
    double *nodes = bench_alloc(r->n_nodes, sizeof(double));
    double *weights = bench_alloc(r->n_nodes, sizeof(double));
    ll_layer *coating, *channels[3], *medium = NULL;
    int c;

    stage_begin(clk, STAGE_SETUP);
    bench_check(ll_quad_gauss_lobatto(r->n_nodes, nodes, weights, NULL), "ll_quad_gauss_lobatto");
    stage_end(clk);

    /* The original's setMicrofacet defaults: conserveEnergy = false,
     * fourierOrders = 0 (the layer's). */
    coating = r->coat_alpha > 0.0 ? new_layer(r, nodes, weights, clk) : NULL;
    if (coating) {
        stage_begin(clk, STAGE_INTERFACES);
        bench_check(bench_set_microfacet(coating, coat_eta, 0.0, r->coat_alpha, 0, 0, NULL),
                    "ll_layer_set_microfacet (coating)");
        stage_end(clk);
    }

    for (c = 0; c < 3; ++c) {
        ll_layer *base = new_layer(r, nodes, weights, clk);
        /* A medium the same in every channel (the dust) is built once and
         * added to each, as llbuild shares it. */
        int shared = r->medium && c > 0 && r->medium->albedo[c] == r->medium->albedo[c - 1];
        stage_begin(clk, STAGE_INTERFACES);
        if (r->base == BASE_GOLD)
            bench_check(bench_set_microfacet(base, gold_eta[c], gold_k[c], r->base_alpha, 0, 0, NULL),
                        "ll_layer_set_microfacet (gold)");
        else
            bench_check(ll_layer_set_diffuse(base, diffuse_albedo[c], NULL), "ll_layer_set_diffuse");
        stage_end(clk);

        if (r->medium && !shared) {
            ll_layer_destroy(medium);
            medium = new_layer(r, nodes, weights, clk);
            stage_begin(clk, STAGE_MEDIA);
            bench_check(ll_layer_set_henyey_greenstein(medium, r->medium->albedo[c],
                                                       r->medium->g, NULL),
                        "ll_layer_set_henyey_greenstein");
            stage_end(clk);
            stage_begin(clk, STAGE_EXPANDING);
            bench_check(ll_layer_expand(medium, r->medium->tau, NULL), "ll_layer_expand");
            stage_end(clk);
        }
        if (r->medium) {
            stage_begin(clk, STAGE_ADDING);
            bench_check(ll_layer_add_to_top(base, medium), "ll_layer_add_to_top (medium)");
            stage_end(clk);
        }

        if (coating) {
            stage_begin(clk, STAGE_ADDING);
            bench_check(ll_layer_add_to_top(base, coating), "ll_layer_add_to_top (coating)");
            stage_end(clk);
        }
        channels[c] = base;
    }

    stage_begin(clk, STAGE_WRITING);
    bench_check(ll_bsdf_write(out_path, (const ll_layer *const *)channels, 3, NULL, NULL),
                "ll_bsdf_write");
    stage_end(clk);

    for (c = 0; c < 3; ++c)
        ll_layer_destroy(channels[c]);
    if (coating)
        ll_layer_destroy(coating);
    ll_layer_destroy(medium);
    free(nodes);
    free(weights);
}

/* x in the fewest significant digits that read back as x (the material
 * text shows 0.1, not 0.10000000000000001, and stays exact). */
static const char *exact(double x, char buf[32])
{
    int digits;
    for (digits = 1; digits < 17; ++digits) {
        snprintf(buf, 32, "%.*g", digits, x);
        if (strtod(buf, NULL) == x)
            return buf;
    }
    snprintf(buf, 32, "%.17g", x);
    return buf;
}

/* The recipe's stack in the material language, at its resolution: what
 * the report names as the benchmark's material, and what the estimate
 * reads (the same layers; the estimate does not depend on the metal's
 * index, which the material language takes relative to the coat). One
 * line per word. */
static void material_text(const recipe *r, char *text, size_t size)
{
    char a[32], b[32], c[32], d[32], e[32], f[32], g[32];
    size_t len;
    len = (size_t)snprintf(text, size, "set nodes=%zu orders=%zu channels=3\n", r->n_nodes,
                           r->n_orders);
    if (r->coat_alpha > 0.0 && len < size)
        len += (size_t)snprintf(text + len, size - len, "dielectric eta=%s alpha=%s\n",
                                exact(coat_eta, a), exact(r->coat_alpha, b));
    if (r->medium && len < size)
        len += (size_t)snprintf(text + len, size - len, "medium albedo=%s,%s,%s g=%s tau=%s\n",
                                exact(r->medium->albedo[0], a), exact(r->medium->albedo[1], b),
                                exact(r->medium->albedo[2], c), exact(r->medium->g, d),
                                exact(r->medium->tau, e));
    if (len >= size)
        bench_die("recipe: the material text of %s is too long", r->name);
    if (r->base == BASE_GOLD)
        len += (size_t)snprintf(text + len, size - len,
                                "conductor eta=%s+%si,%s+%si,%s+%si alpha=%s\n",
                                exact(gold_eta[0], a), exact(gold_k[0], b),
                                exact(gold_eta[1], c), exact(gold_k[1], d),
                                exact(gold_eta[2], e), exact(gold_k[2], f),
                                exact(r->base_alpha, g));
    else
        len += (size_t)snprintf(text + len, size - len, "diffuse albedo=%s,%s,%s\n",
                                exact(diffuse_albedo[0], a), exact(diffuse_albedo[1], b),
                                exact(diffuse_albedo[2], c));
    if (len >= size)
        bench_die("recipe: the material text of %s is too long", r->name);
}

/* The material as one info line: its lines joined by "; ". Energy
 * compensation is off in the recipe, as in the original. */
static void report_material(const char *text)
{
    char line[1200];
    size_t i, k = 0;
    for (i = 0; text[i] && k + 3 < sizeof line; ++i) {
        if (text[i] != '\n') {
            line[k++] = text[i];
        } else if (text[i + 1]) {
            line[k++] = ';';
            line[k++] = ' ';
        }
    }
    line[k] = '\0';
    bench_info("material", line);
}

static void report_estimate(const recipe *r, const char *text)
{
    ll_material *m = NULL;
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    ll_build_estimate e = LL_BUILD_ESTIMATE_INIT;
    double wall, cpu;
    bench_check(ll_material_parse(text, r->name, &m), "ll_material_parse");
    o.threads = ll_get_thread_count();
    bench_check(ll_material_estimate(m, &o, &e, NULL), "ll_material_estimate");
    /* (llbuild --dry-run's time: its model over the estimate's counts.) */
    llbuild_time(&e, &wall, &cpu);
    bench_metric("estimate.wall", "s", wall);
    bench_metric("estimate.cpu", "s", cpu);
    bench_metric("estimate.peak_rss", "MiB", e.peak_bytes / 1048576.0);
    ll_material_destroy(m);
}

int main(int argc, char **argv)
{
    const recipe *r = NULL;
    stage_clock clk;
    char id[64], text[1024];
    size_t i, threads;
    int s;

    if (argc != 4)
        bench_die("usage: %s NAME OUT.bsdf THREADS (NAME: coated-gold, coated-gold-medium, "
                  "coated-diffuse, dust-on-gold-400x1600, dust-on-gold-400, dust-on-gold)",
                  argv[0]);
    for (i = 0; i < sizeof recipes / sizeof recipes[0]; ++i)
        if (strcmp(argv[1], recipes[i].name) == 0)
            r = &recipes[i];
    if (!r)
        bench_die("recipe: unknown recipe \"%s\"", argv[1]);
    threads = bench_parse_size(argv[3], "THREADS");
    bench_check(ll_set_thread_count(threads), "ll_set_thread_count");

    memset(&clk, 0, sizeof clk);
    run_recipe(r, argv[2], &clk);

    for (s = 0; s < STAGE_COUNT; ++s) {
        snprintf(id, sizeof id, "stage.%s", stage_names[s]);
        bench_metric(id, "s", clk.wall[s]);
        snprintf(id, sizeof id, "stage_cpu.%s", stage_names[s]);
        bench_metric(id, "s", clk.cpu[s]);
    }
    snprintf(id, sizeof id, "%zu", r->n_nodes);
    bench_info("n_nodes", id);
    snprintf(id, sizeof id, "%zu", r->n_orders);
    bench_info("n_orders", id);
    snprintf(id, sizeof id, "%zu", ll_get_thread_count());
    bench_info("threads", id);
    material_text(r, text, sizeof text);
    report_material(text);
    report_estimate(r, text);
    return 0;
}
