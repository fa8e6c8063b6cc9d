/*
 * The library's parallel loop (support/threads.c): every item runs once on
 * a slot below the thread count, the first failure by index is returned
 * with its own message, a loop inside an item runs on that item's thread,
 * callers on several threads each have their own workers, a thread that
 * used them exits cleanly, and idle workers sleep rather than spin.
 */
#include "test_util.h"

#include "support/support.h"
#include "support/watch.h"

#include <pthread.h>
#include <time.h>

enum { MAX_ITEMS = 64 };

typedef struct tally {
    int runs[MAX_ITEMS];  /* atomic: how often each item ran */
    size_t slot_max;      /* atomic max of ll_parallel_slot() */
    size_t threads;       /* the caller's thread count */
    int slot_in_range;    /* atomic: cleared by a slot out of range */
} tally;

static ll_status count_item(size_t i, void *ctx)
{
    tally *t = ctx;
    size_t slot = ll_parallel_slot();
    __atomic_add_fetch(&t->runs[i], 1, __ATOMIC_RELAXED);
    if (slot >= t->threads)
        __atomic_store_n(&t->slot_in_range, 0, __ATOMIC_RELAXED);
    return LL_OK;
}

static void every_item_runs_once_on_a_slot_below_the_count(void **state)
{
    size_t threads, count, i;
    (void)state;
    for (threads = 1; threads <= 5; ++threads)
        for (count = 0; count <= 40; count += (count < 8 ? 1 : 11)) {
            tally t;
            memset(&t, 0, sizeof t);
            t.threads = threads;
            t.slot_in_range = 1;
            assert_int_equal(ll_set_thread_count(threads), LL_OK);
            assert_int_equal(ll_parallel_for(count, count_item, &t), LL_OK);
            for (i = 0; i < count; ++i)
                assert_int_equal(t.runs[i], 1);
            assert_true(t.slot_in_range);
            assert_int_equal(ll_parallel_slot(), 0);
        }
    assert_int_equal(ll_set_thread_count(0), LL_OK);
}

/* Items 3 and 7 (and every item from 20) fail, each with its own message. */
static ll_status failing_item(size_t i, void *ctx)
{
    (void)ctx;
    if (i == 3 || i == 7 || i >= 20)
        return ll_fail(i == 3 ? LL_ERROR_CANCELLED : LL_ERROR_INVALID_ARGUMENT, "item %zu failed",
                       i);
    return LL_OK;
}

static void the_first_failure_by_index_is_returned(void **state)
{
    size_t threads;
    (void)state;
    for (threads = 1; threads <= 4; ++threads) {
        assert_int_equal(ll_set_thread_count(threads), LL_OK);
        assert_int_equal(ll_parallel_for(32, failing_item, NULL), LL_ERROR_CANCELLED);
        assert_string_equal(ll_last_error_message(), "item 3 failed");
    }
    assert_int_equal(ll_set_thread_count(0), LL_OK);
}

/* An item that runs a loop of its own: it runs on this item's thread, with
 * slots below the thread count its own thread reports. */
typedef struct nested {
    tally inner[8];
} nested;

static ll_status outer_item(size_t i, void *ctx)
{
    nested *n = ctx;
    tally *t = &n->inner[i];
    t->threads = ll_get_thread_count();
    t->slot_in_range = 1;
    return ll_parallel_for(16, count_item, t);
}

static void a_loop_inside_an_item_runs_on_its_thread(void **state)
{
    nested n;
    size_t i, k;
    (void)state;
    memset(&n, 0, sizeof n);
    assert_int_equal(ll_set_thread_count(3), LL_OK);
    assert_int_equal(ll_parallel_for(8, outer_item, &n), LL_OK);
    for (i = 0; i < 8; ++i) {
        assert_true(n.inner[i].slot_in_range);
        for (k = 0; k < 16; ++k)
            assert_int_equal(n.inner[i].runs[k], 1);
    }
    assert_int_equal(ll_set_thread_count(0), LL_OK);
}

/* A sum whose terms are computed in parallel and added in index order:
 * the same bits whatever the thread count. */
static ll_status square_root_item(size_t i, void *ctx)
{
    double *out = ctx;
    size_t k;
    double s = 0.0;
    for (k = 1; k <= 2000; ++k)
        s += sqrt((double)(i * 2000 + k)) / (double)k;
    out[i] = s;
    return LL_OK;
}

static double ordered_sum(size_t threads)
{
    double out[MAX_ITEMS], sum = 0.0;
    size_t i;
    assert_int_equal(ll_set_thread_count(threads), LL_OK);
    assert_int_equal(ll_parallel_for(MAX_ITEMS, square_root_item, out), LL_OK);
    for (i = 0; i < MAX_ITEMS; ++i)
        sum += out[i];
    return sum;
}

typedef struct caller {
    size_t threads;
    double sum;
    int loops_ok;
} caller;

/* A caller thread: loops on its own workers, then exits (ending them). */
static void *caller_main(void *arg)
{
    caller *c = arg;
    int k;
    c->loops_ok = 1;
    for (k = 0; k < 20; ++k) {
        tally t;
        size_t i;
        memset(&t, 0, sizeof t);
        t.threads = c->threads;
        t.slot_in_range = 1;
        if (ll_set_thread_count(c->threads) != LL_OK ||
            ll_parallel_for(MAX_ITEMS, count_item, &t) != LL_OK || !t.slot_in_range)
            c->loops_ok = 0;
        for (i = 0; i < MAX_ITEMS; ++i)
            if (t.runs[i] != 1)
                c->loops_ok = 0;
    }
    c->sum = ordered_sum(c->threads);
    return NULL;
}

static void callers_on_several_threads_get_the_same_bits(void **state)
{
    pthread_t t[4];
    caller c[4];
    double one = ordered_sum(1);
    size_t k;
    (void)state;
    for (k = 0; k < 4; ++k) {
        c[k].threads = k + 1;
        assert_int_equal(pthread_create(&t[k], NULL, caller_main, &c[k]), 0);
    }
    for (k = 0; k < 4; ++k) {
        assert_int_equal(pthread_join(t[k], NULL), 0);
        assert_true(c[k].loops_ok);
        assert_memory_equal(&c[k].sum, &one, sizeof one);
    }
    assert_int_equal(ll_set_thread_count(0), LL_OK);
}

static double cpu_seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static ll_status short_item(size_t i, void *ctx)
{
    double *out = ctx;
    out[i] = sqrt((double)i);
    return LL_OK;
}

/* Between loops the workers wait on a condition, not in a spin: 40 gaps of
 * 10 ms after short loops cost next to no CPU (1.4 ms measured; an OpenMP
 * team with libgomp's default wait policy took 80 ms). */
static void idle_workers_sleep(void **state)
{
    struct timespec gap = { 0, 10000000L };
    double out[MAX_ITEMS], idle = 0.0;
    int k;
    (void)state;
    assert_int_equal(ll_set_thread_count(2), LL_OK);
    for (k = 0; k < 40; ++k) {
        double start;
        assert_int_equal(ll_parallel_for(MAX_ITEMS, short_item, out), LL_OK);
        start = cpu_seconds();
        nanosleep(&gap, NULL);
        idle += cpu_seconds() - start;
    }
    assert_true(idle < 0.02);
    assert_int_equal(ll_set_thread_count(0), LL_OK);
}

/* The watched loop with a callback: the owner keeps polling while a
 * worker's item is still running, and the callback runs on the owner only. */
typedef struct owner_check {
    pthread_t owner;
    int calls, foreign;
} owner_check;

static int on_progress(void *user, double fraction, const char *stage)
{
    owner_check *o = user;
    (void)fraction;
    (void)stage;
    ++o->calls;
    if (!pthread_equal(pthread_self(), o->owner))
        o->foreign = 1;
    return 0;
}

static ll_status slow_item(size_t i, void *ctx)
{
    ll_watch *w = ctx;
    struct timespec pause = { 0, 5000000L };
    (void)i;
    nanosleep(&pause, NULL);
    ll_watch_advance(w, 1);
    ll_watch_poll(w);
    return LL_OK;
}

static void watched_loop_reports_on_its_owner(void **state)
{
    ll_watch w;
    owner_check o;
    (void)state;
    o.owner = pthread_self();
    o.calls = 0;
    o.foreign = 0;
    ll_watch_begin_raw(&w, on_progress, &o, NULL);
    ll_watch_stage(&w, "items", 0.0, 1.0, 12);
    assert_int_equal(ll_set_thread_count(3), LL_OK);
    assert_int_equal(ll_parallel_for_watched(12, slow_item, &w, &w), LL_OK);
    assert_true(o.calls > 0);
    assert_false(o.foreign);
    assert_int_equal(ll_set_thread_count(0), LL_OK);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(every_item_runs_once_on_a_slot_below_the_count),
        cmocka_unit_test(the_first_failure_by_index_is_returned),
        cmocka_unit_test(a_loop_inside_an_item_runs_on_its_thread),
        cmocka_unit_test(callers_on_several_threads_get_the_same_bits),
        cmocka_unit_test(idle_workers_sleep),
        cmocka_unit_test(watched_loop_reports_on_its_owner),
    };
    return cmocka_run_group_tests_name("parallel loop", tests, NULL, NULL);
}
