/*
 * The scaffolding of the words that fill a layer column by column
 * (microfacet interfaces, MERL BRDFs): one order builder per Fourier
 * order, the columns computed in parallel (each writes its column of every
 * order, so columns are independent and the result is the same for any
 * thread count), an optional serial step, and the layer set from the
 * builders at its single commit point.
 *
 * In a distributed build (the calling thread's split, layer/split.h) the
 * columns are what splits: rank
 * r computes the columns i mod N == r of every order, then one all-to-all
 * moves each order's columns to the order's owner (round robin), which
 * then holds that order whole, byte for byte what one process would have
 * built (the columns are independent and copied as stored).
 */
#include "layer/layer.h"

#include <stdlib.h>
#include <string.h>

/* A rank's share of the items: i = rank, rank + N, ... */
typedef struct share_job {
    size_t rank, n_ranks;
    ll_status (*column)(size_t col, void *ctx);
    void *ctx;
    ll_watch *watch;
} share_job;

static ll_status share_column(size_t i, void *ctx)
{
    share_job *job = ctx;
    ll_status s = job->column(job->rank + i * job->n_ranks, job->ctx);
    /* The others compute the columns in between: the progress of the
     * stage is the fraction of all columns. */
    ll_watch_advance(job->watch, job->n_ranks - 1);
    return s;
}

static size_t items_of(size_t rank, size_t n_ranks, size_t n_items)
{
    return n_items > rank ? (n_items - rank + n_ranks - 1) / n_ranks : 0;
}

/* The bytes this rank sends to rank d: its columns of d's orders and of
 * the dense arrays (every rank's finish reads them whole: an interface's
 * compensation reaches every order). */
static size_t bytes_for(const ll_split *sh, size_t d, ll_order_builder *const *builders,
                        size_t m, size_t n_items, size_t first, size_t n, size_t n_dense)
{
    size_t k, i, total = 0;
    for (k = d; k < m; k += sh->n_ranks)
        for (i = sh->rank; i < n_items; i += sh->n_ranks)
            total += ll_order_builder_column_bytes(builders[k], first + i);
    total += items_of(sh->rank, sh->n_ranks, n_items) * n_dense * n * sizeof(double);
    return total;
}

static unsigned char *pack_for(const ll_split *sh, size_t d, ll_order_builder *const *builders,
                               size_t m, size_t n_items, size_t first, size_t n,
                               double *const *dense, size_t n_dense, unsigned char *p)
{
    size_t k, i, a;
    for (k = d; k < m; k += sh->n_ranks)
        for (i = sh->rank; i < n_items; i += sh->n_ranks)
            p = ll_order_builder_pack_column(builders[k], first + i, p);
    for (a = 0; a < n_dense; ++a)
        for (i = sh->rank; i < n_items; i += sh->n_ranks) {
            memcpy(p, dense[a] + i * n, n * sizeof(double));
            p += n * sizeof(double);
        }
    return p;
}

static ll_status unpack_from(const ll_split *sh, size_t src, ll_order_builder *const *builders,
                             size_t m, size_t n_items, size_t first, size_t n,
                             double *const *dense, size_t n_dense, const unsigned char *p,
                             const unsigned char *end)
{
    size_t k, i, a;
    ll_status s = LL_OK;
    for (k = sh->rank; k < m && s == LL_OK; k += sh->n_ranks)
        for (i = src; i < n_items && s == LL_OK; i += sh->n_ranks)
            s = ll_order_builder_unpack_column(builders[k], first + i, &p, end);
    if (s == LL_OK)
        for (a = 0; a < n_dense && s == LL_OK; ++a)
            for (i = src; i < n_items && s == LL_OK; i += sh->n_ranks) {
                if ((size_t)(end - p) < n * sizeof(double))
                    return ll_fail(LL_ERROR_FORMAT, "rank %zu sent too few columns", src);
                memcpy(dense[a] + i * n, p, n * sizeof(double));
                p += n * sizeof(double);
            }
    if (s == LL_OK && p != end)
        s = ll_fail(LL_ERROR_FORMAT, "rank %zu sent more columns than expected", src);
    return s;
}

/* The all-to-all of a distributed build's columns (s: the columns'
 * outcome on this rank, agreed first): after it, builders[k]
 * holds every column of each order k this rank owns (the others are
 * destroyed: NULL) and the dense arrays whole. */
static ll_status exchange_columns(const ll_split *sh, ll_status s, ll_order_builder **builders,
                                  size_t m, size_t n_items, size_t first, size_t n,
                                  double *const *dense, size_t n_dense)
{
    size_t N = sh->n_ranks, d, k, total = 0, *bytes;
    unsigned char *send = NULL, *recv = NULL, *p = NULL;

    bytes = ll_calloc_array(2 * N, sizeof *bytes);
    if (!bytes && s == LL_OK)
        s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory for the counts of %zu ranks", N);
    for (d = 0; d < N && s == LL_OK; ++d) {
        /* Nothing to itself: its own columns are in its builders. */
        bytes[d] = d == sh->rank ? 0 : bytes_for(sh, d, builders, m, n_items, first, n, n_dense);
        if (!ll_size_add(total, bytes[d], &total))
            s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "the columns are too large to send");
    }
    if (s == LL_OK) {
        send = p = ll_malloc(total ? total : 1);
        if (!send)
            s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory packing %.0f MiB of columns",
                        (double)total / 1048576.0);
    }
    for (d = 0; d < N && s == LL_OK; ++d)
        if (d != sh->rank)
            p = pack_for(sh, d, builders, m, n_items, first, n, dense, n_dense, p);
    /* The orders this rank does not own are in the buffer now. */
    for (k = 0; k < m && s == LL_OK; ++k)
        if (!ll_split_owns(sh, k)) {
            ll_order_builder_destroy(builders[k]);
            builders[k] = NULL;
        }
    s = sh->agree(sh->ctx, s);
    if (s == LL_OK)
        s = sh->exchange(sh->ctx, send, bytes, &recv, bytes + N);
    ll_free(send);
    p = recv;
    for (d = 0; d < N && s == LL_OK; ++d) {
        if (d != sh->rank) /* (its own columns never left) */
            s = unpack_from(sh, d, builders, m, n_items, first, n, dense, n_dense, p,
                            p + bytes[N + d]);
        p += bytes[N + d];
    }
    ll_free(recv);
    ll_free(bytes);
    return s;
}

ll_status ll_layer_build_by_columns(ll_layer *layer, size_t n_columns, size_t first_column,
                                    ll_status (*column)(size_t col, void *ctx),
                                    ll_status (*finish)(void *ctx), void *ctx,
                                    ll_order_builder ***builders_slot, double *const *dense,
                                    size_t n_dense, ll_watch *watch, const char *fn)
{
    size_t k, m = layer->m;
    const ll_split *sh = ll_split_current();
    ll_order_builder **builders = ll_calloc_array(m, sizeof *builders);
    ll_status s = LL_OK;
    if (!builders)
        s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory for the %zu orders of a layer", m);
    for (k = 0; k < m && s == LL_OK; ++k)
        s = ll_order_builder_create(layer->n, &builders[k]);
    *builders_slot = builders;
    if (!sh) {
        if (s == LL_OK)
            s = ll_parallel_for_watched(n_columns, column, ctx, watch);
    } else {
        share_job job;
        job.rank = sh->rank;
        job.n_ranks = sh->n_ranks;
        job.column = column;
        job.ctx = ctx;
        job.watch = watch;
        if (s == LL_OK)
            s = ll_parallel_for_watched(items_of(sh->rank, sh->n_ranks, n_columns),
                                        share_column, &job, watch);
        /* Every rank reaches the exchange (a failed one only agrees). */
        if (builders)
            s = exchange_columns(sh, s, builders, m, n_columns, first_column, layer->n, dense,
                                 n_dense);
        else
            s = sh->agree(sh->ctx, s);
    }
    if (s == LL_OK && finish)
        s = finish(ctx);
    /* The last report comes before the layer changes: a cancel there still
     * leaves it as it was. */
    s = ll_watch_finish(watch, s, fn);
    *builders_slot = NULL;
    if (s == LL_OK) {
        s = ll_layer_set_from_builders(layer, builders); /* takes the builders */
    } else if (builders) {
        for (k = 0; k < m; ++k)
            ll_order_builder_destroy(builders[k]);
    }
    ll_free(builders);
    return s;
}
