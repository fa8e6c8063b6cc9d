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
 * Storage (ll_order): high Fourier orders are mostly zero, and the non-zero
 * part of a column of a block is one contiguous run of rows (a scattering
 * lobe), so each column of each block keeps only its run [lo, lo + len).
 * A column of the full matrix has two halves (rows < h and rows >= h), and
 * segment (col, half) belongs to block:
 *      half 0 (rows < h,  outgoing up):   col < h: T^bt   col >= h: R^t
 *      half 1 (rows >= h, outgoing down): col < h: R^b    col >= h: T^tb
 * An order whose every run is empty is stored as NULL. Orders are immutable
 * once built and reference counted, so clones and layers that differ only in
 * a few orders (the channels of an RGB stack) share the rest.
 * Combining works on dense blocks, one order at a time per thread.
 */
#ifndef LL_LAYER_INTERNAL_H
#define LL_LAYER_INTERNAL_H

#include "support.h"
#include "layerlab/ll_layer.h"

/* One run: rows [lo, lo + len) of a half column, values at val + off. The
 * three fields sit together because evaluation reads them together. */
typedef struct ll_segment {
    uint32_t lo, len;
    size_t off;
} ll_segment;

typedef struct ll_order {
    int refcount;      /* atomic */
    size_t n;          /* matrix size                                   */
    ll_segment *seg;   /* [2n + 1]; seg[2n].off = values stored         */
    double *val;       /* stored values, segment after segment          */
} ll_order;

struct ll_layer {
    size_t n;          /* node count (even)                             */
    size_t m;          /* Fourier orders                                */
    double *nodes;     /* [n] adding-doubling order (see above)         */
    double *weights;   /* [n] matching weights                          */
    ll_order **orders; /* [m], NULL = all zero                          */
};

/* Blocks of an order, as indices for the helpers below. */
enum { LL_BLOCK_TBT = 0, LL_BLOCK_RT = 1, LL_BLOCK_RB = 2, LL_BLOCK_TTB = 3 };

/* Entries with magnitude at or below this are not stored after a
 * combination (the matrices are dimensionless transfer coefficients of
 * order one; cf. the original's prune(1, 1e-9)). */
#define LL_DROP_THRESHOLD 1e-12

/* ---- orders */
LL_INTERNAL ll_order *ll_order_retain(ll_order *o);
LL_INTERNAL void ll_order_release(ll_order *o);

/* Compress a dense column-major n x n matrix, dropping entries with
 * |x| <= drop at both ends of each run. *out = NULL if nothing remains. */
LL_INTERNAL ll_status ll_order_from_dense(const double *dense, size_t n, double drop,
                                          ll_order **out);
/* Compress four dense column-major h x h blocks (any may be NULL = zero). */
LL_INTERNAL ll_status ll_order_from_blocks(const double *const blocks[4], size_t h,
                                           double drop, ll_order **out);
/* Expand (o may be NULL): dense column-major n x n, or one h x h block.
 * Returns 1 if the block has any stored value, else 0 (and zero-fills). */
LL_INTERNAL void ll_order_to_dense(const ll_order *o, size_t n, double *dense);
LL_INTERNAL int ll_order_block_to_dense(const ll_order *o, size_t n, int block, double *dense);
/* Is a block (or the whole order) all zero? */
LL_INTERNAL int ll_order_block_is_zero(const ll_order *o, int block);
/* Entry (row, col) of the full weighted matrix. */
LL_INTERNAL double ll_order_get(const ll_order *o, size_t row, size_t col);
/* The order with only one block kept (NULL if that block is zero); shares o
 * itself when nothing else is stored. */
LL_INTERNAL ll_status ll_order_keep_block(const ll_order *o, int block, ll_order **out);
/* Number of stored values. */
LL_INTERNAL size_t ll_order_stored(const ll_order *o);
/* The order with its top and bottom swapped (reverse), or NULL for NULL. */
LL_INTERNAL ll_status ll_order_reversed(const ll_order *o, ll_order **out);
/* A clear order: T = I, R = 0. */
LL_INTERNAL ll_status ll_order_identity(size_t n, ll_order **out);

/* ---- building an order column by column (interfaces, media, MERL):
 * thread-safe for distinct columns; trims exact zeros (|x| <= drop). */
typedef struct ll_order_builder ll_order_builder;
LL_INTERNAL ll_status ll_order_builder_create(size_t n, ll_order_builder **out);
LL_INTERNAL ll_status ll_order_builder_set_column(ll_order_builder *b, size_t col,
                                                  const double *column, double drop);
/* The same when the caller knows that rows outside [row_lo, row_hi) are zero
 * (only that range is scanned). */
LL_INTERNAL ll_status ll_order_builder_set_column_range(ll_order_builder *b, size_t col,
                                                        const double *column, size_t row_lo,
                                                        size_t row_hi, double drop);
/* Finish: *out = the order (NULL if all zero); frees the builder. */
LL_INTERNAL ll_status ll_order_builder_finish(ll_order_builder *b, ll_order **out);
LL_INTERNAL void ll_order_builder_destroy(ll_order_builder *b);

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

/* ---- doubling with progress and cancellation (for long builds) */
typedef struct ll_expand_monitor {
    const volatile int *cancel;                       /* nullable; nonzero stops */
    void (*progress)(double fraction, void *user);    /* nullable; calling thread */
    void *user;
} ll_expand_monitor;

/* ll_layer_expand with a monitor: progress reports the fraction of Fourier
 * orders finished, on the calling thread; a raised cancel flag stops the
 * doublings early with LL_ERROR_CANCELLED and leaves the layer unchanged. */
LL_INTERNAL ll_status ll_layer_expand_monitored(ll_layer *layer, double tau,
                                                const ll_expand_monitor *monitor);

/* The doubling schedule of ll_layer_expand for nodes whose smallest |mu| is
 * min_mu: the initial thickness tau0 and the count k with tau0 2^k = tau. */
LL_INTERNAL void ll_expand_schedule(double tau, double min_mu, double *tau0, size_t *doublings);

#endif /* LL_LAYER_INTERNAL_H */
