/*
 * ll_bsdf_get_parameter_name (src/reader/bsdf_names.c): the names of a
 * textured file's parameters from the metadata's "parameters" array, the
 * default names "p0", "p1", ... for every other metadata, and hostile
 * metadata (cut, malformed, deeply nested, oversized) that must still open.
 *
 * One textured file (2 x 3 diffuse bases, parameters "coat.alpha" and
 * "base.alpha") is written once; each case replaces its metadata in memory
 * (the metadata is the file's last part, its length at header offset 32) and
 * opens the bytes with ll_bsdf_open_memory.
 */
#include "test_bsdf_util.h"

#define N_BASES 6
static unsigned char *g_file;      /* the file without its metadata */
static size_t g_body;              /* its length                    */

static void put_u32(unsigned char *p, size_t v)
{
    p[0] = (unsigned char)(v & 0xFF);
    p[1] = (unsigned char)((v >> 8) & 0xFF);
    p[2] = (unsigned char)((v >> 16) & 0xFF);
    p[3] = (unsigned char)((v >> 24) & 0xFF);
}

/* The textured file with metadata text[0 .. len), opened (must open). */
static ll_bsdf *open_with(const char *text, size_t len)
{
    unsigned char *bytes = malloc(g_body + len + 1);
    ll_bsdf *b = NULL;
    assert_non_null(bytes);
    memcpy(bytes, g_file, g_body);
    memcpy(bytes + g_body, text, len);
    put_u32(bytes + 32, len);
    if (ll_bsdf_open_memory(bytes, g_body + len, NULL, &b) != LL_OK)
        fail_msg("open with metadata of %zu bytes: %s", len, ll_last_error_message());
    free(bytes);
    return b;
}

static void expect_names(const char *text, size_t len, const char *n0, const char *n1)
{
    ll_bsdf *b = open_with(text, len);
    const char *name = NULL;
    assert_int_equal(ll_bsdf_get_parameter_name(b, 0, &name), LL_OK);
    assert_string_equal(name, n0);
    assert_int_equal(ll_bsdf_get_parameter_name(b, 1, &name), LL_OK);
    assert_string_equal(name, n1);
    ll_bsdf_release(b);
}

static void expect_default(const char *text)
{
    expect_names(text, strlen(text), "p0", "p1");
}

static int setup(void **state)
{
    ll_layer *layers[N_BASES];
    size_t counts[2] = { 2, 3 }, k, size;
    double positions[5] = { 0.1, 0.2, 0.0, 0.5, 1.0 };
    char path[600];
    ll_bsdf_write_options opts = LL_BSDF_WRITE_OPTIONS_INIT;
    unsigned char *bytes;
    size_t meta;
    ll_test_dir_setup(state);
    for (k = 0; k < N_BASES; ++k) {
        layers[k] = ll_test_layer(6, 1);
        assert_int_equal(ll_layer_set_diffuse(layers[k], 0.1 + 0.1 * (double)k, NULL), LL_OK);
    }
    opts.metadata = "{\"parameters\": [\"coat.alpha\", \"base.alpha\"]}";
    snprintf(path, sizeof path, "%s/named.bsdf", ll_test_dir());
    assert_int_equal(ll_bsdf_write_textured(path, (const ll_layer *const *)layers, 1, 2, counts,
                                            positions, &opts, NULL),
                     LL_OK);
    bytes = ll_test_read_file(path, &size);
    meta = (size_t)bytes[32] | (size_t)bytes[33] << 8 | (size_t)bytes[34] << 16 |
           (size_t)bytes[35] << 24;
    assert_int_equal(meta, strlen(opts.metadata));
    g_file = bytes;
    g_body = size - meta;
    /* The default writer's metadata ("parameters": 2, a count). */
    snprintf(path, sizeof path, "%s/default.bsdf", ll_test_dir());
    assert_int_equal(ll_bsdf_write_textured(path, (const ll_layer *const *)layers, 1, 2, counts,
                                            positions, NULL, NULL),
                     LL_OK);
    for (k = 0; k < N_BASES; ++k)
        ll_layer_destroy(layers[k]);
    return 0;
}

static int teardown(void **state)
{
    free(g_file);
    return ll_test_dir_teardown(state);
}

static void names_from_the_written_file(void **state)
{
    char path[600];
    ll_bsdf *b = NULL;
    const char *name = NULL;
    (void)state;
    snprintf(path, sizeof path, "%s/named.bsdf", ll_test_dir());
    assert_int_equal(ll_bsdf_open(path, NULL, &b), LL_OK);
    assert_int_equal(ll_bsdf_get_parameter_name(b, 0, &name), LL_OK);
    assert_string_equal(name, "coat.alpha");
    assert_int_equal(ll_bsdf_get_parameter_name(b, 1, &name), LL_OK);
    assert_string_equal(name, "base.alpha");
    /* Out of range and NULL arguments; the output is left alone. */
    name = "unchanged";
    assert_int_equal(ll_bsdf_get_parameter_name(b, 2, &name), LL_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(ll_last_error_message(), "parameter 2 does not exist"));
    assert_string_equal(name, "unchanged");
    assert_int_equal(ll_bsdf_get_parameter_name(b, 0, NULL), LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_bsdf_get_parameter_name(NULL, 0, &name), LL_ERROR_INVALID_ARGUMENT);
    ll_bsdf_release(b);
}

static void default_writer_gives_default_names(void **state)
{
    char path[600];
    ll_bsdf *b = NULL;
    const char *name = NULL;
    ll_bsdf_info info = LL_BSDF_INFO_INIT;
    (void)state;
    snprintf(path, sizeof path, "%s/default.bsdf", ll_test_dir());
    assert_int_equal(ll_bsdf_open(path, NULL, &b), LL_OK);
    assert_int_equal(ll_bsdf_get_info(b, &info), LL_OK);
    assert_non_null(strstr(info.metadata, "\"parameters\": 2"));
    assert_int_equal(ll_bsdf_get_parameter_name(b, 0, &name), LL_OK);
    assert_string_equal(name, "p0");
    assert_int_equal(ll_bsdf_get_parameter_name(b, 1, &name), LL_OK);
    assert_string_equal(name, "p1");
    ll_bsdf_release(b);
}

static void untextured_file_has_no_names(void **state)
{
    ll_bsdf *b = NULL;
    const char *name = NULL;
    (void)state;
    assert_int_equal(ll_bsdf_open(LL_TEST_GOLDEN, NULL, &b), LL_OK);
    assert_int_equal(ll_bsdf_get_parameter_name(b, 0, &name), LL_ERROR_INVALID_ARGUMENT);
    assert_null(name);
    ll_bsdf_release(b);
}

static void json_is_read_as_json(void **state)
{
    static const char nested[] =
        "{\"a\": {\"parameters\": [\"x\", \"y\"]}, \"s\": \"[{\\\"parameters\\\": ]\", "
        "\"n\": -1.5e3, \"t\": true, \"z\": null, \"e\": [], "
        "\"parameters\": [\"coat.alpha\",\"base.alpha\"], \"parameters\": [\"q\", \"r\"]}";
    (void)state;
    /* Keys in nested objects and inside strings are not top-level; the first
     * top-level "parameters" counts. */
    expect_names(nested, strlen(nested), "coat.alpha", "base.alpha");
    /* Whitespace of every kind, escapes decoded to UTF-8 (a surrogate pair). */
    expect_names(" \r\n\t{ \"parameters\" :\n[ \"co\\u00e4t\\/\\\"x\\\"\" ,\t\"\\ud83d\\ude00\\n\" ] }",
                 strlen(" \r\n\t{ \"parameters\" :\n[ \"co\\u00e4t\\/\\\"x\\\"\" ,\t"
                        "\"\\ud83d\\ude00\\n\" ] }"),
                 "co\xc3\xa4t/\"x\"", "\xf0\x9f\x98\x80\n");
}

static void deep_nesting_costs_no_recursion(void **state)
{
    /* 200000 nested arrays before the key: a recursive parser would run out
     * of stack; the bracket count skips them. */
    size_t depth = 200000, k, at = 0;
    const char *tail = ", \"parameters\": [\"a\", \"b\"]}";
    char *text = malloc(2 * depth + 16 + strlen(tail));
    (void)state;
    assert_non_null(text);
    memcpy(text, "{\"deep\": ", 9);
    at = 9;
    for (k = 0; k < depth; ++k)
        text[at++] = '[';
    for (k = 0; k < depth; ++k)
        text[at++] = ']';
    memcpy(text + at, tail, strlen(tail));
    at += strlen(tail);
    expect_names(text, at, "a", "b");
    /* Never closed: cut inside the nesting, default names. */
    expect_names(text, 9 + depth / 2, "p0", "p1");
    free(text);
}

static void malformed_metadata_gives_default_names(void **state)
{
    static const char *const cases[] = {
        "",
        "not json at all",
        "[\"coat.alpha\", \"base.alpha\"]",                 /* not an object       */
        "{\"parameters\": 2}",                              /* a count             */
        "{\"parameters\": \"coat.alpha\"}",                 /* a string            */
        "{\"parameters\": [\"a\"]}",                        /* too few             */
        "{\"parameters\": [\"a\", \"b\", \"c\"]}",          /* too many            */
        "{\"parameters\": []}",
        "{\"parameters\": [\"a\", 3]}",                     /* not a string        */
        "{\"parameters\": [\"a\", \"\"]}",                  /* empty name          */
        "{\"parameters\": [\"a\", \"a\"]}",                 /* duplicate           */
        "{\"parameters\": [\"a\" \"b\"]}",                  /* no comma            */
        "{\"parameters\": [\"a\", \"b\",]}",                /* trailing comma      */
        "{\"parameters\": [\"a\", \"b\"",                   /* cut after the array */
        "{\"parameters\": [\"a\", \"b",                     /* cut in a string     */
        "{\"parameters\": [\"a\\x\", \"b\"]}",              /* unknown escape      */
        "{\"parameters\": [\"a\\u12\", \"b\"]}",            /* short \\u           */
        "{\"parameters\": [\"a\\ud800\", \"b\"]}",          /* lone high surrogate */
        "{\"parameters\": [\"a\\udc00\", \"b\"]}",          /* lone low surrogate  */
        "{\"parameters\": [\"a\\u0000\", \"b\"]}",          /* NUL in a name       */
        "{\"parameters\": [\"a\tb\", \"b\"]}",              /* raw control char    */
        "{\"x\": \"unterminated, \"parameters\": [\"a\", \"b\"]}",
        "{\"x\" 1, \"parameters\": [\"a\", \"b\"]}",        /* no colon before     */
        "{\"x\": 1 \"parameters\": [\"a\", \"b\"]}",        /* no comma before     */
        "{\"x\": {\"parameters\": [\"a\", \"b\"]}}",        /* nested only         */
    };
    size_t k;
    (void)state;
    for (k = 0; k < sizeof cases / sizeof cases[0]; ++k)
        expect_default(cases[k]);
    /* Values before the key are skipped by counting brackets, not judged:
     * mismatched kinds still balance (the names are where they belong). */
    expect_names("{\"x\": [1, 2}, \"parameters\": [\"a\", \"b\"]}", 39, "a", "b");
}

static void name_length_limit(void **state)
{
    /* 255 bytes are accepted, 256 are not. */
    char text[700], name[300];
    (void)state;
    memset(name, 'n', 255);
    name[255] = '\0';
    snprintf(text, sizeof text, "{\"parameters\": [\"%s\", \"b\"]}", name);
    expect_names(text, strlen(text), name, "b");
    name[255] = 'n';
    name[256] = '\0';
    snprintf(text, sizeof text, "{\"parameters\": [\"%s\", \"b\"]}", name);
    expect_default(text);
}

static void every_cut_of_the_metadata_opens(void **state)
{
    /* Each prefix (and the text with a NUL byte at each place) opens; only
     * the whole text has the names. */
    const char *full = "{\"generator\": \"layerlab\", \"m\": [1, {\"k\": \"v\"}], "
                       "\"parameters\": [\"coat.alpha\", \"base.alpha\"]}";
    size_t len = strlen(full), k;
    char text[200];
    (void)state;
    for (k = 0; k < len; ++k) {
        const char *name = NULL;
        ll_bsdf *b = open_with(full, k);
        assert_int_equal(ll_bsdf_get_parameter_name(b, 1, &name), LL_OK);
        /* The closing brace is not needed once the array is complete. */
        assert_string_equal(name, k >= len - 1 ? "base.alpha" : "p1");
        ll_bsdf_release(b);
        memcpy(text, full, len);
        text[k] = '\0';
        b = open_with(text, len);
        assert_int_equal(ll_bsdf_get_parameter_name(b, 1, &name), LL_OK);
        assert_true(strcmp(name, "p1") == 0 || strcmp(name, "base.alpha") == 0);
        ll_bsdf_release(b);
    }
}

static void names_outlive_other_references(void **state)
{
    /* The name stays valid while b lives, through retain / release. */
    ll_bsdf *b = open_with("{\"parameters\": [\"u\", \"v\"]}", 26);
    const char *name = NULL;
    (void)state;
    ll_bsdf_retain(b);
    assert_int_equal(ll_bsdf_get_parameter_name(b, 1, &name), LL_OK);
    ll_bsdf_release(b);
    assert_string_equal(name, "v");
    ll_bsdf_release(b);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(names_from_the_written_file),
        cmocka_unit_test(default_writer_gives_default_names),
        cmocka_unit_test(untextured_file_has_no_names),
        cmocka_unit_test(json_is_read_as_json),
        cmocka_unit_test(deep_nesting_costs_no_recursion),
        cmocka_unit_test(malformed_metadata_gives_default_names),
        cmocka_unit_test(name_length_limit),
        cmocka_unit_test(every_cut_of_the_metadata_opens),
        cmocka_unit_test(names_outlive_other_references),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
