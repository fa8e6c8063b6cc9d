/*
 * The one streaming writer of .bsdf files (ll_bsdf_writer_*, ll_bsdf_write.h;
 * also behind ll_bsdf_write, ll_bsdf_write_textured and the material
 * builder's channel by channel write, bsdf_write_channels.c). Its unit is
 * one layer: channel c of basis b, handed over as soon as it exists and
 * kept by the writer only as what the file needs of it.
 *
 * Why a spill. The file's coefficient block interleaves the units (pair
 * after pair, [channel][basis][k]), every pair's series as long as the
 * longest over channels and bases (bsdf_write.c's rule), and Y mixes R, G
 * and B in double precision before rounding; the final lengths are known
 * only when the last unit has been seen. So each unit goes, as it arrives,
 * to a spill (bsdf_write_spill.h: an unlinked file beside the output, or
 * memory for the calls that hold every layer anyway), and commit writes
 * the file from it:
 *
 *  - add: the unit's series lengths join the running maxima (length[],
 *    nn * nn); to the spill go its extents E (one past the last order the
 *    layer stores at a pair: beyond it every value is 0, and no final
 *    length exceeds the largest E), nn * nn u32, then its stored doubles,
 *    pair after pair in table order, E a pair. Its order-0 matrix stays in
 *    memory until its basis is complete; then the basis's CDF (which
 *    depends on its own a_0 only: a pair whose final length is 0 has
 *    M_0 = 0 in every layer) goes to the spill as nn * nn floats. A
 *    basis's channels come in any order, the bases in order 0, 1, ...
 *  - commit: offsets from the final lengths, then the file in order
 *    (commit_file below), the units read back in chunks
 *    of LL_WRITER_CHUNK doubles, or of one row of every unit's longest
 *    series if that is more (per column of pairs: every unit's E of that
 *    column, then the rows that fit), each value by the expression of
 *    ll_wjob_staged_value on the same doubles, so that the bytes do not
 *    depend on how the layers were handed over.
 *
 * Memory: the tables of nn * nn entries, one basis's order-0 matrices and
 * one layer's staging while it is added, the chunk, and per unit its spill
 * offset, one column's extents and room in the chunk for one row of its
 * longest series: never a layer. The output itself is the atomic writer's
 * (bsdf_file_out.c).
 */
#include "writer/bsdf_write_job.h"
#include "layer/layer.h"
#include "layerlab/ll_bsdf_write.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Doubles read back at once at commit (512 KiB: big enough that the reads
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
    const char *fn_open, *fn_add, *fn_commit; /* the public call, in messages */
    int failed;                  /* an add failed: only abort is left      */
    size_t basis;                /* the basis being added                  */
    int added[3];                /* its channels added so far              */
    ll_spill spill;              /* bsdf_write_spill.h                     */
    unsigned long long *unit_at; /* [n_bases * n_channels] each unit's spill */
    unsigned long long *cdf_at;  /* [n_bases] each basis's CDF in the spill */
    /* the first layer's shape: every layer's */
    double *nodes, *weights;     /* [n]                                    */
    double *factor;              /* [2 n] surface factor, order 0 | k > 0  */
    /* add's scratch, n * n unless said */
    double *order0[3];           /* the basis's channels' M_0, col * n + row */
    uint32_t *len;
    double *tail;
    uint32_t *ext;               /* nn * nn: the unit's extents            */
    double *stage;               /* n * m: one column's orders             */
    double *values;              /* nn: one CDF row                        */
    float *row_cdf;              /* nn * nn                                */
    /* commit's */
    size_t chunk_doubles;
    double *chunk;               /* [chunk_doubles]                        */
    uint32_t *col_ext;           /* [units * nn] one column's extents      */
    unsigned long long *cursor;  /* [units] next row in the spill          */
    size_t *pos;                 /* [units] its place in the chunk         */
    double *row;                 /* [n_channels * m] one pair of a basis   */
};

/* --------------------------------------------------------------- open */

static void writer_free(ll_bsdf_writer *w)
{
    size_t c;
    ll_spill_close(&w->spill);
    for (c = 0; c < 3; ++c)
        ll_free(w->order0[c]);
    ll_free(w->path);
    ll_free(w->counts);
    ll_free(w->positions);
    ll_free(w->metadata_copy);
    ll_free(w->unit_at);
    ll_free(w->cdf_at);
    ll_free(w->nodes);
    ll_free(w->weights);
    ll_free(w->factor);
    ll_free(w->len);
    ll_free(w->tail);
    ll_free(w->ext);
    ll_free(w->stage);
    ll_free(w->values);
    ll_free(w->row_cdf);
    ll_free(w->chunk);
    ll_free(w->col_ext);
    ll_free(w->cursor);
    ll_free(w->pos);
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
    size_t len, units;
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
    if (!ll_size_mul(w->job.n_bases, n_channels, &units)) {
        s = ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: too many layers", w->fn_open);
        goto fail;
    }
    w->unit_at = ll_calloc_array(units, sizeof *w->unit_at);
    w->cdf_at = ll_calloc_array(w->job.n_bases, sizeof *w->cdf_at);
    if (!w->unit_at || !w->cdf_at) {
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

/* ----------------------------------------------------------------- add */

/* The file's shape from the first layer: what every layer must share. */
static ll_status take_shape(ll_bsdf_writer *w, const ll_layer *l)
{
    write_job *job = &w->job;
    size_t n = l->n, nn = n + 2, n2, nn2, nm, k, c;
    ll_status s = ll_wjob_take_shape(job, l);
    if (s != LL_OK)
        return s;
    if (!ll_size_mul(n, n, &n2) || !ll_size_mul(nn, nn, &nn2) || !ll_size_mul(n, l->m, &nm))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: the layers are too large", w->fn_add);
    w->nodes = ll_alloc_array(n, sizeof *w->nodes);
    w->weights = ll_alloc_array(n, sizeof *w->weights);
    w->factor = ll_alloc_array(n, 2 * sizeof *w->factor);
    w->len = ll_alloc_array(n2, sizeof *w->len);
    w->tail = ll_alloc_array(n2, sizeof *w->tail);
    w->ext = ll_alloc_array(nn2, sizeof *w->ext);
    w->stage = ll_calloc_array(nm, sizeof *w->stage);
    w->values = ll_alloc_array(nn, sizeof *w->values);
    w->row_cdf = ll_alloc_array(nn2, sizeof *w->row_cdf);
    if (!w->nodes || !w->weights || !w->factor || !w->len || !w->tail || !w->ext ||
        !w->stage || !w->values || !w->row_cdf)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", w->fn_add);
    for (c = 0; c < job->n_channels; ++c)
        if (!(w->order0[c] = ll_alloc_array(n2, sizeof *w->order0[c])))
            return ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", w->fn_add);
    memcpy(w->nodes, l->nodes, n * sizeof *w->nodes);
    memcpy(w->weights, l->weights, n * sizeof *w->weights);
    for (k = 0; k < n; ++k) {
        w->factor[k] = ll_layer_surface_factor(l, k, 0);
        w->factor[n + k] = ll_layer_surface_factor(l, k, 1);
    }
    return LL_OK;
}

/* What ll_layer_check_compatible checks, against the first layer's. */
static ll_status check_shape(const ll_bsdf_writer *w, const ll_layer *l)
{
    const write_job *job = &w->job;
    if (l->n != job->n || l->m != job->m)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: the layers do not match (%zu nodes x %zu orders vs %zu x %zu)",
                       w->fn_add, job->n, job->m, l->n, l->m);
    if (memcmp(l->nodes, w->nodes, job->n * sizeof *w->nodes) != 0 ||
        memcmp(l->weights, w->weights, job->n * sizeof *w->weights) != 0)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: the layers use different nodes or weights", w->fn_add);
    return LL_OK;
}

/* The layer's series lengths joined into the running maxima; its order 0
 * kept (for its basis's CDF). */
static ll_status join_lengths(ll_bsdf_writer *w, size_t channel, const ll_layer *l)
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

/* Extent of every file pair of the layer into w->ext (i * nn + o): one
 * past the last order it stores there. */
static void layer_extents(ll_bsdf_writer *w, const ll_layer *l)
{
    const write_job *job = &w->job;
    size_t n = job->n, h = job->h, nn = job->nn, k, col, j;
    int half;
    memset(w->len, 0, n * n * sizeof *w->len); /* (reused: col * n + row) */
    for (k = 0; k < job->m; ++k) {
        const ll_order *o = l->orders[k];
        if (!o)
            continue;
        for (col = 0; col < n; ++col)
            for (half = 0; half < 2; ++half) {
                const ll_segment *sg = &o->seg[2 * col + (size_t)half];
                for (j = 0; j < sg->len; ++j)
                    w->len[col * n + (size_t)half * h + sg->lo + j] = (uint32_t)(k + 1);
            }
    }
    for (j = 0; j < nn; ++j)
        for (k = 0; k < nn; ++k) {
            size_t li = layer_index(j, h), lo = layer_index(k, h);
            w->ext[j * nn + k] = li == (size_t)-1 || lo == (size_t)-1 ? 0 : w->len[li * n + lo];
        }
}

/* The unit to the spill: its extents, then its doubles pair after pair up
 * to each pair's extent; polled per column. */
static ll_status spill_layer(ll_bsdf_writer *w, const ll_layer *l)
{
    write_job *job = &w->job;
    size_t nn = job->nn, m = job->m, i, o;
    ll_status s = ll_spill_put(&w->spill, w->ext, nn * nn * sizeof *w->ext, w->fn_add);
    for (i = 0; i < nn && s == LL_OK; ++i) {
        size_t li = layer_index(i, job->h), kmax = 0;
        if (li == (size_t)-1)
            continue;
        if (ll_watch_poll(job->watch))
            return write_cancelled(job);
        for (o = 0; o < nn; ++o)
            if (w->ext[i * nn + o] > kmax)
                kmax = w->ext[i * nn + o];
        ll_wjob_stage_column(l, li, kmax, w->stage, 0);
        for (o = 0; o < nn && s == LL_OK; ++o) {
            size_t e = w->ext[i * nn + o];
            if (e > 0)
                s = ll_spill_put(&w->spill, w->stage + layer_index(o, job->h) * m,
                                 e * sizeof *w->stage, w->fn_add);
        }
        ll_wjob_stage_column(l, li, kmax, w->stage, 1);
    }
    return s;
}

/* The complete basis's CDF, from its channels' order-0 matrices, to the
 * spill (as bsdf_write.c's rule: the stored float of a_0 of channel 0). */
static ll_status spill_cdf(ll_bsdf_writer *w, size_t basis)
{
    const write_job *job = &w->job;
    size_t nn = job->nn, n = job->n, i, o, c;
    for (i = 0; i < nn; ++i) {
        size_t li = layer_index(i, job->h);
        for (o = 0; o < nn; ++o) {
            size_t lo = layer_index(o, job->h);
            double v[3];
            w->values[o] = 0.0;
            if (li == (size_t)-1 || lo == (size_t)-1)
                continue;
            for (c = 0; c < job->n_channels; ++c)
                v[c] = w->order0[c][li * n + lo];
            w->values[o] = (double)(float)ll_wjob_staged_value(
                job->n_channels, 0, v, 1, 0, fabs(w->nodes[lo]), w->factor[li]);
        }
        ll_wjob_integrate_row(job->nodes, w->values, nn, w->row_cdf + i * nn, 1);
    }
    w->cdf_at[basis] = ll_spill_tell(&w->spill);
    return ll_spill_put(&w->spill, w->row_cdf, nn * nn * sizeof *w->row_cdf, w->fn_add);
}

ll_status ll_writer_add_unit(ll_bsdf_writer *w, size_t basis, size_t channel,
                             const ll_layer *layer, ll_watch *watch)
{
    write_job *job = &w->job;
    size_t c, done = 0;
    ll_status s;
    job->fn = w->fn_add;
    if (w->failed)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: an earlier call failed; only abort is left",
                       w->fn_add);
    job->watch = watch;
    if (basis != w->basis || basis >= job->n_bases) {
        s = ll_fail(LL_ERROR_INVALID_ARGUMENT,
                    w->basis == job->n_bases ? "%s: all %zu bases are added already"
                                             : "%s: basis %zu is not the next one",
                    w->fn_add, w->basis == job->n_bases ? job->n_bases : basis);
        goto fail;
    }
    if (!layer || channel >= job->n_channels || w->added[channel]) {
        s = ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: channel %zu of %zu of basis %zu is %s",
                    w->fn_add, channel, job->n_channels, basis,
                    !layer ? "NULL" : channel >= job->n_channels ? "not one" : "added already");
        goto fail;
    }
    if (!w->nodes && (s = take_shape(w, layer)) != LL_OK)
        goto fail;
    if ((s = check_shape(w, layer)) != LL_OK || (s = join_lengths(w, channel, layer)) != LL_OK)
        goto fail;
    w->unit_at[basis * job->n_channels + channel] = ll_spill_tell(&w->spill);
    layer_extents(w, layer);
    if ((s = spill_layer(w, layer)) != LL_OK)
        goto fail;
    w->added[channel] = 1;
    for (c = 0; c < job->n_channels; ++c)
        done += (size_t)w->added[c];
    if (done == job->n_channels) {
        if ((s = spill_cdf(w, basis)) != LL_OK)
            goto fail;
        memset(w->added, 0, sizeof w->added);
        w->basis++;
    }
    job->watch = NULL;
    return LL_OK;
fail:
    job->watch = NULL;
    w->failed = 1;
    return s;
}

void ll_writer_fail(ll_bsdf_writer *w)
{
    w->failed = 1;
}

ll_status ll_bsdf_writer_add_basis(ll_bsdf_writer *w, const ll_layer *const *layers)
{
    size_t c;
    ll_status s = LL_OK;
    if (!w)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: writer is NULL", api_add);
    if (!w->failed && w->basis < w->job.n_bases && !layers) {
        w->failed = 1;
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: layers is NULL", w->fn_add);
    }
    /* Every layer is checked before any goes in (as the whole call fails). */
    for (c = 0; layers && !w->failed && w->basis < w->job.n_bases && c < w->job.n_channels; ++c)
        if (!layers[c]) {
            w->failed = 1;
            return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: layers[%zu] of basis %zu is NULL",
                           w->fn_add, c, w->basis);
        }
    for (c = 0; c < w->job.n_channels && s == LL_OK; ++c)
        s = ll_writer_add_unit(w, w->basis, c, layers ? layers[c] : NULL, NULL);
    return s;
}

/* -------------------------------------------------------------- commit */

/* The commit's scratch: the add's staging freed,
 * the chunk of LL_WRITER_CHUNK doubles, or one row of every unit's longest
 * series if that is more, one pair of a basis, and per unit one column's
 * extents, its spill cursor and its place in the chunk. */
static ll_status prepare_commit(ll_bsdf_writer *w)
{
    const write_job *job = &w->job;
    size_t nn = job->nn, units = job->n_bases * job->n_channels, u;
    ll_free(w->stage);
    w->stage = NULL;
    if (!ll_size_mul(units, job->m, &w->chunk_doubles))
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", w->fn_commit);
    if (w->chunk_doubles < LL_WRITER_CHUNK)
        w->chunk_doubles = LL_WRITER_CHUNK;
    w->chunk = ll_alloc_array(w->chunk_doubles, sizeof *w->chunk);
    w->col_ext = ll_alloc_array(units, nn * sizeof *w->col_ext);
    w->cursor = ll_alloc_array(units, sizeof *w->cursor);
    w->pos = ll_alloc_array(units, sizeof *w->pos);
    w->row = ll_alloc_array(job->n_channels * job->m, sizeof *w->row);
    if (!w->chunk || !w->col_ext || !w->cursor || !w->pos || !w->row)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", w->fn_commit);
    /* A unit's pairs follow its extents in the spill. */
    for (u = 0; u < units; ++u)
        w->cursor[u] = w->unit_at[u] + nn * nn * sizeof(uint32_t);
    return LL_OK;
}

/* The CDF table, [(i * nn + o) * n_bases + b], from each basis's block. */
static ll_status put_cdf(ll_bsdf_writer *w, ll_bsdf_out *out)
{
    const write_job *job = &w->job;
    size_t nb = job->n_bases, pairs = job->nn * job->nn, at, b, k;
    size_t per = w->chunk_doubles * 2 / nb; /* floats in the chunk's room, a basis */
    float *chunk = (float *)(void *)w->chunk;
    ll_status s = LL_OK;
    if (per == 0)
        per = 1;
    ll_wjob_stage(job, 0.05, 0.05, (pairs + per - 1) / per);
    for (at = 0; at < pairs && s == LL_OK; at += per) {
        size_t count = pairs - at < per ? pairs - at : per;
        if (ll_watch_poll(job->watch))
            return write_cancelled(job);
        for (b = 0; b < nb && s == LL_OK; ++b)
            s = ll_spill_read(&w->spill, w->cdf_at[b] + at * sizeof(float), chunk + b * count,
                              count * sizeof(float), w->fn_commit);
        for (k = 0; k < count && s == LL_OK; ++k)
            for (b = 0; b < nb; ++b)
                ll_bsdf_out_f32(out, chunk[b * count + k]);
        ll_watch_advance(job->watch, 1);
    }
    return s;
}

/* The pair (o, i) of one basis: its channels' doubles gathered into
 * w->row[c * m + k], 0 beyond each one's extent, then each file channel's
 * series of L values. */
static ll_status put_pair(ll_bsdf_writer *w, ll_bsdf_out *out, size_t b, size_t c, size_t o,
                          size_t i, size_t L)
{
    const write_job *job = &w->job;
    size_t nch = job->n_channels, m = job->m, n = job->n, nn = job->nn, cc, k;
    size_t li = layer_index(i, job->h), lo = layer_index(o, job->h);
    for (cc = 0; cc < nch; ++cc) {
        size_t u = b * nch + cc, e = w->col_ext[u * nn + o];
        for (k = 0; k < L; ++k)
            w->row[cc * m + k] = k < e ? w->chunk[w->pos[u] + k] : 0.0;
    }
    for (k = 0; k < L; ++k) {
        double v = ll_wjob_staged_value(nch, c, w->row, m, k, fabs(w->nodes[lo]),
                                        w->factor[(k > 0) * n + li]);
        if (!(fabs(v) <= FLT_MAX))
            return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                           "%s: coefficient %zu of node pair (%zu, %zu) is %g, beyond float "
                           "range",
                           w->fn_commit, k, o, i, v);
        ll_bsdf_out_f32(out, (float)v);
    }
    return LL_OK;
}

/* Column i of the coefficient block: every
 * unit's extents of the column (w->col_ext, [units * nn]), then rows
 * [o0, o1) at a time, as many as fit in the chunk (one row always does);
 * w->cursor[u] is where unit u's data of the next row starts in the spill,
 * w->pos[u] where it stands in the chunk. */
static ll_status put_column(ll_bsdf_writer *w, ll_bsdf_out *out, size_t i)
{
    const write_job *job = &w->job;
    size_t nn = job->nn, nb = job->n_bases, nch = job->n_channels, units = nb * nch;
    size_t o0 = 0, o1, u, o, b, c;
    const uint32_t *ext = w->col_ext;
    ll_status s = LL_OK;
    for (u = 0; u < units && s == LL_OK; ++u)
        s = ll_spill_read(&w->spill, w->unit_at[u] + i * nn * sizeof(uint32_t),
                          w->col_ext + u * nn, nn * sizeof(uint32_t), w->fn_commit);
    while (o0 < nn && s == LL_OK) {
        size_t used = 0, at = 0;
        for (o1 = o0; o1 < nn; ++o1) {
            size_t row = 0;
            for (u = 0; u < units; ++u)
                row += ext[u * nn + o1];
            if (o1 > o0 && used + row > w->chunk_doubles)
                break;
            used += row;
        }
        for (u = 0; u < units && s == LL_OK; ++u) {
            size_t doubles = 0;
            for (o = o0; o < o1; ++o)
                doubles += ext[u * nn + o];
            w->pos[u] = at;
            s = ll_spill_read(&w->spill, w->cursor[u], w->chunk + at, doubles * sizeof(double),
                              w->fn_commit);
            w->cursor[u] += doubles * sizeof(double);
            at += doubles;
        }
        for (o = o0; o < o1 && s == LL_OK; ++o) {
            size_t L = job->length[i * nn + o];
            if (L > 0 && ll_watch_poll(job->watch))
                return write_cancelled(job);
            for (c = 0; c < nch && L > 0 && s == LL_OK; ++c)
                for (b = 0; b < nb && s == LL_OK; ++b)
                    s = put_pair(w, out, b, c, o, i, L);
            for (u = 0; u < units; ++u)
                w->pos[u] += ext[u * nn + o];
        }
        o0 = o1;
    }
    return s;
}

/* The pair table (offset, length of each pair, nn * nn in table order),
 * one unit of the current stage per node row, polled there. */
static ll_status put_pairs(ll_bsdf_out *out, const write_job *job)
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

/* The end of the file once its coefficient block is written (s its
 * outcome so far): the last report, before the temporary file replaces
 * the target so that a cancel there still leaves no file, then the
 * metadata and the commit, or the abort on an error or cancel. */
static ll_status put_end(ll_bsdf_out *out, const write_job *job, ll_status s)
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


/* The file, once every unit is in: the spill flushed, offsets and the
 * default metadata (unless the options give one) from the final lengths,
 * the commit's scratch, all of which can fail for want of memory or of a
 * valid total before the output is begun; then the parts in the order
 * docs/formats.md stores them. Progress: the offsets in [0, 0.05] of
 * the commit's share of "writing" a node row a unit, the CDF in
 * [0.05, 0.1], the pair table in [0.1, 0.15] a node row a unit, the
 * coefficient block in [0.15, 1] a column a unit; the report of 1 comes
 * last (put_end). */
static ll_status commit_file(ll_bsdf_writer *w)
{
    write_job *job = &w->job;
    size_t nn = job->nn, i;
    ll_bsdf_out *out = NULL;
    ll_status s;
    if ((s = ll_spill_flush(&w->spill, job->fn)) != LL_OK ||
        (s = ll_wjob_compute_offsets(job)) != LL_OK || (s = prepare_commit(w)) != LL_OK)
        return s;
    if (!job->opts.metadata && (s = ll_wjob_default_metadata(job)) != LL_OK)
        return s;
    if ((s = ll_bsdf_out_begin(w->path, job->fn, &out)) != LL_OK)
        return s;
    ll_wjob_put_header(out, job, strlen(ll_wjob_metadata(job)));
    s = put_cdf(w, out);
    ll_wjob_stage(job, 0.1, 0.05, nn);
    if (s == LL_OK)
        s = put_pairs(out, job);
    if (s == LL_OK)
        ll_wjob_stage(job, 0.15, 0.85, nn);
    for (i = 0; i < nn && s == LL_OK; ++i) {
        ll_watch_advance(job->watch, 1);
        if (ll_watch_poll(job->watch))
            s = write_cancelled(job);
        else if (layer_index(i, job->h) != (size_t)-1) /* mu = 0 holds no coefficients */
            s = put_column(w, out, i);
    }
    return put_end(out, job, s);
}

ll_status ll_writer_commit_watched(ll_bsdf_writer *w, ll_watch *watch, double progress_from)
{
    write_job *job = &w->job;
    size_t c;

    job->fn = w->fn_commit;
    job->watch = watch;
    job->progress_from = progress_from;
    if (w->failed)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: an earlier call failed; only abort is left",
                       w->fn_commit);
    for (c = 0; c < job->n_channels && job->n_bases == 1; ++c)
        if (w->basis == 0 && !w->added[c])
            return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: channel %zu was not added",
                           w->fn_commit, c);
    if (w->basis != job->n_bases)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: %zu of the %zu bases were added",
                       w->fn_commit, w->basis, job->n_bases);
    return commit_file(w);
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
