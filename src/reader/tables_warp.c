/*
 * The piecewise-bilinear 2D warp (tables_warp.h). All sums in double; the
 * renderers compute the same quantities in float, so the two agree to float
 * rounding.
 */
#include "reader/tables_warp.h"

#include <limits.h>
#include <math.h>
#include <stddef.h>
#include <string.h>

/* Keeps the sampler off the exact edges of the square, where the inverse
 * of a vanishing density would be 0 / 0. */
#define LL_WARP_EPSILON 5.9604644775390625e-08 /* 2^-24 */

typedef ll_warp_slices slice_set;

/* The look-ups' steps start on a cache line. Otherwise where they start
 * within a line follows from wherever the code before them in the
 * library ends, and the time of a sample moved with that alone
 * (docs/benchmarks.md, "Table files"). */
#if defined(__GNUC__)
#define LL_WARP_HOT __attribute__((aligned(64)))
#else
#define LL_WARP_HOT
#endif

void ll_warp2d_free(ll_warp2d *wp)
{
    size_t p;
    if (!wp)
        return;
    for (p = 0; p < LL_WARP_MAX_PARAMS; ++p)
        ll_free(wp->param_values[p]);
    ll_free(wp->data); /* cond points into it */
    ll_free(wp->marg);
    ll_free(wp->row_total);
    ll_free(wp->marg_guide);
    ll_free(wp->cond_guide);
    memset(wp, 0, sizeof *wp);
}

/* Running trapezoid integrals of slice k (in units of grid cells), then
 * the division by the total when the slice is sampled. 0 if sampling and
 * the total is not positive. */
static int build_slice(ll_warp2d *wp, size_t k)
{
    size_t w = wp->w, h = wp->h, x, y;
    float *v = wp->data + k * w * h * 2, *c = wp->cond + k * w * h * 2, *m = wp->marg + k * h;
    double total = 0.0, scale, sum, prev_row = 0.0;
    /* Node i of the slice holds its value v[2 i] and its running integral
     * c[2 i] side by side (ll_warp2d.step). The total first (sums in
     * double), then every table divided by it and the running integrals
     * taken over the divided values, so that they are exactly those of
     * the stored density. */
    for (y = 0; y < h; ++y) {
        double row = 0.0;
        for (x = 0; x + 1 < w; ++x)
            row += 0.5 * ((double)v[2 * (y * w + x)] + (double)v[2 * (y * w + x + 1)]);
        if (y > 0)
            total += 0.5 * (prev_row + row);
        prev_row = row;
    }
    if (!(total > 0.0) || !ll_is_finite(total))
        return 0;
    scale = 1.0 / total;
    for (x = 0; x < w * h; ++x)
        v[2 * x] = (float)((double)v[2 * x] * scale);
    for (y = 0; y < h; ++y) {
        sum = 0.0;
        c[2 * (y * w)] = 0.0f;
        for (x = 0; x + 1 < w; ++x) {
            sum += 0.5 * ((double)v[2 * (y * w + x)] + (double)v[2 * (y * w + x + 1)]);
            c[2 * (y * w + x + 1)] = (float)sum;
        }
    }
    sum = 0.0;
    m[0] = 0.0f;
    for (y = 0; y + 1 < h; ++y) {
        sum += 0.5 * ((double)c[2 * (y * w + w - 1)] + (double)c[2 * ((y + 1) * w + w - 1)]);
        m[y + 1] = (float)sum;
    }
    return 1;
}

/* Whether every row of every slice repeats the first row of its slice,
 * compared as stored: the inner values of each node (a sampling warp's
 * node also holds its running integral, step 2, which is not written yet
 * and not a value). */
static int rows_equal(const ll_warp2d *wp)
{
    size_t st = wp->step, row = wp->w * st, plane = row * wp->h, k, y, x;
    for (k = 0; k < wp->n_slices / wp->inner; ++k)
        for (y = 1; y < wp->h; ++y)
            for (x = 0; x < wp->w; ++x)
                if (memcmp(wp->data + k * plane + x * st,
                           wp->data + k * plane + y * row + x * st,
                           wp->inner * sizeof(float)) != 0)
                    return 0;
    return 1;
}

/* The stride of the first round of a search over n nodes (COUNT_SEARCH):
 * about sqrt(n - 1), so that both rounds read about as many values. */
static size_t search_stride(size_t n)
{
    size_t s = 1;
    while (s * s < n - 1)
        ++s;
    return s;
}

/* The buckets of a guide over n nodes: the least power of two >= (n -
 * 1) / 2, so that a bucket of one part holds about two intervals. A power
 * of two makes u times it exact, so that the bucket of u is the one whose
 * targets bracket u. */
static size_t guide_buckets(size_t n)
{
    size_t g = 1;
    while (2 * g < n - 1)
        g *= 2;
    return g;
}

/* Whether the running integrals at v[0], v[st], ... v[(n - 1) st] do not
 * decrease (so that the count of a search is its last node at or below
 * the target, which the guides find). */
static int ascending(const float *v, size_t n, size_t st)
{
    size_t i;
    for (i = 1; i < n; ++i)
        if (!(v[(i - 1) * st] <= v[i * st]))
            return 0;
    return 1;
}

/* Entries 0 .. g of a guide for the running integrals v[0], v[st], ...
 * of n nodes (not decreasing), from entry `first` of wp's guide out:
 * entry j the last i in [0, n - 2] whose value is at most (j / g) total. */
static void guide_of(const ll_warp2d *wp, const float *v, size_t n, size_t st, size_t g,
                     double total, void *out, size_t first)
{
    size_t i = 0, j;
    for (j = 0; j <= g; ++j) {
        double target = (double)j / (double)g * total;
        while (i + 2 < n && (double)v[(i + 1) * st] <= target)
            ++i;
        if (wp->guide_wide)
            ((uint16_t *)out)[first + j] = (uint16_t)i;
        else
            ((unsigned char *)out)[first + j] = (unsigned char)i;
    }
}

/* The guides of a sampling warp (ll_warp2d.marg_guide): 1, or 0 if out of
 * memory. None (1) where a running integral decreases or a node index
 * does not fit 16 bits. */
static int build_guides(ll_warp2d *wp)
{
    size_t w = wp->w, h = wp->h, n = wp->n_slices, gm, gc, k, y, rows, count, bytes;
    if (w - 2 > UINT16_MAX || h - 2 > UINT16_MAX)
        return 1;
    for (k = 0; k < n; ++k) {
        if (!ascending(wp->marg + k * h, h, 1))
            return 1;
        for (y = 0; y < h; ++y)
            if (!ascending(wp->cond + (k * h + y) * w * 2, w, 2))
                return 1;
    }
    wp->guide_wide = w - 2 > UCHAR_MAX || h - 2 > UCHAR_MAX;
    bytes = wp->guide_wide ? sizeof(uint16_t) : 1;
    gm = guide_buckets(h);
    gc = guide_buckets(w);
    rows = n * h; /* the tables' own size, checked at init */
    if (!ll_size_mul(n, gm + 1, &count) || !(wp->marg_guide = ll_alloc_array(count, bytes)))
        return 0;
    if (!ll_size_mul(rows, gc + 1, &count) || !(wp->cond_guide = ll_alloc_array(count, bytes)))
        return 0;
    wp->marg_buckets = gm;
    wp->cond_buckets = gc;
    for (k = 0; k < n; ++k)
        guide_of(wp, wp->marg + k * h, h, 1, gm, 1.0, wp->marg_guide, k * (gm + 1));
    for (k = 0; k < rows; ++k)
        guide_of(wp, wp->cond + k * w * 2, w, 2, gc, (double)wp->row_total[k], wp->cond_guide,
                 k * (gc + 1));
    return 1;
}

ll_status ll_warp2d_init(ll_warp2d *wp, size_t w, size_t h, size_t n_params,
                         const size_t *param_size, const double *const *params, ll_warp_get get,
                         const void *ctx, int sampling)
{
    size_t p, k, n = 1, total;
    memset(wp, 0, sizeof *wp);
    wp->w = w;
    wp->h = h;
    wp->inv_cells[0] = 1.0 / (double)(w - 1);
    wp->inv_cells[1] = 1.0 / (double)(h - 1);
    wp->area = 1.0;
    wp->n_params = n_params;
    for (p = 0; p < n_params; ++p) {
        wp->param_size[p] = param_size[p];
        if (!ll_size_mul(n, param_size[p], &n))
            return ll_fail(LL_ERROR_FORMAT, "the slice count overflows");
        wp->param_values[p] = ll_alloc_array(param_size[p], sizeof(double));
        if (!wp->param_values[p])
            goto oom;
        memcpy(wp->param_values[p], params[p], param_size[p] * sizeof(double));
    }
    wp->n_slices = n;
    if (!ll_size_mul(w, h, &total) || !ll_size_mul(total, n, &total))
        return ll_fail(LL_ERROR_FORMAT, "the table size overflows");
    wp->inner = !sampling && n_params > 0 ? param_size[n_params - 1] : 1;
    wp->step = sampling ? 2 : wp->inner;
    if (sampling && !ll_size_mul(total, 2, &total))
        return ll_fail(LL_ERROR_FORMAT, "the table size overflows");
    if (!ll_size_mul(total, sizeof(float), &total))
        return ll_fail(LL_ERROR_FORMAT, "the table size overflows");
    wp->data = ll_malloc_large(total);
    if (!wp->data)
        goto oom;
    {
        /* Entry k of the caller's layout, slice (outer, j) at node at, goes
         * to ((outer w h) + at) step + j. */
        size_t area = w * h, in = wp->inner, st = wp->step, outer, j, at;
        for (k = 0, outer = 0; outer < n / in; ++outer)
            for (j = 0; j < in; ++j) {
                float *to = wp->data + outer * area * st + j;
                for (at = 0; at < area; ++at, ++k)
                    to[at * st] = (float)get(ctx, k);
            }
    }
    wp->rows_equal = rows_equal(wp);
    if (!sampling)
        return LL_OK;
    wp->normalized = 1;
    wp->area = (double)(w - 1) * (double)(h - 1);
    wp->cond = wp->data + 1;
    wp->marg = ll_alloc_array(n * h, sizeof(float));
    wp->row_total = ll_alloc_array(n * h, sizeof(float));
    if (!wp->marg || !wp->row_total)
        goto oom;
    for (k = 0; k < n; ++k)
        if (!build_slice(wp, k))
            return ll_fail(LL_ERROR_FORMAT, "slice %zu has no positive finite integral", k);
    for (k = 0; k < n * h; ++k)
        wp->row_total[k] = wp->cond[(k * w + w - 1) * 2];
    wp->marg_stride = search_stride(h);
    wp->guide_stride = search_stride(w);
    if (!build_guides(wp))
        goto oom;
    return LL_OK;
oom:
    return ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory (%zu x %zu table)", w, h);
}

void ll_warp2d_slices(const ll_warp2d *wp, const double *param, slice_set *s)
{
    size_t p, c, idx[LL_WARP_MAX_PARAMS];
    double t[LL_WARP_MAX_PARAMS];
    /* An isotropic file's incident slices: one azimuth, so only the
     * elevation's two neighbours, with the weights the general loop below
     * gives them (1 (1 - t) and 1 t), without its eight corners. */
    if (wp->n_params == 2 && wp->param_size[0] == 1) {
        ll_warp_locate(wp->param_values[1], wp->param_size[1], param[1], &idx[1], &t[1]);
        s->count = 0;
        if (1.0 - t[1] != 0.0) {
            s->index[s->count] = idx[1];
            s->weight[s->count++] = 1.0 - t[1];
        }
        if (t[1] != 0.0 && wp->param_size[1] > 1) {
            s->index[s->count] = idx[1] + 1;
            s->weight[s->count++] = t[1];
        }
        return;
    }
    for (p = 0; p < wp->n_params; ++p)
        ll_warp_locate(wp->param_values[p], wp->param_size[p], param[p], &idx[p], &t[p]);
    /* Only the corners of non-zero weight are kept: an isotropic file's
     * single azimuth and a channel index that hits its node exactly leave
     * two of the eight, and every look-up then reads two slices. */
    s->count = 0;
    for (c = 0; c < ((size_t)1 << wp->n_params); ++c) {
        size_t index = 0;
        double weight = 1.0;
        for (p = 0; p < wp->n_params; ++p) {
            int upper = (int)((c >> (wp->n_params - 1 - p)) & 1u);
            size_t i = idx[p] + (size_t)upper;
            if (upper && wp->param_size[p] < 2) {
                weight = 0.0;
                i = idx[p];
            }
            weight *= upper ? t[p] : 1.0 - t[p];
            index = index * wp->param_size[p] + i;
        }
        if (weight != 0.0) {
            s->index[s->count] = index;
            s->weight[s->count] = weight;
            ++s->count;
        }
    }
}

/* One array's slices of a slice set, as pointers: a look-up mixes the
 * same slices at many places (a search reads a row at every step), so
 * the offsets are taken once. This general form serves sets of more than
 * two slices (anisotropic files); two or fewer take the pair below. */
typedef struct slice_rows {
    size_t count;
    size_t step;                              /* floats from one node to the next */
    const float *p[1 << LL_WARP_MAX_PARAMS];
    double w[1 << LL_WARP_MAX_PARAMS];
} slice_rows;

static void rows_of(const slice_set *s, const float *arr, size_t stride, size_t step,
                    slice_rows *out)
{
    size_t c;
    out->count = s->count;
    out->step = step;
    for (c = 0; c < s->count; ++c) {
        out->p[c] = arr + s->index[c] * stride;
        out->w[c] = s->weight[c];
    }
}

/* The values' slices (ll_warp2d.inner: slice i is (i / inner, i % inner)). */
static void data_rows_of(const ll_warp2d *wp, const slice_set *s, slice_rows *out)
{
    size_t c, in = wp->inner, area = wp->w * wp->h, st = wp->step;
    out->count = s->count;
    out->step = st;
    for (c = 0; c < s->count; ++c) {
        out->p[c] = wp->data + (s->index[c] / in) * area * st + s->index[c] % in;
        out->w[c] = s->weight[c];
    }
}

static inline double mix(const slice_rows *r, size_t node)
{
    size_t c, at = node * r->step;
    double v = 0.0;
    for (c = 0; c < r->count; ++c)
        v += r->w[c] * (double)r->p[c][at];
    return v;
}

/* Two slices (an isotropic file's two neighbouring elevations; one slice
 * is the pair with a second of weight 0 at the same place): the common
 * look-up, without loops or branches. w0 a + w1 b is the general sum to
 * the bit (0 + w0 a + w1 b, and w0 a + 0 b = 0 + w0 a for the finite
 * values stored), so both forms give the same numbers. */
typedef struct slice_pair {
    const float *p0, *p1;
    double w0, w1;
    size_t step;                              /* floats from one node to the next */
} slice_pair;

static inline double pmix(const slice_pair *q, size_t at)
{
    return q->w0 * (double)q->p0[at] + q->w1 * (double)q->p1[at];
}

/* The pair of an array whose slice i starts at arr + i * stride, for a
 * set of one or two slices. */
static void pair_of(const slice_set *s, const float *arr, size_t stride, size_t step,
                    slice_pair *q)
{
    q->step = step;
    q->p0 = arr + s->index[0] * stride;
    q->w0 = s->weight[0];
    if (s->count == 2) {
        q->p1 = arr + s->index[1] * stride;
        q->w1 = s->weight[1];
    } else {
        q->p1 = q->p0;
        q->w1 = 0.0;
    }
}

/* The same for the values (ll_warp2d.inner), the division only where an
 * inner parameter makes it needed. */
static int data_pair_of(const ll_warp2d *wp, const slice_set *s, slice_pair *q)
{
    size_t in = wp->inner, area = wp->w * wp->h, st = wp->step;
    if (s->count > 2)
        return 0;
    if (in == 1) {
        pair_of(s, wp->data, area * st, st, q);
        return 1;
    }
    q->step = st;
    q->p0 = wp->data + (s->index[0] / in) * area * st + s->index[0] % in;
    q->w0 = s->weight[0];
    q->p1 = s->count == 2 ? wp->data + (s->index[1] / in) * area * st + s->index[1] % in
                          : q->p0;
    q->w1 = s->count == 2 ? s->weight[1] : 0.0;
    return 1;
}

/* A node index to double and a non-negative double below the node count
 * to its index, through the signed type: the indices lie far below 2^53,
 * where both conversions are exact, and x86-64 converts a signed integer
 * in one instruction but an unsigned one with a branch and several (these
 * run a few times in every look-up). */
static inline double index_to_double(size_t i) { return (double)(ptrdiff_t)i; }

static inline size_t double_to_index(double f) { return (size_t)(ptrdiff_t)f; }

/* Cell and fraction of coordinate x in [0, 1] over n nodes. */
static inline size_t cell(double x, size_t n, double *t)
{
    double f;
    size_t i;
    if (!(x > 0.0))
        x = 0.0;
    if (x > 1.0)
        x = 1.0;
    f = x * index_to_double(n - 1);
    i = double_to_index(f);
    if (i > n - 2)
        i = n - 2;
    *t = f - index_to_double(i);
    return i;
}

/* The bilinear value in cell (r, c) at (tx, ty) of one array's slices. */
static double bilinear_rows(const slice_rows *d, size_t w, size_t r, double ty, size_t c,
                            double tx)
{
    size_t at = r * w + c;
    double v00 = mix(d, at), v01 = mix(d, at + 1), v10 = mix(d, at + w);
    double v11 = mix(d, at + w + 1);
    return (1.0 - ty) * ((1.0 - tx) * v00 + tx * v01) + ty * ((1.0 - tx) * v10 + tx * v11);
}

/* The same for a pair whose nodes lie step floats apart. */
static inline double bilinear_pair(const slice_pair *q, size_t step, size_t w, size_t r,
                                   double ty, size_t c, double tx)
{
    size_t at = (r * w + c) * step, down = w * step;
    double v00 = pmix(q, at), v01 = pmix(q, at + step), v10 = pmix(q, at + down);
    double v11 = pmix(q, at + down + step);
    return (1.0 - ty) * ((1.0 - tx) * v00 + tx * v01) + ty * ((1.0 - tx) * v10 + tx * v11);
}

/* Density per unit area of the square for a sampling warp (slices hold
 * values per cell area, total 1), the value itself otherwise. */
static double area_scale(const ll_warp2d *wp)
{
    return wp->area;
}

void ll_warp_slices_append(const slice_set *s, size_t k, size_t n, slice_set *out)
{
    size_t c;
    out->count = s->count;
    for (c = 0; c < s->count; ++c) {
        out->index[c] = s->index[c] * n + k;
        out->weight[c] = s->weight[c];
    }
}

double ll_warp2d_eval_at(const ll_warp2d *wp, const slice_set *s, const double pos[2])
{
    double tx, ty;
    size_t c = cell(pos[0], wp->w, &tx), r = cell(pos[1], wp->h, &ty);
    slice_pair q;
    slice_rows d;
    if (data_pair_of(wp, s, &q))
        return bilinear_pair(&q, q.step, wp->w, r, ty, c, tx) * area_scale(wp);
    data_rows_of(wp, s, &d);
    return bilinear_rows(&d, wp->w, r, ty, c, tx) * area_scale(wp);
}

/* The four corner nodes of cell (r, c) of a pair whose nodes lie step
 * floats apart, and the weights that give the bilinear value of the pair
 * there as one sum: sum_j w[j] p[j][0]. */
static void corners(const slice_pair *q, size_t step, size_t w, size_t r, double ty, size_t c,
                    double tx, const float *p[8], double wt[8])
{
    size_t at = (r * w + c) * step, down = w * step;
    double a = (1.0 - ty) * (1.0 - tx), b = (1.0 - ty) * tx, d = ty * (1.0 - tx), e = ty * tx;
    p[0] = q->p0 + at;
    p[1] = q->p0 + at + step;
    p[2] = q->p0 + at + down;
    p[3] = q->p0 + at + down + step;
    p[4] = q->p1 + at;
    p[5] = q->p1 + at + step;
    p[6] = q->p1 + at + down;
    p[7] = q->p1 + at + down + step;
    wt[0] = q->w0 * a;
    wt[1] = q->w0 * b;
    wt[2] = q->w0 * d;
    wt[3] = q->w0 * e;
    wt[4] = q->w1 * a;
    wt[5] = q->w1 * b;
    wt[6] = q->w1 * d;
    wt[7] = q->w1 * e;
}

LL_WARP_HOT void ll_warp2d_eval_nodes(const ll_warp2d *wp, const slice_set *s, size_t n,
                          const double pos[2], double *out)
{
    double tx, ty, scale = area_scale(wp);
    size_t c = cell(pos[0], wp->w, &tx), r = cell(pos[1], wp->h, &ty), st = wp->w * wp->h, k, j;
    slice_rows d;
    /* Channel k of slice index i is slice i n + k (ll_warp_slices_append);
     * with the channels innermost (n == inner) it sits k floats after
     * channel 0 at every node, else a whole table after it. */
    size_t next = n == wp->inner ? 1 : st;
    slice_set first;
    if (n == wp->inner && s->count <= 2) {
        /* The channels of a node share its cache line, and the weights of
         * the eight (slice, corner) nodes are the same for each: one sum of
         * eight products per channel (the bilinear value of the mixed
         * slices to rounding). */
        slice_pair q;
        const float *p[8];
        double wt[8];
        size_t plane = st * n;
        q.p0 = wp->data + s->index[0] * plane;
        q.w0 = s->weight[0];
        q.p1 = s->count == 2 ? wp->data + s->index[1] * plane : q.p0;
        q.w1 = s->count == 2 ? s->weight[1] : 0.0;
        if (n == 3) {
            /* An RGB table: the three sums side by side, straight. */
            size_t at = (r * wp->w + c) * 3, down = wp->w * 3;
            const float *a = q.p0 + at, *b = q.p1 + at;
            double ty1 = 1.0 - ty, tx1 = 1.0 - tx;
            double a0 = q.w0 * ty1 * tx1, a1 = q.w0 * ty1 * tx, a2 = q.w0 * ty * tx1;
            double a3 = q.w0 * ty * tx, b0 = q.w1 * ty1 * tx1, b1 = q.w1 * ty1 * tx;
            double b2 = q.w1 * ty * tx1, b3 = q.w1 * ty * tx;
            for (k = 0; k < 3; ++k)
                out[k] = (a0 * (double)a[k] + a1 * (double)a[3 + k] + a2 * (double)a[down + k] +
                          a3 * (double)a[down + 3 + k] + b0 * (double)b[k] +
                          b1 * (double)b[3 + k] + b2 * (double)b[down + k] +
                          b3 * (double)b[down + 3 + k]) *
                         scale;
            return;
        }
        corners(&q, n, wp->w, r, ty, c, tx, p, wt);
        for (k = 0; k < n; ++k) {
            double v = 0.0;
            for (j = 0; j < 8; ++j)
                v += wt[j] * (double)p[j][k];
            out[k] = v * scale;
        }
        return;
    }
    ll_warp_slices_append(s, 0, n, &first);
    data_rows_of(wp, &first, &d);
    for (k = 0; k < n; ++k) {
        out[k] = bilinear_rows(&d, wp->w, r, ty, c, tx) * scale;
        for (j = 0; j < d.count; ++j)
            d.p[j] += next;
    }
}

void ll_warp2d_prefetch_nodes(const ll_warp2d *wp, const slice_set *s, const double pos[2])
{
#if defined(__GNUC__)
    double tx, ty;
    size_t c = cell(pos[0], wp->w, &tx), r = cell(pos[1], wp->h, &ty), in = wp->step, j;
    size_t plane = wp->w * wp->h * in, at = (r * wp->w + c) * in, down = wp->w * in;
    if (s->count > 2)
        return;
    for (j = 0; j < s->count; ++j) {
        /* Both nodes of each row: their first and last floats. */
        const float *p = wp->data + s->index[j] * plane + at;
        __builtin_prefetch(p);
        __builtin_prefetch(p + 2 * in - 1);
        __builtin_prefetch(p + down);
        __builtin_prefetch(p + down + 2 * in - 1);
    }
#else
    (void)wp;
    (void)s;
    (void)pos;
#endif
}

double ll_warp2d_eval_single(const ll_warp2d *wp, const double pos[2])
{
    double tx, ty, scale = area_scale(wp);
    size_t st = wp->step, w = wp->w * st, c = cell(pos[0], wp->w, &tx), r;
    const float *d = wp->data + c * st;
    if (wp->rows_equal)
        return ((1.0 - tx) * (double)d[0] + tx * (double)d[st]) * scale;
    r = cell(pos[1], wp->h, &ty);
    d += r * w;
    return ((1.0 - ty) * ((1.0 - tx) * (double)d[0] + tx * (double)d[st]) +
            ty * ((1.0 - tx) * (double)d[w] + tx * (double)d[w + st])) *
           scale;
}

void ll_warp_slices_single(slice_set *s)
{
    s->count = 1;
    s->index[0] = 0;
    s->weight[0] = 1.0;
}

double ll_warp2d_eval(const ll_warp2d *wp, const double pos[2], const double *param)
{
    slice_set s;
    ll_warp2d_slices(wp, param, &s);
    return ll_warp2d_eval_at(wp, &s, pos);
}

/* The stored running integrals are float sums, so a cell's stored mass
 * (the difference of its two ends) and the mass of its linear density
 * (the mean of its end values) differ by rounding. sample and invert
 * scale the inside of a cell by their ratio linear / stored, which keeps
 * the two exact inverses of each other whatever the rounding; the ratio
 * is 1 for an empty cell. cell_masses gives the pair (stored, linear)
 * whose ratio that is, both 1 for an empty cell, so that the callers
 * fold the ratio into their one division instead of dividing for it
 * first (a division waits for the one before it: a sample is a chain of
 * them). */
static inline void cell_masses(double stored, double linear, double *s, double *l)
{
    int full = stored > 0.0 && linear > 0.0;
    *s = full ? stored : 1.0;
    *l = full ? linear : 1.0;
}

/* The t in [0, 1] where the integral of the linear density a + (b - a) t
 * from 0 reaches d linear / stored (d scaled by the cell's mass ratio,
 * cell_masses), in the form without cancellation, 2 e / (a + sqrt(a^2 +
 * 2 (b - a) e)) for e = d l / s, multiplied through by s > 0: one
 * division and one square root. */
static double invert_linear(double a, double b, double d, double stored, double linear)
{
    double s, l, dl, disc, den, t;
    cell_masses(stored, linear, &s, &l);
    dl = d * l;
    disc = s * (s * a * a + 2.0 * (b - a) * dl);
    if (!(disc > 0.0))
        disc = 0.0;
    den = s * a + sqrt(disc);
    t = den > 0.0 ? 2.0 * dl / den : 0.0;
    if (!(t > 0.0))
        t = 0.0;
    return t > 1.0 ? 1.0 : t;
}

/* The inverse's share of the cell: m0 + x / ratio (x the mass of the
 * linear density up to the point), and the same divided by total (> 0)
 * in one division. */
static inline double uninvert_row(double m0, double x, double stored, double linear)
{
    double s, l;
    cell_masses(stored, linear, &s, &l);
    return m0 + x * s / l;
}

static inline double uninvert_column(double cdf, double x, double stored, double linear,
                                     double total)
{
    double s, l;
    if (!(total > 0.0))
        return 0.0;
    cell_masses(stored, linear, &s, &l);
    return (cdf * l + x * s) / (l * total);
}

/* Largest i in [0, n - 2] with value(i) <= target (0 if none), for
 * values that do not decrease with i (running integrals of non-negative
 * densities, mixed with non-negative weights). Halving a range whose
 * length does not depend on the data compiles without a data-dependent
 * branch; the searches dominate a sample's cost. */
#define SEARCH(n, value, target, out)                                                     \
    do {                                                                                  \
        size_t lo_ = 0, len_ = (n) - 1;                                                   \
        while (len_ > 1) {                                                                \
            size_t half_ = len_ / 2, i = lo_ + half_;                                     \
            lo_ = (value) <= (target) ? i : lo_;                                          \
            len_ -= half_;                                                                \
        }                                                                                 \
        (out) = lo_;                                                                      \
    } while (0)

/* Rows r and r + 1 (r0 = r w: their first entry) of one array's slices
 * interpolated at ty, at column i: a conditional integral or a value of
 * the row at ty. */
static inline double pair_at(const slice_rows *a, size_t r0, size_t w, double ty, size_t i)
{
    return (1.0 - ty) * mix(a, r0 + i) + ty * mix(a, r0 + w + i);
}

static inline double pair_at2(const slice_pair *a, size_t r0, size_t w, double ty, size_t i)
{
    return (1.0 - ty) * pmix(a, (r0 + i) * a->step) + ty * pmix(a, (r0 + w + i) * a->step);
}

void ll_warp2d_sample(const ll_warp2d *wp, const double u[2], const double *param,
                      double pos[2], double *pdf)
{
    slice_set s;
    ll_warp2d_slices(wp, param, &s);
    ll_warp2d_sample_at(wp, &s, u, pos, pdf);
}

void ll_warp2d_invert(const ll_warp2d *wp, const double pos[2], const double *param,
                      double u[2], double *pdf)
{
    slice_set s;
    ll_warp2d_slices(wp, param, &s);
    ll_warp2d_invert_at(wp, &s, pos, u, pdf);
}

/* SEARCH's answer for values that do not decrease with i, found as the
 * count of i in [1, n - 2] with value(i) <= target (which is what the
 * halving finds for such values), in two rounds: the multiples of stride
 * first (first(j): value(j stride), j >= 1), then the stride - 1 nodes
 * after the last of them that is <= target. Every value of a round is
 * independent of the others, so their reads overlap, where a halving
 * waits for each before it knows the next; whatever the values, out
 * stays in [0, n - 2]. */
#define COUNT_SEARCH(n, stride, first, value, target, out)                                \
    do {                                                                                  \
        size_t base_;                                                                     \
        COUNT_SEARCH_FIRST(n, stride, first, target, base_);                              \
        COUNT_SEARCH_REST(n, stride, base_, value, target, out);                          \
    } while (0)
/* Its two rounds apart (a caller can ask for the stretch the first
 * round leaves before the second reads it): the first gives the last
 * multiple of stride whose value is <= target (0 if none) in base_out,
 * the second the answer from there. */
#define COUNT_SEARCH_FIRST(n, stride, first, target, base_out)                            \
    do {                                                                                  \
        size_t rounds_ = ((n) - 2) / (stride), j;                                         \
        (base_out) = 0;                                                                   \
        for (j = 1; j <= rounds_; ++j)                                                    \
            (base_out) += (first) <= (target) ? (stride) : 0;                             \
    } while (0)
#define COUNT_SEARCH_REST(n, stride, base, value, target, out)                            \
    do {                                                                                  \
        size_t last_ = (n) - 2, count_ = 0, end_, i;                                      \
        end_ = (base) + (stride) <= last_ ? (base) + (stride) : last_ + 1;                \
        for (i = (base) + 1; i < end_; ++i)                                               \
            count_ += (value) <= (target);                                                \
        (out) = (base) + count_;                                                          \
    } while (0)

/* COUNT_SEARCH's answer from the stretch lo .. hi of a guide (lo <= hi
 * <= n - 2): where value(lo) <= target (or lo is 0, which is not counted)
 * and value(hi + 1) > target (or hi is n - 2), the last i in lo .. hi
 * with value(i) <= target, found by halving, which for values that do
 * not decrease is the whole search's count; ok_out 1 then. ok_out 0 (out
 * unset) where the ends do not bracket the target: the whole search
 * decides. */
#define GUIDED_SEARCH(n, lo, hi, value, target, out, ok_out)                              \
    do {                                                                                  \
        size_t lo_ = (lo), hi_ = (hi), count_ = 0, i;                                     \
        (ok_out) = 0;                                                                     \
        i = lo_;                                                                          \
        if (lo_ == 0 || (value) <= (target)) {                                            \
            i = hi_ + 1;                                                                  \
            if (hi_ >= (n) - 2 || !((value) <= (target))) {                               \
                for (i = lo_ + 1; i <= hi_; ++i)                                          \
                    count_ += (value) <= (target);                                        \
                (out) = lo_ + count_;                                                     \
                (ok_out) = 1;                                                             \
            }                                                                             \
        }                                                                                 \
    } while (0)

/* The bucket of u in [0, 1) among g (a power of two: u g is exact). */
static inline size_t bucket_of(double u, size_t g)
{
    size_t j = double_to_index(u * index_to_double(g));
    return j < g ? j : g - 1;
}

static inline size_t min2(size_t a, size_t b) { return a < b ? a : b; }

static inline size_t max2(size_t a, size_t b) { return a > b ? a : b; }

/* sample_at for a pair of slices, in three steps split where they wait
 * on memory: sample_pair_row finds the row interval r from the marginal
 * and its guide (small, read in place); sample_pair_guide the row's
 * fraction and the stretch of the column search from the rows' guides
 * (small too; without guides, the whole search's first round);
 * sample_pair_rest the column and the point from rows r and r + 1 of the
 * table of megabytes. The general form's arithmetic, in the same order,
 * so both give the same numbers; the searches find what COUNT_SEARCH
 * finds. */
static inline LL_WARP_HOT size_t sample_pair_row(const ll_warp2d *wp, const slice_set *s,
                                                  const double u[2])
{
    size_t h = wp->h, hs = wp->marg_stride, r;
    double target = u[1];
    slice_pair marg;
    pair_of(s, wp->marg, h, 1, &marg);
    if (wp->marg_guide) {
        /* Both slices' answers for the bucket of u[1]. */
        const void *gd = wp->marg_guide;
        size_t g = wp->marg_buckets, j = bucket_of(target, g);
        size_t a = s->index[0] * (g + 1) + j, b = s->index[s->count == 2] * (g + 1) + j;
        int ok;
        GUIDED_SEARCH(h, min2(ll_warp_guide_entry(wp, gd, a), ll_warp_guide_entry(wp, gd, b)),
                      max2(ll_warp_guide_entry(wp, gd, a + 1), ll_warp_guide_entry(wp, gd, b + 1)),
                      pmix(&marg, i), target, r, ok);
        if (ok)
            return r;
    }
    COUNT_SEARCH(h, hs, pmix(&marg, j * hs), pmix(&marg, i), target, r);
    return r;
}

static inline LL_WARP_HOT void sample_pair_guide(const ll_warp2d *wp, const slice_set *s,
                                                  const double u[2],
                                     ll_warp_draw *dr)
{
    size_t w = wp->w, h = wp->h, st = w * h, r = dr->r, at = r * w, gs = wp->guide_stride;
    double target = u[1], r0, r1, ty, row_total, m0, m1;
    slice_pair marg, tot, cond;
    pair_of(s, wp->marg, h, 1, &marg);
    pair_of(s, wp->row_total, h, 1, &tot);
    pair_of(s, wp->cond, 2 * st, 2, &cond);
    r0 = pmix(&tot, r);
    r1 = pmix(&tot, r + 1);
    m0 = pmix(&marg, r);
    m1 = pmix(&marg, r + 1);
    ty = invert_linear(r0, r1, target - m0, m1 - m0, 0.5 * (r0 + r1));
    row_total = (1.0 - ty) * r0 + ty * r1;
    target = u[0] * row_total;
    dr->ty = ty;
    dr->target = target;
    dr->guided = wp->cond_guide != NULL;
    if (dr->guided) {
        /* The answers of rows r and r + 1 of both slices for the bucket
         * of u[0] (the blend's target is u[0] times its blended total). */
        const void *gd = wp->cond_guide;
        size_t g = wp->cond_buckets, row = g + 1, j = bucket_of(u[0], g);
        size_t a = (s->index[0] * h + r) * row + j, b = (s->index[s->count == 2] * h + r) * row + j;
        dr->base = min2(min2(ll_warp_guide_entry(wp, gd, a), ll_warp_guide_entry(wp, gd, a + row)),
                        min2(ll_warp_guide_entry(wp, gd, b), ll_warp_guide_entry(wp, gd, b + row)));
        dr->top = max2(max2(ll_warp_guide_entry(wp, gd, a + 1),
                            ll_warp_guide_entry(wp, gd, a + row + 1)),
                       max2(ll_warp_guide_entry(wp, gd, b + 1),
                            ll_warp_guide_entry(wp, gd, b + row + 1)));
        return;
    }
    COUNT_SEARCH_FIRST(w, gs, pair_at2(&cond, at, w, ty, j * gs), target, dr->base);
    dr->top = min2(dr->base + gs - 1, w - 2);
}

static inline LL_WARP_HOT void sample_pair_rest(const ll_warp2d *wp, const slice_set *s,
                                    const ll_warp_draw *dr, double pos[2], double *pdf)
{
    size_t w = wp->w, h = wp->h, st = w * h, c = 0, r = dr->r, at = r * w, gs = wp->guide_stride;
    double target = dr->target, ty = dr->ty, tx, v0, v1, cdf_c, cdf_c1;
    int ok = 0;
    slice_pair cond, data;
    pair_of(s, wp->cond, 2 * st, 2, &cond);
    pair_of(s, wp->data, 2 * st, 2, &data);
    if (dr->guided)
        GUIDED_SEARCH(w, dr->base, dr->top, pair_at2(&cond, at, w, ty, i), target, c, ok);
    if (!dr->guided)
        COUNT_SEARCH_REST(w, gs, dr->base, pair_at2(&cond, at, w, ty, i), target, c);
    else if (!ok)
        COUNT_SEARCH(w, gs, pair_at2(&cond, at, w, ty, j * gs), pair_at2(&cond, at, w, ty, i),
                     target, c);
    cdf_c = pair_at2(&cond, at, w, ty, c);
    cdf_c1 = pair_at2(&cond, at, w, ty, c + 1);
    v0 = pair_at2(&data, at, w, ty, c);
    v1 = pair_at2(&data, at, w, ty, c + 1);
    tx = invert_linear(v0, v1, target - cdf_c, cdf_c1 - cdf_c, 0.5 * (v0 + v1));
    pos[0] = (index_to_double(c) + tx) * wp->inv_cells[0];
    pos[1] = (index_to_double(r) + ty) * wp->inv_cells[1];
    *pdf = ((1.0 - tx) * v0 + tx * v1) * area_scale(wp);
}

/* u_in kept off the edges of the square, as the renderers' samplers keep
 * it. */
static inline void off_edges(const double u_in[2], double u[2])
{
    int k;
    for (k = 0; k < 2; ++k) {
        u[k] = u_in[k];
        if (!(u[k] >= LL_WARP_EPSILON))
            u[k] = LL_WARP_EPSILON;
        if (u[k] > 1.0 - LL_WARP_EPSILON)
            u[k] = 1.0 - LL_WARP_EPSILON;
    }
}

static void sample_general(const ll_warp2d *wp, const slice_set *s, const double u[2],
                           double pos[2], double *pdf);

void ll_warp2d_draw_begin(const ll_warp2d *wp, const slice_set *s, const double u_in[2],
                          ll_warp_draw *dr)
{
    off_edges(u_in, dr->u);
    if (s->count > 2)
        return;
    dr->r = sample_pair_row(wp, s, dr->u);
    sample_pair_guide(wp, s, dr->u, dr);
}

void ll_warp2d_prefetch_draw(const ll_warp2d *wp, const slice_set *s, const ll_warp_draw *dr)
{
#if defined(__GNUC__)
    size_t w = wp->w, plane = 2 * w * wp->h, j, end = dr->top + 1;
    if (s->count > 2)
        return;
    /* Nodes base .. top + 1 of rows r and r + 1 (the stretch and the node
     * after it that settles the search; the two after its answer are
     * among them), each with its running integral. */
    for (j = 0; j < s->count; ++j) {
        const float *p = wp->data + s->index[j] * plane + 2 * (dr->r * w + dr->base);
        size_t n = 2 * (end - dr->base + 1), k;
        /* Its first and last floats, and every line between (none for a
         * stretch of up to 16 floats: two lines at most). */
        __builtin_prefetch(p);
        __builtin_prefetch(p + n - 1);
        __builtin_prefetch(p + 2 * w);
        __builtin_prefetch(p + 2 * w + n - 1);
        for (k = 16; k + 1 < n; k += 16) {
            __builtin_prefetch(p + k);
            __builtin_prefetch(p + 2 * w + k);
        }
    }
#else
    (void)wp;
    (void)s;
    (void)dr;
#endif
}

void ll_warp2d_draw_end(const ll_warp2d *wp, const slice_set *s, const ll_warp_draw *dr,
                        double pos[2], double *pdf)
{
    if (s->count > 2)
        sample_general(wp, s, dr->u, pos, pdf);
    else
        sample_pair_rest(wp, s, dr, pos, pdf);
}

LL_WARP_HOT void ll_warp2d_sample_at(const ll_warp2d *wp, const slice_set *s, const double u_in[2],
                         double pos[2], double *pdf)
{
    ll_warp_draw dr;
    off_edges(u_in, dr.u);
    if (s->count > 2) {
        sample_general(wp, s, dr.u, pos, pdf);
        return;
    }
    dr.r = sample_pair_row(wp, s, dr.u);
    /* The stretch of rows r and r + 1 that the column search reads, as
     * soon as the guide gives it (a few lines, where the whole rows were
     * about forty that crowded the caches). */
    sample_pair_guide(wp, s, dr.u, &dr);
    ll_warp2d_prefetch_draw(wp, s, &dr);
    sample_pair_rest(wp, s, &dr, pos, pdf);
}

/* Three or more slices (an anisotropic file), u already kept off the
 * edges. */
static void sample_general(const ll_warp2d *wp, const slice_set *s, const double u[2],
                           double pos[2], double *pdf)
{
    size_t w = wp->w, h = wp->h, st = w * h, r, c;
    double target, r0, r1, ty, tx, row_total, v0, v1, cdf_c, cdf_c1, m0, m1;
    slice_rows marg, cond, data;
    rows_of(s, wp->marg, h, 1, &marg);
    rows_of(s, wp->cond, 2 * st, 2, &cond);
    data_rows_of(wp, s, &data);
    /* Row interval from the marginal (slices are normalised: total 1). */
    target = u[1];
    SEARCH(h, mix(&marg, i), target, r);
    r0 = mix(&cond, r * w + w - 1);
    r1 = mix(&cond, (r + 1) * w + w - 1);
    m0 = mix(&marg, r);
    m1 = mix(&marg, r + 1);
    ty = invert_linear(r0, r1, target - m0, m1 - m0, 0.5 * (r0 + r1));
    /* Column interval from the conditional row at ty. */
    row_total = (1.0 - ty) * r0 + ty * r1;
    target = u[0] * row_total;
    SEARCH(w, pair_at(&cond, r * w, w, ty, i), target, c);
    cdf_c = pair_at(&cond, r * w, w, ty, c);
    cdf_c1 = pair_at(&cond, r * w, w, ty, c + 1);
    v0 = pair_at(&data, r * w, w, ty, c);
    v1 = pair_at(&data, r * w, w, ty, c + 1);
    tx = invert_linear(v0, v1, target - cdf_c, cdf_c1 - cdf_c, 0.5 * (v0 + v1));
    pos[0] = (index_to_double(c) + tx) * wp->inv_cells[0];
    pos[1] = (index_to_double(r) + ty) * wp->inv_cells[1];
    *pdf = ((1.0 - tx) * v0 + tx * v1) * area_scale(wp);
}

/* invert_at for a pair of slices, as sample_pair. */
static void invert_pair(const ll_warp2d *wp, const slice_set *s, const double pos[2],
                        double u[2], double *pdf)
{
    size_t w = wp->w, h = wp->h, st = w * h;
    double tx, ty, r0, r1, v0, v1, cdf_c, cdf_c1, row_total, m0, m1;
    size_t c = cell(pos[0], w, &tx), r = cell(pos[1], h, &ty), at = r * w;
    slice_pair marg, tot, cond, data;
    pair_of(s, wp->marg, h, 1, &marg);
    pair_of(s, wp->row_total, h, 1, &tot);
    pair_of(s, wp->cond, 2 * st, 2, &cond);
    pair_of(s, wp->data, 2 * st, 2, &data);
    r0 = pmix(&tot, r);
    r1 = pmix(&tot, r + 1);
    m0 = pmix(&marg, r);
    m1 = pmix(&marg, r + 1);
    u[1] = uninvert_row(m0, r0 * ty + 0.5 * (r1 - r0) * ty * ty, m1 - m0, 0.5 * (r0 + r1));
    row_total = (1.0 - ty) * r0 + ty * r1;
    cdf_c = pair_at2(&cond, at, w, ty, c);
    cdf_c1 = pair_at2(&cond, at, w, ty, c + 1);
    v0 = pair_at2(&data, at, w, ty, c);
    v1 = pair_at2(&data, at, w, ty, c + 1);
    u[0] = uninvert_column(cdf_c, v0 * tx + 0.5 * (v1 - v0) * tx * tx, cdf_c1 - cdf_c,
                           0.5 * (v0 + v1), row_total);
    *pdf = ((1.0 - tx) * v0 + tx * v1) * area_scale(wp);
}

LL_WARP_HOT void ll_warp2d_invert_at(const ll_warp2d *wp, const slice_set *s, const double pos[2],
                         double u[2], double *pdf)
{
    size_t w = wp->w, h = wp->h, st = w * h;
    double tx, ty, r0, r1, v0, v1, cdf_c, cdf_c1, row_total, m0, m1;
    size_t c, r;
    slice_rows marg, cond, data;
    if (s->count <= 2) {
        invert_pair(wp, s, pos, u, pdf);
        return;
    }
    c = cell(pos[0], w, &tx);
    r = cell(pos[1], h, &ty);
    rows_of(s, wp->marg, h, 1, &marg);
    rows_of(s, wp->cond, 2 * st, 2, &cond);
    data_rows_of(wp, s, &data);
    r0 = mix(&cond, r * w + w - 1);
    r1 = mix(&cond, (r + 1) * w + w - 1);
    m0 = mix(&marg, r);
    m1 = mix(&marg, r + 1);
    u[1] = uninvert_row(m0, r0 * ty + 0.5 * (r1 - r0) * ty * ty, m1 - m0, 0.5 * (r0 + r1));
    row_total = (1.0 - ty) * r0 + ty * r1;
    cdf_c = pair_at(&cond, r * w, w, ty, c);
    cdf_c1 = pair_at(&cond, r * w, w, ty, c + 1);
    v0 = pair_at(&data, r * w, w, ty, c);
    v1 = pair_at(&data, r * w, w, ty, c + 1);
    u[0] = uninvert_column(cdf_c, v0 * tx + 0.5 * (v1 - v0) * tx * tx, cdf_c1 - cdf_c,
                           0.5 * (v0 + v1), row_total);
    *pdf = ((1.0 - tx) * v0 + tx * v1) * area_scale(wp);
}
