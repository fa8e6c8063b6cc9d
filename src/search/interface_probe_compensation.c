/*
 * The energy compensation of an interface layer at the probes
 * (search/probe.h): the albedos of the single-scattering layer of n nodes
 * (order 0 only, every node pair, as ll_layer_set_microfacet makes them:
 * the same series, nodes, weights and order of summation, except that
 * order 0 on the Filon path is Simpson's rule on Filon's samples, the same
 * integral to rounding: ll_microfacet_order0_simpson), then the same
 * rank-one terms (words/microfacet_compensation*.c).
 *
 * Unlike the lobe, the term cannot be had from the stencils alone: it is
 * made from every node's albedo, O(n^2) order-0 series per evaluation
 * (O(n^2 / 4) for a conductor, whose term needs reflection from above
 * only). That is still far below the layer's O(n^2 m): an order-0 series
 * is 16 samples of the profile and one dot product (about 150 where a
 * kink takes the Filon path, where Simpson's rule on the samples now
 * stands for Filon's moments of every order). Each reflection pair is computed once for
 * itself and its reciprocal (bit for bit the same series), and each
 * transmission pair once for itself and for the reverse pair from the
 * other side, which is eta^2 (or 1 / eta^2) times it, as the layer also
 * mirrors each reciprocal pair (words/microfacet_columns.c); computed both
 * ways, the two agree to 3.4e-12 relative (eta 1.5, alpha 0.1, 200 nodes,
 * the worst of the 4922 non-zero pairs), so 2 (n / 2)^2 series make a
 * dielectric's albedos instead of 3 (n / 2)^2.
 */
#include "search/probe.h"
#include "words/microfacet.h"

#include "layerlab/ll_quad.h"

#include <math.h>
#include <string.h>

typedef struct albedo_job {
    const ll_microfacet_model *mf;
    const double *x; /* the layer's nodes: x[j] = -x[j + h]          */
    const double *w; /* [h] 2 pi w_j x_j of the positive nodes        */
    size_t n;
    int conductor;
    double *albedo[4];
    /* The reflection values of the two halves' columns (index col < h),
     * each pair once: reciprocity makes the reflection of row i, column
     * j (indices within their halves) that of row j, column i, bit for
     * bit (the series of (mu_o, mu_i) and (-mu_i, -mu_o) are computed
     * by the same operations). Packed lower triangles, [j (j + 1) / 2 + i]
     * for i <= j; ref: the conductor's mirror (F = 1). NULL: computed
     * where needed. */
    double *tri[2], *tri_ref;
    /* A dielectric's transmission values of the positive half's columns
     * ([j h + i]: row i, column j, both < h); those of the negative
     * half's follow by reciprocity (transmitted). NULL: computed where
     * needed. */
    double *trans;
    double eta2;
    /* The tables' first pass computes the pairs whose maps the model
     * has and marks the rest NaN; the second (retry, after preparing
     * them) computes the NaN slots alone. */
    int retry;
    ll_watch *watch;
} albedo_job;

/* At most this many positive nodes keep the triangles (8 h^2 bytes: 34 MB
 * here); beyond, each column computes its reflection rows itself. */
#define TRIANGLE_NODES 2048

/* Is row `row` a reflection row of column col (and not a transmission
 * one)? Rows and columns in the layer's order. */
static int reflects(const albedo_job *job, size_t row, size_t col)
{
    size_t h = job->n / 2;
    return job->conductor ? col >= h : (row < h) != (col < h);
}

/* A table's order-0 value of row, column col into *v (and the mirror's
 * into *ref if not NULL). First pass: computed if the model has the
 * pair's map, else NaN (made later: collect_missing); retry: computed
 * where NaN (a NaN series, were there one, the same again), the rest
 * kept. */
static ll_status table_value(const albedo_job *job, size_t row, size_t col, double *v,
                             double *ref, double *scratch)
{
    double value, mirror = 0.0;
    size_t len;
    int missing = 0;
    ll_status s;
    if (job->retry && !isnan(*v))
        return LL_OK;
    /* Depth grows opposite to the normal: the series takes -mu. */
    if (job->retry)
        s = ll_microfacet_series(job->mf, -job->x[row], -job->x[col], 1, &value, &len,
                                 ref ? &mirror : NULL, scratch);
    else
        s = ll_microfacet_series_if_prepared(job->mf, -job->x[row], -job->x[col], 1, &value,
                                             &len, ref ? &mirror : NULL, scratch, &missing);
    if (s != LL_OK)
        return s;
    *v = missing ? NAN : len == 0 ? 0.0 : value;
    if (ref)
        *ref = mirror;
    return LL_OK;
}

/* The reflection triangles' part of column col: rows i <= j. */
static ll_status triangle_column(size_t col, void *ctx)
{
    const albedo_job *job = ctx;
    size_t n = job->n, h = n / 2, i;
    size_t j = col < h ? col : col - h, at = j * (j + 1) / 2;
    double *scratch, *tri = job->tri[col < h ? 0 : 1];
    ll_status s = LL_OK;
    if (job->conductor && col < h)
        return LL_OK;
    scratch = ll_alloc_array(ll_microfacet_scratch_size(1), sizeof(double));
    if (!scratch)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "resolution probes: out of memory");
    if (ll_watch_poll(job->watch))
        s = ll_fail(LL_ERROR_CANCELLED, "resolution search: cancelled");
    for (i = 0; i <= j && s == LL_OK; ++i) {
        size_t row = col < h ? i + h : i;
        s = table_value(job, row, col, tri + at + i, job->conductor ? job->tri_ref + at + i : NULL,
                        scratch);
    }
    ll_free(scratch);
    return s;
}

/* The transmission table's column col (< h): rows i < h. */
static ll_status transmission_column(size_t col, void *ctx)
{
    const albedo_job *job = ctx;
    size_t h = job->n / 2, i;
    double *scratch, *out = job->trans + col * h;
    ll_status s = LL_OK;
    scratch = ll_alloc_array(ll_microfacet_scratch_size(1), sizeof(double));
    if (!scratch)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "resolution probes: out of memory");
    if (ll_watch_poll(job->watch))
        s = ll_fail(LL_ERROR_CANCELLED, "resolution search: cancelled");
    for (i = 0; i < h && s == LL_OK; ++i)
        s = table_value(job, i, col, out + i, NULL, scratch);
    ll_free(scratch);
    return s;
}

/* Pairs per ll_microfacet_prepare_pairs call of collect_missing. */
#define PREPARE_BATCH 16384

/* Append the pair (row, col) to the batch, preparing it when full. */
static ll_status add_missing(ll_microfacet_model *mf, const albedo_job *job, size_t row,
                             size_t col, double *mu, size_t *count)
{
    mu[*count] = -job->x[row];
    mu[PREPARE_BATCH + *count] = -job->x[col];
    if (++*count < PREPARE_BATCH)
        return LL_OK;
    *count = 0;
    return ll_microfacet_prepare_pairs(mf, mu, mu + PREPARE_BATCH, PREPARE_BATCH);
}

/* Prepare the maps of the tables' pairs that the first pass left NaN
 * (after the first node counts of a search, few: the maps are the
 * model's, kept from one count to the next), in batches; *any: whether
 * there were such pairs (then the tables are retried). Planning only
 * these, instead of every pair before the tables, leaves each pair one
 * plan, not two. */
static ll_status collect_missing(ll_microfacet_model *mf, const albedo_job *job, int *any)
{
    size_t n = job->n, h = n / 2, col, i, j, count = 0;
    double *mu = ll_alloc_array(PREPARE_BATCH, 2 * sizeof(double));
    ll_status s = LL_OK;
    *any = 0;
    if (!mu)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "resolution probes: out of memory");
    for (col = 0; col < n && s == LL_OK; ++col) {
        const double *tri = job->tri[col < h ? 0 : 1];
        j = col < h ? col : col - h;
        if (job->conductor && col < h)
            continue; /* (no table: opaque from below) */
        if (ll_watch_poll(job->watch))
            s = ll_fail(LL_ERROR_CANCELLED, "resolution search: cancelled");
        for (i = 0; i <= j && s == LL_OK; ++i)
            if (isnan(tri[j * (j + 1) / 2 + i])) {
                *any = 1;
                s = add_missing(mf, job, col < h ? i + h : i, col, mu, &count);
            }
        for (i = 0; job->trans && col < h && i < h && s == LL_OK; ++i)
            if (isnan(job->trans[col * h + i])) {
                *any = 1;
                s = add_missing(mf, job, i, col, mu, &count);
            }
    }
    if (s == LL_OK && count > 0)
        s = ll_microfacet_prepare_pairs(mf, mu, mu + PREPARE_BATCH, count);
    ll_free(mu);
    return s;
}

/* The order-0 value of row, column col (and the conductor's mirror's in
 * *ref): from the triangles where they hold it. */
static ll_status pair_value(const albedo_job *job, size_t row, size_t col, double *v,
                            double *ref, double *scratch)
{
    size_t h = job->n / 2, len;
    ll_status s;
    if (job->tri[0] && reflects(job, row, col)) {
        size_t i = row < h ? row : row - h, j = col < h ? col : col - h;
        size_t at = i <= j ? j * (j + 1) / 2 + i : i * (i + 1) / 2 + j;
        *v = job->tri[col < h ? 0 : 1][at];
        if (job->conductor)
            *ref = job->tri_ref[at];
        return LL_OK;
    }
    if (job->trans && !reflects(job, row, col)) {
        /* Both in one half. The pair (mu_o, mu_i) of the negative half
         * is the reverse (-mu_i, -mu_o) of the positive half's pair
         * (col - h, row - h), seen from the other side: eta^2 times it. */
        *v = col < h ? job->trans[col * h + row]
                     : job->eta2 * job->trans[(row - h) * h + (col - h)];
        return LL_OK;
    }
    /* Depth grows opposite to the normal: the series takes -mu. */
    s = ll_microfacet_series(job->mf, -job->x[row], -job->x[col], 1, v, &len,
                             job->conductor ? ref : NULL, scratch);
    if (len == 0)
        *v = 0.0;
    return s;
}

/* Column col's albedos: one per block it is the input column of. */
static ll_status albedo_column(size_t col, void *ctx)
{
    const albedo_job *job = ctx;
    size_t n = job->n, h = n / 2, row;
    size_t j = col < h ? col : col - h;
    double *scratch = ll_alloc_array(ll_microfacet_scratch_size(1), sizeof(double));
    double up = 0.0, down = 0.0, v, ref = 0.0;
    ll_status s = LL_OK;
    if (!scratch)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "resolution probes: out of memory");
    if (ll_watch_poll(job->watch))
        s = ll_fail(LL_ERROR_CANCELLED, "resolution search: cancelled");
    if (job->conductor && col < h)
        goto done; /* (opaque: only reflection from above) */
    /* Rows of the negative half first, then the positive, each summed in
     * the order of ll_layer_set_microfacet's block_albedo. */
    for (row = 0; row < (job->conductor ? h : n) && s == LL_OK; ++row) {
        s = pair_value(job, row, col, &v, &ref, scratch);
        if (job->conductor) {
            up += job->w[row] * ref; /* the mirror's (F = 1) */
            down += job->w[row] * v; /* the interface's own */
        } else if (row < h) {
            up += job->w[row] * v;
        } else {
            down += job->w[row - h] * v;
        }
    }
    if (s != LL_OK)
        goto done;
    if (job->conductor) {
        /* (As ll_layer_set_microfacet's: the mirror's in R^t's slot, the
         * interface's in R^b's.) */
        job->albedo[LL_BLOCK_RT][j] = up;
        job->albedo[LL_BLOCK_RB][j] = down;
    } else if (col < h) {
        job->albedo[LL_BLOCK_TBT][j] = up;
        job->albedo[LL_BLOCK_RB][j] = down;
    } else {
        job->albedo[LL_BLOCK_RT][j] = up;
        job->albedo[LL_BLOCK_TTB][j] = down;
    }
done:
    ll_free(scratch);
    return s;
}

ll_status ll_probe_compensation_model(double eta_re, double eta_im, double alpha,
                                      ll_microfacet_model **out)
{
    return ll_probe_compensation_model_distribution(eta_re, eta_im, alpha,
                                                    LL_DISTRIBUTION_BECKMANN, out);
}

ll_status ll_probe_compensation_model_distribution(double eta_re, double eta_im, double alpha,
                                                   int distribution, ll_microfacet_model **out)
{
    /* No widening, series of one term (maps of one order), order 0 of
     * the Filon path by Simpson's rule: the albedos' O(n^2) order-0
     * series were most of a search, and Filon's moments most of those. */
    ll_status s = ll_microfacet_create_distribution(eta_re, eta_im, alpha, distribution,
                                                    LL_PROBE_TRUE_ORDERS, 1, out);
    if (s == LL_OK)
        ll_microfacet_order0_simpson(*out);
    return s;
}

ll_status ll_probe_compensation_make(ll_microfacet_model *mf, double eta_re, double eta_im,
                                     size_t n, ll_watch *watch, ll_probe_compensation *out)
{
    double *rule = ll_alloc_array(n, 2 * sizeof(double));
    ll_status s = rule ? ll_quad_gauss_lobatto(n, rule, rule + n, NULL)
                       : ll_fail(LL_ERROR_OUT_OF_MEMORY,
                                 "resolution probes: out of memory for %zu nodes", n);
    if (s == LL_OK)
        s = ll_probe_compensation_make_rule(mf, eta_re, eta_im, n, rule, rule + n, watch, out);
    else
        memset(out, 0, sizeof *out);
    ll_free(rule);
    return s;
}

ll_status ll_probe_compensation_make_rule(ll_microfacet_model *mf, double eta_re, double eta_im,
                                          size_t n, const double *nodes, const double *weights,
                                          ll_watch *watch, ll_probe_compensation *out)
{
    size_t h = n / 2, k, q;
    int tables, pass;
    double *x = ll_alloc_array(n, 3 * sizeof(double));
    albedo_job job;
    ll_status s = LL_OK;
    memset(out, 0, sizeof *out);
    out->h = h;
    out->memory = ll_alloc_array(h + 1, 9 * sizeof(double));
    if (!x || !out->memory) {
        s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "resolution probes: out of memory for %zu nodes", n);
        goto done;
    }
    /* (mf: ll_probe_compensation_model's. Order 0 of a widened lobe is
     * that of the true one, ll_microfacet_series: the terms hold for
     * every m.) */
    /* The layer's order (ll_layer_create): the negative half reversed. */
    for (k = 0; k < n; ++k)
        x[k] = nodes[k < h ? h - 1 - k : k];
    for (k = 0; k < h; ++k)
        x[n + k] = 2.0 * LL_PI * weights[h + k] * nodes[h + k];
    for (k = 0; k < n; ++k)
        x[2 * n + k] = -x[k];
    /* (Unwatched: ll_microfacet_prepare_watched would start a stage of its
     * own over the search's; the maps it makes are kept by the model.) */
    s = ll_watch_check(watch, "resolution search");
    job.mf = mf;
    job.x = x;
    job.w = x + n;
    job.n = n;
    job.conductor = eta_im > 0.0;
    job.watch = watch;
    for (q = 0; q < 4; ++q)
        job.albedo[q] = out->memory + (4 + q) * h;
    job.tri[0] = job.tri[1] = job.tri_ref = job.trans = NULL;
    job.eta2 = eta_re * eta_re;
    if (s == LL_OK && h <= TRIANGLE_NODES && !job.conductor)
        job.trans = ll_alloc_array(h, h * sizeof(double));
    if (s == LL_OK && h <= TRIANGLE_NODES) {
        size_t packed = h * (h + 1) / 2 + 1;
        job.tri[0] = ll_alloc_array(packed, sizeof(double));
        job.tri[1] = ll_alloc_array(packed, sizeof(double));
        job.tri_ref = job.conductor ? ll_alloc_array(packed, sizeof(double)) : NULL;
        if (!job.tri[0] || !job.tri[1] || (job.conductor && !job.tri_ref)) {
            /* (Then every column computes its own rows.) */
            ll_free(job.tri[0]);
            ll_free(job.tri[1]);
            ll_free(job.tri_ref);
            job.tri[0] = job.tri[1] = job.tri_ref = NULL;
        }
    }
    job.retry = 0;
    /* Without the tables (too many nodes, or no memory for them), every
     * pair's maps first. With them, the pairs whose maps the model has,
     * then the maps of the rest (the pairs of the other halves have the
     * same B) and those pairs. */
    tables = job.tri[0] && (job.conductor || job.trans);
    if (s == LL_OK && !tables)
        s = ll_microfacet_prepare(mf, x + 2 * n, n);
    for (pass = 0; pass < 2 && s == LL_OK && (pass == 0 || job.retry); ++pass) {
        if (job.trans)
            s = ll_parallel_for_watched(h, transmission_column, &job, watch);
        if (s == LL_OK && job.tri[0])
            s = ll_parallel_for_watched(n, triangle_column, &job, watch);
        if (s == LL_OK && tables && pass == 0)
            s = collect_missing(mf, &job, &job.retry);
    }
    if (s == LL_OK)
        s = ll_parallel_for_watched(n, albedo_column, &job, watch);
    ll_free(job.tri[0]);
    ll_free(job.tri[1]);
    ll_free(job.tri_ref);
    ll_free(job.trans);
    if (s != LL_OK)
        goto done;
    /* (The conductor's terms keep the node cosines for their spread.) */
    memcpy(out->memory + 8 * h, x + h, h * sizeof(double));
    if (job.conductor)
        ll_microfacet_compensate_conductor(mf, h, out->memory + 8 * h, job.w,
                                           job.albedo[LL_BLOCK_RT], job.albedo[LL_BLOCK_RB],
                                           out->memory, &out->terms);
    else
        ll_microfacet_compensate_dielectric(mf, h, x + h, job.w, eta_re,
                                            (const double *const *)job.albedo, out->memory,
                                            &out->terms);
done:
    ll_free(x);
    if (s != LL_OK)
        ll_probe_compensation_free(out);
    return s;
}

size_t ll_probe_compensation_series(const ll_probe_compensation *c, int block, size_t i,
                                    size_t j, size_t m, double *out)
{
    return c ? ll_microfacet_compensation_series(&c->terms, block, i, j, m, out) : 0;
}

void ll_probe_compensation_free(ll_probe_compensation *c)
{
    ll_free(c->memory);
    memset(c, 0, sizeof *c);
}
