/*
 * One transmitted lobe of an extended table file across a net interface
 * (tables_internal.h, tables_refract.h), in the lobe's own frame (the
 * fixed direction wi above, wo below, relative index m->refract_eta): as
 * a reflected lobe (tables_eval.c) with the refraction half vector in the
 * place of the reflection's and the refraction's change of variables
 * (tables_refract.h) in the place of 1 / (4 wi.m). The stored values are
 * f |cos theta_o| 4 sigma(wi) / D(m) under the jacobian rule, as for
 * reflection.
 */
#include "reader/tables_internal.h"
#include "reader/tables_refract.h"

#include <math.h>

static void normal_coords(const double m[3], double phi_i, double um[2], double *theta_m)
{
    double u;
    *theta_m = ll_tables_elevation(m);
    um[0] = ll_tables_theta_to_u(*theta_m);
    u = ll_tables_phi_to_u(atan2(m[1], m[0]) - phi_i);
    um[1] = u - floor(u);
}

/* The incident direction's slices and square coordinates. */
static void incident(const ll_measured *t, const double wi[3], double *phi_i, double uwi[2],
                     ll_warp_slices *sl)
{
    double theta_i = ll_tables_elevation(wi), param[2];
    *phi_i = atan2(wi[1], wi[0]);
    uwi[0] = ll_tables_theta_to_u(theta_i);
    uwi[1] = ll_tables_phi_to_u(*phi_i);
    param[0] = *phi_i;
    param[1] = theta_i;
    ll_warp2d_slices(&t->vndf, param, sl);
}

/* The stored channels at s times D(m) / (4 sigma(wi)) (jacobian rule). */
static void values_at(const ll_measured *t, const ll_warp_slices *sl, const double s[2],
                      const double um[2], const double uwi[2], double value[3])
{
    ll_warp_slices one;
    double scale = 1.0;
    if (t->jacobian) {
        ll_warp_slices_single(&one);
        scale = ll_warp2d_eval_at(&t->ndf, &one, um) /
                (4.0 * ll_warp2d_eval_at(&t->sigma, &one, uwi));
        if (!ll_is_finite(scale))
            scale = 0.0;
    }
    ll_measured_values_at(t, sl, s, scale, value);
}

/* pdf of wo from the densities over the two squares: per unit area of the
 * normal's square (2 pi^2 u_theta sin theta_m per steradian), times the
 * refraction's d omega_m / d omega_o. */
/* A set stored over its refraction's transmittance ("transmittance_eta",
 * tables_refract.h): its values times that factor. */
static void scale(double value[3], double k)
{
    value[0] *= k;
    value[1] *= k;
    value[2] *= k;
}

static double refracted_pdf(double p_v, double p_l, double u_theta_m, double theta_m,
                            double jac)
{
    double pdf = p_v * p_l / ll_measured_normal_area(u_theta_m, theta_m) * jac;
    return ll_is_finite(pdf) && pdf > 0.0 ? pdf : 0.0;
}

void ll_measured_refract_eval(const ll_measured *t, const double wi[3], const double wo[3],
                              double value[3])
{
    double m[3], um[2], uwi[2], s[2], theta_m, phi_i, p_v;
    ll_warp_slices sl;
    value[0] = value[1] = value[2] = 0.0;
    if (!ll_tables_refract_half(wi, wo, t->refract_eta, m))
        return;
    incident(t, wi, &phi_i, uwi, &sl);
    normal_coords(m, phi_i, um, &theta_m);
    ll_warp2d_invert_at(&t->vndf, &sl, um, s, &p_v);
    values_at(t, &sl, s, um, uwi, value);
    if (t->transmittance_eta > 0.0)
        scale(value, ll_tables_transmittance_at(wi, wo, m, t->transmittance_eta));
}

double ll_measured_refract_pdf(const ll_measured *t, const double wi[3], const double wo[3])
{
    double m[3], um[2], uwi[2], s[2], theta_m, phi_i, p_v, p_l;
    ll_warp_slices sl;
    if (!ll_tables_refract_half(wi, wo, t->refract_eta, m))
        return 0.0;
    incident(t, wi, &phi_i, uwi, &sl);
    normal_coords(m, phi_i, um, &theta_m);
    ll_warp2d_invert_at(&t->vndf, &sl, um, s, &p_v);
    p_l = ll_warp2d_eval_at(&t->luminance, &sl, s);
    return refracted_pdf(p_v, p_l, um[0], theta_m,
                         ll_tables_refract_jacobian(wi, wo, m, t->refract_eta));
}

int ll_measured_refract_sample(const ll_measured *t, const double wi[3], const double u[2],
                               double wo[3], double *pdf, double value[3])
{
    double phi_i, uwi[2], pt[2], s[2], um[2], p_l, p_v, theta_m, m[3];
    ll_warp_slices sl;
    wo[0] = wo[1] = 0.0;
    wo[2] = 1.0;
    *pdf = 0.0;
    value[0] = value[1] = value[2] = 0.0;
    if (!(wi[2] > 0.0))
        return 0;
    incident(t, wi, &phi_i, uwi, &sl);
    /* u[1] drives the warps' x, as for reflection (tables_eval.c). */
    pt[0] = u[1];
    pt[1] = u[0];
    ll_warp2d_sample_at(&t->luminance, &sl, pt, s, &p_l);
    ll_warp2d_sample_at(&t->vndf, &sl, s, um, &p_v);
    if (!(ll_tables_refract(wi, um, phi_i, t->refract_eta, &theta_m, m, wo) > 0.0) ||
        !(wo[2] < 0.0)) {
        wo[0] = wo[1] = 0.0;
        wo[2] = 1.0;
        return 0;
    }
    *pdf = refracted_pdf(p_v, p_l, um[0], theta_m,
                         ll_tables_refract_jacobian(wi, wo, m, t->refract_eta));
    if (!(*pdf > 0.0)) {
        wo[0] = wo[1] = 0.0;
        wo[2] = 1.0;
        return 0;
    }
    values_at(t, &sl, s, um, uwi, value);
    /* (At wo's own refraction half vector, as the evaluation takes it,
     * not the sampled m: the two agree to rounding only.) */
    if (t->transmittance_eta > 0.0)
        scale(value, ll_tables_transmittance_pair(wi, wo, t->transmittance_eta));
    return 1;
}
