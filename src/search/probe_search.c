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
 * share them: the growth asks for (n, m), (2n, 2m), (2n, m), (n, 2m),
 * and screens the counts just above one that failed against its (2n, 2m)
 * before it steps past them (ladder()).
 */
#include "search/probe.h"

#include <math.h>

#define MAX_EVALS 48
#define GROW 1.25
#define SHRINK 0.85
#define MAX_STEPS 40
#define MAX_SHRINKS 3
#define MARGIN 0.6
/* The screen (screen()) accepts a candidate up to goal / SCREEN_SLACK: it
 * differs from the candidate's own comparison both ways (0.87 to 1.12 of
 * it measured), and a candidate it wrongly ruled out would end the
 * shrinking early -- the coated-gold example had stayed at 610 nodes where
 * its own comparisons take 442. */
#define SCREEN_SLACK 0.85
/* The growth's candidates (ladder()) reach this factor above the node
 * count that failed: their screen is against that count's (2n, 2m), which
 * is then at least 2 / LADDER_REACH times the candidate. Under an error
 * falling like n^-2, such a screen is 0.81 to 1 of the error against the
 * candidate's own twice (1 - 1.25^2 / 4 = 0.61 against 0.75), so it never
 * turns away a candidate that passes; a larger reach would. At 1.2 the
 * frosted glass example (eta 1.5, alpha 0.3) failed at 184 nodes, could
 * not screen 230 and grew to 316, whose 632-node reference cost more than
 * the answer's (230 against 460) and took the search from 0.40 to 0.64 s. */
#define LADDER_REACH 1.25

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

/* The error of (n1, m1) against the (n_ref, m_ref) already made (HUGE_VAL
 * if forgotten): a screen before the comparison with its own twice, whose
 * reference costs four times its candidate (the compensation's albedos
 * are O(n^2)). Against the (2n, 2m) of a larger n that passed it was
 * 0.87 to 0.92 of the error against (2 n1, 2m) (the README's coats, eta
 * 1.5, alpha 0.1 and 0.15, at 236, 376, 442 and 520 nodes). */
static ll_status screen(probe_cache *c, size_t n1, size_t m1, size_t n_ref, size_t m_ref,
                        double *error)
{
    const double *a, *ref = NULL;
    size_t k;
    ll_status s;
    *error = HUGE_VAL;
    for (k = 0; k < c->count; ++k)
        if (c->n[k] == n_ref && c->m[k] == m_ref)
            ref = c->values[k];
    if (!ref)
        return LL_OK;
    s = cached(c, n1, m1, &a);
    if (s != LL_OK)
        return s;
    /* (cached() may have forgotten ref while computing a: look it up again.) */
    for (k = 0, ref = NULL; k < c->count; ++k)
        if (c->n[k] == n_ref && c->m[k] == m_ref)
            ref = c->values[k];
    if (ref)
        *error = ll_probe_error(c->set, a, ref);
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

/* The growth's cheaper step below n1, the next node count that the error
 * of n (failed against (2n, 2m)) asks for: the counts the shrinking would
 * try below n1 (n1 SHRINK^k, k <= MAX_SHRINKS) that are above n and within
 * LADDER_REACH of it are screened against n's (2n, 2m), the smallest
 * first, and the first within the goal (with SCREEN_SLACK) is compared
 * with its own twice. The growth's steps, aimed by an assumed rate,
 * overshoot where the error falls faster: coated gold's coat failed at
 * 392 nodes and grew to 610, whose reference (1220) alone cost more than
 * its answer's (442 against 884); a screen costs a quarter of a
 * comparison.
 *
 * The error is not monotone in n, and a candidate so close above a
 * failure may pass in a dip of it that the points between the probes do
 * not share: copper, alpha 0.8 failed at 144, and 166 passed its own twice
 * (0.53%) where tests/test_convergence.c's points were 1.58% off; the
 * growth's own step, 226, is 0.79% off there. So a passing candidate is
 * kept only if the next count of the ladder above it also screens within
 * the goal against the candidate's (2n, 2m). *next: the candidate that
 * passed (then its comparison is made), or one that failed its own
 * comparison (the growth goes on from it), or 0 (the growth takes n1). */
static ll_status ladder(probe_cache *c, size_t n, size_t m, size_t n1, size_t m1, double goal,
                        size_t min_nodes, size_t *next)
{
    size_t cand[MAX_SHRINKS + 1], count = 0, prev = n1, k;
    ll_status s = LL_OK;
    *next = 0;
    cand[count++] = n1;
    for (k = 0; k < MAX_SHRINKS; ++k) {
        size_t c1 = even_nodes(SHRINK * (double)prev, min_nodes);
        if (c1 == prev || c1 <= n)
            break;
        cand[count++] = prev = c1;
    }
    /* (cand[] falls from n1; cand[0] is n1 itself, never screened.) */
    while (count > 1 && s == LL_OK) {
        size_t c1 = cand[--count];
        double e1;
        if ((double)c1 > LADDER_REACH * (double)n)
            break;
        s = screen(c, c1, m1, 2 * n, 2 * m, &e1);
        if (s != LL_OK || e1 > goal / SCREEN_SLACK)
            continue;
        s = compare(c, c1, m1, 2 * c1, 2 * m1, &e1);
        if (s != LL_OK || e1 > goal) {
            *next = c1;
            break;
        }
        s = screen(c, cand[count - 1], m1, 2 * c1, 2 * m1, &e1);
        if (s == LL_OK && e1 <= goal / SCREEN_SLACK)
            *next = c1;
        break;
    }
    return s;
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
        if (n1 > n) {
            size_t cheaper;
            s = ladder(&cache, n, m, n1, m1, goal, min_nodes, &cheaper);
            if (s != LL_OK)
                break;
            if (cheaper)
                n1 = cheaper;
        }
        n = n1;
        m = m1;
    }
    /* Then shrink (the first guess may be generous): n to the smallest of
     * n SHRINK^k, k <= MAX_SHRINKS, that still passes, then m by SHRINK
     * while it passes (up to MAX_SHRINKS times). The candidates of n are
     * screened against the (2n, 2m) already made, the largest first (the
     * error grows as n falls), and only the smallest that screens within
     * the goal (with SCREEN_SLACK) is compared against its own twice, then
     * the larger ones should it fail: each such reference costs four times
     * its candidate. */
    if (s == LL_OK) {
        size_t cand[MAX_SHRINKS], n_cand = 0, prev = n;
        for (k = 0; k < MAX_SHRINKS && s == LL_OK; ++k) {
            size_t n1 = even_nodes(SHRINK * (double)prev, min_nodes);
            double e1;
            if (n1 == prev)
                break;
            s = screen(&cache, n1, m, 2 * n, 2 * m, &e1);
            if (s != LL_OK || e1 > goal / SCREEN_SLACK)
                break;
            cand[n_cand++] = prev = n1;
        }
        while (n_cand > 0 && s == LL_OK) {
            size_t n1 = cand[--n_cand];
            double e1;
            s = compare(&cache, n1, m, 2 * n1, 2 * m, &e1);
            if (s == LL_OK && e1 <= goal) {
                n = n1;
                e = e1;
                break;
            }
        }
    }
    for (step = 0; step < MAX_SHRINKS && s == LL_OK; ++step) {
        size_t m1 = (size_t)floor(SHRINK * (double)m);
        double e1;
        if (m1 < 1 || m1 == m)
            break;
        s = compare(&cache, n, m1, 2 * n, 2 * m1, &e1);
        if (s != LL_OK || e1 > goal)
            break;
        m = m1;
        e = e1;
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
