/*
 * Building materials: every example at a low resolution, the coated gold
 * against bare gold, channel sharing, the header, progress, cancellation
 * (no file, an existing one untouched) and the estimate.
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <dirent.h>
#include <sys/stat.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <layerlab.h>
#include "test_util.h"

#define EXAMPLES LL_SOURCE_DIR "/examples/"

static char tmpdir[64];

static int make_tmpdir(void **state)
{
    (void)state;
    ll_test_mkdtemp(tmpdir, sizeof tmpdir);
    return 0;
}

static int remove_tmpdir(void **state)
{
    (void)state;
    ll_test_rmdir(tmpdir);
    return 0;
}

static ll_material *parse(const char *text)
{
    ll_material *m = NULL;
    if (ll_material_parse(text, "t", &m) != LL_OK)
        fail_msg("%s", ll_last_error_message());
    return m;
}

static ll_material *parse_file(const char *path)
{
    ll_material *m = NULL;
    if (ll_material_parse_file(path, &m) != LL_OK)
        fail_msg("%s", ll_last_error_message());
    return m;
}

/* Build at a fixed small resolution. */
static size_t build(const ll_material *m, size_t nodes, size_t orders, size_t channels,
                    ll_layer *layers[3])
{
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    size_t n = 0;
    ll_status s;
    o.n_nodes = nodes;
    o.n_orders = orders;
    o.n_channels = channels;
    s = ll_material_build_layers(m, &o, NULL, layers, &n, NULL);
    if (s != LL_OK)
        fail_msg("build: %s", ll_last_error_message());
    return n;
}

static void destroy3(ll_layer *layers[3])
{
    int c;
    for (c = 0; c < 3; ++c)
        ll_layer_destroy(layers[c]);
}

/* Every example builds at a low resolution (too low to resolve their
 * highlights, so only the structure is checked here: colour, opacity). */
static void examples_build_at_low_resolution(void **state)
{
    static const struct {
        const char *file;
        size_t channels;
        int opaque;
    } examples[] = {
        { "coated-gold.layers", 3, 1 },      { "coated-gold-with-scatmedium.layers", 3, 1 },
        { "plastic.layers", 3, 1 },          { "dusty-metal.layers", 3, 1 },
        { "frosted-glass.layers", 1, 0 },    { "varnished-colour.layers", 3, 1 },
    };
    size_t i, c;
    (void)state;
    for (i = 0; i < sizeof examples / sizeof examples[0]; ++i) {
        char path[512];
        ll_material *m;
        ll_layer *layers[3] = { NULL, NULL, NULL };
        snprintf(path, sizeof path, "%s%s", EXAMPLES, examples[i].file);
        m = parse_file(path);
        assert_int_equal(build(m, 24, 16, 0, layers), examples[i].channels);
        for (c = 0; c < examples[i].channels; ++c) {
            double R, T;
            assert_int_equal(ll_layer_albedo(layers[c], 0.8, &R, &T), LL_OK);
            if (!(R > 0.0 && R < 10.0 && T >= 0.0 && T < 10.0))
                fail_msg("%s channel %zu: R %g T %g", examples[i].file, c, R, T);
            if (examples[i].opaque)
                assert_float_equal(T, 0.0, 1e-9);
            else
                assert_true(T > 0.5);
        }
        destroy3(layers);
        ll_material_destroy(m);
    }
}

/* Top to bottom: an interface above an absorbing slab reflects as the bare
 * interface does, one below it is seen through the slab twice (e^(-2 tau/mu)
 * weaker). A white base under a clear coat reflects everything. */
static void words_stack_top_to_bottom(void **state)
{
    ll_material *above = parse("dielectric eta=1.5 alpha=0.3\nmedium albedo=0 tau=1");
    ll_material *below = parse("medium albedo=0 tau=1\ndielectric eta=1.5 alpha=0.3");
    ll_material *bare = parse("dielectric eta=1.5 alpha=0.3");
    ll_material *white = parse("dielectric eta=1.5 alpha=0.3\ndiffuse albedo=1");
    ll_layer *a[3] = { NULL, NULL, NULL }, *b[3] = { NULL, NULL, NULL };
    ll_layer *c[3] = { NULL, NULL, NULL }, *w[3] = { NULL, NULL, NULL };
    double Ra, Rb, Rc, Rw, T;
    (void)state;
    build(above, 92, 61, 1, a);
    build(below, 92, 61, 1, b);
    build(bare, 92, 61, 1, c);
    build(white, 92, 61, 1, w);
    assert_int_equal(ll_layer_albedo(a[0], 0.9, &Ra, &T), LL_OK);
    assert_int_equal(ll_layer_albedo(b[0], 0.9, &Rb, &T), LL_OK);
    assert_int_equal(ll_layer_albedo(c[0], 0.9, &Rc, &T), LL_OK);
    assert_int_equal(ll_layer_albedo(w[0], 0.9, &Rw, &T), LL_OK);
    assert_float_equal(Ra, Rc, 1e-3 * Rc);
    assert_true(Rb < 0.3 * Rc && Rb > 0.0);
    assert_float_equal(Rw, 1.0, 5e-3);
    destroy3(a);
    destroy3(b);
    destroy3(c);
    destroy3(w);
    ll_material_destroy(above);
    ll_material_destroy(below);
    ll_material_destroy(bare);
    ll_material_destroy(white);
}

/* End to end against the original tools: `conductor eta=Au alpha=0.2` at
 * the original's resolution (its fit: 56 nodes, 172 orders; 58 file nodes,
 * as theirs; the default resolution is now chosen by the tolerance and is
 * finer) evaluates like
 * tests/data/roughgold_alpha_0.2.bsdf within 1% for directions up to
 * 63 degrees from the normal (our gold indices differ from theirs by up to
 * 1.2%; at grazing angles the interface models differ by a few percent). */
static void rough_gold_matches_the_original_file(void **state)
{
    ll_material *m = parse("conductor eta=Au alpha=0.2");
    ll_bsdf *ref = NULL, *ours = NULL;
    ll_bsdf_info info = LL_BSDF_INFO_INIT;
    char path[128];
    double ti, to, ph;
    int c, pairs = 0;
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    (void)state;
    o.n_nodes = 56;
    o.n_orders = 172;
    snprintf(path, sizeof path, "%s/roughgold.bsdf", tmpdir);
    assert_int_equal(ll_material_build(m, &o, NULL, path), LL_OK);
    assert_int_equal(ll_bsdf_open(path, NULL, &ours), LL_OK);
    assert_int_equal(ll_bsdf_open(LL_SOURCE_DIR "/tests/data/roughgold_alpha_0.2.bsdf", NULL, &ref),
                     LL_OK);
    assert_int_equal(ll_bsdf_get_info(ours, &info), LL_OK);
    assert_int_equal(info.n_nodes, 58);
    for (ti = 0.05; ti < 1.1; ti += 0.15)
        for (to = 0.05; to < 1.1; to += 0.15)
            for (ph = 0.0; ph < 3.2; ph += 0.4) {
                double wi[3], wo[3], a[3], b[3];
                wi[0] = sin(ti), wi[1] = 0.0, wi[2] = cos(ti);
                wo[0] = sin(to) * cos(ph), wo[1] = sin(to) * sin(ph), wo[2] = cos(to);
                assert_int_equal(
                    ll_bsdf_eval_dir(ref, wo, wi, LL_TRANSPORT_IMPORTANCE, NULL, a), LL_OK);
                assert_int_equal(
                    ll_bsdf_eval_dir(ours, wo, wi, LL_TRANSPORT_IMPORTANCE, NULL, b), LL_OK);
                for (c = 0; c < 3; ++c)
                    if (a[c] > 0.05) {
                        ++pairs;
                        if (fabs(b[c] / a[c] - 1.0) > 0.01)
                            fail_msg("theta_i %g theta_o %g phi %g channel %d: ours %g, "
                                     "original %g",
                                     ti, to, ph, c, b[c], a[c]);
                    }
            }
    assert_true(pairs > 500);
    ll_bsdf_release(ref);
    ll_bsdf_release(ours);
    ll_material_destroy(m);
}

/* The albedo (reflected) of a file for light from mu_i, integrated over the
 * file's own spline nodes in mu_o (3-point Gauss per interval) and over the
 * azimuth with more points than the series has terms (exact for it). */
static void file_albedo(const ll_bsdf *b, double mu_i, double rgb[3])
{
    ll_bsdf_info info = LL_BSDF_INFO_INIT;
    const float *nodes = ll_bsdf_nodes(b);
    static const double gx[3] = { -0.7745966692414834, 0.0, 0.7745966692414834 };
    static const double gw[3] = { 5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0 };
    size_t i, j, k, n_phi;
    int c;
    assert_int_equal(ll_bsdf_get_info(b, &info), LL_OK);
    n_phi = info.max_order + 1; /* trapezoid: exact for cos(k phi), k < n_phi */
    rgb[0] = rgb[1] = rgb[2] = 0.0;
    for (i = 0; i + 1 < info.n_nodes; ++i) {
        double a = nodes[i], z = nodes[i + 1];
        if (z > 0.0 || z <= a)
            continue; /* reflection: mu_o < 0 */
        for (j = 0; j < 3; ++j) {
            double mu_o = 0.5 * (a + z) + 0.5 * (z - a) * gx[j];
            double w = 0.5 * (z - a) * gw[j] * fabs(mu_o) * 2.0 * 3.14159265358979 / n_phi;
            for (k = 0; k < n_phi; ++k) {
                double f[3], phi = 2.0 * 3.14159265358979 * k / n_phi;
                assert_int_equal(ll_bsdf_eval(b, mu_i, mu_o, phi, NULL, f), LL_OK);
                for (c = 0; c < 3; ++c)
                    rgb[c] += w * f[c];
            }
        }
    }
}

/* The coated gold file opens, carries its header, and reflects less than
 * bare gold (the coat reflects some light but traps more between itself and
 * the metal, where the metal absorbs). */
static void coated_gold_is_darker_than_bare_gold(void **state)
{
    char coated_path[128], bare_path[128];
    ll_material *coated = parse_file(EXAMPLES "coated-gold.layers");
    ll_material *bare = parse("conductor eta=Au alpha=0.1");
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    ll_bsdf *bc = NULL, *bb = NULL;
    ll_bsdf_info info = LL_BSDF_INFO_INIT;
    double mu[2] = { 0.95, 0.6 };
    int a, c;
    (void)state;
    /* Converged at normal incidence to 3 digits (the heuristic's 196 x 524
     * gives the same albedos); coarser resolutions overshoot. */
    o.n_nodes = 100;
    o.n_orders = 150;
    snprintf(coated_path, sizeof coated_path, "%s/coated.bsdf", tmpdir);
    snprintf(bare_path, sizeof bare_path, "%s/bare.bsdf", tmpdir);
    assert_int_equal(ll_material_build(coated, &o, NULL, coated_path), LL_OK);
    assert_int_equal(ll_material_build(bare, &o, NULL, bare_path), LL_OK);
    assert_int_equal(ll_bsdf_open(coated_path, NULL, &bc), LL_OK);
    assert_int_equal(ll_bsdf_open(bare_path, NULL, &bb), LL_OK);
    assert_int_equal(ll_bsdf_get_info(bc, &info), LL_OK);
    assert_int_equal(info.n_channels, 3);
    assert_int_equal(info.n_nodes, 102);
    assert_float_equal(info.eta, 1.0, 0.0);
    assert_float_equal(info.alpha[0], 0.1, 1e-7);
    assert_float_equal(info.alpha[1], 0.1, 1e-7);
    assert_non_null(strstr(info.metadata, "\"name\": \"Au\""));
    assert_non_null(strstr(info.metadata, "dielectric  eta=1.5"));
    for (a = 0; a < 2; ++a) {
        double rc[3], rb[3];
        file_albedo(bc, mu[a], rc);
        file_albedo(bb, mu[a], rb);
        for (c = 0; c < 3; ++c) {
            if (!(rc[c] < rb[c] && rc[c] > 0.2 && rb[c] < 1.0))
                fail_msg("mu %g channel %d: coated %g, bare %g", mu[a], c, rc[c], rb[c]);
        }
        /* Gold is yellow: red reflects more than blue. */
        assert_true(rb[0] > rb[2]);
    }
    ll_bsdf_release(bc);
    ll_bsdf_release(bb);
    ll_material_destroy(coated);
    ll_material_destroy(bare);
}

/* A grey stack built as RGB is the monochrome build three times; a coloured
 * stack's channels differ only where the words do. */
static void channels_share_what_is_equal(void **state)
{
    ll_material *grey = parse("dielectric eta=1.5 alpha=0.3\nmedium albedo=0.8 tau=1 g=0.3\n"
                              "diffuse albedo=0.5");
    ll_layer *mono[3] = { NULL, NULL, NULL }, *rgb[3] = { NULL, NULL, NULL };
    size_t n = 16, c, k;
    double *a = malloc(n * n * sizeof(double)), *b = malloc(n * n * sizeof(double));
    (void)state;
    assert_non_null(a);
    assert_non_null(b);
    assert_int_equal(build(grey, n, 8, 1, mono), 1);
    assert_int_equal(build(grey, n, 8, 3, rgb), 3);
    for (c = 0; c < 3; ++c)
        for (k = 0; k < 8; ++k) {
            assert_int_equal(ll_layer_matrix(mono[0], k, a), LL_OK);
            assert_int_equal(ll_layer_matrix(rgb[c], k, b), LL_OK);
            assert_memory_equal(a, b, n * n * sizeof(double));
        }
    destroy3(mono);
    destroy3(rgb);
    ll_material_destroy(grey);

    /* Only the base differs: red and blue agree, green does not. */
    grey = parse("dielectric eta=1.5 alpha=0.3\ndiffuse albedo=0.5,0.2,0.5");
    assert_int_equal(build(grey, n, 4, 0, rgb), 3);
    assert_int_equal(ll_layer_matrix(rgb[0], 0, a), LL_OK);
    assert_int_equal(ll_layer_matrix(rgb[2], 0, b), LL_OK);
    assert_memory_equal(a, b, n * n * sizeof(double));
    assert_int_equal(ll_layer_matrix(rgb[1], 0, b), LL_OK);
    assert_memory_not_equal(a, b, n * n * sizeof(double));
    destroy3(rgb);
    ll_material_destroy(grey);
    free(a);
    free(b);
}

/* A measured BRDF under a coat: a constant MERL table is a Lambertian whose
 * channels carry MERL's scales (1, 1.15, 1.66) / 1500; a monochrome build
 * takes their luminance. */
static void measured_brdf_builds_under_a_coat(void **state)
{
    char bin[128], text[256];
    unsigned char header[12] = { 2, 0, 0, 0, 2, 0, 0, 0, 4, 0, 0, 0 };
    double v = 1500.0 * 0.3 / 3.14159265358979323846, R[3], T;
    ll_material *m;
    ll_layer *layers[3] = { NULL, NULL, NULL };
    FILE *f;
    int k;
    (void)state;
    snprintf(bin, sizeof bin, "%s/flat.binary", tmpdir);
    f = fopen(bin, "wb");
    assert_non_null(f);
    fwrite(header, 1, 12, f);
    for (k = 0; k < 3 * 16; ++k)
        fwrite(&v, 8, 1, f); /* little-endian machine, as MERL's files */
    fclose(f);
    snprintf(text, sizeof text, "measured file=%s", bin);
    m = parse(text);
    assert_int_equal(build(m, 16, 4, 0, layers), 3);
    for (k = 0; k < 3; ++k)
        assert_int_equal(ll_layer_albedo(layers[k], 0.7, &R[k], &T), LL_OK);
    assert_float_equal(R[0], 0.3, 2e-3);
    assert_float_equal(R[1], 0.3 * 1.15, 2e-3);
    assert_float_equal(R[2], 0.3 * 1.66, 3e-3);
    destroy3(layers);
    assert_int_equal(build(m, 16, 4, 1, layers), 1);
    assert_int_equal(ll_layer_albedo(layers[0], 0.7, &R[0], &T), LL_OK);
    assert_float_equal(R[0], 0.3 * (0.212671 + 0.715160 * 1.15 + 0.072169 * 1.66), 2e-3);
    destroy3(layers);
    ll_material_destroy(m);

    snprintf(text, sizeof text, "dielectric eta=1.5 alpha=0.5\nmeasured file=%s", bin);
    m = parse(text);
    assert_int_equal(build(m, 48, 24, 0, layers), 3);
    for (k = 0; k < 3; ++k) {
        assert_int_equal(ll_layer_albedo(layers[k], 0.7, &R[k], &T), LL_OK);
        /* The coat adds its reflection but traps light the base absorbs. */
        assert_true(R[k] > 0.0 && R[k] < 1.0);
        assert_float_equal(T, 0.0, 1e-9);
    }
    assert_true(R[0] < R[1] && R[1] < R[2]);
    destroy3(layers);
    ll_material_destroy(m);
}

/* The header of a transmissive stack, from ll_material_build_layers. */
static void header_is_returned(void **state)
{
    ll_material *m = parse_file(EXAMPLES "frosted-glass.layers");
    ll_layer *layers[3] = { NULL, NULL, NULL };
    ll_bsdf_write_options h = LL_BSDF_WRITE_OPTIONS_INIT;
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    size_t n;
    (void)state;
    o.n_nodes = 16;
    o.n_orders = 8;
    o.error_goal = 1e-4;
    assert_int_equal(ll_material_build_layers(m, &o, NULL, layers, &n, &h), LL_OK);
    assert_int_equal(n, 1);
    assert_float_equal(h.eta, 1.5, 0.0);
    assert_float_equal(h.alpha[0], 0.3, 0.0);
    assert_float_equal(h.alpha[1], 0.3, 0.0);
    assert_float_equal(h.error_goal, 1e-4, 0.0);
    assert_non_null(h.metadata);
    assert_non_null(strstr(h.metadata, "\"type\": \"dielectric\""));
    destroy3(layers);
    ll_material_destroy(m);
}

typedef struct progress_log {
    double last;
    int calls, monotone, saw_adding, saw_writing, saw_medium, done;
    volatile int *cancel_after; /* raised when the medium starts; returned */
} progress_log;

/* The build's monitor: records the reports and returns the cancel flag. */
static int on_progress(void *user, double f, const char *stage)
{
    progress_log *p = user;
    if (f < p->last || f < 0.0 || f > 1.0)
        p->monotone = 0;
    p->last = f;
    p->calls++;
    p->saw_adding |= strcmp(stage, "adding") == 0;
    p->saw_writing |= strcmp(stage, "writing") == 0;
    p->saw_medium |= strcmp(stage, "medium") == 0;
    p->done |= strcmp(stage, "done") == 0 && f == 1.0;
    if (p->cancel_after && strcmp(stage, "medium") == 0)
        *p->cancel_after = 1;
    return p->cancel_after ? *p->cancel_after : 0;
}

static ll_monitor log_monitor(progress_log *log)
{
    ll_monitor monitor = LL_MONITOR_INIT;
    monitor.progress = on_progress;
    monitor.user = log;
    return monitor;
}

static void progress_is_monotone_and_complete(void **state)
{
    ll_material *m = parse_file(EXAMPLES "coated-gold-with-scatmedium.layers");
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    progress_log log = { 0.0, 0, 1, 0, 0, 0, 0, NULL };
    ll_monitor monitor = log_monitor(&log);
    char path[128];
    (void)state;
    o.n_nodes = 16;
    o.n_orders = 8;
    snprintf(path, sizeof path, "%s/progress.bsdf", tmpdir);
    assert_int_equal(ll_material_build(m, &o, &monitor, path), LL_OK);
    assert_true(log.monotone);
    assert_true(log.calls > 5);
    /* Complete: the writer's last report, 1, is the build's last. */
    assert_true(log.saw_adding && log.saw_writing && log.saw_medium && log.last == 1.0);
    ll_material_destroy(m);
}

static int count_files(const char *dir)
{
    DIR *d = opendir(dir);
    struct dirent *e;
    int n = 0;
    assert_non_null(d);
    while ((e = readdir(d)) != NULL)
        if (e->d_name[0] != '.')
            ++n;
    closedir(d);
    return n;
}

/* A cancelled build leaves no file, no temporary, and an existing file as it
 * was. */
static void cancel_leaves_no_file(void **state)
{
    ll_material *m = parse_file(EXAMPLES "coated-gold-with-scatmedium.layers");
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    volatile int cancel = 0;
    progress_log log = { 0.0, 0, 1, 0, 0, 0, 0, &cancel };
    ll_monitor monitor = log_monitor(&log);
    char dir[128], path[160], old[16] = "";
    FILE *f;
    int before;
    (void)state;
    snprintf(dir, sizeof dir, "%s/cancel", tmpdir);
    assert_int_equal(mkdir(dir, 0700), 0);
    snprintf(path, sizeof path, "%s/out.bsdf", dir);
    o.n_nodes = 16;
    o.n_orders = 8;

    /* Raised before the start. */
    cancel = 1;
    assert_int_equal(ll_material_build(m, &o, &monitor, path), LL_ERROR_CANCELLED);
    assert_int_equal(count_files(dir), 0);

    /* Raised in the middle (when the medium starts), over an old file. */
    f = fopen(path, "w");
    assert_non_null(f);
    fputs("old file", f);
    fclose(f);
    before = count_files(dir);
    cancel = 0;
    log.saw_medium = log.saw_writing = 0;
    assert_int_equal(ll_material_build(m, &o, &monitor, path), LL_ERROR_CANCELLED);
    assert_true(log.saw_medium);
    assert_false(log.saw_writing);
    assert_int_equal(count_files(dir), before);
    f = fopen(path, "r");
    assert_non_null(f);
    assert_non_null(fgets(old, sizeof old, f));
    fclose(f);
    assert_string_equal(old, "old file");

    /* In memory: nothing is returned. */
    {
        ll_layer *layers[3] = { (ll_layer *)1, NULL, NULL };
        size_t n = 7;
        cancel = 1;
        assert_int_equal(ll_material_build_layers(m, &o, &monitor, layers, &n, NULL),
                         LL_ERROR_CANCELLED);
        assert_null(layers[0]);
        assert_int_equal(n, 0);
    }
    ll_material_destroy(m);
}

/* opts->threads applies during the build only. */
static void thread_count_is_restored(void **state)
{
    ll_material *m = parse("diffuse albedo=0.5");
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    ll_layer *layers[3] = { NULL, NULL, NULL };
    size_t n;
    (void)state;
    assert_int_equal(ll_set_thread_count(1), LL_OK);
    o.threads = 2;
    o.n_nodes = 10;
    o.n_orders = 1;
    assert_int_equal(ll_material_build_layers(m, &o, NULL, layers, &n, NULL), LL_OK);
    assert_int_equal(ll_get_thread_count(), 1);
    assert_int_equal(ll_set_thread_count(0), LL_OK);
    destroy3(layers);
    ll_material_destroy(m);
}

/* The estimate counts what the build does: a coat shared by all channels,
 * per-channel media and metals, one addition per channel and word above the
 * bottom, the medium's doublings. */
static void estimate_counts_the_work(void **state)
{
    ll_material *m = parse_file(EXAMPLES "coated-gold-with-scatmedium.layers");
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    ll_build_estimate e = LL_BUILD_ESTIMATE_INIT;
    size_t n, k, c;
    (void)state;
    assert_int_equal(ll_material_estimate(m, NULL, &e, NULL), LL_OK);
    assert_int_equal(ll_material_resolution(m, NULL, NULL, &n, &k, &c), LL_OK);
    assert_int_equal(e.n_nodes, n);
    assert_int_equal(e.n_orders, k);
    assert_int_equal(e.n_channels, 3);
    assert_int_equal(e.layers_built, 7);
    assert_int_equal(e.additions, 6);
    /* tau 0.5 from 2^-15: 14 doublings per channel. */
    assert_int_equal(e.doublings, 42);
    assert_true(e.peak_bytes > 8.0 * 1048576.0 && e.peak_bytes < 8.0 * n * n * k * 7);
    /* The work: two interfaces (the coat, the gold) in three channels... */
    assert_true(e.dielectric_pairs > 0.0 && e.conductor_pairs > 0.0 && e.pair_orders > 0.0);
    /* ... the media, the addings and doublings, the writing. */
    assert_true(e.phase_entries > 0.0 && e.add_entries > 0.0 && e.stored_values > 0.0);
    assert_true(e.measured_lookups == 0.0 && e.diffuse_entries == 0.0);
    assert_int_equal(e.threads, ll_get_thread_count());
    o.n_channels = 1;
    assert_int_equal(ll_material_estimate(m, &o, &e, NULL), LL_OK);
    assert_int_equal(e.layers_built, 3);
    assert_int_equal(e.additions, 2);
    e.struct_size = 0;
    assert_int_equal(ll_material_estimate(m, &o, &e, NULL), LL_ERROR_INVALID_ARGUMENT);
    ll_material_destroy(m);
}

static void bad_arguments_are_rejected(void **state)
{
    ll_material *m = parse("diffuse albedo=0.5");
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    ll_layer *layers[3] = { NULL, NULL, NULL };
    size_t n;
    char path[128];
    (void)state;
    snprintf(path, sizeof path, "%s/x.bsdf", tmpdir);
    assert_int_equal(ll_material_build(NULL, NULL, NULL, path), LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_material_build(m, NULL, NULL, NULL), LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_material_build(m, NULL, NULL, ""), LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_material_build_layers(m, NULL, NULL, NULL, &n, NULL),
                     LL_ERROR_INVALID_ARGUMENT);
    o.n_channels = 2;
    assert_int_equal(ll_material_build_layers(m, &o, NULL, layers, &n, NULL),
                     LL_ERROR_INVALID_ARGUMENT);
    o.n_channels = 0;
    o.error_goal = 2.0;
    assert_int_equal(ll_material_build(m, &o, NULL, path), LL_ERROR_INVALID_ARGUMENT);
    o.error_goal = 0.0;
    /* The resolution's messages say the real rule and name the count that
     * is wrong (an unset order count is no "0 orders"). */
    o.n_nodes = 101;
    assert_int_equal(ll_material_build(m, &o, NULL, path), LL_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(ll_last_error_message(), "an even count of at least 10"));
    o.n_nodes = 1000000;
    assert_int_equal(ll_material_build(m, &o, NULL, path), LL_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(ll_last_error_message(), "n_nodes = 1000000 is beyond the 100000"));
    assert_null(strstr(ll_last_error_message(), "orders"));
    o.n_nodes = 0;
    o.n_orders = 1000000;
    assert_int_equal(ll_material_build(m, &o, NULL, path), LL_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(ll_last_error_message(), "n_orders = 1000000 is beyond the 100000"));
    o.n_orders = 0;
    assert_int_equal(ll_material_write(m, NULL, layers, 2, path, NULL), LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_material_write(m, NULL, layers, 1, path, NULL), LL_ERROR_INVALID_ARGUMENT);
    /* A directory that does not exist: an I/O error naming it. */
    assert_int_equal(ll_material_build(m, NULL, NULL, "/nonexistent/dir/x.bsdf"), LL_ERROR_IO);
    assert_non_null(strstr(ll_last_error_message(), "/nonexistent/dir/x.bsdf"));
    ll_material_destroy(m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(examples_build_at_low_resolution),
        cmocka_unit_test(words_stack_top_to_bottom),
        cmocka_unit_test(rough_gold_matches_the_original_file),
        cmocka_unit_test(coated_gold_is_darker_than_bare_gold),
        cmocka_unit_test(channels_share_what_is_equal),
        cmocka_unit_test(measured_brdf_builds_under_a_coat),
        cmocka_unit_test(header_is_returned),
        cmocka_unit_test(progress_is_monotone_and_complete),
        cmocka_unit_test(cancel_leaves_no_file),
        cmocka_unit_test(thread_count_is_restored),
        cmocka_unit_test(estimate_counts_the_work),
        cmocka_unit_test(bad_arguments_are_rejected),
    };
    return cmocka_run_group_tests(tests, make_tmpdir, remove_tmpdir);
}
