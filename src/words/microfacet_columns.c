/*
 * The columns of an interface layer and the energy compensation of its
 * order 0 (words/microfacet_columns.h).
 *
 * Reciprocity. The BSDF of Walter et al. 2007 with the separable Smith
 * term is reciprocal: f(wi, wo) = f(wo, wi) for reflection and
 * f_t(wi -> wo) / eta_o^2 = f_t(wo -> wi) / eta_i^2 for refraction (eta_o,
 * eta_i: the indices of the media the two directions lie in; radiance
 * transport, Veach's thesis, section 5.2). In the layer's matrices (rows
 * outgoing, columns incident; node k and its mirror M(k) = k +- h are the
 * same cosine on the two sides) that makes the unweighted entry (o, i) of
 * every Fourier order (cos(l phi) is even in phi) equal to the entry
 * (M(i), M(o)) times index(o)^2 / index(i)^2, where a row lies in the
 * medium below (eta) when o >= h (light going down) and a column in the
 * medium above (1) when i >= h (light arriving from above): R^t and R^b
 * are each their own mirror, T^bt is T^tb's. The series of a pair and of
 * its mirror take the same plan (microfacet_plan.c's products and sums of
 * the same cosines) and agree to rounding, with the same truncation
 * (tests/test_microfacet_reciprocal.c). So each column computes the
 * series of about half its rows, one entry of each pair, and the finish
 * step writes the others from them. Column i >= h computes rows
 * i - h .. i: the rows a >= i - h of R^t (the mirror of (a, i) is
 * (i - h, a + h); row i - h is the fixed point, its own mirror) and
 * T^tb's rows h .. i, on and above its diagonal; column c < h computes
 * rows c + h .. n - 1 (R^b, the same way) and 0 .. c - 1 (T^bt above its
 * diagonal, whose mirrors lie below T^tb's): h + 1 or h pairs per column,
 * so the parallel columns stay even, and each half column's rows one run.
 */
#include "words/microfacet_columns.h"
#include "words/microfacet_pair.h"
#include "support/watch.h"

#include <stdlib.h>
#include <string.h>

/* Doubles of scratch for one column: every row's series (m each; only the
 * pages that the series reach are touched), the series' scratch and one
 * column of the matrix; 0 if that overflows. */
size_t ll_microfacet_column_doubles(size_t n, size_t m)
{
    size_t count, rows;
    if (m > (SIZE_MAX - 2 * FILON_SAMPLES - 2 * CHEB) / 8 || !ll_size_mul(n, m, &rows) ||
        !ll_size_add(rows, ll_microfacet_scratch_size(m), &count) ||
        !ll_size_add(count, n, &count) || count > SIZE_MAX / sizeof(double))
        return 0;
    return count;
}

/* Rows by decreasing series length (ties by index: deterministic). */
typedef struct row_length {
    size_t row, len;
} row_length;

static int longer_first(const void *a, const void *b)
{
    const row_length *x = a, *y = b;
    if (x->len != y->len)
        return x->len > y->len ? -1 : 1;
    return x->row < y->row ? -1 : x->row > y->row;
}

/* One incident column: every outgoing node, every order. The high orders
 * of a column are nonzero only in the few rows near its lobes, so each
 * order's column is filled from the rows whose series reach it (a prefix
 * of the rows sorted by length) and cleared again, instead of sweeping
 * n x m values. */
static ll_status fill_column(size_t col, const ll_microfacet_job *job);

void ll_microfacet_column_rows(size_t col, size_t n, int reciprocal, size_t *first,
                               size_t *count)
{
    size_t h = n / 2;
    *first = reciprocal ? (col < h ? col + h : col - h) : 0;
    *count = reciprocal ? (col < h ? h : h + 1) : n;
}

ll_status ll_microfacet_layer_column(size_t col, void *ctx)
{
    const ll_microfacet_job *job = ctx;
    ll_status s;
    if (ll_watch_poll(job->watch))
        return ll_fail(LL_ERROR_CANCELLED, "ll_layer_set_microfacet: cancelled");
    s = fill_column(col, job);
    ll_watch_advance(job->watch, 1);
    return s;
}

static ll_status fill_column(size_t col, const ll_microfacet_job *job)
{
    const ll_layer *l = job->layer;
    size_t n = l->n, m = l->m, h = n / 2, row, k, j, count, first;
    double *pool, *scratch, *column, factor;
    row_length *rows = ll_alloc_array(n, sizeof *rows);
    size_t slot = ll_parallel_slot();
    double *memory = NULL;
    ll_status s = LL_OK;
    /* The thread's column scratch (n x m doubles, tens of MB for the
     * largest layers), made by its first column and reused: one per column
     * cost a page fault per 4 KiB touched, again for every column. Every
     * value read is written first in the same column. */
    if (slot < job->slots && !job->column_memory[slot])
        job->column_memory[slot] = ll_alloc_array(job->column_doubles, sizeof(double));
    if (slot < job->slots)
        memory = job->column_memory[slot];
    if (!memory || !rows) {
        ll_free(rows);
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_layer_set_microfacet: out of memory");
    }
    pool = memory;                                   /* row r's series at r m */
    scratch = pool + n * m;
    column = scratch + ll_microfacet_scratch_size(m); /* n, kept zero between uses */
    /* (The rows not computed stay zero in order0 and ref0, which start
     * zero, until the finish mirrors them.) */
    ll_microfacet_column_rows(col, n, job->reciprocal, &first, &count);
    for (j = 0; j < count && s == LL_OK; ++j) {
        /* The reference (F = 1) is only needed for R^t: up from above. */
        double *ref;
        row = first + j < n ? first + j : first + j - n;
        ref = job->ref0 && row < h && col >= h ? &job->ref0[col * n + row] : NULL;
        if (ll_watch_poll(job->watch)) {
            s = ll_fail(LL_ERROR_CANCELLED, "ll_layer_set_microfacet: cancelled");
            break;
        }
        /* Depth grows opposite to the normal: the series takes -mu. */
        rows[j].row = row;
        s = ll_microfacet_series(job->mf, -l->nodes[row], -l->nodes[col], m, pool + row * m,
                                 &rows[j].len, ref, scratch);
        job->order0[col * n + row] = rows[j].len ? pool[row * m] : 0.0;
    }
    if (s == LL_OK) {
        qsort(rows, count, sizeof *rows, longer_first);
        memset(column, 0, n * sizeof(double));
        factor = ll_layer_surface_factor(l, col, 1);
        /* Orders past the column's longest series stay empty in the builders. */
        for (k = 1; k < rows[0].len && s == LL_OK; ++k) {
            size_t lo = n, hi = 0;
            while (count > 0 && rows[count - 1].len <= k)
                --count;
            for (j = 0; j < count; ++j) {
                column[rows[j].row] = pool[rows[j].row * m + k] * factor;
                if (rows[j].row < lo)
                    lo = rows[j].row;
                if (rows[j].row + 1 > hi)
                    hi = rows[j].row + 1;
            }
            s = ll_order_builder_set_column_range(job->builders[k], col, column, lo, hi, 0.0);
            for (j = 0; j < count; ++j)
                column[rows[j].row] = 0.0;
        }
    }
    ll_free(rows);
    return s;
}

/* Column sums with the outgoing weights W_j = 2 pi w_j |mu_j|: the
 * fraction of light of each incident direction that a block sends out. */
static void block_albedo(const double *m0, size_t n, const double *w, size_t row0,
                         size_t col0, double *out)
{
    size_t h = n / 2, i, j;
    for (j = 0; j < h; ++j) {
        double sum = 0.0;
        for (i = 0; i < h; ++i)
            sum += w[i] * m0[(col0 + j) * n + row0 + i];
        out[j] = sum;
    }
}

/* block += scale * u v^T (rows u, columns v). */
static void block_add_outer(double *m0, size_t n, size_t row0, size_t col0, const double *u,
                            const double *v, double scale)
{
    size_t h = n / 2, i, j;
    for (j = 0; j < h; ++j)
        for (i = 0; i < h; ++i)
            m0[(col0 + j) * n + row0 + i] += scale * u[i] * v[j];
}

/* Do blocks p and q of c hold the same term? */
static int same_term(const ll_microfacet_compensation *c, int p, int q)
{
    return c->scale[p] == c->scale[q] && c->u[p] == c->u[q] && c->v[p] == c->v[q];
}

/* The orders past 0 of the terms (ll_microfacet_compensation_series) into
 * the builders that hold the columns of the single-scattering lobe: per
 * incident node j, every row's series of a block's column first (once for
 * blocks that hold the same term: a conductor's two), then each order's
 * column read back, added to and set again (weighted as fill_column's).
 * Orders whose builder this process does not hold are left as they are. */
static ll_status spread_orders(const ll_microfacet_job *job, const ll_microfacet_compensation *c)
{
    const ll_layer *l = job->layer;
    size_t n = l->n, m = l->m, h = n / 2, cells, i, j, k, longest = 0;
    double *series, *column;
    ll_status s = LL_OK;
    int q, made;
    if (m < 2 || !c->mu)
        return LL_OK;
    if (!ll_size_mul(h, m, &cells) || !ll_size_add(cells, n, &cells) ||
        !(series = ll_alloc_array(cells, sizeof(double))))
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_layer_set_microfacet: out of memory");
    column = series + h * m;
    for (j = 0; j < h && s == LL_OK; ++j) {
        made = -1;
        for (q = 0; q < 4 && s == LL_OK; ++q) {
            size_t row0 = (size_t)(q >> 1) * h, col = (size_t)(q & 1) * h + j;
            double factor = ll_layer_surface_factor(l, col, 1);
            if (c->scale[q] == 0.0)
                continue;
            if (made < 0 || !same_term(c, made, q)) {
                longest = 0;
                for (i = 0; i < h; ++i) {
                    size_t got = ll_microfacet_compensation_series(c, q, i, j, m, series + i * m);
                    for (k = got; k < m; ++k)
                        series[i * m + k] = 0.0;
                    if (got > longest)
                        longest = got;
                }
                made = q;
            }
            for (k = 1; k < longest && s == LL_OK; ++k) {
                if (!job->builders[k])
                    continue;
                ll_order_builder_get_column(job->builders[k], col, column);
                for (i = 0; i < h; ++i)
                    column[row0 + i] += series[i * m + k] * factor;
                s = ll_order_builder_set_column(job->builders[k], col, column, 0.0);
            }
        }
    }
    ll_free(series);
    return s;
}

/* Energy compensation (words/microfacet_compensation*.c) of the unweighted
 * order 0, and its spread over the other orders. Blocks of m0
 * (column-major): R^t rows < h, columns >= h; R^b rows >= h, columns < h;
 * T^tb rows, columns >= h; T^bt both < h. work holds 8 h doubles. */
static ll_status compensate(const ll_microfacet_job *job, size_t n, double *work)
{
    size_t h = n / 2, q;
    double *albedo[4];
    ll_microfacet_compensation c;
    for (q = 0; q < 4; ++q)
        albedo[q] = work + (4 + q) * h;
    if (job->eta_im == 0.0) {
        for (q = 0; q < 4; ++q) /* (block q: rows >= h when q > 1, columns when q odd) */
            block_albedo(job->order0, n, job->w, (q >> 1) * h, (q & 1) * h, albedo[q]);
        ll_microfacet_compensate_dielectric(job->mf, h, job->layer->nodes + h, job->w,
                                            job->eta_re, (const double *const *)albedo, work,
                                            &c);
    } else {
        /* (Reflection from above: rows < h, columns >= h; the mirror's
         * albedo in R^t's slot, the layer's in R^b's.) */
        block_albedo(job->ref0, n, job->w, 0, h, albedo[LL_BLOCK_RT]);
        block_albedo(job->order0, n, job->w, 0, h, albedo[LL_BLOCK_RB]);
        ll_microfacet_compensate_conductor(job->mf, h, job->layer->nodes + h, job->w,
                                           albedo[LL_BLOCK_RT], albedo[LL_BLOCK_RB], work, &c);
    }
    for (q = 0; q < 4; ++q)
        if (c.scale[q] != 0.0)
            block_add_outer(job->order0, n, (q >> 1) * h, (q & 1) * h, c.u[q], c.v[q],
                            c.scale[q]);
    return spread_orders(job, &c);
}

/* index(o)^2 / index(i)^2 of the reciprocity (the comment at the top)
 * as a factor of the row and one of the column: the row's square, and
 * one over the column's. A conductor only reflects, within one medium. */
static double row_index2(const ll_microfacet_job *job, size_t row, size_t h)
{
    return job->eta_im == 0.0 && row >= h ? job->eta_re * job->eta_re : 1.0;
}

static double col_index2(const ll_microfacet_job *job, size_t col, size_t h)
{
    return job->eta_im == 0.0 && col < h ? job->eta_re * job->eta_re : 1.0;
}

/* The orders past 0 mirrored in parallel, one order per item (each
 * thread's scratch made by its first order and reused). */
typedef struct mirror_job {
    ll_order_builder **builders;
    const double *left, *right;
    void **scratch; /* [slots] */
    size_t slots, bytes;
} mirror_job;

static ll_status mirror_order(size_t i, void *ctx)
{
    mirror_job *mj = ctx;
    size_t slot = ll_parallel_slot();
    if (!mj->builders[i + 1])
        return LL_OK;
    if (slot < mj->slots && !mj->scratch[slot])
        mj->scratch[slot] = ll_malloc(mj->bytes);
    if (slot >= mj->slots || !mj->scratch[slot])
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_layer_set_microfacet: out of memory");
    return ll_order_builder_mirror(mj->builders[i + 1], mj->left, mj->right, mj->scratch[slot]);
}

/* The entries the columns left out (ll_microfacet_column_rows), from
 * their mirrors: in the dense order 0 (and the conductor's reference,
 * R^t alone), complete on every process, and in each order past 0 whose
 * builder this process holds (all of them, or in a distributed build the
 * orders it owns, whole after the exchange). Each entry is one product
 * of its mirror, and each order one item of the parallel loop, so the
 * bits depend on neither the thread count nor the split. */
static ll_status mirror_rest(const ll_microfacet_job *job)
{
    const ll_layer *l = job->layer;
    size_t n = l->n, m = l->m, h = n / 2, col, row, j, k, first, count;
    double *left;
    mirror_job mj;
    ll_status s;
    for (col = 0; col < n; ++col) {
        size_t to = col < h ? col + h : col - h; /* M(col) */
        double c = col_index2(job, col, h);
        ll_microfacet_column_rows(col, n, 1, &first, &count);
        for (j = count; j < n; ++j) {
            size_t from;
            row = first + j < n ? first + j : first + j - n;
            from = (row < h ? row + h : row - h) * n + to; /* (M(i), M(o)) */
            job->order0[col * n + row] = job->order0[from] * (row_index2(job, row, h) / c);
            if (job->ref0 && row < h && col >= h)
                job->ref0[col * n + row] = job->ref0[from];
        }
    }
    if (m < 2)
        return LL_OK;
    mj.builders = job->builders;
    mj.slots = job->slots;
    mj.bytes = ll_order_builder_mirror_bytes(n);
    left = ll_alloc_array(n, 2 * sizeof(double));
    mj.scratch = ll_calloc_array(mj.slots, sizeof *mj.scratch);
    if (!left || !mj.scratch || !mj.bytes) {
        ll_free(left);
        ll_free(mj.scratch);
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_layer_set_microfacet: out of memory");
    }
    /* The builders hold the weighted entries f(o, i) W_i: the mirror's
     * weight W_M(o) divided out, the column's own put in. */
    for (k = 0; k < n; ++k) {
        size_t mk = k < h ? k + h : k - h;
        left[k] = row_index2(job, k, h) / ll_layer_surface_factor(l, mk, 1);
        left[n + k] = ll_layer_surface_factor(l, k, 1) / col_index2(job, k, h);
    }
    mj.left = left;
    mj.right = left + n;
    s = ll_parallel_for_watched(m - 1, mirror_order, &mj, job->watch);
    for (k = 0; k < mj.slots; ++k)
        ll_free(mj.scratch[k]);
    ll_free(mj.scratch);
    ll_free(left);
    return s;
}

/* After the columns: the entries not computed, then energy compensation
 * on the unweighted order 0, the weights, and order 0 into its builder. */
ll_status ll_microfacet_finish_order0(void *ctx)
{
    const ll_microfacet_job *job = ctx;
    const ll_layer *layer = job->layer;
    size_t n = layer->n, col;
    ll_status s = LL_OK;
    if (ll_watch_stage(job->watch, "interface", 0.95, 0.05, n))
        return ll_watch_check(job->watch, "ll_layer_set_microfacet");
    if (job->reciprocal)
        s = mirror_rest(job);
    if (s == LL_OK && job->conserve_energy)
        s = compensate(job, n, job->work);
    /* (In a distributed build only the owner of order 0 holds its builder.) */
    for (col = 0; col < n && s == LL_OK && job->builders[0]; ++col) {
        double factor = ll_layer_surface_factor(layer, col, 0), *column = job->order0 + col * n;
        size_t row;
        for (row = 0; row < n; ++row)
            column[row] *= factor;
        s = ll_order_builder_set_column(job->builders[0], col, column, 0.0);
        ll_watch_advance(job->watch, 1);
        if (s == LL_OK)
            s = ll_watch_check(job->watch, "ll_layer_set_microfacet");
    }
    return s;
}
