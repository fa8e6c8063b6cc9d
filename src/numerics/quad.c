/*
 * Quadrature rules on [-1, 1]: Gauss-Legendre, Gauss-Lobatto and the
 * composite Newton-Cotes rules (Simpson, Simpson 3/8). Numerics only.
 *
 * The Gauss nodes are found by Newton's method in the angle theta, x =
 * cos(theta), on the three-term Legendre recurrence, started from Bessel-zero
 * asymptotics (Olver; see Hale & Townsend, "Fast and accurate computation of
 * Gauss-Legendre and Gauss-Jacobi quadrature nodes and weights", SISC 2013).
 * Working in theta keeps sin(theta) = sqrt(1 - x^2) exact to rounding near
 * x = +-1, where 1 - x*x would cancel; that cancellation and starting Newton
 * in x from Chebyshev points are why the original loses accuracy past
 * n ~ 200. Each node costs O(n), so a rule costs O(n^2): about 0.12 s at
 * n = 4096 (measured on one core).
 *
 * Only the half x > 0 is computed; the other half is its exact mirror, so
 * nodes are exactly antisymmetric and weights exactly symmetric, as the
 * layer code needs (it pairs mu with -mu).
 */
#include "support/support.h"
#include "support/watch.h"
#include "layerlab/ll_quad.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Newton stops when a step is below this fraction of the root spacing pi/n:
 * with quadratic convergence the next error would be ~n * step^2, far below
 * rounding. */
#define LL_QUAD_STEP_FRACTION 1e-9
/* Newton steps allowed per root; from the starting guesses one step is
 * needed for n in the thousands, two or three for small n (measured). */
#define LL_QUAD_MAX_NEWTON 50

/* Which polynomial's roots in theta a Newton iteration looks for. */
typedef enum {
    LL_QUAD_ROOTS_OF_P, /* P_n(cos theta): Gauss-Legendre nodes */
    LL_QUAD_ROOTS_OF_DP /* d/dtheta P_n(cos theta): Gauss-Lobatto interior nodes */
} ll_quad_roots;

/* P_n and P_n - P_{n-1} (n >= 1) at x = cos(theta) = 1 - delta, with
 * delta = 2 sin^2(theta / 2). Bonnet's recurrence
 * (k + 1) P_{k+1} = (2k + 1) x P_k - k P_{k-1} is run on the differences
 * D_k = P_k - P_{k-1} (as in Reinsch's modification of Clenshaw's recurrence):
 *     (k + 1) D_{k+1} = k D_k - (2k + 1) delta P_k,   P_{k+1} = P_k + D_{k+1},
 * so only delta enters, never x. Near x = 1 the rounding of x would
 * otherwise move the computed roots by ~eps / sin(theta) and the end weights
 * by ~1e-10 relative at n = 4096. Stable for x in [0, 1]. */
static void legendre_at_angle(size_t n, double theta, double *p_n, double *d_n)
{
    double h = sin(0.5 * theta);
    double delta = 2.0 * h * h;
    double p = 1.0 - delta, d = -delta;
    size_t k;
    for (k = 1; k < n; ++k) {
        /* The same step as (k D_k - (2k + 1) delta P_k) / (k + 1), written
         * as (D - 2 delta P) - (D - delta P) / (k + 1) so that the division
         * (by its reciprocal, computed off the loop-carried dependency
         * chain) only touches a correction term: the rounding of 1 / (k + 1),
         * common to every root, then no longer biases all weights alike
         * (measured: sum of weights off by 1.4e-14 at n = 4096 otherwise). */
        double r = 1.0 / ((double)k + 1.0);
        double delta_p = delta * p;
        d = (d - 2.0 * delta_p) - r * (d - delta_p);
        p += d;
    }
    *p_n = p;
    *d_n = d;
}

/* d/dtheta P_n(cos theta) = n (x P_n - P_{n-1}) / sin(theta) =
 * n (D_n - delta P_n) / sin(theta), with D_n, delta as above. */
static double legendre_angle_derivative(size_t n, double theta, double p_n, double d_n)
{
    double h = sin(0.5 * theta);
    return (double)n * (d_n - 2.0 * h * h * p_n) / sin(theta);
}

/* McMahon's expansion of the k-th positive zero of J_nu (nu = 0 or 1),
 * Abramowitz & Stegun 9.5.12, three terms: off by less than 2e-3 at k = 1
 * and far less beyond, well inside Newton's basin (zeros are ~pi apart). */
static double bessel_zero(int nu, size_t k)
{
    double mu = 4.0 * nu * nu;
    double beta = ((double)k + 0.5 * nu - 0.25) * LL_PI;
    double e = 8.0 * beta;
    return beta - (mu - 1.0) / e - 4.0 * (mu - 1.0) * (7.0 * mu - 31.0) / (3.0 * e * e * e);
}

/* Starting angle of the k-th root (k = 1 nearest theta = 0) of P_n(cos theta)
 * or of its theta-derivative. The roots of P_n' are those of the Jacobi
 * polynomial P^(1,1)_{n-1}, and P^(a,a)_N(cos theta) behaves like
 * J_a(rho theta) with rho = N + a + 1/2 = n + 1/2 in both cases, so the
 * roots sit near psi = j_{a,k} / rho (Gatteschi). The second-order term
 * (1 - 4 a^2) (psi cot psi - 1) / (8 psi rho^2) blends that boundary form
 * with Gatteschi & Pittaluga's interior one, phi - (a^2 - 1/4) cot(phi) /
 * (2 rho^2) (Tricomi's for a = 0). The guesses improve with n, so the
 * larger the rule, the fewer Newton steps it takes. */
static double initial_angle(ll_quad_roots kind, size_t n, size_t k)
{
    int a = kind == LL_QUAD_ROOTS_OF_P ? 0 : 1;
    double rho = (double)n + 0.5;
    double psi = bessel_zero(a, k) / rho;
    return psi + (1.0 - 4.0 * a * a) * (psi / tan(psi) - 1.0) / (8.0 * psi * rho * rho);
}

/* Newton's method in theta for one root, which must lie in (previous, pi/2]
 * where previous is the root found before it: roots found in increasing order
 * are then all distinct, so none is missed. On return *theta is the root.
 * 0 if Newton did not settle there (never seen; reported rather than
 * trusted). */
static int newton_angle(ll_quad_roots kind, size_t n, double previous, double *theta)
{
    double nd = (double)n;
    double tolerance = LL_QUAD_STEP_FRACTION * LL_PI / nd;
    double t = *theta;
    int iteration;

    for (iteration = 0; iteration < LL_QUAD_MAX_NEWTON; ++iteration) {
        double p, d, dp, step;
        legendre_at_angle(n, t, &p, &d);
        dp = legendre_angle_derivative(n, t, p, d);
        if (kind == LL_QUAD_ROOTS_OF_P) {
            step = p / dp;
        } else {
            /* Legendre's equation in theta, P'' + cot(t) P' + n(n+1) P = 0,
             * gives the derivative of dp. */
            step = dp / (-dp / tan(t) - nd * (nd + 1.0) * p);
        }
        t -= step;
        /* A step below a few ulps of t is rounding noise, not progress. */
        if (fabs(step) <= tolerance || fabs(step) <= 4.0 * DBL_EPSILON * t)
            break;
    }
    if (iteration == LL_QUAD_MAX_NEWTON || !(t > previous) || !(t <= 0.5 * LL_PI))
        return 0;
    *theta = t;
    return 1;
}

/* Mirror the node x > 0 and its weight into positions i (negative side) and
 * n - 1 - i (positive side). */
static void place_pair(double *nodes, double *weights, size_t n, size_t i, double x, double w)
{
    nodes[i] = -x;
    nodes[n - 1 - i] = x;
    weights[i] = w;
    weights[n - 1 - i] = w;
}

/* Shared checks: n >= min_n, both buffers given and distinct. */
static ll_status check_buffers(const char *fn, size_t n, size_t min_n, const double *nodes,
                               const double *weights)
{
    if (n < min_n)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: n = %zu, but the rule needs n >= %zu",
                       fn, n, min_n);
    if (!nodes || !weights)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: the %s buffer is NULL", fn,
                       nodes ? "weights" : "nodes");
    if (nodes == weights)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: nodes and weights must be two different buffers", fn);
    return LL_OK;
}

/* Root k (1 nearest x = 1) of the polynomial `kind` of the given degree,
 * as an angle, starting from the asymptotic guess; the middle root of an odd
 * count is x = 0 exactly. `previous` is root k - 1 (0 for k = 1): Newton's
 * method must land between it and pi / 2. */
static ll_status root_angle(ll_quad_roots kind, size_t degree, size_t k, int middle, double previous,
                            double *theta, ll_watch *w, const char *fn)
{
    if (ll_watch_poll(w))
        return ll_fail(LL_ERROR_CANCELLED, "%s: cancelled", fn);
    if (middle) {
        *theta = 0.5 * LL_PI;
        return LL_OK;
    }
    *theta = initial_angle(kind, degree, k);
    if (!newton_angle(kind, degree, previous, theta))
        return ll_fail(LL_ERROR_NUMERICAL,
                       "%s: Newton's method did not settle on root %zu of P_%zu%s", fn, k,
                       degree, kind == LL_QUAD_ROOTS_OF_DP ? "'" : "");
    return LL_OK;
}

/* The rules proper, into buffers checked by the caller; one unit of
 * progress and one poll per root (each O(n): the rule is O(n^2)). */
static ll_status legendre_rule(size_t n, double *nodes, double *weights, ll_watch *w)
{
    static const char fn[] = "ll_quad_gauss_legendre";
    double theta = 0.0;
    size_t k;

    /* Roots of P_n, k = 1 nearest x = 1, then x = 0 for odd n. The weight
     * 2 / ((1 - x^2) P_n'(x)^2) (A&S 25.4.29) is 2 / (dP_n/dtheta)^2 in
     * theta, which needs no 1 - x^2. */
    for (k = 1; k <= (n + 1) / 2; ++k) {
        double p, d, dp;
        int middle = 2 * k - 1 == n;
        ll_status s = root_angle(LL_QUAD_ROOTS_OF_P, n, k, middle, theta, &theta, w, fn);
        if (s != LL_OK)
            return s;
        legendre_at_angle(n, theta, &p, &d);
        dp = legendre_angle_derivative(n, theta, p, d);
        place_pair(nodes, weights, n, k - 1, middle ? 0.0 : cos(theta), 2.0 / (dp * dp));
        ll_watch_advance(w, 1);
    }
    return LL_OK;
}

static ll_status lobatto_rule(size_t n, double *nodes, double *weights, ll_watch *w)
{
    static const char fn[] = "ll_quad_gauss_lobatto";
    double theta = 0.0, scale;
    size_t k, m = n - 1;

    /* End points, then the roots of P_m' (m = n - 1), k = 1 nearest x = 1,
     * then x = 0 for odd n. Every weight is 2 / (n (n - 1) P_m(x)^2)
     * (A&S 25.4.32); P_m(+-1)^2 = 1. */
    scale = 2.0 / ((double)n * (double)m);
    place_pair(nodes, weights, n, 0, 1.0, scale);
    for (k = 1; k <= (n - 1) / 2; ++k) {
        double p, d;
        int middle = 2 * k + 1 == n;
        ll_status s = root_angle(LL_QUAD_ROOTS_OF_DP, m, k, middle, theta, &theta, w, fn);
        if (s != LL_OK)
            return s;
        legendre_at_angle(m, theta, &p, &d);
        place_pair(nodes, weights, n, k, middle ? 0.0 : cos(theta), scale / (p * p));
        ll_watch_advance(w, 1);
    }
    return LL_OK;
}

typedef ll_status (*rule_fn)(size_t n, double *nodes, double *weights, ll_watch *w);

/* A Gauss rule with a monitor: without a callback straight into the
 * caller's buffers, as always; with one into scratch, copied out only when
 * the rule is complete and not cancelled, so that a cancel leaves the
 * buffers as they were. */
static ll_status watched_rule(const char *fn, rule_fn rule, size_t n, size_t min_n,
                              double *nodes, double *weights, const ll_monitor *monitor)
{
    ll_watch w;
    double *scratch = NULL, *x = nodes, *wt = weights;
    ll_status s = check_buffers(fn, n, min_n, nodes, weights);
    if (s == LL_OK)
        s = ll_watch_begin(&w, monitor, fn);
    if (s != LL_OK)
        return s;
    if (w.progress) {
        scratch = ll_alloc_array(n, 2 * sizeof(double));
        if (!scratch)
            return ll_fail(LL_ERROR_OUT_OF_MEMORY,
                           "%s: out of memory for the scratch copy of %zu nodes", fn, n);
        x = scratch;
        wt = scratch + n;
    }
    s = ll_watch_stage(&w, "quadrature", 0.0, 1.0, (n + 1) / 2) ? ll_watch_check(&w, fn)
                                                                 : LL_OK;
    if (s == LL_OK)
        s = rule(n, x, wt, &w);
    s = ll_watch_finish(&w, s, fn);
    if (s == LL_OK && scratch) {
        memcpy(nodes, x, n * sizeof(double));
        memcpy(weights, wt, n * sizeof(double));
    }
    ll_free(scratch);
    return s;
}

ll_status ll_quad_gauss_legendre(size_t n, double *nodes, double *weights,
                                 const ll_monitor *monitor)
{
    return watched_rule("ll_quad_gauss_legendre", legendre_rule, n, 1, nodes, weights,
                        monitor);
}

ll_status ll_quad_gauss_lobatto(size_t n, double *nodes, double *weights,
                                const ll_monitor *monitor)
{
    return watched_rule("ll_quad_gauss_lobatto", lobatto_rule, n, 2, nodes, weights, monitor);
}

/* Composite closed Newton-Cotes rule: n equidistant nodes split into panels
 * of `panel` intervals, each integrated with the integer weights
 * pattern[0..panel] times `unit`. Node i is (2i - (n-1)) / (n-1): the end
 * points are exactly +-1 and, since the numerators are exact integers and
 * division rounds symmetrically, the nodes are exactly antisymmetric. */
static void composite_newton_cotes(size_t n, size_t panel, const double *pattern, double unit,
                                   double *nodes, double *weights)
{
    double intervals = (double)(n - 1);
    size_t i;
    for (i = 0; i < n; ++i) {
        size_t j = i % panel;
        /* Panel joints belong to two panels: end weight + start weight. */
        double w = (j == 0 && i != 0 && i != n - 1) ? pattern[0] + pattern[panel] : pattern[j];
        nodes[i] = (2.0 * (double)i - intervals) / intervals;
        weights[i] = w * unit;
    }
}

ll_status ll_quad_composite_simpson(size_t n, double *nodes, double *weights)
{
    static const char fn[] = "ll_quad_composite_simpson";
    static const double pattern[3] = {1.0, 4.0, 1.0};
    ll_status s = check_buffers(fn, n, 3, nodes, weights);
    if (s != LL_OK)
        return s;
    if (n % 2 == 0)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: n = %zu is even; Simpson's rule needs an odd n (an even number "
                       "of intervals)",
                       fn, n);
    /* Panels of two intervals of width h = 2 / (n - 1): weights h/3 (1, 4, 1). */
    composite_newton_cotes(n, 2, pattern, 2.0 / (3.0 * (double)(n - 1)), nodes, weights);
    return LL_OK;
}

ll_status ll_quad_composite_simpson38(size_t n, double *nodes, double *weights)
{
    static const char fn[] = "ll_quad_composite_simpson38";
    static const double pattern[4] = {1.0, 3.0, 3.0, 1.0};
    ll_status s = check_buffers(fn, n, 4, nodes, weights);
    if (s != LL_OK)
        return s;
    if ((n - 1) % 3 != 0)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: n = %zu, but Simpson's 3/8 rule needs n - 1 divisible by 3", fn,
                       n);
    /* Panels of three intervals of width h = 2 / (n - 1): weights 3h/8 (1, 3, 3, 1). */
    composite_newton_cotes(n, 3, pattern, 3.0 / (4.0 * (double)(n - 1)), nodes, weights);
    return LL_OK;
}
