/*
 * Internal representation of an ll_layer.
 *
 * Nodes are stored in the adding-doubling order: index j < h holds
 * mu = -x_j and index j + h holds mu = +x_j, with 0 < x_0 < ... < x_{h-1} <= 1
 * (h = n / 2). Each Fourier order is an n x n matrix (rows = outgoing,
 * columns = incident) whose columns carry the integration weights:
 * surfaces multiply column i by w_i |mu_i| pi, media by w_i pi, and order 0
 * by a further 2 (method.md, "Discretisation").
 *
 * Each order is an ll_order (layer/order.h): one run of rows per block
 * column, NULL when all zero, immutable and reference counted.
 * Combining works on dense blocks, one order at a time per thread.
 */
#ifndef LL_LAYER_LAYER_H
#define LL_LAYER_LAYER_H

#include "support/support.h"
#include "layer/order.h"
#include "support/watch.h"
#include "layerlab/ll_layer.h"
#include "layerlab/ll_distribution.h"

/* A distributed build's shared state (layerlab/ll_distribution.h;
 * distribution.c): the caller's collective, and whether a failure has
 * been agreed already (after which no rank makes another exchange). One
 * per build, used on the calling thread only. */
typedef struct ll_share {
    ll_distribution dist;  /* the caller's, read up to its struct_size     */
    size_t rank, n_ranks;
    int settled;           /* a failure was agreed: no further exchanges   */
    double peak_bytes;     /* this rank's estimated peak, for messages     */
    /* What the agreements and the counts of the exchanges use, allocated
     * by ll_share_begin, so that agreeing never fails to allocate. */
    void *scratch;
    size_t *agree_bytes, *exchange_bytes, *gather_bytes; /* [2 n_ranks] each */
    unsigned char *agree_send, *agree_recv;
    uint64_t *wire;        /* [2 n_ranks]                                  */
} ll_share;

struct ll_layer {
    size_t n;          /* node count (even)                             */
    size_t m;          /* Fourier orders                                */
    double *nodes;     /* [n] adding-doubling order (see above)         */
    double *weights;   /* [n] matching weights                          */
    ll_order **orders; /* [m], NULL = all zero                          */
    ll_share *share;   /* NULL; in a distributed build, only the orders
                          this rank owns are kept (the rest are NULL)   */
};

/* ---- distributed builds (distribution.c) */
/* Start a share from a checked distribution: the scratch of the
 * agreements. If even that cannot be allocated this rank cannot take part:
 * the distribution's abort is called (if any) and LL_ERROR_OUT_OF_MEMORY
 * returned, with no agreement. ll_share_end frees it (NULL-safe). */
LL_INTERNAL ll_status ll_share_begin(ll_share *share, const ll_distribution *dist);
LL_INTERNAL void ll_share_end(ll_share *share);
/* Does this rank compute order k of the layer? Always without a share;
 * with one, round robin: k mod n_ranks == rank. */
LL_INTERNAL int ll_layer_owns_order(const ll_layer *layer, size_t k);
LL_INTERNAL size_t ll_share_owner(const ll_share *share, size_t k);
/* Every rank's status, exchanged: the outcome of the whole (a real failure
 * before a cancel, the lowest rank first), with on rank 0 the failing
 * rank's message and on the others a pointer to rank 0's. Marks the share
 * settled when it is a failure. A rank must call it (once) after a failure
 * of its own before it returns, since the others wait in it. */
LL_INTERNAL ll_status ll_share_agree(ll_share *share, ll_status local);
/* The all-to-all of bytes, counts included: send_bytes[d] bytes to rank d
 * (concatenated in rank order); *recv receives what every rank sent here
 * (ll_free it), recv_bytes[s] from rank s. Only after an agreement that
 * found no failure. */
LL_INTERNAL ll_status ll_share_exchange(ll_share *share, const unsigned char *send,
                                        const size_t *send_bytes, unsigned char **recv,
                                        size_t *recv_bytes);
/* Rank 0 receives every order of the n_channels layers from their owners
 * and its layers become whole (share NULL); the other ranks send theirs.
 * Only after an agreement that found no failure. */
LL_INTERNAL ll_status ll_share_gather_layers(ll_share *share, ll_layer *const *layers,
                                             size_t n_channels);

/* ---- layers */
/* Replace all orders of layer with new_orders[0..m-1] (takes ownership of
 * the references; releases the old ones). */
LL_INTERNAL void ll_layer_replace_orders(ll_layer *layer, ll_order **new_orders);
/* The end of every whole-layer computation: on success (status LL_OK) the
 * new orders replace the layer's; on failure they are released and the
 * layer stays as it was. Frees the array either way; returns status. */
LL_INTERNAL ll_status ll_layer_commit_orders(ll_layer *layer, ll_order **new_orders,
                                             ll_status status);
/* Check that two layers can be combined (same n, m, nodes); message names fn. */
LL_INTERNAL ll_status ll_layer_check_compatible(const ll_layer *a, const ll_layer *b,
                                                const char *fn);
/* Column factor of the weight folding of surfaces: w |mu| pi, times 2 for
 * order 0 (media fold w pi; see media.c). */
LL_INTERNAL double ll_layer_surface_factor(const ll_layer *l, size_t col, size_t order);

/* Set every order from per-order builders (helper for the words):
 * builders[l] finished into order l; takes ownership of the builders. */
LL_INTERNAL ll_status ll_layer_set_from_builders(ll_layer *layer, ll_order_builder **builders);
/* Fill a layer column by column (columns.c): one builder per order is made
 * and stored in *builders_slot (a field of ctx, where `column` finds it),
 * column(i, ctx) runs for i in [0, n_columns) on the worker threads and
 * writes builder column first_column + i, and also column i of the dense
 * n x n column-major arrays dense[0..n_dense) (nullable; e.g. an
 * interface's unweighted order 0) that finish reads; finish(ctx)
 * (nullable) runs once after them on the calling thread, then the layer is
 * set from the builders; on failure the layer is unchanged. *builders_slot
 * is NULL again on return. The columns run under watch (nullable;
 * support/watch.h): they poll it, and its last report, which may still
 * cancel, comes before the layer is set (fn names the call in the cancel
 * message). In a distributed build (layer->share) each rank computes the
 * items i mod n_ranks == rank, one all-to-all gives every rank its orders
 * of every column and the dense columns to the owner of order 0, and
 * finish runs there only (it may write only builder 0). */
LL_INTERNAL ll_status ll_layer_build_by_columns(ll_layer *layer, size_t n_columns,
                                                size_t first_column,
                                                ll_status (*column)(size_t col, void *ctx),
                                                ll_status (*finish)(void *ctx), void *ctx,
                                                ll_order_builder ***builders_slot,
                                                double *const *dense, size_t n_dense,
                                                ll_watch *watch, const char *fn);

#endif /* LL_LAYER_LAYER_H */
