/*
 * The commit of a .bsdf file (bsdf_write_commit.h). The progress of the
 * streaming commit: the offsets in [0, 0.05] of "writing" a node row a
 * unit, the CDF in [0.05, 0.1] (the source's stage), the pair table in [0.1, 0.15] a node row a unit, the coefficient block
 * in [0.15, 1] a column a unit; the report of 1 comes last, before the
 * temporary file replaces the target. A call that handed the layers over
 * itself (ll_bsdf_write) reported their going in first: the commit then
 * fills what is left of "writing" after job->progress_from.
 */
#include "storage/bsdf_write_commit.h"

#include <string.h>

ll_status ll_wjob_put_pairs(ll_bsdf_out *out, const write_job *job)
{
    size_t k;
    for (k = 0; k < job->nn * job->nn; ++k) {
        if (k % job->nn == 0) {
            ll_watch_advance(job->watch, 1);
            if (ll_watch_poll(job->watch))
                return write_cancelled(job);
        }
        ll_bsdf_out_u32(out, job->offset[k]);
        ll_bsdf_out_u32(out, job->length[k]);
    }
    return LL_OK;
}

ll_status ll_wjob_put_end(ll_bsdf_out *out, const write_job *job, ll_status s)
{
    const char *metadata = ll_wjob_metadata(job);
    /* The last report comes before the temporary file replaces the
     * target: a cancel there still leaves no file. */
    s = ll_watch_finish(job->watch, s, job->fn);
    if (s != LL_OK) {
        ll_bsdf_out_abort(out);
        return s;
    }
    ll_bsdf_out_bytes(out, metadata, strlen(metadata));
    return ll_bsdf_out_commit(out);
}

/* The CDF table as it is in memory (the channel writer's, computed by its
 * prepare from the order-0 matrices it kept). */
static void put_cdf_table(ll_bsdf_out *out, const write_job *job)
{
    size_t k;
    for (k = 0; k < job->nn * job->nn * job->n_bases; ++k)
        ll_bsdf_out_f32(out, job->cdf[k]);
}

ll_status ll_wjob_commit(write_job *job, ll_spill *spill, const char *path,
                         const ll_wjob_source *src)
{
    size_t nn = job->nn, i;
    ll_bsdf_out *out = NULL;
    ll_status s;
    /* Everything that can fail for want of memory or of a valid total comes
     * before the output is begun. */
    if ((s = ll_spill_flush(spill, job->fn)) != LL_OK ||
        (s = ll_wjob_compute_offsets(job)) != LL_OK ||
        (src->prepare && (s = src->prepare(src->writer)) != LL_OK))
        return s;
    if (!job->opts.metadata && (s = ll_wjob_default_metadata(job)) != LL_OK)
        return s;
    if ((s = ll_bsdf_out_begin(path, job->fn, &out)) != LL_OK)
        return s;
    ll_wjob_put_header(out, job, strlen(ll_wjob_metadata(job)));
    if (src->put_cdf)
        s = src->put_cdf(src->writer, out);
    else
        put_cdf_table(out, job);
    ll_wjob_stage(job, 0.1, 0.05, nn);
    if (s == LL_OK)
        s = ll_wjob_put_pairs(out, job);
    if (s == LL_OK)
        ll_wjob_stage(job, 0.15, 0.85, nn);
    for (i = 0; i < nn && s == LL_OK; ++i) {
        ll_watch_advance(job->watch, 1);
        if (ll_watch_poll(job->watch))
            s = write_cancelled(job);
        else if (layer_index(i, job->h) != (size_t)-1) /* mu = 0 holds no coefficients */
            s = src->put_column(src->writer, out, i);
    }
    return ll_wjob_put_end(out, job, s);
}
