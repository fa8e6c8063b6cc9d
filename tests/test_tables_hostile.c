/*
 * Hostile table files (docs/formats.md): truncated, wrong magic or
 * version, shapes that disagree, offsets outside the file, NaN and negative
 * values, absurd sizes, the max_bytes limit, random damage. Each gives a
 * clear error naming what is wrong, never a crash; the damaged bytes are a
 * small valid table written by ll_tables_write_from_bsdf. The same for a
 * transmissive (extended) table: its layout, eta and the fields of its
 * sets, which errors name with their prefix. A textured table file too:
 * its parameter block, its layout, each basis' fields named in full
 * (reader/tables_textured.c), and its float16 grids, as a transmissive
 * file's: a NaN, an infinity or a negative value there is refused as in a
 * float32 field, and float16 is refused outside those grids (the format's
 * fields, which Mitsuba's and pbrt-v4's `measured` read, are float32).
 */
#include "test_bsdf_util.h"
#include "support/support.h"

static unsigned char *good, *tgood, *rgood, *cgood;
static size_t good_size, tgood_size, rgood_size, cgood_size;
/* A textured table file (seven bases of one parameter, coat alpha 0.1 to
 * 0.22 over a conductor: more fields than an opaque file's writer ever
 * wrote), as tiny. */
static unsigned char *tex;
static size_t tex_size;

/* The table file of a material (built to NAME.bsdf, written to NAME.tab
 * with options o), as bytes; NULL when a step fails (a group fixture
 * returns a failure rather than asserting). */
static unsigned char *table_of(const char *text, const char *name, const ll_tables_options *o,
                               size_t *size)
{
    ll_material *m = NULL;
    ll_bsdf *src = NULL;
    char bsdf[600], path[600];
    ll_status s;
    snprintf(bsdf, sizeof bsdf, "%s/%s.bsdf", ll_test_dir(), name);
    snprintf(path, sizeof path, "%s/%s.tab", ll_test_dir(), name);
    s = ll_material_parse(text, name, &m);
    if (s == LL_OK)
        s = ll_material_build(m, NULL, NULL, bsdf);
    ll_material_destroy(m);
    if (s == LL_OK)
        s = ll_bsdf_open(bsdf, NULL, &src);
    if (s == LL_OK)
        s = ll_tables_write_from_bsdf(src, path, o, NULL);
    ll_bsdf_release(src);
    return s == LL_OK ? ll_test_read_file(path, size) : NULL;
}

static int setup(void **state)
{
    ll_bsdf *src = NULL;
    ll_tables_options o = LL_TABLES_OPTIONS_INIT;
    char path[600];
    ll_test_dir_setup(state);
    o.n_theta_i = 3;
    o.vndf_size = 4;
    o.sample_size = 3;
    snprintf(path, sizeof path, "%s/small.tab", ll_test_dir());
    if (ll_bsdf_open(LL_TEST_GOLDEN, NULL, &src) != LL_OK ||
        ll_tables_write_from_bsdf(src, path, &o, NULL) != LL_OK)
        return 1;
    ll_bsdf_release(src);
    good = ll_test_read_file(path, &good_size);
    /* A transmissive table: a small rough glass. */
    tgood = table_of("set nodes=12 orders=6\ndielectric eta=1.5 alpha=0.3\n", "glass", &o,
                     &tgood_size);
    /* One whose transmitted set from above is warped about the refraction
     * half vector and stored over its transmittance. */
    rgood = table_of("set nodes=24 orders=16\ndielectric eta=1.5 alpha=0.3 compensate=0\n",
                     "refracted", &o, &rgood_size);
    /* A coat over a medium without a base: its reflected set from below
     * is stored over F with a floor ("fresnel_floor"). */
    cgood = table_of("set nodes=12 orders=6\ndielectric eta=1.5 alpha=0.3\n"
                     "medium albedo=0.8,0.6,0.4 g=0.5 tau=0.5\n",
                     "coat", &o, &cgood_size);
    tex = table_of("set nodes=12 orders=6\n"
                   "dielectric name=coat eta=1.5 alpha=[0.1 0.12 0.14 0.16 0.18 0.2 0.22]\n"
                   "conductor eta=2+3i alpha=0.2\n",
                   "textured", &o, &tex_size);
    return good && tgood && rgood && cgood && tex ? 0 : 1;
}

static int teardown(void **state)
{
    free(good);
    free(tgood);
    free(rgood);
    free(cgood);
    free(tex);
    return ll_test_dir_teardown(state);
}

static uint64_t get_u64(const unsigned char *p)
{
    uint64_t v = 0;
    int k;
    for (k = 7; k >= 0; --k)
        v = (v << 8) | p[k];
    return v;
}

static void put_u64(unsigned char *p, uint64_t v)
{
    int k;
    for (k = 0; k < 8; ++k)
        p[k] = (unsigned char)(v >> (8 * k));
}

/* Where field name's entry keeps its offset and its first extent. */
static void locate(const unsigned char *d, const char *name, size_t *offset_at,
                   size_t *shape_at, size_t *rank)
{
    size_t at = 18, n = d[14] | (d[15] << 8), k;
    for (k = 0; k < n; ++k) {
        size_t len = d[at] | (d[at + 1] << 8);
        size_t r = d[at + 2 + len] | (d[at + 3 + len] << 8);
        if (len == strlen(name) && memcmp(d + at + 2, name, len) == 0) {
            *offset_at = at + 2 + len + 3;
            *shape_at = *offset_at + 8;
            *rank = r;
            return;
        }
        at += 2 + len + 2 + 1 + 8 + 8 * r;
    }
    fail_msg("no field %s", name);
}

/* Open a damaged copy from memory; expect status and a message with what. */
static void expect(const unsigned char *data, size_t size, ll_status status, const char *what)
{
    ll_bsdf *b = (ll_bsdf *)1;
    ll_status s = ll_bsdf_open_memory(data, size, NULL, &b);
    if (s != status || (what && !strstr(ll_last_error_message(), what)))
        fail_msg("status %d (%s), expected %d naming \"%s\"", (int)s, ll_last_error_message(),
                 (int)status, what ? what : "");
    assert_null(b);
}

/* A copy of a table file's bytes to damage. */
static unsigned char *copy_of(const unsigned char *bytes, size_t size)
{
    unsigned char *d = malloc(size);
    assert_non_null(d);
    memcpy(d, bytes, size);
    return d;
}

/* Random damage: copies of bytes with one to four bits flipped each, drawn
 * from seed. Whatever the bytes, an answer and no crash; what opens
 * evaluates and samples at wo to finite values. With weights, only a copy
 * that still has n_bases bases is evaluated, with those weights. Returns
 * how many copies opened. */
static int damage(const unsigned char *bytes, size_t size, uint64_t seed, int copies,
                  const double wo[3], const float *weights, size_t n_bases)
{
    uint64_t rng = seed;
    int k, j, opened = 0;
    for (k = 0; k < copies; ++k) {
        unsigned char *d = copy_of(bytes, size);
        ll_bsdf *b = NULL;
        int flips = 1 + (int)(ll_test_uniform(&rng) * 4);
        for (j = 0; j < flips; ++j)
            d[(size_t)(ll_test_uniform(&rng) * (double)size)] ^=
                (unsigned char)(1u << (int)(ll_test_uniform(&rng) * 8));
        if (ll_bsdf_open_memory(d, size, NULL, &b) == LL_OK) {
            double wi[3] = { -0.4, 0.0, 0.8 }, f[3], pdf, u[2];
            int evaluate = 1;
            ++opened;
            if (weights) {
                ll_bsdf_info info = LL_BSDF_INFO_INIT;
                assert_int_equal(ll_bsdf_get_info(b, &info), LL_OK);
                evaluate = info.n_bases == n_bases;
            }
            if (evaluate) {
                assert_int_equal(ll_bsdf_eval_dir(b, wo, wi, LL_TRANSPORT_RADIANCE, weights, f),
                                 LL_OK);
                assert_true(isfinite(f[0]) && isfinite(f[1]) && isfinite(f[2]));
                u[0] = ll_test_uniform(&rng);
                u[1] = ll_test_uniform(&rng);
                assert_int_equal(ll_bsdf_sample_dir(b, wo, u, LL_TRANSPORT_RADIANCE, weights, wi,
                                                    &pdf, f),
                                 LL_OK);
                assert_true(isfinite(pdf) && isfinite(f[0]) && isfinite(f[1]) &&
                            isfinite(f[2]));
            }
            ll_bsdf_release(b);
        }
        free(d);
    }
    return opened;
}

/* Out of memory at each allocation of opening bytes: the error, no handle,
 * every block freed again. Returns how many allocations an opening makes. */
static size_t open_out_of_memory(const unsigned char *bytes, size_t size)
{
    size_t n, k;
    ll_bsdf *b = NULL;
    ll_alloc_fail_after(0);
    assert_int_equal(ll_bsdf_open_memory(bytes, size, NULL, &b), LL_OK);
    ll_bsdf_release(b);
    n = ll_alloc_count();
    ll_alloc_hook_off();
    for (k = 1; k <= n; ++k) {
        ll_status s;
        long long live;
        b = (ll_bsdf *)1;
        ll_alloc_fail_after(k);
        s = ll_bsdf_open_memory(bytes, size, NULL, &b);
        live = ll_alloc_live();
        ll_alloc_hook_off();
        assert_int_equal(s, LL_ERROR_OUT_OF_MEMORY);
        assert_null(b);
        assert_true(live == 0);
    }
    return n;
}

static void test_good_opens(void **state)
{
    ll_bsdf *b = NULL;
    ll_bsdf_info info = LL_BSDF_INFO_INIT;
    (void)state;
    assert_int_equal(ll_bsdf_open_memory(good, good_size, NULL, &b), LL_OK);
    assert_int_equal(ll_bsdf_get_info(b, &info), LL_OK);
    assert_int_equal(info.format, LL_BSDF_FORMAT_TABLES);
    ll_bsdf_release(b);
}

static void test_truncated(void **state)
{
    size_t n;
    (void)state;
    for (n = 12; n < good_size; ++n) {
        ll_bsdf *b = NULL;
        assert_int_equal(ll_bsdf_open_memory(good, n, NULL, &b), LL_ERROR_FORMAT);
        assert_null(b);
    }
    expect(good, 17, LL_ERROR_FORMAT, "truncated header");
    expect(good, good_size - 1, LL_ERROR_FORMAT, "outside the file");
}

static void test_magic_and_version(void **state)
{
    unsigned char *d = copy_of(good, good_size);
    (void)state;
    d[12] = 2;
    expect(d, good_size, LL_ERROR_FORMAT, "version 2.0");
    d[12] = 1;
    d[13] = 1;
    expect(d, good_size, LL_ERROR_FORMAT, "version 1.1");
    d[13] = 0;
    d[0] = 'T';
    /* No longer a tensor file: read as a .bsdf, which it is not either. */
    expect(d, good_size, LL_ERROR_FORMAT, NULL);
    free(d);
}

/* A copy of bytes in which extent `extent` of field name's shape is value:
 * a format error naming the field. */
static void expect_extent(const unsigned char *bytes, size_t size, const char *name,
                          size_t extent, uint64_t value)
{
    unsigned char *d = copy_of(bytes, size);
    size_t off, shape, rank;
    char what[64];
    locate(d, name, &off, &shape, &rank);
    put_u64(d + shape + 8 * extent, value);
    snprintf(what, sizeof what, "\"%s\"", name);
    expect(d, size, LL_ERROR_FORMAT, what);
    free(d);
}

static void test_shapes_disagree(void **state)
{
    size_t off, shape, rank;
    (void)state;
    /* rgb with 2 channels (its data then still lies inside the file). */
    locate(good, "rgb", &off, &shape, &rank);
    assert_int_equal(rank, 5);
    expect_extent(good, good_size, "rgb", 2, 2);
    /* luminance with one incident elevation less than theta_i. */
    expect_extent(good, good_size, "luminance", 1, 2);
    /* a vndf of one node per row */
    expect_extent(good, good_size, "vndf", 3, 1);
}

static void test_offsets_and_sizes(void **state)
{
    unsigned char *d = copy_of(good, good_size);
    size_t off, shape, rank;
    (void)state;
    locate(d, "sigma", &off, &shape, &rank);
    put_u64(d + off, good_size - 4);
    expect(d, good_size, LL_ERROR_FORMAT, "\"sigma\": data at offset");
    put_u64(d + off, UINT64_MAX - 3);
    expect(d, good_size, LL_ERROR_FORMAT, "\"sigma\"");
    put_u64(d + off, 0);
    expect(d, good_size, LL_ERROR_FORMAT, "overlaps the field table");
    free(d);
    d = copy_of(good, good_size);
    locate(d, "vndf", &off, &shape, &rank);
    put_u64(d + shape, (uint64_t)1 << 62);
    expect(d, good_size, LL_ERROR_FORMAT, "\"vndf\"");
    put_u64(d + shape, 1);
    put_u64(d + shape + 8, (uint64_t)1 << 40);
    put_u64(d + shape + 16, (uint64_t)1 << 40);
    expect(d, good_size, LL_ERROR_FORMAT, "overflows");
    free(d);
    d = copy_of(good, good_size);
    d[14] = d[15] = d[16] = 0xff;
    d[17] = 0x7f;
    expect(d, good_size, LL_ERROR_FORMAT, "field count");
    d[14] = d[15] = d[16] = d[17] = 0;
    expect(d, good_size, LL_ERROR_FORMAT, "field count");
    free(d);
}

static void test_values(void **state)
{
    static const unsigned char nan_bytes[4] = { 0x00, 0x00, 0xc0, 0x7f };
    static const unsigned char minus_one[4] = { 0x00, 0x00, 0x80, 0xbf };
    static const unsigned char zero[4] = { 0, 0, 0, 0 };
    unsigned char *d = copy_of(good, good_size);
    size_t off, shape, rank, at;
    (void)state;
    locate(d, "luminance", &off, &shape, &rank);
    at = (size_t)get_u64(d + off);
    memcpy(d + at + 4, nan_bytes, 4);
    expect(d, good_size, LL_ERROR_FORMAT, "\"luminance\": element 1");
    memcpy(d + at + 4, minus_one, 4);
    expect(d, good_size, LL_ERROR_FORMAT, "\"luminance\": element 1");
    free(d);
    d = copy_of(good, good_size);
    locate(d, "sigma", &off, &shape, &rank);
    memcpy(d + (size_t)get_u64(d + off), zero, 4);
    expect(d, good_size, LL_ERROR_FORMAT, "\"sigma\"");
    free(d);
    d = copy_of(good, good_size);
    /* theta_i not ascending */
    locate(d, "theta_i", &off, &shape, &rank);
    memcpy(d + (size_t)get_u64(d + off) + 4, zero, 4);
    expect(d, good_size, LL_ERROR_FORMAT, "\"theta_i\"");
    free(d);
    d = copy_of(good, good_size);
    /* a jacobian of 2 */
    locate(d, "jacobian", &off, &shape, &rank);
    d[(size_t)get_u64(d + off)] = 2;
    expect(d, good_size, LL_ERROR_FORMAT, "\"jacobian\"");
    free(d);
}

static void test_limits(void **state)
{
    ll_open_options o = LL_OPEN_OPTIONS_INIT;
    ll_bsdf *b = NULL;
    (void)state;
    o.max_bytes = good_size - 1;
    assert_int_equal(ll_bsdf_open_memory(good, good_size, &o, &b), LL_ERROR_UNSUPPORTED);
    assert_non_null(strstr(ll_last_error_message(), "max_bytes"));
    assert_null(b);
}

static void test_random_damage(void **state)
{
    static const double wo[3] = { 0.3, 0.1, 0.9 };
    (void)state;
    printf("%d of 3000 damaged copies opened (damage in values or padding)\n",
           damage(good, good_size, 77, 3000, wo, NULL, 0));
}

static void test_out_of_memory(void **state)
{
    (void)state;
    assert_true(open_out_of_memory(good, good_size) > 5);
}

/* Out of memory at each allocation of writing a table: the error, every
 * block freed again, no file. */
static void test_writer_out_of_memory(void **state)
{
    ll_bsdf *src = NULL;
    ll_tables_options o = LL_TABLES_OPTIONS_INIT;
    char path[600];
    size_t n, k, reference_size;
    unsigned char *reference;
    (void)state;
    o.n_theta_i = 3;
    o.vndf_size = 4;
    o.sample_size = 3;
    snprintf(path, sizeof path, "%s/oom.tab", ll_test_dir());
    assert_int_equal(ll_bsdf_open(LL_TEST_GOLDEN, NULL, &src), LL_OK);
    ll_alloc_fail_after(0);
    assert_int_equal(ll_tables_write_from_bsdf(src, path, &o, NULL), LL_OK);
    n = ll_alloc_count();
    ll_alloc_hook_off();
    reference = ll_test_read_file(path, &reference_size);
    assert_int_equal(unlink(path), 0);
    for (k = 1; k <= n; ++k) {
        ll_status s;
        long long live;
        ll_alloc_fail_after(k);
        s = ll_tables_write_from_bsdf(src, path, &o, NULL);
        live = ll_alloc_live();
        ll_alloc_hook_off();
        assert_true(live == 0);
        if (s == LL_OK) {
            /* An allocation the output can do without (the sweep of stale
             * temporary files): the same file. */
            size_t size;
            unsigned char *bytes = ll_test_read_file(path, &size);
            assert_int_equal(size, reference_size);
            assert_memory_equal(bytes, reference, size);
            free(bytes);
            assert_int_equal(unlink(path), 0);
            continue;
        }
        if (s != LL_ERROR_OUT_OF_MEMORY)
            fail_msg("allocation %zu of %zu: status %d (%s)", k, n, (int)s,
                     ll_last_error_message());
        assert_int_equal(access(path, F_OK), -1);
    }
    free(reference);
    ll_bsdf_release(src);
}

/* A monitor that cancels while the tables are computed: LL_ERROR_CANCELLED
 * and no file. */
static int cancel_in_tables(void *user, double fraction, const char *stage)
{
    (void)user;
    (void)fraction;
    return strcmp(stage, "tables") == 0;
}

static void test_cancel(void **state)
{
    ll_bsdf *src = NULL;
    ll_monitor m = LL_MONITOR_INIT;
    char path[600];
    (void)state;
    m.progress = cancel_in_tables;
    snprintf(path, sizeof path, "%s/cancelled.tab", ll_test_dir());
    assert_int_equal(ll_bsdf_open(LL_TEST_GOLDEN, NULL, &src), LL_OK);
    assert_int_equal(ll_tables_write_from_bsdf(src, path, NULL, &m), LL_ERROR_CANCELLED);
    assert_int_equal(access(path, F_OK), -1);
    ll_bsdf_release(src);
}

/* The first byte of field name's data. */
static size_t data_at(const unsigned char *d, const char *name)
{
    size_t off, shape, rank;
    locate(d, name, &off, &shape, &rank);
    return (size_t)get_u64(d + off);
}

/* A copy of bytes whose one-element field name holds the 4 bytes value: a
 * format error naming the field. */
static void expect_scalar_refused(const unsigned char *bytes, size_t size, const char *name,
                                  const unsigned char *value)
{
    unsigned char *d = copy_of(bytes, size);
    char what[64];
    memcpy(d + data_at(d, name), value, 4);
    snprintf(what, sizeof what, "\"%s\"", name);
    expect(d, size, LL_ERROR_FORMAT, what);
    free(d);
}

/* A copy of bytes without the optional field name (its name damaged)
 * opens. */
static void expect_opens_without(const unsigned char *bytes, size_t size, const char *name)
{
    unsigned char *d = copy_of(bytes, size);
    size_t off, shape, rank;
    ll_bsdf *b = NULL;
    locate(d, name, &off, &shape, &rank);
    d[off - 4] = 'x';
    assert_int_equal(ll_bsdf_open_memory(d, size, NULL, &b), LL_OK);
    ll_bsdf_release(b);
    free(d);
}

static void test_transmissive_fields(void **state)
{
    static const unsigned char nan_bytes[4] = { 0x00, 0x00, 0xc0, 0x7f };
    static const unsigned char one_bytes[4] = { 0x00, 0x00, 0x80, 0x3f };
    static const unsigned char minus_one_bytes[4] = { 0x00, 0x00, 0x80, 0xbf };
    static const unsigned char big_bytes[4] = { 0x00, 0x00, 0xfa, 0x44 }; /* 2000 */
    ll_bsdf *b = NULL;
    ll_bsdf_info info = LL_BSDF_INFO_INIT;
    unsigned char *d;
    size_t off, shape, rank, at;
    (void)state;
    assert_int_equal(ll_bsdf_open_memory(tgood, tgood_size, NULL, &b), LL_OK);
    assert_int_equal(ll_bsdf_get_info(b, &info), LL_OK);
    assert_int_equal(info.format, LL_BSDF_FORMAT_TABLES);
    assert_true(fabs(info.eta - 1.5) < 1e-6);
    ll_bsdf_release(b);
    /* A set this reader does not know. */
    d = copy_of(tgood, tgood_size);
    d[data_at(d, "layerlab_layout")] = 'x';
    expect(d, tgood_size, LL_ERROR_UNSUPPORTED, "\"layerlab_layout\": set \"xeflect_top\"");
    free(d);
    /* A set named twice. */
    d = copy_of(tgood, tgood_size);
    at = data_at(d, "layerlab_layout");
    memcpy(d + at + strlen("reflect_top "), "reflect_top   ", strlen("reflect_top   "));
    expect(d, tgood_size, LL_ERROR_FORMAT, "named twice");
    free(d);
    /* eta not a number. */
    d = copy_of(tgood, tgood_size);
    memcpy(d + data_at(d, "eta"), nan_bytes, 4);
    expect(d, tgood_size, LL_ERROR_FORMAT, "\"eta\"");
    free(d);
    /* A set's field missing: its name damaged. */
    d = copy_of(tgood, tgood_size);
    locate(d, "transmit_top.ndf", &off, &shape, &rank);
    d[off - 4] = 'x';
    expect(d, tgood_size, LL_ERROR_FORMAT, "\"transmit_top.ndf\" is missing");
    free(d);
    /* A NaN in a set's luminance (float16, as a transmissive file's grids
     * are: element 1 the bits 0x7e00). */
    d = copy_of(tgood, tgood_size);
    d[data_at(d, "transmit_bottom.luminance") + 2] = 0x00;
    d[data_at(d, "transmit_bottom.luminance") + 3] = 0x7e;
    expect(d, tgood_size, LL_ERROR_FORMAT, "\"transmit_bottom.luminance\": element 1");
    free(d);
    /* A reflected set's Fresnel index of 1 (no interface); without the
     * field the file opens, its values then f's own. */
    expect_scalar_refused(tgood, tgood_size, "reflect_bottom.fresnel_eta", one_bytes);
    expect_opens_without(tgood, tgood_size, "reflect_bottom.fresnel_eta");
    /* A refracted set's transmittance index other than its warp_eta (1,
     * where the warp is 1.5's) or not a number; without the field the
     * file opens, its values then f's own. */
    assert_int_equal(ll_bsdf_open_memory(rgood, rgood_size, NULL, &b), LL_OK);
    ll_bsdf_release(b);
    expect_scalar_refused(rgood, rgood_size, "transmit_top.transmittance_eta", one_bytes);
    expect_scalar_refused(rgood, rgood_size, "transmit_top.transmittance_eta", nan_bytes);
    expect_opens_without(rgood, rgood_size, "transmit_top.transmittance_eta");
    /* A reflected set's Fresnel floor: not a number, negative, beyond
     * 1000, of no value, or without the set's fresnel_eta; without the
     * floor (a file written before it) the file opens, its values then
     * over F itself. */
    assert_int_equal(ll_bsdf_open_memory(cgood, cgood_size, NULL, &b), LL_OK);
    ll_bsdf_release(b);
    expect_scalar_refused(cgood, cgood_size, "reflect_bottom.fresnel_floor", nan_bytes);
    expect_scalar_refused(cgood, cgood_size, "reflect_bottom.fresnel_floor", minus_one_bytes);
    expect_scalar_refused(cgood, cgood_size, "reflect_bottom.fresnel_floor", big_bytes);
    expect_extent(cgood, cgood_size, "reflect_bottom.fresnel_floor", 0, 0);
    d = copy_of(cgood, cgood_size);
    locate(d, "reflect_bottom.fresnel_eta", &off, &shape, &rank);
    d[off - 4] = 'x';
    expect(d, cgood_size, LL_ERROR_FORMAT, "\"reflect_bottom.fresnel_floor\"");
    free(d);
    expect_opens_without(cgood, cgood_size, "reflect_bottom.fresnel_floor");
    /* Shapes: a set's rgb of 2 channels, an albedo of too few values. */
    expect_extent(tgood, tgood_size, "reflect_bottom.rgb", 2, 2);
    expect_extent(tgood, tgood_size, "transmit_top.albedo", 0, 2);
}

/* Random damage and out of memory on the transmissive table, as on the
 * opaque one. */
static void test_transmissive_damage(void **state)
{
    static const double wo[3] = { 0.3, 0.1, -0.9 };
    static const double wo_top[3] = { 0.3, 0.1, 0.9 };
    (void)state;
    printf("%d of 2000 damaged transmissive copies opened\n",
           damage(tgood, tgood_size, 78, 2000, wo, NULL, 0));
    open_out_of_memory(tgood, tgood_size);
    /* The refracted set stored over its transmittance, seen from above. */
    printf("%d of 1000 damaged refracted copies opened\n",
           damage(rgood, rgood_size, 79, 1000, wo_top, NULL, 0));
    open_out_of_memory(rgood, rgood_size);
}

/* The float32 element i of field name in d. */
static void set_f32(unsigned char *d, const char *name, size_t i, float v)
{
    size_t off, shape, rank;
    locate(d, name, &off, &shape, &rank);
    memcpy(d + (size_t)get_u64(d + off) + 4 * i, &v, 4); /* little-endian host */
}

static void test_textured_opens(void **state)
{
    ll_bsdf *b = NULL;
    ll_bsdf_info info = LL_BSDF_INFO_INIT;
    (void)state;
    assert_int_equal(ll_bsdf_open_memory(tex, tex_size, NULL, &b), LL_OK);
    assert_int_equal(ll_bsdf_get_info(b, &info), LL_OK);
    assert_int_equal(info.format, LL_BSDF_FORMAT_TABLES);
    assert_int_equal(info.n_bases, 7);
    assert_int_equal(info.n_parameters, 1);
    ll_bsdf_release(b);
}

static void test_textured_fields(void **state)
{
    unsigned char *d = copy_of(tex, tex_size);
    size_t off, shape, rank, at;
    (void)state;
    /* Eight sample positions: a basis the file does not have. */
    set_f32(d, "layerlab_parameter_counts", 0, 8.0f);
    expect(d, tex_size, LL_ERROR_FORMAT, "\"layerlab_parameter_positions\"");
    free(d);
    d = copy_of(tex, tex_size);
    set_f32(d, "layerlab_parameter_counts", 0, 1.5f);
    expect(d, tex_size, LL_ERROR_FORMAT, "\"layerlab_parameter_counts\": element 0");
    set_f32(d, "layerlab_parameter_counts", 0, 1e9f);
    expect(d, tex_size, LL_ERROR_FORMAT, "\"layerlab_parameter_counts\": element 0");
    free(d);
    d = copy_of(tex, tex_size);
    /* Positions not ascending, or not finite. */
    set_f32(d, "layerlab_parameter_positions", 1, 0.05f);
    expect(d, tex_size, LL_ERROR_FORMAT, "\"layerlab_parameter_positions\"");
    set_f32(d, "layerlab_parameter_positions", 1, NAN);
    expect(d, tex_size, LL_ERROR_FORMAT, "\"layerlab_parameter_positions\"");
    free(d);
    d = copy_of(tex, tex_size);
    /* A layout this reader does not know; an empty one. */
    locate(d, "layerlab_layout", &off, &shape, &rank);
    at = (size_t)get_u64(d + off);
    d[at] = 'X';
    expect(d, tex_size, LL_ERROR_UNSUPPORTED, "\"layerlab_layout\"");
    memset(d + at, ' ', 8);
    expect(d, tex_size, LL_ERROR_FORMAT, "\"layerlab_layout\"");
    free(d);
    /* A field of basis 1 that disagrees with its set, named in full. */
    expect_extent(tex, tex_size, "basis1.vndf", 3, 1);
    d = copy_of(tex, tex_size);
    set_f32(d, "basis1.sigma", 0, 0.0f);
    expect(d, tex_size, LL_ERROR_FORMAT, "\"basis1.sigma\"");
    free(d);
    d = copy_of(tex, tex_size);
    /* basis1's theta_i renamed away: the set is missing. */
    locate(d, "basis1.theta_i", &off, &shape, &rank);
    d[off - 3 - 7] = 'X'; /* "basis1.theta_i" -> "basis1.Xheta_i" */
    expect(d, tex_size, LL_ERROR_FORMAT, "\"basis1.theta_i\" is missing");
    free(d);
    d = copy_of(tex, tex_size);
    /* The parameter block renamed away. */
    locate(d, "layerlab_parameter_counts", &off, &shape, &rank);
    d[off - 3 - 1] = 'X';
    expect(d, tex_size, LL_ERROR_FORMAT, "\"layerlab_parameter_counts\" is missing");
    free(d);
}

/* Element i of the float16 field name set to the binary16 bits h. */
static void set_f16(unsigned char *d, const char *name, size_t i, unsigned h)
{
    size_t off, shape, rank, at;
    locate(d, name, &off, &shape, &rank);
    at = (size_t)get_u64(d + off) + 2 * i;
    d[at] = (unsigned char)(h & 0xffu);
    d[at + 1] = (unsigned char)(h >> 8);
}

/* The dtype code of field name set to code (its data then lies inside
 * the file still, for a code of fewer bytes). */
static void set_dtype(unsigned char *d, const char *name, unsigned char code)
{
    size_t off, shape, rank;
    locate(d, name, &off, &shape, &rank);
    d[off - 1] = code;
}

static void test_textured_float16(void **state)
{
    /* binary16: a quiet NaN, +infinity, -1, -0 (which is >= 0: read). */
    static const unsigned bad[3] = { 0x7e00u, 0x7c00u, 0xbc00u };
    static const char *const grids[6] = { "basis1.vndf",           "basis1.luminance",
                                          "basis6.rgb",            "reflect_top.vndf",
                                          "transmit_bottom.luminance", "transmit_top.rgb" };
    unsigned char *d;
    size_t off, shape, rank;
    ll_bsdf *b = NULL;
    char what[64];
    int g, k;
    (void)state;
    for (g = 0; g < 6; ++g) {
        /* (The first three a textured file's, the others a transmissive
         * one's.) */
        const unsigned char *file = g < 3 ? tex : tgood;
        size_t size = g < 3 ? tex_size : tgood_size;
        locate(file, grids[g], &off, &shape, &rank);
        assert_int_equal(file[off - 1], 9); /* float16 */
        for (k = 0; k < 3; ++k) {
            d = copy_of(file, size);
            set_f16(d, grids[g], 1, bad[k]);
            snprintf(what, sizeof what, "\"%s\": element 1 = ", grids[g]);
            expect(d, size, LL_ERROR_FORMAT, what);
            free(d);
        }
    }
    d = copy_of(tex, tex_size);
    set_f16(d, "basis1.luminance", 1, 0x8000u);
    assert_int_equal(ll_bsdf_open_memory(d, tex_size, NULL, &b), LL_OK);
    ll_bsdf_release(b);
    free(d);
    /* Float16 anywhere else is refused: a textured or transmissive
     * file's small fields are float32 as an opaque file's, and an opaque
     * file's grids float32, as `measured` reads them. */
    {
        const struct {
            const unsigned char *file;
            size_t size;
            const char *field;
        } float32_only[7] = { { tex, tex_size, "basis2.theta_i" },
                              { tex, tex_size, "basis2.sigma" },
                              { good, good_size, "vndf" },
                              { good, good_size, "rgb" },
                              { tgood, tgood_size, "reflect_top.ndf" },
                              { tgood, tgood_size, "transmit_top.albedo" },
                              { tgood, tgood_size, "transmit_bottom.warp_eta" } };
        for (k = 0; k < 7; ++k) {
            d = copy_of(float32_only[k].file, float32_only[k].size);
            set_dtype(d, float32_only[k].field, 9);
            snprintf(what, sizeof what, "\"%s\" is float16", float32_only[k].field);
            expect(d, float32_only[k].size, LL_ERROR_FORMAT, what);
            free(d);
        }
    }
}

static void test_textured_truncated_and_damaged(void **state)
{
    static const double wo[3] = { 0.3, 0.1, 0.9 };
    static const float w[7] = { 0.0f, 0.25f, 0.75f, 0.0f, 0.0f, 0.0f, 0.0f };
    size_t n;
    (void)state;
    for (n = 12; n < tex_size; n += 1 + n / 64) {
        ll_bsdf *b = NULL;
        assert_int_equal(ll_bsdf_open_memory(tex, n, NULL, &b), LL_ERROR_FORMAT);
        assert_null(b);
    }
    printf("%d of 2000 damaged textured copies opened\n",
           damage(tex, tex_size, 5, 2000, wo, w, 7));
}

static void test_textured_out_of_memory(void **state)
{
    (void)state;
    open_out_of_memory(tex, tex_size);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_good_opens),
        cmocka_unit_test(test_truncated),
        cmocka_unit_test(test_magic_and_version),
        cmocka_unit_test(test_shapes_disagree),
        cmocka_unit_test(test_offsets_and_sizes),
        cmocka_unit_test(test_values),
        cmocka_unit_test(test_limits),
        cmocka_unit_test(test_random_damage),
        cmocka_unit_test(test_out_of_memory),
        cmocka_unit_test(test_writer_out_of_memory),
        cmocka_unit_test(test_cancel),
        cmocka_unit_test(test_transmissive_fields),
        cmocka_unit_test(test_transmissive_damage),
        cmocka_unit_test(test_textured_opens),
        cmocka_unit_test(test_textured_fields),
        cmocka_unit_test(test_textured_float16),
        cmocka_unit_test(test_textured_truncated_and_damaged),
        cmocka_unit_test(test_textured_out_of_memory),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
