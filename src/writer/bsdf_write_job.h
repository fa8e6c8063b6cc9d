/*
 * The inside of the .bsdf writer (bsdf_writer.c: one layer, a (basis,
 * channel) unit, at a time; behind ll_bsdf_writer_*, ll_bsdf_write and
 * the material builder's channel writer): what is known about one file
 * before its bytes are produced, and the pieces of bsdf_write.c it uses
 * (the rules are in bsdf_write.c's comment).
 */
#ifndef LL_BSDF_WRITE_JOB_H
#define LL_BSDF_WRITE_JOB_H

#include "layerlab/ll_bsdf_write.h"
#include "writer/bsdf_file_out.h"
#include "reader/bsdf_format.h"
#include "writer/bsdf_write_spill.h"
#include "support/watch.h"

/* Everything known about one file before its bytes are produced. */
typedef struct write_job {
    const char *fn;
    size_t n_channels, n_bases, n_parameters, n_parameter_values;
    const size_t *param_counts;
    const double *param_positions;
    ll_bsdf_write_options opts;
    size_t n, h, m;                /* layer nodes, half, orders            */
    size_t nn;                     /* file nodes = n + 2                   */
    float *nodes;                  /* [nn] file nodes                      */
    uint32_t *length;              /* [nn * nn] series length, i * nn + o  */
    uint32_t *offset;              /* [nn * nn]                            */
    size_t max_order, n_coeffs;
    char *metadata;                /* default JSON, when opts has none     */
    ll_watch *watch;               /* polled per column / node row        */
    double progress_from;          /* the commit's stages fill [this, 1]  */
} write_job;

static inline ll_status write_cancelled(const write_job *job)
{
    return ll_fail(LL_ERROR_CANCELLED, "%s: cancelled", job->fn);
}

/* A stage of the commit at [start, start + span] of its share of
 * "writing" (all of it, unless the layers went in earlier in the same
 * call: then the share after job->progress_from). */
static inline void ll_wjob_stage(const write_job *job, double start, double span, size_t total)
{
    double rest = 1.0 - job->progress_from;
    ll_watch_stage(job->watch, "writing", job->progress_from + start * rest, span * rest, total);
}

/* Layer index of file node f, or (size_t)-1 for the two mu = 0 nodes. */
static inline size_t layer_index(size_t f, size_t h)
{
    if (f < h)
        return h - 1 - f;
    if (f >= h + 2)
        return f - 2;
    return (size_t)-1;
}

/* Options (up to the caller's struct_size) and checks; parameters. */
LL_INTERNAL ll_status ll_wjob_read_options(write_job *job, const ll_bsdf_write_options *opts);
LL_INTERNAL ll_status ll_wjob_check_parameters(write_job *job);
/* The streaming writers' open: the options read and checked, and the
 * metadata (if any) copied into *metadata_copy, which job->opts then
 * points at, so the caller's strings need not outlive the call. */
LL_INTERNAL ll_status ll_wjob_keep_options(write_job *job, const ll_bsdf_write_options *opts,
                                           char **metadata_copy);
/* The streaming writers' shape from their first layer: n, h, m, nn, the
 * file's nodes, and the length (zeroed) and offset tables of nn * nn. */
LL_INTERNAL ll_status ll_wjob_take_shape(write_job *job, const ll_layer *l);
/* Series lengths of one layer, col * n + row (layer indices); checks that
 * every value is finite. len, tail, ref0: n * n scratch each. */
LL_INTERNAL ll_status ll_wjob_layer_lengths(const write_job *job, const ll_layer *l,
                                            uint32_t *len, double *tail, double *ref0);
/* offset[], max_order, n_coeffs from length[]. */
LL_INTERNAL ll_status ll_wjob_compute_offsets(write_job *job);
/* The CDF of one row: running exact integrals of the Catmull-Rom segments. */
LL_INTERNAL void ll_wjob_integrate_row(const float *nodes, const double *values, size_t n,
                                       float *cdf, size_t stride);
LL_INTERNAL ll_status ll_wjob_default_metadata(write_job *job);
/* The file's start, what comes before the CDF: the header, the nodes, the
 * parameters' position counts and positions. */
LL_INTERNAL void ll_wjob_put_header(ll_bsdf_out *out, const write_job *job,
                                    size_t metadata_size);
/* Column col of a layer's orders k < kmax into stage[row * m + k] (or
 * clear them). */
LL_INTERNAL void ll_wjob_stage_column(const ll_layer *l, size_t col, size_t kmax, double *stage,
                                      int clear);

/* The stored value of channel c (Y, R, B of colour files) from one basis's
 * staged columns: set[L * per_layer + k] is layer L's order k at the row;
 * mu_o the row's |mu|, f the column's surface factor of order k. */
static inline double ll_wjob_staged_value(size_t n_channels, size_t c, const double *set,
                                          size_t per_layer, size_t k, double mu_o, double f)
{
    if (n_channels == 1 || c == 1)
        return set[k] * mu_o / f;
    if (c == 2)
        return set[2 * per_layer + k] * mu_o / f;
    return LL_BSDF_Y_FROM_R * (set[k] * mu_o / f) +
           LL_BSDF_Y_FROM_G * (set[per_layer + k] * mu_o / f) +
           LL_BSDF_Y_FROM_B * (set[2 * per_layer + k] * mu_o / f);
}

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

#endif /* LL_BSDF_WRITE_JOB_H */
