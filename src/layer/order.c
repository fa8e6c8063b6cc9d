/*
 * Compact storage of one Fourier order (see order.h): per column
 * and half, one run of stored rows.
 */
#include "layer/layer.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

ll_order *ll_order_retain(ll_order *o)
{
    if (o)
        __atomic_add_fetch(&o->refcount, 1, __ATOMIC_RELAXED);
    return o;
}

void ll_order_release(ll_order *o)
{
    if (!o || __atomic_sub_fetch(&o->refcount, 1, __ATOMIC_ACQ_REL) != 0)
        return;
    ll_free(o->seg);
    ll_free(o->val);
    ll_free(o);
}

/* Allocate an order of size n with room for `stored` values. */
static ll_order *order_alloc(size_t n, size_t stored)
{
    ll_order *o = ll_calloc(1, sizeof *o);
    size_t segs;
    if (!o || !ll_size_mul(n, 2, &segs))
        goto fail;
    o->refcount = 1;
    o->n = n;
    o->seg = ll_calloc_array(segs + 1, sizeof *o->seg);
    o->val = ll_alloc_array(stored, sizeof *o->val);
    if (!o->seg || !o->val)
        goto fail;
    return o;
fail:
    if (o) {
        ll_free(o->seg);
        ll_free(o->val);
        ll_free(o);
    }
    return NULL;
}

ll_status ll_order_from_runs(size_t n, const ll_segment *seg, const double *val,
                             ll_order **out)
{
    size_t stored = seg[2 * n].off;
    ll_order *o = order_alloc(n, stored);
    *out = NULL;
    if (!o)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory reading a layer back");
    memcpy(o->seg, seg, (2 * n + 1) * sizeof *seg);
    memcpy(o->val, val, stored * sizeof *val);
    *out = o;
    return LL_OK;
}

/* The run of x[0..count) (stride 1) outside which |x| <= drop. */
static void find_run(const double *x, size_t count, double drop, size_t *lo, size_t *len)
{
    size_t a = 0, b = count;
    /* fabs(NaN) <= drop is false: a NaN is kept (and shows), never trimmed. */
    while (a < b && fabs(x[a]) <= drop)
        ++a;
    while (b > a && fabs(x[b - 1]) <= drop)
        --b;
    *lo = a;
    *len = b - a;
}

/* Segment s = 2 * col + half; which block and which column of it. */
static const double *block_column(const double *const blocks[4], size_t h, size_t col,
                                  int half)
{
    int block;
    size_t c = col < h ? col : col - h;
    if (half == 0)
        block = col < h ? LL_BLOCK_TBT : LL_BLOCK_RT;
    else
        block = col < h ? LL_BLOCK_RB : LL_BLOCK_TTB;
    return blocks[block] ? blocks[block] + c * h : NULL;
}

ll_status ll_order_from_blocks(const double *const blocks[4], size_t h, double drop,
                               ll_order **out)
{
    size_t n = 2 * h, col, total = 0;
    int half;
    ll_order *o;
    size_t *lo = ll_alloc_array(2 * n, sizeof *lo), *len = ll_alloc_array(2 * n, sizeof *len);

    *out = NULL;
    if (!lo || !len) {
        ll_free(lo);
        ll_free(len);
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory storing a %zu x %zu order", n, n);
    }
    for (col = 0; col < n; ++col) {
        for (half = 0; half < 2; ++half) {
            const double *x = block_column(blocks, h, col, half);
            size_t s = 2 * col + (size_t)half;
            if (x)
                find_run(x, h, drop, &lo[s], &len[s]);
            else
                lo[s] = len[s] = 0;
            total += len[s];
        }
    }
    if (total == 0) {
        ll_free(lo);
        ll_free(len);
        return LL_OK;
    }
    o = order_alloc(n, total);
    if (!o) {
        ll_free(lo);
        ll_free(len);
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory storing a %zu x %zu order", n, n);
    }
    total = 0;
    for (col = 0; col < n; ++col) {
        for (half = 0; half < 2; ++half) {
            size_t s = 2 * col + (size_t)half;
            o->seg[s].lo = (uint32_t)lo[s];
            o->seg[s].len = (uint32_t)len[s];
            o->seg[s].off = total;
            if (len[s])
                memcpy(o->val + total, block_column(blocks, h, col, half) + lo[s],
                       len[s] * sizeof(double));
            total += len[s];
        }
    }
    o->seg[2 * n].off = total;
    ll_free(lo);
    ll_free(len);
    *out = o;
    return LL_OK;
}

ll_status ll_order_from_dense(const double *dense, size_t n, double drop, ll_order **out)
{
    /* Split the column-major n x n matrix into its blocks by copying; the
     * blocks are h x h column-major with leading dimension h. */
    size_t h = n / 2, c;
    ll_status s;
    double *tmp = ll_alloc_array(4 * h, h * sizeof(double));
    const double *blocks[4];
    if (!tmp)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory storing a %zu x %zu order", n, n);
    for (c = 0; c < h; ++c) {
        memcpy(tmp + 0 * h * h + c * h, dense + c * n, h * sizeof(double));           /* T^bt */
        memcpy(tmp + 1 * h * h + c * h, dense + (c + h) * n, h * sizeof(double));     /* R^t  */
        memcpy(tmp + 2 * h * h + c * h, dense + c * n + h, h * sizeof(double));       /* R^b  */
        memcpy(tmp + 3 * h * h + c * h, dense + (c + h) * n + h, h * sizeof(double)); /* T^tb */
    }
    blocks[0] = tmp;
    blocks[1] = tmp + h * h;
    blocks[2] = tmp + 2 * h * h;
    blocks[3] = tmp + 3 * h * h;
    s = ll_order_from_blocks(blocks, h, drop, out);
    ll_free(tmp);
    return s;
}

/* Which columns and half a block occupies. */
static void block_layout(int block, size_t h, size_t *col0, int *half)
{
    switch (block) {
    case LL_BLOCK_TBT: *col0 = 0; *half = 0; break;
    case LL_BLOCK_RT: *col0 = h; *half = 0; break;
    case LL_BLOCK_RB: *col0 = 0; *half = 1; break;
    default: *col0 = h; *half = 1; break;
    }
}

int ll_order_block_to_dense(const ll_order *o, size_t n, int block, double *dense)
{
    size_t h = n / 2, col0, c;
    int half, any = 0;
    if (!o) {
        memset(dense, 0, h * h * sizeof(double));
        return 0;
    }
    block_layout(block, h, &col0, &half);
    /* Each column once: zeros around its run, the run copied (clearing the
     * whole block first wrote every dense column twice; 2% of a build). */
    for (c = 0; c < h; ++c) {
        size_t s = 2 * (col0 + c) + (size_t)half, lo = 0, len = o->seg[s].len;
        double *col = dense + c * h;
        if (len) {
            lo = o->seg[s].lo;
            memcpy(col + lo, o->val + o->seg[s].off, len * sizeof(double));
            any = 1;
        }
        memset(col, 0, lo * sizeof(double));
        memset(col + lo + len, 0, (h - lo - len) * sizeof(double));
    }
    return any;
}

void ll_order_to_dense(const ll_order *o, size_t n, double *dense)
{
    size_t col, h = n / 2;
    int half;
    memset(dense, 0, n * n * sizeof(double));
    if (!o)
        return;
    for (col = 0; col < n; ++col)
        for (half = 0; half < 2; ++half) {
            size_t s = 2 * col + (size_t)half;
            if (o->seg[s].len)
                memcpy(dense + col * n + (size_t)half * h + o->seg[s].lo, o->val + o->seg[s].off,
                       o->seg[s].len * sizeof(double));
        }
}

int ll_order_block_is_zero(const ll_order *o, int block)
{
    size_t h, col0, c;
    int half;
    if (!o)
        return 1;
    h = o->n / 2;
    block_layout(block, h, &col0, &half);
    for (c = 0; c < h; ++c)
        if (o->seg[2 * (col0 + c) + (size_t)half].len)
            return 0;
    return 1;
}

double ll_order_get(const ll_order *o, size_t row, size_t col)
{
    size_t h, s, r;
    int half;
    if (!o)
        return 0.0;
    h = o->n / 2;
    half = row >= h;
    r = half ? row - h : row;
    s = 2 * col + (size_t)half;
    if (r < o->seg[s].lo || r >= (size_t)o->seg[s].lo + o->seg[s].len)
        return 0.0;
    return o->val[o->seg[s].off + (r - o->seg[s].lo)];
}

ll_status ll_order_keep_block(ll_order *o, int block, ll_order **out)
{
    size_t n, h, col0, c, total = 0, s;
    int half, only_block = 1;
    ll_order *r;

    *out = NULL;
    if (!o || ll_order_block_is_zero(o, block))
        return LL_OK;
    n = o->n;
    h = n / 2;
    block_layout(block, h, &col0, &half);
    for (s = 0; s < 2 * n; ++s) {
        int in_block = (s % 2 == (size_t)half) && s / 2 >= col0 && s / 2 < col0 + h;
        if (!in_block && o->seg[s].len)
            only_block = 0;
    }
    if (only_block) {
        /* Nothing else is stored: share the order itself. */
        *out = ll_order_retain(o);
        return LL_OK;
    }
    for (c = 0; c < h; ++c)
        total += o->seg[2 * (col0 + c) + (size_t)half].len;
    r = order_alloc(n, total);
    if (!r)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory storing a %zu x %zu order", n, n);
    total = 0;
    for (s = 0; s < 2 * n; ++s) {
        int in_block = (s % 2 == (size_t)half) && s / 2 >= col0 && s / 2 < col0 + h;
        r->seg[s].off = total;
        if (in_block && o->seg[s].len) {
            r->seg[s].lo = o->seg[s].lo;
            r->seg[s].len = o->seg[s].len;
            memcpy(r->val + total, o->val + o->seg[s].off, o->seg[s].len * sizeof(double));
            total += o->seg[s].len;
        }
    }
    r->seg[2 * n].off = total;
    *out = r;
    return LL_OK;
}

size_t ll_order_stored(const ll_order *o) { return o ? o->seg[2 * o->n].off : 0; }

ll_status ll_order_reversed(const ll_order *o, ll_order **out)
{
    /* Reversal maps direction index j <-> j +- h (flip the sign of every mu):
     * entry (r, c) moves to (r', c'). Blocks T^bt <-> T^tb and R^t <-> R^b. */
    size_t n, h, col;
    int half;
    ll_order *r;
    *out = NULL;
    if (!o)
        return LL_OK;
    n = o->n;
    h = n / 2;
    r = order_alloc(n, ll_order_stored(o));
    if (!r)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory reversing a layer");
    {
        size_t total = 0;
        for (col = 0; col < n; ++col) {
            size_t src_col = col < h ? col + h : col - h;
            for (half = 0; half < 2; ++half) {
                size_t s = 2 * col + (size_t)half, t = 2 * src_col + (size_t)(1 - half);
                r->seg[s].lo = o->seg[t].lo;
                r->seg[s].len = o->seg[t].len;
                r->seg[s].off = total;
                memcpy(r->val + total, o->val + o->seg[t].off, o->seg[t].len * sizeof(double));
                total += o->seg[t].len;
            }
        }
        r->seg[2 * n].off = total;
    }
    *out = r;
    return LL_OK;
}

ll_status ll_order_identity(size_t n, ll_order **out)
{
    size_t col, h = n / 2;
    ll_order *o = order_alloc(n, n);
    *out = NULL;
    if (!o)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory creating a %zu-node layer", n);
    for (col = 0; col < n; ++col) {
        /* T blocks: column col < h has its diagonal in half 0, else half 1. */
        size_t s_t = 2 * col + (col < h ? 0 : 1), s_r = 2 * col + (col < h ? 1 : 0);
        o->seg[s_t].lo = (uint32_t)(col < h ? col : col - h);
        o->seg[s_t].len = 1;
        o->seg[s_r].lo = 0;
        o->seg[s_r].len = 0;
    }
    for (col = 0; col < 2 * n; ++col)
        o->seg[col].off = 0;
    {
        size_t total = 0, s;
        for (s = 0; s < 2 * n; ++s) {
            o->seg[s].off = total;
            if (o->seg[s].len)
                o->val[total] = 1.0;
            total += o->seg[s].len;
        }
        o->seg[2 * n].off = total;
    }
    *out = o;
    return LL_OK;
}

/* ------------------------------------------------------------- builder */

struct ll_order_builder {
    size_t n;
    double **seg;      /* [2n] stored runs, malloc'ed each */
    uint32_t *lo, *len;
};

ll_status ll_order_builder_create(size_t n, ll_order_builder **out)
{
    ll_order_builder *b = ll_calloc(1, sizeof *b);
    *out = NULL;
    if (!b)
        goto fail;
    b->n = n;
    b->seg = ll_calloc_array(2 * n, sizeof *b->seg);
    b->lo = ll_calloc_array(2 * n, sizeof *b->lo);
    b->len = ll_calloc_array(2 * n, sizeof *b->len);
    if (!b->seg || !b->lo || !b->len)
        goto fail;
    *out = b;
    return LL_OK;
fail:
    ll_order_builder_destroy(b);
    return ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory building a %zu-node order", n);
}

void ll_order_builder_destroy(ll_order_builder *b)
{
    size_t s;
    if (!b)
        return;
    if (b->seg)
        for (s = 0; s < 2 * b->n; ++s)
            ll_free(b->seg[s]);
    ll_free(b->seg);
    ll_free(b->lo);
    ll_free(b->len);
    ll_free(b);
}

ll_status ll_order_builder_set_column_range(ll_order_builder *b, size_t col,
                                            const double *column, size_t row_lo,
                                            size_t row_hi, double drop)
{
    size_t h = b->n / 2;
    int half;
    for (half = 0; half < 2; ++half) {
        size_t s = 2 * col + (size_t)half, first = (size_t)half * h, lo = 0, len = 0;
        /* Scan only the rows that may be non-zero: a sparse column of a
         * high order costs its length, not n. */
        size_t a = row_lo > first ? row_lo - first : 0;
        size_t e = row_hi < first + h ? (row_hi > first ? row_hi - first : 0) : h;
        if (a < e) {
            find_run(column + first + a, e - a, drop, &lo, &len);
            lo += a;
        }
        ll_free(b->seg[s]);
        b->seg[s] = NULL;
        b->lo[s] = (uint32_t)lo;
        b->len[s] = 0;
        if (len) {
            b->seg[s] = ll_malloc(len * sizeof(double));
            if (!b->seg[s])
                return ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory building an order");
            memcpy(b->seg[s], column + first + lo, len * sizeof(double));
            b->len[s] = (uint32_t)len;
        }
    }
    return LL_OK;
}

void ll_order_builder_get_column(const ll_order_builder *b, size_t col, double *column)
{
    size_t h = b->n / 2;
    int half;
    memset(column, 0, b->n * sizeof(double));
    for (half = 0; half < 2; ++half) {
        size_t s = 2 * col + (size_t)half;
        if (b->len[s])
            memcpy(column + (size_t)half * h + b->lo[s], b->seg[s], b->len[s] * sizeof(double));
    }
}

ll_status ll_order_builder_set_column(ll_order_builder *b, size_t col, const double *column,
                                      double drop)
{
    return ll_order_builder_set_column_range(b, col, column, 0, b->n, drop);
}

ll_status ll_order_builder_finish(ll_order_builder *b, ll_order **out)
{
    size_t s, total = 0, segs = 2 * b->n;
    ll_order *o;
    *out = NULL;
    for (s = 0; s < segs; ++s)
        total += b->len[s];
    if (total == 0) {
        ll_order_builder_destroy(b);
        return LL_OK;
    }
    o = order_alloc(b->n, total);
    if (!o) {
        ll_order_builder_destroy(b);
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory building an order");
    }
    total = 0;
    for (s = 0; s < segs; ++s) {
        o->seg[s].lo = b->len[s] ? b->lo[s] : 0;
        o->seg[s].len = b->len[s];
        o->seg[s].off = total;
        if (b->len[s])
            memcpy(o->val + total, b->seg[s], b->len[s] * sizeof(double));
        total += b->len[s];
    }
    o->seg[segs].off = total;
    ll_order_builder_destroy(b);
    *out = o;
    return LL_OK;
}

/* ------------------------------------------- builder, reciprocal half */

/* The mirror of node k: the same cosine on the other side. */
static size_t mirror_node(size_t k, size_t h) { return k < h ? k + h : k - h; }

/* A run that has entries to mirror, as it was before any was written. */
typedef struct mirror_source {
    const double *val;
    size_t seg;
    uint32_t lo, len;
} mirror_source;

size_t ll_order_builder_mirror_bytes(size_t n)
{
    size_t segs, each = sizeof(mirror_source) + sizeof(size_t) + sizeof(double *) +
                        2 * sizeof(uint32_t);
    return n <= (SIZE_MAX - 1) / 2 && ll_size_mul(2 * n, each, &segs) ? segs : 0;
}

/* Segment s = 2 col + half scatters to one row of the other half (row
 * col mod h, in half 1 when col < h), entry t to the mirror column of its
 * own row. So in the order of s each segment's landing rows come in
 * increasing order (col mod h grows with col in either half of the
 * columns): the first sets a segment's lo, the last its hi. Every entry
 * lands on a zero (order.h), and the result does not depend on the order
 * the segments are visited in. */
ll_status ll_order_builder_mirror(ll_order_builder *b, const double *row_scale,
                                  const double *col_scale, void *scratch)
{
    size_t n = b->n, h = n / 2, segs = 2 * n, s, t, k, n_src = 0, n_dst = 0;
    mirror_source *src = scratch;
    size_t *dst = (size_t *)(src + segs);
    double **old = (double **)(dst + segs);
    uint32_t *lo = (uint32_t *)(old + segs), *hi = lo + segs;
    ll_status st = LL_OK;
    memset(lo, 0xff, segs * sizeof *lo); /* UINT32_MAX: nothing lands yet */
    for (s = 0; s < segs; ++s) {
        size_t col = s / 2, first = (s % 2) * h, fixed = mirror_node(col, h);
        size_t to_half = col < h, c0;
        uint32_t to_row = (uint32_t)(col % h);
        const double *v = b->seg[s];
        if (!b->len[s])
            continue;
        src[n_src].val = v;
        src[n_src].seg = s;
        src[n_src].lo = b->lo[s];
        src[n_src].len = b->len[s];
        ++n_src;
        c0 = mirror_node(first + b->lo[s], h); /* the columns c0, c0 + 1, ... */
        for (t = 0; t < b->len[s]; ++t) {
            size_t d = 2 * (c0 + t) + to_half;
            if (v[t] == 0.0 || first + b->lo[s] + t == fixed)
                continue;
            if (lo[d] == UINT32_MAX) {
                lo[d] = to_row;
                dst[n_dst++] = d;
            }
            hi[d] = to_row + 1;
        }
    }
    /* Each segment that receives entries gets a new run: the old one and
     * the landing rows together, zero between. */
    for (k = 0; k < n_dst && st == LL_OK; ++k) {
        uint32_t a, e;
        double *run;
        s = dst[k];
        a = lo[s];
        e = hi[s];
        old[k] = b->seg[s];
        if (b->len[s]) {
            a = b->lo[s] < a ? b->lo[s] : a;
            e = b->lo[s] + b->len[s] > e ? b->lo[s] + b->len[s] : e;
        }
        run = ll_calloc_array(e - a, sizeof(double));
        if (!run) {
            st = ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory mirroring a %zu-node order", n);
            n_dst = k; /* (the ones replaced so far free their old runs) */
            break;
        }
        if (b->len[s])
            memcpy(run + (b->lo[s] - a), old[k], b->len[s] * sizeof(double));
        b->seg[s] = run;
        b->lo[s] = a;
        b->len[s] = e - a;
    }
    for (k = 0; k < n_src && st == LL_OK; ++k) {
        const mirror_source *r = &src[k];
        size_t col = r->seg / 2, first = (r->seg % 2) * h, fixed = mirror_node(col, h);
        size_t to_half = col < h, to_row = col % h, c0 = mirror_node(first + r->lo, h);
        double left = row_scale[mirror_node(col, h)];
        for (t = 0; t < r->len; ++t) {
            size_t d = 2 * (c0 + t) + to_half;
            if (r->val[t] == 0.0 || first + r->lo + t == fixed)
                continue;
            b->seg[d][to_row - b->lo[d]] += r->val[t] * left * col_scale[c0 + t];
        }
    }
    for (k = 0; k < n_dst; ++k)
        ll_free(old[k]);
    return st;
}

/* ------------------------------------------- orders without dense work */

/* Is segment s (= 2 col + half) in a transmission block? */
static int segment_transmits(size_t col, int half, size_t h) { return (col < h) == (half == 0); }

int ll_order_diagonal(const ll_order *o, double *down, double *up)
{
    size_t n, h, col;
    int half;
    if (!o)
        return 0;
    n = o->n;
    h = n / 2;
    for (col = 0; col < n; ++col)
        for (half = 0; half < 2; ++half) {
            const ll_segment *g = &o->seg[2 * col + (size_t)half];
            size_t c = col < h ? col : col - h;
            double *diag = col < h ? up : down;
            if (!segment_transmits(col, half, h)) {
                if (g->len != 0)
                    return 0;
                continue;
            }
            if (g->len == 0)
                diag[c] = 0.0;
            else if (g->len == 1 && g->lo == c)
                diag[c] = o->val[g->off];
            else
                return 0;
        }
    return 1;
}

ll_status ll_order_scaled(const ll_order *o, const double *left, const double *right,
                          double drop, ll_order **out)
{
    size_t n, h, col, total = 0, s;
    int half;
    ll_order *r;
    *out = NULL;
    if (!o)
        return LL_OK;
    n = o->n;
    h = n / 2;
    r = order_alloc(n, ll_order_stored(o) ? ll_order_stored(o) : 1);
    if (!r)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory scaling a %zu x %zu order", n, n);
    for (col = 0; col < n; ++col)
        for (half = 0; half < 2; ++half) {
            const ll_segment *g = &o->seg[2 * col + (size_t)half];
            const double *row_scale = left + (half ? h : 0);
            double *v = r->val + total;
            size_t i, lo, len;
            s = 2 * col + (size_t)half;
            /* (x right) left: the order of the dense products it replaces
             * (adding.c), so the bits are theirs. */
            for (i = 0; i < g->len; ++i)
                v[i] = (o->val[g->off + i] * right[col]) * row_scale[g->lo + i];
            find_run(v, g->len, drop, &lo, &len);
            if (lo > 0 && len > 0)
                memmove(v, v + lo, len * sizeof(double));
            r->seg[s].lo = (uint32_t)(g->lo + lo);
            r->seg[s].len = (uint32_t)len;
            r->seg[s].off = total;
            total += len;
        }
    r->seg[2 * n].off = total;
    if (total == 0)
        ll_order_release(r);
    else
        *out = r;
    return LL_OK;
}

ll_status ll_order_from_diagonals(size_t n, const double *down, const double *up, double drop,
                                  ll_order **out)
{
    size_t h = n / 2, i;
    ll_order *id = NULL;
    double *ones = ll_alloc_array(n, sizeof(double)), *right = ll_alloc_array(n, sizeof(double));
    ll_status s;
    *out = NULL;
    if (!ones || !right) {
        s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory storing a %zu x %zu order", n, n);
        goto done;
    }
    for (i = 0; i < h; ++i) {
        ones[i] = ones[h + i] = 1.0;
        right[i] = up[i];
        right[h + i] = down[i];
    }
    s = ll_order_identity(n, &id);
    if (s == LL_OK)
        s = ll_order_scaled(id, ones, right, drop, out);
done:
    ll_order_release(id);
    ll_free(ones);
    ll_free(right);
    return s;
}

/* ------------------------------------------- builder columns, packed
 * (a distributed build's all-to-all, layer/columns.c): per half column its
 * uint32 lo and len, then len doubles, all copied byte for byte, so the
 * receiving builder holds exactly the run the sending one held. */

size_t ll_order_builder_column_bytes(const ll_order_builder *b, size_t col)
{
    return 4 * sizeof(uint32_t) +
           ((size_t)b->len[2 * col] + (size_t)b->len[2 * col + 1]) * sizeof(double);
}

unsigned char *ll_order_builder_pack_column(const ll_order_builder *b, size_t col,
                                            unsigned char *dst)
{
    size_t s;
    for (s = 2 * col; s < 2 * col + 2; ++s) {
        memcpy(dst, &b->lo[s], sizeof(uint32_t));
        memcpy(dst + sizeof(uint32_t), &b->len[s], sizeof(uint32_t));
        dst += 2 * sizeof(uint32_t);
        if (b->len[s])
            memcpy(dst, b->seg[s], b->len[s] * sizeof(double));
        dst += b->len[s] * sizeof(double);
    }
    return dst;
}

ll_status ll_order_builder_unpack_column(ll_order_builder *b, size_t col,
                                         const unsigned char **src, const unsigned char *end)
{
    const unsigned char *p = *src;
    size_t s, h = b->n / 2;
    for (s = 2 * col; s < 2 * col + 2; ++s) {
        uint32_t lo, len;
        if ((size_t)(end - p) < 2 * sizeof(uint32_t))
            goto truncated;
        memcpy(&lo, p, sizeof lo);
        memcpy(&len, p + sizeof lo, sizeof len);
        p += 2 * sizeof(uint32_t);
        if ((size_t)lo + len > h || (size_t)(end - p) / sizeof(double) < len)
            goto truncated;
        ll_free(b->seg[s]);
        b->seg[s] = NULL;
        b->lo[s] = lo;
        b->len[s] = 0;
        if (len) {
            b->seg[s] = ll_malloc((size_t)len * sizeof(double));
            if (!b->seg[s])
                return ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory receiving an order");
            memcpy(b->seg[s], p, (size_t)len * sizeof(double));
            b->len[s] = len;
        }
        p += (size_t)len * sizeof(double);
    }
    *src = p;
    return LL_OK;
truncated:
    return ll_fail(LL_ERROR_FORMAT, "a received column of an order is malformed");
}
