/*
 * Error messages (thread-local), checked allocation and the parallel loop.
 *
 * The only mutable state in the library is per thread: the last error
 * message and the worker-thread count requested by the calling thread.
 */
#include "support/support.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef _OPENMP
#include <omp.h>
#endif
#if defined(__SSE__)
#include <xmmintrin.h>
#endif

#define LL_MESSAGE_CAPACITY 1024

static __thread char tls_message[LL_MESSAGE_CAPACITY];
static __thread size_t tls_thread_count; /* 0 = all processors */

int ll_version_number(void) { return LL_VERSION_NUMBER; }

const char *ll_version_string(void) { return LL_VERSION_STRING; }

const char *ll_status_string(ll_status status)
{
    switch (status) {
    case LL_OK: return "success";
    case LL_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case LL_ERROR_OUT_OF_MEMORY: return "out of memory";
    case LL_ERROR_IO: return "input/output error";
    case LL_ERROR_FORMAT: return "malformed file";
    case LL_ERROR_NUMERICAL: return "numerical failure";
    case LL_ERROR_UNSUPPORTED: return "unsupported";
    case LL_ERROR_PARSE: return "parse error";
    case LL_ERROR_CANCELLED: return "cancelled";
    default: return "unknown status";
    }
}

const char *ll_last_error_message(void) { return tls_message; }

ll_status ll_fail(ll_status status, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(tls_message, sizeof tls_message, fmt, ap);
    va_end(ap);
    return status;
}

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

int ll_size_mul(size_t a, size_t b, size_t *out)
{
    if (a != 0 && b > SIZE_MAX / a)
        return 0;
    *out = a * b;
    return 1;
}

int ll_size_add(size_t a, size_t b, size_t *out)
{
    if (b > SIZE_MAX - a)
        return 0;
    *out = a + b;
    return 1;
}

void *ll_alloc_array(size_t count, size_t size)
{
    size_t bytes;
    if (!ll_size_mul(count, size, &bytes))
        return NULL;
    return malloc(bytes ? bytes : 1);
}

void *ll_calloc_array(size_t count, size_t size)
{
    size_t bytes;
    if (!ll_size_mul(count, size, &bytes))
        return NULL;
    return calloc(bytes ? count : 1, bytes ? size : 1);
}

int ll_is_finite(double x) { return isfinite(x) != 0; }

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

ll_status ll_parallel_for(size_t count, ll_parallel_body body, void *ctx)
{
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
#pragma omp for schedule(dynamic, 1)
        for (i = 0; i < n; ++i) {
            ll_status s = body((size_t)i, ctx);
            if (s != LL_OK) {
#pragma omp critical(ll_parallel_error)
                {
                    if ((size_t)i < first_index) {
                        first_index = (size_t)i;
                        first_status = s;
                        memcpy(first_message, tls_message, sizeof first_message);
                    }
                }
            }
        }
        restore_float_mode(saved_mode);
    }
#else
    unsigned saved_mode = flush_subnormals();
    (void)threads;
    for (i = 0; i < n; ++i) {
        ll_status s = body((size_t)i, ctx);
        if (s != LL_OK) {
            first_status = s;
            memcpy(first_message, tls_message, sizeof first_message);
            break;
        }
    }
    restore_float_mode(saved_mode);
#endif
    if (first_status != LL_OK)
        memcpy(tls_message, first_message, sizeof tls_message);
    return first_status;
}
