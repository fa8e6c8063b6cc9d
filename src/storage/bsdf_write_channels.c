/*
 * The channel-by-channel writer (bsdf_write_channels.h): what the material
 * builder hands the file to as soon as a channel's stack is complete, so
 * that its double layer can be freed before the next channel's is built.
 *
 * Why a spill. A file's coefficient block is pair-major (pair after pair,
 * channels Y, R, B within a pair) with every pair's series as long as the
 * longest over the channels (bsdf_write.c's rule), and Y mixes all three
 * in double precision before rounding, so nothing of a pair can be written
 * before the last channel is seen. Each channel therefore goes, as it
 * arrives, to a spill file beside the output (unlinked right after it is
 * created, as ll_bsdf_writer's: no name while the writer works, its space
 * returns however the process ends): for each column, each row's stored
 * doubles up to the row's extent E (one past the last order the layer
 * stores there; beyond it every value is 0 and no final length exceeds
 * the largest E). In memory stay only what is n x n: the channel's series
 * lengths (joined into the running maxima), its extents and its order-0
 * matrix (the CDF's), about 20 n^2 bytes a channel, against the layer's
 * 8 bytes per stored value plus 16 per column per order.
 *
 * Commit (ll_wjob_commit, bsdf_write_commit.c, as ll_bsdf_writer's: this
 * file gives it the CDF, computed from the order-0 matrices, and each
 * column) reads the spill back column by column and writes every value by
 * the expression bsdf_write.c uses (ll_wjob_staged_value on the same
 * doubles), so the file is byte for byte ll_bsdf_write's for the same
 * layers; the output itself is the atomic writer's (bsdf_file_out.c).
 */
#include "storage/bsdf_write_channels.h"
#include "storage/bsdf_write_commit.h"
#include "layer/layer.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static const char *const fn_open = "ll_material_build (opening the file)";
static const char *const fn_add = "ll_material_build (a finished channel)";
static const char *const fn_commit = "ll_material_build (writing)";

struct ll_channel_writer {
    char *path;
    write_job job;                 /* options, shape, lengths (max), offsets */
    char *metadata_copy;
    int failed;                    /* only abort is left                     */
    int added[3];
    double *nodes, *weights;       /* [n] the first channel's: every layer's */
    double *factor;                /* [2 n] surface factor, order 0 | k > 0  */
    double *order0[3];             /* [n * n] col * n + row: M_0 (the CDF)   */
    uint32_t *ext[3];              /* [n * n] col * n + row: extents         */
    unsigned long long *col_at[3]; /* [n] spill offset of each column       */
    size_t *col_values[3];         /* [n] doubles of each column in the spill */
    uint32_t *len;                 /* [n * n] one channel's lengths (add)    */
    double *tail;                  /* [n * n] scratch of the lengths (add)   */
    double *stage;                 /* [n * m] one column's orders (add)      */
    double *col[3];                /* commit: one spilled column a channel   */
    size_t *row_at[3];             /* [n] commit: each row's place in col[c] */
    double *row;                   /* [channels * m] commit: one pair's      */
    ll_spill spill;                /* bsdf_write_spill.h                     */
};

/* ------------------------------------------------------------------ open */

static void writer_free(ll_channel_writer *w)
{
    size_t c;
    ll_spill_close(&w->spill);
    for (c = 0; c < 3; ++c) {
        ll_free(w->order0[c]);
        ll_free(w->ext[c]);
        ll_free(w->col_at[c]);
        ll_free(w->col_values[c]);
        ll_free(w->col[c]);
        ll_free(w->row_at[c]);
    }
    ll_free(w->row);
    ll_free(w->path);
    ll_free(w->metadata_copy);
    ll_free(w->nodes);
    ll_free(w->weights);
    ll_free(w->factor);
    ll_free(w->len);
    ll_free(w->tail);
    ll_free(w->stage);
    ll_free(w->job.nodes);
    ll_free(w->job.length);
    ll_free(w->job.offset);
    ll_free(w->job.cdf);
    ll_free(w->job.metadata);
    ll_free(w);
}

static char *copy_text(const char *text)
{
    size_t len = strlen(text);
    char *c = ll_malloc(len + 1);
    if (c)
        memcpy(c, text, len + 1);
    return c;
}

ll_status ll_channel_writer_open(const char *path, size_t n_channels,
                                 const ll_bsdf_write_options *opts, ll_channel_writer **out)
{
    ll_channel_writer *w;
    ll_status s;
    *out = NULL;
    if (!path || !*path)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: path is NULL or empty", fn_open);
    if (n_channels != 1 && n_channels != 3)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: n_channels = %zu (must be 1, or 3 for R, G, B)", fn_open,
                       n_channels);
    w = ll_calloc(1, sizeof *w);
    if (!w)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", fn_open);
    ll_spill_init(&w->spill);
    w->job.fn = fn_open;
    w->job.n_channels = n_channels;
    w->job.n_bases = 1;
    w->path = copy_text(path);
    if (!w->path) {
        s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", fn_open);
        goto fail;
    }
    if ((s = ll_wjob_keep_options(&w->job, opts, &w->metadata_copy)) != LL_OK)
        goto fail;
    if ((s = ll_spill_open(&w->spill, w->path, fn_open)) != LL_OK)
        goto fail;
    *out = w;
    return LL_OK;
fail:
    writer_free(w);
    return s;
}

/* ------------------------------------------------------------------- add */

/* The file's shape from the first channel's layer (as check_layers and
 * prepare of bsdf_write.c take it). */
static ll_status take_shape(ll_channel_writer *w, const ll_layer *l)
{
    write_job *job = &w->job;
    size_t n = l->n, n2, nm, k, c;
    ll_status s = ll_wjob_take_shape(job, l);
    if (s != LL_OK)
        return s;
    if (!ll_size_mul(n, n, &n2) || !ll_size_mul(n, l->m, &nm))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: the layers are too large", fn_add);
    w->nodes = ll_alloc_array(n, sizeof *w->nodes);
    w->weights = ll_alloc_array(n, sizeof *w->weights);
    w->factor = ll_alloc_array(n, 2 * sizeof *w->factor);
    w->len = ll_alloc_array(n2, sizeof *w->len);
    w->tail = ll_alloc_array(n2, sizeof *w->tail);
    w->stage = ll_calloc_array(nm, sizeof *w->stage);
    if (!w->nodes || !w->weights || !w->factor || !w->len || !w->tail || !w->stage)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", fn_add);
    for (c = 0; c < job->n_channels; ++c) {
        w->order0[c] = ll_alloc_array(n2, sizeof *w->order0[c]);
        w->ext[c] = ll_alloc_array(n2, sizeof *w->ext[c]);
        w->col_at[c] = ll_alloc_array(n, sizeof *w->col_at[c]);
        w->col_values[c] = ll_alloc_array(n, sizeof *w->col_values[c]);
        if (!w->order0[c] || !w->ext[c] || !w->col_at[c] || !w->col_values[c])
            return ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", fn_add);
    }
    memcpy(w->nodes, l->nodes, n * sizeof *w->nodes);
    memcpy(w->weights, l->weights, n * sizeof *w->weights);
    for (k = 0; k < n; ++k) {
        w->factor[k] = ll_layer_surface_factor(l, k, 0);
        w->factor[n + k] = ll_layer_surface_factor(l, k, 1);
    }
    return LL_OK;
}

/* What ll_layer_check_compatible checks, against the first channel's. */
static ll_status check_shape(const ll_channel_writer *w, const ll_layer *l)
{
    const write_job *job = &w->job;
    if (l->n != job->n || l->m != job->m)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: the layers do not match (%zu nodes x %zu orders vs %zu x %zu)",
                       fn_add, job->n, job->m, l->n, l->m);
    if (memcmp(l->nodes, w->nodes, job->n * sizeof *w->nodes) != 0 ||
        memcmp(l->weights, w->weights, job->n * sizeof *w->weights) != 0)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: the layers use different nodes or weights",
                       fn_add);
    return LL_OK;
}

/* The layer's series lengths joined into the running maxima (as
 * bsdf_write.c's compute_lengths); its order 0 kept for the CDF. */
static ll_status join_lengths(ll_channel_writer *w, size_t channel, const ll_layer *l)
{
    write_job *job = &w->job;
    size_t n = job->n, nn = job->nn, i, o;
    ll_status s = ll_wjob_layer_lengths(job, l, w->len, w->tail, w->order0[channel]);
    for (i = 0; i < nn && s == LL_OK; ++i) {
        size_t li = layer_index(i, job->h);
        if (li == (size_t)-1)
            continue;
        for (o = 0; o < nn; ++o) {
            size_t lo = layer_index(o, job->h);
            uint32_t *dst = &job->length[i * nn + o];
            if (lo != (size_t)-1 && w->len[li * n + lo] > *dst)
                *dst = w->len[li * n + lo];
        }
    }
    return s;
}

/* Extents of the layer (col * n + row): one past its last stored order. */
static void layer_extents(const ll_layer *l, uint32_t *ext)
{
    size_t n = l->n, h = n / 2, k, col, j;
    int half;
    memset(ext, 0, n * n * sizeof *ext);
    for (k = 0; k < l->m; ++k) {
        const ll_order *o = l->orders[k];
        if (!o)
            continue;
        for (col = 0; col < n; ++col)
            for (half = 0; half < 2; ++half) {
                const ll_segment *sg = &o->seg[2 * col + (size_t)half];
                for (j = 0; j < sg->len; ++j)
                    ext[col * n + (size_t)half * h + sg->lo + j] = (uint32_t)(k + 1);
            }
    }
}

/* The layer's stored doubles to the spill, column after column, each row
 * up to its extent. */
static ll_status spill_layer(ll_channel_writer *w, size_t channel, const ll_layer *l,
                             ll_watch *watch)
{
    const write_job *job = &w->job;
    size_t n = job->n, m = job->m, col, row;
    const uint32_t *ext = w->ext[channel];
    ll_status s = LL_OK;
    for (col = 0; col < n && s == LL_OK; ++col) {
        size_t kmax = 0, values = 0;
        if (ll_watch_poll(watch))
            return write_cancelled(job);
        for (row = 0; row < n; ++row) {
            size_t e = ext[col * n + row];
            kmax = e > kmax ? e : kmax;
            values += e;
        }
        w->col_at[channel][col] = ll_spill_tell(&w->spill);
        w->col_values[channel][col] = values;
        ll_wjob_stage_column(l, col, kmax, w->stage, 0);
        for (row = 0; row < n && s == LL_OK; ++row)
            s = ll_spill_put(&w->spill, w->stage + row * m, ext[col * n + row] * sizeof(double),
                             fn_add);
        ll_wjob_stage_column(l, col, kmax, w->stage, 1);
    }
    return s;
}

ll_status ll_channel_writer_add(ll_channel_writer *w, size_t channel, const ll_layer *layer,
                                const ll_monitor *monitor)
{
    write_job *job = &w->job;
    ll_watch watch;
    ll_status s;
    if (w->failed)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: an earlier call failed; only abort is left", fn_add);
    job->fn = fn_add;
    if ((s = ll_watch_begin(&watch, monitor, fn_add)) != LL_OK)
        goto fail;
    job->watch = &watch;
    if (!layer || channel >= job->n_channels || w->added[channel]) {
        s = ll_fail(LL_ERROR_INVALID_ARGUMENT,
                    "%s: channel %zu of %zu is %s", fn_add, channel, job->n_channels,
                    !layer ? "NULL" : channel >= job->n_channels ? "not one" : "added already");
        goto fail;
    }
    if (!w->nodes && (s = take_shape(w, layer)) != LL_OK)
        goto fail;
    if ((s = check_shape(w, layer)) != LL_OK)
        goto fail;
    ll_watch_stage(&watch, "writing", 0.0, 1.0, job->m);
    if ((s = join_lengths(w, channel, layer)) != LL_OK)
        goto fail;
    layer_extents(layer, w->ext[channel]);
    if ((s = spill_layer(w, channel, layer, &watch)) != LL_OK)
        goto fail;
    job->watch = NULL;
    w->added[channel] = 1;
    return LL_OK;
fail:
    job->watch = NULL;
    w->failed = 1;
    return s;
}

/* ---------------------------------------------------------------- commit */

/* Stored value of file channel c (Y, R, B) at order k from the channels'
 * doubles v[L * stride + k], by bsdf_write.c's expression. */
static double stored_value(const write_job *job, size_t c, const double *v, size_t stride,
                           size_t k, size_t lo, double factor, const double *nodes)
{
    return ll_wjob_staged_value(job->n_channels, c, v, stride, k, fabs(nodes[lo]), factor);
}

/* The CDF table, as bsdf_write.c's compute_cdf (one basis). */
static ll_status compute_cdf(ll_channel_writer *w)
{
    write_job *job = &w->job;
    size_t nn = job->nn, n = job->n, i, o, c;
    double *values = ll_alloc_array(nn, sizeof *values);
    job->cdf = ll_alloc_array(nn * nn, sizeof *job->cdf);
    if (!values || !job->cdf) {
        ll_free(values);
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", fn_commit);
    }
    ll_wjob_stage(job, 0.05, 0.05, nn);
    for (i = 0; i < nn; ++i) {
        size_t li = layer_index(i, job->h);
        ll_watch_advance(job->watch, 1);
        if (ll_watch_poll(job->watch)) {
            ll_free(values);
            return write_cancelled(job);
        }
        for (o = 0; o < nn; ++o) {
            size_t lo = layer_index(o, job->h);
            double v[3];
            values[o] = 0.0;
            if (!job->length[i * nn + o])
                continue; /* (also every pair with a mu = 0 node) */
            for (c = 0; c < job->n_channels; ++c)
                v[c] = w->order0[c][li * n + lo];
            values[o] = (double)(float)stored_value(job, 0, v, 1, 0, lo, w->factor[li],
                                                    w->nodes);
        }
        ll_wjob_integrate_row(job->nodes, values, nn, job->cdf + i * nn, 1);
    }
    ll_free(values);
    return LL_OK;
}

/* The commit's scratch and CDF (ll_wjob_source.prepare): the add's stage
 * freed (the commit reads columns instead), job->cdf, and for each channel
 * room for its longest spilled column and its rows' places in it, and one
 * pair's doubles of every channel. */
static ll_status prepare_commit(void *writer)
{
    ll_channel_writer *w = writer;
    const write_job *job = &w->job;
    size_t n = job->n, c, i;
    ll_free(w->stage);
    w->stage = NULL;
    for (c = 0; c < job->n_channels; ++c) {
        size_t most = 0;
        for (i = 0; i < n; ++i)
            most = w->col_values[c][i] > most ? w->col_values[c][i] : most;
        w->col[c] = ll_alloc_array(most ? most : 1, sizeof *w->col[c]);
        w->row_at[c] = ll_alloc_array(n, sizeof *w->row_at[c]);
        if (!w->col[c] || !w->row_at[c])
            return ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", fn_commit);
    }
    w->row = ll_alloc_array(job->n_channels * job->m, sizeof *w->row);
    if (!w->row)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", fn_commit);
    return compute_cdf(w);
}

/* File column i (layer column li) of the coefficient block
 * (ll_wjob_source.put_column): every channel's spilled column read back
 * into w->col[c] (rows at w->row_at[c][row]), then each pair's series. */
static ll_status put_column(void *writer, ll_bsdf_out *out, size_t i)
{
    ll_channel_writer *w = writer;
    const write_job *job = &w->job;
    size_t n = job->n, m = job->m, nn = job->nn, nch = job->n_channels, li, o, c, k, r;
    double *row = w->row;
    ll_status s = LL_OK;
    li = layer_index(i, job->h);
    for (c = 0; c < nch && s == LL_OK; ++c) {
        size_t at = 0;
        s = ll_spill_read(&w->spill, w->col_at[c][li], w->col[c],
                          w->col_values[c][li] * sizeof(double), fn_commit);
        for (r = 0; r < n; ++r) {
            w->row_at[c][r] = at;
            at += w->ext[c][li * n + r];
        }
    }
    for (o = 0; o < nn && s == LL_OK; ++o) {
        size_t len = job->length[i * nn + o], lo = layer_index(o, job->h);
        if (len == 0)
            continue;
        if (ll_watch_poll(job->watch))
            return write_cancelled(job);
        /* row[c * m + k]: channel c's order k at (lo, li), 0 beyond its extent. */
        for (c = 0; c < nch; ++c) {
            size_t e = w->ext[c][li * n + lo];
            for (k = 0; k < len; ++k)
                row[c * m + k] = k < e ? w->col[c][w->row_at[c][lo] + k] : 0.0;
        }
        for (c = 0; c < nch && s == LL_OK; ++c)
            for (k = 0; k < len; ++k) {
                double v = stored_value(job, c, row, m, k, lo, w->factor[(k > 0) * n + li],
                                        w->nodes);
                if (!(fabs(v) <= FLT_MAX)) {
                    s = ll_fail(LL_ERROR_INVALID_ARGUMENT,
                                "%s: coefficient %zu of node pair (%zu, %zu) is %g, beyond "
                                "float range",
                                fn_commit, k, o, i, v);
                    break;
                }
                ll_bsdf_out_f32(out, (float)v);
            }
    }
    return s;
}

static ll_status commit_file(ll_channel_writer *w, const ll_monitor *monitor)
{
    write_job *job = &w->job;
    ll_wjob_source src = { w, prepare_commit, NULL, put_column };
    ll_watch watch;
    size_t c;
    ll_status s;

    job->fn = fn_commit;
    if ((s = ll_watch_begin(&watch, monitor, fn_commit)) != LL_OK)
        return s;
    job->watch = &watch;
    if (w->failed)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: an earlier call failed; only abort is left", fn_commit);
    for (c = 0; c < job->n_channels; ++c)
        if (!w->added[c])
            return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: channel %zu was not added",
                           fn_commit, c);
    return ll_wjob_commit(job, &w->spill, w->path, &src);
}

ll_status ll_channel_writer_commit(ll_channel_writer *w, const ll_monitor *monitor)
{
    ll_status s;
    if (!w)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: writer is NULL", fn_commit);
    s = commit_file(w, monitor);
    writer_free(w);
    return s;
}

void ll_channel_writer_abort(ll_channel_writer *w)
{
    if (w)
        writer_free(w);
}
