/*
 * The writer's contract: arguments and options checked, and atomicity: on
 * any failure (bad path, invalid layer, full disk) the target is untouched
 * and no temporary file is left; on success the target is replaced whole.
 */
#include "test_bsdf_util.h"

#include <errno.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>

static const char OLD_CONTENT[] = "the previous file";

/* A target holding OLD_CONTENT, alone in the scratch directory. */
static void fresh_target(char *path, size_t size)
{
    ll_test_rmdir(ll_test_dir());
    assert_int_equal(mkdir(ll_test_dir(), 0700), 0);
    snprintf(path, size, "%s/target.bsdf", ll_test_dir());
    ll_test_write_file(path, OLD_CONTENT, sizeof OLD_CONTENT);
}

static void assert_untouched(const char *path)
{
    size_t size;
    unsigned char *d = ll_test_read_file(path, &size);
    assert_int_equal(size, sizeof OLD_CONTENT);
    assert_memory_equal(d, OLD_CONTENT, size);
    free(d);
    /* No temporary file beside it. */
    assert_int_equal(ll_test_count_entries(ll_test_dir()), 1);
}

static ll_layer *diffuse_layer(size_t n, size_t m, double albedo)
{
    ll_layer *l = ll_test_layer(n, m);
    assert_int_equal(ll_layer_set_diffuse(l, albedo, NULL), LL_OK);
    return l;
}

static double nan_fn(size_t k, double mu_o, double mu_i, const void *ctx)
{
    (void)ctx;
    /* Inside a run of stored values (the builder trims zeros and NaNs at
     * the ends of a run). */
    return (k == 2 && mu_o > 0.4 && mu_o < 0.6 && mu_i < -0.5) ? NAN : 0.1;
}

static void invalid_arguments(void **state)
{
    char path[600];
    ll_layer *a = diffuse_layer(8, 2, 0.5), *other = diffuse_layer(10, 2, 0.5), *bad;
    const ll_layer *one[1], *three[3], *mixed[3];
    ll_bsdf_write_options opts = LL_BSDF_WRITE_OPTIONS_INIT;
    (void)state;
    fresh_target(path, sizeof path);
    one[0] = a;
    three[0] = three[1] = three[2] = a;
    mixed[0] = a;
    mixed[1] = other;
    mixed[2] = a;
    assert_int_equal(ll_bsdf_write(NULL, one, 1, NULL, NULL), LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_bsdf_write("", one, 1, NULL, NULL), LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_bsdf_write(path, NULL, 1, NULL, NULL), LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_bsdf_write(path, one, 2, NULL, NULL), LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_bsdf_write(path, one, 0, NULL, NULL), LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_bsdf_write(path, mixed, 3, NULL, NULL), LL_ERROR_INVALID_ARGUMENT);
    {
        const ll_layer *with_null[3] = { a, NULL, a };
        assert_int_equal(ll_bsdf_write(path, with_null, 3, NULL, NULL), LL_ERROR_INVALID_ARGUMENT);
    }
    opts.eta = 0.0;
    assert_int_equal(ll_bsdf_write(path, one, 1, &opts, NULL), LL_ERROR_INVALID_ARGUMENT);
    opts.eta = NAN;
    assert_int_equal(ll_bsdf_write(path, one, 1, &opts, NULL), LL_ERROR_INVALID_ARGUMENT);
    opts.eta = 1.5;
    opts.alpha[1] = -0.1;
    assert_int_equal(ll_bsdf_write(path, one, 1, &opts, NULL), LL_ERROR_INVALID_ARGUMENT);
    opts.alpha[1] = 0.0;
    opts.error_goal = -1.0;
    assert_int_equal(ll_bsdf_write(path, one, 1, &opts, NULL), LL_ERROR_INVALID_ARGUMENT);
    opts.error_goal = 1e-3;
    opts.struct_size = 0;
    assert_int_equal(ll_bsdf_write(path, one, 1, &opts, NULL), LL_ERROR_INVALID_ARGUMENT);
    /* Textured: counts and positions. */
    {
        const size_t zero[1] = { 0 }, two[1] = { 2 };
        const double same[2] = { 0.5, 0.5 }, good[2] = { 0.0, 1.0 };
        const ll_layer *pair[2] = { a, a };
        assert_int_equal(ll_bsdf_write_textured(path, pair, 1, 1, zero, good, NULL, NULL),
                         LL_ERROR_INVALID_ARGUMENT);
        assert_int_equal(ll_bsdf_write_textured(path, pair, 1, 1, two, same, NULL, NULL),
                         LL_ERROR_INVALID_ARGUMENT);
        assert_int_equal(ll_bsdf_write_textured(path, pair, 1, 1, two, NULL, NULL, NULL),
                         LL_ERROR_INVALID_ARGUMENT);
    }
    /* An invalid layer: a NaN in its matrices. */
    bad = ll_test_layer(8, 4);
    ll_test_fill(bad, nan_fn, NULL);
    one[0] = bad;
    assert_int_equal(ll_bsdf_write(path, one, 1, NULL, NULL), LL_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(ll_last_error_message(), "non-finite"));
    assert_untouched(path);
    ll_layer_destroy(a);
    ll_layer_destroy(other);
    ll_layer_destroy(bad);
}

static void bad_paths(void **state)
{
    char path[600], dir_as_file[600];
    ll_layer *a = diffuse_layer(8, 1, 0.5);
    const ll_layer *one[1];
    (void)state;
    one[0] = a;
    fresh_target(path, sizeof path);
    /* A directory that does not exist. */
    snprintf(dir_as_file, sizeof dir_as_file, "%s/missing/sub/x.bsdf", ll_test_dir());
    assert_int_equal(ll_bsdf_write(dir_as_file, one, 1, NULL, NULL), LL_ERROR_IO);
    assert_non_null(strstr(ll_last_error_message(), "missing/sub/x.bsdf"));
    /* A path naming a directory. */
    snprintf(dir_as_file, sizeof dir_as_file, "%s/", ll_test_dir());
    assert_int_equal(ll_bsdf_write(dir_as_file, one, 1, NULL, NULL), LL_ERROR_IO);
    /* An existing directory as the target: the rename fails. */
    snprintf(dir_as_file, sizeof dir_as_file, "%s/adir", ll_test_dir());
    assert_int_equal(mkdir(dir_as_file, 0700), 0);
    assert_int_equal(ll_bsdf_write(dir_as_file, one, 1, NULL, NULL), LL_ERROR_IO);
    assert_int_equal(rmdir(dir_as_file), 0);
    assert_untouched(path);
    ll_layer_destroy(a);
}

/* A full disk, played by the file size limit in a child process: writing
 * fails part-way, and the target and the directory stay as they were. */
static void disk_full(void **state)
{
    char path[600];
    pid_t pid;
    int status;
    (void)state;
    fresh_target(path, sizeof path);
    pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        struct rlimit limit;
        ll_layer *l = ll_test_layer(40, 60);
        const ll_layer *one[1];
        double sharp = 4.0;
        ll_bsdf_write_options opts = LL_BSDF_WRITE_OPTIONS_INIT;
        ll_status s;
        signal(SIGXFSZ, SIG_IGN);
        ll_test_fill(l, ll_test_lobe_fn, &sharp);
        one[0] = l;
        opts.error_goal = 0.0;
        limit.rlim_cur = limit.rlim_max = 100000; /* the file needs ~1 MB */
        if (setrlimit(RLIMIT_FSIZE, &limit) != 0)
            _exit(3);
        s = ll_bsdf_write(path, one, 1, &opts, NULL);
        ll_layer_destroy(l);
        _exit(s == LL_ERROR_IO && strstr(ll_last_error_message(), "writing failed") ? 0 : 1);
    }
    assert_int_equal(waitpid(pid, &status, 0), pid);
    assert_true(WIFEXITED(status));
    assert_int_equal(WEXITSTATUS(status), 0);
    assert_untouched(path);
}

static void replaces_atomically(void **state)
{
    char path[600];
    ll_layer *a = diffuse_layer(8, 1, 0.25), *b = diffuse_layer(8, 1, 0.75);
    const ll_layer *one[1];
    ll_bsdf *f = NULL;
    double rgb[3];
    struct stat st;
    (void)state;
    fresh_target(path, sizeof path);
    one[0] = a;
    assert_int_equal(ll_bsdf_write(path, one, 1, NULL, NULL), LL_OK);
    one[0] = b;
    assert_int_equal(ll_bsdf_write(path, one, 1, NULL, NULL), LL_OK);
    assert_int_equal(ll_test_count_entries(ll_test_dir()), 1);
    assert_int_equal(ll_bsdf_open(path, NULL, &f), LL_OK);
    assert_int_equal(ll_bsdf_eval(f, 0.8, -0.8, 0.0, NULL, rgb), LL_OK);
    assert_true(fabs(rgb[0] - 0.75 / LL_TEST_PI) < 1e-6);
    ll_bsdf_release(f);
    /* An ordinary readable file, not mkstemp's private one. */
    assert_int_equal(stat(path, &st), 0);
    assert_int_equal(st.st_mode & 0777, 0644);
    /* A relative path (no directory part) works too. */
    {
        char cwd[1024];
        assert_non_null(getcwd(cwd, sizeof cwd));
        assert_int_equal(chdir(ll_test_dir()), 0);
        assert_int_equal(ll_bsdf_write("relative.bsdf", one, 1, NULL, NULL), LL_OK);
        assert_int_equal(chdir(cwd), 0);
        assert_int_equal(ll_test_count_entries(ll_test_dir()), 2);
    }
    ll_layer_destroy(a);
    ll_layer_destroy(b);
}

/* Options read only as far as struct_size reaches (an older caller). */
static void short_options(void **state)
{
    char path[600];
    ll_layer *a = diffuse_layer(8, 1, 0.5);
    const ll_layer *one[1];
    ll_bsdf_write_options opts;
    ll_bsdf *f = NULL;
    ll_bsdf_info info = LL_BSDF_INFO_INIT;
    (void)state;
    fresh_target(path, sizeof path);
    one[0] = a;
    memset(&opts, 0xFF, sizeof opts); /* garbage beyond the declared size */
    opts.struct_size = offsetof(ll_bsdf_write_options, alpha);
    opts.eta = 1.25;
    assert_int_equal(ll_bsdf_write(path, one, 1, &opts, NULL), LL_OK);
    assert_int_equal(ll_bsdf_open(path, NULL, &f), LL_OK);
    assert_int_equal(ll_bsdf_get_info(f, &info), LL_OK);
    assert_true(info.eta == 1.25 && info.alpha[0] == 0.0 && info.alpha[1] == 0.0);
    assert_non_null(strstr(info.metadata, "\"generator\": \"layerlab"));
    ll_bsdf_release(f);
    ll_layer_destroy(a);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(invalid_arguments),
        cmocka_unit_test(bad_paths),
        cmocka_unit_test(disk_full),
        cmocka_unit_test(replaces_atomically),
        cmocka_unit_test(short_options),
    };
    return cmocka_run_group_tests_name("bsdf_write", tests, ll_test_dir_setup, ll_test_dir_teardown);
}
