/*
 * Evaluating and sampling a table file (tables_internal.h) as the
 * renderers' `measured` readers do (docs/formats.md, "Evaluation
 * and sampling"): the half vector's coordinates on the unit square, the
 * VNDF warp's inverse to the sample square, the stored values there times
 * D / (4 sigma) under the jacobian rule; sampling by the luminance warp,
 * then the VNDF warp, then reflection about the normal. Then the cores of
 * the public calls in the layer convention of ll_bsdf.h.
 */
#include "reader/tables_internal.h"
#include "reader/bsdf_format.h"
#include "reader/tables_atan.h"

#include <math.h>

/* The fixed direction wi as every look-up needs it: ll_measured_incident
 * (tables_internal.h). */
/* Below this |x| + |y| of wi, products with wi's azimuth vector could
 * underflow: such a wi takes the plain form with phi_i itself. */
#define LL_TABLES_MIN_AZIMUTH 1e-100

typedef ll_measured_incident incident;

static void incident_of(const ll_measured *t, const double wi[3], int unit, incident *in)
{
    double param[2], r = sqrt(wi[0] * wi[0] + wi[1] * wi[1]);
    int need_phi = t->vndf.param_size[0] > 1 || (t->jacobian && !t->sigma.rows_equal);
    /* The elevation of unit wi as atan2's (tables_atan.h), exact at the
     * pole and the horizon alike. */
    in->theta = ll_tables_atan2(r, wi[2]);
    in->u_theta = ll_tables_theta_to_u(in->theta);
    in->ax = wi[0];
    in->ay = wi[1];
    in->has_azimuth = fabs(wi[0]) + fabs(wi[1]) > LL_TABLES_MIN_AZIMUTH;
    in->phi = need_phi || !in->has_azimuth ? atan2(wi[1], wi[0]) : 0.0;
    in->u_phi = ll_tables_phi_to_u(in->phi);
    if (!in->has_azimuth) {
        /* At the pole phi_i is atan2's of what is left, as the renderers
         * take it. */
        in->ax = cos(in->phi);
        in->ay = sin(in->phi);
    } else if (unit) {
        in->ax = wi[0] / r;
        in->ay = wi[1] / r;
    }
    /* The vndf, luminance and (with the channel appended) rgb tables have
     * the file's theta_i and phi_i alike as parameter lists. */
    param[0] = in->phi;
    param[1] = in->theta;
    ll_warp2d_slices(&t->vndf, param, &in->sl);
}

/* The unit-square coordinates (u_theta, u_phi) of the normal along m (of
 * any positive length), with its azimuth relative to phi_i, are stored
 * with u_theta as the last axis: warp x = u_theta, y = u_phi. Both angles
 * by ll_tables_atan2 of m as it is: an eval waits for them before it can
 * read the tables, and the C library's atan2 and asin, and making m unit
 * first, were most of that wait (tables_atan.h). */
static void normal_coords(const double m[3], const incident *in, double um[2], double *theta_m)
{
    double u, phi;
    *theta_m = ll_tables_atan2(sqrt(m[0] * m[0] + m[1] * m[1]), m[2]);
    um[0] = ll_tables_theta_to_u(*theta_m);
    if (in->has_azimuth)
        phi = ll_tables_atan2(m[1] * in->ax - m[0] * in->ay, m[0] * in->ax + m[1] * in->ay);
    else
        phi = atan2(m[1], m[0]) - in->phi;
    u = ll_tables_phi_to_u(phi);
    um[1] = u - floor(u);
}

/* The jacobian factor D(m) / (4 sigma(wi)) (1 for a file without it); 0
 * if it is not finite. */
static double jacobian(const ll_measured *t, const double um[2], const incident *in)
{
    double r, uwi[2];
    if (!t->jacobian)
        return 1.0;
    uwi[0] = in->u_theta;
    uwi[1] = in->u_phi;
    r = ll_warp2d_eval_single(&t->ndf, um) / (4.0 * ll_warp2d_eval_single(&t->sigma, uwi));
    return isfinite(r) ? r : 0.0;
}

/* pdf of the reflected direction from the densities over the two squares
 * (sin_theta_m: the sine of the normal's elevation). */
static double reflected_pdf(double p_v, double p_l, double u_theta_m, double sin_theta_m,
                            double wi_dot_m)
{
    double pdf =
        p_v * p_l / (ll_measured_normal_area_sin(u_theta_m, sin_theta_m) * 4.0 * wi_dot_m);
    return isfinite(pdf) && pdf > 0.0 ? pdf : 0.0;
}

/* The half vector of wi and wo as wi + wo, not made unit (normal_coords
 * and the pdf's cosines take any length), or 0 if both do not lie above
 * the surface. */
static int half_vector(const double wi[3], const double wo[3], double m[3])
{
    if (!(wi[2] > 0.0 && wo[2] > 0.0))
        return 0;
    m[0] = wi[0] + wo[0];
    m[1] = wi[1] + wo[1];
    m[2] = wi[2] + wo[2];
    return 1;
}

/* The look-ups split at their loads from memory (tables_internal.h);
 * the scalar calls below run the steps in a row. */
int ll_measured_look_begin(const ll_measured *t, const double wi[3], const double wo[3],
                           ll_measured_look *lk)
{
    if (!half_vector(wi, wo, lk->m))
        return 0;
    lk->wi[0] = wi[0];
    lk->wi[1] = wi[1];
    lk->wi[2] = wi[2];
    incident_of(t, wi, 0, &lk->in);
    normal_coords(lk->m, &lk->in, lk->um, &lk->theta_m);
    return 1;
}

void ll_measured_look_prefetch_vndf(const ll_measured *t, const ll_measured_look *lk)
{
    ll_warp2d_prefetch_nodes(&t->vndf, &lk->in.sl, lk->um);
}

void ll_measured_look_invert(const ll_measured *t, ll_measured_look *lk)
{
    ll_warp2d_invert_at(&t->vndf, &lk->in.sl, lk->um, lk->s, &lk->p_v);
}

void ll_measured_look_prefetch_values(const ll_measured *t, const ll_measured_look *lk,
                                      int pdf)
{
    ll_warp2d_prefetch_nodes(pdf ? &t->luminance : &t->rgb, &lk->in.sl, lk->s);
}

void ll_measured_look_value(const ll_measured *t, const ll_measured_look *lk, double value[3])
{
    ll_measured_values_at(t, &lk->in.sl, lk->s, jacobian(t, lk->um, &lk->in), value);
}

double ll_measured_look_pdf(const ll_measured *t, const ll_measured_look *lk)
{
    const double *wi = lk->wi, *m = lk->m;
    double p_l = ll_warp2d_eval_at(&t->luminance, &lk->in.sl, lk->s);
    /* The unit normal's sine of elevation and wi . m, m being wi + wo. */
    double inv = 1.0 / sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
    return reflected_pdf(lk->p_v, p_l, lk->um[0], sqrt(m[0] * m[0] + m[1] * m[1]) * inv,
                         (wi[0] * m[0] + wi[1] * m[1] + wi[2] * m[2]) * inv);
}

void ll_measured_eval(const ll_measured *t, const double wi[3], const double wo[3],
                      double value[3])
{
    ll_measured_look lk;
    if (t->extended) {
        ll_measured_lobes_eval(t, wi, wo, value);
        return;
    }
    value[0] = value[1] = value[2] = 0.0;
    if (!ll_measured_look_begin(t, wi, wo, &lk))
        return;
    ll_measured_look_invert(t, &lk);
    ll_measured_look_value(t, &lk, value);
}

double ll_measured_pdf(const ll_measured *t, const double wi[3], const double wo[3])
{
    ll_measured_look lk;
    if (t->extended)
        return ll_measured_lobes_pdf(t, wi, wo);
    if (!ll_measured_look_begin(t, wi, wo, &lk))
        return 0.0;
    ll_measured_look_invert(t, &lk);
    return ll_measured_look_pdf(t, &lk);
}

int ll_measured_draw_begin(const ll_measured *t, const double wi[3], const double u[2],
                           ll_measured_look *lk)
{
    double pt[2];
    if (!(wi[2] > 0.0))
        return 0;
    lk->wi[0] = wi[0];
    lk->wi[1] = wi[1];
    lk->wi[2] = wi[2];
    incident_of(t, wi, 1, &lk->in);
    /* The second number drives the warps' x (the elevation-like axis), as
     * Mitsuba's swap of the two does. */
    pt[0] = u[1];
    pt[1] = u[0];
    ll_warp2d_draw_begin(&t->luminance, &lk->in.sl, pt, &lk->dr);
    ll_warp2d_prefetch_draw(&t->luminance, &lk->in.sl, &lk->dr);
    return 1;
}

void ll_measured_draw_middle(const ll_measured *t, ll_measured_look *lk)
{
    ll_warp2d_draw_end(&t->luminance, &lk->in.sl, &lk->dr, lk->s, &lk->p_l);
    ll_warp2d_prefetch_nodes(&t->rgb, &lk->in.sl, lk->s);
    ll_warp2d_draw_begin(&t->vndf, &lk->in.sl, lk->s, &lk->dr);
    ll_warp2d_prefetch_draw(&t->vndf, &lk->in.sl, &lk->dr);
}

/* A sample's last steps once both warps have sampled (s with density
 * p_l, um with p_v): the reflected direction, its pdf and the values. wo,
 * pdf and value hold the answer for no direction when called. */
static int draw_tail(const ll_measured *t, const double wi[3], const incident *in,
                     const double s[2], double p_l, const double um[2], double p_v,
                     double wo[3], double *pdf, double value[3])
{
    double theta_m, sin_m, m[3];
    double d = ll_tables_mirror_dir(wi, um, in->ax, in->ay, &theta_m, &sin_m, m, wo);
    if (!(wo[2] > 0.0) || !(d > 0.0)) {
        wo[0] = wo[1] = 0.0;
        wo[2] = 1.0;
        return 0;
    }
    *pdf = reflected_pdf(p_v, p_l, um[0], sin_m, d);
    if (!(*pdf > 0.0)) {
        wo[0] = wo[1] = 0.0;
        wo[2] = 1.0;
        return 0;
    }
    ll_measured_values_at(t, &in->sl, s, jacobian(t, um, in), value);
    return 1;
}

static void no_direction(double wo[3], double *pdf, double value[3])
{
    wo[0] = wo[1] = 0.0;
    wo[2] = 1.0;
    *pdf = 0.0;
    value[0] = value[1] = value[2] = 0.0;
}

int ll_measured_draw_end(const ll_measured *t, ll_measured_look *lk, double wo[3], double *pdf,
                         double value[3])
{
    no_direction(wo, pdf, value);
    ll_warp2d_draw_end(&t->vndf, &lk->in.sl, &lk->dr, lk->um, &lk->p_v);
    return draw_tail(t, lk->wi, &lk->in, lk->s, lk->p_l, lk->um, lk->p_v, wo, pdf, value);
}

/* The steps of draw_begin, _middle and _end in a row, each warp's
 * sampling in one call (ll_warp2d_sample_at: the same steps). */
int ll_measured_sample(const ll_measured *t, const double wi[3], const double u[2],
                       double wo[3], double *pdf, double value[3])
{
    double pt[2], s[2], um[2], p_l, p_v;
    incident in;
    if (t->extended)
        return ll_measured_lobes_sample(t, wi, u, wo, pdf, value);
    no_direction(wo, pdf, value);
    if (!(wi[2] > 0.0))
        return 0;
    incident_of(t, wi, 1, &in);
    pt[0] = u[1]; /* as in ll_measured_draw_begin */
    pt[1] = u[0];
    ll_warp2d_sample_at(&t->luminance, &in.sl, pt, s, &p_l);
    /* The values are read at s after the vndf's sampling, which does not
     * depend on them: their fetch from memory runs meanwhile. */
    ll_warp2d_prefetch_nodes(&t->rgb, &in.sl, s);
    ll_warp2d_sample_at(&t->vndf, &in.sl, s, um, &p_v);
    return draw_tail(t, wi, &in, s, p_l, um, p_v, wo, pdf, value);
}

/* ------------------------------------------------ the layer convention */

/* The viewer at azimuth 0 (the files are isotropic): wi of the format is
 * our incident direction reversed, wo the outgoing one reversed, with the
 * azimuth phi_d measured from the mirror direction (ll_bsdf.h). A plain
 * file reflects from the top only; an extended one (tables_lobes.c) has
 * every pair of sides. */
static int covers(const ll_bsdf *b, double mu_i, double mu_o)
{
    if (b->measured->extended)
        return mu_i != 0.0 && mu_o != 0.0 && ll_is_finite(mu_i) && ll_is_finite(mu_o);
    return mu_i > 0.0 && mu_o < 0.0;
}

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
    if (!covers(b, mu_i, mu_o))
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
    if (!covers(b, mu_i, mu_o))
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
    if (!(b->measured->extended ? mu_i != 0.0 && ll_is_finite(mu_i) : mu_i > 0.0))
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
