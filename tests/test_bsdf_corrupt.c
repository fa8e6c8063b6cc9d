/*
 * Damaged files: every truncation of the golden file, each header field
 * set to 0, 1, huge and negative-as-float, offsets out of range, lengths
 * over the maximum order, NaN nodes, coefficients and CDF entries, version
 * 2, textured-parameter damage. Each is LL_ERROR_FORMAT (or UNSUPPORTED for
 * harmonic extrapolation) with a message naming the file and the field, and
 * nothing leaks (LeakSanitizer checks at exit under SANITIZE=1).
 */
#include "test_bsdf_util.h"
#include "reader/bsdf_format.h"

/* The golden file's layout (tests/data/README.md). */
enum {
    G_NODES = 64,
    G_N = 58,
    G_CDF = G_NODES + 4 * G_N,
    G_TABLE = G_CDF + 4 * G_N * G_N,
    G_COEFFS = G_TABLE + 8 * G_N * G_N,
    G_NCOEFFS = 41502,
    G_META = G_COEFFS + 4 * G_NCOEFFS,
    G_SIZE = G_META + 682
};

static unsigned char *g_gold;
static size_t g_size;
static char g_dir[512];

static int setup(void **state)
{
    (void)state;
    g_gold = ll_test_read_file(LL_TEST_GOLDEN, &g_size);
    assert_int_equal(g_size, G_SIZE);
    ll_test_mkdtemp(g_dir, sizeof g_dir);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    free(g_gold);
    ll_test_rmdir(g_dir);
    return 0;
}

static unsigned char *copy_gold(void)
{
    unsigned char *d = malloc(g_size + 16);
    assert_non_null(d);
    memcpy(d, g_gold, g_size);
    return d;
}

/* Opening must fail with `status`, leave *out NULL, and say `needle`. */
static void expect_status(const unsigned char *d, size_t n, ll_status status, const char *needle)
{
    static char sentinel;
    ll_bsdf *b = (ll_bsdf *)(void *)&sentinel; /* must be overwritten with NULL */
    ll_status s = ll_bsdf_open_memory(d, n, NULL, &b);
    if (s != status)
        fail_msg("status %d (wanted %d): %s", (int)s, (int)status, ll_last_error_message());
    assert_null(b);
    assert_non_null(strstr(ll_last_error_message(), "ll_bsdf_open: <memory>: "));
    if (needle && !strstr(ll_last_error_message(), needle))
        fail_msg("message \"%s\" does not mention \"%s\"", ll_last_error_message(), needle);
}

static void expect_format(const unsigned char *d, size_t n, const char *needle)
{
    expect_status(d, n, LL_ERROR_FORMAT, needle);
}

/* Opening succeeds and the file evaluates to something finite. */
static void expect_ok(const unsigned char *d, size_t n)
{
    ll_bsdf *b = NULL;
    ll_bsdf_info info = LL_BSDF_INFO_INIT;
    double wo[3] = { 0.3, 0.2, 0.9 }, wi[3] = { -0.2, -0.3, 0.9 }, rgb[3];
    float basis[8] = { 0.25f, 0.25f, 0.25f, 0.25f, 0.25f, 0.25f, 0.25f, 0.25f };
    if (ll_bsdf_open_memory(d, n, NULL, &b) != LL_OK)
        fail_msg("%s", ll_last_error_message());
    assert_int_equal(ll_bsdf_get_info(b, &info), LL_OK);
    assert_true(info.n_bases <= 8);
    assert_int_equal(ll_bsdf_eval_dir(b, wo, wi, LL_TRANSPORT_RADIANCE,
                                      info.n_bases > 1 ? basis : NULL, rgb),
                     LL_OK);
    assert_true(isfinite(rgb[0]) && isfinite(rgb[1]) && isfinite(rgb[2]));
    ll_bsdf_release(b);
}

static void put_u32(unsigned char *d, size_t at, uint32_t v) { ll_le_put_u32(d + at, v); }
static void put_f32(unsigned char *d, size_t at, float v) { ll_le_put_f32(d + at, v); }

/* ---------------------------------------------------------------- tests */

static void every_truncation(void **state)
{
    unsigned char *d = copy_gold();
    size_t n;
    (void)state;
    /* Every length short of the whole file (the header is checked against
     * the real size before anything is allocated, so this is quick). */
    for (n = 0; n < g_size; ++n) {
        ll_bsdf *b = NULL;
        ll_status s = ll_bsdf_open_memory(d, n, NULL, &b);
        if (s != LL_ERROR_FORMAT || b)
            fail_msg("length %zu: status %d", n, (int)s);
    }
    expect_format(d, 10, "truncated header");
    expect_format(d, G_CDF + 5, "truncated");
    expect_format(d, G_META + 3, "describes 207354 bytes but there are");
    d[g_size] = 0;
    expect_format(d, g_size + 1, "trailing bytes");
    expect_ok(d, g_size);
    free(d);
}

/* One truncation per part, through real files: the message names the path. */
static void truncated_files(void **state)
{
    static const size_t cuts[] = { 0, 5, 63, G_NODES + 7, G_CDF + 1001, G_TABLE + 8, G_COEFFS + 2,
                                   G_META + 100, G_SIZE - 1 };
    size_t k;
    char path[600];
    (void)state;
    snprintf(path, sizeof path, "%s/cut.bsdf", g_dir);
    for (k = 0; k < sizeof cuts / sizeof cuts[0]; ++k) {
        ll_bsdf *b = (ll_bsdf *)(void *)path;
        ll_test_write_file(path, g_gold, cuts[k]);
        assert_int_equal(ll_bsdf_open(path, NULL, &b), LL_ERROR_FORMAT);
        assert_null(b);
        assert_non_null(strstr(ll_last_error_message(), path));
    }
    ll_test_write_file(path, g_gold, g_size);
    {
        ll_bsdf *b = NULL;
        assert_int_equal(ll_bsdf_open(path, NULL, &b), LL_OK);
        ll_bsdf_release(b);
    }
}

typedef struct field_case {
    size_t at;
    uint32_t bits;
    ll_status expect;
    const char *needle;
} field_case;

#define NEG_ONE 0xBF800000u  /* -1.0f */
#define HUGE_U 0xFFFFFFFFu   /* also a NaN as a float */
#define BIG_F 0x7149F2CAu    /* 1e30f */
#define INF_F 0x7F800000u
#define ONE_F 0x3F800000u

static void header_fields(void **state)
{
    static const field_case cases[] = {
        /* flags */
        { 8, 0, LL_ERROR_FORMAT, "flags" },
        { 8, 1, LL_OK, NULL },
        { 8, HUGE_U, LL_ERROR_FORMAT, "unknown bits" },
        { 8, NEG_ONE, LL_ERROR_FORMAT, "flags" },
        { 8, 2, LL_ERROR_FORMAT, "bit 0" },
        { 8, 3, LL_ERROR_UNSUPPORTED, "harmonic extrapolation" },
        /* nNodes */
        { 12, 0, LL_ERROR_FORMAT, "nNodes = 0" },
        { 12, 1, LL_ERROR_FORMAT, "nNodes = 1" },
        { 12, HUGE_U, LL_ERROR_FORMAT, "nNodes 4294967295" },
        { 12, 0x7FFFFFFFu, LL_ERROR_FORMAT, "nNodes" },
        { 12, NEG_ONE, LL_ERROR_FORMAT, "nNodes" },
        { 12, 57, LL_ERROR_FORMAT, "nNodes 57" },
        { 12, 59, LL_ERROR_FORMAT, "nNodes 59" },
        /* nCoeffs */
        { 16, 0, LL_ERROR_FORMAT, "nCoeffs = 0" },
        { 16, 1, LL_ERROR_FORMAT, "nCoeffs = 1" },
        { 16, HUGE_U, LL_ERROR_FORMAT, "nCoeffs" },
        { 16, NEG_ONE, LL_ERROR_FORMAT, "nCoeffs" },
        { 16, G_NCOEFFS - 1, LL_ERROR_FORMAT, "nCoeffs" },
        /* nMaxOrder */
        { 20, 0, LL_ERROR_FORMAT, "nMaxOrder = 0" },
        { 20, 1, LL_ERROR_FORMAT, "nMaxOrder = 1" },
        { 20, HUGE_U, LL_ERROR_FORMAT, "exceeds nCoeffs" },
        { 20, NEG_ONE, LL_ERROR_FORMAT, "nMaxOrder" },
        { 20, 171, LL_ERROR_FORMAT, "exceeds nMaxOrder = 171" },
        { 20, 173, LL_ERROR_FORMAT, "longest series has 172" },
        /* nChannels */
        { 24, 0, LL_ERROR_FORMAT, "nChannels = 0" },
        { 24, 1, LL_ERROR_FORMAT, "nCoeffs" },
        { 24, 2, LL_ERROR_FORMAT, "nChannels = 2" },
        { 24, HUGE_U, LL_ERROR_FORMAT, "nChannels" },
        { 24, NEG_ONE, LL_ERROR_FORMAT, "nChannels" },
        /* nBases */
        { 28, 0, LL_ERROR_FORMAT, "nBases = 0" },
        { 28, 1, LL_OK, NULL },
        { 28, 2, LL_ERROR_FORMAT, "nBases = 2" },
        { 28, HUGE_U, LL_ERROR_FORMAT, "nBases" },
        { 28, NEG_ONE, LL_ERROR_FORMAT, "nBases" },
        /* nMetadataBytes */
        { 32, 0, LL_ERROR_FORMAT, "nMetadataBytes 0" },
        { 32, 1, LL_ERROR_FORMAT, "nMetadataBytes 1" },
        { 32, HUGE_U, LL_ERROR_FORMAT, "nMetadataBytes" },
        { 32, NEG_ONE, LL_ERROR_FORMAT, "nMetadataBytes" },
        { 32, 683, LL_ERROR_FORMAT, "truncated" },
        /* nParameters, nParameterValues */
        { 36, 0, LL_OK, NULL },
        { 36, 1, LL_ERROR_FORMAT, "nParameters" },
        { 36, HUGE_U, LL_ERROR_FORMAT, "nParameters" },
        { 36, NEG_ONE, LL_ERROR_FORMAT, "nParameters" },
        { 40, 0, LL_OK, NULL },
        { 40, 1, LL_ERROR_FORMAT, "nParameterValues = 1" },
        { 40, HUGE_U, LL_ERROR_FORMAT, "nParameterValues" },
        { 40, NEG_ONE, LL_ERROR_FORMAT, "nParameterValues" },
        /* eta (a float: the integer bit patterns are a zero, a denormal,
         * a NaN and -1) */
        { 44, 0, LL_ERROR_FORMAT, "eta = 0" },
        { 44, 1, LL_ERROR_FORMAT, "eta" },
        { 44, HUGE_U, LL_ERROR_FORMAT, "eta = " },
        { 44, NEG_ONE, LL_ERROR_FORMAT, "eta = -1" },
        { 44, BIG_F, LL_ERROR_FORMAT, "eta = 1e+30" },
        { 44, INF_F, LL_ERROR_FORMAT, "eta = inf" },
        { 44, ONE_F, LL_OK, NULL },
        { 44, 0x3FC00000u, LL_OK, NULL }, /* 1.5 */
        /* alpha (informational: any finite non-negative value) */
        { 48, 0, LL_OK, NULL },
        { 48, 1, LL_OK, NULL },
        { 48, ONE_F, LL_OK, NULL },
        { 48, HUGE_U, LL_ERROR_FORMAT, "alpha" },
        { 48, NEG_ONE, LL_ERROR_FORMAT, "alpha = (-1" },
        { 48, INF_F, LL_ERROR_FORMAT, "alpha" },
        { 52, HUGE_U, LL_ERROR_FORMAT, "alpha" },
        { 52, NEG_ONE, LL_ERROR_FORMAT, "alpha = (0, -1" },
        { 52, BIG_F, LL_OK, NULL },
        /* the unused pair is ignored, as pbrt-v3 ignores it */
        { 56, HUGE_U, LL_OK, NULL },
        { 60, NEG_ONE, LL_OK, NULL },
    };
    size_t k;
    (void)state;
    for (k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
        unsigned char *d = copy_gold();
        put_u32(d, cases[k].at, cases[k].bits);
        if (cases[k].expect == LL_OK)
            expect_ok(d, g_size);
        else
            expect_status(d, g_size, cases[k].expect, cases[k].needle);
        free(d);
    }
}

static void identifier_and_version(void **state)
{
    static const unsigned char versions[] = { 0, 3, 255 };
    unsigned char *d = copy_gold();
    size_t k;
    (void)state;
    d[LL_BSDF_AT_VERSION] = 2;
    expect_format(d, g_size, "version 2");
    assert_non_null(strstr(ll_last_error_message(), "not supported"));
    for (k = 0; k < sizeof versions; ++k) {
        d[LL_BSDF_AT_VERSION] = versions[k];
        expect_format(d, g_size, "version");
    }
    d[LL_BSDF_AT_VERSION] = 1;
    d[0] = 'X';
    expect_format(d, g_size, "SCATFUN");
    free(d);
}

/* A table entry (o, i) with a non-empty series. */
static size_t busy_entry(const unsigned char *d)
{
    size_t k;
    for (k = 0; k < G_N * G_N; ++k)
        if (ll_le_get_u32(d + G_TABLE + 8 * k + 4) > 3)
            return k;
    fail_msg("no busy entry");
    return 0;
}

static void offset_table(void **state)
{
    unsigned char *d = copy_gold();
    size_t k = busy_entry(d), empty;
    uint32_t len = ll_le_get_u32(d + G_TABLE + 8 * k + 4);
    (void)state;
    /* Offsets out of range. */
    put_u32(d, G_TABLE + 8 * k, G_NCOEFFS - 1);
    expect_format(d, g_size, "outside");
    put_u32(d, G_TABLE + 8 * k, HUGE_U);
    expect_format(d, g_size, "outside");
    put_u32(d, G_TABLE + 8 * k, G_NCOEFFS - 3 * len + 1);
    expect_format(d, g_size, "outside");
    memcpy(d, g_gold, g_size);
    /* A length over the maximum order. */
    put_u32(d, G_TABLE + 8 * k + 4, 173);
    expect_format(d, g_size, "exceeds nMaxOrder");
    put_u32(d, G_TABLE + 8 * k + 4, HUGE_U);
    expect_format(d, g_size, "exceeds nMaxOrder");
    memcpy(d, g_gold, g_size);
    /* A series appearing where there was none: the blocks no longer add up. */
    for (empty = 0; ll_le_get_u32(d + G_TABLE + 8 * empty + 4) != 0; ++empty)
        ;
    put_u32(d, G_TABLE + 8 * empty, 0);
    put_u32(d, G_TABLE + 8 * empty + 4, 2);
    expect_format(d, g_size, "nCoeffs");
    /* The same series twice (overlapping blocks) is harmless and accepted
     * only if the total still matches: it does not here. */
    memcpy(d, g_gold, g_size);
    put_u32(d, G_TABLE + 8 * k + 4, len - 1);
    expect_format(d, g_size, "nCoeffs");
    free(d);
}

static void nodes_coefficients_cdf(void **state)
{
    unsigned char *d = copy_gold();
    (void)state;
    put_f32(d, G_NODES + 4 * 10, NAN);
    expect_format(d, g_size, "node 10");
    memcpy(d, g_gold, g_size);
    put_f32(d, G_NODES + 4 * 57, INFINITY);
    expect_format(d, g_size, "node 57");
    memcpy(d, g_gold, g_size);
    put_f32(d, G_NODES + 4 * 57, 1.5f);
    expect_format(d, g_size, "node 57");
    memcpy(d, g_gold, g_size);
    put_f32(d, G_NODES + 4 * 20, 0.5f); /* not ascending */
    expect_format(d, g_size, "ascending");
    memcpy(d, g_gold, g_size);
    put_f32(d, G_NODES + 4 * 27, 0.0f); /* three zeros */
    expect_format(d, g_size, "three times");
    memcpy(d, g_gold, g_size);
    put_f32(d, G_NODES + 4 * 56, 1.0f); /* last two equal */
    expect_format(d, g_size, "coincide");
    memcpy(d, g_gold, g_size);

    put_f32(d, G_COEFFS + 4 * 1234, NAN);
    expect_format(d, g_size, "coefficient 1234");
    memcpy(d, g_gold, g_size);
    put_f32(d, G_COEFFS + 4 * (G_NCOEFFS - 1), -INFINITY);
    expect_format(d, g_size, "coefficient 41501");
    memcpy(d, g_gold, g_size);

    put_f32(d, G_CDF + 4 * (40 * G_N + 10), NAN);
    expect_format(d, g_size, "CDF row 40");
    memcpy(d, g_gold, g_size);
    put_f32(d, G_CDF + 4 * (40 * G_N + 57), 0.0f); /* decreasing at the end */
    expect_format(d, g_size, "CDF row 40");
    memcpy(d, g_gold, g_size);
    put_f32(d, G_CDF + 4 * (3 * G_N), 0.25f); /* not starting at 0 */
    expect_format(d, g_size, "CDF row 3");
    free(d);
}

/* A small textured file from the writer, then damaged parameters. */
static void textured_parameters(void **state)
{
    const size_t counts[2] = { 2, 2 };
    const double positions[4] = { 0.0, 1.0, 0.0, 1.0 };
    ll_layer *l = ll_test_layer(4, 1);
    const ll_layer *layers[4];
    char path[600];
    unsigned char *d;
    size_t size, k, at_counts, at_positions;
    (void)state;
    assert_int_equal(ll_layer_set_diffuse(l, 0.5, NULL), LL_OK);
    for (k = 0; k < 4; ++k)
        layers[k] = l;
    snprintf(path, sizeof path, "%s/textured.bsdf", g_dir);
    assert_int_equal(ll_bsdf_write_textured(path, layers, 1, 2, counts, positions, NULL, NULL), LL_OK);
    d = ll_test_read_file(path, &size);
    at_counts = 64 + 4 * 6;
    at_positions = at_counts + 8;
    expect_ok(d, size);

    put_u32(d, at_counts, 0);
    expect_format(d, size, "parameter 0 has 0 sample positions");
    put_u32(d, at_counts, 3);
    expect_format(d, size, "sample counts");
    put_u32(d, at_counts, 1);
    put_u32(d, at_counts + 4, 3);
    expect_format(d, size, "multiply to 3, not nBases = 4");
    put_u32(d, at_counts, 2);
    put_u32(d, at_counts + 4, 2);
    expect_ok(d, size);
    put_f32(d, at_positions + 4, NAN);
    expect_format(d, size, "parameter 0: sample position 1");
    put_f32(d, at_positions + 4, 0.0f);
    expect_format(d, size, "increasing");
    put_f32(d, at_positions + 4, 1.0f);
    put_u32(d, LL_BSDF_AT_BASES, 1); /* nBases vs the counts (and the CDF size) */
    expect_format(d, size, NULL);
    free(d);
    ll_layer_destroy(l);
}

static void io_and_arguments(void **state)
{
    ll_bsdf *b = (ll_bsdf *)(void *)g_dir;
    char path[600];
    (void)state;
    snprintf(path, sizeof path, "%s/does-not-exist.bsdf", g_dir);
    assert_int_equal(ll_bsdf_open(path, NULL, &b), LL_ERROR_IO);
    assert_null(b);
    assert_non_null(strstr(ll_last_error_message(), "does-not-exist.bsdf"));
    assert_int_equal(ll_bsdf_open(g_dir, NULL, &b), LL_ERROR_IO);
    assert_non_null(strstr(ll_last_error_message(), "not a regular file"));
    assert_int_equal(ll_bsdf_open(NULL, NULL, &b), LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_bsdf_open(path, NULL, NULL), LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_bsdf_open_memory(NULL, 10, NULL, &b), LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_bsdf_open_memory(g_gold, g_size, NULL, NULL), LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_bsdf_open_memory(NULL, 0, NULL, &b), LL_ERROR_FORMAT);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(every_truncation),
        cmocka_unit_test(truncated_files),
        cmocka_unit_test(header_fields),
        cmocka_unit_test(identifier_and_version),
        cmocka_unit_test(offset_table),
        cmocka_unit_test(nodes_coefficients_cdf),
        cmocka_unit_test(textured_parameters),
        cmocka_unit_test(io_and_arguments),
    };
    return cmocka_run_group_tests_name("bsdf_corrupt", tests, setup, teardown);
}
