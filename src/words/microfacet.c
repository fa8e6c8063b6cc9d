/*
 * Rough interfaces: the Beckmann or GGX microfacet BSDF of Walter et al. 2007
 * (dielectric or conductor) as a layer (Jakob et al. 2014, section 6.2 and
 * the appendix; the original layerlab's microfacetFourierSeries and
 * Layer::setMicrofacet, whose BSDF and conventions this reproduces).
 *
 * Per pair of zenith cosines the BSDF depends on the azimuth phi only
 * through t = wi . wo, and the Beckmann exponent -tan^2(theta_h) / alpha^2
 * is exactly A + B cos phi, so
 *     f(phi) = exp(A + B cos phi) g(phi) = e^(A + B) E_B(v) g(v),
 *     v = 1 - cos phi,  E_B(v) = exp(-B v),
 * where E_B carries the sharp peak (width ~ B^-1/2) and g (Fresnel,
 * shadowing, Jacobian, the rest of D) is smooth and wide.
 *
 * The method. Only the azimuths where E_B > e^-27.6 = 1e-12 matter: the
 * window v <= Delta = 27.6 / B (the whole circle for small B). On it, g is
 * a smooth function of u = v / Delta in [0, 1] and is replaced by its
 * Chebyshev interpolant at 16 Chebyshev points of u. The Fourier series of
 * f is then a fixed linear map of those 16 samples:
 *     f_l = e^(A + B) sum_i M_B[l][i] g(u_i),
 *     M_B = (cosine series of E_B T_j(2u - 1) on the window) x (Chebyshev
 *           transform),
 * where M_B depends on B alone. B is rounded down to a grid of 4 points per
 * octave, B_k <= B, and the rest exp(-(B - B_k) v) moves into g (a smooth
 * factor); the matrices of the grid points that a layer's pairs use are
 * computed once per call, by Gauss-Legendre quadrature of the window. A
 * pair then costs 16 evaluations of g and one small matrix-vector product.
 *
 * Why not the original's route (the cosine series of exp(A + B cos phi)
 * from Bessel function ratios, convolved with a 12-term cosine series of
 * g fitted by least squares on [0, phi_max] via an SVD): the cosines are
 * nearly dependent on a short interval, so the fit keeps only 2-4 usable
 * terms once small singular values are dropped, and the fitted polynomial
 * runs free outside [0, phi_max] where g can be 10^4 times larger (the
 * 1 / cos^4 of D at grazing angles). Measured against direct integration
 * of the BSDF it misses by 1e-3 to 2e-2 of the peak at grazing pairs and
 * by up to 25% near critical azimuths. The Chebyshev form above is well
 * conditioned (|T_j| <= 1 on the window, where the fit is exact at the
 * nodes) and stays below 2e-4 (test_microfacet.c checks 1e-3).
 *
 * Where g has a kink inside the window (the critical azimuth of total
 * internal reflection, or the azimuth where refraction ends), or a branch
 * point just outside it (grazing pairs), no polynomial fits it (3-10% of
 * the pairs). The product f itself is then integrated by Filon's rule for
 * every order, split at the kink and with panels shrinking geometrically
 * towards it (Fresnel's square-root behaviour there): Filon is exact for
 * the oscillation of cos(l phi) whatever l.
 *
 * Lobes too sharp for the layer's orders (grazing angles) are widened as
 * in the original, but keep the energy (order 0) of the true lobe: the
 * original keeps only the integral of exp(A + B cos phi), and with g not
 * constant across the wider lobe that adds up to 10% at grazing angles
 * (R + T = 1.06 for eta = 1.5, alpha = 0.3 at its 61 orders).
 *
 * GGX has the same g and the same A + B cos phi, but its peak factor
 * (1 - A - B cos phi)^-2 has tails that never fall below 1e-12 on the
 * circle: its window is the whole circle, where the peak's series is known
 * in closed form and g is interpolated in cos phi (words/microfacet_ggx.h);
 * its Filon path grades the panels geometrically away from the peak.
 */
#include "words/microfacet.h"
#include "support/watch.h"

#include "numerics/filon.h"
#include "words/fresnel.h"
#include "words/microfacet_ggx.h"
#include "layer/layer.h"
#include "numerics/series.h"

#include "layerlab/ll_quad.h"

#include <cblas.h>
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define CHEB 16               /* Chebyshev points of g on the window           */
#define WINDOW_LOG 27.6       /* the window: B v <= -ln(1e-12)                 */
#define GAUSS_NODES 128       /* quadrature of the window for the matrices     */
#define GRID_PER_OCTAVE 4.0   /* B_k = GRID_B0 2^((k - 1) / 4), k >= 1         */
#define GRID_B0 (1.0 / 16.0)  /* below this B, B_k = 0 (k = 0)                 */
#define TAIL_GOAL 1e-6        /* matrices keep orders until exp(-B v)'s series
                               * falls below this fraction of its first term   */
#define FILON_EXTRA 100       /* a kinked f may need this many orders beyond
                               * its peak's (as the original allows)           */
#define FILON_SAMPLES 129     /* Filon samples of a main piece (odd)           */
#define FILON_LEVELS 4        /* geometric pieces towards a singular point     */
#define FILON_LEVEL_SAMPLES 5 /* samples of each of them (odd)                 */
#define NEAR_SINGULAR 0.1     /* a branch point of g within this fraction of
                               * the window from it spoils the Chebyshev form  */
#define ANGLE_EPS 1e-7        /* azimuths this close count as equal            */
#define NEGLIGIBLE 1e-10      /* skip pairs whose peak series starts below     */
#define GGX_FILON_SAMPLES 17  /* Filon samples of each of GGX's pieces (odd),
                               * which double in width away from the peak      */
#define GGX_KINK_SAMPLES 17   /* samples of each piece towards a singular
                               * point (odd); the pieces shrink by 4 ...       */
#define GGX_KINK_LEVELS 8     /* ... this many times                           */
#define GGX_NEGLIGIBLE 1e-6   /* Filon pieces of GGX below this fraction of the
                               * pair's peak add nothing (ggx_piece)           */
#define GGX_TAIL_GOAL 1e-4    /* GGX's peak series falls geometrically: its
                               * terms below 1e-4 (a tenth of what the layer
                               * keeps, LL_MICROFACET_RELERR) would double the
                               * orders of TAIL_GOAL's 1e-6 for nothing        */

/* The largest B whose exp(B cos phi) series a layer with n orders holds at
 * relative error 1e-3 (the original's fit, Bmax(n, 1e-3)). A sharper lobe
 * is widened to B_max, keeping its energy (see ll_microfacet_series). */
static double max_b(size_t n_orders) { return 0.0538 * pow((double)n_orders, 2.05001); }

/* The precomputed map of one grid point. */
typedef struct grid_entry {
    double b;            /* B_k                                            */
    double delta;        /* the window 0 <= v <= delta                     */
    size_t len;          /* orders it produces                             */
    double cos_phi[CHEB];/* cos phi at the Chebyshev points                */
    double u[CHEB];      /* u there                                        */
    double *matrix;      /* CHEB x len, point-major: matrix[i * len + l]   */
} grid_entry;

struct ll_microfacet_model {
    double eta_re, eta_im, alpha;
    int conductor;
    int ggx;             /* GGX, else Beckmann                             */
    ll_ggx_basis ggx_basis;
    double b_max;        /* lobes sharper than this are widened            */
    double map_b_max;    /* the maps hold every order up to this B (the
                          * b_max of creation; ll_microfacet_set_orders
                          * may lower b_max, never this)                   */
    size_t max_len;      /* orders wanted                                  */
    size_t n_grid;
    grid_entry **grid;   /* [n_grid] NULL until prepared                   */
};

/* Everything one pair needs, from its two cosines. */
typedef struct pair_plan {
    int reflect;
    double eta;        /* relative index in the half vector wi + eta wo     */
    double a_plus_b;   /* log of the peak of exp(A + B cos phi) (GGX: of
                        * (1 - A - B cos phi)^-2)                           */
    double b;          /* Beckmann: B; GGX: beta (words/microfacet_ggx.h)    */
    int widened;       /* B was reduced to what the orders hold             */
    size_t grid;       /* B_k <= B                                           */
    double phi_end;    /* the window in phi: [0, phi_end]                   */
    int filon;         /* g is not smooth enough: integrate f by Filon      */
    double split;      /* > 0: g has a kink here (inside the window)        */
    int grade_start;   /* a branch point of g lies just before phi = 0 ...  */
    int grade_end;     /* ... or just after phi_end                         */
    /* g from t = wi . wo = -sin_prod cos phi - mu_prod: */
    double sin_prod, mu_prod;
    double sign_h;     /* sign of the half vector's z                       */
    double mu_i, mu_o;
    double scale;      /* G1(wi) G1(wo) / (pi alpha^2 h_z^4 |mu_i mu_o|)    */
} pair_plan;

double ll_microfacet_smith_g1(double tan_theta, double alpha)
{
    double a = 1.0 / (alpha * tan_theta);
    if (a >= 1.6) /* also tan_theta = 0 (a = inf) */
        return 1.0;
    return (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a);
}

static double grid_b(size_t k)
{
    return k == 0 ? 0.0 : GRID_B0 * exp2((double)(k - 1) / GRID_PER_OCTAVE);
}

/* The grid point at or below b. */
static size_t grid_index(double b)
{
    size_t k;
    if (b < GRID_B0)
        return 0;
    k = (size_t)floor(GRID_PER_OCTAVE * (log2(b) - log2(GRID_B0))) + 1;
    while (k > 1 && grid_b(k) > b) /* guard the rounding of log2 */
        --k;
    return k;
}

/* The window in v = 1 - cos phi for exp(-b v): v <= WINDOW_LOG / b, at most
 * the whole circle (v <= 2). */
static double window_delta(double b)
{
    return b * 2.0 > WINDOW_LOG ? WINDOW_LOG / b : 2.0;
}

/* The azimuth where v = 1 - cos phi reaches delta, without the
 * cancellation of acos(1 - delta) for tiny delta. */
static double window_angle(double delta)
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
 * graded towards that end. */
static void note_branch_point(pair_plan *p, double u, double delta)
{
    if (u > ANGLE_EPS && u < 1.0 - ANGLE_EPS) {
        p->split = window_angle(delta * u);
        p->filon = 1;
    } else if (u > -NEAR_SINGULAR && u <= ANGLE_EPS) {
        p->grade_start = p->filon = 1;
    } else if (u >= 1.0 - ANGLE_EPS && u < 1.0 + NEAR_SINGULAR) {
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
static int classify_window(const ll_microfacet_model *mf, pair_plan *p)
{
    double delta = mf->ggx ? 2.0 : window_delta(p->b), t0 = -p->sin_prod - p->mu_prod;
    double span = p->sin_prod * delta;
    p->phi_end = window_angle(delta);
    p->filon = p->grade_start = p->grade_end = 0;
    p->split = 0.0;
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

/* The phi-independent factor of g (plan_pair): G1(wi) G1(wo) / (pi
 * alpha^2 h_z^4 |mu_i mu_o|), times eta^2 for refraction. */
static double pair_scale(const ll_microfacet_model *mf, const pair_plan *p, double g1_i, double g1_o,
                         double h_z)
{
    double scale = g1_i * g1_o /
                   (LL_PI * mf->alpha * mf->alpha * (h_z * h_z) * (h_z * h_z) * fabs(p->mu_prod));
    return p->reflect ? scale : scale * p->eta * p->eta;
}

/* plan_pair for GGX, from Beckmann's A + B = -X_0 and B: the peak factor
 * (1 + X_0)^-2 (1 + beta v)^-2, beta = B / (1 + X_0). */
static int plan_ggx(const ll_microfacet_model *mf, pair_plan *p, double b_limit, double mu_i,
                    double si, double so, double h_z)
{
    double x0 = -p->a_plus_b, e0, gmax;
    p->b /= 1.0 + x0;
    p->a_plus_b = -2.0 * log1p(x0);
    e0 = exp(p->a_plus_b);
    if (!(p->b < HUGE_VAL) || !(e0 > 0.0))
        return 0;
    p->widened = p->b > b_limit;
    if (p->widened) {
        /* Widen, keeping the mean of the peak (the energy of the whole
         * lobe is restored by ll_microfacet_series). */
        p->a_plus_b += log(ll_ggx_peak_mean(p->b) / ll_ggx_peak_mean(b_limit));
        p->b = b_limit;
    }
    p->grid = 0; /* no maps: the peak's series is closed-form */
    if (!classify_window(mf, p))
        return 0;
    p->sign_h = h_z > 0.0 ? 1.0 : -1.0;
    p->scale = pair_scale(mf, p, ll_ggx_smith_g1(si / fabs(mu_i), mf->alpha),
                          ll_ggx_smith_g1(so / fabs(p->mu_o), mf->alpha), h_z);
    /* Negligible when f's mean over phi is, in absolute terms: unlike
     * Beckmann's, the peak factor alone says nothing, as its tails fall
     * like X^-2 ~ h_z^4, which the scale's h_z^-4 makes up for (a grazing
     * pair whose factor is 1e-12 can have f ~ 1). g / scale is at most
     * (1 + t)^2 <= 4 for reflection, |wi.H wo.H| <= (1 + eta)^2 for
     * refraction. */
    gmax = p->reflect ? 4.0 : (1.0 + p->eta) * (1.0 + p->eta);
    return exp(p->a_plus_b) * ll_ggx_peak_mean(p->b) * p->scale * gmax >= NEGLIGIBLE;
}

/* Plan a pair, its lobe widened to at most B = b_limit; returns 0 if it
 * does not scatter at all (or negligibly). */
static int plan_pair(const ll_microfacet_model *mf, double mu_o, double mu_i, double b_limit,
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
    si = sqrt(fmax(0.0, (1.0 - mu_i) * (1.0 + mu_i)));
    so = sqrt(fmax(0.0, (1.0 - mu_o) * (1.0 + mu_o)));
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
        return plan_ggx(mf, p, b_limit, mu_i, si, so, h_z);
    /* The series' first term i0e(B) e^(A + B), with i0e <= 1. */
    e0 = exp(p->a_plus_b);
    if (!(e0 >= NEGLIGIBLE) || !(e0 * ll_bessel_i0e(p->b) >= NEGLIGIBLE))
        return 0;
    p->widened = p->b > b_limit;
    if (p->widened) {
        /* Widen, keeping the integral i0e(B) e^(A + B) of the peak (the
         * original's rule; ll_microfacet_series then restores the energy
         * of the whole lobe, g included). */
        p->a_plus_b += log(ll_bessel_i0e(p->b) / ll_bessel_i0e(b_limit));
        p->b = b_limit;
    }
    p->grid = grid_index(p->b);
    if (!classify_window(mf, p))
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

/* g at the azimuths with the given cosines into g, and g with F = 1 into
 * no_fresnel (either may be NULL). With t = wi . wo and unnormalised H:
 *   reflection:   |H|^2 = 2 (1 + t),  wi.H = 1 + t,
 *                 g = F D G / (4 |mu_i mu_o|) = scale F (1 + t)^2
 *   refraction:   |H|^2 = 1 + eta^2 + 2 eta t,  wi.H = 1 + eta t,
 *                 wo.H = t + eta, and the Jacobian's
 *                 (wi.H)(wo.H) / (wi.H + eta wo.H)^2 = (wi.H)(wo.H)/|H|^4,
 *                 g = scale (1 - F) |(1 + eta t)(t + eta)|
 *                 where both directions see the front of the facet. */
static void sample_profile(const ll_microfacet_model *mf, const pair_plan *p, const double *cos_phi,
                           size_t count, double *g, double *no_fresnel)
{
    size_t k;
    double eta = p->eta, s = p->sign_h;
    for (k = 0; k < count; ++k) {
        double t = -p->sin_prod * cos_phi[k] - p->mu_prod, value, f, unused;
        if (p->reflect) {
            double one_t = fmax(0.0, 1.0 + t);
            double cos_h = s * sqrt(fmin(1.0, 0.5 * one_t)); /* wi . m */
            f = mf->conductor ? ll_fresnel_conductor_kernel(fabs(cos_h), mf->eta_re, mf->eta_im)
                              : ll_fresnel_dielectric_kernel(cos_h, mf->eta_re, &unused);
            value = p->scale * one_t * one_t;
            if (g)
                g[k] = f * value;
        } else {
            double wi_h = 1.0 + eta * t, wo_h = t + eta;
            double len2 = fmax(1e-300, 1.0 + eta * eta + 2.0 * eta * t);
            /* Both sides: v.m cos(theta_v) > 0 (wi.z = -mu_i, wo.z = mu_o). */
            if (s * wi_h * -p->mu_i > 0.0 && s * wo_h * p->mu_o > 0.0) {
                double cos_h = fmax(-1.0, fmin(1.0, s * wi_h / sqrt(len2)));
                f = ll_fresnel_dielectric_kernel(cos_h, mf->eta_re, &unused);
                value = p->scale * fabs(wi_h * wo_h);
                if (g)
                    g[k] = (1.0 - f) * value;
            } else {
                value = 0.0;
                if (g)
                    g[k] = 0.0;
            }
        }
        if (no_fresnel)
            no_fresnel[k] = value;
    }
}

/* ------------------------------------------------- the Filon path */

/* cos(a + k h) for k < count, h = (b - a) / (count - 1), by rotation
 * (the error grows by about one rounding per step). */
static void azimuth_cosines(double a, double b, size_t count, double *out)
{
    double h = (b - a) / (double)(count - 1), ch = cos(h), sh = sin(h);
    double c = cos(a), s = sin(a);
    size_t k;
    for (k = 0; k < count; ++k) {
        double next_c = c * ch - s * sh;
        out[k] = c;
        s = s * ch + c * sh;
        c = next_c;
    }
}

/* Scratch of the Filon path: samples, their cosines, Filon's own. */
enum { FILON_SCR_F = 0, FILON_SCR_COS = FILON_SAMPLES, FILON_SCR_FILON = 2 * FILON_SAMPLES };

/* Add the Filon moments of f = exp(A + B cos phi) g over [a, b] to out
 * (with F = 1 in g for the reference). */
static void add_piece(const ll_microfacet_model *mf, const pair_plan *p, int reference, double a,
                      double b, size_t samples, size_t n_out, double *out, double *scratch)
{
    double *f = scratch + FILON_SCR_F, *cos_phi = scratch + FILON_SCR_COS;
    double *filon = scratch + FILON_SCR_FILON;
    size_t k;
    if (!(b > a))
        return;
    azimuth_cosines(a, b, samples, cos_phi);
    sample_profile(mf, p, cos_phi, samples, reference ? NULL : f, reference ? f : NULL);
    for (k = 0; k < samples; ++k)
        f[k] *= exp(p->a_plus_b + p->b * (cos_phi[k] - 1.0));
    ll_filon_moments(f, samples, a, b, n_out, out, filon);
}

/* add_piece for GGX, with its peak factor; *seen is the largest f of the
 * pair's pieces so far. A piece whose samples all stay below
 * GGX_NEGLIGIBLE of it adds no moments: its share of f at any azimuth, of
 * the series' partial sums too, is below that fraction of the peak (the
 * tails of a sharp lobe and the kinks far out in them cost most of the
 * samples otherwise). */
static void ggx_piece(const ll_microfacet_model *mf, const pair_plan *p, int reference, double a,
                      double b, size_t samples, size_t n_out, double *out, double *scratch,
                      double *seen)
{
    double *f = scratch + FILON_SCR_F, *cos_phi = scratch + FILON_SCR_COS;
    double *filon = scratch + FILON_SCR_FILON, peak = exp(p->a_plus_b), largest = 0.0;
    size_t k;
    if (!(b > a))
        return;
    azimuth_cosines(a, b, samples, cos_phi);
    sample_profile(mf, p, cos_phi, samples, reference ? NULL : f, reference ? f : NULL);
    for (k = 0; k < samples; ++k) {
        double c = 1.0 + p->b * (1.0 - cos_phi[k]);
        f[k] *= peak / (c * c);
        largest = fmax(largest, fabs(f[k]));
    }
    *seen = fmax(*seen, largest);
    if (largest < GGX_NEGLIGIBLE * *seen || !(largest > 0.0))
        return;
    ll_filon_moments(f, samples, a, b, n_out, out, filon);
}

/* [a, b] on uniform panels, except that next to an end at (or near) a
 * branch point the first panel pair is replaced by pieces shrinking by 4
 * towards it: Fresnel's square root there would cost O(h^1/2) on uniform
 * panels; graded, only the last tiny piece errs. */
static void add_graded(const ll_microfacet_model *mf, const pair_plan *p, int reference, double a,
                       double b, size_t samples, int grade_a, int grade_b, size_t n_out,
                       double *out, double *scratch)
{
    double edge = 2.0 * (b - a) / (double)(samples - 1), lo_frac = 0.25, hi_frac = 1.0;
    double main_a = grade_a ? a + edge : a, main_b = grade_b ? b - edge : b;
    int level;
    add_piece(mf, p, reference, main_a, main_b, samples, n_out, out, scratch);
    for (level = 0; level < FILON_LEVELS; ++level) {
        double lo = level == FILON_LEVELS - 1 ? 0.0 : lo_frac;
        if (grade_a)
            add_piece(mf, p, reference, a + lo * edge, a + hi_frac * edge,
                      FILON_LEVEL_SAMPLES, n_out, out, scratch);
        if (grade_b)
            add_piece(mf, p, reference, b - hi_frac * edge, b - lo * edge,
                      FILON_LEVEL_SAMPLES, n_out, out, scratch);
        hi_frac = lo_frac;
        lo_frac *= 0.25;
    }
}

/* [a, b] for GGX, graded towards a singular end over its whole length:
 * pieces at distances [d / 4, d] from it, d = b - a, b - a / 4, ..., each
 * with the same samples, so that every piece resolves the square root of
 * Fresnel at the kink to the same relative accuracy (on uniform panels,
 * as add_graded's, the panels next to the graded ones err by O(h^1/2)
 * there, and a kink under a wide GGX lobe is summed over ~100 orders). */
static void add_towards(const ll_microfacet_model *mf, const pair_plan *p, int reference, double a,
                        double b, int at_a, int at_b, size_t n_out, double *out,
                        double *scratch, double *seen)
{
    double d = b - a;
    int level;
    if (!(b > a))
        return;
    if (at_a && at_b) {
        double mid = 0.5 * (a + b);
        add_towards(mf, p, reference, a, mid, 1, 0, n_out, out, scratch, seen);
        add_towards(mf, p, reference, mid, b, 0, 1, n_out, out, scratch, seen);
        return;
    }
    if (!at_a && !at_b) {
        ggx_piece(mf, p, reference, a, b, GGX_FILON_SAMPLES, n_out, out, scratch, seen);
        return;
    }
    for (level = 0; level < GGX_KINK_LEVELS; ++level) {
        double near = level == GGX_KINK_LEVELS - 1 ? 0.0 : 0.25 * d;
        if (at_a)
            ggx_piece(mf, p, reference, a + near, a + d, GGX_KINK_SAMPLES, n_out, out, scratch,
                      seen);
        else
            ggx_piece(mf, p, reference, b - d, b - near, GGX_KINK_SAMPLES, n_out, out, scratch,
                      seen);
        d = near;
    }
}

/* GGX's f over [0, pi] (or [0, split] for refraction): pieces doubling in
 * width from the peak's half width beta^-1/2 on (the tails fall like
 * phi^-4, so each piece spans the same relative change of f), cut at the
 * kink and graded towards it and towards near branch points. */
static void ggx_filon(const ll_microfacet_model *mf, const pair_plan *p, int reference,
                      size_t n_out, double *out, double *scratch)
{
    double end = (!p->reflect && p->split > 0.0) ? p->split : LL_PI;
    double a = 0.0, first = p->b > 0.0 ? fmin(LL_PI, 1.0 / sqrt(p->b)) : LL_PI, seen = 0.0;
    while (a < end) {
        double b = a == 0.0 ? first : 2.0 * a;
        int grade_a = a == 0.0 ? p->grade_start : a == p->split, grade_b;
        if (b > end - ANGLE_EPS)
            b = end;
        if (p->split > a && p->split < b)
            b = p->split;
        /* Reflection's kink is total internal reflection, which holds
         * below the split (t < 1 - 2 eta^2, and t grows with phi): F = 1
         * there, and Fresnel's square root is on the far side alone. */
        grade_b = (b == p->split && !p->reflect) || (b == LL_PI && p->grade_end);
        add_towards(mf, p, reference, a, b, grade_a, grade_b, n_out, out, scratch, &seen);
        a = b;
    }
}

/* The cosine series c_l = (2 - [l = 0]) / pi integral_0^pi f cos(l phi)
 * dphi, l < n_out, over the window (f is below 1e-12 of its peak beyond),
 * split at a kink. */
static void filon_series(const ll_microfacet_model *mf, const pair_plan *p, int reference,
                         size_t n_out, double *out, double *scratch)
{
    size_t l;
    memset(out, 0, n_out * sizeof(double));
    if (mf->ggx) {
        ggx_filon(mf, p, reference, n_out, out, scratch);
    } else if (p->split > 0.0) {
        add_graded(mf, p, reference, 0.0, p->split, FILON_SAMPLES, p->grade_start, 1, n_out,
                   out, scratch);
        if (p->reflect) /* refracted light ends at the split */
            add_graded(mf, p, reference, p->split, p->phi_end, FILON_SAMPLES, 1, p->grade_end,
                       n_out, out, scratch);
    } else {
        add_graded(mf, p, reference, 0.0, p->phi_end, FILON_SAMPLES, p->grade_start,
                   p->grade_end, n_out, out, scratch);
    }
    out[0] *= LL_INV_PI;
    for (l = 1; l < n_out; ++l)
        out[l] *= 2.0 * LL_INV_PI;
}

/* ------------------------------------------------------------ series */

size_t ll_microfacet_scratch_size(size_t max_len)
{
    /* Chebyshev path: 2 CHEB; Filon path: 2 FILON_SAMPLES + 7 max_len. */
    return 2 * FILON_SAMPLES + 7 * max_len + 2 * CHEB;
}

/* GGX's smooth pairs: g at the Chebyshev points of cos phi, the closed
 * form of the peak's series (words/microfacet_ggx.h). */
static ll_status ggx_pair_series(const ll_microfacet_model *mf, const pair_plan *p, size_t max_len,
                                 double *out, size_t *n_out, double *ref0, double *scratch)
{
    double *g = scratch, *g_ref = scratch + LL_GGX_CHEB, *rest = scratch + 2 * LL_GGX_CHEB;
    double peak = exp(p->a_plus_b);
    size_t i, len = ll_ggx_peak_length(p->b, GGX_TAIL_GOAL, max_len) + LL_GGX_CHEB;
    sample_profile(mf, p, mf->ggx_basis.cos_phi, LL_GGX_CHEB, g, ref0 ? g_ref : NULL);
    for (i = 0; i < LL_GGX_CHEB; ++i) {
        g[i] *= peak;
        g_ref[i] = ref0 ? g_ref[i] * peak : 0.0;
    }
    *n_out = len < max_len ? len : max_len;
    ll_ggx_series(&mf->ggx_basis, p->b, g, *n_out, out, rest);
    if (ref0)
        ll_ggx_series(&mf->ggx_basis, p->b, g_ref, 1, ref0, rest);
    return LL_OK;
}

/* The series of a planned pair, n_out <= max_len terms (*n_out), and the
 * order 0 of its reference (F = 1) if ref0 is not NULL. */
static ll_status pair_series(const ll_microfacet_model *mf, const pair_plan *p, size_t max_len,
                             double *out, size_t *n_out, double *ref0, double *scratch)
{
    const grid_entry *e;
    double *g = scratch, *g_ref = ref0 ? scratch + CHEB : NULL, rest, peak;
    size_t i, l, len;
    if (mf->ggx && !p->filon)
        return ggx_pair_series(mf, p, max_len, out, n_out, ref0, scratch);
    if (p->filon) {
        len = (mf->ggx ? ll_ggx_peak_length(p->b, GGX_TAIL_GOAL, max_len)
                       : ll_expcos_length(p->b, TAIL_GOAL)) +
              FILON_EXTRA;
        *n_out = len < max_len ? len : max_len;
        if (ref0) /* order 0 of the reference, by the same rule */
            filon_series(mf, p, 1, 1, ref0, scratch);
        filon_series(mf, p, 0, *n_out, out, scratch);
        return LL_OK;
    }
    e = p->grid < mf->n_grid ? mf->grid[p->grid] : NULL;
    if (!e)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "microfacet series: the pair (%g, %g) was not prepared", p->mu_o,
                       p->mu_i);
    /* g times the part of exp(-B v) that the grid point leaves out. */
    sample_profile(mf, p, e->cos_phi, CHEB, g, g_ref);
    rest = (p->b - e->b) * e->delta;
    peak = exp(p->a_plus_b);
    for (i = 0; i < CHEB; ++i) {
        double factor = peak * exp(-rest * e->u[i]);
        g[i] *= factor;
        if (g_ref)
            g_ref[i] *= factor;
    }
    *n_out = e->len < max_len ? e->len : max_len;
    memset(out, 0, *n_out * sizeof(double));
    for (i = 0; i < CHEB; ++i) {
        const double *column = e->matrix + i * e->len;
        for (l = 0; l < *n_out; ++l)
            out[l] += g[i] * column[l];
    }
    if (g_ref) {
        double sum = 0.0;
        for (i = 0; i < CHEB; ++i)
            sum += g_ref[i] * e->matrix[i * e->len];
        *ref0 = sum;
    }
    return LL_OK;
}

ll_status ll_microfacet_series(const ll_microfacet_model *mf, double mu_o, double mu_i,
                               size_t max_len, double *out, size_t *len, double *ref0,
                               double *scratch)
{
    pair_plan p;
    size_t n_out, l, last;
    double energy = 0.0, ref_energy = 0.0;
    ll_status s;

    *len = 0;
    if (ref0)
        *ref0 = 0.0;
    if (max_len > mf->max_len)
        max_len = mf->max_len;
    if (max_len == 0 || !plan_pair(mf, mu_o, mu_i, HUGE_VAL, &p))
        return LL_OK;
    if (p.b > mf->b_max) {
        /* A lobe too sharp for the orders is widened. The original keeps the
         * integral of the peak, but g is not constant across the wider
         * lobe, and at grazing angles the energy so grows by up to 10%
         * (R + T = 1.06 for eta = 1.5, alpha = 0.3 at 61 orders). So the
         * order 0 of the true lobe is computed first, and the widened
         * series scaled to it. */
        s = pair_series(mf, &p, 1, &energy, &n_out, ref0 ? &ref_energy : NULL, scratch);
        if (s != LL_OK)
            return s;
        if (!plan_pair(mf, mu_o, mu_i, mf->b_max, &p))
            return LL_OK;
    }
    s = pair_series(mf, &p, max_len, out, &n_out, ref0, scratch);
    if (s != LL_OK)
        return s;
    if (p.widened) {
        double scale = out[0] > 0.0 ? energy / out[0] : 0.0;
        for (l = 0; l < n_out; ++l)
            out[l] *= scale;
        if (ref0)
            *ref0 = ref_energy;
    }

    /* Truncate after the last term that matters. */
    if (!(out[0] > 0.0))
        return LL_OK; /* a vanishing mean: nothing */
    last = 0;
    for (l = 1; l < n_out; ++l)
        if (fabs(out[l]) >= LL_MICROFACET_RELERR * out[0])
            last = l;
    *len = last + 1;
    return LL_OK;
}

/* -------------------------------------------------------- life cycle */

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
    e->b = grid_b(k);
    e->delta = window_delta(e->b);
    phi_end = window_angle(e->delta);
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
    double x[GAUSS_NODES];  /* Gauss-Legendre rule on [-1, 1]   */
    double w[GAUSS_NODES];
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
    *n_grid = grid_index(DBL_MAX) + 1;
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
    if (mf->ggx || !plan_pair(mf, mu_o, mu_i, HUGE_VAL, &p))
        return; /* GGX needs no maps */
    if (!p.filon)
        need[p.grid] = 1;
    if (p.b > mf->b_max && plan_pair(mf, mu_o, mu_i, mf->b_max, &p) && !p.filon)
        need[p.grid] = 1;
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
    s = n_items ? ll_quad_gauss_legendre(GAUSS_NODES, job.x, job.w, NULL) : LL_OK;
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

/* ------------------------------------------------------------- layer */

typedef struct layer_job {
    const ll_layer *layer;
    const ll_microfacet_model *mf;
    size_t column_doubles;       /* scratch of one column               */
    double **column_memory;      /* [slots]: each thread's, reused      */
    size_t slots;
    ll_order_builder **builders; /* [m]; order 0 goes through order0 */
    double *order0;              /* n x n column-major, unweighted     */
    double *ref0;                /* n x n or NULL (conductor compensation) */
    ll_watch *watch;             /* one unit per column, polled per row */
    const double *w;             /* [h] outgoing weights 2 pi w_j mu_j  */
    double *work;                /* [8 h] compensation scratch          */
    double eta_re, eta_im;
    int conserve_energy;
} layer_job;

/* Doubles of scratch for one column: every row's series (m each; only the
 * pages that the series reach are touched), the series' scratch and one
 * column of the matrix; 0 if that overflows. */
static size_t column_doubles(size_t n, size_t m)
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
static ll_status fill_column(size_t col, const layer_job *job);

static ll_status layer_column(size_t col, void *ctx)
{
    const layer_job *job = ctx;
    ll_status s;
    if (ll_watch_poll(job->watch))
        return ll_fail(LL_ERROR_CANCELLED, "ll_layer_set_microfacet: cancelled");
    s = fill_column(col, job);
    ll_watch_advance(job->watch, 1);
    return s;
}

static ll_status fill_column(size_t col, const layer_job *job)
{
    const ll_layer *l = job->layer;
    size_t n = l->n, m = l->m, h = n / 2, row, k, j, count;
    double *pool, *scratch, *column, factor;
    row_length *rows = ll_alloc_array(n, sizeof *rows);
    size_t slot = ll_parallel_slot();
    double *memory = NULL;
    ll_status s = LL_OK;
    /* The thread's column scratch (n x m, 37 MB at n = 1098, m = 4194),
     * made by its first column and reused: one per column cost a page
     * fault per 4 KiB touched, again for every column. Every value read
     * is written first in the same column. */
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
    for (row = 0; row < n && s == LL_OK; ++row) {
        /* The reference (F = 1) is only needed for R^t: up from above. */
        double *ref = job->ref0 && row < h && col >= h ? &job->ref0[col * n + row] : NULL;
        if (ll_watch_poll(job->watch)) {
            s = ll_fail(LL_ERROR_CANCELLED, "ll_layer_set_microfacet: cancelled");
            break;
        }
        /* Depth grows opposite to the normal: the series takes -mu. */
        rows[row].row = row;
        s = ll_microfacet_series(job->mf, -l->nodes[row], -l->nodes[col], m, pool + row * m,
                                 &rows[row].len, ref, scratch);
        job->order0[col * n + row] = rows[row].len ? pool[row * m] : 0.0;
    }
    if (s == LL_OK) {
        qsort(rows, n, sizeof *rows, longer_first);
        memset(column, 0, n * sizeof(double));
        factor = ll_layer_surface_factor(l, col, 1);
        count = n;
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

/* Energy compensation (words/microfacet_compensation.c) of the unweighted
 * order 0. Blocks of m0 (column-major): R^t rows < h, columns >= h; R^b
 * rows >= h, columns < h; T^tb rows, columns >= h; T^bt both < h. work
 * holds 8 h doubles. */
static void compensate(const layer_job *job, size_t n, double *work)
{
    size_t h = n / 2, q;
    double *albedo[4];
    ll_microfacet_compensation c;
    for (q = 0; q < 4; ++q)
        albedo[q] = work + (4 + q) * h;
    if (job->eta_im == 0.0) {
        for (q = 0; q < 4; ++q) /* (block q: rows >= h when q > 1, columns when q odd) */
            block_albedo(job->order0, n, job->w, (q >> 1) * h, (q & 1) * h, albedo[q]);
        ll_microfacet_compensate_dielectric(h, job->w, job->eta_re,
                                            (const double *const *)albedo, work, &c);
    } else {
        block_albedo(job->ref0, n, job->w, 0, h, albedo[LL_BLOCK_RT]);
        ll_microfacet_compensate_conductor(h, job->w, job->eta_re, job->eta_im,
                                           albedo[LL_BLOCK_RT], work, &c);
    }
    for (q = 0; q < 4; ++q)
        if (c.scale[q] != 0.0)
            block_add_outer(job->order0, n, (q >> 1) * h, (q & 1) * h, c.u[q], c.v[q],
                            c.scale[q]);
}

static ll_status check_arguments(const ll_layer *layer, double eta_re, double eta_im,
                                 double alpha)
{
    static const char fn[] = "ll_layer_set_microfacet";
    if (!layer)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: layer is NULL", fn);
    if (!(alpha >= LL_MICROFACET_MIN_ALPHA) || !ll_is_finite(alpha))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: alpha = %g; the smallest roughness supported is "
                       "LL_MICROFACET_MIN_ALPHA = %g (smoother interfaces need more Fourier "
                       "orders than a layer can hold)",
                       fn, alpha, LL_MICROFACET_MIN_ALPHA);
    if (!ll_is_finite(eta_re) || !ll_is_finite(eta_im) || !(eta_im >= 0.0) ||
        !(eta_im > 0.0 ? eta_re >= 0.0 : eta_re > 0.0))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: eta = %g + %g i is not a valid index (need eta_im >= 0, and "
                       "eta_re > 0 for a dielectric, >= 0 for a conductor)",
                       fn, eta_re, eta_im);
    return LL_OK;
}

/* After the columns: energy compensation on the unweighted order 0, then
 * the weights, and order 0 into its builder. */
static ll_status finish_order0(void *ctx)
{
    const layer_job *job = ctx;
    const ll_layer *layer = job->layer;
    size_t n = layer->n, col;
    ll_status s = LL_OK;
    if (ll_watch_stage(job->watch, "interface", 0.95, 0.05, n))
        return ll_watch_check(job->watch, "ll_layer_set_microfacet");
    if (job->conserve_energy)
        compensate(job, n, job->work);
    for (col = 0; col < n && s == LL_OK; ++col) {
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

ll_status ll_microfacet_read(const ll_microfacet *in, ll_microfacet *out, const char *fn)
{
    ll_microfacet defaults = LL_MICROFACET_INIT;
    ll_status s;
    *out = defaults;
    if (!in)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: microfacet is NULL", fn);
    s = ll_struct_read(out, sizeof *out, in, fn, "ll_microfacet");
    if (s != LL_OK)
        return s;
    if (out->distribution != LL_MICROFACET_BECKMANN && out->distribution != LL_MICROFACET_GGX)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: distribution = %d is not an ll_microfacet_distribution", fn,
                       out->distribution);
    return LL_OK;
}

ll_status ll_layer_set_microfacet(ll_layer *layer, const ll_microfacet *microfacet,
                                  const ll_monitor *monitor)
{
    static const char fn[] = "ll_layer_set_microfacet";
    size_t n, m, h, k, n_orders_internal;
    ll_microfacet_model *mf = NULL;
    double *mu = NULL, *order0 = NULL, *ref0 = NULL, *w = NULL, *work = NULL;
    double eta_re, eta_im, alpha;
    int conserve_energy, distribution;
    layer_job job;
    ll_watch watch;
    ll_microfacet in;
    ll_status s = layer ? ll_microfacet_read(microfacet, &in, fn)
                        : ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: layer is NULL", fn);
    if (s != LL_OK)
        return s;
    eta_re = in.eta_re;
    eta_im = in.eta_im;
    alpha = in.alpha;
    conserve_energy = in.compensate;
    n_orders_internal = in.n_orders_internal;
    distribution = in.distribution;
    s = check_arguments(layer, eta_re, eta_im, alpha);
    if (s == LL_OK)
        s = ll_watch_begin(&watch, monitor, fn);
    if (s != LL_OK)
        return s;
    if (eta_im == 0.0 && eta_re == 1.0) {
        /* index-matched: no interface */
        ll_watch_stage(&watch, "interface", 0.0, 1.0, 0);
        s = ll_watch_finish(&watch, LL_OK, fn);
        return s == LL_OK ? ll_layer_clear(layer) : s;
    }
    n = layer->n;
    m = layer->m;
    h = n / 2;
    if (n_orders_internal < m)
        n_orders_internal = m;
    job.column_memory = NULL;
    job.slots = 0;

    s = ll_microfacet_create_distribution(eta_re, eta_im, alpha, distribution,
                                          n_orders_internal, m, &mf);
    if (s != LL_OK)
        return s;
    mu = ll_alloc_array(n, sizeof(double));
    w = ll_alloc_array(h, sizeof(double));
    work = ll_alloc_array(h, 8 * sizeof(double));
    order0 = ll_calloc_array(n, n * sizeof(double));
    if (eta_im > 0.0 && conserve_energy)
        ref0 = ll_calloc_array(n, n * sizeof(double));
    if (!mu || !w || !work || !order0 || (eta_im > 0.0 && conserve_energy && !ref0))
        goto oom;
    for (k = 0; k < n; ++k)
        mu[k] = -layer->nodes[k];
    s = ll_microfacet_prepare_watched(mf, mu, n, &watch);
    if (s != LL_OK)
        goto done;
    for (k = 0; k < h; ++k)
        w[k] = 2.0 * LL_PI * layer->weights[h + k] * layer->nodes[h + k];

    job.layer = layer;
    job.mf = mf;
    job.column_doubles = column_doubles(n, m);
    job.slots = ll_get_thread_count();
    job.column_memory = ll_calloc_array(job.slots, sizeof(double *));
    if (!job.column_doubles || !job.column_memory)
        goto oom;
    job.builders = NULL;
    job.order0 = order0;
    job.ref0 = ref0;
    job.watch = &watch;
    job.w = w;
    job.work = work;
    job.eta_re = eta_re;
    job.eta_im = eta_im;
    job.conserve_energy = conserve_energy;
    s = ll_watch_stage(&watch, "interface", 0.1, 0.85, n) ? ll_watch_check(&watch, fn) : LL_OK;
    if (s == LL_OK) {
        /* finish_order0 reads order 0 (and the mirror's) whole. */
        double *dense[2];
        dense[0] = order0;
        dense[1] = ref0;
        s = ll_layer_build_by_columns(layer, n, 0, layer_column, finish_order0, &job,
                                      &job.builders, dense, ref0 ? 2 : 1, &watch, fn);
    }
    goto done;
oom:
    s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_layer_set_microfacet: out of memory for %zu nodes",
                n);
done:
    for (k = 0; job.column_memory && k < job.slots; ++k)
        ll_free(job.column_memory[k]);
    ll_free(job.column_memory);
    ll_microfacet_destroy(mf);
    ll_free(mu);
    ll_free(w);
    ll_free(work);
    ll_free(order0);
    ll_free(ref0);
    return s;
}
