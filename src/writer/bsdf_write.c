/*
 * Writing layers as a .bsdf file (docs/formats.md), what the
 * original layerlab's BSDFStorage::fromLayerGeneral stores:
 *
 *  - nodes: the layer's, ascending, with two explicit mu = 0 nodes in the
 *    middle, [-x_{h-1} .. -x_0, 0, 0, x_0 .. x_{h-1}], with the layer's
 *    signs (file node o < h is layer node h-1-o, o >= h+2 is layer node
 *    o-2): then pbrt-v3's muI = CosTheta(-wi) for light arriving from above
 *    is negative like a layer's upward-travelling outgoing direction, and
 *    top reflection reads the R^t block. The rows and columns of the zero
 *    nodes hold nothing; they pin the splines to 0 at grazing angles.
 *  - coefficients: a_k(o, i) = M_k(o, i) |mu_o| / (pi |mu_i| w_i), halved
 *    for k = 0, i.e. the layer's order-k entry with its column's surface
 *    weight factor (ll_layer_surface_factor) divided out and the outgoing
 *    cosine kept in, so that sum_k a_k cos(k phi) = f |mu_o|. Layers must
 *    hold surfaces or slabs (the adding-doubling results), not a bare phase
 *    function before ll_layer_expand, whose columns are weighted by w pi.
 *  - truncation: the series of a pair ends after the last order k at which
 *    the tail sum_{j >= k} |M_j| still exceeds error_goal * |M_0|, over all
 *    channels and bases (the original's rule, relative to the order-0 matrix
 *    entry, i.e. to 2 |a_0|); a pair with M_0 = 0 stores nothing. Unlike the
 *    original, an exact zero inside a series does not end it early.
 *  - colour: R, G, B layers are stored as Y, R, B.
 *  - CDF: per incident node and basis, the running integral over outgoing
 *    nodes of the stored a_0 of channel 0 (luminance), each Catmull-Rom
 *    segment integrated exactly over the file's (float) nodes, so the last
 *    entry is the albedo / 2 pi that the reader normalises with. A segment
 *    whose integral is negative (spline overshoot next to a zero) adds 0,
 *    keeping rows non-decreasing as readers require.
 *
 * This file holds those rules' pieces that every writer shares (options,
 * lengths, offsets, CDF rows, header, metadata) and ll_bsdf_write and
 * ll_bsdf_write_textured, which hand their layers to the writer
 * (bsdf_writer.c) with its spill in memory.
 */
#include "layerlab/ll_bsdf_write.h"
#include "writer/bsdf_file_out.h"
#include "writer/bsdf_write_job.h"
#include "reader/bsdf_format.h"
#include "support/parse_number.h"
#include "layer/layer.h"
#include "layer/order.h"
#include "support/watch.h"
#include "layerlab/ll_bsdf.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------ arguments */

ll_status ll_wjob_read_options(write_job *job, const ll_bsdf_write_options *opts)
{
    ll_bsdf_write_options defaults = LL_BSDF_WRITE_OPTIONS_INIT;
    job->opts = defaults;
    /* Read only what the caller's struct has; newer fields keep their
     * defaults. */
    if (opts) {
        ll_status s = ll_struct_read(&job->opts, sizeof job->opts, opts, job->fn,
                                     "ll_bsdf_write_options");
        if (s != LL_OK)
            return s;
    }
    if (!(job->opts.eta >= LL_BSDF_ETA_MIN && job->opts.eta <= LL_BSDF_ETA_MAX))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: eta = %g is not a relative index of refraction in [%g, %g]",
                       job->fn, job->opts.eta, LL_BSDF_ETA_MIN, LL_BSDF_ETA_MAX);
    if (!(job->opts.alpha[0] >= 0.0 && job->opts.alpha[0] <= FLT_MAX) ||
        !(job->opts.alpha[1] >= 0.0 && job->opts.alpha[1] <= FLT_MAX))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: alpha = (%g, %g) must be finite and non-negative", job->fn,
                       job->opts.alpha[0], job->opts.alpha[1]);
    if (!(job->opts.error_goal >= 0.0 && job->opts.error_goal <= DBL_MAX))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: error_goal = %g must be finite and non-negative", job->fn,
                       job->opts.error_goal);
    if (job->opts.metadata && strlen(job->opts.metadata) > UINT32_MAX)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: the metadata is longer than 4 GiB",
                       job->fn);
    return LL_OK;
}

ll_status ll_wjob_keep_options(write_job *job, const ll_bsdf_write_options *opts,
                               char **metadata_copy)
{
    size_t len;
    ll_status s = ll_wjob_read_options(job, opts);
    if (s != LL_OK || !job->opts.metadata)
        return s;
    len = strlen(job->opts.metadata);
    *metadata_copy = ll_malloc(len + 1);
    if (!*metadata_copy)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", job->fn);
    memcpy(*metadata_copy, job->opts.metadata, len + 1);
    job->opts.metadata = *metadata_copy;
    return LL_OK;
}

ll_status ll_wjob_take_shape(write_job *job, const ll_layer *l)
{
    size_t n = l->n, nn = n + 2, nn2, k;
    job->n = n;
    job->h = n / 2;
    job->m = l->m;
    job->nn = nn;
    /* (Offsets and lengths are u32; the file's pair table is nn^2.) */
    if (nn > UINT32_MAX / 2)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: %zu nodes are too many", job->fn, n);
    if (!ll_size_mul(nn, nn, &nn2))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: the layers are too large", job->fn);
    job->nodes = ll_alloc_array(nn, sizeof *job->nodes);
    job->length = ll_calloc_array(nn2, sizeof *job->length);
    job->offset = ll_alloc_array(nn2, sizeof *job->offset);
    if (!job->nodes || !job->length || !job->offset)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", job->fn);
    for (k = 0; k < nn; ++k) {
        size_t li = layer_index(k, job->h);
        job->nodes[k] = li == (size_t)-1 ? 0.0f : (float)l->nodes[li];
    }
    return LL_OK;
}

ll_status ll_wjob_check_parameters(write_job *job)
{
    size_t p, k, bases = 1, values = 0;
    if (job->n_parameters > 0 && (!job->param_counts || !job->param_positions))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: param_counts or param_positions is NULL", job->fn);
    for (p = 0; p < job->n_parameters; ++p) {
        size_t c = job->param_counts[p];
        if (c < 1 || !ll_size_mul(bases, c, &bases) || !ll_size_add(values, c, &values) ||
            bases > UINT32_MAX || values > UINT32_MAX)
            return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                           "%s: parameter %zu has %zu positions (need at least 1, and at most "
                           "2^32 - 1 bases and positions in all)",
                           job->fn, p, c);
        for (k = 0; k < c; ++k) {
            double x = job->param_positions[values - c + k];
            /* Strictly increasing after rounding to the stored float. */
            if (!ll_is_finite(x) || fabs(x) > FLT_MAX ||
                (k > 0 && !((float)x > (float)job->param_positions[values - c + k - 1])))
                return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                               "%s: parameter %zu: position %zu = %g is not finite and "
                               "increasing (as a float)",
                               job->fn, p, k, x);
        }
    }
    if (job->n_parameters > UINT32_MAX)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: %zu parameters are too many", job->fn,
                       job->n_parameters);
    job->n_bases = bases;
    job->n_parameter_values = values;
    return LL_OK;
}

/* ------------------------------------------------------- series lengths */

/* Truncated series lengths of one layer, indexed col * n + row (layer
 * indices), by the tail-sum rule of the file comment: scanning orders from
 * the top, a pair's length is fixed at the first order where its running
 * tail exceeds error_goal * |M_0|. Visits stored entries only. Also checks
 * that every stored value is finite. */
ll_status ll_wjob_layer_lengths(const write_job *job, const ll_layer *l, uint32_t *len,
                               double *tail, double *ref0)
{
    size_t n = job->n, h = job->h, col, j, k;
    int half;
    memset(len, 0, n * n * sizeof *len);
    memset(tail, 0, n * n * sizeof *tail);
    /* Order 0 densely (column-major, like `at` below): the reference of every
     * tail test, which looked up one by one cost a cache miss each. */
    ll_order_to_dense(l->orders[0], n, ref0);
    for (k = job->m; k-- > 0;) {
        const ll_order *o = l->orders[k];
        ll_watch_advance(job->watch, 1);
        if (!o)
            continue;
        for (col = 0; col < n; ++col) {
            if (ll_watch_poll(job->watch))
                return write_cancelled(job);
            for (half = 0; half < 2; ++half) {
                size_t seg = 2 * col + (size_t)half;
                for (j = 0; j < o->seg[seg].len; ++j) {
                    size_t row = (size_t)half * h + o->seg[seg].lo + j, at = col * n + row;
                    double v = o->val[o->seg[seg].off + j], ref;
                    if (!ll_is_finite(v))
                        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                                       "%s: the layer has a non-finite value (order %zu, "
                                       "row %zu, column %zu)",
                                       job->fn, k, row, col);
                    if (k == 0) {
                        if (len[at] == 0 && v != 0.0)
                            len[at] = 1;
                        continue;
                    }
                    if (len[at] != 0)
                        continue; /* already decided */
                    tail[at] += fabs(v);
                    ref = fabs(ref0[at]);
                    if (tail[at] > job->opts.error_goal * ref)
                        len[at] = (uint32_t)(k + 1);
                }
            }
        }
    }
    /* A pair whose tail never exceeded the goal keeps order 0 alone, and
     * one with M_0 = 0 nothing (the original's rule). */
    for (j = 0; j < n * n; ++j) {
        if (ref0[j] == 0.0)
            len[j] = 0;
        else if (len[j] == 0)
            len[j] = 1;
    }
    return LL_OK;
}

ll_status ll_wjob_compute_offsets(write_job *job)
{
    size_t k, total = 0, block = job->n_bases * job->n_channels;
    job->max_order = 0;
    ll_wjob_stage(job, 0.0, 0.05, job->nn);
    for (k = 0; k < job->nn * job->nn; ++k) {
        size_t size;
        if (k % job->nn == 0) {
            ll_watch_advance(job->watch, 1);
            if (ll_watch_poll(job->watch))
                return write_cancelled(job);
        }
        job->offset[k] = (uint32_t)total;
        if (job->length[k] > job->max_order)
            job->max_order = job->length[k];
        if (!ll_size_mul(job->length[k], block, &size) || !ll_size_add(total, size, &total) ||
            total > UINT32_MAX)
            return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                           "%s: more than 2^32 - 1 coefficients (raise error_goal or "
                           "lower the resolution)",
                           job->fn);
    }
    job->n_coeffs = total;
    return LL_OK;
}

/* ------------------------------------------------------------------ CDF */

void ll_wjob_integrate_row(const float *nodes, const double *values, size_t n, float *cdf,
                          size_t stride)
{
    double sum = 0.0;
    size_t k;
    cdf[0] = 0.0f;
    for (k = 0; k + 1 < n; ++k) {
        double x0 = nodes[k], x1 = nodes[k + 1], f0 = values[k], f1 = values[k + 1];
        double width = x1 - x0, d0, d1, segment;
        /* Catmull-Rom derivatives (times the width) by finite differences,
         * one-sided at the ends, as the readers interpolate. */
        d0 = k > 0 ? width * (f1 - values[k - 1]) / (x1 - nodes[k - 1]) : f1 - f0;
        d1 = k + 2 < n ? width * (values[k + 2] - f0) / (nodes[k + 2] - x0) : f1 - f0;
        /* Exact integral of the cubic Hermite segment. */
        segment = ((d0 - d1) * (1.0 / 12.0) + (f0 + f1) * 0.5) * width;
        if (segment > 0.0)
            sum += segment;
        cdf[(k + 1) * stride] = (float)sum;
    }
}

/* ------------------------------------------------------------- metadata */

ll_status ll_wjob_default_metadata(write_job *job)
{
    char text[1024];
    int len = ll_format_c(
        text, sizeof text,
        "{\n"
        "    \"generator\": \"layerlab %s\",\n"
        "    \"nodes\": %zu,\n"
        "    \"layer_nodes\": %zu,\n"
        "    \"orders\": %zu,\n"
        "    \"max_order\": %zu,\n"
        "    \"channels\": %s,\n"
        "    \"bases\": %zu,\n"
        "    \"parameters\": %zu,\n"
        "    \"eta\": %.9g,\n"
        "    \"alpha\": [%.9g, %.9g],\n"
        "    \"error_goal\": %.9g\n"
        "}\n",
        ll_version_string(), job->nn, job->n, job->m, job->max_order,
        job->n_channels == 1 ? "[\"Y\"]" : "[\"Y\", \"R\", \"B\"]", job->n_bases,
        job->n_parameters, job->opts.eta, job->opts.alpha[0], job->opts.alpha[1],
        job->opts.error_goal);
    if (len < 0 || (size_t)len >= sizeof text)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: the metadata does not fit", job->fn);
    job->metadata = ll_malloc((size_t)len + 1);
    if (!job->metadata)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", job->fn);
    memcpy(job->metadata, text, (size_t)len + 1);
    return LL_OK;
}

/* ------------------------------------------------------------ the bytes */

void ll_wjob_put_header(ll_bsdf_out *out, const write_job *job, size_t metadata_size)
{
    unsigned char h[LL_BSDF_HEADER_SIZE];
    size_t k;
    memset(h, 0, sizeof h);
    memcpy(h, LL_BSDF_MAGIC, LL_BSDF_MAGIC_SIZE);
    h[LL_BSDF_AT_VERSION] = LL_BSDF_VERSION;
    ll_le_put_u32(h + LL_BSDF_AT_FLAGS, LL_BSDF_FLAG_BSDF);
    ll_le_put_u32(h + LL_BSDF_AT_NODES, (uint32_t)job->nn);
    ll_le_put_u32(h + LL_BSDF_AT_COEFFS, (uint32_t)job->n_coeffs);
    ll_le_put_u32(h + LL_BSDF_AT_MAX_ORDER, (uint32_t)job->max_order);
    ll_le_put_u32(h + LL_BSDF_AT_CHANNELS, (uint32_t)job->n_channels);
    ll_le_put_u32(h + LL_BSDF_AT_BASES, (uint32_t)job->n_bases);
    ll_le_put_u32(h + LL_BSDF_AT_METADATA_BYTES, (uint32_t)metadata_size);
    ll_le_put_u32(h + LL_BSDF_AT_PARAMETERS, (uint32_t)job->n_parameters);
    ll_le_put_u32(h + LL_BSDF_AT_PARAMETER_VALUES, (uint32_t)job->n_parameter_values);
    ll_le_put_f32(h + LL_BSDF_AT_ETA, (float)job->opts.eta);
    ll_le_put_f32(h + LL_BSDF_AT_ALPHA, (float)job->opts.alpha[0]);
    ll_le_put_f32(h + LL_BSDF_AT_ALPHA + 4, (float)job->opts.alpha[1]);
    ll_bsdf_out_bytes(out, h, sizeof h);
    for (k = 0; k < job->nn; ++k)
        ll_bsdf_out_f32(out, job->nodes[k]);
    for (k = 0; k < job->n_parameters; ++k)
        ll_bsdf_out_u32(out, (uint32_t)job->param_counts[k]);
    for (k = 0; k < job->n_parameter_values; ++k)
        ll_bsdf_out_f32(out, (float)job->param_positions[k]);
}

/* Copy (or clear) column col of a layer's orders k < kmax into
 * stage[row * m + k]: each order's two runs of that column are read once,
 * where looking every coefficient up separately cost a cache miss each. */
void ll_wjob_stage_column(const ll_layer *l, size_t col, size_t kmax, double *stage, int clear)
{
    size_t h = l->n / 2, m = l->m, k, j;
    int half;
    for (k = 0; k < kmax; ++k) {
        const ll_order *o = l->orders[k];
        if (!o)
            continue;
        for (half = 0; half < 2; ++half) {
            const ll_segment *sg = &o->seg[2 * col + (size_t)half];
            double *dst = stage + ((size_t)half * h + sg->lo) * m + k;
            for (j = 0; j < sg->len; ++j)
                dst[j * m] = clear ? 0.0 : o->val[sg->off + j];
        }
    }
}

/* ---------------------------------------------------------------- driver */

/* The share of "writing" that the layers' going in to the writer takes
 * (their series lengths, an order of a layer a unit); the commit has the
 * rest. */
#define LL_WRITE_LAYERS_SHARE 0.45

/* Layers whose stored values take more than this spill to a file beside
 * the output, as a build's do: in memory the spill would double what the
 * caller already holds. Below it the spill stays in memory (no second
 * file, no disk traffic for the small writes that are most of them). */
#define LL_WRITE_MEMORY_SPILL ((size_t)64 << 20)

/* Whether the spill of these layers (about their stored values) fits
 * LL_WRITE_MEMORY_SPILL; NULL layers count nothing (the writer refuses
 * them). */
static int spill_fits_memory(const ll_layer *const *layers, size_t count)
{
    size_t bytes = 0, L, k;
    for (L = 0; L < count; ++L)
        for (k = 0; layers[L] && k < layers[L]->m; ++k) {
            if (layers[L]->orders[k])
                bytes += 8 * ll_order_stored(layers[L]->orders[k]);
            if (bytes > LL_WRITE_MEMORY_SPILL)
                return 0;
        }
    return 1;
}

/* Every layer at once: the writer (bsdf_writer.c), fed layer after layer,
 * so that there is one way to write a file. */
static ll_status write_general(const char *fn, const char *path, const ll_layer *const *layers,
                               size_t n_channels, size_t n_parameters,
                               const size_t *param_counts, const double *param_positions,
                               const ll_bsdf_write_options *opts, const ll_monitor *monitor)
{
    const char *const fns[3] = { fn, fn, fn };
    ll_bsdf_writer *w = NULL;
    ll_watch watch;
    size_t n_bases = 1, units, p, b, c;
    ll_status s;
    if (!path || !*path)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: path is NULL or empty", fn);
    if ((s = ll_watch_begin(&watch, monitor, fn)) != LL_OK)
        return s;
    if (!layers)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: layers is NULL", fn);
    if ((s = ll_writer_open_as(fns, path, n_channels, n_parameters, param_counts,
                               param_positions, opts, 1, &w)) != LL_OK)
        return s;
    /* (open checked the channels and that the counts' product fits.) */
    for (p = 0; p < n_parameters; ++p)
        n_bases *= param_counts[p];
    if (!spill_fits_memory(layers, n_bases * n_channels)) {
        ll_bsdf_writer_abort(w);
        if ((s = ll_writer_open_as(fns, path, n_channels, n_parameters, param_counts,
                                   param_positions, opts, 0, &w)) != LL_OK)
            return s;
    }
    if (!ll_size_mul(n_bases, n_channels, &units) ||
        !ll_size_mul(units, layers[0] ? layers[0]->m : 0, &units))
        units = 0;
    ll_watch_stage(&watch, "writing", 0.0, LL_WRITE_LAYERS_SHARE, units);
    for (b = 0; b < n_bases && s == LL_OK; ++b)
        for (c = 0; c < n_channels && s == LL_OK; ++c)
            s = ll_writer_add_unit(w, b, c, layers[b * n_channels + c], &watch);
    if (s == LL_OK)
        s = ll_writer_commit_watched(w, &watch, LL_WRITE_LAYERS_SHARE);
    ll_bsdf_writer_abort(w);
    return s;
}

ll_status ll_bsdf_write(const char *path, const ll_layer *const *layers, size_t n_channels,
                        const ll_bsdf_write_options *opts, const ll_monitor *monitor)
{
    return write_general("ll_bsdf_write", path, layers, n_channels, 0, NULL, NULL, opts,
                         monitor);
}

ll_status ll_bsdf_write_textured(const char *path, const ll_layer *const *layers,
                                 size_t n_channels, size_t n_parameters,
                                 const size_t *param_counts, const double *param_positions,
                                 const ll_bsdf_write_options *opts, const ll_monitor *monitor)
{
    return write_general("ll_bsdf_write_textured", path, layers, n_channels, n_parameters,
                         param_counts, param_positions, opts, monitor);
}
