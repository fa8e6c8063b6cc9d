/*
 * One transmitted lobe of an extended table file (tables_internal.h,
 * tables_refract.h), in the lobe's own frame (the fixed direction wi
 * above, wo below). Across a net interface whose lobe the refraction half
 * vector reaches (m->refract_eta > 0): as a reflected lobe (tables_eval.c)
 * with the refraction half vector in the place of the reflection's and the
 * refraction's change of variables (tables_refract.h) in the place of
 * 1 / (4 wi.m). Otherwise (the warp of the z-flipped direction, a pane's
 * or a lobe the refraction half vector does not reach) as a reflected
 * lobe of wo with z negated. The stored values are f |cos theta_o|
 * 4 sigma(wi) / D(m) under the jacobian rule, as for reflection.
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
 *
 * A set of the z-flipped warp is read between elevations the same way,
 * except that wo turns at the rate of the refracted direction across a net
 * interface (turn_rate, at most MAX_TURN_RATE), and that
 * each elevation's values take D / (4 sigma) at their own turned pair
 * (own_factor). Read at the same sample node of both elevations, frosted
 * glass's transmission from below beyond the critical angle, where T falls
 * by a factor of about 1.25 per degree, was up to 1.4% off between
 * elevations 1.5 degrees apart.
 */
#include "reader/tables_internal.h"
#include "reader/tables_refract.h"

#include <math.h>

/* The largest rate at which a z-flipped set turns wo with wi (turn_rate),
 * chosen by measuring frosted glass's transmission from below
 * (docs/benchmarks.md, "Transmitted sets' warps"). */
#define MAX_TURN_RATE 1.5

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
 * rotations turning wi to each and wi turned (wi[k]), and the rotations
 * turning wo with it (ro[k]: turn_rate's share of r[k]). */
typedef struct elevations {
    size_t n;
    double theta[2], w[2], wi[2][3];
    turn r[2], ro[2];
    double phi; /* wi's azimuth, the turned wi's too (at the pole as well) */
} elevations;

/* The rate at which a set of the z-flipped warp turns wo with wi between
 * two elevations: that of the refracted direction, d theta_t / d theta_i
 * = cos theta_i / (eta' cos theta_t) by Snell's law (eta' the side's
 * relative index), at most MAX_TURN_RATE, and 1 (wo turned as wi is) where
 * nothing refracts or the set has no net interface. Seen from the rarer
 * side the transmitted lobe follows the refracted direction, which moves
 * by a third to two thirds of wi's step at eta 1.5: turned as wi, the lobe
 * read at the neighbouring elevation lay up to 0.6 of a step off its peak,
 * and frosted glass's transmission from above came out worse (99th
 * percentile of f) than read at the same sample node. Seen from the
 * denser side the refracted direction moves faster than wi (1.6 times at
 * 20 degrees, 2.4 times at 35 at eta 1.5) and without bound at the
 * critical angle: turned as wi, or at that full rate, the lobe's f
 * between elevations was further off than turned at a rate held to
 * MAX_TURN_RATE (docs/benchmarks.md, "Transmitted sets' warps"). Beyond
 * the critical angle the lobe is the light the compensation returns,
 * spread over the azimuths, which
 * wi's own turn follows (rate 1). A set of the refraction warp turns wo
 * as wi: that keeps wi.m and wo.m. */
static double turn_rate(const ll_measured *t, double theta)
{
    double e = t->side_eta, st, r;
    if (t->refract_eta > 0.0 || !(e > 0.0) || e == 1.0)
        return 1.0;
    st = sin(theta) / e;
    if (!(st < 1.0))
        return 1.0;
    r = cos(theta) / (e * sqrt(1.0 - st * st));
    return r < MAX_TURN_RATE ? r : MAX_TURN_RATE;
}

static void elevations_of(const ll_measured *t, const double wi[3], elevations *e)
{
    const double *v = t->vndf.param_values[1];
    double theta = ll_tables_elevation(wi), f, rr = sqrt(wi[0] * wi[0] + wi[1] * wi[1]);
    double phi = atan2(wi[1], wi[0]);
    /* At the pole the turn goes towards the azimuth atan2 gives, which
     * the normals' coordinates are read against. */
    double cp = rr > 0.0 ? wi[0] / rr : cos(phi), sp = rr > 0.0 ? wi[1] / rr : sin(phi);
    double rate = turn_rate(t, theta);
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
        e->ro[k] = e->r[k];
        if (rate != 1.0) {
            e->ro[k].c = cos(rate * (e->theta[k] - theta));
            e->ro[k].s = sin(rate * (e->theta[k] - theta));
        }
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

/* Whether each elevation's stored values take D / (4 sigma) at their own
 * turned pair (the z-flipped warp) rather than the blend at the pair
 * itself (the refraction warp). A turn moves the flipped half vector over
 * the normals (it keeps neither wi.m nor wo.m), and that warp's D is
 * narrow (the straight-through lobe narrowed by the refraction: alpha
 * 0.05-0.1), so the stored remainder is smooth only about each
 * elevation's own normal (with D at the pair, frosted glass's
 * transmission from above was 4.2% off at the 99th percentile of f, 3.7%
 * so, at 64 x 96^2 x 96^2). */
static int own_factor(const ll_measured *t)
{
    return !(t->refract_eta > 0.0);
}

/* The factor of the stored values read at one elevation theta_i. */
static double own_scale(const ll_measured *t, const double um[2], double theta_i, double phi_i)
{
    return own_factor(t) ? jacobian_rule(t, um, theta_i, phi_i) : 1.0;
}

/* pdf of wo from the densities over the two squares: per unit area of the
 * normal's square (2 pi^2 u_theta sin theta_m per steradian), times the
 * warp's d omega_m / d omega_o (dir_jacobian). */
static double refracted_pdf(double p_v, double p_l, double u_theta_m, double theta_m,
                            double jac)
{
    double pdf = p_v * p_l / ll_measured_normal_area(u_theta_m, theta_m) * jac;
    return ll_is_finite(pdf) && pdf > 0.0 ? pdf : 0.0;
}

/* The set's half vector of the pair (wi above, wo below) and 1, or 0 if
 * the pair is not one of its lobe: the refraction half vector, or for the
 * warp of the z-flipped direction the reflection half vector of wi and wo
 * with z negated. */
static int pair_half(const ll_measured *t, const double wi[3], const double wo[3], double m[3])
{
    double len;
    if (t->refract_eta > 0.0)
        return ll_tables_refract_half(wi, wo, t->refract_eta, m);
    if (!(wi[2] > 0.0 && wo[2] < 0.0))
        return 0;
    m[0] = wi[0] + wo[0];
    m[1] = wi[1] + wo[1];
    m[2] = wi[2] - wo[2];
    len = sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
    m[0] /= len;
    m[1] /= len;
    m[2] /= len;
    return 1;
}

/* d omega_m / d omega_o of the set's warp at the pair and its half vector
 * m: the refraction's, or the reflection's 1 / (4 wi.m) (negating z keeps
 * solid angle). */
static double dir_jacobian(const ll_measured *t, const double wi[3], const double wo[3],
                           const double m[3])
{
    double c;
    if (t->refract_eta > 0.0)
        return ll_tables_refract_jacobian(wi, wo, m, t->refract_eta);
    c = wi[0] * m[0] + wi[1] * m[1] + wi[2] * m[2];
    return c > 0.0 ? 1.0 / (4.0 * c) : 0.0;
}

/* At one of the file's elevations theta_i (wi's own): the stored values
 * of the pair (as they are, without the factors the reader multiplies
 * them by) and, if pdf is given, the elevation's sampling density; 0 if
 * the pair is not one of the set's lobe. */
static int stored_at(const ll_measured *t, const double wi[3], double theta_i, double phi_i,
                     const double wo[3], double value[3], double *pdf)
{
    double m[3], um[2], s[2], theta_m, p_v;
    ll_warp_slices sl;
    if (!pair_half(t, wi, wo, m))
        return 0;
    incident(t, theta_i, phi_i, &sl);
    normal_coords(m, phi_i, um, &theta_m);
    ll_warp2d_invert_at(&t->vndf, &sl, um, s, &p_v);
    if (value)
        ll_measured_values_at(t, &sl, s, own_scale(t, um, theta_i, phi_i), value);
    if (pdf)
        *pdf = refracted_pdf(p_v, ll_warp2d_eval_at(&t->luminance, &sl, s), um[0], theta_m,
                             dir_jacobian(t, wi, wo, m));
    return 1;
}

/* The sampler of one of the file's elevations theta_i (wi's own): wo,
 * the stored values there and the elevation's density (stored_at's, to
 * rounding, without its inversion of the warp); 0 if the sample gives no
 * direction of the lobe. */
static int sample_at(const ll_measured *t, const double wi[3], double theta_i, double phi_i,
                     const double u[2], double wo[3], double value[3], double *pdf)
{
    double pt[2], s[2], um[2], p_l, p_v, theta_m, m[3], c;
    ll_warp_slices sl;
    incident(t, theta_i, phi_i, &sl);
    /* u[1] drives the warps' x, as for reflection (tables_eval.c). */
    pt[0] = u[1];
    pt[1] = u[0];
    ll_warp2d_sample_at(&t->luminance, &sl, pt, s, &p_l);
    ll_warp2d_prefetch_nodes(&t->rgb, &sl, s);
    ll_warp2d_sample_at(&t->vndf, &sl, s, um, &p_v);
    if (t->refract_eta > 0.0) {
        c = ll_tables_refract(wi, um, phi_i, t->refract_eta, &theta_m, m, wo);
    } else {
        /* Reflected about m, then z negated. */
        c = ll_tables_mirror(wi, um, phi_i, &theta_m, m, wo);
        if (!(wo[2] > 0.0))
            return 0;
        wo[2] = -wo[2];
    }
    if (!(c > 0.0) || !(wo[2] < 0.0))
        return 0;
    *pdf = refracted_pdf(p_v, p_l, um[0], theta_m, dir_jacobian(t, wi, wo, m));
    ll_measured_values_at(t, &sl, s, own_scale(t, um, theta_i, phi_i), value);
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
        turn_apply(&e->ro[k], 1.0, wo, o);
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
    k_factor = own_factor(t) ? 1.0 : jacobian_rule(t, um, ll_tables_elevation(wi), e->phi);
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
    if (!pair_half(t, wi, wo, m))
        return;
    elevations_of(t, wi, &e);
    blend(t, wi, &e, wo, m, e.n, value, NULL);
}

double ll_measured_refract_pdf(const ll_measured *t, const double wi[3], const double wo[3])
{
    elevations e;
    double m[3], pdf = 0.0;
    if (!pair_half(t, wi, wo, m))
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
        turn_apply(&e.ro[k], -1.0, o, wo);
        if (pair_half(t, wi, wo, m)) {
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
