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

#include "layerlab/ll_layer.h"

#include <math.h>
#include <string.h>

static double dot(const double *a, const double *b, size_t n)
{
    double sum = 0.0;
    size_t i;
    for (i = 0; i < n; ++i)
        sum += a[i] * b[i];
    return sum;
}

static void clear(ll_microfacet_compensation *out)
{
    memset(out, 0, sizeof *out);
}

/* Per incident direction, the energy that single scattering loses
 * (1 - R - T) goes back first into transmission in proportion to the
 * current T / (R + T), as the product of the two sides' deficits so that
 * T^bt = (T^tb)^T / eta^2 keeps reciprocity, then the rest into reflection
 * as a symmetric u u^T / (W.u). */
void ll_microfacet_compensate_dielectric(size_t h, const double *w, double eta,
                                         const double *const albedo[4], double *work,
                                         ll_microfacet_compensation *out)
{
    const double *rt = albedo[LL_BLOCK_RT], *rb = albedo[LL_BLOCK_RB];
    const double *ttb = albedo[LL_BLOCK_TTB], *tbt = albedo[LL_BLOCK_TBT];
    double *a_tb = work, *a_bt = work + h, *r_t = work + 2 * h, *r_b = work + 3 * h;
    double eta2 = eta * eta, norm, w_tb, w_bt, wa;
    size_t j;

    clear(out);
    for (j = 0; j < h; ++j) {
        double sum_t = rt[j] + ttb[j], sum_b = rb[j] + tbt[j];
        a_tb[j] = sum_t > 0.0 ? fmax(0.0, (1.0 - sum_t) * ttb[j] / sum_t) : 0.0;
        a_bt[j] = sum_b > 0.0 ? fmax(0.0, (1.0 - sum_b) * tbt[j] / sum_b) : 0.0;
    }
    /* C^tb = a_bt a_tb^T / norm; column j of W C^tb sums to a_tb[j] (W.a_bt)
     * / norm <= a_tb[j], and C^bt = (C^tb)^T / eta^2 sums to at most
     * a_bt[j]: the larger of the two normalisations keeps both below the
     * deficit. */
    w_bt = dot(w, a_bt, h);
    w_tb = dot(w, a_tb, h);
    norm = fmax(w_bt, w_tb / eta2);
    if (norm > 0.0) {
        out->u[LL_BLOCK_TTB] = a_bt;
        out->v[LL_BLOCK_TTB] = a_tb;
        out->scale[LL_BLOCK_TTB] = 1.0 / norm;
        out->u[LL_BLOCK_TBT] = a_tb;
        out->v[LL_BLOCK_TBT] = a_bt;
        out->scale[LL_BLOCK_TBT] = 1.0 / (norm * eta2);
    }
    /* What is left for reflection: the transmission albedos now include
     * the terms above, column j of W C^tb being a_tb[j] (W.a_bt) / norm. */
    for (j = 0; j < h; ++j) {
        double t_tb = ttb[j], t_bt = tbt[j];
        if (norm > 0.0) {
            t_tb += a_tb[j] * w_bt / norm;
            t_bt += a_bt[j] * w_tb / (norm * eta2);
        }
        r_t[j] = fmax(0.0, 1.0 - rt[j] - t_tb); /* reflection deficit, top    */
        r_b[j] = fmax(0.0, 1.0 - rb[j] - t_bt); /* reflection deficit, bottom */
    }
    wa = dot(w, r_t, h);
    if (wa > 0.0) {
        out->u[LL_BLOCK_RT] = out->v[LL_BLOCK_RT] = r_t;
        out->scale[LL_BLOCK_RT] = 1.0 / wa;
    }
    wa = dot(w, r_b, h);
    if (wa > 0.0) {
        out->u[LL_BLOCK_RB] = out->v[LL_BLOCK_RB] = r_b;
        out->scale[LL_BLOCK_RB] = 1.0 / wa;
    }
}

/* A perfect mirror of the same roughness (F = 1) keeps the fraction E(mu)
 * of the light arriving along mu and loses 1 - E(mu) to shadowing; that
 * light returns after further bounces, each reflecting about the average
 * Fresnel reflectance F_avg. The term is u u^T (W.u)^-1 f, u = 1 - E, so
 * direction mu gets back f (1 - E(mu)), with
 * f = F_avg E_avg / (1 - F_avg (1 - E_avg)) and E_avg the hemispherical
 * average of E. Same on both sides. */
void ll_microfacet_compensate_conductor(size_t h, const double *w, double eta_re,
                                        double eta_im, const double *mirror_albedo,
                                        double *work, ll_microfacet_compensation *out)
{
    double *lost = work, f_avg, e_avg, factor, wl;
    size_t j;
    clear(out);
    for (j = 0; j < h; ++j)
        lost[j] = fmax(0.0, 1.0 - mirror_albedo[j]);
    wl = dot(w, lost, h);
    if (!(wl > 0.0))
        return;
    /* (The interface's index was checked: this cannot fail.) */
    (void)ll_fresnel_conductor_average(eta_re, eta_im, &f_avg);
    e_avg = 1.0 - wl * LL_INV_PI; /* hemispherical albedo of the mirror */
    factor = f_avg * e_avg / (1.0 - f_avg * (1.0 - e_avg));
    out->u[LL_BLOCK_RT] = out->v[LL_BLOCK_RT] = lost;
    out->u[LL_BLOCK_RB] = out->v[LL_BLOCK_RB] = lost;
    out->scale[LL_BLOCK_RT] = out->scale[LL_BLOCK_RB] = factor / wl;
}
