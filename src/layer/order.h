/*
 * One Fourier order of a layer's scattering matrix, stored compactly.
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
 */
#ifndef LL_LAYER_ORDER_H
#define LL_LAYER_ORDER_H

#include "support/support.h"

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
 * itself when nothing else is stored (a new reference, so o is not const). */
LL_INTERNAL ll_status ll_order_keep_block(ll_order *o, int block, ll_order **out);
/* Number of stored values. */
LL_INTERNAL size_t ll_order_stored(const ll_order *o);
/* The order with its top and bottom swapped (reverse), or NULL for NULL. */
LL_INTERNAL ll_status ll_order_reversed(const ll_order *o, ll_order **out);
/* An order from its runs as stored (seg[2n + 1], val[seg[2n].off]): the
 * exact copy of an order whose fields these were (a builder's cache of
 * word layers on disk, material_sweep_build.c). */
LL_INTERNAL ll_status ll_order_from_runs(size_t n, const ll_segment *seg, const double *val,
                                         ll_order **out);
/* A clear order: T = I, R = 0. */
LL_INTERNAL ll_status ll_order_identity(size_t n, ll_order **out);

/* ---- orders that need no dense work (Fourier orders beyond a phase
 * function's moments hold only the unscattered light: a diagonal T)
 * Is o only the diagonals of its two T blocks (R blocks empty, each T
 * column at most its diagonal entry)? Then down[j] = T^tb(j, j) and
 * up[j] = T^bt(j, j), j < h, and 1; else 0 (and down, up unspecified),
 * also for NULL. */
LL_INTERNAL int ll_order_diagonal(const ll_order *o, double *down, double *up);
/* diag(left) o diag(right) (left, right: n each), every run trimmed at both
 * ends by drop; entries are (x right[col]) left[row]. NULL for NULL/empty. */
LL_INTERNAL ll_status ll_order_scaled(const ll_order *o, const double *left,
                                      const double *right, double drop, ll_order **out);
/* The order whose T blocks are diag(down) (T^tb) and diag(up) (T^bt), h
 * each, R empty; entries |x| <= drop not stored (NULL if none is left). */
LL_INTERNAL ll_status ll_order_from_diagonals(size_t n, const double *down, const double *up,
                                              double drop, ll_order **out);

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
/* The column as set so far (n doubles; zero where nothing is stored): for
 * a term added to the columns once they are all known. */
LL_INTERNAL void ll_order_builder_get_column(const ll_order_builder *b, size_t col,
                                             double *column);
/* The other half of a reciprocal order (an interface's: entry (r, c) is
 * entry (M(c), M(r)) times factors of its row and column, M(k) = k +- h
 * being the same cosine on the other side), from the half that is set:
 * every stored entry (r, c) off the fixed points r = M(c) is written at
 * (M(c), M(r)) as well, times row_scale[M(c)] col_scale[M(r)] (n each).
 * The builder must hold at most one entry of each pair, the other zero:
 * then every written entry lands on a zero, and the result is the same
 * whatever order the columns were set in. Exact zeros are not written, so
 * each run still ends on a stored value, as a column set whole would.
 * Costs the stored entries, not n^2. scratch: ll_order_builder_mirror_bytes(n)
 * bytes (0 if that overflows), suitably aligned for doubles and pointers
 * (from ll_malloc), its contents on entry unused. */
LL_INTERNAL size_t ll_order_builder_mirror_bytes(size_t n);
LL_INTERNAL ll_status ll_order_builder_mirror(ll_order_builder *b, const double *row_scale,
                                              const double *col_scale, void *scratch);
/* Finish: *out = the order (NULL if all zero); frees the builder. */
LL_INTERNAL ll_status ll_order_builder_finish(ll_order_builder *b, ll_order **out);
LL_INTERNAL void ll_order_builder_destroy(ll_order_builder *b);
/* One column of a builder as bytes, for a distributed build's exchange
 * (layer/columns.c): its size, the packing (returns the end of what was
 * written) and the unpacking into another builder of the same n (advances
 * *src; LL_ERROR_FORMAT if [*src, end) is not a column). */
LL_INTERNAL size_t ll_order_builder_column_bytes(const ll_order_builder *b, size_t col);
LL_INTERNAL unsigned char *ll_order_builder_pack_column(const ll_order_builder *b, size_t col,
                                                        unsigned char *dst);
LL_INTERNAL ll_status ll_order_builder_unpack_column(ll_order_builder *b, size_t col,
                                                     const unsigned char **src,
                                                     const unsigned char *end);

/* ---- a whole order as bytes (order_pack.c), for gathering a distributed
 * build's layers: a flag (NULL or not), then the segments and values as
 * stored, so the copy is the same order bit for bit. */
LL_INTERNAL size_t ll_order_packed_bytes(const ll_order *o);
LL_INTERNAL unsigned char *ll_order_pack(const ll_order *o, unsigned char *dst);
/* *out = the order (NULL for a packed NULL) of an n x n matrix; advances
 * *src; LL_ERROR_FORMAT if the bytes are not an order of that size. */
LL_INTERNAL ll_status ll_order_unpack(size_t n, const unsigned char **src,
                                      const unsigned char *end, ll_order **out);

#endif /* LL_LAYER_ORDER_H */
