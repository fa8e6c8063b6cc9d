/*
 * One batch call of the renderer convention (bsdf_batch.c) as its workers
 * see it, shared with the pipelined path of a table file
 * (tables_batch.c).
 */
#ifndef LL_BSDF_BATCH_H
#define LL_BSDF_BATCH_H

#include "reader/bsdf_internal.h"

typedef enum { LL_BATCH_EVAL, LL_BATCH_PDF, LL_BATCH_SAMPLE } ll_batch_kind;

/* One batch call's arguments, shared read-only by the workers. */
typedef struct ll_batch_job {
    ll_batch_kind kind;
    const ll_bsdf *b;
    const double *wo, *wi, *u;
    ll_transport mode;
    const float *basis_coeffs;
    size_t coeff_stride;
    double *wi_out, *pdf_out, *rgb_out;
} ll_batch_job;

/* Element k's weights (NULL if the call gave none). */
static inline const float *ll_batch_basis(const ll_batch_job *job, size_t k)
{
    return job->basis_coeffs ? job->basis_coeffs + k * job->coeff_stride : NULL;
}

/* Element k by the scalar _dir call, its outputs written in place; its
 * status (bsdf_batch.c). */
LL_INTERNAL ll_status ll_batch_element(const ll_batch_job *job, size_t k);

/* The elements [begin, end) of a job on a plain table file, whose loads
 * from memory overlap across elements (tables_batch.c); each element's
 * outputs are those of its scalar call. Returns the lowest index in the
 * range whose scalar call fails (end if none) and its status in
 * *failed. ll_measured_batch_fits says whether the job can take it (a
 * plain, untextured table file; else each element takes its scalar
 * call). */
LL_INTERNAL int ll_measured_batch_fits(const ll_batch_job *job);
LL_INTERNAL size_t ll_measured_batch_range(const ll_batch_job *job, size_t begin, size_t end,
                                           ll_status *failed);

#endif /* LL_BSDF_BATCH_H */
