/*
 * The Fourier series of the microfacet BSDF of Walter et al. 2007 for one
 * pair of zenith cosines (ll_microfacet_series): the Beckmann lobe by the
 * maps below, the widening of lobes too sharp for the layer's orders, and
 * the truncation (Jakob et al. 2014, section 6.2 and the appendix; the
 * original layerlab's microfacetFourierSeries, whose BSDF and conventions
 * this reproduces).
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
 * computed once per model, by Gauss-Legendre quadrature of the window
 * (microfacet_model.c). A
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
 * Where g has a kink inside the window, or a branch point just outside
 * it, f is integrated by Filon's rule instead (microfacet_filon.c).
 *
 * Lobes too sharp for the layer's orders (grazing angles) are widened as
 * in the original, but keep the energy (order 0) of the true lobe: the
 * original keeps only the integral of exp(A + B cos phi), and with g not
 * constant across the wider lobe that adds up to 10% at grazing angles
 * (R + T = 1.06 for eta = 1.5, alpha = 0.3 at its 61 orders).
 *
 * GGX: microfacet_ggx_pair.c.
 */
#include "words/microfacet_pair.h"

#include "numerics/series.h"

#include <math.h>
#include <string.h>

size_t ll_microfacet_scratch_size(size_t max_len)
{
    return MICROFACET_SCRATCH(max_len);
}

/* The series of a planned pair, n_out <= max_len terms (*n_out), and the
 * order 0 of its reference (F = 1) if ref0 is not NULL. Where its map is
 * missing: with missing not NULL, *missing = 1 and nothing computed, else
 * a failure. */
static ll_status pair_series(const ll_microfacet_model *mf, const pair_plan *p, size_t max_len,
                             double *out, size_t *n_out, double *ref0, double *scratch,
                             int *missing)
{
    const grid_entry *e;
    double *g = scratch, *g_ref = ref0 ? scratch + CHEB : NULL, rest, peak;
    size_t i, l, len;
    if (mf->ggx && !p->filon)
        return ll_microfacet_ggx_pair_series(mf, p, max_len, out, n_out, ref0, scratch);
    if (mf->ggx && p->reflect && p->split > 0.0)
        return ll_microfacet_ggx_tir_series(mf, p, max_len, out, n_out, ref0, scratch);
    if (p->filon) {
        /* (At most FILON_EXTRA orders, as for the order 0 of a probe or a
         * widened lobe, need not ask the peak's length: len exceeds it.) */
        len = max_len <= FILON_EXTRA
                  ? max_len
                  : (mf->ggx ? ll_ggx_length_at(&p->peak_len, max_len)
                             : ll_expcos_length(p->b, TAIL_GOAL)) +
                        FILON_EXTRA;
        *n_out = len < max_len ? len : max_len;
        if (ref0) /* order 0 of the reference, by the same rule */
            ll_microfacet_filon_series(mf, p, 1, 1, ref0, scratch);
        ll_microfacet_filon_series(mf, p, 0, *n_out, out, scratch);
        return LL_OK;
    }
    e = p->grid < mf->n_grid ? mf->grid[p->grid] : NULL;
    if (!e && missing) {
        *n_out = 0;
        *missing = 1;
        return LL_OK;
    }
    if (!e)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "microfacet series: the pair (%g, %g) was not prepared", p->mu_o,
                       p->mu_i);
    /* g times the part of exp(-B v) that the grid point leaves out. */
    ll_microfacet_sample_profile(mf, p, e->cos_phi, CHEB, g, g_ref);
    rest = (p->b - e->b) * e->delta;
    peak = p->peak;
    for (i = 0; i < CHEB; ++i) {
        double factor = peak * exp(-rest * e->u[i]);
        g[i] *= factor;
        if (g_ref)
            g_ref[i] *= factor;
    }
    *n_out = e->len < max_len ? e->len : max_len;
    /* Each order summed over the points in a register, in the points'
     * order (through out, which may alias nothing the compiler can rule
     * out, every term was a store and a load). */
    for (l = 0; l < *n_out; ++l) {
        double sum = 0.0;
        for (i = 0; i < CHEB; ++i)
            sum += g[i] * e->matrix[i * e->len + l];
        out[l] = sum;
    }
    if (g_ref) {
        double sum = 0.0;
        for (i = 0; i < CHEB; ++i)
            sum += g_ref[i] * e->matrix[i * e->len];
        *ref0 = sum;
    }
    return LL_OK;
}

/* ll_microfacet_series_widened, and with missing not NULL,
 * ll_microfacet_series_if_prepared's report of a missing map. */
static ll_status series(const ll_microfacet_model *mf, double mu_o, double mu_i, size_t max_len,
                        double *out, size_t *len, double *ref0, double *scratch, int *widened,
                        int *missing)
{
    pair_plan p;
    size_t n_out, l, last;
    double energy = 0.0, ref_energy = 0.0, keep;
    ll_status s;

    *len = 0;
    *widened = 0;
    if (ref0)
        *ref0 = 0.0;
    if (max_len > mf->max_len)
        max_len = mf->max_len;
    if (max_len == 0 || !ll_microfacet_plan_pair(mf, mu_o, mu_i, HUGE_VAL, &p))
        return LL_OK;
    *widened = p.b > mf->b_max; /* (as ll_microfacet_widened) */
    if (*widened) {
        /* A lobe too sharp for the orders is widened. The original keeps the
         * integral of the peak, but g is not constant across the wider
         * lobe, and at grazing angles the energy so grows by up to 10%
         * (R + T = 1.06 for eta = 1.5, alpha = 0.3 at 61 orders). So the
         * order 0 of the true lobe is computed first, and the widened
         * series scaled to it. */
        if (mf->ggx)
            ll_ggx_length_prepare(p.b, GGX_TAIL_GOAL, 1, &p.peak_len);
        s = pair_series(mf, &p, 1, &energy, &n_out, ref0 ? &ref_energy : NULL, scratch,
                        missing);
        if (s != LL_OK || (missing && *missing))
            return s;
        if (!ll_microfacet_plan_pair(mf, mu_o, mu_i, mf->b_max, &p))
            return LL_OK;
    }
    if (mf->ggx)
        ll_ggx_length_prepare(p.b, GGX_TAIL_GOAL, max_len, &p.peak_len);
    s = pair_series(mf, &p, max_len, out, &n_out, ref0, scratch, missing);
    if (s != LL_OK || (missing && *missing))
        return s;
    if (p.widened) {
        double scale = out[0] > 0.0 ? energy / out[0] : 0.0;
        for (l = 0; l < n_out; ++l)
            out[l] *= scale;
        if (ref0)
            *ref0 = ref_energy;
    }

    /* Truncate after the last term that matters: found from the end, as
     * a series' last terms are the small ones (GGX's are computed to a
     * tenth of what is kept). */
    if (!(out[0] > 0.0))
        return LL_OK; /* a vanishing mean: nothing */
    keep = ll_microfacet_keep(mf) * out[0];
    for (last = n_out > 0 ? n_out - 1 : 0; last > 0 && !(fabs(out[last]) >= keep); --last)
        ;
    *len = last + 1;
    return LL_OK;
}

ll_status ll_microfacet_series(const ll_microfacet_model *mf, double mu_o, double mu_i,
                               size_t max_len, double *out, size_t *len, double *ref0,
                               double *scratch)
{
    int widened;
    return series(mf, mu_o, mu_i, max_len, out, len, ref0, scratch, &widened, NULL);
}

ll_status ll_microfacet_series_widened(const ll_microfacet_model *mf, double mu_o, double mu_i,
                                       size_t max_len, double *out, size_t *len, double *ref0,
                                       double *scratch, int *widened)
{
    return series(mf, mu_o, mu_i, max_len, out, len, ref0, scratch, widened, NULL);
}

ll_status ll_microfacet_series_if_prepared(const ll_microfacet_model *mf, double mu_o,
                                           double mu_i, size_t max_len, double *out,
                                           size_t *len, double *ref0, double *scratch,
                                           int *missing)
{
    int widened;
    *missing = 0;
    return series(mf, mu_o, mu_i, max_len, out, len, ref0, scratch, &widened, missing);
}

double ll_microfacet_keep(const ll_microfacet_model *mf)
{
    return mf->ggx ? LL_MICROFACET_RELERR : LL_MICROFACET_KEEP;
}

int ll_microfacet_widened(const ll_microfacet_model *mf, double mu_o, double mu_i)
{
    pair_plan p;
    return mf->max_len > 0 && ll_microfacet_plan_pair(mf, mu_o, mu_i, HUGE_VAL, &p) &&
           p.b > mf->b_max;
}
