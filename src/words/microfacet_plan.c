/*
 * The plan of one pair of zenith cosines of a rough interface: the
 * exponent A + B cos phi of its peak, whether and how far the lobe is
 * widened, its window of azimuths and the branch points of g there (which
 * decide between the Chebyshev maps and the Filon path), and the factors
 * of g that do not depend on the azimuth (g itself: microfacet_profile.c;
 * microfacet_series.c describes the method).
 */
#include "words/microfacet_pair.h"

#include "numerics/series.h"

#include <math.h>

#define WINDOW_LOG 27.6       /* the window: B v <= -ln(1e-12)                 */
#define GRID_PER_OCTAVE 4.0   /* B_k = GRID_B0 2^((k - 1) / 4), k >= 1         */
#define GRID_B0 (1.0 / 16.0)  /* below this B, B_k = 0 (k = 0)                 */
#define NEAR_SINGULAR 0.1     /* a branch point of g within this fraction of
                               * the window from it spoils the Chebyshev form  */
#define NEGLIGIBLE_LOG -23.1  /* below ln(NEGLIGIBLE) = -23.03 by more than
                               * exp's rounding                                */

double ll_microfacet_smith_g1(double tan_theta, double alpha)
{
    double a = 1.0 / (alpha * tan_theta);
    if (a >= 1.6) /* also tan_theta = 0 (a = inf) */
        return 1.0;
    return (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a);
}

double ll_microfacet_grid_b(size_t k)
{
    return k == 0 ? 0.0 : GRID_B0 * exp2((double)(k - 1) / GRID_PER_OCTAVE);
}

/* The grid point at or below b. Every planned pair asks, and log2 and
 * exp2 are library calls; so where b lies well inside a grid interval
 * (1e-9 of it from either end, where the floor of 4 (log2(b) + 4), off
 * from b's own by about 1e-12 at most, cannot differ), the interval is
 * read from b's exponent and mantissa instead, giving the same index
 * (tests/test_microfacet_profile.c compares the two). */
size_t ll_microfacet_grid_index(double b)
{
    /* 2^(j / 4), j = 0 .. 4 (only 1e-9 of accuracy matters) */
    static const double quarter[5] = { 1.0, 1.189207115002721, 1.4142135623730951,
                                       1.6817928305074290, 2.0 };
    size_t k;
    int e, j;
    double r;
    if (b < GRID_B0)
        return 0;
    r = 2.0 * frexp(b, &e); /* b = r 2^(e - 1), 1 <= r < 2 (not NaN or inf) */
    j = r >= quarter[2] ? (r >= quarter[3] ? 3 : 2) : (r >= quarter[1] ? 1 : 0);
    if (r > quarter[j] * (1.0 + 1e-9) && r < quarter[j + 1] * (1.0 - 1e-9))
        /* (log2(GRID_B0) = -4, and b >= GRID_B0: e - 1 >= -4) */
        return (size_t)(GRID_PER_OCTAVE * (e - 1 + 4)) + (size_t)j + 1;
    k = (size_t)floor(GRID_PER_OCTAVE * (log2(b) - log2(GRID_B0))) + 1;
    while (k > 1 && ll_microfacet_grid_b(k) > b) /* guard the rounding of log2 */
        --k;
    return k;
}

/* The window in v = 1 - cos phi for exp(-b v): v <= WINDOW_LOG / b, at most
 * the whole circle (v <= 2). */
double ll_microfacet_window_delta(double b)
{
    return b * 2.0 > WINDOW_LOG ? WINDOW_LOG / b : 2.0;
}

/* The azimuth where v = 1 - cos phi reaches delta, without the
 * cancellation of acos(1 - delta) for tiny delta. */
double ll_microfacet_window_angle(double delta)
{
    return delta >= 2.0 ? LL_PI : 2.0 * asin(sqrt(0.5 * delta));
}

/* Where g, as a function of u = v / Delta on the window, stops being
 * analytic: record a branch point at u (in t = wi . wo, t(u) = t_0 +
 * sin_prod Delta u). Inside the window it is a kink to split at. Close
 * outside, it slows the Chebyshev interpolant's convergence (the error of
 * 16 points falls like rho^-16, rho = |y| + sqrt(y^2 - 1), y = 2u - 1: a
 * point 0.1 outside gives rho = 1.86 and 5e-5 times the size of the
 * singular part), so such pairs take the Filon path too, with the panels
 * graded towards that end (and near_start, near_end say how far out the
 * nearest such point lies, which bounds how fine that grading must be). */
static void note_branch_point(pair_plan *p, double u, double delta)
{
    if (u > ANGLE_EPS && u < 1.0 - ANGLE_EPS) {
        p->split = ll_microfacet_window_angle(delta * u);
        p->filon = 1;
    } else if (u > -NEAR_SINGULAR && u <= ANGLE_EPS) {
        p->near_start = p->grade_start ? fmax(p->near_start, u) : u;
        p->grade_start = p->filon = 1;
    } else if (u >= 1.0 - ANGLE_EPS && u < 1.0 + NEAR_SINGULAR) {
        p->near_end = p->grade_end ? fmin(p->near_end, u) : u;
        p->grade_end = p->filon = 1;
    }
}

/* The window and the branch points of g on or near it; returns 0 if no
 * azimuth refracts into the pair. The branch points, in t:
 *  - reflection: t = -1, where wi.m = sqrt((1 + t) / 2) vanishes (grazing
 *    pairs come close), and for a dielectric t = 1 - 2 eta^2, where
 *    Fresnel's cos(theta_t) does: total internal reflection below it for
 *    eta < 1, a branch point outside the range otherwise;
 *  - refraction: t = -1 / eta_denser, where wi.m or wo.m changes sign and
 *    refraction ends (no light beyond it), and t = -(1 + eta^2) / (2 eta),
 *    where |H| vanishes. */
int ll_microfacet_classify_window(const ll_microfacet_model *mf, pair_plan *p)
{
    double delta = mf->ggx ? 2.0 : ll_microfacet_window_delta(p->b), t0 = -p->sin_prod - p->mu_prod;
    double span = p->sin_prod * delta;
    p->phi_end = ll_microfacet_window_angle(delta);
    p->filon = p->grade_start = p->grade_end = 0;
    p->split = p->near_start = 0.0;
    p->near_end = 1.0;
    if (!p->reflect) {
        double dense = p->eta > 1.0 ? p->eta : 1.0 / p->eta, t_end = -1.0 / dense;
        if (!(t0 < t_end))
            return 0; /* refraction ends before phi = 0 */
        if (!(span > 0.0))
            return 1; /* g does not depend on phi */
        note_branch_point(p, (t_end - t0) / span, delta);
        note_branch_point(p, (-(1.0 + p->eta * p->eta) / (2.0 * p->eta) - t0) / span, delta);
        return 1;
    }
    if (!(span > 0.0))
        return 1;
    note_branch_point(p, (-1.0 - t0) / span, delta);
    if (!mf->conductor)
        note_branch_point(p, (1.0 - 2.0 * p->eta * p->eta - t0) / span, delta);
    return 1;
}

/* The phi-independent factor of g (ll_microfacet_plan_pair): G1(wi) G1(wo) / (pi
 * alpha^2 h_z^4 |mu_i mu_o|), times eta^2 for refraction. */
double ll_microfacet_pair_scale(const ll_microfacet_model *mf, const pair_plan *p, double g1_i,
                                double g1_o, double h_z)
{
    double scale = g1_i * g1_o /
                   (LL_PI * mf->alpha * mf->alpha * (h_z * h_z) * (h_z * h_z) * fabs(p->mu_prod));
    return p->reflect ? scale : scale * p->eta * p->eta;
}

/* Plan a pair, its lobe widened to at most B = b_limit; returns 0 if it
 * does not scatter at all (or negligibly). */
int ll_microfacet_plan_pair(const ll_microfacet_model *mf, double mu_o, double mu_i, double b_limit,
                            pair_plan *p)
{
    double si, so, eta_h, h_z, lateral, inv, e0, tan_i, tan_o;

    if (mu_o == 0.0 || mu_i == 0.0)
        return 0;
    p->reflect = -mu_i * mu_o > 0.0;
    if (!p->reflect && mf->conductor)
        return 0; /* conductors are opaque */
    /* Light with -mu_i > 0 arrives from the side where the relative index is
     * eta; from the other side it is 1/eta (never for conductors, which
     * reflect the same from both sides). */
    p->eta = (-mu_i > 0.0 || mf->conductor) ? mf->eta_re : 1.0 / mf->eta_re;
    p->mu_i = mu_i;
    p->mu_o = mu_o;
    /* (max(0, x) without fmax's library call: x is never -0 nor NaN here,
     * so the comparison gives fmax's double) */
    si = (1.0 - mu_i) * (1.0 + mu_i);
    so = (1.0 - mu_o) * (1.0 + mu_o);
    si = sqrt(si > 0.0 ? si : 0.0);
    so = sqrt(so > 0.0 ? so : 0.0);
    p->sin_prod = si * so;
    p->mu_prod = mu_i * mu_o;

    /* Half vector H = wi + eta_h wo (eta_h = 1 for reflection):
     * tan^2(theta_h) = (lateral^2 + 2 eta_h si so (1 - cos phi)) / h_z^2, so
     * A + B = -(lateral / (alpha h_z))^2 and B = 2 eta_h si so / (alpha h_z)^2. */
    eta_h = p->reflect ? 1.0 : p->eta;
    h_z = eta_h * mu_o - mu_i;
    if (h_z == 0.0)
        return 0; /* H horizontal for every phi: D = 0 */
    lateral = si - eta_h * so;
    inv = 1.0 / (mf->alpha * h_z);
    p->a_plus_b = -(lateral * inv) * (lateral * inv);
    p->b = 2.0 * eta_h * p->sin_prod * inv * inv;
    if (!(p->b < HUGE_VAL))
        return 0;
    if (mf->ggx)
        return ll_microfacet_plan_ggx(mf, p, b_limit, mu_i, si, so, h_z);
    /* The series' first term i0e(B) e^(A + B), with i0e <= 1. Most of a
     * layer's pairs lie far outside the lobe, where A + B alone rules
     * them out: below NEGLIGIBLE_LOG, e^(A + B) < NEGLIGIBLE whatever
     * exp's rounding, so the test below would fail too. And where
     * e^(A + B) / (2 sqrt(1 + 2 pi B)) reaches NEGLIGIBLE, so does
     * e^(A + B) i0e(B), as i0e(B) >= 1 / sqrt(1 + 2 pi B) for every B >= 0
     * (equal at B = 0; i0e ~ (2 pi B)^-1/2 (1 + 1 / (8 B)) for large B),
     * so i0e's series is summed only for the pairs in between. */
    if (!(p->a_plus_b >= NEGLIGIBLE_LOG))
        return 0;
    e0 = exp(p->a_plus_b);
    if (!(e0 >= NEGLIGIBLE) ||
        (!(e0 * (0.5 / sqrt(1.0 + 2.0 * LL_PI * p->b)) >= NEGLIGIBLE) &&
         !(e0 * ll_bessel_i0e(p->b) >= NEGLIGIBLE)))
        return 0;
    p->widened = p->b > b_limit;
    if (p->widened) {
        /* Widen, keeping the integral i0e(B) e^(A + B) of the peak (the
         * original's rule; ll_microfacet_series then restores the energy
         * of the whole lobe, g included). */
        p->a_plus_b += log(ll_bessel_i0e(p->b) / ll_bessel_i0e(b_limit));
        p->b = b_limit;
        e0 = exp(p->a_plus_b);
    }
    p->peak = e0;
    p->grid = ll_microfacet_grid_index(p->b);
    if (!ll_microfacet_classify_window(mf, p))
        return 0;

    /* The phi-independent factors of g: shadowing depends on phi only
     * through which side of the microfacet a direction sees (handled per
     * sample), D = |H|^4 / (pi alpha^2 h_z^4) without its exponential. */
    tan_i = si / fabs(mu_i);
    tan_o = so / fabs(mu_o);
    p->sign_h = h_z > 0.0 ? 1.0 : -1.0;
    p->scale = ll_microfacet_smith_g1(tan_i, mf->alpha) *
               ll_microfacet_smith_g1(tan_o, mf->alpha) /
               (LL_PI * mf->alpha * mf->alpha * (h_z * h_z) * (h_z * h_z) * fabs(p->mu_prod));
    if (!p->reflect)
        p->scale *= p->eta * p->eta;
    return 1;
}
