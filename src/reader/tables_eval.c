/*
 * Evaluating and sampling a table file (tables_internal.h) as the
 * renderers' `measured` readers do (docs/measured-format.md, "Evaluation
 * and sampling"): the half vector's coordinates on the unit square, the
 * VNDF warp's inverse to the sample square, the stored values there times
 * D / (4 sigma) under the jacobian rule; sampling by the luminance warp,
 * then the VNDF warp, then reflection about the normal. Then the cores of
 * the public calls in the layer convention of ll_bsdf.h.
 */
#include "reader/tables_internal.h"
#include "reader/bsdf_format.h"

#include <math.h>

/* Elevation of a unit vector, stable near the pole: 2 asin(|d - n| / 2). */
static double elevation(const double d[3])
{
    double x = d[0], y = d[1], z = d[2] - 1.0, r = 0.5 * sqrt(x * x + y * y + z * z);
    return 2.0 * asin(r > 1.0 ? 1.0 : r);
}

static double theta_to_u(double theta) { return sqrt(theta * (2.0 / LL_PI)); }

static double phi_to_u(double phi) { return (phi + LL_PI) * (0.5 / LL_PI); }

/* The unit-square coordinates (u_theta, u_phi) are stored with u_theta as
 * the last axis: warp x = u_theta, y = u_phi. */
static void normal_coords(const double m[3], double phi_i, double um[2], double *theta_m)
{
    double u;
    *theta_m = elevation(m);
    um[0] = theta_to_u(*theta_m);
    u = phi_to_u(atan2(m[1], m[0]) - phi_i);
    um[1] = u - floor(u);
}

/* The jacobian factor D(m) / (4 sigma(wi)) (1 for a file without it); 0
 * if it is not finite. */
static double jacobian(const ll_measured *t, const double um[2], const double uwi[2])
{
    ll_warp_slices one;
    double r;
    if (!t->jacobian)
        return 1.0;
    ll_warp_slices_single(&one);
    r = ll_warp2d_eval_at(&t->ndf, &one, um) / (4.0 * ll_warp2d_eval_at(&t->sigma, &one, uwi));
    return ll_is_finite(r) ? r : 0.0;
}

/* The slices of an incident direction: the same for the vndf, luminance
 * and (with the channel appended) rgb tables, whose parameter lists are
 * the file's theta_i and phi_i alike. */
static void incident_slices(const ll_measured *t, double phi_i, double theta_i,
                            ll_warp_slices *sl)
{
    double param[2] = { phi_i, theta_i };
    ll_warp2d_slices(&t->vndf, param, sl);
}

/* The channels at s; channel c hits node c of the 3 exactly (as the
 * renderers evaluate an RGB file at 0, 1, 2). */
static void values_at(const ll_measured *t, const ll_warp_slices *sl, const double s[2],
                      double scale, double value[3])
{
    size_t c;
    ll_warp2d_eval_nodes(&t->rgb, sl, 3, s, value);
    for (c = 0; c < 3; ++c) {
        double v = value[c] * scale;
        value[c] = v > 0.0 ? v : 0.0;
    }
}

/* pdf of the reflected direction from the densities over the two squares. */
static double reflected_pdf(double p_v, double p_l, double u_theta_m, double theta_m,
                            double wi_dot_m)
{
    double area = 2.0 * LL_PI * LL_PI * u_theta_m * sin(theta_m);
    double pdf;
    if (area < 1e-6)
        area = 1e-6;
    pdf = p_v * p_l / (area * 4.0 * wi_dot_m);
    return ll_is_finite(pdf) && pdf > 0.0 ? pdf : 0.0;
}

/* The half vector of wi and wo, or 0 if both do not lie above the surface. */
static int half_vector(const double wi[3], const double wo[3], double m[3])
{
    double len;
    if (!(wi[2] > 0.0 && wo[2] > 0.0))
        return 0;
    m[0] = wi[0] + wo[0];
    m[1] = wi[1] + wo[1];
    m[2] = wi[2] + wo[2];
    len = sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
    m[0] /= len;
    m[1] /= len;
    m[2] /= len;
    return 1;
}

void ll_measured_eval(const ll_measured *t, const double wi[3], const double wo[3],
                      double value[3])
{
    double m[3], um[2], uwi[2], s[2], theta_m, theta_i, phi_i, p_v;
    ll_warp_slices sl;
    value[0] = value[1] = value[2] = 0.0;
    if (!half_vector(wi, wo, m))
        return;
    theta_i = elevation(wi);
    phi_i = atan2(wi[1], wi[0]);
    uwi[0] = theta_to_u(theta_i);
    uwi[1] = phi_to_u(phi_i);
    normal_coords(m, phi_i, um, &theta_m);
    incident_slices(t, phi_i, theta_i, &sl);
    ll_warp2d_invert_at(&t->vndf, &sl, um, s, &p_v);
    values_at(t, &sl, s, jacobian(t, um, uwi), value);
}

double ll_measured_pdf(const ll_measured *t, const double wi[3], const double wo[3])
{
    double m[3], um[2], s[2], theta_m, theta_i, phi_i, p_v, p_l;
    ll_warp_slices sl;
    if (!half_vector(wi, wo, m))
        return 0.0;
    theta_i = elevation(wi);
    phi_i = atan2(wi[1], wi[0]);
    normal_coords(m, phi_i, um, &theta_m);
    incident_slices(t, phi_i, theta_i, &sl);
    ll_warp2d_invert_at(&t->vndf, &sl, um, s, &p_v);
    p_l = ll_warp2d_eval_at(&t->luminance, &sl, s);
    return reflected_pdf(p_v, p_l, um[0], theta_m,
                         wi[0] * m[0] + wi[1] * m[1] + wi[2] * m[2]);
}

int ll_measured_sample(const ll_measured *t, const double wi[3], const double u[2],
                       double wo[3], double *pdf, double value[3])
{
    double theta_i, phi_i, pt[2], s[2], um[2], p_l, p_v, theta_m, m[3], d;
    double uwi[2];
    ll_warp_slices sl;
    wo[0] = wo[1] = 0.0;
    wo[2] = 1.0;
    *pdf = 0.0;
    value[0] = value[1] = value[2] = 0.0;
    if (!(wi[2] > 0.0))
        return 0;
    theta_i = elevation(wi);
    phi_i = atan2(wi[1], wi[0]);
    incident_slices(t, phi_i, theta_i, &sl);
    /* The second number drives the warps' x (the elevation-like axis), as
     * Mitsuba's swap of the two does. */
    pt[0] = u[1];
    pt[1] = u[0];
    ll_warp2d_sample_at(&t->luminance, &sl, pt, s, &p_l);
    ll_warp2d_sample_at(&t->vndf, &sl, s, um, &p_v);
    d = ll_tables_mirror(wi, um, phi_i, &theta_m, m, wo);
    if (!(wo[2] > 0.0) || !(d > 0.0)) {
        wo[0] = wo[1] = 0.0;
        wo[2] = 1.0;
        return 0;
    }
    *pdf = reflected_pdf(p_v, p_l, um[0], theta_m, d);
    if (!(*pdf > 0.0)) {
        wo[0] = wo[1] = 0.0;
        wo[2] = 1.0;
        return 0;
    }
    uwi[0] = theta_to_u(theta_i);
    uwi[1] = phi_to_u(phi_i);
    values_at(t, &sl, s, jacobian(t, um, uwi), value);
    return 1;
}

/* ------------------------------------------------ the layer convention */

/* The viewer at azimuth 0 (the files are isotropic): wi of the format is
 * our incident direction reversed, wo the outgoing one reversed, with the
 * azimuth phi_d measured from the mirror direction (ll_bsdf.h). */
static void viewer(double mu_i, double wi[3])
{
    double s = 1.0 - mu_i * mu_i;
    wi[0] = s > 0.0 ? sqrt(s) : 0.0;
    wi[1] = 0.0;
    wi[2] = mu_i;
}

static void light(double mu_o, double cos_phi, double wo[3])
{
    double s = 1.0 - mu_o * mu_o, sp = 1.0 - cos_phi * cos_phi;
    s = s > 0.0 ? sqrt(s) : 0.0;
    wo[0] = -s * cos_phi;
    wo[1] = -s * (sp > 0.0 ? sqrt(sp) : 0.0);
    wo[2] = -mu_o;
}

void ll_measured_eval_cos(const ll_bsdf *b, double mu_i, double mu_o, double cos_phi,
                          const float *basis, double extra_scale, double rgb[3])
{
    double wi[3], wo[3], v[3], scale;
    int c;
    rgb[0] = rgb[1] = rgb[2] = 0.0;
    if (!(mu_i > 0.0 && mu_o < 0.0))
        return;
    viewer(mu_i, wi);
    light(mu_o, cos_phi, wo);
    ll_measured_blend_eval(b, wi, wo, basis, v);
    scale = extra_scale * ll_bsdf_cosine_scale(mu_o);
    for (c = 0; c < 3; ++c) {
        rgb[c] = v[c] * scale;
        if (!(rgb[c] > 0.0) || !ll_is_finite(rgb[c]))
            rgb[c] = 0.0;
    }
}

double ll_measured_pdf_cos(const ll_bsdf *b, double mu_i, double mu_o, double cos_phi,
                          const float *basis)
{
    double wi[3], wo[3];
    if (!(mu_i > 0.0 && mu_o < 0.0))
        return 0.0;
    viewer(mu_i, wi);
    light(mu_o, cos_phi, wo);
    return ll_measured_blend_pdf(b, wi, wo, basis);
}

int ll_measured_sample_core(const ll_bsdf *b, double mu_i, const double u[2],
                            const float *basis, double *mu_o, double *phi_d, double *pdf,
                            double sums[3])
{
    double wi[3], wo[3], v[3], phi;
    *mu_o = *phi_d = *pdf = 0.0;
    sums[0] = sums[1] = sums[2] = 0.0;
    if (!(mu_i > 0.0))
        return 0;
    viewer(mu_i, wi);
    if (!ll_measured_blend_sample(b, wi, u, basis, wo, pdf, v))
        return 0;
    *mu_o = -wo[2];
    phi = atan2(-wo[1], -wo[0]);
    *phi_d = phi < 0.0 ? phi + 2.0 * LL_PI : phi;
    /* The callers turn (Y, R, B) sums into RGB with the green of
     * ll_bsdf_to_rgb; this Y gives the stored green back. */
    sums[1] = v[0];
    sums[2] = v[2];
    sums[0] = (v[1] - LL_BSDF_G_FROM_B * sums[2] - LL_BSDF_G_FROM_R * sums[1]) /
              LL_BSDF_G_FROM_Y;
    return 1;
}
