/*
 * Phase functions of participating media: isotropic, Henyey-Greenstein,
 * von Mises-Fisher (the "words" for media; Jakob et al. 2014, section 6.1).
 *
 * Why not sample the phase function at the nodes (as the original does):
 * on a finite grid the discrete phase matrix of a peaked phase function
 * does not integrate to one, so a non-absorbing slab loses energy, and the
 * forward peak is badly resolved at normal incidence. Instead the phase
 * function is expanded in Legendre polynomials, p = sum_k (2k+1)/(4 pi)
 * chi_k P_k(cos theta), truncated with the delta-M method (Wiscombe 1977,
 * J. Atmos. Sci. 34, the method of DISORT): with K kept moments the
 * remainder f = chi_K is treated as exactly forward scattering,
 *     p = f delta + sum_{k<K} (2k+1)/(4 pi) (chi_k - f) P_k(cos theta).
 * By the addition theorem the azimuthal Fourier order l of the smooth part
 * is (c_l / 2 pi) sum_k (chi_k - f) Y_k^l(mu_o) Y_k^l(mu_i) with the
 * normalised associated Legendre functions Y_k^l (integral of Y^2 = 1),
 * c_0 = 1, c_l = 2. Folding the medium weights w_i pi (x2 for l = 0) turns
 * every order into the same form
 *     P_l = Y_l diag(chi - f) Y_l^T diag(w),
 * a BLAS-3 product. A Gauss rule with n nodes integrates Y_k^0 exactly for
 * k < K = n, so each column of P_0 integrates to exactly 1 - f and the
 * forward term supplies f: the discrete scattering conserves energy to
 * rounding and is reciprocal (symmetric once weights are removed). A final
 * diagonal correction makes this hold for quadrature rules that are not
 * exact (composite Simpson).
 */
#include "words/media.h"
#include "support/watch.h"

#include <cblas.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct medium_job {
    const ll_layer *layer;
    size_t K;                /* Legendre moments kept                       */
    const double *moment;    /* [K] albedo (chi_k - f)                       */
    double forward;          /* albedo f: exactly forward scattering         */
    const long double *diag; /* [L x n] Y_l^l at every node                  */
    ll_order *straight;      /* every order >= K: forward * I (shared)       */
    double **scratch;        /* [threads] P, Y, Z of one order, per thread   */
    const ll_medium_finish *finish; /* nullable: each order's last step      */
    size_t slots;
    ll_order **result;
    ll_watch *watch;         /* one unit per order; polled per node          */
    const ll_split *split;   /* the calling thread's (layer/split.h)         */
    const char *fn;
} medium_job;

/* Y_l^l(mu) for l < L at every node (long double: (1 - mu^2)^(l/2) would
 * underflow a double for large l, while later Y_k^l recover). Row l. */
static long double *sectoral_values(const ll_layer *l, size_t L)
{
    size_t n = l->n, j, k;
    long double *diag = ll_alloc_array(L ? L : 1, n * sizeof(long double));
    if (!diag)
        return NULL;
    for (j = 0; j < n; ++j) {
        long double mu = l->nodes[j], s = sqrtl(fmaxl(0.0L, (1.0L - mu) * (1.0L + mu)));
        long double y = 1.0L / sqrtl(2.0L);
        for (k = 0; k < L; ++k) {
            if (k > 0) /* Y_k^k = sqrt((2k+1)/(2k)) sin Y_{k-1}^{k-1} (phase dropped) */
                y *= sqrtl((2.0L * k + 1.0L) / (2.0L * k)) * s;
            diag[k * n + j] = y;
        }
    }
    return diag;
}

static ll_status build_order(size_t order, const medium_job *job);

static ll_status medium_order(size_t order, void *ctx)
{
    medium_job *job = ctx;
    ll_status s;
    if (ll_watch_poll(job->watch))
        return ll_fail(LL_ERROR_CANCELLED, "%s: cancelled", job->fn);
    /* Another rank's order in a distributed build (layer/split.h):
     * not computed, NULL. Beyond the kept moments an order is the forward
     * term alone, the same for all of them: one shared order, no n x n
     * matrix (order 0 always has a moment, K >= 1). */
    if (!ll_split_owns(job->split, order)) {
        s = LL_OK;
    } else if (order >= job->K && job->finish) {
        s = job->finish->order(job->finish->user, order, NULL, job->forward,
                               &job->result[order]);
    } else if (order >= job->K) {
        job->result[order] = ll_order_retain(job->straight);
        s = LL_OK;
    } else {
        s = build_order(order, job);
    }
    ll_watch_advance(job->watch, 1);
    return s;
}

/* The phase matrix of one order; polls once per node of the recurrence
 * and around the O(n^2 K) product. */
static ll_status build_order(size_t order, const medium_job *job)
{
    const ll_layer *l = job->layer;
    size_t n = l->n, K = job->K, cols, j, c, r, k, slot = ll_parallel_slot();
    double *Y = NULL, *Z = NULL, *P = NULL;
    long double *ab = NULL;
    ll_status s = LL_OK;

    cols = order < K ? K - order : 0;
    /* The thread's scratch, made by its first order and reused (fresh
     * n x n matrices per order cost a page fault per 4 KiB): n^2 + 2 n K. */
    if (slot >= job->slots)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "medium: thread %zu of %zu", slot, job->slots);
    if (!job->scratch[slot])
        job->scratch[slot] = ll_alloc_array(n, (n + 2 * K) * sizeof(double));
    if (!job->scratch[slot])
        goto oom;
    P = job->scratch[slot];
    memset(P, 0, n * n * sizeof(double));
    if (cols > 0) {
        long double m = (long double)order;
        Y = P + n * n;
        Z = Y + n * cols;
        /* The recurrence's coefficients depend on the degree alone: made
         * once per order, not per node (two long double square roots per
         * node and degree were about 3% of the dust on gold's CPU); the
         * same values, so the same bits. */
        ab = ll_alloc_array(cols, 2 * sizeof *ab);
        if (!ab)
            goto oom;
        for (c = 1; c < cols; ++c) {
            long double kk = m + c;
            ab[2 * c] = sqrtl((4.0L * kk * kk - 1.0L) / (kk * kk - m * m));
            ab[2 * c + 1] = (c >= 2) ? sqrtl(((kk - 1) * (kk - 1) - m * m) /
                                             (4.0L * (kk - 1) * (kk - 1) - 1.0L))
                                     : 0.0L;
        }
        /* Y[:, c] = Y_{order + c}^{order}(mu_j) by the three-term recurrence in
         * the degree (stable upward for fixed order). */
        for (j = 0; j < n; ++j) {
            long double mu = l->nodes[j];
            long double y_prev = 0.0L, y = job->diag[order * n + j];
            if (ll_watch_poll(job->watch))
                goto cancelled;
            Y[j] = (double)y;
            for (c = 1; c < cols; ++c) {
                long double y_next = ab[2 * c] * (mu * y - ab[2 * c + 1] * y_prev);
                y_prev = y;
                y = y_next;
                Y[c * n + j] = (double)y;
            }
        }
        ll_free(ab);
        ab = NULL;
        for (c = 0; c < cols; ++c)
            for (j = 0; j < n; ++j)
                Z[c * n + j] = Y[c * n + j] * job->moment[order + c];
        /* P = Z Y^T, then fold the medium weights into the columns. */
        if (ll_watch_poll(job->watch))
            goto cancelled;
        cblas_dgemm(CblasColMajor, CblasNoTrans, CblasTrans, (blasint)n, (blasint)n,
                    (blasint)cols, 1.0, Z, (blasint)n, Y, (blasint)n, 0.0, P, (blasint)n);
        if (ll_watch_poll(job->watch))
            goto cancelled;
        for (c = 0; c < n; ++c)
            for (r = 0; r < n; ++r)
                P[c * n + r] *= l->weights[c];
    }
    for (k = 0; k < n; ++k)
        P[k * n + k] += job->forward;

    if (order == 0) {
        /* Exact energy whatever the quadrature: sum_o w_o P(o, i) = albedo w_i,
         * with the (rounding-level) deficit put on the forward diagonal. */
        double albedo = job->forward + job->moment[0];
        for (c = 0; c < n; ++c) {
            double sum = 0.0;
            for (r = 0; r < n; ++r)
                sum += l->weights[r] * P[c * n + r];
            P[c * n + c] += (albedo * l->weights[c] - sum) / l->weights[c];
        }
    }
    if (job->finish)
        s = job->finish->order(job->finish->user, order, P, job->forward, &job->result[order]);
    else
        s = ll_order_from_dense(P, n, 0.0, &job->result[order]);
    return s;
oom:
    return ll_fail(LL_ERROR_OUT_OF_MEMORY, "medium: out of memory for order %zu", order);
cancelled:
    ll_free(ab);
    return ll_fail(LL_ERROR_CANCELLED, "%s: cancelled", job->fn);
}

/* Build all orders from the Legendre moments chi[0..K] (chi[K] is the first
 * moment not kept, the delta-M forward fraction). */
static ll_status set_medium(ll_layer *layer, double albedo, const double *chi, size_t K,
                            const char *fn, const ll_medium_finish *finish, ll_watch *watch)
{
    medium_job job;
    double *moment = NULL, *forward;
    long double *diag = NULL;
    size_t k, L = layer->m < K ? layer->m : K;
    ll_status s;

    job.straight = NULL;
    job.finish = finish;
    job.slots = ll_get_thread_count();
    job.scratch = ll_calloc_array(job.slots, sizeof(double *));
    moment = ll_alloc_array(K + layer->n, sizeof(double));
    forward = moment ? moment + K : NULL;
    diag = sectoral_values(layer, L);
    job.result = ll_calloc_array(layer->m, sizeof(ll_order *));
    if (!moment || !diag || !job.result || !job.scratch) {
        s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", fn);
        goto done;
    }
    for (k = 0; k < K; ++k)
        moment[k] = albedo * (chi[k] - chi[K]);
    /* Moments below 1e-12 of the first are not kept: the orders beyond the
     * last one kept hold only the forward term, a diagonal that needs no
     * dense work (the slab takes its exponential, doubling squares it).
     * At 1e-12, the compact orders' own drop threshold (LL_DROP_THRESHOLD), the
     * slab of HG g = 0.9, tau = 4 at n = 400 moves by at most 1.0e-8 in
     * BSDF units (values up to 465; 4.3e-8 relative where |f| > 1e-3)
     * against a cutoff of 1e-15, with 263 dense orders instead of 328: a
     * fifth less of the slab, the adding and the stored stack. (HG g = 0.5
     * keeps 40 of 196 moments.) */
    while (K > 1 && !(fabs(moment[K - 1]) > 1e-12 * fabs(moment[0])))
        --K;
    job.layer = layer;
    job.split = ll_split_current();
    job.K = K;
    job.moment = moment;
    job.forward = albedo * chi[K];
    job.diag = diag;
    job.watch = watch;
    job.fn = fn;
    for (k = 0; k < layer->n; ++k)
        forward[k] = job.forward;
    s = ll_order_from_diagonals(layer->n, forward, forward, 0.0, &job.straight);
    if (s != LL_OK)
        goto done;
    s = ll_watch_stage(watch, "phase function", 0.0, 1.0, layer->m) ? ll_watch_check(watch, fn)
                                                                    : LL_OK;
    if (s == LL_OK)
        s = ll_parallel_for_watched(layer->m, medium_order, &job, watch);
    s = ll_watch_finish(watch, s, fn);
    s = ll_layer_commit_orders(layer, job.result, s);
    job.result = NULL;
done:
    for (k = 0; job.scratch && k < job.slots; ++k)
        ll_free(job.scratch[k]);
    ll_free(job.scratch);
    ll_order_release(job.straight);
    ll_free(job.result);
    ll_free(moment);
    ll_free(diag);
    return s;
}

static ll_status check_medium_args(const ll_layer *layer, double albedo, const char *fn)
{
    if (!layer)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: layer is NULL", fn);
    if (!(albedo >= 0.0 && albedo <= 1.0))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: albedo %g is outside [0, 1]", fn, albedo);
    return LL_OK;
}

/* Moments kept: as many as the quadrature integrates exactly (n nodes). */
static size_t kept_moments(const ll_layer *layer) { return layer->n; }

static ll_status isotropic(ll_layer *layer, double albedo, const ll_medium_finish *finish,
                           const ll_monitor *monitor)
{
    double *chi;
    size_t K;
    ll_watch watch;
    ll_status s = check_medium_args(layer, albedo, "ll_layer_set_isotropic");
    if (s == LL_OK)
        s = ll_watch_begin(&watch, monitor, "ll_layer_set_isotropic");
    if (s != LL_OK)
        return s;
    K = kept_moments(layer);
    chi = ll_calloc_array(K + 1, sizeof(double));
    if (!chi)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_layer_set_isotropic: out of memory");
    chi[0] = 1.0;
    s = set_medium(layer, albedo, chi, K, "ll_layer_set_isotropic", finish, &watch);
    ll_free(chi);
    return s;
}

static ll_status henyey_greenstein(ll_layer *layer, double albedo, double g,
                                   const ll_medium_finish *finish, const ll_monitor *monitor)
{
    double *chi;
    size_t K, k;
    ll_watch watch;
    ll_status s = check_medium_args(layer, albedo, "ll_layer_set_henyey_greenstein");
    if (s == LL_OK)
        s = ll_watch_begin(&watch, monitor, "ll_layer_set_henyey_greenstein");
    if (s != LL_OK)
        return s;
    if (!(g > -1.0 && g < 1.0))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_layer_set_henyey_greenstein: asymmetry g = %g is outside (-1, 1)", g);
    K = kept_moments(layer);
    chi = ll_alloc_array(K + 1, sizeof(double));
    if (!chi)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_layer_set_henyey_greenstein: out of memory");
    /* The Legendre moments of Henyey-Greenstein are powers of g. */
    chi[0] = 1.0;
    for (k = 1; k <= K; ++k)
        chi[k] = chi[k - 1] * g;
    s = set_medium(layer, albedo, chi, K, "ll_layer_set_henyey_greenstein", finish, &watch);
    ll_free(chi);
    return s;
}

static ll_status von_mises_fisher(ll_layer *layer, double albedo, double kappa,
                                  const ll_medium_finish *finish, const ll_monitor *monitor)
{
    double *chi;
    size_t K, k, start;
    double ratio;
    ll_watch watch;
    ll_status s = check_medium_args(layer, albedo, "ll_layer_set_von_mises_fisher");
    if (s == LL_OK)
        s = ll_watch_begin(&watch, monitor, "ll_layer_set_von_mises_fisher");
    if (s != LL_OK)
        return s;
    if (!(kappa >= 0.0) || !ll_is_finite(kappa) || kappa > 1e6)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_layer_set_von_mises_fisher: kappa = %g is outside [0, 1e6]", kappa);
    K = kept_moments(layer);
    chi = ll_calloc_array(K + 1, sizeof(double));
    if (!chi)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_layer_set_von_mises_fisher: out of memory");
    /* chi_k = I_{k+1/2}(kappa) / I_{1/2}(kappa). The ratios
     * r_k = I_{k+1/2} / I_{k-1/2} satisfy r_k = 1 / ((2k+1)/kappa + r_{k+1})
     * (from I_{v-1} - I_{v+1} = (2v/kappa) I_v), stable backwards from far
     * beyond the last index needed. */
    chi[0] = 1.0;
    if (kappa > 0.0) {
        double *r = ll_alloc_array(K + 1, sizeof(double));
        if (!r) {
            ll_free(chi);
            return ll_fail(LL_ERROR_OUT_OF_MEMORY,
                           "ll_layer_set_von_mises_fisher: out of memory");
        }
        start = K + 64 + (size_t)(kappa < 1e6 ? 2.0 * kappa : 2e6);
        ratio = 0.0;
        for (k = start; k >= 1; --k) {
            ratio = 1.0 / ((2.0 * (double)k + 1.0) / kappa + ratio);
            if (k <= K)
                r[k] = ratio;
        }
        for (k = 1; k <= K; ++k)
            chi[k] = chi[k - 1] * r[k];
        ll_free(r);
    }
    s = set_medium(layer, albedo, chi, K, "ll_layer_set_von_mises_fisher", finish, &watch);
    ll_free(chi);
    return s;
}

ll_status ll_layer_set_isotropic(ll_layer *layer, double albedo, const ll_monitor *monitor)
{
    return isotropic(layer, albedo, NULL, monitor);
}

ll_status ll_layer_set_henyey_greenstein(ll_layer *layer, double albedo, double g,
                                         const ll_monitor *monitor)
{
    return henyey_greenstein(layer, albedo, g, NULL, monitor);
}

ll_status ll_layer_set_von_mises_fisher(ll_layer *layer, double albedo, double kappa,
                                        const ll_monitor *monitor)
{
    return von_mises_fisher(layer, albedo, kappa, NULL, monitor);
}

ll_status ll_layer_set_medium_finished(ll_layer *layer, ll_medium_kind kind, double albedo,
                                       double shape, const ll_medium_finish *finish,
                                       const ll_monitor *monitor)
{
    switch (kind) {
    case LL_MEDIUM_HG: return henyey_greenstein(layer, albedo, shape, finish, monitor);
    case LL_MEDIUM_VMF: return von_mises_fisher(layer, albedo, shape, finish, monitor);
    default: return isotropic(layer, albedo, finish, monitor);
    }
}
