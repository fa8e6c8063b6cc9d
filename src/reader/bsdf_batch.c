/*
 * The batch calls of the renderer convention (ll_bsdf.h): one call
 * evaluates, or samples, a whole array of directions, as a wavefront
 * renderer (Mitsuba 3's LLVM variants) hands them over. Each element is
 * exactly the scalar _dir call on that element -- the batch calls call
 * them, or on a plain table file run their steps interleaved across
 * elements (tables_batch.c) -- so a batch result is bit-identical to the
 * scalar one and does not depend on how the array is split between
 * threads.
 *
 * Threads: POSIX threads of libc (the reader library links no OpenMP). The
 * array is cut into contiguous ranges of at least LL_BATCH_MIN_PER_THREAD
 * elements, one per thread, because starting a thread costs about as much
 * as a few hundred evaluations. The number of threads is the number of
 * online processors, or LAYERLAB_BATCH_THREADS (1 to LL_BATCH_MAX_THREADS)
 * from the environment; a thread that cannot be started leaves its range
 * to the calling thread, so the results stay the same.
 *
 * Errors: an invalid element gets what the scalar call gives it (zeros);
 * the batch finishes every other element and returns the status of the
 * invalid element with the lowest index, whose message is made again on the
 * calling thread (ll_last_error_message is per thread) by repeating that
 * one scalar call.
 */
#include "reader/bsdf_batch.h"

#include <pthread.h>
#include <stdlib.h>
#include <unistd.h>

#define LL_BATCH_MIN_PER_THREAD 1024
#define LL_BATCH_MAX_THREADS 64

/* One thread's range [begin, end) and the lowest index in it whose scalar
 * call failed (end if none). */
typedef struct batch_range {
    const ll_batch_job *job;
    size_t begin, end, first_failed;
    ll_status failed_status;
} batch_range;

ll_status ll_batch_element(const ll_batch_job *job, size_t k)
{
    const float *basis = ll_batch_basis(job, k);
    switch (job->kind) {
    case LL_BATCH_EVAL:
        return ll_bsdf_eval_dir(job->b, job->wo + 3 * k, job->wi + 3 * k, job->mode, basis,
                                job->rgb_out + 3 * k);
    case LL_BATCH_PDF:
        return ll_bsdf_pdf_dir(job->b, job->wo + 3 * k, job->wi + 3 * k, basis, job->pdf_out + k);
    default:
        return ll_bsdf_sample_dir(job->b, job->wo + 3 * k, job->u + 2 * k, job->mode, basis,
                                  job->wi_out + 3 * k, job->pdf_out + k, job->rgb_out + 3 * k);
    }
}

static void *run_range(void *arg)
{
    batch_range *r = arg;
    size_t k;
    r->first_failed = r->end;
    r->failed_status = LL_OK;
    if (ll_measured_batch_fits(r->job)) {
        r->first_failed = ll_measured_batch_range(r->job, r->begin, r->end, &r->failed_status);
        return NULL;
    }
    for (k = r->begin; k < r->end; ++k) {
        ll_status s = ll_batch_element(r->job, k);
        if (s != LL_OK && r->first_failed == r->end) {
            r->first_failed = k;
            r->failed_status = s;
        }
    }
    return NULL;
}

static size_t thread_limit(void)
{
    const char *env = getenv("LAYERLAB_BATCH_THREADS");
    long n;
    if (env && *env) {
        char *end;
        n = strtol(env, &end, 10);
        if (*end == '\0' && n >= 1)
            return n > LL_BATCH_MAX_THREADS ? LL_BATCH_MAX_THREADS : (size_t)n;
    }
    n = sysconf(_SC_NPROCESSORS_ONLN);
    if (n < 1)
        return 1;
    return n > LL_BATCH_MAX_THREADS ? LL_BATCH_MAX_THREADS : (size_t)n;
}

/* Run every element; returns the lowest failing element's status with its
 * message (made again here when the failure happened on a worker). */
static ll_status run_batch(const ll_batch_job *job, size_t count)
{
    batch_range ranges[LL_BATCH_MAX_THREADS];
    pthread_t threads[LL_BATCH_MAX_THREADS];
    int started[LL_BATCH_MAX_THREADS];
    size_t n_threads = thread_limit(), t, per, first = count;
    ll_status status = LL_OK;
    if (n_threads > count / LL_BATCH_MIN_PER_THREAD)
        n_threads = count / LL_BATCH_MIN_PER_THREAD;
    if (n_threads < 1)
        n_threads = 1;
    per = count / n_threads + (count % n_threads != 0);
    for (t = 0; t < n_threads; ++t) {
        ranges[t].job = job;
        ranges[t].begin = t * per < count ? t * per : count;
        ranges[t].end = ranges[t].begin + per < count ? ranges[t].begin + per : count;
        /* Range 0 runs on the calling thread, after the others started. */
        started[t] = t > 0 && pthread_create(&threads[t], NULL, run_range, &ranges[t]) == 0;
    }
    for (t = 0; t < n_threads; ++t)
        if (!started[t])
            run_range(&ranges[t]);
    for (t = 0; t < n_threads; ++t) {
        if (started[t])
            pthread_join(threads[t], NULL);
        if (ranges[t].first_failed < ranges[t].end && ranges[t].first_failed < first) {
            first = ranges[t].first_failed;
            status = ranges[t].failed_status;
        }
    }
    if (first < count)
        status = ll_batch_element(job, first); /* the message, on this thread */
    return status;
}

/* The checks of the batch itself, before any element: pointers, and the
 * sizes of the arrays (3 count doubles and count * coeff_stride floats
 * must be addressable). */
static ll_status check_batch(const ll_bsdf *b, size_t count, int arrays_present,
                             const float *basis_coeffs, size_t coeff_stride, const char *fn)
{
    size_t bytes;
    if (!b)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: the ll_bsdf is NULL", fn);
    if (count > 0 && !arrays_present)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: a direction or output array is NULL for %zu elements", fn, count);
    if (!ll_size_mul(count, 3 * sizeof(double), &bytes) ||
        (basis_coeffs && (!ll_size_mul(count, coeff_stride, &bytes) ||
                          !ll_size_mul(bytes, sizeof(float), &bytes))))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: %zu elements (coefficient stride %zu) overflow the address space",
                       fn, count, coeff_stride);
    return LL_OK;
}

/* The three entry points: their arguments checked, then run_batch. */
static ll_status start_batch(const ll_batch_job *job, size_t count, int arrays_present,
                             const char *fn)
{
    ll_status s = check_batch(job->b, count, arrays_present, job->basis_coeffs,
                              job->coeff_stride, fn);
    return s != LL_OK ? s : run_batch(job, count);
}

ll_status ll_bsdf_eval_dir_batch(const ll_bsdf *b, size_t count, const double *wo,
                                 const double *wi, ll_transport mode,
                                 const float *basis_coeffs, size_t coeff_stride,
                                 double *rgb_out)
{
    ll_batch_job job = { .kind = LL_BATCH_EVAL, .b = b, .wo = wo, .wi = wi, .mode = mode,
                      .basis_coeffs = basis_coeffs, .coeff_stride = coeff_stride,
                      .rgb_out = rgb_out };
    return start_batch(&job, count, wo && wi && rgb_out, "ll_bsdf_eval_dir_batch");
}

ll_status ll_bsdf_pdf_dir_batch(const ll_bsdf *b, size_t count, const double *wo,
                                const double *wi, const float *basis_coeffs,
                                size_t coeff_stride, double *pdf_out)
{
    ll_batch_job job = { .kind = LL_BATCH_PDF, .b = b, .wo = wo, .wi = wi,
                      .mode = LL_TRANSPORT_RADIANCE, .basis_coeffs = basis_coeffs,
                      .coeff_stride = coeff_stride, .pdf_out = pdf_out };
    return start_batch(&job, count, wo && wi && pdf_out, "ll_bsdf_pdf_dir_batch");
}

ll_status ll_bsdf_sample_dir_batch(const ll_bsdf *b, size_t count, const double *wo,
                                   const double *u, ll_transport mode,
                                   const float *basis_coeffs, size_t coeff_stride,
                                   double *wi_out, double *pdf_out, double *rgb_out)
{
    ll_batch_job job = { .kind = LL_BATCH_SAMPLE, .b = b, .wo = wo, .u = u, .mode = mode,
                      .basis_coeffs = basis_coeffs, .coeff_stride = coeff_stride,
                      .wi_out = wi_out, .pdf_out = pdf_out, .rgb_out = rgb_out };
    return start_batch(&job, count, wo && u && wi_out && pdf_out && rgb_out,
                       "ll_bsdf_sample_dir_batch");
}
