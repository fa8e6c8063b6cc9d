/*
 * The streaming writer of textured files (ll_bsdf_writer_*, ll_bsdf_write.h):
 * bases arrive one at a time, and the file's coefficient block interleaves
 * them (pair after pair, [channel][basis][k]), with every pair's series as
 * long as the longest over channels and bases (bsdf_write.c's rule). The
 * final lengths are known only when the last basis has been seen, so each
 * basis goes to a spill file as it arrives, and commit writes the file
 * from the spill:
 *
 *  - add_basis: the basis's series lengths join the running maxima
 *    (length[], nn * nn); its CDF (which depends on its own a_0 only:
 *    a pair whose final length is 0 has a_0 = 0 in every basis) and, for
 *    each pair, its stored floats up to the pair's extent E (one past the
 *    last order that stores anything, over the channels: beyond it every
 *    coefficient is 0, and a final length never exceeds the largest E) go
 *    to the spill: [CDF nn*nn floats][E nn*nn u32][pairs in table order:
 *    channel-major, E floats per channel]. The values are the floats the
 *    file will hold, computed by the same expression as bsdf_write.c's.
 *  - commit: offsets from the final lengths, then the file in order
 *    (ll_wjob_commit, bsdf_write_commit.c, as the channel writer's), the
 *    interleaved parts read back in chunks of LL_WRITER_CHUNK floats, or
 *    of one row of every basis's longest series if that is more (per
 *    column of pairs: every basis's E of that column, then the rows that
 *    fit), padding with zeros from E to the final length.
 *
 * Memory: the tables of nn * nn entries (as the in-memory writer), one
 * basis's staging while it is added, the chunk, and per basis its spill
 * offset, one column's extents and room in the chunk for one row of its
 * longest series (4 nn + 12 m + 16 bytes): never a layer per basis.
 * The spill lives beside the output (same file system; it was 0.55 of the
 * output's size on an 8 x 8 grid) and is unlinked right after it is
 * created, so no path names it while the writer works: however the process
 * ends, the space returns when the descriptor closes. The output itself is
 * the atomic writer's (bsdf_file_out.c).
 *
 * ll_bsdf_write and ll_bsdf_write_textured (bsdf_write.c) are this writer
 * with its spill in memory, fed every basis in one call under one monitor:
 * the internal open, add and commit below take the calls' names and watch.
 */
#include "storage/bsdf_write_commit.h"
#include "layer/layer.h"
#include "layerlab/ll_bsdf_write.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Floats read back at once at commit (256 KiB: big enough that the reads
 * are few, small beside a layer). */
#define LL_WRITER_CHUNK ((size_t)1 << 16)

static const char *const api_open = "ll_bsdf_writer_open";
static const char *const api_add = "ll_bsdf_writer_add_basis";
static const char *const api_commit = "ll_bsdf_writer_commit";

struct ll_bsdf_writer {
    char *path;
    write_job job;               /* lengths, nodes, options, parameters   */
    size_t *counts;              /* copies of the parameters              */
    double *positions;
    char *metadata_copy;
    size_t added;                /* bases added so far                     */
    int failed;                  /* an add failed: only abort is left      */
    ll_spill spill;              /* bsdf_write_spill.h                     */
    unsigned long long *basis_at;/* [n_bases] spill offset of each basis   */
    size_t chunk_floats;         /* commit's read-back chunk               */
    float *chunk;                /* commit: [chunk_floats]                 */
    unsigned char *bytes;        /* commit: one series as file bytes (4 m) */
    uint32_t *col_ext;           /* commit: [n_bases * nn] one column's E  */
    unsigned long long *cursor;  /* commit: [n_bases] next row in the spill */
    size_t *pos;                 /* commit: [n_bases] its place in chunk   */
    /* one basis's scratch, n * n unless said */
    uint32_t *len, *ext;
    double *tail, *ref0, *stage, *values;
    float *row_cdf;              /* nn * nn                                */
    float *row;                  /* channels * m: one pair's floats        */
    ll_layer *first;             /* basis 0's layer 0 (a clone): the shape */
    const char *fn_open, *fn_add, *fn_commit; /* the public call, in messages */
};

/* --------------------------------------------------------------- open */

static void writer_free(ll_bsdf_writer *w)
{
    ll_spill_close(&w->spill);
    ll_layer_destroy(w->first);
    ll_free(w->path);
    ll_free(w->counts);
    ll_free(w->positions);
    ll_free(w->metadata_copy);
    ll_free(w->basis_at);
    ll_free(w->chunk);
    ll_free(w->bytes);
    ll_free(w->col_ext);
    ll_free(w->cursor);
    ll_free(w->pos);
    ll_free(w->len);
    ll_free(w->ext);
    ll_free(w->tail);
    ll_free(w->ref0);
    ll_free(w->stage);
    ll_free(w->values);
    ll_free(w->row_cdf);
    ll_free(w->row);
    ll_free(w->job.nodes);
    ll_free(w->job.length);
    ll_free(w->job.offset);
    ll_free(w->job.metadata);
    ll_free(w);
}

/* Check the parameters as ll_bsdf_write_textured does, then keep copies. */
static ll_status copy_parameters(ll_bsdf_writer *w, size_t n_parameters, const size_t *counts,
                                 const double *positions)
{
    ll_status s;
    w->job.n_parameters = n_parameters;
    w->job.param_counts = counts;
    w->job.param_positions = positions;
    if ((s = ll_wjob_check_parameters(&w->job)) != LL_OK)
        return s;
    if (n_parameters > 0) {
        w->counts = ll_alloc_array(n_parameters, sizeof *w->counts);
        w->positions = ll_alloc_array(w->job.n_parameter_values, sizeof *w->positions);
        if (!w->counts || !w->positions)
            return ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", w->fn_open);
        memcpy(w->counts, counts, n_parameters * sizeof *counts);
        memcpy(w->positions, positions, w->job.n_parameter_values * sizeof *positions);
    }
    w->job.param_counts = w->counts;
    w->job.param_positions = w->positions;
    return LL_OK;
}

ll_status ll_writer_open_as(const char *const fn[3], const char *path, size_t n_channels,
                            size_t n_parameters, const size_t *param_counts,
                            const double *param_positions, const ll_bsdf_write_options *opts,
                            int in_memory, ll_bsdf_writer **out)
{
    ll_bsdf_writer *w = NULL;
    ll_status s;
    size_t len;
    if (!out)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: out is NULL", fn[0]);
    *out = NULL;
    if (!path || !*path)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: path is NULL or empty", fn[0]);
    if (n_channels != 1 && n_channels != 3)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: n_channels = %zu (must be 1, or 3 for R, G, B)", fn[0],
                       n_channels);
    w = ll_calloc(1, sizeof *w);
    if (!w)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", fn[0]);
    ll_spill_init(&w->spill);
    w->fn_open = fn[0];
    w->fn_add = fn[1];
    w->fn_commit = fn[2];
    w->job.fn = w->fn_open;
    w->job.n_channels = n_channels;
    len = strlen(path);
    w->path = ll_malloc(len + 1);
    if (!w->path) {
        s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", w->fn_open);
        goto fail;
    }
    memcpy(w->path, path, len + 1);
    if ((s = ll_wjob_keep_options(&w->job, opts, &w->metadata_copy)) != LL_OK ||
        (s = copy_parameters(w, n_parameters, param_counts, param_positions)) != LL_OK)
        goto fail;
    w->basis_at = ll_calloc_array(w->job.n_bases, sizeof *w->basis_at);
    if (!w->basis_at) {
        s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", w->fn_open);
        goto fail;
    }
    if (in_memory)
        ll_spill_open_memory(&w->spill, w->path);
    else if ((s = ll_spill_open(&w->spill, w->path, w->fn_open)) != LL_OK)
        goto fail;
    *out = w;
    return LL_OK;
fail:
    writer_free(w);
    return s;
}

ll_status ll_bsdf_writer_open(const char *path, size_t n_channels, size_t n_parameters,
                              const size_t *param_counts, const double *param_positions,
                              const ll_bsdf_write_options *opts, ll_bsdf_writer **out)
{
    static const char *const fn[3] = { api_open, api_add, api_commit };
    return ll_writer_open_as(fn, path, n_channels, n_parameters, param_counts, param_positions,
                             opts, 0, out);
}

/* ----------------------------------------------------------- add_basis */

/* The shape of the file, from the first basis's first layer. */
static ll_status take_shape(ll_bsdf_writer *w, const ll_layer *l)
{
    write_job *job = &w->job;
    size_t n = l->n, nn = n + 2, n2, nn2, per_layer;
    ll_status s = ll_wjob_take_shape(job, l);
    if (s != LL_OK)
        return s;
    if (!ll_size_mul(n, n, &n2) || !ll_size_mul(nn, nn, &nn2) ||
        !ll_size_mul(n, l->m, &per_layer) || !ll_size_mul(per_layer, job->n_channels, &per_layer))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: the layers are too large", w->fn_add);
    w->len = ll_alloc_array(n2, sizeof *w->len);
    w->ext = ll_alloc_array(nn2, sizeof *w->ext);
    w->tail = ll_alloc_array(n2, sizeof *w->tail);
    w->ref0 = ll_alloc_array(n2, sizeof *w->ref0);
    w->stage = ll_calloc_array(per_layer, sizeof *w->stage);
    w->values = ll_alloc_array(nn, sizeof *w->values);
    w->row_cdf = ll_alloc_array(nn2, sizeof *w->row_cdf);
    w->row = ll_alloc_array(job->n_channels * l->m, sizeof *w->row);
    if (!w->len || !w->ext || !w->tail || !w->ref0 || !w->stage || !w->values || !w->row_cdf ||
        !w->row)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", w->fn_add);
    return ll_layer_clone(l, &w->first);
}

/* Extent of every file pair of this basis into w->ext (i * nn + o): one
 * past the last order that stores an entry there, over the channels. */
static void basis_extents(ll_bsdf_writer *w, const ll_layer *const *layers)
{
    const write_job *job = &w->job;
    size_t n = job->n, h = job->h, nn = job->nn, c, k, col, j;
    int half;
    memset(w->len, 0, n * n * sizeof *w->len); /* (reused: col * n + row) */
    for (c = 0; c < job->n_channels; ++c)
        for (k = 0; k < job->m; ++k) {
            const ll_order *o = layers[c]->orders[k];
            if (!o)
                continue;
            for (col = 0; col < n; ++col)
                for (half = 0; half < 2; ++half) {
                    const ll_segment *sg = &o->seg[2 * col + (size_t)half];
                    for (j = 0; j < sg->len; ++j) {
                        size_t row = (size_t)half * h + sg->lo + j;
                        if (w->len[col * n + row] < k + 1)
                            w->len[col * n + row] = (uint32_t)(k + 1);
                    }
                }
        }
    for (j = 0; j < nn; ++j)
        for (k = 0; k < nn; ++k) {
            size_t li = layer_index(j, h), lo = layer_index(k, h);
            w->ext[j * nn + k] =
                li == (size_t)-1 || lo == (size_t)-1 ? 0 : w->len[li * n + lo];
        }
}

/* The basis's CDF, as bsdf_write.c's compute_cdf for one basis. */
static ll_status basis_cdf(ll_bsdf_writer *w)
{
    write_job *job = &w->job;
    size_t nn = job->nn, i, o;
    for (i = 0; i < nn; ++i) {
        size_t li = layer_index(i, job->h);
        for (o = 0; o < nn; ++o) {
            size_t lo = layer_index(o, job->h);
            /* A pair of final length 0 has a_0 = 0 here too (its M_0 is 0
             * in every layer): the value bsdf_write.c reads as 0. */
            w->values[o] = li == (size_t)-1 || lo == (size_t)-1
                               ? 0.0
                               : (double)(float)ll_wjob_stored_coeff(job, 0, 0, o, i, 0);
        }
        ll_wjob_integrate_row(job->nodes, w->values, nn, w->row_cdf + i * nn, 1);
    }
    return ll_spill_put(&w->spill, w->row_cdf, nn * nn * sizeof *w->row_cdf, w->fn_add);
}

/* The basis's stored floats, pair after pair, up to each pair's extent. */
static ll_status basis_values(ll_bsdf_writer *w, const ll_layer *const *layers)
{
    write_job *job = &w->job;
    size_t nn = job->nn, m = job->m, per_layer = job->n * job->m, i, o, c, k, L;
    ll_status s = ll_spill_put(&w->spill, w->ext, nn * nn * sizeof *w->ext, w->fn_add);
    for (i = 0; i < nn && s == LL_OK; ++i) {
        size_t li = layer_index(i, job->h), kmax = 0;
        double factor[2];
        if (li == (size_t)-1)
            continue;
        if (ll_watch_poll(job->watch))
            return write_cancelled(job);
        for (o = 0; o < nn; ++o)
            if (w->ext[i * nn + o] > kmax)
                kmax = w->ext[i * nn + o];
        for (L = 0; L < job->n_channels; ++L)
            ll_wjob_stage_column(layers[L], li, kmax, w->stage + L * per_layer, 0);
        factor[0] = ll_layer_surface_factor(layers[0], li, 0);
        factor[1] = ll_layer_surface_factor(layers[0], li, 1);
        for (o = 0; o < nn && s == LL_OK; ++o) {
            size_t e = w->ext[i * nn + o], lo = layer_index(o, job->h);
            double mu_o;
            if (e == 0)
                continue;
            mu_o = fabs(layers[0]->nodes[lo]);
            /* The pair's floats, channel-major, then one copy to the spill
             * (a private file of this process: the floats as in memory). */
            for (c = 0; c < job->n_channels; ++c)
                for (k = 0; k < e; ++k)
                    w->row[c * e + k] = (float)ll_wjob_staged_value(
                        job->n_channels, c, w->stage + lo * m, per_layer, k, mu_o,
                        factor[k > 0]);
            s = ll_spill_put(&w->spill, w->row, job->n_channels * e * sizeof *w->row, w->fn_add);
        }
        for (L = 0; L < job->n_channels; ++L)
            ll_wjob_stage_column(layers[L], li, kmax, w->stage + L * per_layer, 1);
    }
    return s;
}

ll_status ll_writer_add_watched(ll_bsdf_writer *w, const ll_layer *const *layers,
                                ll_watch *watch)
{
    write_job *job = &w->job;
    size_t c, i, o;
    ll_status s = LL_OK;
    job->fn = w->fn_add;
    if (w->failed)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: an earlier call failed; only ll_bsdf_writer_abort is left", w->fn_add);
    if (w->added == job->n_bases) {
        s = ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: all %zu bases are added already", w->fn_add,
                    job->n_bases);
        goto fail;
    }
    if (!layers) {
        s = ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: layers is NULL", w->fn_add);
        goto fail;
    }
    for (c = 0; c < job->n_channels; ++c)
        if (!layers[c]) {
            s = ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: layers[%zu] of basis %zu is NULL",
                        w->fn_add, c, w->added);
            goto fail;
        }
    if (!w->first && (s = take_shape(w, layers[0])) != LL_OK)
        goto fail;
    for (c = 0; c < job->n_channels; ++c)
        if ((s = ll_layer_check_compatible(w->first, layers[c], w->fn_add)) != LL_OK)
            goto fail;
    /* The lengths: each layer's, joined into the running maxima. */
    for (c = 0; c < job->n_channels; ++c) {
        if ((s = ll_wjob_layer_lengths(job, layers[c], w->len, w->tail, w->ref0)) != LL_OK)
            goto fail;
        for (i = 0; i < job->nn; ++i)
            for (o = 0; o < job->nn; ++o) {
                size_t li = layer_index(i, job->h), lo = layer_index(o, job->h);
                uint32_t *dst = &job->length[i * job->nn + o];
                if (li != (size_t)-1 && lo != (size_t)-1 && w->len[li * job->n + lo] > *dst)
                    *dst = w->len[li * job->n + lo];
            }
    }
    job->layers = layers;
    job->watch = watch;
    w->basis_at[w->added] = ll_spill_tell(&w->spill);
    basis_extents(w, layers);
    if ((s = basis_cdf(w)) != LL_OK || (s = basis_values(w, layers)) != LL_OK)
        goto fail;
    job->layers = NULL;
    job->watch = NULL;
    w->added++;
    return LL_OK;
fail:
    job->layers = NULL;
    job->watch = NULL;
    w->failed = 1;
    return s;
}

ll_status ll_bsdf_writer_add_basis(ll_bsdf_writer *w, const ll_layer *const *layers)
{
    if (!w)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: writer is NULL", api_add);
    return ll_writer_add_watched(w, layers, NULL);
}

/* ---------------------------------------------------------------- commit */

/* The commit's scratch (ll_wjob_source.prepare): the chunk of
 * LL_WRITER_CHUNK floats, or one row of every basis's longest series if
 * that is more (12 m bytes a basis), one series as file bytes, and per
 * basis one column's extents, its spill cursor and its place in the
 * chunk. */
static ll_status prepare_commit(void *writer)
{
    ll_bsdf_writer *w = writer;
    const write_job *job = &w->job;
    size_t nn = job->nn, nb = job->n_bases, b;
    if (!ll_size_mul(nb * job->n_channels, job->m, &w->chunk_floats))
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", w->fn_commit);
    if (w->chunk_floats < LL_WRITER_CHUNK)
        w->chunk_floats = LL_WRITER_CHUNK;
    w->chunk = ll_alloc_array(w->chunk_floats, sizeof *w->chunk);
    w->bytes = ll_alloc_array(job->m, 4);
    w->col_ext = ll_alloc_array(nb * nn, sizeof *w->col_ext);
    w->cursor = ll_alloc_array(nb, sizeof *w->cursor);
    w->pos = ll_alloc_array(nb, sizeof *w->pos);
    if (!w->chunk || !w->bytes || !w->col_ext || !w->cursor || !w->pos)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", w->fn_commit);
    /* A basis's pairs follow its CDF and extents in the spill. */
    for (b = 0; b < nb; ++b)
        w->cursor[b] = w->basis_at[b] + nn * nn * (sizeof(float) + sizeof(uint32_t));
    return LL_OK;
}

/* The CDF table, [(i * nn + o) * n_bases + b], from each basis's block. */
static ll_status put_cdf(void *writer, ll_bsdf_out *out)
{
    ll_bsdf_writer *w = writer;
    const write_job *job = &w->job;
    size_t nb = job->n_bases, pairs = job->nn * job->nn, per = w->chunk_floats / nb, at, b, k;
    float *chunk = w->chunk;
    ll_status s = LL_OK;
    if (per == 0)
        per = 1;
    ll_wjob_stage(job, 0.05, 0.05, (pairs + per - 1) / per);
    for (at = 0; at < pairs && s == LL_OK; at += per) {
        size_t count = pairs - at < per ? pairs - at : per;
        if (ll_watch_poll(job->watch))
            return write_cancelled(job);
        for (b = 0; b < nb && s == LL_OK; ++b)
            s = ll_spill_read(&w->spill, w->basis_at[b] + at * sizeof(float),
                              chunk + b * count, count * sizeof(float), w->fn_commit);
        for (k = 0; k < count && s == LL_OK; ++k)
            for (b = 0; b < nb; ++b)
                ll_bsdf_out_f32(out, chunk[b * count + k]);
        ll_watch_advance(job->watch, 1);
    }
    return s;
}

/* One series of L coefficients, the first e of them (e <= L or not) from
 * values, the rest 0: checked, then as little-endian bytes in one call. */
static ll_status put_series(const ll_bsdf_writer *w, ll_bsdf_out *out, const float *values,
                            size_t e, size_t L, size_t o, size_t i)
{
    size_t k;
    for (k = 0; k < L; ++k) {
        float v = k < e ? values[k] : 0.0f;
        if (!(fabsf(v) <= FLT_MAX))
            return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                           "%s: coefficient %zu of node pair (%zu, %zu) is %g, beyond float "
                           "range",
                           w->fn_commit, k, o, i, (double)v);
        ll_le_put_f32(w->bytes + 4 * k, v);
    }
    ll_bsdf_out_bytes(out, w->bytes, 4 * L);
    return LL_OK;
}

/* Column i of the coefficient block (ll_wjob_source.put_column): every
 * basis's extents of the column (w->col_ext, [n_bases * nn]), then rows
 * [o0, o1) at a time, as many as fit in the chunk of w->chunk_floats (one
 * row always does); w->cursor[b] is where basis b's data of the next row
 * starts in the spill, w->pos[b] where it stands in the chunk. */
static ll_status put_column(void *writer, ll_bsdf_out *out, size_t i)
{
    ll_bsdf_writer *w = writer;
    const write_job *job = &w->job;
    size_t nn = job->nn, nb = job->n_bases, nch = job->n_channels, o0 = 0, o1, b, o, c;
    const uint32_t *ext = w->col_ext;
    float *chunk = w->chunk;
    ll_status s = LL_OK;
    for (b = 0; b < nb && s == LL_OK; ++b)
        s = ll_spill_read(&w->spill,
                          w->basis_at[b] + nn * nn * sizeof(float) + i * nn * sizeof(uint32_t),
                          w->col_ext + b * nn, nn * sizeof(uint32_t), w->fn_commit);
    while (o0 < nn && s == LL_OK) {
        size_t used = 0, at = 0;
        for (o1 = o0; o1 < nn; ++o1) {
            size_t row = 0;
            for (b = 0; b < nb; ++b)
                row += ext[b * nn + o1] * nch;
            if (o1 > o0 && used + row > w->chunk_floats)
                break;
            used += row;
        }
        for (b = 0; b < nb && s == LL_OK; ++b) {
            size_t floats = 0;
            for (o = o0; o < o1; ++o)
                floats += ext[b * nn + o] * nch;
            w->pos[b] = at;
            s = ll_spill_read(&w->spill, w->cursor[b], chunk + at, floats * sizeof(float),
                              w->fn_commit);
            w->cursor[b] += floats * sizeof(float);
            at += floats;
        }
        for (o = o0; o < o1 && s == LL_OK; ++o) {
            size_t L = job->length[i * nn + o];
            for (c = 0; c < nch && L > 0 && s == LL_OK; ++c)
                for (b = 0; b < nb && s == LL_OK; ++b) {
                    size_t e = ext[b * nn + o];
                    s = put_series(w, out, chunk + w->pos[b] + c * e, e, L, o, i);
                }
            for (b = 0; b < nb; ++b)
                w->pos[b] += ext[b * nn + o] * nch;
        }
        o0 = o1;
    }
    return s;
}

ll_status ll_writer_commit_watched(ll_bsdf_writer *w, ll_watch *watch, double progress_from)
{
    write_job *job = &w->job;
    ll_wjob_source src = { w, prepare_commit, put_cdf, put_column };

    job->fn = w->fn_commit;
    job->watch = watch;
    job->progress_from = progress_from;
    if (w->failed)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: an earlier call failed; only ll_bsdf_writer_abort is left",
                       w->fn_commit);
    if (w->added != job->n_bases)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: %zu of the %zu bases were added",
                       w->fn_commit, w->added, job->n_bases);
    return ll_wjob_commit(job, &w->spill, w->path, &src);
}

ll_status ll_bsdf_writer_commit(ll_bsdf_writer *w, const ll_monitor *monitor)
{
    ll_watch watch;
    ll_status s;
    if (!w)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: writer is NULL", api_commit);
    w->job.fn = w->fn_commit;
    s = ll_watch_begin(&watch, monitor, w->fn_commit);
    if (s == LL_OK)
        s = ll_writer_commit_watched(w, &watch, 0.0);
    writer_free(w);
    return s;
}

void ll_bsdf_writer_abort(ll_bsdf_writer *w)
{
    if (w)
        writer_free(w);
}
