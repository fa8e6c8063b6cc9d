/*
 * The refraction warp of a transmitted lobe across a net interface
 * (tables_internal.h): the generalised half vector of Walter et al. 2007,
 * "Microfacet Models for Refraction through Rough Surfaces", sec. 5.2,
 * m = -(wi + eta wo) / |wi + eta wo| turned above the surface, with wi
 * above (index 1) and wo below (relative index eta); wo is wi refracted
 * through m. Shared by the reader's sampler and the writer's sample grid,
 * as ll_tables_mirror is for reflection: the writer stores values at the
 * very directions the readers' warps produce.
 */
#ifndef LL_TABLES_REFRACT_H
#define LL_TABLES_REFRACT_H

#include "support/support.h"
#include "reader/tables_warp.h"

#include <math.h>

/* The normal m of the visible-normal square's point um (as
 * ll_tables_mirror maps it) and wi refracted through it; returns wi.m, or
 * 0 where wi.m <= 0 or total internal reflection leaves no refracted
 * direction (wo then (0, 0, 1)). */
static inline double ll_tables_refract(const double wi[3], const double um[2], double phi_i,
                                       double eta, double *theta_m, double m[3], double wo[3])
{
    double tm = um[0] * um[0] * (LL_PI / 2), pm = (2.0 * um[1] - 1.0) * LL_PI + phi_i;
    double c, k, inv = 1.0 / eta, a;
    m[0] = sin(tm) * cos(pm);
    m[1] = sin(tm) * sin(pm);
    m[2] = cos(tm);
    *theta_m = tm;
    c = wi[0] * m[0] + wi[1] * m[1] + wi[2] * m[2];
    k = 1.0 - inv * inv * (1.0 - c * c);
    wo[0] = wo[1] = 0.0;
    wo[2] = 1.0;
    if (!(c > 0.0) || !(k > 0.0))
        return 0.0;
    a = inv * c - sqrt(k);
    wo[0] = a * m[0] - inv * wi[0];
    wo[1] = a * m[1] - inv * wi[1];
    wo[2] = a * m[2] - inv * wi[2];
    return c;
}

/* The half vector of the pair (wi above, wo below), and 1; 0 if the pair
 * is not one of a refraction through it (wi.m > 0 > wo.m). */
static inline int ll_tables_refract_half(const double wi[3], const double wo[3], double eta,
                                         double m[3])
{
    double len;
    int k;
    if (!(wi[2] > 0.0 && wo[2] < 0.0))
        return 0;
    for (k = 0; k < 3; ++k)
        m[k] = -(wi[k] + eta * wo[k]);
    len = sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
    if (!(len > 0.0))
        return 0;
    if (m[2] < 0.0)
        len = -len;
    for (k = 0; k < 3; ++k)
        m[k] /= len;
    return wi[0] * m[0] + wi[1] * m[1] + wi[2] * m[2] > 0.0 &&
           wo[0] * m[0] + wo[1] * m[1] + wo[2] * m[2] < 0.0;
}

/* d omega_m / d omega_o of the refraction (Walter et al. eq. 16):
 * eta^2 |wo.m| / (wi.m + eta wo.m)^2; 0 where it is not finite. */
static inline double ll_tables_refract_jacobian(const double wi[3], const double wo[3],
                                                const double m[3], double eta)
{
    double im = wi[0] * m[0] + wi[1] * m[1] + wi[2] * m[2];
    double om = wo[0] * m[0] + wo[1] * m[1] + wo[2] * m[2], d = im + eta * om;
    double j = eta * eta * fabs(om) / (d * d);
    return ll_is_finite(j) ? j : 0.0;
}

/* The unpolarised Fresnel reflectance of a smooth interface for light
 * at cosine c (> 0) to its normal on the side of index 1, the far side of
 * relative index eta: 1 under total internal reflection. */
static inline double ll_tables_fresnel(double c, double eta)
{
    double s2 = (1.0 - c * c) / (eta * eta), ct, rs, rp;
    if (!(s2 < 1.0))
        return 1.0;
    ct = sqrt(1.0 - s2);
    rs = (c - eta * ct) / (c + eta * ct);
    rp = (eta * c - ct) / (eta * c + ct);
    return 0.5 * (rs * rs + rp * rp);
}

/* That reflectance at the reflection half vector of (wi, wo), both above:
 * the factor a reflected set stored over it ("fresnel_eta") is
 * multiplied by; 1 where the pair has no half vector. */
static inline double ll_tables_fresnel_pair(const double wi[3], const double wo[3], double eta)
{
    double h[3] = { wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2] };
    double len = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]), c;
    if (!(len > 0.0))
        return 1.0;
    c = (wi[0] * h[0] + wi[1] * h[1] + wi[2] * h[2]) / len;
    return c > 0.0 ? ll_tables_fresnel(c > 1.0 ? 1.0 : c, eta) : 1.0;
}

/* The largest share q of the floor below: beyond it (F + q) / (1 + q) is 1
 * to double precision's use here, and D(m) = 0 (a normal the set's D does
 * not reach) takes it. */
#define LL_TABLES_FLOOR_SHARE_MAX 1e6

/* The factor of a reflected set stored over F with a floor k
 * ("fresnel_floor"): (F + q) / (1 + q) with q = k D(0) / D(m), D the set's
 * own normal distribution (its "ndf" table, ndf: isotropic, read at
 * u_phi 0.5) and m the reflection half vector of (wi, wo). F for k = 0,
 * and 1 beyond the edge of total internal reflection for every k; the
 * share of the floor grows where D, and with it the microfacets' own
 * reflection that F describes, falls off (bsdf_write_tables_lobes.c says
 * why). Shared by the writer, its horizon fit and the reader, so that
 * all three divide and multiply by the same factor. */
static inline double ll_tables_fresnel_floor_pair(const double wi[3], const double wo[3],
                                                  double eta, double floor,
                                                  const ll_warp2d *ndf)
{
    double f = ll_tables_fresnel_pair(wi, wo, eta), q, d;
    double h[3] = { wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2] };
    double pole[2] = { 0.0, 0.5 }, um[2];
    if (!(floor > 0.0))
        return f;
    um[0] = ll_tables_theta_to_u(atan2(sqrt(h[0] * h[0] + h[1] * h[1]), h[2]));
    um[1] = 0.5;
    d = ll_warp2d_eval(ndf, um, NULL);
    q = d > 0.0 ? floor * ll_warp2d_eval(ndf, pole, NULL) / d : LL_TABLES_FLOOR_SHARE_MAX;
    if (!(q <= LL_TABLES_FLOOR_SHARE_MAX))
        q = LL_TABLES_FLOOR_SHARE_MAX;
    return (f + q) / (1.0 + q);
}

/* The factor a transmitted set stored over its refraction's transmittance
 * ("transmittance_eta") is multiplied by: 1 - F(wi.m) times d omega_m /
 * d omega_o at the refraction half vector m of (wi above, wo below). Both factors vanish like |wo.m| at the edge of
 * total internal reflection, where the refracted direction grazes the
 * microfacet, so f |cos| / D over them is smooth across it. */
static inline double ll_tables_transmittance_at(const double wi[3], const double wo[3],
                                                const double m[3], double eta)
{
    double c = wi[0] * m[0] + wi[1] * m[1] + wi[2] * m[2];
    return (1.0 - ll_tables_fresnel(c > 1.0 ? 1.0 : c, eta)) *
           ll_tables_refract_jacobian(wi, wo, m, eta);
}

/* The same where m is the pair's own refraction half vector. */
static inline double ll_tables_transmittance_pair(const double wi[3], const double wo[3],
                                                  double eta)
{
    double m[3];
    return ll_tables_refract_half(wi, wo, eta, m) ? ll_tables_transmittance_at(wi, wo, m, eta)
                                                  : 0.0;
}

#endif /* LL_TABLES_REFRACT_H */
