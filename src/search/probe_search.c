/*
 * The search for the resolution that meets a tolerance (search/probe.h).
 *
 * Criterion: (n, m) is accepted when its probe values agree with those at
 * (2n, 2m) within the tolerance wherever the latter are above 1% of their
 * group's peak. If the error falls like a power of the resolution,
 * |f(n) - f(inf)| = |f(n) - f(2n)| / (1 - 2^-p), so this understates the
 * error against the converged answer by 2^-p of it; the growth below
 * stops at the first (n, m) that passes, and the shrinking after it only
 * takes steps that still pass.
 *
 * Every evaluation is kept (a few dozen at most), so the comparisons
 * share them: the growth asks for (n, m), (2n, 2m), (2n, m), (n, 2m).
 */
#include "search/probe.h"

#include <math.h>

#define MAX_EVALS 48
#define GROW 1.25
#define SHRINK 0.85
#define MAX_STEPS 40
#define MAX_SHRINKS 3
#define MARGIN 0.6

typedef struct probe_cache {
    const ll_probe_set *set;
    ll_probe_eval_fn eval;
    void *ctx;
    ll_watch *watch;
    size_t count;
    size_t n[MAX_EVALS], m[MAX_EVALS];
    double *values[MAX_EVALS];
} probe_cache;

static ll_status cached(probe_cache *c, size_t n, size_t m, const double **out)
{
    size_t k;
    ll_status s;
    for (k = 0; k < c->count; ++k)
        if (c->n[k] == n && c->m[k] == m) {
            *out = c->values[k];
            return LL_OK;
        }
    if (c->count == MAX_EVALS) {
        /* Forget the oldest (the search has moved past it). */
        ll_free(c->values[0]);
        for (k = 1; k < MAX_EVALS; ++k) {
            c->n[k - 1] = c->n[k];
            c->m[k - 1] = c->m[k];
            c->values[k - 1] = c->values[k];
        }
        --c->count;
    }
    k = c->count;
    s = ll_watch_check(c->watch, "resolution search");
    if (s != LL_OK)
        return s;
    c->values[k] = ll_alloc_array(LL_PROBE_VALUES(c->set) + 1, sizeof(double));
    if (!c->values[k])
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "resolution search: out of memory");
    s = c->eval(c->ctx, n, m, c->watch, c->values[k]);
    ll_watch_advance(c->watch, 1); /* (the stage's total caps it) */
    if (s != LL_OK) {
        ll_free(c->values[k]);
        return s;
    }
    c->n[k] = n;
    c->m[k] = m;
    ++c->count;
    *out = c->values[k];
    return LL_OK;
}

/* The error of (n, m) against (n2, m2). */
static ll_status compare(probe_cache *c, size_t n, size_t m, size_t n2, size_t m2,
                         double *error)
{
    const double *a, *b;
    ll_status s = cached(c, n2, m2, &b);
    if (s == LL_OK)
        s = cached(c, n, m, &a);
    /* (cached() may have forgotten b while computing a: look it up again.) */
    if (s == LL_OK)
        s = cached(c, n2, m2, &b);
    if (s == LL_OK)
        *error = ll_probe_error(c->set, a, b);
    return s;
}

/* Is fewer nodes, n1 < n at the accepted (n, m), hopeless? Its values
 * against the (2n, 2m) already made: a node count's reference costs four
 * times its own evaluation (the compensation's albedos are O(n^2)), and
 * where the shrunk count is well off against the finer reference it fails
 * against its own too. Measured, the error against (2n, 2m) was 0.87 to
 * 0.92 of that against (2 n1, 2m) (a dielectric coat, eta 1.5, alpha 0.1
 * and 0.15, at 236, 376, 442 and 520 nodes): SCREEN leaves room for more. */
#define SCREEN 1.25

static ll_status screen(probe_cache *c, size_t n1, size_t n, size_t m, double goal,
                        int *hopeless)
{
    const double *a, *ref = NULL;
    size_t k;
    ll_status s;
    *hopeless = 0;
    for (k = 0; k < c->count; ++k)
        if (c->n[k] == 2 * n && c->m[k] == 2 * m)
            ref = c->values[k];
    if (!ref)
        return LL_OK; /* (forgotten: no screening) */
    s = cached(c, n1, m, &a);
    if (s != LL_OK)
        return s;
    /* (cached() may have forgotten ref while computing a: look it up again.) */
    for (k = 0, ref = NULL; k < c->count; ++k)
        if (c->n[k] == 2 * n && c->m[k] == 2 * m)
            ref = c->values[k];
    if (ref)
        *hopeless = ll_probe_error(c->set, a, ref) > SCREEN * goal;
    return LL_OK;
}

static size_t even_nodes(double n, size_t min_nodes)
{
    size_t k = (size_t)ceil(n);
    k += k % 2;
    return k < min_nodes ? min_nodes : k;
}

/* The factor to grow by when one dimension alone is off by e: as if the
 * error fell like the square of the resolution (the spline's rate on a
 * lobe's flank, as measured: eta 1.5, alpha 0.5 went 6.1%, 2.6%, 0.7% at
 * 120, 160, 240 nodes), aiming at 0.7 of the tolerance, between GROW and
 * twice. Fewer steps than a fixed factor: each costs three evaluations. */
static double growth(double e, double tolerance)
{
    double f = sqrt(e / (0.7 * tolerance));
    return f < GROW ? GROW : f > 2.0 ? 2.0 : f;
}

ll_status ll_probe_search(const ll_probe_set *set, ll_probe_eval_fn eval, void *ctx,
                          ll_watch *watch, double tolerance, size_t min_nodes, size_t limit,
                          const char *what, size_t *n_nodes, size_t *n_orders, double *error)
{
    /* The probes accept at MARGIN of the tolerance: they are a sample of
     * the directions (tests/test_convergence.c measured up to 1.03% at
     * other points when they accepted at 1%, and 1.05% at 0.75%: eta 2,
     * alpha 0.5), and the
     * difference to twice the resolution understates the error to the
     * converged one by the factor 1 - 2^-p. */
    const double goal = MARGIN * tolerance;
    probe_cache cache;
    size_t n, m, step, k;
    double e = HUGE_VAL, en, em;
    ll_status s = LL_OK;

    cache.set = set;
    cache.eval = eval;
    cache.ctx = ctx;
    cache.watch = watch;
    cache.count = 0;
    min_nodes += min_nodes % 2;
    n = even_nodes((double)*n_nodes, min_nodes);
    m = *n_orders ? *n_orders : 1;

    /* Grow until (n, m) passes. */
    for (step = 0; s == LL_OK; ++step) {
        size_t n1 = n, m1 = m;
        s = compare(&cache, n, m, 2 * n, 2 * m, &e);
        if (s != LL_OK || e <= goal)
            break;
        if (step == MAX_STEPS || 2 * n > limit || 2 * m > limit) {
            s = ll_fail(LL_ERROR_INVALID_ARGUMENT,
                        "%s: the tolerance %g is not met within %zu nodes x %zu orders (the "
                        "lobes still differ by %.3g from twice that resolution); give the "
                        "resolution yourself (set nodes=N orders=M) or a larger tolerance",
                        what, tolerance, n, m, e);
            break;
        }
        s = compare(&cache, n, m, 2 * n, m, &en);
        if (s == LL_OK)
            s = compare(&cache, n, m, n, 2 * m, &em);
        if (s != LL_OK)
            break;
        if (en > 0.5 * goal)
            n1 = even_nodes(growth(en, goal) * (double)n, min_nodes);
        if (em > 0.5 * goal)
            m1 = (size_t)ceil(growth(em, goal) * (double)m);
        if (n1 == n && m1 == m) {
            n1 = even_nodes(GROW * (double)n, min_nodes);
            m1 = (size_t)ceil(GROW * (double)m);
        }
        n = n1;
        m = m1;
    }
    /* Then shrink each while it still passes (the first guess may be
     * generous). */
    for (step = 0; step < MAX_SHRINKS && s == LL_OK; ++step) {
        int moved = 0;
        for (k = 0; k < 2 && s == LL_OK; ++k) {
            size_t n1 = k == 0 ? even_nodes(SHRINK * (double)n, min_nodes) : n;
            size_t m1 = k == 1 ? (size_t)floor(SHRINK * (double)m) : m;
            double e1;
            if (m1 < 1 || (n1 == n && m1 == m))
                continue;
            if (k == 0) {
                int hopeless = 0;
                s = screen(&cache, n1, n, m, goal, &hopeless);
                if (s != LL_OK || hopeless)
                    continue;
            }
            s = compare(&cache, n1, m1, 2 * n1, 2 * m1, &e1);
            if (s == LL_OK && e1 <= goal) {
                n = n1;
                m = m1;
                e = e1;
                moved = 1;
            }
        }
        if (!moved)
            break;
    }
    for (k = 0; k < cache.count; ++k)
        ll_free(cache.values[k]);
    if (s != LL_OK)
        return s;
    *n_nodes = n;
    *n_orders = m;
    if (error)
        *error = e;
    return LL_OK;
}
