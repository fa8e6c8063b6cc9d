/*
 * Distributed builds (layerlab/ll_distribution.h) without MPI: the ranks
 * are threads of this process and alltoallv a shared table behind a
 * barrier, so the library's side runs in every `make test`, OpenMPI or
 * not (tests/llbuild_mpi.sh runs the real thing). Files byte-identical to
 * ll_material_build's for 1 to 4 ranks (media, rough interfaces, a
 * measured BRDF, mono and RGB); a failure on one rank (over its budget,
 * cancelled, out of memory at any allocation of any rank) ends every rank
 * with the same status, no file, and rank 0's message naming the rank.
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <layerlab.h>
#include "support/support.h"
#include "test_util.h"

#define MAX_RANKS 4

/* The ranks' meeting point: each posts its send buffer, all meet, each
 * copies its parts from everyone's, all meet again. A rank that aborts
 * (it could not take part) releases the others, whose calls then fail. */
typedef struct fabric {
    int n, arrived, aborted;
    unsigned long generation;
    pthread_mutex_t lock;
    pthread_cond_t moved;
    const unsigned char *send[MAX_RANKS];
    const size_t *send_bytes[MAX_RANKS];
    int calls[MAX_RANKS];
} fabric;

typedef struct rank_run {
    fabric *f;
    int rank;
    const ll_material *material;
    ll_build_options opts;
    const ll_monitor *monitor;
    const char *out;
    ll_status status;
    char message[2048];
} rank_run;

/* All n meet (0), or the fabric was aborted (-1). */
static int meet(fabric *f)
{
    int ok;
    pthread_mutex_lock(&f->lock);
    if (!f->aborted && ++f->arrived == f->n) {
        f->arrived = 0;
        f->generation++;
        pthread_cond_broadcast(&f->moved);
    } else {
        unsigned long g = f->generation;
        while (!f->aborted && g == f->generation)
            pthread_cond_wait(&f->moved, &f->lock);
    }
    ok = !f->aborted;
    pthread_mutex_unlock(&f->lock);
    return ok ? 0 : -1;
}

static void fabric_abort(void *user, ll_status status)
{
    fabric *f = ((rank_run *)user)->f;
    (void)status;
    pthread_mutex_lock(&f->lock);
    f->aborted = 1;
    pthread_cond_broadcast(&f->moved);
    pthread_mutex_unlock(&f->lock);
}

static ll_status fabric_alltoallv(void *user, const void *send, const size_t *send_bytes,
                                  void *recv, const size_t *recv_bytes)
{
    rank_run *r = user;
    fabric *f = r->f;
    size_t at = 0, off, d;
    int s, ok = 1;
    f->send[r->rank] = send;
    f->send_bytes[r->rank] = send_bytes;
    f->calls[r->rank]++;
    if (meet(f) != 0)
        return LL_ERROR_IO;
    for (s = 0; s < f->n; ++s) {
        for (off = 0, d = 0; d < (size_t)r->rank; ++d)
            off += f->send_bytes[s][d];
        /* What the library expects must be what was sent. */
        if (f->send_bytes[s][r->rank] != recv_bytes[s])
            ok = 0;
        else if (recv_bytes[s] > 0) /* (a rank with nothing to send may pass NULL) */
            memcpy((unsigned char *)recv + at, f->send[s] + off, recv_bytes[s]);
        at += recv_bytes[s];
    }
    if (meet(f) != 0)
        return LL_ERROR_IO;
    return ok ? LL_OK : LL_ERROR_FORMAT;
}

static void *run_rank(void *arg)
{
    rank_run *r = arg;
    ll_distribution d = LL_DISTRIBUTION_INIT;
    d.rank = r->rank;
    d.n_ranks = r->f->n;
    d.user = r;
    d.alltoallv = fabric_alltoallv;
    d.abort = fabric_abort;
    r->status = ll_material_build_distributed(r->material, &r->opts, r->monitor, &d,
                                              r->rank == 0 ? r->out : NULL);
    snprintf(r->message, sizeof r->message, "%s", ll_last_error_message());
    return NULL;
}

/* Run n ranks; opts[r] and monitors[r] (nullable) per rank. */
static void run_ranks_ex(int n, const ll_material *m, const ll_build_options *opts,
                         const ll_monitor *const *monitors, const char *out, rank_run *runs,
                         int *aborted)
{
    fabric f;
    pthread_t t[MAX_RANKS];
    int r;
    memset(&f, 0, sizeof f);
    f.n = n;
    assert_int_equal(pthread_mutex_init(&f.lock, NULL), 0);
    assert_int_equal(pthread_cond_init(&f.moved, NULL), 0);
    for (r = 0; r < n; ++r) {
        memset(&runs[r], 0, sizeof runs[r]);
        runs[r].f = &f;
        runs[r].rank = r;
        runs[r].material = m;
        runs[r].opts = opts[r];
        runs[r].monitor = monitors ? monitors[r] : NULL;
        runs[r].out = out;
        assert_int_equal(pthread_create(&t[r], NULL, run_rank, &runs[r]), 0);
    }
    for (r = 0; r < n; ++r)
        assert_int_equal(pthread_join(t[r], NULL), 0);
    /* Every rank made the same number of collective calls (unless one
     * could not take part). */
    for (r = 1; r < n && !f.aborted; ++r)
        assert_int_equal(f.calls[r], f.calls[0]);
    pthread_mutex_destroy(&f.lock);
    pthread_cond_destroy(&f.moved);
    *aborted = f.aborted;
}

static void run_ranks(int n, const ll_material *m, const ll_build_options *opts,
                      const ll_monitor *const *monitors, const char *out, rank_run *runs)
{
    int aborted;
    run_ranks_ex(n, m, opts, monitors, out, runs, &aborted);
    assert_false(aborted);
}

static ll_build_options small_options(size_t channels)
{
    ll_build_options o = LL_BUILD_OPTIONS_INIT;
    o.threads = 1;
    o.n_channels = channels;
    return o;
}

static void assert_same_file(const char *a, const char *b)
{
    size_t na, nb;
    unsigned char *x = ll_test_read_file(a, &na), *y = ll_test_read_file(b, &nb);
    assert_int_equal(na, nb);
    assert_memory_equal(x, y, na);
    free(x);
    free(y);
}

/* A glossy measured table (MERL layout, 90 x 90 x 180 is not needed: the
 * reader takes any dimensions). */
static void write_merl(const char *file)
{
    FILE *f = fopen(file, "wb");
    uint32_t dims[3] = { 12, 10, 20 };
    size_t i, count = 3 * 12 * 10 * 20;
    assert_non_null(f);
    assert_int_equal(fwrite(dims, 4, 3, f), 3);
    for (i = 0; i < count; ++i) {
        size_t ih = (i / 200) % 12;
        double v = 1500.0 * (double)(1 + i / 2400) * 2.0 / (1.0 + (double)(ih * ih));
        assert_int_equal(fwrite(&v, 8, 1, f), 1);
    }
    fclose(f);
}

static void check_identical(const char *text, size_t channels)
{
    char ref[600], out[600];
    ll_build_options opts[MAX_RANKS];
    rank_run runs[MAX_RANKS];
    ll_material *m = NULL;
    int n, r;
    assert_int_equal(ll_material_parse(text, "test.layers", &m), LL_OK);
    snprintf(ref, sizeof ref, "%s/ref.bsdf", ll_test_dir());
    snprintf(out, sizeof out, "%s/ranks.bsdf", ll_test_dir());
    opts[0] = small_options(channels);
    assert_int_equal(ll_material_build(m, &opts[0], NULL, ref), LL_OK);
    for (n = 1; n <= MAX_RANKS; ++n) {
        for (r = 0; r < n; ++r)
            opts[r] = small_options(channels);
        unlink(out);
        run_ranks(n, m, opts, NULL, out, runs);
        for (r = 0; r < n; ++r)
            assert_int_equal(runs[r].status, LL_OK);
        assert_same_file(ref, out);
    }
    ll_material_destroy(m);
}

static void medium_between_rough_interfaces(void **state)
{
    (void)state;
    check_identical("dielectric eta=1.5 alpha=0.2\n"
                    "medium albedo=0.8,0.5,0.9 g=0.6 tau=1.5\n"
                    "conductor eta=Au alpha=0.15\n"
                    "set nodes=30 orders=40\n",
                    3);
    check_identical("dielectric eta=1.5 alpha=0.3\n"
                    "medium albedo=0.95 phase=vmf kappa=3 tau=0.5\n"
                    "dielectric eta=0.8 alpha=0.1\n"
                    "set nodes=24 orders=30\n",
                    1);
    /* A clear layer (tau = 0) and a diffuse base: orders that are another
     * rank's identity or order 0. */
    check_identical("dielectric eta=1.5 alpha=0.2\n"
                    "medium albedo=0.5 tau=0\n"
                    "diffuse albedo=0.6\n"
                    "set nodes=20 orders=20\n",
                    1);
}

static void measured_brdf_under_a_coat(void **state)
{
    char merl[600], text[800];
    (void)state;
    snprintf(merl, sizeof merl, "%s/glossy.binary", ll_test_dir());
    write_merl(merl);
    snprintf(text, sizeof text,
             "dielectric eta=1.5 alpha=0.2\nmeasured file=%s\nset nodes=20 orders=24\n", merl);
    check_identical(text, 3);
}

/* Rank 1 alone is over its budget: every rank fails alike. */
static void one_rank_over_budget_fails_all(void **state)
{
    char out[600];
    ll_build_options opts[3];
    rank_run runs[3];
    ll_material *m = NULL;
    size_t entries = ll_test_count_entries(ll_test_dir());
    int r;
    (void)state;
    assert_int_equal(ll_material_parse("dielectric eta=1.5 alpha=0.2\nmedium albedo=0.9 "
                                       "tau=1 g=0.5\ndiffuse albedo=0.5\nset nodes=30 "
                                       "orders=30\n",
                                       "budget.layers", &m),
                     LL_OK);
    snprintf(out, sizeof out, "%s/budget.bsdf", ll_test_dir());
    for (r = 0; r < 3; ++r)
        opts[r] = small_options(1);
    opts[1].max_memory_bytes = 1000;
    run_ranks(3, m, opts, NULL, out, runs);
    for (r = 0; r < 3; ++r)
        assert_int_equal(runs[r].status, LL_ERROR_OUT_OF_MEMORY);
    assert_non_null(strstr(runs[0].message, "rank 1 of 3: "));
    assert_non_null(strstr(runs[0].message, "budget.layers"));
    assert_non_null(strstr(runs[0].message, "estimated peak of this rank"));
    assert_non_null(strstr(runs[2].message, "rank 1 of 3 failed"));
    /* No file, no temporary. */
    assert_int_equal(access(out, F_OK), -1);
    assert_int_equal(ll_test_count_entries(ll_test_dir()), entries);
    ll_material_destroy(m);
}

/* A monitor that stops the build at its third report. */
static int stop_soon(void *user, double fraction, const char *stage)
{
    int *calls = user;
    (void)fraction;
    (void)stage;
    return ++*calls >= 3;
}

static void one_rank_cancelled_stops_all(void **state)
{
    char out[600];
    ll_build_options opts[MAX_RANKS];
    rank_run runs[MAX_RANKS];
    ll_monitor stop = LL_MONITOR_INIT;
    const ll_monitor *monitors[MAX_RANKS] = { NULL, NULL, NULL, NULL };
    ll_material *m = NULL;
    size_t entries = ll_test_count_entries(ll_test_dir());
    int r, calls = 0, victim;
    (void)state;
    assert_int_equal(ll_material_parse("dielectric eta=1.5 alpha=0.2\nmedium albedo=0.9 "
                                       "tau=2 g=0.5\nconductor eta=Au alpha=0.2\nset nodes=30 "
                                       "orders=30\n",
                                       "cancel.layers", &m),
                     LL_OK);
    snprintf(out, sizeof out, "%s/cancel.bsdf", ll_test_dir());
    stop.progress = stop_soon;
    stop.user = &calls;
    /* Each rank in turn: the first, a middle one, the last. */
    for (victim = 0; victim < MAX_RANKS; victim += 3) {
        calls = 0;
        for (r = 0; r < MAX_RANKS; ++r) {
            opts[r] = small_options(0);
            monitors[r] = r == victim ? &stop : NULL;
        }
        run_ranks(MAX_RANKS, m, opts, monitors, out, runs);
        for (r = 0; r < MAX_RANKS; ++r)
            assert_int_equal(runs[r].status, LL_ERROR_CANCELLED);
        assert_int_equal(access(out, F_OK), -1);
        assert_int_equal(ll_test_count_entries(ll_test_dir()), entries);
    }
    ll_material_destroy(m);
}

/* The k-th allocation of the whole run fails, on whichever rank makes it:
 * every rank returns the same status (none waits for ever), nothing
 * leaks, and there is a file exactly when all succeeded (a failure the
 * build could do without). Every fourth k of the run, to stay quick. */
static void out_of_memory_anywhere_is_agreed(void **state)
{
    char out[600];
    ll_build_options opts[3];
    rank_run runs[3];
    ll_material *m = NULL;
    size_t entries, total, k;
    int r, failures = 0;
    (void)state;
    assert_int_equal(ll_material_parse("dielectric eta=1.5 alpha=0.3\nmedium albedo=0.9 "
                                       "tau=0.5 g=0.5\nconductor eta=2+3i alpha=0.3\n"
                                       "set nodes=10 orders=6\n",
                                       "oom.layers", &m),
                     LL_OK);
    snprintf(out, sizeof out, "%s/oom.bsdf", ll_test_dir());
    for (r = 0; r < 3; ++r)
        opts[r] = small_options(1);
    ll_alloc_fail_after(0);
    run_ranks(3, m, opts, NULL, out, runs);
    total = ll_alloc_count();
    ll_alloc_hook_off();
    assert_int_equal(runs[0].status, LL_OK);
    unlink(out);
    entries = ll_test_count_entries(ll_test_dir());
    for (k = 1; k <= total; k += 4) {
        int aborted;
        ll_alloc_fail_after(k);
        run_ranks_ex(3, m, opts, NULL, out, runs, &aborted);
        assert_int_equal(ll_alloc_live(), 0);
        ll_alloc_hook_off();
        if (aborted) {
            /* A rank could not even start agreeing: it ended the job. */
            for (r = 0; r < 3; ++r)
                assert_int_not_equal(runs[r].status, LL_OK);
            assert_int_equal(access(out, F_OK), -1);
            ++failures;
            continue;
        }
        for (r = 1; r < 3; ++r)
            assert_int_equal(runs[r].status, runs[0].status);
        if (runs[0].status == LL_OK) {
            assert_int_equal(access(out, F_OK), 0);
            unlink(out);
        } else {
            assert_int_equal(runs[0].status, LL_ERROR_OUT_OF_MEMORY);
            assert_non_null(strstr(runs[0].message, "rank "));
            assert_int_equal(access(out, F_OK), -1);
            ++failures;
        }
        assert_int_equal(ll_test_count_entries(ll_test_dir()), entries);
    }
    print_message("%zu allocations over 3 ranks; %d of the failures injected failed the "
                  "build\n", total, failures);
    assert_true(failures > 0);
    ll_material_destroy(m);
}

/* A packed layer unpacks to the same layer (the same .bsdf bytes); every
 * truncation and a damaged count are refused as LL_ERROR_FORMAT. */
static void packed_layers_round_trip(void **state)
{
    char a[600], b[600];
    ll_material *m = NULL;
    ll_layer *layers[3], *copy[3] = { NULL, NULL, NULL };
    size_t nch, c, size, cut;
    unsigned char *bytes;
    ll_build_options o = small_options(3);
    (void)state;
    assert_int_equal(ll_material_parse("dielectric eta=1.5 alpha=0.3\nmedium albedo=0.8 g=0.5 "
                                       "tau=1\nconductor eta=Au alpha=0.2\nset nodes=16 "
                                       "orders=12\n",
                                       "pack.layers", &m),
                     LL_OK);
    assert_int_equal(ll_material_build_layers(m, &o, NULL, layers, &nch, NULL), LL_OK);
    for (c = 0; c < nch; ++c) {
        size = ll_layer_pack_size(layers[c]);
        bytes = malloc(size);
        assert_non_null(bytes);
        assert_int_equal(ll_layer_pack(layers[c], bytes, size - 1), LL_ERROR_INVALID_ARGUMENT);
        assert_int_equal(ll_layer_pack(layers[c], bytes, size), LL_OK);
        assert_int_equal(ll_layer_unpack(bytes, size, &copy[c]), LL_OK);
        assert_int_equal(ll_layer_stored_count(copy[c]), ll_layer_stored_count(layers[c]));
        for (cut = 0; cut < size; cut += 1 + cut / 7) {
            ll_layer *bad = NULL;
            assert_int_equal(ll_layer_unpack(bytes, cut, &bad), LL_ERROR_FORMAT);
            assert_null(bad);
        }
        {
            ll_layer *bad = NULL;
            bytes[8] = 0xff; /* the node count: 255, odd */
            assert_int_equal(ll_layer_unpack(bytes, size, &bad), LL_ERROR_FORMAT);
            assert_null(bad);
        }
        free(bytes);
    }
    snprintf(a, sizeof a, "%s/pack.a.bsdf", ll_test_dir());
    snprintf(b, sizeof b, "%s/pack.b.bsdf", ll_test_dir());
    assert_int_equal(ll_material_write(m, NULL, layers, nch, a, NULL), LL_OK);
    assert_int_equal(ll_material_write(m, NULL, copy, nch, b, NULL), LL_OK);
    assert_same_file(a, b);
    unlink(a);
    unlink(b);
    for (c = 0; c < 3; ++c) {
        ll_layer_destroy(layers[c]);
        ll_layer_destroy(copy[c]);
    }
    assert_int_equal(ll_layer_pack_size(NULL), 0);
    ll_material_destroy(m);
}

static void bad_distributions_are_refused(void **state)
{
    ll_distribution d = LL_DISTRIBUTION_INIT;
    ll_material *m = NULL;
    ll_layer *layers[3];
    size_t nch;
    (void)state;
    assert_int_equal(ll_material_parse("diffuse albedo=0.5\n", "x.layers", &m), LL_OK);
    assert_int_equal(ll_material_build_distributed(m, NULL, NULL, NULL, "x.bsdf"),
                     LL_ERROR_INVALID_ARGUMENT);
    assert_int_equal(ll_material_build_distributed(m, NULL, NULL, &d, "x.bsdf"),
                     LL_ERROR_INVALID_ARGUMENT); /* no alltoallv */
    d.alltoallv = fabric_alltoallv;
    d.rank = 2;
    d.n_ranks = 2;
    assert_int_equal(ll_material_build_layers_distributed(m, NULL, NULL, &d, layers, &nch,
                                                          NULL),
                     LL_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(ll_last_error_message(), "rank 2 of 2"));
    assert_int_equal(access("x.bsdf", F_OK), -1);
    ll_material_destroy(m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(medium_between_rough_interfaces),
        cmocka_unit_test(measured_brdf_under_a_coat),
        cmocka_unit_test(one_rank_over_budget_fails_all),
        cmocka_unit_test(one_rank_cancelled_stops_all),
        cmocka_unit_test(out_of_memory_anywhere_is_agreed),
        cmocka_unit_test(packed_layers_round_trip),
        cmocka_unit_test(bad_distributions_are_refused),
    };
    return cmocka_run_group_tests(tests, ll_test_dir_setup, ll_test_dir_teardown);
}
