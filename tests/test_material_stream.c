/*
 * The streamed build: ll_material_build hands each channel's
 * finished stack to the file as soon as it is complete (writer/
 * bsdf_write_channels.c) and makes a channel's bottom word only when it is
 * needed. Its file must be byte for byte what building the layers and
 * writing them all at once gives, for any thread count and any sharing of
 * words and stacks between channels; channel_done must see every channel
 * once; a cancel while a channel goes to the file or while the file is
 * written must leave nothing (no file, no temporary, no spill) and keep an
 * existing file.
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <layerlab.h>
#include "test_util.h"

static ll_material *parse(const char *text)
{
    ll_material *m = NULL;
    if (ll_material_parse(text, "t", &m) != LL_OK)
        fail_msg("%s", ll_last_error_message());
    return m;
}

typedef struct seen {
    int count[3];
    size_t nodes;
} seen;

static void on_channel(void *user, size_t channel, const ll_layer *layer)
{
    seen *s = user;
    assert_true(channel < 3);
    assert_non_null(layer);
    s->count[channel]++;
    s->nodes = ll_layer_node_count(layer);
}

/* The material built both ways at (nodes, orders) on `threads` threads:
 * the two files must be the same bytes. */
static void same_bytes(const char *text, size_t nodes, size_t orders, size_t threads)
{
    ll_material *m = parse(text);
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    ll_layer *layers[3] = { NULL, NULL, NULL };
    size_t n_channels = 0, c, size_a, size_b;
    char a[600], b[600];
    unsigned char *bytes_a, *bytes_b;
    seen s;
    memset(&s, 0, sizeof s);
    snprintf(a, sizeof a, "%s/streamed.bsdf", ll_test_dir());
    snprintf(b, sizeof b, "%s/at-once.bsdf", ll_test_dir());
    o.n_nodes = nodes;
    o.n_orders = orders;
    o.threads = threads;
    o.channel_done = on_channel;
    o.channel_done_user = &s;
    if (ll_material_build(m, &o, NULL, a) != LL_OK)
        fail_msg("%s", ll_last_error_message());
    o.channel_done = NULL;
    assert_int_equal(ll_material_build_layers(m, &o, NULL, layers, &n_channels, NULL), LL_OK);
    assert_int_equal(ll_material_write(m, &o, layers, n_channels, b, NULL), LL_OK);
    for (c = 0; c < 3; ++c) {
        assert_int_equal(s.count[c], c < n_channels ? 1 : 0);
        ll_layer_destroy(layers[c]);
    }
    assert_int_equal(s.nodes, nodes);
    bytes_a = ll_test_read_file(a, &size_a);
    bytes_b = ll_test_read_file(b, &size_b);
    assert_int_equal(size_a, size_b);
    assert_memory_equal(bytes_a, bytes_b, size_a);
    free(bytes_a);
    free(bytes_b);
    remove(a);
    remove(b);
    /* Nothing else is left beside them (no temporary, no spill). */
    assert_int_equal(ll_test_count_entries(ll_test_dir()), 0);
    ll_material_destroy(m);
}

/* Channels with their own bottoms under a shared medium (the dust on gold's
 * shape), a grey stack (one channel's stack for all three), stacks that
 * part at the top or in the middle, one word, mono. */
static const char *const stacks[] = {
    "medium albedo=0.9 g=0.9 tau=4\n"
    "conductor eta=0.143+3.98i,0.373+2.39i,1.44+1.60i alpha=0.02\n",
    "dielectric eta=1.5 alpha=0.1\nmedium albedo=0.8 g=0.5 tau=1\ndiffuse albedo=0.5\n",
    "dielectric eta=1.5 alpha=0.1\nmedium albedo=0.8,0.8,0.5 g=0.5 tau=1\n"
    "diffuse albedo=0.5\n",
    "dielectric eta=1.5 alpha=0.2,0.1,0.2\nmedium albedo=0.8 g=0.5 tau=1\n"
    "diffuse albedo=0.5,0.2,0.5\n",
    "conductor eta=0.2+3i,0.4+2.4i,1.4+1.6i alpha=0.2\n",
    "set channels=1\ndielectric eta=1.5 alpha=0.1\nmedium albedo=0.7 g=0.3 tau=2\n"
    "diffuse albedo=0.5\n",
};

static void streamed_file_is_the_layers_file(void **state)
{
    size_t k, t;
    (void)state;
    for (t = 1; t <= 2; ++t)
        for (k = 0; k < sizeof stacks / sizeof stacks[0]; ++k)
            same_bytes(stacks[k], 24, 20, t);
}

/* The medium slab at a resolution where the streamed spill holds long
 * series (orders well past the medium's moments). */
static void streamed_file_with_long_series(void **state)
{
    (void)state;
    same_bytes(stacks[0], 60, 90, 2);
}

typedef struct stopper {
    int writing_reports; /* reports of stage "writing" so far */
    int stop_at;         /* stop at this one (1-based) */
    int stopped;
} stopper;

static int stop_in_writing(void *user, double fraction, const char *stage)
{
    stopper *s = user;
    (void)fraction;
    if (strcmp(stage, "writing") == 0 && ++s->writing_reports == s->stop_at) {
        s->stopped = 1;
        return 1;
    }
    return 0;
}

/* A stop at the first "writing" report (a channel going to the file) and
 * at the last ones (the file itself): LL_ERROR_CANCELLED, the old file
 * kept, nothing else left. */
static void cancel_while_streaming_leaves_nothing(void **state)
{
    ll_material *m = parse(stacks[0]);
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    ll_monitor mon = LL_MONITOR_INIT;
    stopper counter = { 0, 0, 0 };
    char path[600];
    unsigned char *old;
    size_t size;
    int reports, at;
    (void)state;
    o.n_nodes = 24;
    o.n_orders = 20;
    snprintf(path, sizeof path, "%s/out.bsdf", ll_test_dir());
    ll_test_write_file(path, "old file", 8);
    /* How many "writing" reports a whole build makes. */
    mon.progress = stop_in_writing;
    mon.user = &counter;
    counter.stop_at = -1;
    assert_int_equal(ll_material_build(m, &o, &mon, path), LL_OK);
    reports = counter.writing_reports;
    assert_true(reports >= 3);
    for (at = 1; at <= reports; at += reports - 1) {
        stopper s = { 0, 0, 0 };
        s.stop_at = at;
        ll_test_write_file(path, "old file", 8);
        mon.user = &s;
        assert_int_equal(ll_material_build(m, &o, &mon, path), LL_ERROR_CANCELLED);
        assert_true(s.stopped);
        assert_int_equal(ll_test_count_entries(ll_test_dir()), 1);
        old = ll_test_read_file(path, &size);
        assert_int_equal(size, 8);
        assert_memory_equal(old, "old file", 8);
        free(old);
    }
    remove(path);
    ll_material_destroy(m);
}

/* A file that cannot be created fails before any layer is built. */
static void unwritable_directory_fails_first(void **state)
{
    ll_material *m = parse(stacks[1]);
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    seen s;
    char path[600];
    (void)state;
    memset(&s, 0, sizeof s);
    o.n_nodes = 24;
    o.n_orders = 20;
    o.channel_done = on_channel;
    o.channel_done_user = &s;
    snprintf(path, sizeof path, "%s/no/such/dir/out.bsdf", ll_test_dir());
    assert_int_equal(ll_material_build(m, &o, NULL, path), LL_ERROR_IO);
    assert_non_null(strstr(ll_last_error_message(), "spill"));
    assert_int_equal(s.count[0] + s.count[1] + s.count[2], 0);
    ll_material_destroy(m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(streamed_file_is_the_layers_file),
        cmocka_unit_test(streamed_file_with_long_series),
        cmocka_unit_test(cancel_while_streaming_leaves_nothing),
        cmocka_unit_test(unwritable_directory_fails_first),
    };
    return cmocka_run_group_tests(tests, ll_test_dir_setup, ll_test_dir_teardown);
}
