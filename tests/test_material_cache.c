/*
 * The resolution search's choices kept between processes
 * (ll_build_options.cache_dir): a word searched once is answered from its
 * entry; an entry that is damaged, or holds another key, is not trusted
 * but searched again and rewritten; no cache_dir, no file; builds sharing
 * the directory at once leave whole entries; the user's directory comes
 * from LAYERLAB_CACHE_DIR, XDG_CACHE_HOME or HOME; a channel whose search
 * starts at the channel before's answer is remembered under that start,
 * so a build chooses the same whatever the cache holds. Every directory is
 * a scratch one (the user's own cache is never touched).
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <dirent.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <layerlab.h>
#include "test_util.h"

/* One word with a cheap search (0.2 s of CPU): a rough conductor. */
static const char conductor[] = "conductor eta=0.2+3i alpha=0.5\n";

/* Counts the searches a call runs: each is one "resolution K/COUNT"
 * stage (ll_material.h's monitor); a cache hit runs none. */
typedef struct search_count {
    int searches;
    char last[64];
} search_count;

static int count_searches(void *user, double fraction, const char *stage)
{
    search_count *c = user;
    (void)fraction;
    if (strncmp(stage, "resolution ", 11) == 0 && strcmp(stage, c->last) != 0) {
        ++c->searches;
        snprintf(c->last, sizeof c->last, "%s", stage);
    }
    return 0;
}

/* The resolution of text with cache_dir (nullable); *searches receives the
 * searches it ran. */
static void resolve(const char *text, const char *cache_dir, size_t *n, size_t *m,
                    int *searches)
{
    ll_material *mat = NULL;
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    ll_monitor monitor = LL_MONITOR_INIT;
    search_count count = { 0, "" };
    size_t c;
    assert_int_equal(ll_material_parse(text, "t", &mat), LL_OK);
    o.cache_dir = cache_dir;
    monitor.progress = count_searches;
    monitor.user = &count;
    if (ll_material_resolution(mat, &o, &monitor, n, m, &c) != LL_OK)
        fail_msg("%s", ll_last_error_message());
    ll_material_destroy(mat);
    *searches = count.searches;
}

/* A fresh directory under the group's scratch directory. */
static void fresh_dir(const char *name, char *dir, size_t size)
{
    snprintf(dir, size, "%s/%s", ll_test_dir(), name);
    ll_test_rmdir(dir);
}

/* The path of the directory's only entry. */
static void only_entry(const char *dir, char *path, size_t size)
{
    char name[300];
    DIR *d = opendir(dir);
    struct dirent *e;
    int found = 0;
    assert_non_null(d);
    while ((e = readdir(d)) != NULL)
        if (e->d_name[0] != '.') {
            assert_false(found);
            snprintf(name, sizeof name, "%s", e->d_name);
            found = 1;
        }
    closedir(d);
    assert_true(found);
    assert_true((size_t)snprintf(path, size, "%s/%.299s", dir, name) < size);
}

/* The entries' checksum (FNV-1a, 64 bits), to forge a whole entry. */
static unsigned long long fnv1a(const char *text, size_t len)
{
    unsigned long long h = 14695981039346656037ULL;
    size_t k;
    for (k = 0; k < len; ++k) {
        h ^= (unsigned char)text[k];
        h *= 1099511628211ULL;
    }
    return h;
}

static void write_text(const char *path, const char *text, size_t len)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(text, 1, len, f), len);
    assert_int_equal(fclose(f), 0);
}

/* Searched once, then answered from the entry with the same resolution;
 * without a cache_dir nothing is written and the search runs every time. */
static void second_call_is_answered_from_the_cache(void **state)
{
    char dir[600];
    size_t n1, m1, n2, m2, n3, m3;
    int searches;
    (void)state;
    fresh_dir("hit", dir, sizeof dir);
    resolve(conductor, dir, &n1, &m1, &searches);
    assert_int_equal(searches, 1);
    assert_int_equal(ll_test_count_entries(dir), 1); /* (created, one entry) */
    resolve(conductor, dir, &n2, &m2, &searches);
    assert_int_equal(searches, 0);
    assert_int_equal(n2, n1);
    assert_int_equal(m2, m1);
    /* Another tolerance is another key. */
    resolve("set tolerance=0.02\nconductor eta=0.2+3i alpha=0.5\n", dir, &n3, &m3, &searches);
    assert_int_equal(searches, 1);
    assert_int_equal(ll_test_count_entries(dir), 2);
    /* No cache_dir: the search runs and nothing is written anywhere. */
    resolve(conductor, NULL, &n3, &m3, &searches);
    assert_int_equal(searches, 1);
    assert_int_equal(n3, n1);
    assert_int_equal(m3, m1);
    assert_int_equal(ll_test_count_entries(dir), 2);
}

/* A metal's second channel starts its search at the first channel's
 * answer: the same channel after another first channel is another key. B
 * shares its second and third channels with A (the third is the second's
 * search), not its first; after A has filled the cache, B searches its
 * first channel and its second again, and chooses what it chose cold. */
static void a_channels_start_is_part_of_its_key(void **state)
{
    static const char a[] = "conductor eta=0.2+3i alpha=0.5,0.3,0.3\n";
    static const char b[] = "conductor eta=0.2+3i alpha=0.2,0.3,0.3\n";
    char dir[600];
    size_t na, ma, nb, mb, n, m;
    int searches;
    (void)state;
    fresh_dir("start", dir, sizeof dir);
    resolve(b, NULL, &nb, &mb, &searches);
    assert_int_equal(searches, 2);
    resolve(a, dir, &na, &ma, &searches);
    assert_int_equal(searches, 2);
    assert_int_equal(ll_test_count_entries(dir), 2);
    resolve(b, dir, &n, &m, &searches);
    assert_int_equal(searches, 2);
    assert_int_equal(ll_test_count_entries(dir), 4);
    assert_int_equal(n, nb);
    assert_int_equal(m, mb);
    resolve(a, dir, &n, &m, &searches);
    assert_int_equal(searches, 0);
    assert_int_equal(n, na);
    assert_int_equal(m, ma);
}

/* Damage of every kind: the entry is searched again and rewritten whole. */
static void damaged_entries_are_not_trusted(void **state)
{
    char dir[600], path[1024];
    unsigned char *good, *now;
    size_t n, m, n1, m1, len, now_len, k;
    int searches;
    (void)state;
    fresh_dir("damaged", dir, sizeof dir);
    resolve(conductor, dir, &n, &m, &searches);
    only_entry(dir, path, sizeof path);
    good = ll_test_read_file(path, &len);
    for (k = 0; k < 6; ++k) {
        char text[8192];
        size_t text_len = len;
        assert_true(len < sizeof text);
        memcpy(text, good, len);
        text[len] = '\0';
        switch (k) {
        case 0: /* truncated */
            text_len = len / 2;
            break;
        case 1: { /* the answer changed, checksum kept: 2 more nodes */
            char *line = strchr(strchr(text, '\n') + 1, '\n') + 1;
            char rest[8192];
            unsigned long nodes = strtoul(line, NULL, 10);
            snprintf(rest, sizeof rest, "%s", strchr(line, ' '));
            text_len = (size_t)(line - text) +
                       (size_t)snprintf(line, sizeof text - (size_t)(line - text), "%lu%s",
                                        nodes + 2, rest);
            break;
        }
        case 2: /* one flipped bit in the checksum */
            text[len - 2] ^= 1;
            break;
        case 3: /* empty */
            text_len = 0;
            break;
        case 4: { /* an entry of another search revision, checksum and all */
            char *sum, *at = strstr(text, " search ");
            assert_non_null(at);
            at[8] = at[8] == '0' ? '1' : '0'; /* (the revision's first digit) */
            sum = text + len - 17;
            snprintf(sum, 18, "%016llx\n", fnv1a(text, (size_t)(sum - text)));
            break;
        }
        default: { /* another key's whole entry, checksum and all, under this name */
            char *sum;
            memcpy(strstr(text, "conductor"), "dielectri", 9);
            sum = text + len - 17;
            snprintf(sum, 18, "%016llx\n", fnv1a(text, (size_t)(sum - text)));
            break;
        }
        }
        write_text(path, text, text_len);
        resolve(conductor, dir, &n1, &m1, &searches);
        assert_int_equal(searches, 1);
        assert_int_equal(n1, n);
        assert_int_equal(m1, m);
        now = ll_test_read_file(path, &now_len);
        assert_int_equal(now_len, len);
        assert_memory_equal(now, good, len);
        free(now);
    }
    assert_int_equal(ll_test_count_entries(dir), 1); /* (no temporary left) */
    free(good);
}

/* Builds sharing the directory at once (threads here, each its own
 * call, as processes would be): each gets the answer, and the entry left
 * is whole (then a hit), with no temporary file beside it. */
typedef struct racer {
    const char *dir;
    size_t n, m;
    ll_status status;
} racer;

static void *race(void *arg)
{
    racer *r = arg;
    ll_material *mat = NULL;
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    size_t c;
    o.cache_dir = r->dir;
    o.threads = 1;
    r->status = ll_material_parse(conductor, "t", &mat);
    if (r->status == LL_OK)
        r->status = ll_material_resolution(mat, &o, NULL, &r->n, &r->m, &c);
    ll_material_destroy(mat);
    return NULL;
}

static void concurrent_builds_leave_whole_entries(void **state)
{
    char dir[600];
    size_t n, m, n1, m1;
    pthread_t thread[4];
    racer racers[4];
    int k, searches;
    (void)state;
    fresh_dir("concurrent", dir, sizeof dir);
    resolve(conductor, NULL, &n, &m, &searches);
    for (k = 0; k < 4; ++k) {
        racers[k].dir = dir;
        assert_int_equal(pthread_create(&thread[k], NULL, race, &racers[k]), 0);
    }
    for (k = 0; k < 4; ++k) {
        assert_int_equal(pthread_join(thread[k], NULL), 0);
        assert_int_equal(racers[k].status, LL_OK);
        assert_int_equal(racers[k].n, n);
        assert_int_equal(racers[k].m, m);
    }
    assert_int_equal(ll_test_count_entries(dir), 1);
    resolve(conductor, dir, &n1, &m1, &searches);
    assert_int_equal(searches, 0);
    assert_int_equal(n1, n);
    assert_int_equal(m1, m);
}

/* A caller built against the struct without cache_dir gets no cache. */
static void older_struct_has_no_cache(void **state)
{
    char dir[600];
    ll_material *mat = NULL;
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    size_t n, m, c;
    (void)state;
    fresh_dir("older", dir, sizeof dir);
    assert_int_equal(ll_material_parse(conductor, "t", &mat), LL_OK);
    o.cache_dir = dir;
    o.struct_size = offsetof(ll_build_options, cache_dir);
    assert_int_equal(ll_material_resolution(mat, &o, NULL, &n, &m, &c), LL_OK);
    assert_int_equal(access(dir, F_OK), -1);
    ll_material_destroy(mat);
}

/* $LAYERLAB_CACHE_DIR, else an absolute $XDG_CACHE_HOME/layerlab, else
 * $HOME/.cache/layerlab; a short buffer or no variable is refused. */
static void the_user_cache_directory(void **state)
{
    char buf[256], tiny[8];
    const char *saved[3] = { getenv("LAYERLAB_CACHE_DIR"), getenv("XDG_CACHE_HOME"),
                             getenv("HOME") };
    char *copy[3];
    int k;
    (void)state;
    for (k = 0; k < 3; ++k)
        copy[k] = saved[k] ? strdup(saved[k]) : NULL;
    setenv("LAYERLAB_CACHE_DIR", "/x/ll", 1);
    setenv("XDG_CACHE_HOME", "/x/xdg", 1);
    setenv("HOME", "/x/home", 1);
    assert_int_equal(ll_material_cache_dir(buf, sizeof buf), LL_OK);
    assert_string_equal(buf, "/x/ll");
    unsetenv("LAYERLAB_CACHE_DIR");
    assert_int_equal(ll_material_cache_dir(buf, sizeof buf), LL_OK);
    assert_string_equal(buf, "/x/xdg/layerlab");
    setenv("XDG_CACHE_HOME", "relative", 1);
    assert_int_equal(ll_material_cache_dir(buf, sizeof buf), LL_OK);
    assert_string_equal(buf, "/x/home/.cache/layerlab");
    assert_int_equal(ll_material_cache_dir(tiny, sizeof tiny), LL_ERROR_INVALID_ARGUMENT);
    assert_string_equal(tiny, "");
    unsetenv("XDG_CACHE_HOME");
    unsetenv("HOME");
    assert_int_equal(ll_material_cache_dir(buf, sizeof buf), LL_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(ll_last_error_message(), "HOME"));
    assert_int_equal(ll_material_cache_dir(NULL, 4), LL_ERROR_INVALID_ARGUMENT);
    {
        static const char *const names[3] = { "LAYERLAB_CACHE_DIR", "XDG_CACHE_HOME", "HOME" };
        for (k = 0; k < 3; ++k) {
            if (copy[k])
                setenv(names[k], copy[k], 1);
            else
                unsetenv(names[k]);
            free(copy[k]);
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(second_call_is_answered_from_the_cache),
        cmocka_unit_test(damaged_entries_are_not_trusted),
        cmocka_unit_test(a_channels_start_is_part_of_its_key),
        cmocka_unit_test(concurrent_builds_leave_whole_entries),
        cmocka_unit_test(older_struct_has_no_cache),
        cmocka_unit_test(the_user_cache_directory),
    };
    return cmocka_run_group_tests(tests, ll_test_dir_setup, ll_test_dir_teardown);
}
