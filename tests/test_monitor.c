/*
 * The public monitor (ll_monitor), the last argument of every long call:
 * the results with a monitor equal those without (NULL), bit for bit;
 * progress is called on the calling thread only, never decreases, starts
 * at 0 and ends at 1; a cancel from the callback at the first, a middle and
 * the last report returns LL_ERROR_CANCELLED and leaves the output exactly
 * as it was (layers, quadrature buffers, files); a callback returning a
 * flag raised from outside (as a signal handler would) stops doubling; a
 * monitor with a bad struct_size is refused.
 */
#include "test_util.h"
#include "grammar/grammar.h"

#include <pthread.h>
#include <stdint.h>

#define N 40
#define M 8

/* ------------------------------------------------------------ recording */

/* When to cancel: never, at report `at` (1-based), at the first report at
 * or past fraction 0.5 (and below 1), or at the report of 1. */
typedef enum { NEVER, AT_FIRST, AT_MIDDLE, AT_LAST } when;

typedef struct recorder {
    when cancel_when;
    size_t calls, calls_after_cancel;
    int cancelled, monotone, wrong_thread, bad_fraction, saw_middle;
    double first, last;
    const char *stage;
    pthread_t thread;
} recorder;

static int record(void *user, double fraction, const char *stage)
{
    recorder *r = user;
    int stop = 0;
    if (r->cancelled)
        ++r->calls_after_cancel;
    if (!pthread_equal(pthread_self(), r->thread))
        r->wrong_thread = 1;
    if (!(fraction >= 0.0 && fraction <= 1.0))
        r->bad_fraction = 1;
    if (r->calls == 0)
        r->first = fraction;
    else if (fraction < r->last)
        r->monotone = 0;
    if (fraction >= 0.5 && fraction < 1.0)
        r->saw_middle = 1;
    r->last = fraction;
    r->stage = stage;
    ++r->calls;
    switch (r->cancel_when) {
    case AT_FIRST: stop = r->calls == 1; break;
    case AT_MIDDLE: stop = fraction >= 0.5 && fraction < 1.0; break;
    case AT_LAST: stop = fraction == 1.0; break;
    default: break;
    }
    if (stop && !r->cancelled) {
        r->cancelled = 1;
        return 1;
    }
    return 0;
}

static ll_monitor recorder_monitor(recorder *r, when w)
{
    ll_monitor m = LL_MONITOR_INIT;
    memset(r, 0, sizeof *r);
    r->cancel_when = w;
    r->monotone = 1;
    r->thread = pthread_self();
    m.progress = record;
    m.user = r;
    return m;
}

/* ------------------------------------------------------------ snapshots */

typedef struct snapshot {
    size_t n, m;
    double *values; /* m x n x n */
} snapshot;

static snapshot take(const ll_layer *l)
{
    snapshot s;
    size_t k;
    s.n = ll_layer_node_count(l);
    s.m = ll_layer_order_count(l);
    s.values = malloc(s.m * s.n * s.n * sizeof(double));
    assert_non_null(s.values);
    for (k = 0; k < s.m; ++k)
        assert_int_equal(ll_layer_matrix(l, k, s.values + k * s.n * s.n), LL_OK);
    return s;
}

static void assert_same(const snapshot *a, const ll_layer *l, const char *what)
{
    snapshot b = take(l);
    assert_int_equal(a->n, b.n);
    assert_int_equal(a->m, b.m);
    if (memcmp(a->values, b.values, a->m * a->n * a->n * sizeof(double)) != 0)
        fail_msg("%s: the layer differs", what);
    free(b.values);
}

/* --------------------------------------------------------- the operations */

static char merl_path[600];

typedef struct operation {
    const char *name;
    void (*prepare)(ll_layer *l); /* the state before the call */
    ll_status (*run)(ll_layer *l, const ll_monitor *monitor);
} operation;

static ll_layer *other_layer(void)
{
    ll_layer *t = ll_test_layer(N, M);
    assert_int_equal(ll_test_set_microfacet(t, 1.5, 0.0, 0.3, 1, 0, NULL), LL_OK);
    return t;
}

static void prep_hg(ll_layer *l)
{
    assert_int_equal(ll_layer_set_henyey_greenstein(l, 0.9, 0.6, NULL), LL_OK);
}
static void prep_diffuse(ll_layer *l) { assert_int_equal(ll_layer_set_diffuse(l, 0.4, NULL), LL_OK); }

static ll_status run_expand(ll_layer *l, const ll_monitor *m)
{
    return ll_layer_expand(l, 2.0, m);
}
static ll_status run_add(ll_layer *l, const ll_monitor *m)
{
    ll_layer *top = other_layer();
    ll_status s = ll_layer_add(top, l, l, 0, m);
    ll_layer_destroy(top);
    return s;
}
static ll_status run_dielectric(ll_layer *l, const ll_monitor *m)
{
    return ll_test_set_microfacet(l, 1.5, 0.0, 0.2, 1, 0, m);
}
static ll_status run_conductor(ll_layer *l, const ll_monitor *m)
{
    return ll_test_set_microfacet(l, 0.2, 3.0, 0.4, 1, 0, m);
}
static ll_status run_isotropic(ll_layer *l, const ll_monitor *m)
{
    return ll_layer_set_isotropic(l, 0.8, m);
}
static ll_status run_hg(ll_layer *l, const ll_monitor *m)
{
    return ll_layer_set_henyey_greenstein(l, 0.8, -0.4, m);
}
static ll_status run_vmf(ll_layer *l, const ll_monitor *m)
{
    return ll_layer_set_von_mises_fisher(l, 0.8, 5.0, m);
}
static ll_status run_diffuse(ll_layer *l, const ll_monitor *m)
{
    return ll_layer_set_diffuse(l, 0.3, m);
}
static ll_status run_matusik(ll_layer *l, const ll_monitor *m)
{
    return ll_layer_set_matusik(l, merl_path, 1, 0, m);
}

static const operation operations[] = {
    { "expand", prep_hg, run_expand },
    { "add", prep_diffuse, run_add },
    { "dielectric", prep_diffuse, run_dielectric },
    { "conductor", prep_hg, run_conductor },
    { "isotropic", prep_diffuse, run_isotropic },
    { "henyey-greenstein", prep_diffuse, run_hg },
    { "von mises-fisher", prep_diffuse, run_vmf },
    { "matusik", prep_hg, run_matusik },
    { "diffuse", prep_hg, run_diffuse },
};

static ll_layer *prepared(const operation *op)
{
    ll_layer *l = ll_test_layer(N, M);
    op->prepare(l);
    return l;
}

/* A small glossy MERL file (as the database's layout, 16 x 12 x 24). */
static void write_merl(const char *file)
{
    FILE *f = fopen(file, "wb");
    uint32_t dims[3] = { 16, 12, 24 };
    size_t i, k, count = 3 * 16 * 12 * 24;
    unsigned char b[8];
    assert_non_null(f);
    for (k = 0; k < 3; ++k) {
        for (i = 0; i < 4; ++i)
            b[i] = (unsigned char)(dims[k] >> (8 * i) & 0xff);
        assert_int_equal(fwrite(b, 1, 4, f), 4);
    }
    for (k = 0; k < count; ++k) {
        size_t ih = k / (12 * 24) % 16;
        double v = 100.0 + 2000.0 * exp(-(double)ih);
        uint64_t bits;
        memcpy(&bits, &v, 8);
        for (i = 0; i < 8; ++i)
            b[i] = (unsigned char)(bits >> (8 * i) & 0xff);
        assert_int_equal(fwrite(b, 1, 8, f), 8);
    }
    fclose(f);
}

static int setup(void **state)
{
    ll_test_dir_setup(state);
    snprintf(merl_path, sizeof merl_path, "%s/glossy.binary", ll_test_dir());
    write_merl(merl_path);
    return 0;
}

/* ------------------------------------------------------------------ tests */

/* On one thread the calling thread does every item and polls at every
 * step, so the reports do not depend on timing (with more threads a small
 * call may be finished by a worker before the calling thread polls). */
static void results_with_a_monitor_equal_results_without(void **state)
{
    size_t i, saved = ll_get_thread_count();
    (void)state;
    assert_int_equal(ll_set_thread_count(1), LL_OK);
    for (i = 0; i < sizeof operations / sizeof operations[0]; ++i) {
        const operation *op = &operations[i];
        ll_layer *plain = prepared(op), *watched = prepared(op);
        recorder r;
        ll_monitor m = recorder_monitor(&r, NEVER);
        snapshot want;
        assert_int_equal(op->run(plain, NULL), LL_OK);
        assert_int_equal(op->run(watched, &m), LL_OK);
        want = take(plain);
        assert_same(&want, watched, op->name);
        /* Progress: on this thread, in [0, 1], never back, 0 first, 1 last. */
        if (r.calls < 3)
            fail_msg("%s: %zu progress reports", op->name, r.calls);
        assert_false(r.wrong_thread);
        assert_false(r.bad_fraction);
        assert_true(r.monotone);
        assert_true(r.first == 0.0);
        assert_true(r.last == 1.0);
        assert_true(r.saw_middle);
        assert_non_null(r.stage);
        assert_true(strlen(r.stage) > 0);
        free(want.values);
        ll_layer_destroy(plain);
        ll_layer_destroy(watched);
    }
    ll_set_thread_count(saved);
}

/* On one thread, and on two (where a middle report may not come for a
 * small call: then that case is skipped). */
static void cancel_at_first_middle_and_last_report_leaves_the_layer(void **state)
{
    static const when moments[] = { AT_FIRST, AT_MIDDLE, AT_LAST };
    size_t i, j, threads, saved = ll_get_thread_count();
    (void)state;
    for (threads = 1; threads <= 2; ++threads)
    for (i = 0; i < sizeof operations / sizeof operations[0]; ++i)
        for (j = 0; j < 3; ++j) {
            const operation *op = &operations[i];
            ll_layer *l = prepared(op);
            snapshot before = take(l);
            recorder r;
            ll_monitor m = recorder_monitor(&r, moments[j]);
            ll_status s;
            assert_int_equal(ll_set_thread_count(threads), LL_OK);
            s = op->run(l, &m);
            if (threads > 1 && moments[j] == AT_MIDDLE && !r.cancelled) {
                assert_int_equal(s, LL_OK);
                free(before.values);
                ll_layer_destroy(l);
                continue;
            }
            if (s != LL_ERROR_CANCELLED)
                fail_msg("%s, cancel %zu: status %d (%s), %zu reports", op->name, j, (int)s,
                         ll_last_error_message(), r.calls);
            assert_true(r.cancelled);
            assert_false(r.wrong_thread);
            assert_same(&before, l, op->name);
            free(before.values);
            ll_layer_destroy(l);
        }
    ll_set_thread_count(saved);
}

/* One thread or two, the monitor changes nothing (the bodies run the
 * same operations) and still only the calling thread is called back. */
static void any_thread_count_gives_the_same_bits(void **state)
{
    size_t saved = ll_get_thread_count(), i;
    (void)state;
    for (i = 0; i < sizeof operations / sizeof operations[0]; ++i) {
        const operation *op = &operations[i];
        ll_layer *one = prepared(op), *two = prepared(op);
        recorder r;
        ll_monitor m = recorder_monitor(&r, NEVER);
        snapshot want;
        assert_int_equal(ll_set_thread_count(1), LL_OK);
        assert_int_equal(op->run(one, &m), LL_OK);
        assert_int_equal(ll_set_thread_count(2), LL_OK);
        assert_int_equal(op->run(two, &m), LL_OK);
        want = take(one);
        assert_same(&want, two, op->name);
        assert_false(r.wrong_thread);
        free(want.values);
        ll_layer_destroy(one);
        ll_layer_destroy(two);
    }
    ll_set_thread_count(saved);
}

typedef ll_status (*rule)(size_t, double *, double *, const ll_monitor *);

static void quadrature_with_a_monitor(void **state)
{
    static const rule rules[2] = { ll_quad_gauss_legendre, ll_quad_gauss_lobatto };
    static const when moments[] = { AT_FIRST, AT_MIDDLE, AT_LAST };
    const size_t n = 3000;
    double *x = malloc(n * sizeof *x), *w = malloc(n * sizeof *w);
    double *x0 = malloc(n * sizeof *x0), *w0 = malloc(n * sizeof *w0);
    size_t k, j, i;
    (void)state;
    assert_true(x && w && x0 && w0);
    /* (The rules run on the calling thread alone.) */
    for (k = 0; k < 2; ++k) {
        recorder r;
        ll_monitor m = recorder_monitor(&r, NEVER);
        assert_int_equal(rules[k](n, x0, w0, NULL), LL_OK);
        assert_int_equal(rules[k](n, x, w, &m), LL_OK);
        assert_memory_equal(x, x0, n * sizeof *x);
        assert_memory_equal(w, w0, n * sizeof *w);
        assert_true(r.calls >= 3 && r.monotone && r.first == 0.0 && r.last == 1.0);
        assert_true(r.saw_middle);
        assert_string_equal(r.stage, "quadrature");
        for (j = 0; j < 3; ++j) {
            m = recorder_monitor(&r, moments[j]);
            for (i = 0; i < n; ++i)
                x[i] = w[i] = -7.0;
            assert_int_equal(rules[k](n, x, w, &m), LL_ERROR_CANCELLED);
            for (i = 0; i < n; ++i)
                if (x[i] != -7.0 || w[i] != -7.0)
                    fail_msg("rule %zu, cancel %zu: buffer entry %zu was written", k, j, i);
        }
    }
    free(x);
    free(w);
    free(x0);
    free(w0);
}

static void writer_with_a_monitor(void **state)
{
    static const when moments[] = { AT_FIRST, AT_MIDDLE, AT_LAST };
    char plain_path[700], path[700];
    ll_layer *l = other_layer();
    const ll_layer *layers[1];
    unsigned char *a, *b;
    size_t size_a, size_b, j, entries;
    recorder r;
    ll_monitor m = recorder_monitor(&r, NEVER);
    (void)state;
    layers[0] = l;
    snprintf(plain_path, sizeof plain_path, "%s/plain.bsdf", ll_test_dir());
    snprintf(path, sizeof path, "%s/watched.bsdf", ll_test_dir());
    assert_int_equal(ll_bsdf_write(plain_path, layers, 1, NULL, NULL), LL_OK);
    assert_int_equal(ll_bsdf_write(path, layers, 1, NULL, &m), LL_OK);
    assert_true(r.calls >= 3 && r.monotone && r.first == 0.0 && r.last == 1.0);
    assert_false(r.wrong_thread);
    a = ll_test_read_file(plain_path, &size_a);
    b = ll_test_read_file(path, &size_b);
    assert_int_equal(size_a, size_b);
    assert_memory_equal(a, b, size_a);
    free(b);
    entries = ll_test_count_entries(ll_test_dir());
    /* A cancelled write keeps the existing file as it was and leaves no
     * temporary; a new target is not created. */
    for (j = 0; j < 3; ++j) {
        char fresh[720];
        m = recorder_monitor(&r, moments[j]);
        assert_int_equal(ll_bsdf_write(path, layers, 1, NULL, &m), LL_ERROR_CANCELLED);
        b = ll_test_read_file(path, &size_b);
        assert_int_equal(size_a, size_b);
        assert_memory_equal(a, b, size_a);
        free(b);
        snprintf(fresh, sizeof fresh, "%s/fresh%zu.bsdf", ll_test_dir(), j);
        m = recorder_monitor(&r, moments[j]);
        assert_int_equal(ll_bsdf_write(fresh, layers, 1, NULL, &m), LL_ERROR_CANCELLED);
        assert_int_equal(access(fresh, F_OK), -1);
        assert_int_equal(ll_test_count_entries(ll_test_dir()), entries);
    }
    free(a);
    ll_layer_destroy(l);
}

/* A callback that returns a flag raised from outside (as llbuild's signal
 * handler raises one): the doublings stop and leave the phase function. */
static int flag_from_callback(void *user, double fraction, const char *stage)
{
    (void)fraction;
    (void)stage;
    return *(const volatile int *)user;
}

static void a_raised_flag_and_bad_monitors(void **state)
{
    ll_layer *l = ll_test_layer(N, M);
    volatile int answer = 1; /* what the callback returns: cancel */
    ll_monitor m = LL_MONITOR_INIT, bad = LL_MONITOR_INIT, old = LL_MONITOR_INIT;
    snapshot before;
    (void)state;
    prep_hg(l);
    before = take(l);
    m.progress = flag_from_callback;
    m.user = (void *)(uintptr_t)&answer;
    assert_int_equal(ll_layer_expand(l, 3.0, &m), LL_ERROR_CANCELLED);
    assert_same(&before, l, "monitor");
    /* struct_size 0 is an uninitialised monitor. */
    bad.struct_size = 0;
    bad.progress = flag_from_callback;
    assert_int_equal(ll_layer_expand(l, 3.0, &bad), LL_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(ll_last_error_message(), "LL_MONITOR_INIT"));
    assert_same(&before, l, "bad monitor");
    /* An older, smaller struct without progress: no callback, no cancel. */
    old.struct_size = sizeof(size_t);
    old.progress = flag_from_callback;
    old.user = (void *)(uintptr_t)&answer;
    assert_int_equal(ll_layer_expand(l, 3.0, &old), LL_OK);
    free(before.values);
    ll_layer_destroy(l);
}

/* The material builds: the same layers and file with a monitor; a cancel
 * at the first, a middle and the last report returns no layers, writes no
 * file, keeps an existing one and leaves no temporary. */
static void material_builds_with_a_monitor(void **state)
{
    static const when moments[] = { AT_FIRST, AT_MIDDLE, AT_LAST };
    static const char text[] = "set nodes=40 orders=8\n"
                               "dielectric eta=1.5 alpha=0.3\n"
                               "medium albedo=0.8 g=0.5 tau=0.5\n"
                               "diffuse albedo=0.5\n";
    ll_material *mat = NULL;
    ll_layer *plain[3] = { NULL, NULL, NULL }, *watched[3] = { NULL, NULL, NULL };
    size_t nch = 0, nch2 = 0, j, entries, saved = ll_get_thread_count();
    char path[700], plain_path[700];
    unsigned char *a, *b;
    size_t size_a, size_b;
    recorder r;
    ll_monitor m = recorder_monitor(&r, NEVER);
    snapshot want;
    (void)state;
    assert_int_equal(ll_set_thread_count(1), LL_OK);
    assert_int_equal(ll_material_parse(text, "monitor.layers", &mat), LL_OK);
    assert_int_equal(ll_material_build_layers(mat, NULL, NULL, plain, &nch, NULL), LL_OK);
    assert_int_equal(ll_material_build_layers(mat, NULL, &m, watched, &nch2, NULL), LL_OK);
    assert_int_equal(nch, nch2);
    want = take(plain[0]);
    assert_same(&want, watched[0], "ll_material_build_layers with a monitor");
    free(want.values);
    assert_true(r.calls >= 3 && r.monotone && r.first == 0.0 && r.last == 1.0);
    assert_true(r.saw_middle);
    assert_false(r.wrong_thread);
    snprintf(plain_path, sizeof plain_path, "%s/material-plain.bsdf", ll_test_dir());
    snprintf(path, sizeof path, "%s/material.bsdf", ll_test_dir());
    assert_int_equal(ll_material_build(mat, NULL, NULL, plain_path), LL_OK);
    m = recorder_monitor(&r, NEVER);
    assert_int_equal(ll_material_build(mat, NULL, &m, path), LL_OK);
    assert_true(r.calls >= 3 && r.monotone && r.first == 0.0 && r.last == 1.0);
    assert_string_equal(r.stage, "writing");
    a = ll_test_read_file(plain_path, &size_a);
    b = ll_test_read_file(path, &size_b);
    assert_int_equal(size_a, size_b);
    assert_memory_equal(a, b, size_a);
    free(b);
    entries = ll_test_count_entries(ll_test_dir());
    for (j = 0; j < 3; ++j) {
        ll_layer *none[3] = { NULL, NULL, NULL };
        char fresh[720];
        m = recorder_monitor(&r, moments[j]);
        assert_int_equal(ll_material_build_layers(mat, NULL, &m, none, &nch2, NULL),
                         LL_ERROR_CANCELLED);
        assert_true(none[0] == NULL && none[1] == NULL && none[2] == NULL);
        m = recorder_monitor(&r, moments[j]);
        assert_int_equal(ll_material_build(mat, NULL, &m, path), LL_ERROR_CANCELLED);
        b = ll_test_read_file(path, &size_b);
        assert_int_equal(size_a, size_b);
        assert_memory_equal(a, b, size_a);
        free(b);
        snprintf(fresh, sizeof fresh, "%s/material-fresh%zu.bsdf", ll_test_dir(), j);
        m = recorder_monitor(&r, moments[j]);
        assert_int_equal(ll_material_build(mat, NULL, &m, fresh), LL_ERROR_CANCELLED);
        assert_int_equal(access(fresh, F_OK), -1);
        assert_int_equal(ll_test_count_entries(ll_test_dir()), entries);
    }
    free(a);
    for (j = 0; j < 3; ++j) {
        ll_layer_destroy(plain[j]);
        ll_layer_destroy(watched[j]);
    }
    ll_material_destroy(mat);
    ll_set_thread_count(saved);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(results_with_a_monitor_equal_results_without),
        cmocka_unit_test(cancel_at_first_middle_and_last_report_leaves_the_layer),
        cmocka_unit_test(any_thread_count_gives_the_same_bits),
        cmocka_unit_test(quadrature_with_a_monitor),
        cmocka_unit_test(writer_with_a_monitor),
        cmocka_unit_test(a_raised_flag_and_bad_monitors),
        cmocka_unit_test(material_builds_with_a_monitor),
    };
    return cmocka_run_group_tests(tests, setup, ll_test_dir_teardown);
}
