/*
 * The energy compensation of a rough interface (ll_layer_set_microfacet's
 * conserve_energy; Jakob et al. 2014, sec. 6.2, the original's
 * "pseudo-diffuse" term): from the order-0 albedos of the single-scattering
 * layer, the rank-one order-0 terms that give back what shadowing loses.
 *
 * One code path for the layer and the resolution probes (search/probe.h):
 * the probes compute the same albedos at the probed resolution and add the
 * same terms at the spline stencil of each probe, so the search measures
 * the layer the build makes (copper, alpha 0.8 at 214 x 45 was 1.32% off
 * twice that resolution with the term and 0.33% without it, while probes
 * that left it out accepted the resolution).
 */
#include "words/microfacet.h"
#include "words/microfacet_pair.h"
#include "words/fresnel.h"

#include "layerlab/ll_layer.h"
#include "layerlab/ll_quad.h"

#include <math.h>
#include <string.h>

static void clear(ll_microfacet_compensation *out)
{
    memset(out, 0, sizeof *out);
}

/* Quadrature of the visible normals: slope radii s (in units of alpha) by
 * s = q / (1 - q) on Gauss-Legendre q, azimuths of the slope on [0, pi]
 * (the integrand is even in them). */
#define VISIBLE_RADII 32
#define VISIBLE_AZIMUTHS 24

/* The quadrature of visible_fresnel with what does not depend on mu
 * computed once per surface, not per node (each node's average took 32
 * exponentials and 768 cosines of the same arguments): per slope radius
 * alpha s, the radial weight and 1 / sqrt(1 + alpha^2 s^2), per azimuth
 * its cosine and weight. */
typedef struct visible_rule {
    double alpha_s[VISIBLE_RADII], radial[VISIBLE_RADII], norm[VISIBLE_RADII];
    double cos_phi[VISIBLE_AZIMUTHS], weight[VISIBLE_AZIMUTHS];
} visible_rule;

/* The Fresnel reflectance averaged over the normals that the direction of
 * cosine mu sees (weights max(0, wi.m) D(m)): what the first bounce of
 * light arriving along mu reflects before any shadowing. In slopes (the
 * normal m = (-x, -y, 1) / |.|, x = alpha s cos phi, wi in the xz plane)
 * the weight is (mu - x sin theta)_+ P(s) s ds dphi with P Beckmann's
 * exp(-s^2) or GGX's (1 + s^2)^-2, and the facet's cosine is
 * (mu - x sin theta) / sqrt(1 + alpha^2 s^2). The normalisation is the
 * same sum without F: F = 1 gives 1 exactly. The radii s = q / (1 - q)
 * on Gauss-Legendre q, the azimuths of the slope on [0, pi] (the
 * integrand is even in them); rule holds 2 (VISIBLE_RADII +
 * VISIBLE_AZIMUTHS) doubles of Gauss-Legendre nodes and weights on
 * [-1, 1]. */
static void visible_prepare(const ll_microfacet_model *mf, const double *rule, visible_rule *v)
{
    const double *xq = rule, *wq = rule + VISIBLE_RADII;
    const double *xp = rule + 2 * VISIBLE_RADII, *wp = xp + VISIBLE_AZIMUTHS;
    size_t a, b;
    for (a = 0; a < VISIBLE_RADII; ++a) {
        double q = 0.5 * (xq[a] + 1.0), s = q / (1.0 - q), ds = 0.5 * wq[a] / ((1.0 - q) * (1.0 - q));
        double p = mf->ggx ? 1.0 / ((1.0 + s * s) * (1.0 + s * s)) : exp(-s * s);
        v->alpha_s[a] = mf->alpha * s;
        v->radial[a] = p * s * ds;
        v->norm[a] = 1.0 / sqrt(1.0 + mf->alpha * mf->alpha * s * s);
    }
    for (b = 0; b < VISIBLE_AZIMUTHS; ++b) {
        v->cos_phi[b] = cos(0.5 * LL_PI * (xp[b] + 1.0));
        v->weight[b] = wp[b];
    }
}

static double visible_fresnel(const ll_microfacet_model *mf, const visible_rule *v, double mu)
{
    double sin_t = sqrt(fmax(0.0, 1.0 - mu * mu)), num = 0.0, den = 0.0;
    size_t a, b;
    for (a = 0; a < VISIBLE_RADII; ++a) {
        double radial = v->radial[a], norm = v->norm[a], alpha_s = v->alpha_s[a];
        if (!(radial > 0.0))
            continue;
        for (b = 0; b < VISIBLE_AZIMUTHS; ++b) {
            double vis = mu - alpha_s * v->cos_phi[b] * sin_t, weight, c;
            if (vis <= 0.0)
                continue;
            weight = radial * v->weight[b] * vis;
            den += weight;
            c = vis * norm; /* (> 0: min(1, c) without fmin's library call) */
            num += weight * ll_fresnel_conductor_kernel(c < 1.0 ? c : 1.0, mf->eta_re,
                                                        mf->eta_im);
        }
    }
    return den > 0.0 ? num / den : 1.0;
}

/* How light that a first bounce sent back into the surface goes on, for a
 * white (F = 1) surface lit with a cosine-weighted hemisphere: of what
 * reaches a second facet, the fraction that reaches a third (c2), and of
 * that, a fourth (c3), at alpha = 0.1, 0.2, .., 1. Measured with the random
 * walk on the Smith microsurface (tests/reference/ms_walk.c, 10^6 paths
 * each; below alpha 0.3 the multiple scattering they scale is below 1% of
 * the albedo). Lost light escapes far sooner than the mirror's average
 * albedo says: at Beckmann alpha 1, 1 - E_avg = 0.34 but c2 = 0.12. */
static const double chain_beckmann[2][10] = {
    { 0.0484, 0.0478, 0.0507, 0.0545, 0.0591, 0.0652, 0.0743, 0.0861, 0.1008, 0.1189 },
    { 0.0351, 0.0199, 0.0329, 0.0354, 0.0391, 0.0391, 0.0434, 0.0495, 0.0545, 0.0640 },
};
static const double chain_ggx[2][10] = {
    { 0.0692, 0.1004, 0.1376, 0.1790, 0.2236, 0.2700, 0.3169, 0.3656, 0.4109, 0.4540 },
    { 0.0630, 0.0740, 0.1004, 0.1321, 0.1697, 0.2096, 0.2492, 0.2884, 0.3278, 0.3683 },
};

/* c2 (which = 0) or c3 (1) at the model's roughness: linear in alpha,
 * held at the ends of the measured range. */
static double chain(const ll_microfacet_model *mf, int which)
{
    const double *t = mf->ggx ? chain_ggx[which] : chain_beckmann[which];
    double x = mf->alpha * 10.0 - 1.0, f;
    size_t k;
    if (x <= 0.0)
        return t[0];
    if (x >= 9.0)
        return t[9];
    k = (size_t)x; /* 0 .. 8 */
    f = x - (double)k;
    return t[k] + f * (t[k + 1] - t[k]);
}

/* The reshaping of the returned light by its colour (below). */
#define COLOUR_EXPONENT_BECKMANN 0.25
#define COLOUR_TILT_GGX 0.6

/* How the returned light spreads over the azimuth
 * (ll_microfacet_compensation_series): fitted to the walk's multiple part
 * (tests/data/ms_walk.txt, F rows: Beckmann alpha 0.3 .. 1, GGX 0.5 and
 * 1, incidence 0 .. 60 degrees, exitance 0 .. 75, azimuths 0 .. 180). A
 * Beckmann metal's is a peak toward the mirror side whose concentration
 * grows as the roughness falls (alpha 0.5, 60 / 60 degrees: about 8.5;
 * 1.3 sin_i sin_j / alpha^3 / (mu_i + mu_j)^0.75 here) over a floor of a
 * tenth; GGX's long tails leave most of it flat, a fifth in a peak
 * of concentration 0.5 sin_i sin_j / alpha^3. Below the fitted range
 * (alpha 0.3; there the multiple scattering is below 1% of the albedo)
 * the concentration stays that of alpha 0.3, as alpha^-3 would make the
 * small term a peak far narrower than the lobe, and the peak fades to a
 * flat term at alpha 0.2, where the walk gives no shape to fit. */
#define SPREAD_ALPHA_MIN 0.3
#define SPREAD_ALPHA_FLAT 0.2
static void spread(const ll_microfacet_model *mf, const double *mu,
                   ll_microfacet_compensation *out)
{
    double alpha = fmax(mf->alpha, SPREAD_ALPHA_MIN), a3 = alpha * alpha * alpha;
    double fade = fmin(1.0, fmax(0.0, (mf->alpha - SPREAD_ALPHA_FLAT) /
                                          (SPREAD_ALPHA_MIN - SPREAD_ALPHA_FLAT)));
    out->mu = mu;
    if (mf->ggx) {
        out->spread = 0.5 / a3;
        out->power = 0.0;
        out->peaked = 0.2 * fade;
    } else {
        out->spread = 1.3 / a3;
        out->power = 0.75;
        out->peaked = 0.9 * fade;
    }
}

/* The light that single scattering loses along mu has been reflected once
 * already, at a facet that mu sees: of the mirror's loss 1 - E(mu) (F = 1,
 * the same roughness), the metal's is A(mu) - E_F(mu), with A the Fresnel
 * reflectance averaged over the visible normals and E_F the layer's own
 * single-scattering albedo (Kulla and Conty 2017 put F_avg here, the same
 * for every mu: at grazing incidence the first facets are hit at grazing
 * angles too, where a metal reflects more). That light bounces on among
 * the facets, each bounce reflecting F_2, the first bounce's reflectance
 * averaged over the lost light of a cosine-weighted hemisphere, (W.(A -
 * E_F)) / (W.(1 - E)). Of what reaches the second facet the fraction c2
 * reaches a third, and of that c3 each further one (the walk's, above: the
 * chain of the lost light escapes far sooner than the geometric series in
 * the mirror's average albedo E_avg of Kulla and Conty assumes). So
 * direction mu gets back k (A(mu) - E_F(mu)) with
 *   k = F_2 ((1 - c2) + c2 F_2 (1 - c3) / (1 - F_2 c3)),
 * as the symmetric (reciprocal) s u u^T with u = A - E_F reshaped by
 * direction (below) and s such that the hemisphere gets back k (W.(A -
 * E_F)). F = 1 gives u = 1 - E, F_2 = 1 and k = 1: every loss returns.
 * Same on both sides.
 *
 * The reshaping: against the walk's total, a constant k per surface left
 * the weakly reflecting channels (gold's blue, copper's green and blue) of
 * the roughest surfaces too bright near normal incidence and too dark at
 * grazing incidence (GGX alpha 1, gold's blue: +7.1% at 0 degrees, -13.9%
 * at 75; Beckmann alpha 1: +1.9%, -2.8%): light lost at grazing incidence
 * meets the facets at grazing angles again on its later bounces, where a
 * metal reflects more. With rho = (A - E_F) / (1 - E) the first bounce's
 * colour along mu, u = (A - E_F) rho^e (1 - t (1 - rho) mu), both
 * growing from 0 at alpha 0.5 (where a constant k holds) to their values
 * at alpha 1: for Beckmann the exponent e, to COLOUR_EXPONENT_BECKMANN
 * (its rho grows toward grazing incidence), for GGX, whose rho is nearly
 * flat in mu, the tilt t, to COLOUR_TILT_GGX. Both fitted to the walk's
 * albedos (tests/data/ms_walk.txt, A rows); rho = 1 leaves u as it was. */
void ll_microfacet_compensate_conductor(const ll_microfacet_model *mf, size_t h, const double *mu,
                                        const double *w, const double *mirror_albedo,
                                        const double *albedo, double *work,
                                        ll_microfacet_compensation *out)
{
    double *lost = work, *first = work + h, rule[2 * (VISIBLE_RADII + VISIBLE_AZIMUTHS)];
    visible_rule visible;
    double f2, factor, wl, wf, wu, ramp, exponent, tilt, c2 = chain(mf, 0), c3 = chain(mf, 1);
    size_t j;
    clear(out);
    /* (The rules cannot fail for these counts.) */
    (void)ll_quad_gauss_legendre(VISIBLE_RADII, rule, rule + VISIBLE_RADII, NULL);
    (void)ll_quad_gauss_legendre(VISIBLE_AZIMUTHS, rule + 2 * VISIBLE_RADII,
                                 rule + 2 * VISIBLE_RADII + VISIBLE_AZIMUTHS, NULL);
    visible_prepare(mf, rule, &visible);
    for (j = 0; j < h; ++j) {
        lost[j] = fmax(0.0, 1.0 - mirror_albedo[j]);
        first[j] = fmin(lost[j], fmax(0.0, visible_fresnel(mf, &visible, mu[j]) - albedo[j]));
    }
    wl = ll_microfacet_dot(w, lost, h);
    wf = ll_microfacet_dot(w, first, h);
    if (!(wl > 0.0) || !(wf > 0.0))
        return;
    f2 = fmin(1.0, wf / wl);
    factor = f2 * ((1.0 - c2) + c2 * f2 * (1.0 - c3) / (1.0 - f2 * c3));
    /* The returned light by direction: first reshaped by its colour rho =
     * first / lost (the first bounce's Fresnel average; 1 for F = 1, so a
     * white conductor's term is unchanged), then scaled so that the
     * hemisphere gets back factor (W.first) as before. */
    ramp = fmax(0.0, mf->alpha - 0.5) / 0.5;
    exponent = 1.0 + (mf->ggx ? 0.0 : COLOUR_EXPONENT_BECKMANN * ramp);
    tilt = mf->ggx ? COLOUR_TILT_GGX * ramp : 0.0;
    for (j = 0; j < h; ++j) {
        double rho = lost[j] > 0.0 ? first[j] / lost[j] : 1.0;
        first[j] *= pow(rho, exponent - 1.0) * (1.0 - tilt * (1.0 - rho) * mu[j]);
    }
    wu = ll_microfacet_dot(w, first, h);
    if (!(wu > 0.0))
        return;
    out->u[LL_BLOCK_RT] = out->v[LL_BLOCK_RT] = first;
    out->u[LL_BLOCK_RB] = out->v[LL_BLOCK_RB] = first;
    out->scale[LL_BLOCK_RT] = out->scale[LL_BLOCK_RB] = factor * wf / (wu * wu);
    spread(mf, mu, out);
}
