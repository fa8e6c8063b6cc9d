/*
 * Common API: versions, status strings, the thread-local error message and
 * the per-thread worker count.
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <pthread.h>
#include <stdio.h>
#include <string.h>

#include <layerlab.h>

static void test_versions(void **state)
{
    char expected[64];
    (void)state;
    assert_int_equal(ll_version_number(), LL_VERSION_NUMBER);
    assert_int_equal(LL_VERSION_NUMBER,
                     LL_VERSION_MAJOR * 10000 + LL_VERSION_MINOR * 100 + LL_VERSION_PATCH);
    snprintf(expected, sizeof expected, "%d.%d.%d", LL_VERSION_MAJOR, LL_VERSION_MINOR,
             LL_VERSION_PATCH);
    assert_non_null(ll_version_string());
    assert_string_equal(ll_version_string(), expected);
    assert_string_equal(LL_VERSION_STRING, expected);
    assert_true(LL_AT_LEAST_VERSION(LL_VERSION_MAJOR, LL_VERSION_MINOR, LL_VERSION_PATCH));
    assert_true(LL_AT_LEAST_VERSION(0, 0, 0));
    assert_false(LL_AT_LEAST_VERSION(LL_VERSION_MAJOR + 1, 0, 0));
    assert_false(LL_AT_LEAST_VERSION(LL_VERSION_MAJOR, LL_VERSION_MINOR, LL_VERSION_PATCH + 1));
    assert_true(LL_ABI_VERSION >= 1);
}

static void test_status_strings(void **state)
{
    /* Codes are only ever appended: their values are part of the ABI. */
    static const ll_status codes[] = {
        LL_OK,        LL_ERROR_INVALID_ARGUMENT, LL_ERROR_OUT_OF_MEMORY,
        LL_ERROR_IO,  LL_ERROR_FORMAT,           LL_ERROR_NUMERICAL,
        LL_ERROR_UNSUPPORTED, LL_ERROR_PARSE,    LL_ERROR_CANCELLED,
    };
    static const ll_status unknown[] = {-1, 9, 1000, INT32_MIN, INT32_MAX};
    const char *unknown_text = ll_status_string(9);
    size_t i, j, count = sizeof codes / sizeof codes[0];
    (void)state;

    for (i = 0; i < count; ++i)
        assert_int_equal(codes[i], (ll_status)i);
    assert_non_null(unknown_text);
    for (i = 0; i < count; ++i) {
        const char *text = ll_status_string(codes[i]);
        assert_non_null(text);
        assert_true(strlen(text) > 0);
        assert_string_not_equal(text, unknown_text);
        for (j = 0; j < i; ++j)
            assert_string_not_equal(text, ll_status_string(codes[j]));
    }
    for (i = 0; i < sizeof unknown / sizeof unknown[0]; ++i) {
        assert_non_null(ll_status_string(unknown[i]));
        assert_string_equal(ll_status_string(unknown[i]), unknown_text);
    }
}

/* A call that fails with LL_ERROR_INVALID_ARGUMENT on any thread. */
static ll_status fail_with_zero_nodes(void)
{
    double x[1], w[1];
    return ll_quad_gauss_legendre(0, x, w, NULL);
}

/* What a second thread saw: its message before and after its own failure. */
typedef struct {
    char before[256];
    char after[256];
    ll_status status;
} thread_report;

static void *fail_on_other_thread(void *arg)
{
    thread_report *r = arg;
    snprintf(r->before, sizeof r->before, "%s", ll_last_error_message());
    r->status = ll_set_thread_count(5000);
    snprintf(r->after, sizeof r->after, "%s", ll_last_error_message());
    return NULL;
}

static void test_last_error_message(void **state)
{
    thread_report report;
    pthread_t thread;
    char mine[256];
    double x[4], w[4];
    (void)state;

    assert_int_equal(fail_with_zero_nodes(), LL_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(ll_last_error_message(), "ll_quad_gauss_legendre"));
    assert_non_null(strstr(ll_last_error_message(), "n = 0"));
    snprintf(mine, sizeof mine, "%s", ll_last_error_message());

    /* Success does not clear the message. */
    assert_int_equal(ll_quad_gauss_legendre(4, x, w, NULL), LL_OK);
    assert_string_equal(ll_last_error_message(), mine);

    /* A fresh thread starts with "", its failure is its own, and ours is
     * untouched by it. */
    memset(&report, 0, sizeof report);
    assert_int_equal(pthread_create(&thread, NULL, fail_on_other_thread, &report), 0);
    assert_int_equal(pthread_join(thread, NULL), 0);
    assert_string_equal(report.before, "");
    assert_int_equal(report.status, LL_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(report.after, "ll_set_thread_count"));
    assert_non_null(strstr(report.after, "5000"));
    assert_string_equal(ll_last_error_message(), mine);

    /* A new failure here replaces the message. */
    assert_int_equal(ll_quad_composite_simpson(4, x, w), LL_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(ll_last_error_message(), "ll_quad_composite_simpson"));
    assert_null(strstr(ll_last_error_message(), "ll_quad_gauss_legendre"));
}

/* The other thread's view of the count, before and after setting its own
 * (checked on the test's thread: cmocka's asserts must not fire elsewhere). */
typedef struct {
    size_t initial;
    ll_status status;
    size_t after_set;
} count_report;

static void *count_on_other_thread(void *arg)
{
    count_report *r = arg;
    r->initial = ll_get_thread_count();
    r->status = ll_set_thread_count(1);
    r->after_set = ll_get_thread_count();
    return NULL;
}

static void test_thread_count(void **state)
{
    size_t all;
    count_report report;
    pthread_t thread;
    (void)state;

    assert_int_equal(ll_set_thread_count(0), LL_OK);
    all = ll_get_thread_count();
    assert_true(all >= 1);

    assert_int_equal(ll_set_thread_count(3), LL_OK);
    assert_int_equal(ll_get_thread_count(), 3);

    /* A refused count leaves the setting as it was and says why. */
    assert_int_equal(ll_set_thread_count(4097), LL_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(ll_last_error_message(), "4097"));
    assert_int_equal(ll_get_thread_count(), 3);
    assert_int_equal(ll_set_thread_count(4096), LL_OK);
    assert_int_equal(ll_get_thread_count(), 4096);
    assert_int_equal(ll_set_thread_count(3), LL_OK);

    /* The setting belongs to the calling thread. */
    memset(&report, 0, sizeof report);
    assert_int_equal(pthread_create(&thread, NULL, count_on_other_thread, &report), 0);
    assert_int_equal(pthread_join(thread, NULL), 0);
    assert_int_equal(report.initial, all);
    assert_int_equal(report.status, LL_OK);
    assert_int_equal(report.after_set, 1);
    assert_int_equal(ll_get_thread_count(), 3);

    assert_int_equal(ll_set_thread_count(0), LL_OK);
    assert_int_equal(ll_get_thread_count(), all);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_versions),
        cmocka_unit_test(test_status_strings),
        cmocka_unit_test(test_last_error_message),
        cmocka_unit_test(test_thread_count),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
