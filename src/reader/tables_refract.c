/*
 * One transmitted lobe of an extended table file across a net interface
 * (tables_internal.h, tables_refract.h), in the lobe's own frame (the
 * fixed direction wi above, wo below, relative index m->refract_eta): as
 * a reflected lobe (tables_eval.c) with the refraction half vector in the
 * place of the reflection's and the refraction's change of variables
 * (tables_refract.h) in the place of 1 / (4 wi.m). The stored values are
 * f |cos theta_o| 4 sigma(wi) / D(m) under the jacobian rule, as for
 * reflection.
 *
 * Between two incident elevations of the file the stored values are not
 * read at the same sample node of both (as a reflected set and Mitsuba's
 * `measured` read them) but with the lobe turned with wi: the pair
 * (wi, wo) is rotated in wi's plane of incidence until wi lies at each of
 * the two elevations, that elevation's set is read there, and the two
 * stored values are blended with the elevations' weights; D / (4 sigma)
 * and the transmittance are then taken at the pair itself. The rotation
 * keeps wi.m and wo.m, so the edge of total internal reflection (seen from
 * the denser side, wi.m at a fixed cosine) lies at the same pairs at both
 * elevations. At the same node it moves over the normals between them:
 * beyond the critical angle the lobe is a narrow band of tilted normals by
 * that edge, and the blend there read one elevation beyond its edge (the
 * writer's continuation), which left T from below 0.7-1.5% low between
 * elevations at 42-60 degrees while within 0.2% at them. Sampling picks
 * one of the two elevations with its weight (u[0] rescaled), samples that
 * elevation's set and turns the direction back; the pdf is the mixture of
 * both elevations' densities, each at the pair turned to it (a rotation
 * keeps solid angle).
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

/* The slices of the incident direction at (phi_i, theta_i); theta_i is
 * one of the file's elevations, so that the slices are that elevation's
 * alone. */
static void incident(const ll_measured *t, double theta_i, double phi_i, ll_warp_slices *sl)
{
    double param[2];
    param[0] = phi_i;
    param[1] = theta_i;
    ll_warp2d_slices(&t->vndf, param, sl);
}

/* The rotation about the axis (ax, ay, 0) orthogonal to wi's plane of
 * incidence by the angle whose cosine and sine are c and s: the one that
 * takes wi's elevation to an elevation of the file. */
typedef struct turn {
    double ax, ay, c, s;
} turn;

static void turn_apply(const turn *r, double sign, const double v[3], double out[3])
{
    /* Rodrigues: v c + (a x v) s + a (a.v) (1 - c); sign -1 turns back. */
    double s = sign * r->s, k = (r->ax * v[0] + r->ay * v[1]) * (1.0 - r->c);
    out[0] = v[0] * r->c + r->ay * v[2] * s + r->ax * k;
    out[1] = v[1] * r->c - r->ax * v[2] * s + r->ay * k;
    out[2] = v[2] * r->c + (r->ax * v[1] - r->ay * v[0]) * s;
}

/* wi's elevation between the file's: at most two elevations theta[k]
 * with weights w[k] (linear in the elevation, as the slices are), the
 * rotations turning wi to each and wi turned (wi[k]). */
typedef struct elevations {
    size_t n;
    double theta[2], w[2], wi[2][3];
    turn r[2];
    double phi; /* wi's azimuth, the turned wi's too (at the pole as well) */
} elevations;

static void elevations_of(const ll_measured *t, const double wi[3], elevations *e)
{
    const double *v = t->vndf.param_values[1];
    double theta = ll_tables_elevation(wi), f, rr = sqrt(wi[0] * wi[0] + wi[1] * wi[1]);
    double phi = atan2(wi[1], wi[0]);
    /* At the pole the turn goes towards the azimuth atan2 gives, which
     * the normals' coordinates are read against. */
    double cp = rr > 0.0 ? wi[0] / rr : cos(phi), sp = rr > 0.0 ? wi[1] / rr : sin(phi);
    size_t lo, k;
    e->phi = phi;
    ll_warp_locate(v, t->vndf.param_size[1], theta, &lo, &f);
    if (!(f > 0.0)) {
        e->n = 1;
        e->theta[0] = v[lo];
        e->w[0] = 1.0;
    } else if (!(f < 1.0)) {
        e->n = 1;
        e->theta[0] = v[lo + 1];
        e->w[0] = 1.0;
    } else {
        e->n = 2;
        e->theta[0] = v[lo];
        e->theta[1] = v[lo + 1];
        e->w[0] = 1.0 - f;
        e->w[1] = f;
    }
    for (k = 0; k < e->n; ++k) {
        e->r[k].ax = -sp;
        e->r[k].ay = cp;
        e->r[k].c = cos(e->theta[k] - theta);
        e->r[k].s = sin(e->theta[k] - theta);
        turn_apply(&e->r[k], 1.0, wi, e->wi[k]);
    }
}

/* D(m) / (4 sigma(wi)) of the jacobian rule at wi's own elevation
 * theta_i (1 for a file without it); 0 if it is not finite. */
static double jacobian_rule(const ll_measured *t, const double um[2], double theta_i,
                            double phi_i)
{
    ll_warp_slices one;
    double uwi[2], r;
    if (!t->jacobian)
        return 1.0;
    uwi[0] = ll_tables_theta_to_u(theta_i);
    uwi[1] = ll_tables_phi_to_u(phi_i);
    ll_warp_slices_single(&one);
    r = ll_warp2d_eval_at(&t->ndf, &one, um) / (4.0 * ll_warp2d_eval_at(&t->sigma, &one, uwi));
    return ll_is_finite(r) ? r : 0.0;
}

/* pdf of wo from the densities over the two squares: per unit area of the
 * normal's square (2 pi^2 u_theta sin theta_m per steradian), times the
 * refraction's d omega_m / d omega_o. */
static double refracted_pdf(double p_v, double p_l, double u_theta_m, double theta_m,
                            double jac)
{
    double pdf = p_v * p_l / ll_measured_normal_area(u_theta_m, theta_m) * jac;
    return ll_is_finite(pdf) && pdf > 0.0 ? pdf : 0.0;
}

/* At one of the file's elevations theta_i (wi's own): the stored values
 * of the pair (as they are, without the factors the reader multiplies
 * them by) and, if pdf is given, the elevation's sampling density; 0 if
 * the pair is not one of a refraction. */
static int stored_at(const ll_measured *t, const double wi[3], double theta_i, double phi_i,
                     const double wo[3], double value[3], double *pdf)
{
    double m[3], um[2], s[2], theta_m, p_v;
    ll_warp_slices sl;
    if (!ll_tables_refract_half(wi, wo, t->refract_eta, m))
        return 0;
    incident(t, theta_i, phi_i, &sl);
    normal_coords(m, phi_i, um, &theta_m);
    ll_warp2d_invert_at(&t->vndf, &sl, um, s, &p_v);
    if (value)
        ll_measured_values_at(t, &sl, s, 1.0, value);
    if (pdf)
        *pdf = refracted_pdf(p_v, ll_warp2d_eval_at(&t->luminance, &sl, s), um[0], theta_m,
                             ll_tables_refract_jacobian(wi, wo, m, t->refract_eta));
    return 1;
}

/* The sampler of one of the file's elevations theta_i (wi's own): wo,
 * the stored values there and the elevation's density (stored_at's, to
 * rounding, without its inversion of the warp); 0 if the sample refracts
 * nothing. */
static int sample_at(const ll_measured *t, const double wi[3], double theta_i, double phi_i,
                     const double u[2], double wo[3], double value[3], double *pdf)
{
    double pt[2], s[2], um[2], p_l, p_v, theta_m, m[3];
    ll_warp_slices sl;
    incident(t, theta_i, phi_i, &sl);
    /* u[1] drives the warps' x, as for reflection (tables_eval.c). */
    pt[0] = u[1];
    pt[1] = u[0];
    ll_warp2d_sample_at(&t->luminance, &sl, pt, s, &p_l);
    ll_warp2d_prefetch_nodes(&t->rgb, &sl, s);
    ll_warp2d_sample_at(&t->vndf, &sl, s, um, &p_v);
    if (!(ll_tables_refract(wi, um, phi_i, t->refract_eta, &theta_m, m, wo) > 0.0) ||
        !(wo[2] < 0.0))
        return 0;
    *pdf = refracted_pdf(p_v, p_l, um[0], theta_m,
                         ll_tables_refract_jacobian(wi, wo, m, t->refract_eta));
    ll_measured_values_at(t, &sl, s, 1.0, value);
    return *pdf > 0.0;
}

/* The value (value non-NULL) and the sampler's density (pdf non-NULL) at
 * (wi, wo), wi above and wo below, m their refraction half vector, e wi's
 * elevations; elevation skip's weighted part is given in value and pdf
 * (the sampled elevation's), none if skip is e->n. The stored values
 * are blended over the pair turned to each elevation (an elevation where
 * the turned pair refracts nothing, wo turned past the horizon, adds
 * nothing: dividing by the weights of the others instead made the lobe's
 * last degrees by the horizon 1-3% too bright beyond 57 degrees), then
 * multiplied by D / (4 sigma) and the transmittance at the pair itself:
 * both are the lobe's steep factors (the falling tail of D that is all
 * the lobe holds beyond the critical angle, and the edge of total
 * internal reflection), which are exact so; the stored remainder is
 * smooth. The density is the mixture of the elevations' samplers. */
static void blend(const ll_measured *t, const double wi[3], const elevations *e,
                  const double wo[3], const double m[3], size_t skip, double value[3],
                  double *pdf)
{
    double sum[3] = { 0.0, 0.0, 0.0 }, um[2], theta_m, k_factor;
    int any = skip < e->n;
    size_t k;
    if (value && any) {
        sum[0] = value[0];
        sum[1] = value[1];
        sum[2] = value[2];
    }
    for (k = 0; k < e->n; ++k) {
        double o[3], v[3], p = 0.0;
        if (k == skip)
            continue;
        turn_apply(&e->r[k], 1.0, wo, o);
        if (!stored_at(t, e->wi[k], e->theta[k], e->phi, o, value ? v : NULL, pdf ? &p : NULL))
            continue;
        if (pdf)
            *pdf += e->w[k] * p;
        if (value) {
            sum[0] += e->w[k] * v[0];
            sum[1] += e->w[k] * v[1];
            sum[2] += e->w[k] * v[2];
            any = 1;
        }
    }
    if (pdf && !(ll_is_finite(*pdf) && *pdf > 0.0))
        *pdf = 0.0;
    if (!value)
        return;
    value[0] = value[1] = value[2] = 0.0;
    if (!any)
        return;
    normal_coords(m, e->phi, um, &theta_m);
    k_factor = jacobian_rule(t, um, ll_tables_elevation(wi), e->phi);
    if (t->transmittance_eta > 0.0)
        k_factor *= ll_tables_transmittance_at(wi, wo, m, t->transmittance_eta);
    for (k = 0; k < 3; ++k) {
        double x = sum[k] * k_factor;
        value[k] = ll_is_finite(x) && x > 0.0 ? x : 0.0;
    }
}

void ll_measured_refract_eval(const ll_measured *t, const double wi[3], const double wo[3],
                              double value[3])
{
    elevations e;
    double m[3];
    value[0] = value[1] = value[2] = 0.0;
    if (!ll_tables_refract_half(wi, wo, t->refract_eta, m))
        return;
    elevations_of(t, wi, &e);
    blend(t, wi, &e, wo, m, e.n, value, NULL);
}

double ll_measured_refract_pdf(const ll_measured *t, const double wi[3], const double wo[3])
{
    elevations e;
    double m[3], pdf = 0.0;
    if (!ll_tables_refract_half(wi, wo, t->refract_eta, m))
        return 0.0;
    elevations_of(t, wi, &e);
    blend(t, wi, &e, wo, m, e.n, NULL, &pdf);
    return pdf;
}

int ll_measured_refract_sample(const ll_measured *t, const double wi[3], const double u[2],
                               double wo[3], double *pdf, double value[3])
{
    elevations e;
    double v[2], o[3], m[3], p;
    size_t k;
    wo[0] = wo[1] = 0.0;
    wo[2] = 1.0;
    *pdf = 0.0;
    value[0] = value[1] = value[2] = 0.0;
    if (!(wi[2] > 0.0))
        return 0;
    elevations_of(t, wi, &e);
    k = e.n == 2 && !(u[0] < e.w[0]) ? 1 : 0;
    v[0] = k ? (u[0] - e.w[0]) / e.w[1] : u[0] / e.w[0];
    v[0] = v[0] < 0.0 ? 0.0 : (v[0] > 1.0 ? 1.0 : v[0]);
    v[1] = u[1];
    if (sample_at(t, e.wi[k], e.theta[k], e.phi, v, o, value, &p)) {
        turn_apply(&e.r[k], -1.0, o, wo);
        if (ll_tables_refract_half(wi, wo, t->refract_eta, m)) {
            value[0] *= e.w[k];
            value[1] *= e.w[k];
            value[2] *= e.w[k];
            *pdf = e.w[k] * p;
            blend(t, wi, &e, wo, m, k, value, pdf);
        }
    }
    if (!(*pdf > 0.0)) {
        wo[0] = wo[1] = 0.0;
        wo[2] = 1.0;
        *pdf = 0.0;
        value[0] = value[1] = value[2] = 0.0;
        return 0;
    }
    return 1;
}
