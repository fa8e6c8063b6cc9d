/*
 * The parallel loop over independent items (Fourier orders, columns) and
 * the worker-thread count of the calling thread. This is the only part of
 * support/ that needs OpenMP; the reader library does without it.
 */
#include "support/support.h"
#include "support/watch.h"
#include "layerlab/ll_layer.h" /* ll_set_thread_count, ll_get_thread_count */

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

/* The owner's wait for the other threads' items: poll, then sleep 1 ms
 * (so a loop ends at most 1 ms later than at the barrier). */
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
#ifdef _OPENMP
    return (size_t)omp_get_thread_num();
#else
    return 0;
#endif
}

ll_status ll_parallel_for(size_t count, ll_parallel_body body, void *ctx)
{
    return ll_parallel_for_watched(count, body, ctx, NULL);
}

ll_status ll_parallel_for_watched(size_t count, ll_parallel_body body, void *ctx, ll_watch *w)
{
    size_t finished = 0;
    ll_status first_status = LL_OK;
    size_t first_index = SIZE_MAX;
    char first_message[LL_MESSAGE_CAPACITY];
    size_t threads = ll_get_thread_count();
    long long i, n = (long long)count;

    first_message[0] = '\0';
    if (count == 0)
        return LL_OK;
    if (threads > count)
        threads = count;

#ifdef _OPENMP
    /* One item is always computed by one thread with single-threaded BLAS:
     * omp_set_num_threads(1) inside the region sets the nested default of
     * this implicit task only, and OpenBLAS (OpenMP build) follows it. */
#pragma omp parallel num_threads((int)threads)
    {
        unsigned saved_mode = flush_subnormals();
        omp_set_num_threads(1);
#pragma omp for schedule(dynamic, 1) nowait
        for (i = 0; i < n; ++i) {
            ll_status s = body((size_t)i, ctx);
            __atomic_add_fetch(&finished, 1, __ATOMIC_RELEASE);
            if (s != LL_OK) {
#pragma omp critical(ll_parallel_error)
                {
                    if ((size_t)i < first_index) {
                        first_index = (size_t)i;
                        first_status = s;
                        ll_message_copy(first_message, sizeof first_message);
                    }
                }
            }
        }
        /* Only a callback needs the owner; a flag is read by every thread. */
        if (w && w->progress && omp_get_thread_num() == 0)
            wait_polling(w, &finished, count);
        restore_float_mode(saved_mode);
    }
#else
    unsigned saved_mode = flush_subnormals();
    (void)threads;
    (void)finished;
    (void)wait_polling;
    (void)w;
    for (i = 0; i < n; ++i) {
        ll_status s = body((size_t)i, ctx);
        if (s != LL_OK) {
            first_status = s;
            ll_message_copy(first_message, sizeof first_message);
            break;
        }
    }
    restore_float_mode(saved_mode);
#endif
    if (first_status != LL_OK)
        ll_fail(first_status, "%s", first_message);
    return first_status;
}
