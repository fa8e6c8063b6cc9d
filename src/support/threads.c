/*
 * The parallel loop over independent items (Fourier orders, columns) and
 * the worker-thread count of the calling thread. This is the only part of
 * support/ that starts threads; the reader library does without it.
 *
 * The loop runs on a pool of worker threads that each calling thread keeps
 * (started when a loop first needs them, ended when that thread exits) and
 * that sleep on a condition variable between loops. An OpenMP team did the
 * same job, but libgomp's idle workers spin for about 11 ms after every
 * region by default (GOMP_SPINCOUNT), and the resolution search runs
 * hundreds of short loops with serial work between them: with two threads
 * its CPU time was 40-60% above one thread's. OMP_WAIT_POLICY=passive
 * stops the spinning, but libgomp reads it when it is loaded, and a
 * library does not set its host process's environment.
 */
#include "support/support.h"
#include "support/watch.h"
#include "layerlab/ll_layer.h" /* ll_set_thread_count, ll_get_thread_count */

#include <pthread.h>
#include <stdint.h>
#include <string.h>
#include <time.h>

#ifdef _OPENMP
#include <omp.h>
#endif
#if defined(__SSE__)
#include <xmmintrin.h>
#endif

static __thread size_t tls_thread_count; /* 0 = all processors */
static __thread size_t tls_slot;         /* ll_parallel_slot() */
static __thread int tls_in_loop;         /* inside an item: loops run serially */

static size_t processor_count(void)
{
#ifdef _OPENMP
    int n = omp_get_num_procs();
    return n > 0 ? (size_t)n : 1;
#else
    return 1;
#endif
}

ll_status ll_set_thread_count(size_t n_threads)
{
    if (n_threads > 4096)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_set_thread_count: %zu threads is more than the 4096 supported",
                       n_threads);
    tls_thread_count = n_threads;
    return LL_OK;
}

size_t ll_get_thread_count(void)
{
    return tls_thread_count ? tls_thread_count : processor_count();
}

/* Subnormal numbers (below 2.2e-308) carry no physics here, but the decaying
 * high Fourier orders produce them and they slow BLAS kernels down several
 * times. Worker threads flush them to zero (FTZ/DAZ) and restore the
 * caller's floating-point mode afterwards. */
static unsigned flush_subnormals(void)
{
#if defined(__SSE__)
    unsigned saved = _mm_getcsr();
    _mm_setcsr(saved | 0x8040u);
    return saved;
#else
    return 0;
#endif
}

static void restore_float_mode(unsigned saved)
{
#if defined(__SSE__)
    _mm_setcsr(saved);
#else
    (void)saved;
#endif
}

/* One loop: its items are taken in order, one at a time, by whichever
 * thread is free (the dynamic schedule); it lives on the caller's stack
 * until every worker that joined it has left it. */
typedef struct loop {
    size_t count;
    ll_parallel_body body;
    void *ctx;
    size_t next;     /* atomic: the next item to take */
    size_t finished; /* atomic: items done */
    ll_status first_status;
    size_t first_index;
    char first_message[LL_MESSAGE_CAPACITY];
} loop;

/* A calling thread's workers. It sits in that thread's own storage, not
 * on the heap: it outlives the calls that use it, and every heap block of
 * the library is a call's (tests/test_alloc_failure.c counts them). */
typedef struct pool {
    int ready;                 /* the mutex and conditions are made       */
    pthread_mutex_t lock;
    pthread_cond_t wake;       /* workers: a new loop, or the end         */
    pthread_cond_t idle;       /* the caller: the workers left the loop   */
    size_t created;            /* workers started and not yet ended       */
    size_t slots;              /* slots handed out (1, 2, ...)            */
    unsigned long generation;  /* loops begun (the first is 1)            */
    size_t wanted;             /* the current loop's workers: slots <= it */
    size_t busy;               /* of those, still inside it               */
    loop *current;
    int shutdown;
} pool;

static __thread pool tls_pool;
static pthread_key_t pool_key;
static pthread_once_t pool_once = PTHREAD_ONCE_INIT;
static int pool_key_made;

/* Items of lp until none are left to take. The first failure by index is
 * recorded (under the pool's lock, rarely taken) before its item counts
 * as finished, so the caller sees it once every item is. */
static void run_items(loop *lp, pthread_mutex_t *lock)
{
    size_t i;
    while ((i = __atomic_fetch_add(&lp->next, 1, __ATOMIC_RELAXED)) < lp->count) {
        ll_status s = lp->body(i, lp->ctx);
        if (s != LL_OK) {
            pthread_mutex_lock(lock);
            if (i < lp->first_index) {
                lp->first_index = i;
                lp->first_status = s;
                ll_message_copy(lp->first_message, sizeof lp->first_message);
            }
            pthread_mutex_unlock(lock);
        }
        __atomic_add_fetch(&lp->finished, 1, __ATOMIC_RELEASE);
    }
}

static void *worker_main(void *arg)
{
    pool *p = arg;
    unsigned long seen = 0; /* a new worker joins the loop it was made for */
    size_t slot;
    (void)flush_subnormals(); /* for the thread's whole life: it runs only items */
#ifdef _OPENMP
    /* OpenBLAS (OpenMP build) runs single-threaded where the calling
     * thread's OpenMP default is one thread: every item is computed by the
     * same operations whatever the thread count. */
    omp_set_num_threads(1);
#endif
    tls_in_loop = 1;
    pthread_mutex_lock(&p->lock);
    slot = ++p->slots;
    for (;;) {
        loop *lp;
        while (!p->shutdown && p->generation == seen)
            pthread_cond_wait(&p->wake, &p->lock);
        if (p->shutdown)
            break;
        seen = p->generation;
        if (slot > p->wanted)
            continue;
        lp = p->current;
        pthread_mutex_unlock(&p->lock);
        tls_slot = slot;
        run_items(lp, &p->lock);
        pthread_mutex_lock(&p->lock);
        if (--p->busy == 0)
            pthread_cond_signal(&p->idle);
    }
    if (--p->created == 0)
        pthread_cond_broadcast(&p->idle);
    pthread_mutex_unlock(&p->lock);
    return NULL;
}

/* End a thread's workers when it exits (the pthread key's destructor). */
static void pool_end(void *arg)
{
    pool *p = arg;
    if (!p->ready)
        return; /* (forgotten in a forked child) */
    pthread_mutex_lock(&p->lock);
    p->shutdown = 1;
    pthread_cond_broadcast(&p->wake);
    while (p->created > 0)
        pthread_cond_wait(&p->idle, &p->lock);
    pthread_mutex_unlock(&p->lock);
    pthread_cond_destroy(&p->wake);
    pthread_cond_destroy(&p->idle);
    pthread_mutex_destroy(&p->lock);
    p->ready = 0;
}

/* A forked child has only the thread that forked: its pool's workers are
 * gone, so it starts a new one (the old mutex may be held by a worker). */
static void pool_forget(void)
{
    memset(&tls_pool, 0, sizeof tls_pool);
}

static void pool_key_make(void)
{
    pool_key_made = pthread_key_create(&pool_key, pool_end) == 0 &&
                    pthread_atfork(NULL, NULL, pool_forget) == 0;
}

/* The calling thread's pool, made ready; NULL when it cannot be (then
 * the loop runs on the caller alone, with the same results). */
static pool *pool_get(void)
{
    pool *p = &tls_pool;
    if (p->ready)
        return p;
    pthread_once(&pool_once, pool_key_make);
    if (!pool_key_made)
        return NULL;
    memset(p, 0, sizeof *p);
    if (pthread_mutex_init(&p->lock, NULL) != 0)
        return NULL;
    if (pthread_cond_init(&p->wake, NULL) != 0) {
        pthread_mutex_destroy(&p->lock);
        return NULL;
    }
    if (pthread_cond_init(&p->idle, NULL) != 0) {
        pthread_cond_destroy(&p->wake);
        pthread_mutex_destroy(&p->lock);
        return NULL;
    }
    if (pthread_setspecific(pool_key, p) != 0) {
        pthread_cond_destroy(&p->idle);
        pthread_cond_destroy(&p->wake);
        pthread_mutex_destroy(&p->lock);
        return NULL;
    }
    p->ready = 1;
    return p;
}

/* Start workers up to `wanted` (lock held); how many there are. Workers
 * are detached: the pool counts them, and its end waits for that count. */
static size_t pool_grow(pool *p, size_t wanted)
{
    pthread_attr_t attr;
    if (p->created >= wanted)
        return wanted;
    if (pthread_attr_init(&attr) != 0)
        return p->created;
    pthread_attr_setdetachstate(&attr, PTHREAD_CREATE_DETACHED);
    while (p->created < wanted) {
        pthread_t t;
        if (pthread_create(&t, &attr, worker_main, p) != 0)
            break;
        ++p->created;
    }
    pthread_attr_destroy(&attr);
    return p->created;
}

/* The owner's wait for the other threads' items: poll, then sleep 1 ms
 * (so a loop ends at most 1 ms later than without a callback). */
static void wait_polling(ll_watch *w, const size_t *finished, size_t count)
{
    struct timespec pause = { 0, 1000000L };
    while (__atomic_load_n(finished, __ATOMIC_ACQUIRE) < count) {
        ll_watch_poll(w);
        nanosleep(&pause, NULL);
    }
}

size_t ll_parallel_slot(void)
{
    return tls_slot;
}

ll_status ll_parallel_for(size_t count, ll_parallel_body body, void *ctx)
{
    return ll_parallel_for_watched(count, body, ctx, NULL);
}

ll_status ll_parallel_for_watched(size_t count, ll_parallel_body body, void *ctx, ll_watch *w)
{
    static pthread_mutex_t serial_lock = PTHREAD_MUTEX_INITIALIZER;
    loop lp;
    pool *p = NULL;
    pthread_mutex_t *lock = &serial_lock;
    size_t workers = 0, threads = ll_get_thread_count(), saved_slot = tls_slot;
    int saved_in_loop = tls_in_loop;
    unsigned saved_mode;
#ifdef _OPENMP
    int saved_omp = omp_get_max_threads();
#endif

    if (count == 0)
        return LL_OK;
    if (threads > count)
        threads = count;
    lp.count = count;
    lp.body = body;
    lp.ctx = ctx;
    lp.next = 0;
    lp.finished = 0;
    lp.first_status = LL_OK;
    lp.first_index = SIZE_MAX;
    lp.first_message[0] = '\0';

    /* A loop inside an item runs on that item's thread, as a nested
     * OpenMP region did. */
    if (threads > 1 && !tls_in_loop)
        p = pool_get();
    if (p) {
        pthread_mutex_lock(&p->lock);
        workers = pool_grow(p, threads - 1);
        if (workers > 0) {
            p->current = &lp;
            p->wanted = workers;
            p->busy = workers;
            ++p->generation;
            pthread_cond_broadcast(&p->wake);
            lock = &p->lock;
        }
        pthread_mutex_unlock(&p->lock);
    }

    saved_mode = flush_subnormals();
#ifdef _OPENMP
    omp_set_num_threads(1); /* (single-threaded BLAS inside the items) */
#endif
    tls_in_loop = 1;
    tls_slot = 0;
    run_items(&lp, lock);
    tls_slot = saved_slot;
    tls_in_loop = saved_in_loop;
#ifdef _OPENMP
    omp_set_num_threads(saved_omp);
#endif
    restore_float_mode(saved_mode);

    if (workers > 0) {
        /* Only a callback needs the owner; a flag is read by every thread. */
        if (w && w->progress)
            wait_polling(w, &lp.finished, count);
        pthread_mutex_lock(&p->lock);
        while (p->busy > 0)
            pthread_cond_wait(&p->idle, &p->lock);
        p->current = NULL;
        pthread_mutex_unlock(&p->lock);
    }
    if (lp.first_status != LL_OK)
        ll_fail(lp.first_status, "%s", lp.first_message);
    return lp.first_status;
}
