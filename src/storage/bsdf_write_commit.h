/*
 * The commit of a .bsdf file, shared by the writers (internal): the file's
 * parts in the order docs/bsdf-format.md stores them, through the atomic
 * writer (bsdf_file_out.c), so that every writer writes the same bytes and
 * fails the same way.
 *
 * ll_wjob_commit is the whole commit of the two streaming writers
 * (ll_bsdf_writer_*, bsdf_writer.c, basis by basis; the material builder's
 * channel writer, bsdf_write_channels.c, channel by channel): both keep
 * what they were given in a spill file and know the final series lengths
 * only at the end, and differ only in where the CDF and a column's
 * coefficients come from, which they say through an ll_wjob_source. The
 * in-memory writer (bsdf_write.c) uses its pieces: the pair table and the
 * end.
 */
#ifndef LL_STORAGE_BSDF_WRITE_COMMIT_H
#define LL_STORAGE_BSDF_WRITE_COMMIT_H

#include "storage/bsdf_write_job.h"
#include "storage/bsdf_write_spill.h"

/* What one streaming writer supplies at commit. job->watch is polled by
 * the commit between the calls; a callback polls it inside its own loops. */
typedef struct ll_wjob_source {
    void *writer;
    /* After the offsets are known and before the output is begun: the
     * writer's commit scratch, and job->cdf if it is to come from memory.
     * Nullable. */
    ll_status (*prepare)(void *writer);
    /* The CDF table, [(i * nn + o) * n_bases + b], as file floats, with a
     * stage of its own in [0.05, 0.1] of the commit (ll_wjob_stage). NULL: job->cdf is written
     * as it is (its stage, if any, was prepare's). */
    ll_status (*put_cdf)(void *writer, ll_bsdf_out *out);
    /* File column i of the coefficient block (i not a mu = 0 node): the
     * pairs (o, i) in table order, each job->length[i * nn + o] long,
     * [channel][basis][k]; fails if a value is beyond float range. */
    ll_status (*put_column)(void *writer, ll_bsdf_out *out, size_t i);
} ll_wjob_source;

/* The streaming writers' commit once every part was added (job->fn and
 * job->watch set by the caller): the spill flushed, offsets and the
 * default metadata (unless the options give one) from the final lengths,
 * then the file to path. An error or a cancel, also at the last report,
 * leaves no file and an existing one as it was. */
LL_INTERNAL ll_status ll_wjob_commit(write_job *job, ll_spill *spill, const char *path,
                                     const ll_wjob_source *src);

/* The pair table (offset, length of each pair, nn * nn in table order),
 * one unit of the current stage per node row, polled there. */
LL_INTERNAL ll_status ll_wjob_put_pairs(ll_bsdf_out *out, const write_job *job);

/* The end of a file whose coefficient block is written (s its outcome so
 * far): the last report, then the metadata and the commit, or the abort
 * on an error or cancel. Returns the outcome. */
LL_INTERNAL ll_status ll_wjob_put_end(ll_bsdf_out *out, const write_job *job, ll_status s);

/* The writer (bsdf_writer.c) as the calls that are not ll_bsdf_writer_*
 * use it: ll_bsdf_write and ll_bsdf_write_textured (bsdf_write.c), the
 * material builder's channel writer (bsdf_write_channels.c). open: fn
 * names the calls in messages (open, add, commit); in_memory keeps the
 * spill in memory (no file beside path). add_unit: channel `channel` of
 * basis `basis` (the bases in order, a basis's channels in any), polling
 * watch (nullable) per order and column and counting an order a unit of
 * its stage. commit: the file, its stages in [progress_from, 1] of
 * "writing"; w is left to the caller to free (ll_bsdf_writer_abort). */
LL_INTERNAL ll_status ll_writer_open_as(const char *const fn[3], const char *path,
                                        size_t n_channels, size_t n_parameters,
                                        const size_t *param_counts,
                                        const double *param_positions,
                                        const ll_bsdf_write_options *opts, int in_memory,
                                        ll_bsdf_writer **out);
LL_INTERNAL ll_status ll_writer_add_unit(ll_bsdf_writer *w, size_t basis, size_t channel,
                                         const ll_layer *layer, ll_watch *watch);
/* After a failure of the caller's own (its monitor): only abort is left. */
LL_INTERNAL void ll_writer_fail(ll_bsdf_writer *w);
LL_INTERNAL ll_status ll_writer_commit_watched(ll_bsdf_writer *w, ll_watch *watch,
                                               double progress_from);

/* The file's metadata: the options', else the default one. */
static inline const char *ll_wjob_metadata(const write_job *job)
{
    return job->opts.metadata ? job->opts.metadata : job->metadata;
}

#endif /* LL_STORAGE_BSDF_WRITE_COMMIT_H */
