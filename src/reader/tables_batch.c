/*
 * The batch calls on a plain table file (bsdf_batch.h): a software
 * pipeline over the elements, so that the loads from memory of different
 * elements overlap (memory-level parallelism) where the scalar calls wait
 * for each in turn. A cold look-up reads two levels of tables of
 * megabytes one after the other, each a miss to DRAM (docs/benchmarks.md,
 * "Table files"): eval the vndf warp's nodes at the half vector, then the
 * values at the point its inversion gives; pdf the same with the
 * luminance; sample the stretch of the luminance warp's rows that its
 * column search reads, then the vndf warp's and the values. Each element
 * runs the steps of tables_internal.h's split look-ups: while element k
 * finishes, element k + d / 2 does its
 * first level's work (its nodes asked for d / 2 elements ago) and asks
 * for its second level, and element k + d starts and asks for its first
 * level. The elements in flight keep their state in a ring of fixed size
 * on the stack, so nothing is done twice and nothing is allocated.
 *
 * Every element gets the bits of its scalar _dir call: the steps are the
 * ones the scalar calls run in a row, and the public layer's mapping
 * (unit directions, the weight, the cosine and the transport scale) is
 * the one of bsdf_dir.c's table branch, step for step (test_bsdf_batch
 * compares the bits). An element that this path does not take (an
 * invalid direction, u or weight) gets its scalar call when its turn to
 * finish comes, which also gives its status.
 */
#include "reader/bsdf_batch.h"
#include "reader/bsdf_dir.h"
#include "reader/tables_internal.h"

#include <math.h>

/* Elements between an element's start and its finish (even: the middle
 * step comes half way). Each level of an element has the work of half
 * that many elements to arrive in: in cache an eval's work takes about
 * one DRAM latency, a sample's about three (docs/benchmarks.md, "Table
 * files"). Chosen by measurement on that bench: distances 4, 6 and 8 gave
 * evals the same time (8 kept: a loaded machine's latencies are longer),
 * while samples got slower from 8 on (their stretches of rows in flight
 * crowd the first-level cache). */
#define LL_PIPE_EVAL 8
#define LL_PIPE_SAMPLE 4
/* The ring: a slot per element in flight. Step i finishes element i - d
 * before it starts element i, so d slots hold them (a power of two, at
 * least the larger distance). */
#define LL_PIPE_RING 8

typedef enum { SLOT_SCALAR, SLOT_ZERO, SLOT_LIVE } slot_state;

typedef struct pipe_slot {
    ll_measured_look lk;
    double v[3];              /* the viewer, unit (the format's wi)     */
    double light_z;           /* eval: the light's unit z               */
    double weight;            /* the element's (untextured) weight      */
    slot_state state;
} pipe_slot;

int ll_measured_batch_fits(const ll_batch_job *job)
{
    const ll_bsdf *b = job->b;
    if (!b->measured || b->measured_bases || b->n_bases != 1 || b->measured->extended)
        return 0;
    /* An invalid mode fails every element: their scalar calls say so. */
    return job->kind == LL_BATCH_PDF || job->mode == LL_TRANSPORT_RADIANCE ||
           job->mode == LL_TRANSPORT_IMPORTANCE;
}

static const char *kind_name(ll_batch_kind kind)
{
    return kind == LL_BATCH_EVAL ? "ll_bsdf_eval_dir"
                                 : kind == LL_BATCH_PDF ? "ll_bsdf_pdf_dir" : "ll_bsdf_sample_dir";
}

/* Element k's first step: its checks, then the look-up's start, which
 * asks for the first level's nodes. */
static void start(const ll_batch_job *job, size_t k, pipe_slot *p)
{
    const ll_bsdf *b = job->b;
    const ll_measured *t = b->measured;
    const float *basis;
    int c;
    p->state = SLOT_SCALAR;
    if (ll_bsdf_check_basis(b, ll_batch_basis(job, k), kind_name(job->kind), &basis) != LL_OK)
        return;
    p->weight = (double)basis[0];
    if (job->kind == LL_BATCH_SAMPLE) {
        const double *wo = job->wo + 3 * k, *u = job->u + 2 * k;
        double lo = ll_bsdf_dir_length(wo);
        if (!(lo > 0.0) || !(u[0] >= 0.0 && u[0] <= 1.0) || !(u[1] >= 0.0 && u[1] <= 1.0))
            return;
        for (c = 0; c < 3; ++c)
            p->v[c] = wo[c] / lo;
        /* ll_measured_draw_begin asks for the luminance warp's rows. */
        p->state = ll_measured_draw_begin(t, p->v, u, &p->lk) ? SLOT_LIVE : SLOT_ZERO;
    } else {
        double l[3];
        if (!ll_bsdf_unit_pair(job->wo + 3 * k, job->wi + 3 * k, p->v, l))
            return;
        p->light_z = l[2];
        /* An eval of weight 0 is 0 without a look-up (the blend skips
         * it); a pdf does not depend on the weight. */
        if ((job->kind == LL_BATCH_EVAL && p->weight == 0.0) ||
            !ll_measured_look_begin(t, p->v, l, &p->lk)) {
            p->state = SLOT_ZERO;
            return;
        }
        p->state = SLOT_LIVE;
        ll_measured_look_prefetch_vndf(t, &p->lk);
    }
}

/* The first level's work (its nodes now in cache, or on their way), which
 * asks for the second level's. */
static void middle(const ll_batch_job *job, pipe_slot *p)
{
    const ll_measured *t = job->b->measured;
    if (p->state != SLOT_LIVE)
        return;
    if (job->kind == LL_BATCH_SAMPLE) {
        ll_measured_draw_middle(t, &p->lk);
        return;
    }
    ll_measured_look_invert(t, &p->lk);
    ll_measured_look_prefetch_values(t, &p->lk, job->kind == LL_BATCH_PDF);
}

/* The last level and the outputs; the scalar call for an element this
 * path did not take. Returns the element's status. */
static ll_status finish(const ll_batch_job *job, size_t k, pipe_slot *p)
{
    const ll_bsdf *b = job->b;
    const ll_measured *t = b->measured;
    double value[3];
    int c;
    if (p->state == SLOT_SCALAR)
        return ll_batch_element(job, k);
    if (job->kind == LL_BATCH_PDF) {
        job->pdf_out[k] = p->state == SLOT_LIVE ? ll_measured_look_pdf(t, &p->lk) : 0.0;
    } else if (job->kind == LL_BATCH_EVAL) {
        double *rgb = job->rgb_out + 3 * k;
        rgb[0] = rgb[1] = rgb[2] = 0.0;
        if (p->state != SLOT_LIVE)
            return LL_OK;
        /* ll_measured_blend_eval's sum of one basis. */
        ll_measured_look_value(t, &p->lk, value);
        for (c = 0; c < 3; ++c)
            value[c] = 0.0 + p->weight * value[c];
        ll_bsdf_measured_rgb(value, p->light_z,
                             ll_bsdf_transport_scale(b, p->v[2], -p->light_z, job->mode), rgb);
    } else {
        double *wi = job->wi_out + 3 * k, *pdf = job->pdf_out + k, *rgb = job->rgb_out + 3 * k;
        rgb[0] = rgb[1] = rgb[2] = 0.0;
        if (p->state != SLOT_LIVE) {
            wi[0] = wi[1] = 0.0;
            wi[2] = 1.0;
            *pdf = 0.0;
            return LL_OK;
        }
        if (!ll_measured_draw_end(t, &p->lk, wi, pdf, value))
            return LL_OK;
        /* ll_measured_blend_sample's weight of one basis. */
        for (c = 0; c < 3; ++c)
            value[c] *= p->weight;
        ll_bsdf_measured_rgb(value, wi[2], ll_bsdf_transport_scale(b, p->v[2], -wi[2], job->mode),
                             rgb);
    }
    return LL_OK;
}

size_t ll_measured_batch_range(const ll_batch_job *job, size_t begin, size_t end,
                               ll_status *failed)
{
    pipe_slot ring[LL_PIPE_RING];
    const size_t d = job->kind == LL_BATCH_SAMPLE ? LL_PIPE_SAMPLE : LL_PIPE_EVAL;
    const size_t half = d / 2, mask = LL_PIPE_RING - 1;
    size_t i, first = end;
    *failed = LL_OK;
    /* Step i finishes element i - d, moves element i - d / 2 on and starts
     * element i; the indices outside [begin, end) are the pipeline's
     * filling and draining. */
    for (i = begin; i < end + d; ++i) {
        if (i >= begin + d) {
            ll_status s = finish(job, i - d, &ring[(i - d) & mask]);
            if (s != LL_OK && first == end) {
                first = i - d;
                *failed = s;
            }
        }
        if (i >= begin + half && i - half < end)
            middle(job, &ring[(i - half) & mask]);
        if (i < end)
            start(job, i, &ring[i & mask]);
    }
    return first;
}
