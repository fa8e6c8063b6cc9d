/*
 * The piecewise-bilinear 2D warp (tables_warp.h). All sums in double; the
 * renderers compute the same quantities in float, so the two agree to float
 * rounding.
 */
#include "reader/tables_warp.h"

#include <math.h>
#include <string.h>

/* Keeps the sampler off the exact edges of the square, where the inverse
 * of a vanishing density would be 0 / 0. */
#define LL_WARP_EPSILON 5.9604644775390625e-08 /* 2^-24 */

typedef ll_warp_slices slice_set;

void ll_warp2d_free(ll_warp2d *wp)
{
    size_t p;
    if (!wp)
        return;
    for (p = 0; p < LL_WARP_MAX_PARAMS; ++p)
        ll_free(wp->param_values[p]);
    ll_free(wp->data);
    ll_free(wp->cond);
    ll_free(wp->marg);
    memset(wp, 0, sizeof *wp);
}

/* Running trapezoid integrals of slice k (in units of grid cells), then
 * the division by the total when the slice is sampled. 0 if sampling and
 * the total is not positive. */
static int build_slice(ll_warp2d *wp, size_t k)
{
    size_t w = wp->w, h = wp->h, x, y;
    float *v = wp->data + k * w * h, *c = wp->cond + k * w * h, *m = wp->marg + k * h;
    double total = 0.0, scale, sum, prev_row = 0.0;
    /* The total first (sums in double), then every table divided by it and
     * the running integrals taken over the divided values, so that they
     * are exactly those of the stored density. */
    for (y = 0; y < h; ++y) {
        double row = 0.0;
        for (x = 0; x + 1 < w; ++x)
            row += 0.5 * ((double)v[y * w + x] + (double)v[y * w + x + 1]);
        if (y > 0)
            total += 0.5 * (prev_row + row);
        prev_row = row;
    }
    if (!(total > 0.0) || !ll_is_finite(total))
        return 0;
    scale = 1.0 / total;
    for (x = 0; x < w * h; ++x)
        v[x] = (float)((double)v[x] * scale);
    for (y = 0; y < h; ++y) {
        sum = 0.0;
        c[y * w] = 0.0f;
        for (x = 0; x + 1 < w; ++x) {
            sum += 0.5 * ((double)v[y * w + x] + (double)v[y * w + x + 1]);
            c[y * w + x + 1] = (float)sum;
        }
    }
    sum = 0.0;
    m[0] = 0.0f;
    for (y = 0; y + 1 < h; ++y) {
        sum += 0.5 * ((double)c[y * w + w - 1] + (double)c[(y + 1) * w + w - 1]);
        m[y + 1] = (float)sum;
    }
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
    wp->data = ll_alloc_array(total, sizeof(float));
    if (!wp->data)
        goto oom;
    wp->inner = !sampling && n_params > 0 ? param_size[n_params - 1] : 1;
    {
        /* Entry k of the caller's layout, slice (outer, j) at node at, goes
         * to ((outer w h) + at) inner + j. */
        size_t area = w * h, in = wp->inner, outer, j, at;
        for (k = 0, outer = 0; outer < n / in; ++outer)
            for (j = 0; j < in; ++j) {
                float *to = wp->data + outer * area * in + j;
                for (at = 0; at < area; ++at, ++k)
                    to[at * in] = (float)get(ctx, k);
            }
    }
    if (!sampling)
        return LL_OK;
    wp->normalized = 1;
    wp->cond = ll_alloc_array(total, sizeof(float));
    wp->marg = ll_alloc_array(n * h, sizeof(float));
    if (!wp->cond || !wp->marg)
        goto oom;
    for (k = 0; k < n; ++k)
        if (!build_slice(wp, k))
            return ll_fail(LL_ERROR_FORMAT, "slice %zu has no positive finite integral", k);
    return LL_OK;
oom:
    return ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory (%zu x %zu table)", w, h);
}

/* The interval of an ascending list that holds x, and the weight of its
 * upper end, clamped to the list's ends; a single value needs no weight. */
static void locate(const double *v, size_t n, double x, size_t *i, double *t)
{
    size_t lo = 0, hi;
    if (n < 2) {
        *i = 0;
        *t = 0.0;
        return;
    }
    hi = n - 2;
    while (lo < hi) {
        size_t mid = (lo + hi + 1) / 2;
        if (v[mid] <= x)
            lo = mid;
        else
            hi = mid - 1;
    }
    *i = lo;
    *t = (x - v[lo]) / (v[lo + 1] - v[lo]);
    if (!(*t > 0.0))
        *t = 0.0;
    if (*t > 1.0)
        *t = 1.0;
}

void ll_warp2d_slices(const ll_warp2d *wp, const double *param, slice_set *s)
{
    size_t p, c, idx[LL_WARP_MAX_PARAMS];
    double t[LL_WARP_MAX_PARAMS];
    /* An isotropic file's incident slices: one azimuth, so only the
     * elevation's two neighbours, with the weights the general loop below
     * gives them (1 (1 - t) and 1 t), without its eight corners. */
    if (wp->n_params == 2 && wp->param_size[0] == 1) {
        locate(wp->param_values[1], wp->param_size[1], param[1], &idx[1], &t[1]);
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
        locate(wp->param_values[p], wp->param_size[p], param[p], &idx[p], &t[p]);
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
 * the offsets are taken once. Two slices (an isotropic file: two
 * elevations) is the common case and has its own path; its sum is the
 * general loop's to the bit (0 + a + b is a + b). */
typedef struct slice_rows {
    size_t count;
    size_t step;                              /* floats from one node to the next */
    const float *p[1 << LL_WARP_MAX_PARAMS];
    double w[1 << LL_WARP_MAX_PARAMS];
} slice_rows;

static void rows_of(const slice_set *s, const float *arr, size_t stride, slice_rows *out)
{
    size_t c;
    out->count = s->count;
    out->step = 1;
    for (c = 0; c < s->count; ++c) {
        out->p[c] = arr + s->index[c] * stride;
        out->w[c] = s->weight[c];
    }
}

/* The values' slices (ll_warp2d.inner: slice i is (i / inner, i % inner)). */
static void data_rows_of(const ll_warp2d *wp, const slice_set *s, slice_rows *out)
{
    size_t c, in = wp->inner, area = wp->w * wp->h;
    out->count = s->count;
    out->step = in;
    for (c = 0; c < s->count; ++c) {
        out->p[c] = wp->data + (s->index[c] / in) * area * in + s->index[c] % in;
        out->w[c] = s->weight[c];
    }
}

static inline double mix(const slice_rows *r, size_t node)
{
    size_t c, at = node * r->step;
    double v;
    if (r->count == 2)
        return r->w[0] * (double)r->p[0][at] + r->w[1] * (double)r->p[1][at];
    v = 0.0;
    for (c = 0; c < r->count; ++c)
        v += r->w[c] * (double)r->p[c][at];
    return v;
}

/* Cell and fraction of coordinate x in [0, 1] over n nodes. */
static size_t cell(double x, size_t n, double *t)
{
    double f;
    size_t i;
    if (!(x > 0.0))
        x = 0.0;
    if (x > 1.0)
        x = 1.0;
    f = x * (double)(n - 1);
    i = (size_t)f;
    if (i > n - 2)
        i = n - 2;
    *t = f - (double)i;
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

static double bilinear(const ll_warp2d *wp, const slice_set *s, size_t r, double ty, size_t c,
                       double tx)
{
    slice_rows d;
    data_rows_of(wp, s, &d);
    return bilinear_rows(&d, wp->w, r, ty, c, tx);
}

/* Density per unit area of the square for a sampling warp (slices hold
 * values per cell area, total 1), the value itself otherwise. */
static double area_scale(const ll_warp2d *wp)
{
    return wp->normalized ? (double)(wp->w - 1) * (double)(wp->h - 1) : 1.0;
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
    return bilinear(wp, s, r, ty, c, tx) * area_scale(wp);
}

void ll_warp2d_eval_nodes(const ll_warp2d *wp, const slice_set *s, size_t n,
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
    ll_warp_slices_append(s, 0, n, &first);
    data_rows_of(wp, &first, &d);
    for (k = 0; k < n; ++k) {
        out[k] = bilinear_rows(&d, wp->w, r, ty, c, tx) * scale;
        for (j = 0; j < d.count; ++j)
            d.p[j] += next;
    }
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

/* The t in [0, 1] where the integral of the linear density a + (b - a) t
 * from 0 reaches d, in the form without cancellation. */
static double invert_linear(double a, double b, double d)
{
    double disc = a * a + 2.0 * (b - a) * d, den, t;
    if (!(disc > 0.0))
        disc = 0.0;
    den = a + sqrt(disc);
    t = den > 0.0 ? 2.0 * d / den : 0.0;
    if (!(t > 0.0))
        t = 0.0;
    return t > 1.0 ? 1.0 : t;
}

/* The stored running integrals are float sums, so a cell's stored mass
 * (the difference of its two ends) and the mass of its linear density
 * (the mean of its end values) differ by rounding. sample and invert
 * scale the inside of a cell by their ratio, which keeps the two exact
 * inverses of each other whatever the rounding. 1 for an empty cell. */
static double mass_ratio(double stored, double linear)
{
    return stored > 0.0 && linear > 0.0 ? linear / stored : 1.0;
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

void ll_warp2d_sample_at(const ll_warp2d *wp, const slice_set *s, const double u_in[2],
                         double pos[2], double *pdf)
{
    size_t w = wp->w, h = wp->h, st = w * h, r, c;
    double u[2], target, r0, r1, ty, tx, row_total, v0, v1, cdf_c, cdf_c1, m0, m1;
    slice_rows marg, cond, data;
    int k;
    for (k = 0; k < 2; ++k) {
        u[k] = u_in[k];
        if (!(u[k] >= LL_WARP_EPSILON))
            u[k] = LL_WARP_EPSILON;
        if (u[k] > 1.0 - LL_WARP_EPSILON)
            u[k] = 1.0 - LL_WARP_EPSILON;
    }
    rows_of(s, wp->marg, h, &marg);
    rows_of(s, wp->cond, st, &cond);
    data_rows_of(wp, s, &data);
    /* Row interval from the marginal (slices are normalised: total 1). */
    target = u[1];
    SEARCH(h, mix(&marg, i), target, r);
    r0 = mix(&cond, r * w + w - 1);
    r1 = mix(&cond, (r + 1) * w + w - 1);
    m0 = mix(&marg, r);
    m1 = mix(&marg, r + 1);
    ty = invert_linear(r0, r1, (target - m0) * mass_ratio(m1 - m0, 0.5 * (r0 + r1)));
    /* Column interval from the conditional row at ty. */
    row_total = (1.0 - ty) * r0 + ty * r1;
    target = u[0] * row_total;
    SEARCH(w, pair_at(&cond, r * w, w, ty, i), target, c);
    cdf_c = pair_at(&cond, r * w, w, ty, c);
    cdf_c1 = pair_at(&cond, r * w, w, ty, c + 1);
    v0 = pair_at(&data, r * w, w, ty, c);
    v1 = pair_at(&data, r * w, w, ty, c + 1);
    tx = invert_linear(v0, v1, (target - cdf_c) * mass_ratio(cdf_c1 - cdf_c, 0.5 * (v0 + v1)));
    pos[0] = ((double)c + tx) / (double)(w - 1);
    pos[1] = ((double)r + ty) / (double)(h - 1);
    *pdf = ((1.0 - tx) * v0 + tx * v1) * area_scale(wp);
}

void ll_warp2d_invert_at(const ll_warp2d *wp, const slice_set *s, const double pos[2],
                         double u[2], double *pdf)
{
    size_t w = wp->w, h = wp->h, st = w * h;
    double tx, ty, r0, r1, v0, v1, cdf_c, cdf_c1, row_total, m0, m1;
    size_t c = cell(pos[0], w, &tx), r = cell(pos[1], h, &ty);
    slice_rows marg, cond, data;
    rows_of(s, wp->marg, h, &marg);
    rows_of(s, wp->cond, st, &cond);
    data_rows_of(wp, s, &data);
    r0 = mix(&cond, r * w + w - 1);
    r1 = mix(&cond, (r + 1) * w + w - 1);
    m0 = mix(&marg, r);
    m1 = mix(&marg, r + 1);
    u[1] = m0 + (r0 * ty + 0.5 * (r1 - r0) * ty * ty) / mass_ratio(m1 - m0, 0.5 * (r0 + r1));
    row_total = (1.0 - ty) * r0 + ty * r1;
    cdf_c = pair_at(&cond, r * w, w, ty, c);
    cdf_c1 = pair_at(&cond, r * w, w, ty, c + 1);
    v0 = pair_at(&data, r * w, w, ty, c);
    v1 = pair_at(&data, r * w, w, ty, c + 1);
    u[0] = row_total > 0.0 ? (cdf_c + (v0 * tx + 0.5 * (v1 - v0) * tx * tx) /
                                          mass_ratio(cdf_c1 - cdf_c, 0.5 * (v0 + v1))) /
                                 row_total
                           : 0.0;
    *pdf = ((1.0 - tx) * v0 + tx * v1) * area_scale(wp);
}
