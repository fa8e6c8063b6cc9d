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
#include "layer/split.h"
#include "layerlab/ll_layer.h"

/* In a distributed build the calling thread's split (layer/split.h) says
 * which orders are computed: the others stay NULL. */
struct ll_layer {
    size_t n;          /* node count (even)                             */
    size_t m;          /* Fourier orders                                */
    double *nodes;     /* [n] adding-doubling order (see above)         */
    double *weights;   /* [n] matching weights                          */
    ll_order **orders; /* [m], NULL = all zero                          */
};

/* ---- layers */
/* Replace all orders of layer with new_orders[0..m-1] (takes ownership of
 * the references; releases the old ones); an order the calling thread's
 * split does not compute is released and stays NULL. */
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
 * message). In a distributed build (the calling thread's split) each rank
 * computes the items i mod n_ranks == rank, one all-to-all gives every rank its orders
 * of every column and the dense columns whole, and finish runs on every
 * rank, with the builders of that rank's orders (the others NULL). */
LL_INTERNAL ll_status ll_layer_build_by_columns(ll_layer *layer, size_t n_columns,
                                                size_t first_column,
                                                ll_status (*column)(size_t col, void *ctx),
                                                ll_status (*finish)(void *ctx), void *ctx,
                                                ll_order_builder ***builders_slot,
                                                double *const *dense, size_t n_dense,
                                                ll_watch *watch, const char *fn);

#endif /* LL_LAYER_LAYER_H */
