/*
 * The GGX parts of a pair's series. GGX has the same g and the same
 * A + B cos phi as Beckmann, but its peak factor (1 - A - B cos phi)^-2 has
 * tails that never fall below 1e-12 on the circle: its window is the whole
 * circle, where the peak's series is known in closed form and g is
 * interpolated in cos phi (words/microfacet_ggx.h); its Filon path
 * (microfacet_filon.c) grades the panels geometrically away from the peak.
 */
#include "words/microfacet_pair.h"

#include <math.h>

/* ll_microfacet_plan_pair for GGX, from Beckmann's A + B = -X_0 and B: the peak factor
 * (1 + X_0)^-2 (1 + beta v)^-2, beta = B / (1 + X_0). */
int ll_microfacet_plan_ggx(const ll_microfacet_model *mf, pair_plan *p, double b_limit, double mu_i,
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
    if (!ll_microfacet_classify_window(mf, p))
        return 0;
    p->sign_h = h_z > 0.0 ? 1.0 : -1.0;
    p->scale = ll_microfacet_pair_scale(mf, p, ll_ggx_smith_g1(si / fabs(mu_i), mf->alpha),
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

/* GGX's smooth pairs: g at the Chebyshev points of cos phi, the closed
 * form of the peak's series (words/microfacet_ggx.h). */
ll_status ll_microfacet_ggx_pair_series(const ll_microfacet_model *mf, const pair_plan *p,
                                        size_t max_len, double *out, size_t *n_out, double *ref0,
                                        double *scratch)
{
    double *g = scratch, *g_ref = scratch + LL_GGX_CHEB, *rest = scratch + 2 * LL_GGX_CHEB;
    double peak = exp(p->a_plus_b);
    size_t i, len = ll_ggx_length_at(&p->peak_len, max_len) + LL_GGX_CHEB;
    ll_microfacet_sample_profile(mf, p, mf->ggx_basis.cos_phi, LL_GGX_CHEB, g, ref0 ? g_ref : NULL);
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

/* Reflection with total internal reflection below the split (light from
 * the denser side): F = 1 there, so f is its reference (F = 1), whose g
 * is a quadratic in cos phi and whose series the closed form gives
 * exactly, plus f minus the reference, which vanishes below the split.
 * Only that part, with Fresnel's square root at the split, takes the
 * Filon path; it lies in the peak's tail, away from the azimuths where the
 * pieces are narrow, and as it is small against the pair's mean, far
 * fewer of its orders matter than the peak has. */
ll_status ll_microfacet_ggx_tir_series(const ll_microfacet_model *mf, const pair_plan *p,
                                       size_t max_len, double *out, size_t *n_out, double *ref0,
                                       double *scratch)
{
    double *g_ref = scratch, *rest = scratch + LL_GGX_CHEB, *part, peak = exp(p->a_plus_b);
    double seen = 0.0;
    size_t i, l, len = ll_ggx_length_at(&p->peak_len, max_len), n_part;
    size_t n_filon = len + FILON_EXTRA < max_len ? len + FILON_EXTRA : max_len;
    len = len + LL_GGX_CHEB < max_len ? len + LL_GGX_CHEB : max_len;
    ll_microfacet_sample_profile(mf, p, mf->ggx_basis.cos_phi, LL_GGX_CHEB, NULL, g_ref);
    for (i = 0; i < LL_GGX_CHEB; ++i) {
        double c = 1.0 + p->b * (1.0 - mf->ggx_basis.cos_phi[i]), value;
        g_ref[i] *= peak;
        value = g_ref[i] / (c * c);
        if (value > seen) /* (fmax's choice: a NaN value leaves seen) */
            seen = value;
    }
    ll_ggx_series(&mf->ggx_basis, p->b, g_ref, len, out, rest);
    if (ref0)
        *ref0 = out[0];
    /* The part after the series' scratch is done with: the part's terms,
     * then Filon's scratch. */
    part = scratch;
    n_part = ll_microfacet_ggx_fresnel_part(mf, p, out[0], seen, n_filon, part,
                                            scratch + max_len);
    for (l = len; l < n_part; ++l)
        out[l] = 0.0;
    for (l = 0; l < n_part; ++l)
        out[l] += part[l];
    *n_out = n_part > len ? n_part : len;
    return LL_OK;
}
