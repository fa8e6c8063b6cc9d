/*
 * What the atomic writer leaves in the target's directory: no visible
 * placeholder, hidden temporaries (.NAME.XXXXXX.tmp) and stale ones of the
 * same target removed by the next writer; the mode of a new file follows the umask and an existing target
 * keeps its own; a symbolic link is written through; names up to NAME_MAX
 * work; a full disk names the target, not the temporary.
 */
#include "test_bsdf_util.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <signal.h>
#include <sys/mount.h>
#include <sys/resource.h>
#include <sys/time.h>
#include <sys/wait.h>

static ll_layer *g_layer;

static int setup(void **state)
{
    ll_test_dir_setup(state);
    g_layer = ll_test_layer(8, 1);
    return ll_layer_set_diffuse(g_layer, 0.5, NULL) == LL_OK ? 0 : -1;
}

static int teardown(void **state)
{
    ll_layer_destroy(g_layer);
    return ll_test_dir_teardown(state);
}

static ll_status write_to(const char *path)
{
    const ll_layer *one[1];
    one[0] = g_layer;
    return ll_bsdf_write(path, one, 1, NULL, NULL);
}

/* A fresh, empty scratch folder "<dir>/<name>" in path. */
static void fresh_dir(const char *name, char *path, size_t size)
{
    snprintf(path, size, "%s/%s", ll_test_dir(), name);
    ll_test_rmdir(path);
    assert_int_equal(mkdir(path, 0700), 0);
}

static void opens(const char *path)
{
    ll_bsdf *b = NULL;
    if (ll_bsdf_open(path, NULL, &b) != LL_OK)
        fail_msg("%s", ll_last_error_message());
    ll_bsdf_release(b);
}

static void touch(const char *path, time_t age)
{
    struct timeval times[2];
    ll_test_write_file(path, "x", 1);
    gettimeofday(&times[0], NULL);
    times[0].tv_sec -= age;
    times[1] = times[0];
    assert_int_equal(utimes(path, times), 0);
}

static int exists(const char *path)
{
    struct stat st;
    return lstat(path, &st) == 0;
}

static void stale_temporaries_removed(void **state)
{
    char dir[600], path[700], stale[700], fresh[700], other[700], near[700];
    (void)state;
    fresh_dir("stale", dir, sizeof dir);
    snprintf(path, sizeof path, "%s/t.bsdf", dir);
    /* What a killed writer of t.bsdf left an hour ago, one that is still
     * writing (modified a second ago), another target's, and a name that
     * only resembles the pattern (5 random characters). */
    snprintf(stale, sizeof stale, "%s/.t.bsdf.Ab3xYz.tmp", dir);
    snprintf(fresh, sizeof fresh, "%s/.t.bsdf.Qq9Rr8.tmp", dir);
    snprintf(other, sizeof other, "%s/.u.bsdf.Ab3xYz.tmp", dir);
    snprintf(near, sizeof near, "%s/.t.bsdf.Ab3xY.tmp", dir);
    touch(stale, 3600);
    touch(fresh, 1);
    touch(other, 3600);
    touch(near, 3600);
    assert_int_equal(write_to(path), LL_OK);
    opens(path);
    assert_false(exists(stale));
    assert_true(exists(fresh) && exists(other) && exists(near));
    /* The target and the three that are not ours to remove: no placeholder
     * of this write remains. */
    assert_int_equal(ll_test_count_entries(dir), 4);
}

static void temporary_is_hidden(void **state)
{
    char dir[600], path[700];
    pid_t pid;
    int status;
    (void)state;
    fresh_dir("hidden", dir, sizeof dir);
    snprintf(path, sizeof path, "%s/t.bsdf", dir);
    /* A write killed half-way (file size limit, SIGXFSZ at its default)
     * leaves its temporary: it must be hidden and of the documented
     * pattern, and the next writer (an hour later) removes it. */
    pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        struct rlimit limit;
        limit.rlim_cur = limit.rlim_max = 100;
        setrlimit(RLIMIT_FSIZE, &limit);
        write_to(path);
        _exit(0);
    }
    assert_int_equal(waitpid(pid, &status, 0), pid);
    {
        DIR *d = opendir(dir);
        struct dirent *e;
        size_t found = 0;
        assert_non_null(d);
        while ((e = readdir(d)) != NULL) {
            char temp[800];
            size_t len = strlen(e->d_name);
            if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0)
                continue;
            assert_true(e->d_name[0] == '.');
            assert_true(strncmp(e->d_name, ".t.bsdf.", 8) == 0 && len == 8 + 6 + 4 &&
                        strcmp(e->d_name + len - 4, ".tmp") == 0);
            snprintf(temp, sizeof temp, "%s/%s", dir, e->d_name);
            touch(temp, 3600);
            ++found;
        }
        closedir(d);
        assert_int_equal(found, 1);
    }
    assert_int_equal(write_to(path), LL_OK);
    assert_int_equal(ll_test_count_entries(dir), 1);
}

static void mode_follows_umask(void **state)
{
    char dir[600], path[700];
    struct stat st;
    mode_t old = umask(027);
    (void)state;
    fresh_dir("mode", dir, sizeof dir);
    snprintf(path, sizeof path, "%s/t.bsdf", dir);
    assert_int_equal(write_to(path), LL_OK);
    assert_int_equal(stat(path, &st), 0);
    assert_int_equal(st.st_mode & 07777, 0640);
    /* An existing target keeps its mode, whatever the umask. */
    assert_int_equal(chmod(path, 0604), 0);
    assert_int_equal(write_to(path), LL_OK);
    assert_int_equal(stat(path, &st), 0);
    assert_int_equal(st.st_mode & 07777, 0604);
    umask(old);
}

static void symlink_written_through(void **state)
{
    char dir[600], sub[700], link[700], real[800], chain[700], dangling[700], made[800];
    struct stat st;
    (void)state;
    fresh_dir("links", dir, sizeof dir);
    snprintf(sub, sizeof sub, "%s/store", dir);
    assert_int_equal(mkdir(sub, 0700), 0);
    snprintf(real, sizeof real, "%s/real.bsdf", sub);
    ll_test_write_file(real, "old", 3);
    snprintf(link, sizeof link, "%s/link.bsdf", dir);
    assert_int_equal(symlink("store/real.bsdf", link), 0);   /* relative */
    snprintf(chain, sizeof chain, "%s/chain.bsdf", dir);
    assert_int_equal(symlink(link, chain), 0);                /* absolute, to a link */
    assert_int_equal(write_to(chain), LL_OK);
    /* Both links stay links; the file at the end is the new one, replaced
     * in its own directory (nothing else appeared in either folder). */
    assert_int_equal(lstat(link, &st), 0);
    assert_true(S_ISLNK(st.st_mode));
    assert_int_equal(lstat(chain, &st), 0);
    assert_true(S_ISLNK(st.st_mode));
    assert_int_equal(lstat(real, &st), 0);
    assert_true(S_ISREG(st.st_mode) && st.st_size > 3);
    opens(link);
    assert_int_equal(ll_test_count_entries(dir), 3);
    assert_int_equal(ll_test_count_entries(sub), 1);
    /* A dangling link: the file it names is created. */
    snprintf(dangling, sizeof dangling, "%s/dangling.bsdf", dir);
    assert_int_equal(symlink("store/made.bsdf", dangling), 0);
    assert_int_equal(write_to(dangling), LL_OK);
    snprintf(made, sizeof made, "%s/made.bsdf", sub);
    opens(made);
    assert_int_equal(lstat(dangling, &st), 0);
    assert_true(S_ISLNK(st.st_mode));
    /* A cycle is an error naming the path. */
    {
        char a[700], b[700];
        snprintf(a, sizeof a, "%s/a.bsdf", dir);
        snprintf(b, sizeof b, "%s/b.bsdf", dir);
        assert_int_equal(symlink("b.bsdf", a), 0);
        assert_int_equal(symlink("a.bsdf", b), 0);
        assert_int_equal(write_to(a), LL_ERROR_IO);
        assert_non_null(strstr(ll_last_error_message(), a));
    }
}

static void long_names(void **state)
{
    char dir[600], path[1000], name[NAME_MAX + 2];
    size_t len;
    (void)state;
    fresh_dir("long", dir, sizeof dir);
    /* The longest names the file system takes, and one beyond. */
    for (len = NAME_MAX - 13; len <= NAME_MAX; ++len) {
        memset(name, 'n', len);
        memcpy(name + len - 5, ".bsdf", 5);
        name[len] = '\0';
        snprintf(path, sizeof path, "%s/%s", dir, name);
        if (write_to(path) != LL_OK)
            fail_msg("name of %zu bytes: %s", len, ll_last_error_message());
        opens(path);
        assert_int_equal(ll_test_count_entries(dir), 1);
        assert_int_equal(unlink(path), 0);
    }
    memset(name, 'n', NAME_MAX + 1);
    name[NAME_MAX + 1] = '\0';
    snprintf(path, sizeof path, "%s/%s", dir, name);
    assert_int_equal(write_to(path), LL_ERROR_IO);
    assert_int_equal(ll_test_count_entries(dir), 0);
}

/* A real full disk: a 64 KiB tmpfs (needs the right to mount, as root in
 * CI's container); else the file size limit plays it (EFBIG). Either way
 * the message names the target and no temporary remains. */
static void disk_full_names_target(void **state)
{
    char dir[600], path[700];
    ll_layer *big = ll_test_layer(40, 60);
    const ll_layer *one[1];
    double sharp = 4.0;
    ll_bsdf_write_options opts = LL_BSDF_WRITE_OPTIONS_INIT;
    int mounted;
    (void)state;
    fresh_dir("full", dir, sizeof dir);
    ll_test_fill(big, ll_test_lobe_fn, &sharp);
    one[0] = big;
    opts.error_goal = 0.0; /* about 1 MB */
    mounted = mount("tmpfs", dir, "tmpfs", 0, "size=64k") == 0;
    snprintf(path, sizeof path, "%s/t.bsdf", dir);
    if (mounted) {
        assert_int_equal(ll_bsdf_write(path, one, 1, &opts, NULL), LL_ERROR_IO);
        assert_non_null(strstr(ll_last_error_message(), strerror(ENOSPC)));
    } else {
        pid_t pid;
        int status;
        print_message("[ INFO     ] cannot mount a tmpfs (%s): the file size limit plays "
                      "the full disk\n", strerror(errno));
        pid = fork();
        assert_true(pid >= 0);
        if (pid == 0) {
            struct rlimit limit;
            ll_status s;
            signal(SIGXFSZ, SIG_IGN);
            limit.rlim_cur = limit.rlim_max = 65536;
            setrlimit(RLIMIT_FSIZE, &limit);
            s = ll_bsdf_write(path, one, 1, &opts, NULL);
            _exit(s == LL_ERROR_IO && strstr(ll_last_error_message(), path) &&
                          !strstr(ll_last_error_message(), ".tmp")
                      ? 0
                      : 1);
        }
        assert_int_equal(waitpid(pid, &status, 0), pid);
        assert_true(WIFEXITED(status) && WEXITSTATUS(status) == 0);
    }
    if (mounted) {
        const char *msg = ll_last_error_message();
        if (!strstr(msg, "\"") || !strstr(msg, path) || strstr(msg, ".tmp"))
            fail_msg("the message should name %s and no temporary: %s", path, msg);
        assert_int_equal(ll_test_count_entries(dir), 0);
        assert_int_equal(umount(dir), 0);
    }
    assert_int_equal(ll_test_count_entries(dir), 0);
    ll_layer_destroy(big);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(stale_temporaries_removed),
        cmocka_unit_test(temporary_is_hidden),
        cmocka_unit_test(mode_follows_umask),
        cmocka_unit_test(symlink_written_through),
        cmocka_unit_test(long_names),
        cmocka_unit_test(disk_full_names_target),
    };
    return cmocka_run_group_tests_name("bsdf_output", tests, setup, teardown);
}
