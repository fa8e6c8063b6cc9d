/*
 * Reader limits and what is not a regular file:
 *  - ll_bsdf_open / ll_bsdf_open_memory with ll_open_options:
 *    defaults, each limit, struct_size of an older caller;
 *  - a sparse .bsdf file (4 KB on disk, 960 MB apparent, one series of
 *    240 M zeros) opened with 4.6 GB of RSS and 1 s per eval: now refused
 *    by the defaults before anything is allocated;
 *  - a sparse MERL file (1.5 GB apparent) peaked at 2.9 GB: refused by the
 *    resolution maxima;
 *  - a FIFO, a directory and a device as a .bsdf, MERL, material or
 *    spectrum file: refused without blocking, naming the path and what it
 *    is. alarm() ends the program if an open blocks (a regression fails,
 *    it does not hang).
 */
#include "test_bsdf_util.h"
#include "reader/bsdf_format.h"
#include "words/merl.h"

#include <fcntl.h>
#include <sys/resource.h>

static unsigned char *g_gold;
static size_t g_size;

static int setup(void **state)
{
    ll_test_dir_setup(state);
    g_gold = ll_test_read_file(LL_TEST_GOLDEN, &g_size);
    /* Nothing here may block: 60 s is far beyond any of these calls. */
    alarm(60);
    return 0;
}

static int teardown(void **state)
{
    free(g_gold);
    alarm(0);
    return ll_test_dir_teardown(state);
}

static long peak_rss_kb(void)
{
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    return ru.ru_maxrss;
}

static void expect(ll_status got, ll_status want, const char *needle)
{
    if (got != want || (needle && !strstr(ll_last_error_message(), needle)))
        fail_msg("status %d (wanted %d), message \"%s\" (wanted \"%s\")", (int)got, (int)want,
                 ll_last_error_message(), needle ? needle : "");
}

static void options(void **state)
{
    ll_open_options o = LL_OPEN_OPTIONS_INIT;
    ll_bsdf_info info = LL_BSDF_INFO_INIT;
    ll_bsdf *b = NULL;
    char path[600];
    (void)state;
    /* Defaults (NULL or zeros) open the golden file. */
    expect(ll_bsdf_open_memory(g_gold, g_size, NULL, &b), LL_OK, NULL);
    assert_int_equal(ll_bsdf_get_info(b, &info), LL_OK);
    ll_bsdf_release(b);
    expect(ll_bsdf_open_memory(g_gold, g_size, &o, &b), LL_OK, NULL);
    ll_bsdf_release(b);
    /* Each limit just at and just below the file's value. */
    o.max_bytes = g_size;
    expect(ll_bsdf_open_memory(g_gold, g_size, &o, &b), LL_OK, NULL);
    ll_bsdf_release(b);
    o.max_bytes = g_size - 1;
    expect(ll_bsdf_open_memory(g_gold, g_size, &o, &b), LL_ERROR_UNSUPPORTED,
           "exceed the limit of");
    assert_null(b);
    o.max_bytes = 0;
    o.max_order = info.max_order;
    expect(ll_bsdf_open_memory(g_gold, g_size, &o, &b), LL_OK, NULL);
    ll_bsdf_release(b);
    o.max_order = info.max_order - 1;
    expect(ll_bsdf_open_memory(g_gold, g_size, &o, &b), LL_ERROR_UNSUPPORTED,
           "ll_open_options.max_order");
    o.max_order = 0;
    o.max_nodes = info.n_nodes - 1;
    expect(ll_bsdf_open_memory(g_gold, g_size, &o, &b), LL_ERROR_UNSUPPORTED,
           "ll_open_options.max_nodes");
    /* An older caller's struct (only max_bytes): the rest are defaults,
     * whatever lies beyond its size. */
    o.struct_size = offsetof(ll_open_options, max_bytes) + sizeof o.max_bytes;
    o.max_bytes = 0;
    o.max_order = 1;
    o.max_nodes = 1;
    expect(ll_bsdf_open_memory(g_gold, g_size, &o, &b), LL_OK, NULL);
    ll_bsdf_release(b);
    /* The struct_size field alone is the oldest struct (every limit its
     * default); less than that is not a struct at all. */
    o.struct_size = sizeof o.struct_size;
    expect(ll_bsdf_open_memory(g_gold, g_size, &o, &b), LL_OK, NULL);
    ll_bsdf_release(b);
    o.struct_size = sizeof o.struct_size - 1;
    expect(ll_bsdf_open_memory(g_gold, g_size, &o, &b), LL_ERROR_INVALID_ARGUMENT,
           "struct_size");
    /* The same through a file, with the path in the message. */
    snprintf(path, sizeof path, "%s/gold.bsdf", ll_test_dir());
    ll_test_write_file(path, g_gold, g_size);
    o = (ll_open_options)LL_OPEN_OPTIONS_INIT;
    o.max_bytes = 1000;
    expect(ll_bsdf_open(path, &o, &b), LL_ERROR_UNSUPPORTED, path);
    expect(ll_bsdf_open(path, NULL, &b), LL_OK, NULL);
    ll_bsdf_release(b);
    assert_int_equal(LL_OPEN_DEFAULT_MAX_BYTES, (size_t)512 << 20);
}

/* Header, nodes (-1, 1), zero CDF and one series of `length` coefficients;
 * the coefficients themselves are a hole (ftruncate). */
static void write_sparse_bsdf(const char *path, uint32_t length)
{
    unsigned char h[64 + 8 + 16 + 32];
    int fd;
    memset(h, 0, sizeof h);
    memcpy(h, LL_BSDF_MAGIC, LL_BSDF_MAGIC_SIZE);
    h[LL_BSDF_AT_VERSION] = LL_BSDF_VERSION;
    ll_le_put_u32(h + LL_BSDF_AT_FLAGS, LL_BSDF_FLAG_BSDF);
    ll_le_put_u32(h + LL_BSDF_AT_NODES, 2);
    ll_le_put_u32(h + LL_BSDF_AT_COEFFS, length);
    ll_le_put_u32(h + LL_BSDF_AT_MAX_ORDER, length);
    ll_le_put_u32(h + LL_BSDF_AT_CHANNELS, 1);
    ll_le_put_u32(h + LL_BSDF_AT_BASES, 1);
    ll_le_put_f32(h + LL_BSDF_AT_ETA, 1.0f);
    ll_le_put_f32(h + 64, -1.0f);
    ll_le_put_f32(h + 68, 1.0f);
    ll_le_put_u32(h + 64 + 8 + 16 + 4, length); /* pair 0: offset 0, length */
    fd = open(path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    assert_true(fd >= 0);
    assert_int_equal(write(fd, h, sizeof h), (ssize_t)sizeof h);
    assert_int_equal(ftruncate(fd, (off_t)sizeof h + 4 * (off_t)length), 0);
    close(fd);
}

static void sparse_bsdf_refused_before_allocating(void **state)
{
    char path[600];
    ll_bsdf *b = NULL;
    long before;
    (void)state;
    snprintf(path, sizeof path, "%s/sparse.bsdf", ll_test_dir());
    write_sparse_bsdf(path, 240000000u);
    before = peak_rss_kb();
    expect(ll_bsdf_open(path, NULL, &b), LL_ERROR_UNSUPPORTED, "960000120 bytes exceed the limit");
    assert_null(b);
    /* Below the byte limit, the series length is refused. */
    write_sparse_bsdf(path, 2000000u);
    expect(ll_bsdf_open(path, NULL, &b), LL_ERROR_UNSUPPORTED, "nMaxOrder = 2000000");
    /* Nothing sized by the header was allocated (4.6 GB before). */
    assert_true(peak_rss_kb() - before < 32 * 1024);
    /* Within the limits it opens and evaluates to 0. */
    write_sparse_bsdf(path, 1000u);
    expect(ll_bsdf_open(path, NULL, &b), LL_OK, NULL);
    {
        double rgb[3];
        assert_int_equal(ll_bsdf_eval(b, 0.5, -0.5, 0.0, NULL, rgb), LL_OK);
        assert_true(rgb[0] == 0.0);
    }
    ll_bsdf_release(b);
    unlink(path);
}

static void write_merl_header(const char *path, uint32_t a, uint32_t b, uint32_t c)
{
    unsigned char h[12];
    int fd;
    ll_le_put_u32(h, a);
    ll_le_put_u32(h + 4, b);
    ll_le_put_u32(h + 8, c);
    fd = open(path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    assert_true(fd >= 0);
    assert_int_equal(write(fd, h, sizeof h), 12);
    assert_int_equal(ftruncate(fd, 12 + 24 * (off_t)a * b * c), 0);
    close(fd);
}

static void sparse_merl_refused(void **state)
{
    char path[600];
    ll_merl *m = NULL;
    long before;
    (void)state;
    snprintf(path, sizeof path, "%s/sparse.binary", ll_test_dir());
    before = peak_rss_kb();
    /* 1.5 GB apparent, every resolution below the old cap of 100000. */
    write_merl_header(path, 250, 250, 1000);
    expect(ll_merl_load(path, &m), LL_ERROR_FORMAT, "exceed the supported maximum");
    assert_null(m);
    write_merl_header(path, 721, 1, 1);
    expect(ll_merl_check(path), LL_ERROR_FORMAT, "theta_half resolution 721 is not in [1, 720]");
    write_merl_header(path, 1, 1, 1441);
    expect(ll_merl_check(path), LL_ERROR_FORMAT, "phi_diff resolution 1441");
    assert_true(peak_rss_kb() - before < 32 * 1024);
    /* The database's own size loads. */
    write_merl_header(path, 90, 90, 180);
    expect(ll_merl_load(path, &m), LL_OK, NULL);
    ll_merl_free(m);
    unlink(path);
}

/* Every reader refuses path, a `kind`, with a message naming both. */
static void refused_everywhere(const char *path, const char *kind)
{
    char text[800];
    ll_bsdf *b = NULL;
    ll_material *m = NULL;
    ll_merl *merl = NULL;
    expect(ll_bsdf_open(path, NULL, &b), LL_ERROR_IO, kind);
    assert_non_null(strstr(ll_last_error_message(), path));
    expect(ll_merl_load(path, &merl), LL_ERROR_IO, kind);
    assert_non_null(strstr(ll_last_error_message(), path));
    expect(ll_material_parse_file(path, &m), LL_ERROR_IO, kind);
    assert_non_null(strstr(ll_last_error_message(), path));
    snprintf(text, sizeof text, "measured file=\"%s\"\n", path);
    expect(ll_material_parse(text, "t", &m), LL_ERROR_PARSE, kind);
    assert_null(m);
}

static void non_regular_paths(void **state)
{
    char fifo[600], dir[600], text[100];
    ll_material *m = NULL;
    (void)state;
    snprintf(fifo, sizeof fifo, "%s/pipe", ll_test_dir());
    assert_int_equal(mkfifo(fifo, 0600), 0);
    refused_everywhere(fifo, "is a FIFO (named pipe), not a regular file");
    snprintf(dir, sizeof dir, "%s/folder", ll_test_dir());
    assert_int_equal(mkdir(dir, 0700), 0);
    refused_everywhere(dir, "is a directory, not a regular file");
    refused_everywhere("/dev/null", "is a character device, not a regular file");
    /* A metal's spectrum that is a FIFO. */
    snprintf(fifo, sizeof fifo, "%s/Pp.eta.spd", ll_test_dir());
    assert_int_equal(mkfifo(fifo, 0600), 0);
    snprintf(fifo, sizeof fifo, "%s/Pp.k.spd", ll_test_dir());
    assert_int_equal(mkfifo(fifo, 0600), 0);
    setenv("LAYERLAB_IOR_DIR", ll_test_dir(), 1);
    snprintf(text, sizeof text, "conductor eta=Pp alpha=0.1\n");
    expect(ll_material_parse(text, "t", &m), LL_ERROR_PARSE, "is a FIFO");
    unsetenv("LAYERLAB_IOR_DIR");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(options),
        cmocka_unit_test(sparse_bsdf_refused_before_allocating),
        cmocka_unit_test(sparse_merl_refused),
        cmocka_unit_test(non_regular_paths),
    };
    return cmocka_run_group_tests_name("bsdf_limits", tests, setup, teardown);
}
