/*
 * The microfacet model's life cycle and its maps: the matrices M_B of the
 * grid points of B that a layer's pairs use (microfacet_series.c), computed
 * once per model, in parallel, by Gauss-Legendre quadrature of the window.
 */
#include "words/microfacet_pair.h"
#include "support/watch.h"

#include "numerics/series.h"

#include "layerlab/ll_quad.h"

#include <cblas.h>
#include <float.h>
#include <math.h>
#include <string.h>

#define GAUSS_NODES 128       /* quadrature of the window for the matrices     */

/* The largest B whose exp(B cos phi) series a layer with n orders holds at
 * relative error 1e-3 (the original's fit, Bmax(n, 1e-3)). A sharper lobe
 * is widened to B_max, keeping its energy (see ll_microfacet_series). */
static double max_b(size_t n_orders) { return 0.0538 * pow((double)n_orders, 2.05001); }

ll_status ll_microfacet_create(double eta_re, double eta_im, double alpha, size_t n_orders,
                               size_t max_len, ll_microfacet_model **out)
{
    return ll_microfacet_create_distribution(eta_re, eta_im, alpha, LL_DISTRIBUTION_BECKMANN,
                                             n_orders, max_len, out);
}

/* The widest lobe that n orders hold (the model's distribution). */
static double model_max_b(const ll_microfacet_model *mf, size_t n_orders)
{
    return mf->ggx ? ll_ggx_max_beta(n_orders, LL_MICROFACET_RELERR) : max_b(n_orders);
}

ll_status ll_microfacet_create_distribution(double eta_re, double eta_im, double alpha,
                                            int distribution, size_t n_orders, size_t max_len,
                                            ll_microfacet_model **out)
{
    ll_microfacet_model *mf = ll_calloc(1, sizeof *mf);
    *out = NULL;
    if (!mf)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "microfacet: out of memory");
    mf->eta_re = eta_re;
    mf->eta_im = eta_im;
    mf->alpha = alpha;
    mf->conductor = eta_im != 0.0;
    mf->ggx = distribution == LL_DISTRIBUTION_GGX;
    if (mf->ggx)
        ll_ggx_basis_init(&mf->ggx_basis);
    mf->b_max = model_max_b(mf, n_orders);
    mf->map_b_max = mf->b_max;
    mf->max_len = max_len;
    *out = mf;
    return LL_OK;
}

void ll_microfacet_set_orders(ll_microfacet_model *mf, size_t n_orders)
{
    mf->b_max = fmin(model_max_b(mf, n_orders), mf->map_b_max);
}

void ll_microfacet_order0_simpson(ll_microfacet_model *mf)
{
    mf->simpson_order0 = 1;
}

static void grid_entry_free(grid_entry *e)
{
    if (e)
        ll_free(e->matrix);
    ll_free(e);
}

void ll_microfacet_destroy(ll_microfacet_model *mf)
{
    size_t k;
    if (!mf)
        return;
    for (k = 0; k < mf->n_grid; ++k)
        grid_entry_free(mf->grid[k]);
    ll_free(mf->grid);
    ll_free(mf->window_rule);
    ll_free(mf);
}

/* T_j(y) for j < CHEB by T_(j+1) = 2 y T_j - T_(j-1). */
static void chebyshev_values(double y, double *t)
{
    size_t j;
    t[0] = 1.0;
    t[1] = y;
    for (j = 2; j < CHEB; ++j)
        t[j] = 2.0 * y * t[j - 1] - t[j - 2];
}

/* The map of grid point k. With y = 2u - 1 and the Chebyshev points
 * y_i = cos(pi (i + 1/2) / CHEB), the interpolant of g is
 *     sum_j a_j T_j(y),  a_j = (2 - [j = 0]) / CHEB sum_i g_i T_j(y_i),
 * so column i of the map is sum_j (2 - [j = 0]) / CHEB T_j(y_i) S_j with
 * S_j the cosine series of exp(-B_k v) T_j(y) on the window:
 *     S_j[l] = (2 - [l = 0]) / pi integral_0^phi_end exp(-B_k v) T_j(y)
 *              cos(l phi) dphi,
 * by Gauss-Legendre quadrature (the integrand is smooth; beyond the window
 * it is below 1e-12 and dropped). */
static ll_status make_entry(const ll_microfacet_model *mf, size_t k, const double *x,
                            const double *w, grid_entry **out)
{
    grid_entry *e = ll_calloc(1, sizeof *e);
    double *basis = NULL, *cosines = NULL, *series = NULL;
    double phi_end;
    size_t i, j, l, q, n = GAUSS_NODES, len;

    *out = NULL;
    if (!e)
        goto oom;
    e->b = ll_microfacet_grid_b(k);
    e->delta = ll_microfacet_window_delta(e->b);
    phi_end = ll_microfacet_window_angle(e->delta);
    /* Orders: exp(-B v)'s series down to TAIL_GOAL, widened by the degree
     * CHEB - 1 (in cos phi) of the interpolant. Beyond B_max only the
     * energy (order 0) of true lobes is asked for. */
    len = e->b > mf->map_b_max ? 1 : ll_expcos_length(e->b, TAIL_GOAL) + CHEB;
    e->len = len < mf->max_len ? len : mf->max_len;
    len = e->len;
    for (i = 0; i < CHEB; ++i) {
        double y = cos(LL_PI * ((double)i + 0.5) / CHEB);
        e->u[i] = 0.5 * (y + 1.0);
        e->cos_phi[i] = 1.0 - e->delta * e->u[i];
    }
    basis = ll_alloc_array(n, CHEB * sizeof(double));  /* CHEB x n       */
    cosines = ll_alloc_array(n, len * sizeof(double)); /* n x len        */
    series = ll_alloc_array(len, CHEB * sizeof(double)); /* CHEB x len  */
    e->matrix = ll_alloc_array(len, CHEB * sizeof(double));
    if (!basis || !cosines || !series || !e->matrix)
        goto oom;
    for (q = 0; q < n; ++q) {
        double phi = 0.5 * phi_end * (x[q] + 1.0), half = sin(0.5 * phi);
        double v = 2.0 * half * half; /* 1 - cos phi, without cancellation */
        double y = 2.0 * v / e->delta - 1.0, c1 = cos(phi), c_prev = c1, c_cur = 1.0;
        double weight = 0.5 * phi_end * w[q] * exp(-e->b * v) * LL_INV_PI;
        double t[CHEB];
        chebyshev_values(y, t);
        for (j = 0; j < CHEB; ++j)
            basis[j * n + q] = weight * t[j];
        /* cos(l phi) by cos((l+1) phi) = 2 cos phi cos(l phi) - cos((l-1) phi);
         * order 0 counts once, the others twice. */
        for (l = 0; l < len; ++l) {
            double next;
            cosines[q * len + l] = l == 0 ? c_cur : 2.0 * c_cur;
            next = 2.0 * c1 * c_cur - c_prev;
            c_prev = c_cur;
            c_cur = next;
        }
    }
    /* series (CHEB x len) = basis (CHEB x n) . cosines (n x len) */
    cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, CHEB, (int)len, (int)n, 1.0, basis,
                (int)n, cosines, (int)len, 0.0, series, (int)len);
    /* matrix[i] = sum_j (2 - [j = 0]) / CHEB T_j(y_i) series[j] */
    memset(e->matrix, 0, len * CHEB * sizeof(double));
    for (i = 0; i < CHEB; ++i) {
        double t[CHEB];
        chebyshev_values(2.0 * e->u[i] - 1.0, t);
        for (j = 0; j < CHEB; ++j) {
            double coef = (j == 0 ? 1.0 : 2.0) / CHEB * t[j];
            for (l = 0; l < len; ++l)
                e->matrix[i * len + l] += coef * series[j * len + l];
        }
    }
    ll_free(basis);
    ll_free(cosines);
    ll_free(series);
    *out = e;
    return LL_OK;
oom:
    ll_free(basis);
    ll_free(cosines);
    ll_free(series);
    grid_entry_free(e);
    return ll_fail(LL_ERROR_OUT_OF_MEMORY, "microfacet: out of memory for a %zu-order map",
                   mf->max_len);
}

typedef struct prepare_job {
    ll_microfacet_model *mf;
    ll_watch *watch;        /* nullable; one unit per entry     */
    size_t *grid;           /* the grid points to compute       */
    const double *x, *w;    /* Gauss-Legendre rule on [-1, 1]   */
} prepare_job;

static ll_status prepare_one(size_t index, void *ctx)
{
    prepare_job *job = ctx;
    size_t k = job->grid[index];
    ll_status s;
    if (ll_watch_poll(job->watch))
        return ll_fail(LL_ERROR_CANCELLED, "ll_layer_set_microfacet: cancelled");
    s = make_entry(job->mf, k, job->x, job->w, &job->mf->grid[k]);
    ll_watch_advance(job->watch, 1);
    return s;
}

ll_status ll_microfacet_prepare(ll_microfacet_model *mf, const double *mu, size_t count)
{
    return ll_microfacet_prepare_watched(mf, mu, count, NULL);
}

/* Room for every B a double holds (4 points per octave: ~4100), in
 * mf->grid; and the bytes of a "needed" mark per grid point. */
static ll_status grow_grid(ll_microfacet_model *mf, size_t *n_grid, unsigned char **need)
{
    size_t k;
    *n_grid = ll_microfacet_grid_index(DBL_MAX) + 1;
    *need = ll_calloc_array(*n_grid, 1);
    if (!*need)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "microfacet: out of memory for the maps");
    if (*n_grid > mf->n_grid) {
        grid_entry **grid = ll_realloc(mf->grid, *n_grid * sizeof *grid);
        if (!grid) {
            ll_free(*need);
            *need = NULL;
            return ll_fail(LL_ERROR_OUT_OF_MEMORY, "microfacet: out of memory for the maps");
        }
        for (k = mf->n_grid; k < *n_grid; ++k)
            grid[k] = NULL;
        mf->grid = grid;
        mf->n_grid = *n_grid;
    }
    return LL_OK;
}

/* Mark the grid points that the pair uses: its (widened) lobe, and the
 * true lobe of a widened one (ll_microfacet_series). */
static void mark_pair(const ll_microfacet_model *mf, double mu_o, double mu_i, unsigned char *need)
{
    pair_plan p;
    if (mf->ggx || !ll_microfacet_plan_pair(mf, mu_o, mu_i, HUGE_VAL, &p))
        return; /* GGX needs no maps */
    if (!p.filon)
        need[p.grid] = 1;
    if (p.b > mf->b_max && ll_microfacet_plan_pair(mf, mu_o, mu_i, mf->b_max, &p) && !p.filon)
        need[p.grid] = 1;
}

/* The maps' Gauss-Legendre rule in mf->window_rule, made once. */
static ll_status window_rule(ll_microfacet_model *mf)
{
    ll_status s;
    if (mf->window_rule)
        return LL_OK;
    mf->window_rule = ll_alloc_array(GAUSS_NODES, 2 * sizeof(double));
    if (!mf->window_rule)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "microfacet: out of memory for the maps");
    s = ll_quad_gauss_legendre(GAUSS_NODES, mf->window_rule, mf->window_rule + GAUSS_NODES,
                               NULL);
    if (s != LL_OK) {
        ll_free(mf->window_rule);
        mf->window_rule = NULL;
    }
    return s;
}

/* Compute the marked maps that are missing (in parallel). */
static ll_status make_marked(ll_microfacet_model *mf, const unsigned char *need, size_t n_grid,
                             ll_watch *watch)
{
    size_t k, n_items = 0;
    prepare_job job;
    ll_status s;
    job.grid = ll_alloc_array(n_grid, sizeof(size_t));
    if (!job.grid)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "microfacet: out of memory for the maps");
    for (k = 0; k < n_grid; ++k)
        if (need[k] && !mf->grid[k])
            job.grid[n_items++] = k;
    job.mf = mf;
    job.watch = watch;
    s = n_items ? window_rule(mf) : LL_OK;
    job.x = mf->window_rule;
    job.w = mf->window_rule + GAUSS_NODES;
    if (s == LL_OK)
        s = ll_watch_stage(watch, "interface", 0.05, 0.05, n_items)
                ? ll_fail(LL_ERROR_CANCELLED, "ll_layer_set_microfacet: cancelled")
                : LL_OK;
    if (s == LL_OK && n_items)
        s = ll_parallel_for_watched(n_items, prepare_one, &job, watch);
    ll_free(job.grid);
    return s;
}

ll_status ll_microfacet_prepare_watched(ll_microfacet_model *mf, const double *mu, size_t count,
                                        ll_watch *watch)
{
    size_t a, b, n_grid;
    unsigned char *need = NULL;
    ll_status s = grow_grid(mf, &n_grid, &need);
    if (s != LL_OK)
        return s;
    /* The missing entries that the pairs use. O(count^2) plans: polled per
     * column. */
    ll_watch_stage(watch, "interface", 0.0, 0.05, count);
    for (b = 0; b < count; ++b) {
        if (ll_watch_poll(watch)) {
            s = ll_fail(LL_ERROR_CANCELLED, "ll_layer_set_microfacet: cancelled");
            goto done;
        }
        ll_watch_advance(watch, 1);
        for (a = 0; a < count; ++a)
            mark_pair(mf, mu[a], mu[b], need);
    }
    s = make_marked(mf, need, n_grid, watch);
done:
    ll_free(need);
    return s;
}

ll_status ll_microfacet_prepare_pairs(ll_microfacet_model *mf, const double *mu_o,
                                      const double *mu_i, size_t count)
{
    size_t k, n_grid;
    unsigned char *need = NULL;
    ll_status s = grow_grid(mf, &n_grid, &need);
    if (s != LL_OK)
        return s;
    for (k = 0; k < count; ++k)
        mark_pair(mf, mu_o[k], mu_i[k], need);
    s = make_marked(mf, need, n_grid, NULL);
    ll_free(need);
    return s;
}
