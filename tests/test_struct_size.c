/*
 * Size-tagged public structs at every field boundary: a caller whose
 * struct_size is offsetof(some field) (an older header's struct) gets the
 * fields before it read or written, and the bytes from struct_size on are
 * neither read nor written. The bytes beyond are filled with a canary
 * (0xA5: as a size, more than any limit; as a double, negative; as a
 * pointer, not a valid one), so reading them makes the call fail or crash,
 * and writing them shows in the canary check.
 *  - Read structs (ll_bsdf_write_options into ll_bsdf_write,
 *    ll_build_options into the material calls, ll_microfacet into
 *    ll_layer_set_microfacet): a truncated struct behaves
 *    exactly like the full struct with the defaults beyond struct_size, and
 *    each field changes the outcome (so the comparison can fail).
 *  - Written structs (ll_bsdf_info, ll_build_estimate, the header of
 *    ll_material_build_layers): the bytes before struct_size are what a
 *    full-size caller gets, the rest keep the canary, and struct_size stays.
 */
#include "test_util.h"

#define CANARY 0xA5
#define SLACK 32

static const size_t write_options_ends[] = {
    sizeof(size_t), offsetof(ll_bsdf_write_options, alpha),
    offsetof(ll_bsdf_write_options, metadata), offsetof(ll_bsdf_write_options, error_goal),
    sizeof(ll_bsdf_write_options),
};
static const size_t info_ends[] = {
    sizeof(size_t),
    offsetof(ll_bsdf_info, max_order),
    offsetof(ll_bsdf_info, n_channels),
    offsetof(ll_bsdf_info, n_bases),
    offsetof(ll_bsdf_info, n_parameters),
    offsetof(ll_bsdf_info, n_coeffs),
    offsetof(ll_bsdf_info, eta),
    offsetof(ll_bsdf_info, alpha),
    offsetof(ll_bsdf_info, metadata),
    offsetof(ll_bsdf_info, metadata_size),
    offsetof(ll_bsdf_info, file_size),
    offsetof(ll_bsdf_info, flags),
    offsetof(ll_bsdf_info, format),
    offsetof(ll_bsdf_info, n_wavelengths),
    sizeof(ll_bsdf_info),
};
static const size_t build_options_ends[] = {
    sizeof(size_t),
    offsetof(ll_build_options, n_orders),
    offsetof(ll_build_options, n_channels),
    offsetof(ll_build_options, threads),
    offsetof(ll_build_options, tolerance),
    offsetof(ll_build_options, mu_min),
    offsetof(ll_build_options, error_goal),
    offsetof(ll_build_options, max_memory_bytes),
    offsetof(ll_build_options, channel_done),
    offsetof(ll_build_options, channel_done_user),
    offsetof(ll_build_options, cache_dir),
    sizeof(ll_build_options),
};
static const size_t estimate_ends[] = {
    sizeof(size_t),
    offsetof(ll_build_estimate, n_orders),
    offsetof(ll_build_estimate, n_channels),
    offsetof(ll_build_estimate, n_bases),
    offsetof(ll_build_estimate, threads),
    offsetof(ll_build_estimate, resolution_error),
    offsetof(ll_build_estimate, peak_bytes),
    offsetof(ll_build_estimate, file_bytes),
    offsetof(ll_build_estimate, max_memory_bytes),
    offsetof(ll_build_estimate, over_budget),
    offsetof(ll_build_estimate, layers_built),
    offsetof(ll_build_estimate, additions),
    offsetof(ll_build_estimate, doublings),
    offsetof(ll_build_estimate, dielectric_pairs),
    offsetof(ll_build_estimate, conductor_pairs),
    offsetof(ll_build_estimate, pair_orders),
    offsetof(ll_build_estimate, measured_lookups),
    offsetof(ll_build_estimate, measured_files),
    offsetof(ll_build_estimate, phase_entries),
    offsetof(ll_build_estimate, diffuse_entries),
    offsetof(ll_build_estimate, add_entries),
    offsetof(ll_build_estimate, add_empty_entries),
    offsetof(ll_build_estimate, stored_values),
    sizeof(ll_build_estimate),
};
static const size_t microfacet_ends[] = {
    sizeof(size_t),
    offsetof(ll_microfacet, eta_im),
    offsetof(ll_microfacet, alpha),
    offsetof(ll_microfacet, distribution),
    offsetof(ll_microfacet, compensate),
    offsetof(ll_microfacet, n_orders_internal),
    sizeof(ll_microfacet),
};
static const size_t monitor_ends[] = {
    sizeof(size_t),
    offsetof(ll_monitor, user),
    sizeof(ll_monitor),
};
static const size_t open_options_ends[] = {
    sizeof(size_t),
    offsetof(ll_open_options, max_order),
    offsetof(ll_open_options, max_nodes),
    sizeof(ll_open_options),
};
#define COUNT(a) (sizeof a / sizeof a[0])

/* A caller's struct of `size` bytes (struct_size = size) in a buffer with
 * the canary after it (and in it, before the fields are set). */
typedef struct caller {
    unsigned char bytes[256];
} caller;

static void *caller_init(caller *c, size_t size)
{
    assert_true(size + SLACK <= sizeof c->bytes);
    memset(c->bytes, CANARY, sizeof c->bytes);
    memcpy(c->bytes, &size, sizeof size);
    return c->bytes;
}

/* Copy the fields of full that lie before `size` into the caller's struct. */
static void caller_take(caller *c, const void *full, size_t size)
{
    memcpy(c->bytes + sizeof(size_t), (const unsigned char *)full + sizeof(size_t),
           size - sizeof(size_t));
}

static void assert_canary_from(const caller *c, size_t from, const char *what)
{
    size_t i;
    for (i = from; i < sizeof c->bytes; ++i)
        if (c->bytes[i] != CANARY)
            fail_msg("%s: byte %zu (struct_size %zu) was written", what, i, from);
}

/* The default (INIT) value of bytes beyond size, the given ones before:
 * what a full-size caller passes to mean the same as a truncated one. */
static void merge(void *out, const void *defaults, const void *given, size_t size, size_t full)
{
    memcpy(out, defaults, full);
    memcpy((unsigned char *)out + sizeof(size_t), (const unsigned char *)given + sizeof(size_t),
           size - sizeof(size_t));
}

static ll_layer *coated(double albedo)
{
    ll_layer *l = ll_test_layer(8, 4), *c = ll_test_layer(8, 4);
    assert_int_equal(ll_layer_set_diffuse(l, albedo, NULL), LL_OK);
    assert_int_equal(ll_test_set_microfacet(c, 1.5, 0.0, 0.3, 1, 0, NULL), LL_OK);
    assert_int_equal(ll_layer_add_to_top(l, c), LL_OK);
    ll_layer_destroy(c);
    return l;
}

/* -------------------------------------------------- ll_bsdf_write_options */

static unsigned char *write_and_read(const ll_layer *l, const ll_bsdf_write_options *o,
                                     size_t *size)
{
    char path[700];
    const ll_layer *one[1];
    unsigned char *data;
    one[0] = l;
    snprintf(path, sizeof path, "%s/w.bsdf", ll_test_dir());
    assert_int_equal(ll_bsdf_write(path, one, 1, o, NULL), LL_OK);
    data = ll_test_read_file(path, size);
    unlink(path);
    return data;
}

static void write_options_read_to_struct_size(void **state)
{
    ll_bsdf_write_options defaults = LL_BSDF_WRITE_OPTIONS_INIT, given = LL_BSDF_WRITE_OPTIONS_INIT,
                          full;
    ll_layer *l = coated(0.5);
    unsigned char *previous = NULL;
    size_t previous_size = 0, i;
    caller c;
    (void)state;
    given.eta = 1.33;
    given.alpha[0] = 0.2;
    given.alpha[1] = 0.3;
    given.metadata = "given metadata";
    given.error_goal = 0.3;
    for (i = 0; i < COUNT(write_options_ends); ++i) {
        size_t b = write_options_ends[i], got_size, want_size;
        ll_bsdf_write_options *opts = caller_init(&c, b);
        unsigned char *got, *want;
        caller_take(&c, &given, b);
        got = write_and_read(l, opts, &got_size);
        assert_canary_from(&c, b, "ll_bsdf_write");
        merge(&full, &defaults, &given, b, sizeof full);
        want = write_and_read(l, &full, &want_size);
        if (got_size != want_size || memcmp(got, want, got_size) != 0)
            fail_msg("ll_bsdf_write: struct_size %zu wrote another file than the full struct "
                     "with defaults beyond it", b);
        /* Each field read shows in the file. */
        if (previous && previous_size == got_size && memcmp(previous, got, got_size) == 0)
            fail_msg("ll_bsdf_write: the field ending at %zu made no difference", b);
        free(previous);
        free(want);
        previous = got;
        previous_size = got_size;
    }
    free(previous);
    ll_layer_destroy(l);
}

static void write_options_below_struct_size_field(void **state)
{
    ll_layer *l = coated(0.5);
    const ll_layer *one[1];
    char path[700];
    caller c;
    size_t b;
    (void)state;
    one[0] = l;
    snprintf(path, sizeof path, "%s/never.bsdf", ll_test_dir());
    for (b = 0; b < sizeof(size_t); b += 4) {
        ll_bsdf_write_options *opts = caller_init(&c, b);
        assert_int_equal(ll_bsdf_write(path, one, 1, opts, NULL), LL_ERROR_INVALID_ARGUMENT);
        assert_non_null(strstr(ll_last_error_message(), "struct_size"));
        assert_int_equal(access(path, F_OK), -1);
    }
    ll_layer_destroy(l);
}

/* ----------------------------------------------------------- ll_bsdf_info */

static void info_written_to_struct_size(void **state)
{
    char path[700];
    ll_layer *l = coated(0.5);
    const ll_layer *one[1];
    ll_bsdf *f = NULL;
    caller full_c, c;
    size_t i;
    (void)state;
    one[0] = l;
    snprintf(path, sizeof path, "%s/info.bsdf", ll_test_dir());
    assert_int_equal(ll_bsdf_write(path, one, 1, NULL, NULL), LL_OK);
    assert_int_equal(ll_bsdf_open(path, NULL, &f), LL_OK);
    assert_int_equal(ll_bsdf_get_info(f, caller_init(&full_c, sizeof(ll_bsdf_info))), LL_OK);
    assert_canary_from(&full_c, sizeof(ll_bsdf_info), "ll_bsdf_get_info");
    for (i = 0; i < COUNT(info_ends); ++i) {
        size_t b = info_ends[i];
        assert_int_equal(ll_bsdf_get_info(f, caller_init(&c, b)), LL_OK);
        assert_memory_equal(c.bytes, &b, sizeof b);
        assert_memory_equal(c.bytes + sizeof b, full_c.bytes + sizeof b, b - sizeof b);
        assert_canary_from(&c, b, "ll_bsdf_get_info");
    }
    for (i = 0; i < sizeof(size_t); i += 4) {
        assert_int_equal(ll_bsdf_get_info(f, caller_init(&c, i)), LL_ERROR_INVALID_ARGUMENT);
        assert_canary_from(&c, sizeof(size_t), "ll_bsdf_get_info");
    }
    ll_bsdf_release(f);
    unlink(path);
    ll_layer_destroy(l);
}

/* ------------------------------------------------------- ll_build_options */

static const char material_text[] = "set nodes=10 orders=4\n"
                                    "dielectric eta=1.5 alpha=0.3\n"
                                    "medium albedo=0.9 g=0.5 tau=0.5\n"
                                    "diffuse albedo=0.5\n";

/* What the build's monitor saw (whether it was called, not how often:
 * with several threads that depends on which thread finishes which order):
 * the thread count the options set for the build. */
typedef struct seen {
    size_t called;
    size_t threads;
    void *user;
} seen;
static seen progress_seen;

static int on_progress(void *user, double fraction, const char *stage)
{
    (void)fraction;
    (void)stage;
    progress_seen.called = 1;
    progress_seen.threads = ll_get_thread_count();
    progress_seen.user = user;
    return 0;
}

/* Everything the options change, in one comparable record. */
typedef struct outcome {
    ll_status resolution_status, estimate_status, build_status;
    size_t n_nodes, n_orders, n_channels;
    ll_build_estimate estimate;
    size_t built_channels, built_nodes, built_orders;
    double error_goal;
    seen progress;
    ll_status goal_status;     /* ll_material_goal: the resolution's goal */
    double tolerance, mu_min;
    int chosen;
    ll_status file_status;     /* ll_material_build */
    seen channels;             /* what channel_done saw there */
    ll_status searched_status; /* a searched resolution (cache_dir) */
    size_t cache_entries;      /* what it left in the cache directory */
} outcome;

/* The cache of chosen resolutions (cache_dir) shows only where a search
 * runs: a material with no resolution set and one cheap search (an HG
 * medium's), resolved with the caller's options less the resolution, and
 * the directory the options name. */
static ll_material *searched_material;
static char cache_dir[600];

static seen channels_seen;

static void on_channel_done(void *user, size_t channel, const ll_layer *layer)
{
    channels_seen.called += channel + 1 + ll_layer_node_count(layer);
    channels_seen.user = user;
}

static void run_material(const ll_material *m, const ll_build_options *o, outcome *out)
{
    ll_layer *layers[3] = { NULL, NULL, NULL };
    ll_bsdf_write_options header = LL_BSDF_WRITE_OPTIONS_INIT;
    ll_monitor monitor = LL_MONITOR_INIT;
    static int monitor_tag;
    size_t c;
    monitor.progress = on_progress;
    monitor.user = &monitor_tag;
    memset(out, 0, sizeof *out);
    out->estimate.struct_size = sizeof out->estimate;
    out->resolution_status =
        ll_material_resolution(m, o, NULL, &out->n_nodes, &out->n_orders, &out->n_channels);
    out->estimate_status = ll_material_estimate(m, o, &out->estimate, NULL);
    out->goal_status = ll_material_goal(m, o, &out->tolerance, &out->mu_min, &out->chosen);
    memset(&progress_seen, 0, sizeof progress_seen);
    out->build_status =
        ll_material_build_layers(m, o, &monitor, layers, &out->built_channels, &header);
    out->progress = progress_seen;
    if (out->build_status == LL_OK) {
        out->built_nodes = ll_layer_node_count(layers[0]);
        out->built_orders = ll_layer_order_count(layers[0]);
        out->error_goal = header.error_goal;
    }
    for (c = 0; c < 3; ++c)
        ll_layer_destroy(layers[c]);
    {
        char dir[64], path[96];
        ll_test_mkdtemp(dir, sizeof dir);
        snprintf(path, sizeof path, "%s/out.bsdf", dir);
        memset(&channels_seen, 0, sizeof channels_seen);
        out->file_status = ll_material_build(m, o, NULL, path);
        out->channels = channels_seen;
        ll_test_rmdir(dir);
    }
    {
        ll_build_options searched = LL_BUILD_OPTIONS_INIT;
        size_t n, k, ch;
        memcpy(&searched, o, o->struct_size);
        searched.n_nodes = searched.n_orders = 0; /* (read only if within struct_size) */
        out->searched_status =
            ll_material_resolution(searched_material, &searched, NULL, &n, &k, &ch);
        out->cache_entries = access(cache_dir, F_OK) == 0 ? ll_test_count_entries(cache_dir) : 0;
    }
}

static void build_options_read_to_struct_size(void **state)
{
    static int channel_tag;
    ll_build_options defaults = LL_BUILD_OPTIONS_INIT, given = LL_BUILD_OPTIONS_INIT, full;
    ll_material *m = NULL;
    outcome got, want, previous;
    caller c;
    size_t i;
    (void)state;
    assert_int_equal(ll_material_parse(material_text, "sizes.layers", &m), LL_OK);
    /* Every given value differs from the material's settings and the
     * defaults; the calling thread runs one worker, the options ask 3. */
    assert_int_equal(ll_set_thread_count(1), LL_OK);
    given.n_nodes = 12;
    given.n_orders = 3;
    given.n_channels = 3;
    given.threads = 3;
    given.error_goal = 0.25;
    /* A budget that the build fits in, unlike no other: the estimate
     * reports it. */
    given.max_memory_bytes = (size_t)1 << 40;
    /* The resolution's goal (ignored by the build, whose resolution is
     * given, but reported by ll_material_goal). */
    given.tolerance = 0.05;
    given.mu_min = 0.2;
    /* The streamed file build's channels. */
    given.channel_done = on_channel_done;
    given.channel_done_user = &channel_tag;
    /* Where the searched material's choice is remembered. */
    assert_int_equal(ll_material_parse("medium albedo=0.9 g=0.5 tau=0.5\ndiffuse albedo=0.5\n",
                                       "searched.layers", &searched_material),
                     LL_OK);
    ll_test_mkdtemp(cache_dir, sizeof cache_dir);
    given.cache_dir = cache_dir;
    for (i = 0; i < COUNT(build_options_ends); ++i) {
        size_t b = build_options_ends[i];
        ll_build_options *opts = caller_init(&c, b);
        caller_take(&c, &given, b);
        run_material(m, opts, &got);
        assert_canary_from(&c, b, "the material calls");
        merge(&full, &defaults, &given, b, sizeof full);
        run_material(m, &full, &want);
        if (memcmp(&got, &want, sizeof got) != 0)
            fail_msg("build options: struct_size %zu changed the outcome against the full "
                     "struct with defaults beyond it", b);
        assert_int_equal(got.resolution_status, LL_OK);
        assert_int_equal(got.estimate_status, LL_OK);
        assert_int_equal(got.build_status, LL_OK);
        if (i > 0 && memcmp(&got, &previous, sizeof got) == 0)
            fail_msg("build options: the field ending at %zu made no difference", b);
        previous = got;
    }
    assert_int_equal(ll_get_thread_count(), 1);
    ll_test_rmdir(cache_dir);
    ll_material_destroy(searched_material);
    for (i = 0; i < sizeof(size_t); i += 4) {
        size_t n, o, ch;
        assert_int_equal(ll_material_resolution(m, caller_init(&c, i), NULL, &n, &o, &ch),
                         LL_ERROR_INVALID_ARGUMENT);
        assert_non_null(strstr(ll_last_error_message(), "struct_size"));
    }
    assert_int_equal(ll_set_thread_count(0), LL_OK);
    ll_material_destroy(m);
}

/* ------------------------------- ll_build_estimate and the build header */

static void estimate_and_header_written_to_struct_size(void **state)
{
    ll_material *m = NULL;
    ll_layer *layers[3];
    caller full_c, c;
    size_t i, n, k;
    (void)state;
    assert_int_equal(ll_material_parse(material_text, "sizes.layers", &m), LL_OK);
    /* ll_build_estimate: every older, smaller struct is accepted. */
    assert_int_equal(ll_material_estimate(m, NULL, caller_init(&full_c, sizeof(ll_build_estimate)), NULL),
                     LL_OK);
    for (i = 0; i < COUNT(estimate_ends); ++i) {
        size_t b = estimate_ends[i];
        assert_int_equal(ll_material_estimate(m, NULL, caller_init(&c, b), NULL), LL_OK);
        assert_memory_equal(c.bytes, &b, sizeof b);
        assert_memory_equal(c.bytes + sizeof b, full_c.bytes + sizeof b, b - sizeof b);
        assert_canary_from(&c, b, "ll_material_estimate");
    }
    for (i = 0; i < sizeof(size_t); i += 4) {
        assert_int_equal(ll_material_estimate(m, NULL, caller_init(&c, i), NULL),
                         LL_ERROR_INVALID_ARGUMENT);
        assert_canary_from(&c, sizeof(size_t), "ll_material_estimate");
    }
    /* The header of ll_material_build_layers. */
    assert_int_equal(ll_material_build_layers(m, NULL, NULL, layers, &n,
                                              caller_init(&full_c, sizeof(ll_bsdf_write_options))),
                     LL_OK);
    for (k = 0; k < n; ++k)
        ll_layer_destroy(layers[k]);
    for (i = 0; i < COUNT(write_options_ends); ++i) {
        size_t b = write_options_ends[i];
        assert_int_equal(ll_material_build_layers(m, NULL, NULL, layers, &n, caller_init(&c, b)), LL_OK);
        for (k = 0; k < n; ++k)
            ll_layer_destroy(layers[k]);
        assert_memory_equal(c.bytes, &b, sizeof b);
        assert_memory_equal(c.bytes + sizeof b, full_c.bytes + sizeof b, b - sizeof b);
        assert_canary_from(&c, b, "ll_material_build_layers header");
    }
    assert_int_equal(ll_material_build_layers(m, NULL, NULL, layers, &n, caller_init(&c, 4)),
                     LL_ERROR_INVALID_ARGUMENT);
    ll_material_destroy(m);
}

/* The boundaries listed here are all the fields: they end where the next
 * begins, and the last at sizeof (a field added to a struct without a line
 * here fails this). */
static void every_field_is_listed(void **state)
{
    (void)state;
    assert_int_equal(COUNT(write_options_ends), 5);
    assert_int_equal(COUNT(info_ends), 15);
    assert_int_equal(COUNT(build_options_ends), 12);
    assert_int_equal(COUNT(estimate_ends), 24);
    assert_int_equal(COUNT(microfacet_ends), 7);
    assert_int_equal(COUNT(monitor_ends), 3);
    assert_int_equal(COUNT(open_options_ends), 4);
    assert_int_equal(offsetof(ll_bsdf_write_options, error_goal) + sizeof(double),
                     sizeof(ll_bsdf_write_options));
    assert_int_equal(offsetof(ll_build_options, channel_done_user) + sizeof(void *),
                     offsetof(ll_build_options, cache_dir));
    assert_int_equal(offsetof(ll_build_options, cache_dir) + sizeof(const char *),
                     sizeof(ll_build_options));
    assert_true(offsetof(ll_build_estimate, over_budget) + sizeof(int) <=
                    offsetof(ll_build_estimate, layers_built) &&
                offsetof(ll_build_estimate, over_budget) + 8 >=
                    offsetof(ll_build_estimate, layers_built));
    assert_int_equal(offsetof(ll_build_estimate, stored_values) + sizeof(double),
                     sizeof(ll_build_estimate));
    assert_int_equal(offsetof(ll_microfacet, n_orders_internal) + sizeof(size_t),
                     sizeof(ll_microfacet));
    assert_int_equal(offsetof(ll_monitor, user) + sizeof(void *), sizeof(ll_monitor));
    assert_int_equal(offsetof(ll_open_options, max_nodes) + sizeof(size_t),
                     sizeof(ll_open_options));
    assert_int_equal(offsetof(ll_bsdf_info, flags) + sizeof(uint32_t),
                     offsetof(ll_bsdf_info, format));
    assert_true(offsetof(ll_bsdf_info, format) + sizeof(uint32_t) <=
                    offsetof(ll_bsdf_info, n_wavelengths) &&
                offsetof(ll_bsdf_info, format) + 8 >= offsetof(ll_bsdf_info, n_wavelengths));
    assert_int_equal(offsetof(ll_bsdf_info, n_wavelengths) + sizeof(size_t),
                     sizeof(ll_bsdf_info));
}

/* ------------------------------------------------------- ll_microfacet */

/* Every matrix entry of the interface a microfacet makes, and the status. */
#define MF_NODES 12
#define MF_ORDERS 4
typedef struct interface_outcome {
    ll_status status;
    double f[MF_ORDERS][MF_NODES * MF_NODES];
} interface_outcome;

static void run_interface(const ll_microfacet *mf, interface_outcome *out)
{
    ll_layer *l = ll_test_layer(MF_NODES, MF_ORDERS);
    size_t k;
    memset(out, 0, sizeof *out);
    out->status = ll_layer_set_microfacet(l, mf, NULL);
    for (k = 0; k < MF_ORDERS; ++k)
        assert_int_equal(ll_layer_matrix(l, k, out->f[k]), LL_OK);
    ll_layer_destroy(l);
}

static void microfacet_read_to_struct_size(void **state)
{
    ll_microfacet defaults = LL_MICROFACET_INIT, given = LL_MICROFACET_INIT, full;
    static interface_outcome got, want, previous;
    caller c;
    size_t i;
    (void)state;
    /* Every given value differs from the default: a GGX conductor, rough,
     * uncompensated, resolved with more orders than the layer's. */
    given.eta_re = 1.3;
    given.eta_im = 0.5;
    given.alpha = 0.5;
    given.distribution = LL_MICROFACET_GGX;
    given.compensate = 0;
    given.n_orders_internal = 40;
    for (i = 0; i < COUNT(microfacet_ends); ++i) {
        size_t b = microfacet_ends[i];
        ll_microfacet *mf = caller_init(&c, b);
        caller_take(&c, &given, b);
        run_interface(mf, &got);
        assert_canary_from(&c, b, "ll_layer_set_microfacet");
        merge(&full, &defaults, &given, b, sizeof full);
        run_interface(&full, &want);
        assert_int_equal(got.status, LL_OK);
        if (memcmp(&got, &want, sizeof got) != 0)
            fail_msg("microfacet: struct_size %zu changed the layer against the full struct "
                     "with defaults beyond it", b);
        if (i > 0 && memcmp(&got, &previous, sizeof got) == 0)
            fail_msg("microfacet: the field ending at %zu made no difference", b);
        previous = got;
    }
    /* A distribution that is none of ll_microfacet_distribution's. */
    full = given;
    full.distribution = 7;
    run_interface(&full, &got);
    assert_int_equal(got.status, LL_ERROR_INVALID_ARGUMENT);
    for (i = 0; i < sizeof(size_t); i += 4) {
        run_interface(caller_init(&c, i), &got);
        assert_int_equal(got.status, LL_ERROR_INVALID_ARGUMENT);
    }
}

/* ---------------------------------------------------------- ll_monitor */

static size_t calls_without_user;

static int count_call(void *user, double fraction, const char *stage)
{
    (void)fraction;
    (void)stage;
    if (user)
        ++*(size_t *)user;
    else
        ++calls_without_user;
    return 0;
}

/* The monitor is read up to its struct_size: without `progress` no call,
 * without `user` the calls get NULL; the canary past it would be a wild
 * pointer if it were read. */
static void monitor_read_to_struct_size(void **state)
{
    ll_monitor given = LL_MONITOR_INIT;
    size_t calls = 0, i;
    caller c;
    (void)state;
    given.progress = count_call;
    given.user = &calls;
    for (i = 0; i < COUNT(monitor_ends); ++i) {
        size_t b = monitor_ends[i];
        ll_layer *l = ll_test_layer(8, 4);
        ll_monitor *m = caller_init(&c, b);
        caller_take(&c, &given, b);
        calls = calls_without_user = 0;
        assert_int_equal(ll_layer_set_henyey_greenstein(l, 0.9, 0.5, NULL), LL_OK);
        assert_int_equal(ll_layer_expand(l, 1.0, m), LL_OK);
        assert_canary_from(&c, b, "ll_layer_expand_ex monitor");
        if (b < offsetof(ll_monitor, user)) {
            assert_int_equal(calls + calls_without_user, 0);
        } else if (b < sizeof(ll_monitor)) {
            assert_int_equal(calls, 0);
            assert_true(calls_without_user > 0);
        } else {
            assert_true(calls > 0);
            assert_int_equal(calls_without_user, 0);
        }
        ll_layer_destroy(l);
    }
    {
        ll_layer *l = ll_test_layer(8, 4);
        assert_int_equal(ll_layer_expand(l, 1.0, caller_init(&c, 4)), LL_ERROR_INVALID_ARGUMENT);
        assert_non_null(strstr(ll_last_error_message(), "LL_MONITOR_INIT"));
        ll_layer_destroy(l);
    }
}

/* ---------------------------------------------------- ll_open_options */

/* Each limit applies exactly when struct_size covers it (the golden file
 * is 207 KB, holds 71 nodes and series up to 36 terms). */
static void open_options_read_to_struct_size(void **state)
{
    ll_open_options given = LL_OPEN_OPTIONS_INIT;
    size_t i;
    caller c;
    (void)state;
    for (i = 0; i < COUNT(open_options_ends); ++i) {
        size_t b = open_options_ends[i], field;
        for (field = 0; field < 3; ++field) {
            size_t end = offsetof(ll_open_options, max_bytes) + (field + 1) * sizeof(size_t);
            ll_bsdf *f = NULL;
            ll_status s;
            given.max_bytes = field == 0 ? 1000 : 0;
            given.max_order = field == 1 ? 2 : 0;
            given.max_nodes = field == 2 ? 4 : 0;
            caller_init(&c, b);
            caller_take(&c, &given, b);
            s = ll_bsdf_open(LL_SOURCE_DIR "/tests/data/roughgold_alpha_0.2.bsdf",
                             (const ll_open_options *)(const void *)c.bytes, &f);
            assert_canary_from(&c, b, "ll_bsdf_open options");
            if (b >= end) {
                assert_int_equal(s, LL_ERROR_UNSUPPORTED);
                assert_null(f);
            } else {
                assert_int_equal(s, LL_OK);
                ll_bsdf_release(f);
            }
        }
    }
    assert_int_equal(ll_bsdf_open(LL_SOURCE_DIR "/tests/data/roughgold_alpha_0.2.bsdf",
                                  (const ll_open_options *)(const void *)caller_init(&c, 0),
                                  &(ll_bsdf *){ NULL }),
                     LL_ERROR_INVALID_ARGUMENT);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(every_field_is_listed),
        cmocka_unit_test(write_options_read_to_struct_size),
        cmocka_unit_test(write_options_below_struct_size_field),
        cmocka_unit_test(info_written_to_struct_size),
        cmocka_unit_test(build_options_read_to_struct_size),
        cmocka_unit_test(estimate_and_header_written_to_struct_size),
        cmocka_unit_test(monitor_read_to_struct_size),
        cmocka_unit_test(microfacet_read_to_struct_size),
        cmocka_unit_test(open_options_read_to_struct_size),
    };
    return cmocka_run_group_tests_name("struct_size", tests, ll_test_dir_setup,
                                       ll_test_dir_teardown);
}
