/*
 * What a build refuses before it starts: the memory budget, the
 * caps of the resolution heuristics and of `set`, the smallest meaningful
 * resolution; estimates from counts alone for any input; the metadata
 * without comments and capped; the reason an unreadable material fails.
 */
/* sysconf(_SC_PHYS_PAGES), as the library reads it. */
#define _DEFAULT_SOURCE 1

#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <layerlab.h>
#include "material/material.h"
#include "test_util.h"

static ll_material *parse(const char *text)
{
    ll_material *m = NULL;
    if (ll_material_parse(text, "t", &m) != LL_OK)
        fail_msg("%s", ll_last_error_message());
    return m;
}

/* The resolution of text fails with status and a message holding what. */
static void expect_resolution_error(const char *text, const ll_build_options *o,
                                    ll_status status, const char *what)
{
    ll_material *m = parse(text);
    ll_build_estimate e = LL_BUILD_ESTIMATE_INIT;
    size_t n, k, c;
    ll_status s = ll_material_resolution(m, o, NULL, &n, &k, &c);
    if (s != status || !strstr(ll_last_error_message(), what))
        fail_msg("for\n%s\nexpected status %d and \"%s\", got %d: \"%s\"", text, status, what,
                 s, ll_last_error_message());
    /* The estimate and a build refuse it the same way. */
    assert_int_equal(ll_material_estimate(m, o, &e, NULL), status);
    ll_material_destroy(m);
}

/* A build over the budget is refused with the estimate, the budget and how
 * to raise it, and writes nothing; the same build fits a larger budget. */
static void budget_refuses_before_building(void **state)
{
    ll_material *m = parse("dielectric eta=1.5 alpha=0.3\ndiffuse albedo=0.5");
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    ll_build_estimate e = LL_BUILD_ESTIMATE_INIT;
    ll_layer *layers[3] = { NULL, NULL, NULL };
    size_t n = 7, c;
    char path[600];
    const char *msg;
    (void)state;
    snprintf(path, sizeof path, "%s/refused.bsdf", ll_test_dir());
    o.n_nodes = 40;
    o.n_orders = 20;
    o.max_memory_bytes = 1 << 20;
    assert_int_equal(ll_material_estimate(m, &o, &e, NULL), LL_OK);
    assert_true(e.peak_bytes > (double)o.max_memory_bytes);
    assert_true(e.over_budget);
    assert_int_equal(e.max_memory_bytes, o.max_memory_bytes);
    assert_int_equal(ll_material_build(m, &o, NULL, path), LL_ERROR_OUT_OF_MEMORY);
    msg = ll_last_error_message();
    assert_non_null(strstr(msg, "memory budget of 1 MiB"));
    assert_non_null(strstr(msg, "--max-memory"));
    assert_non_null(strstr(msg, "max_memory_bytes"));
    assert_non_null(strstr(msg, "40 nodes x 20 orders"));
    assert_int_equal(access(path, F_OK), -1);
    assert_int_equal(ll_material_build_layers(m, &o, NULL, layers, &n, NULL),
                     LL_ERROR_OUT_OF_MEMORY);
    assert_int_equal(n, 0);
    for (c = 0; c < 3; ++c)
        assert_null(layers[c]);
    o.max_memory_bytes = (size_t)e.peak_bytes + 1;
    assert_int_equal(ll_material_estimate(m, &o, &e, NULL), LL_OK);
    assert_false(e.over_budget);
    assert_int_equal(ll_material_build(m, &o, NULL, path), LL_OK);
    assert_int_equal(access(path, F_OK), 0);
    ll_material_destroy(m);
}

/* 0 is the default, half of the physical memory; an older options struct
 * (ending before max_memory_bytes) gets it too. */
static void budget_defaults_to_half_the_memory(void **state)
{
    ll_material *m = parse("diffuse albedo=0.5");
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    ll_build_estimate e = LL_BUILD_ESTIMATE_INIT;
    long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
    (void)state;
    assert_true(pages > 0 && page > 0);
    assert_int_equal(ll_material_estimate(m, NULL, &e, NULL), LL_OK);
    assert_int_equal(e.max_memory_bytes, (size_t)pages * (size_t)page / 2);
    assert_false(e.over_budget);
    o.max_memory_bytes = 12345; /* beyond the older struct: not read */
    o.struct_size = offsetof(ll_build_options, max_memory_bytes);
    assert_int_equal(ll_material_estimate(m, &o, &e, NULL), LL_OK);
    assert_int_equal(e.max_memory_bytes, (size_t)pages * (size_t)page / 2);
    ll_material_destroy(m);
}

/* Absurd resolutions are estimated from counts alone (no quadrature of
 * 100000 nodes, no 16 GB reserved) and refused. */
static void absurd_builds_are_estimated_and_refused(void **state)
{
    ll_material *m = parse("set nodes=100000 orders=100000\ndielectric eta=1.5 alpha=0.15\n"
                           "diffuse albedo=0.8,0.1,0.1");
    ll_build_estimate e = LL_BUILD_ESTIMATE_INIT;
    char path[600];
    (void)state;
    snprintf(path, sizeof path, "%s/absurd.bsdf", ll_test_dir());
    assert_int_equal(ll_material_estimate(m, NULL, &e, NULL), LL_OK);
    assert_int_equal(e.n_nodes, 100000);
    assert_true(e.over_budget);
    assert_true(e.peak_bytes > 1e12);
    assert_int_equal(ll_material_build(m, NULL, NULL, path), LL_ERROR_OUT_OF_MEMORY);
    assert_int_equal(access(path, F_OK), -1);
    ll_material_destroy(m);

    m = parse("set nodes=99998 orders=100000\nmedium albedo=0.5 tau=1 g=0.9999");
    assert_int_equal(ll_material_estimate(m, NULL, &e, NULL), LL_OK);
    assert_true(e.over_budget);
    ll_material_destroy(m);
}

/* The heuristics stop at |g| = 0.99 and kappa = 100, with an error naming
 * the largest supported value; at the cap they still answer. */
static void heuristics_are_capped(void **state)
{
    ll_material *m;
    size_t n, k, c;
    (void)state;
    expect_resolution_error("medium albedo=0.5 tau=1 g=0.9999", NULL,
                            LL_ERROR_INVALID_ARGUMENT, "the largest is |g| = 0.99");
    expect_resolution_error("medium albedo=0.5 tau=1 g=-0.99999999", NULL,
                            LL_ERROR_INVALID_ARGUMENT, "the largest is |g| = 0.99");
    expect_resolution_error("medium albedo=0.5 tau=1 phase=vmf kappa=10000", NULL,
                            LL_ERROR_INVALID_ARGUMENT, "the largest is kappa = 100");
    expect_resolution_error("medium albedo=0.5 tau=1 g=0.9999", NULL,
                            LL_ERROR_INVALID_ARGUMENT, "t:1:1: ");
    m = parse("medium albedo=0.5 tau=1 g=-0.99");
    assert_int_equal(ll_material_resolution(m, NULL, NULL, &n, &k, &c), LL_OK);
    assert_int_equal(n, 860);
    assert_int_equal(k, 539);
    ll_material_destroy(m);
    m = parse("medium albedo=0.5 tau=1 phase=vmf kappa=100");
    assert_int_equal(ll_material_resolution(m, NULL, NULL, &n, &k, &c), LL_OK);
    assert_true(n <= 860 && n > 800);
    ll_material_destroy(m);
    /* With the resolution given, a narrow lobe builds (or is estimated). */
    m = parse("set nodes=40 orders=30\nmedium albedo=0.5 tau=1 g=0.9999");
    assert_int_equal(ll_material_resolution(m, NULL, NULL, &n, &k, &c), LL_OK);
    assert_int_equal(n, 40);
    ll_material_destroy(m);
}

/* `set` accepts what the options accept: at most 100000 nodes or orders. */
static void settings_are_capped(void **state)
{
    ll_material *m = (ll_material *)1;
    (void)state;
    assert_int_equal(ll_material_parse("set nodes=999999998\ndiffuse albedo=0.5", "t", &m),
                     LL_ERROR_PARSE);
    assert_non_null(strstr(ll_last_error_message(), "t:1:11: nodes=999999998 is beyond the "
                                                    "100000 supported"));
    assert_null(m);
    assert_int_equal(ll_material_parse("set orders=100001\ndiffuse albedo=0.5", "t", &m),
                     LL_ERROR_PARSE);
    assert_non_null(strstr(ll_last_error_message(), "orders=100001 is beyond"));
    m = parse("set nodes=100000 orders=100000\ndiffuse albedo=0.5");
    ll_material_destroy(m);
}

/* Fewer than 10 nodes is refused with the reason, from `set` or the
 * options; the heuristics never ask for fewer. */
static void tiny_resolutions_are_refused(void **state)
{
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    ll_material *m;
    size_t n, k, c;
    (void)state;
    expect_resolution_error("set nodes=2 orders=1\ndiffuse albedo=0.5", NULL,
                            LL_ERROR_INVALID_ARGUMENT, "2 nodes is below the 10");
    expect_resolution_error("set nodes=8 orders=1\ndiffuse albedo=0.5", NULL,
                            LL_ERROR_INVALID_ARGUMENT, "quadrature's error");
    o.n_nodes = 4;
    expect_resolution_error("diffuse albedo=0.5", &o, LL_ERROR_INVALID_ARGUMENT,
                            "4 nodes is below the 10");
    m = parse("set nodes=10 orders=1\ndiffuse albedo=0.5");
    assert_int_equal(ll_material_resolution(m, NULL, NULL, &n, &k, &c), LL_OK);
    assert_int_equal(n, 10);
    ll_material_destroy(m);
    /* An index-matched interface asks for 2 nodes; the build gets 10. */
    m = parse("dielectric eta=1.5 alpha=0.3");
    assert_int_equal(ll_material_resolution(m, NULL, NULL, &n, &k, &c), LL_OK);
    assert_true(n >= 10);
    ll_material_destroy(m);
}

/* The metadata holds the material without comments; `#` inside quotes is
 * text. */
static void metadata_has_no_comments(void **state)
{
    ll_material *m = parse("# a secret note\nset nodes=20   # another\n\n"
                           "dielectric eta=1.5 alpha=0.3 # third\ndiffuse albedo=0.5\n");
    (void)state;
    assert_null(strstr(m->metadata, "secret"));
    assert_null(strstr(m->metadata, "another"));
    assert_null(strstr(m->metadata, "third"));
    assert_non_null(strstr(m->metadata, "\"material\": \"set nodes=20\\ndielectric eta=1.5 "
                                        "alpha=0.3\\ndiffuse albedo=0.5\\n\""));
    assert_non_null(strstr(m->metadata, "\"type\": \"dielectric\", \"eta\": 1.5"));
    ll_material_destroy(m);
}

/* A 3 MB comment adds nothing; a huge stack is described in at most
 * 64 KiB (the text, then the layers left out and their size said). */
static void metadata_is_capped(void **state)
{
    size_t big = 3 << 20, i, len;
    char *text = malloc(big + 64);
    ll_material *m;
    (void)state;
    assert_non_null(text);
    text[0] = '#';
    memset(text + 1, 'x', big);
    strcpy(text + 1 + big, "\ndiffuse albedo=0.5\n");
    m = parse(text);
    assert_true(strlen(m->metadata) < 1024);
    ll_material_destroy(m);

    /* 60000 media over a base: about 1.7 MB of text. */
    len = 0;
    for (i = 0; i < 60000; ++i)
        len += (size_t)sprintf(text + len, "medium albedo=0.5 tau=0.001\n");
    strcpy(text + len, "diffuse albedo=0.5\n");
    m = parse(text);
    assert_true(strlen(m->metadata) <= 65536);
    assert_non_null(strstr(m->metadata, "\"material_omitted\""));
    assert_non_null(strstr(m->metadata, "\"layer_count\": 60001"));
    ll_material_destroy(m);
    free(text);
}

/* A smaller ll_build_estimate (a struct_size that ends before the counts
 * of work, as a struct of another generation might) is accepted and
 * nothing past it is written. */
static void estimate_accepts_an_older_struct(void **state)
{
    ll_material *m = parse("dielectric eta=1.5 alpha=0.3\ndiffuse albedo=0.5");
    ll_build_estimate e;
    (void)state;
    memset(&e, 0xab, sizeof e);
    e.struct_size = offsetof(ll_build_estimate, layers_built);
    assert_int_equal(ll_material_estimate(m, NULL, &e, NULL), LL_OK);
    assert_true(e.peak_bytes > 0.0);
    assert_int_equal(e.struct_size, offsetof(ll_build_estimate, layers_built));
    {
        const unsigned char *past = (const unsigned char *)&e.layers_built;
        size_t k;
        for (k = 0; k < sizeof e - offsetof(ll_build_estimate, layers_built); ++k)
            assert_int_equal(past[k], 0xab);
    }
    /* Only a struct_size below the field itself is refused (one rule for
     * every size-tagged struct). */
    e.struct_size = sizeof(size_t) - 1;
    assert_int_equal(ll_material_estimate(m, NULL, &e, NULL), LL_ERROR_INVALID_ARGUMENT);
    ll_material_destroy(m);
}

/* An unreadable material says why, as strerror does. */
static void unreadable_material_says_why(void **state)
{
    ll_material *m = (ll_material *)1;
    (void)state;
    assert_int_equal(ll_material_parse_file("/nonexistent/x.layers", &m), LL_ERROR_IO);
    assert_null(m);
    assert_non_null(strstr(ll_last_error_message(), strerror(ENOENT)));
}

/* A layer's stored values, in bytes: less than the layer holds (its
 * segment tables come on top), so a lower bound of its share of a peak. */
static double stored_bytes(const ll_layer *l)
{
    return 8.0 * (double)ll_layer_stored_count(l);
}

/* The streamed build's estimate (ll_material_build hands each finished
 * channel to the writer and frees it; each channel's gold is made only
 * when needed) lies between what must be alive at once and the old
 * model, which held every channel's stack and the writer's staging: above
 * the medium word and one finished stack (both alive while that channel's
 * adding commits), below the all-stacks model by at least the two other
 * finished stacks it no longer holds. Measured layers, at a small size. */
static void streamed_estimate_is_between_one_stack_and_all(void **state)
{
    static const char stack[] =
        "set nodes=240 orders=480 channels=3\nmedium albedo=0.9 g=0.9 tau=4\n"
        "conductor eta=0.143+3.98i,0.373+2.39i,1.44+1.60i alpha=0.02\n";
    static const char medium[] = "set nodes=240 orders=480 channels=1\n"
                                 "medium albedo=0.9 g=0.9 tau=4\n";
    ll_material *m = parse(stack), *md = parse(medium);
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    ll_build_estimate e = LL_BUILD_ESTIMATE_INIT;
    ll_layer *layers[3] = { NULL, NULL, NULL }, *word[3] = { NULL, NULL, NULL };
    ll_word_params(*params)[3] = calloc(ll_material_word_count(m), sizeof *params);
    ll_cost_plan plan;
    double most = 0.0, others = 0.0, process = ll_cost_process_bytes();
    size_t nch = 0, one = 0, c;
    (void)state;
    assert_non_null(params);
    o.threads = 2;
    assert_int_equal(ll_material_build_layers(m, &o, NULL, layers, &nch, NULL), LL_OK);
    assert_int_equal(nch, 3);
    assert_int_equal(ll_material_build_layers(md, &o, NULL, word, &one, NULL), LL_OK);
    for (c = 0; c < nch; ++c)
        most = stored_bytes(layers[c]) > most ? stored_bytes(layers[c]) : most;
    for (c = 0; c < nch; ++c)
        others += stored_bytes(layers[c]);
    others -= most;
    assert_int_equal(ll_material_estimate(m, &o, &e, NULL), LL_OK);
    ll_material_params(m, 3, params);
    ll_material_cost(m, (const ll_word_params(*)[3])params, e.n_nodes, e.n_orders, 3, 2,
                     &plan);
    assert_true(plan.peak_bytes == e.peak_bytes);
    if (!(e.peak_bytes >= process + stored_bytes(word[0]) + most))
        fail_msg("the estimate %.0f is below the process, the medium and one stack: %.0f",
                 e.peak_bytes, process + stored_bytes(word[0]) + most);
    if (!(e.peak_bytes <= plan.held_peak_bytes - others))
        fail_msg("the estimate %.0f is not below the all-stacks model %.0f by the other "
                 "stacks' %.0f bytes",
                 e.peak_bytes, plan.held_peak_bytes, others);
    for (c = 0; c < 3; ++c) {
        ll_layer_destroy(layers[c]);
        ll_layer_destroy(word[c]);
    }
    free(params);
    ll_material_destroy(m);
    ll_material_destroy(md);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(budget_refuses_before_building),
        cmocka_unit_test(streamed_estimate_is_between_one_stack_and_all),
        cmocka_unit_test(budget_defaults_to_half_the_memory),
        cmocka_unit_test(absurd_builds_are_estimated_and_refused),
        cmocka_unit_test(heuristics_are_capped),
        cmocka_unit_test(settings_are_capped),
        cmocka_unit_test(tiny_resolutions_are_refused),
        cmocka_unit_test(metadata_has_no_comments),
        cmocka_unit_test(metadata_is_capped),
        cmocka_unit_test(estimate_accepts_an_older_struct),
        cmocka_unit_test(unreadable_material_says_why),
    };
    return cmocka_run_group_tests(tests, ll_test_dir_setup, ll_test_dir_teardown);
}
