/*
 * The lobes of an extended table file (tables_internal.h): a direction
 * pair goes to the set of its lobe -- reflection or transmission, by the
 * side of the fixed direction wi -- in that set's own frame, where wi lies
 * above: a set of the bottom side sees both directions with z negated.
 *
 * Transmitted lobes. Across a net interface (file eta != 1) the set is
 * warped about the refraction half vector (tables_refract.c). Where the
 * stack has none (eta 1: a pane, glass between air and air) there is no
 * refraction half vector: wi + wo vanishes at the straight-through
 * direction wo = -wi, which is the lobe's peak. Negating wo's z turns that
 * peak into wi's mirror direction, and the transmitted lobe of a pane
 * (two rough interfaces whose deviations largely cancel) into a lobe about
 * it like a reflected one, so such a set is a reflection set of the
 * z-flipped direction and reuses its warp. Both kinds of transmitted set
 * are read between two incident elevations at the pair turned with wi to
 * each (tables_refract.c).
 *
 * A reflected set with a "fresnel_eta" (one seen from the denser side)
 * holds its values over the Fresnel reflectance at its half vector, which
 * is multiplied back here: f over F is smooth across the edge of total
 * internal reflection, which F restores exactly. With a "fresnel_floor" k
 * the values are over (F + q) / (1 + q) instead, q = k D(0) / D(m) by the
 * set's own D (a coat's set, where much of f does not follow F:
 * tables_refract.h, bsdf_write_tables_lobes.c). A refracted set with a
 * "transmittance_eta" holds its values over the Fresnel transmittance
 * times the refraction's d omega_m / d omega_o (tables_refract.h), both
 * of which vanish at the edge of total internal reflection seen from the
 * denser side; the refraction's evaluation and sampler multiply them back
 * (tables_refract.c).
 *
 * Sampling picks the reflected or the transmitted lobe of wi's side in
 * proportion to their luminance albedos at wi's elevation (stored per
 * incident elevation, interpolated linearly as the slices are), reusing
 * u[0] rescaled into the chosen share; the pdf is the share times the
 * lobe's.
 */
#include "reader/tables_internal.h"
#include "reader/tables_refract.h"

#include <math.h>

static const char *const prefixes[LL_MEASURED_LOBES] = {
    "reflect_top.", "reflect_bottom.", "transmit_top.", "transmit_bottom."
};

const char *ll_measured_lobe_prefix(int lobe)
{
    return lobe >= 0 && lobe < LL_MEASURED_LOBES ? prefixes[lobe] : "";
}

static void flip(const double in[3], double out[3])
{
    out[0] = in[0];
    out[1] = in[1];
    out[2] = -in[2];
}

/* in as seen from the side below the surface (bottom: z negated), or as
 * it is. */
static void to_side(int bottom, const double in[3], double out[3])
{
    if (bottom)
        flip(in, out);
    else {
        out[0] = in[0];
        out[1] = in[1];
        out[2] = in[2];
    }
}

/* A reflected set stored over the Fresnel reflectance of its half vector
 * (a set seen from the denser side, whose reflection has the edge of total
 * internal reflection: f over F is smooth across it, so the tables need
 * not resolve the edge, which F puts back exactly): the value times F, or
 * with the set's floor k times (F + q) / (1 + q), q = k D(0) / D(m). */
static void fresnel(const ll_measured *set, const double wi[3], const double wo[3],
                    double value[3])
{
    double k;
    if (!(set->fresnel_eta > 0.0))
        return;
    k = ll_tables_fresnel_floor_pair(wi, wo, set->fresnel_eta, set->fresnel_floor, &set->ndf);
    value[0] *= k;
    value[1] *= k;
    value[2] *= k;
}

/* The set's value at (wi, wo) in its frame (wi above). */
static void lobe_eval(const ll_measured *set, int transmit, const double wi[3],
                      const double wo[3], double value[3])
{
    if (!transmit) {
        ll_measured_eval(set, wi, wo, value);
        fresnel(set, wi, wo, value);
    } else {
        ll_measured_refract_eval(set, wi, wo, value);
    }
}

static double lobe_pdf(const ll_measured *set, int transmit, const double wi[3],
                       const double wo[3])
{
    if (!transmit)
        return ll_measured_pdf(set, wi, wo);
    return ll_measured_refract_pdf(set, wi, wo);
}

/* The set's luminance albedo at wi's elevation, interpolated as the
 * set's slices are. */
static double weight_at(const ll_measured *set, const double wi[3])
{
    size_t lo;
    double t;
    if (!set)
        return 0.0;
    ll_warp_locate(set->vndf.param_values[1], set->vndf.param_size[1],
                   acos(wi[2] > 1.0 ? 1.0 : wi[2]), &lo, &t);
    return t == 0.0 ? set->weight[lo] : (1.0 - t) * set->weight[lo] + t * set->weight[lo + 1];
}

/* wi in the frame of its side's sets, and the sets. 0 if wi lies in the
 * surface. */
static int side_of(const ll_measured *m, const double wi[3], double w[3],
                   const ll_measured **reflect, const ll_measured **transmit)
{
    int bottom = wi[2] < 0.0;
    if (wi[2] == 0.0)
        return 0;
    to_side(bottom, wi, w);
    *reflect = m->lobe[bottom ? LL_LOBE_REFLECT_BOTTOM : LL_LOBE_REFLECT_TOP];
    *transmit = m->lobe[bottom ? LL_LOBE_TRANSMIT_BOTTOM : LL_LOBE_TRANSMIT_TOP];
    return bottom ? -1 : 1;
}

/* wi and wo in the frame of wi's side, that side's sets, and whether the
 * pair transmits. 0 if either lies in the surface. */
static int pair_of(const ll_measured *m, const double wi[3], const double wo[3], double w[3],
                   double o[3], const ll_measured **reflect, const ll_measured **transmit,
                   int *transmits)
{
    int side = side_of(m, wi, w, reflect, transmit);
    if (!side || wo[2] == 0.0)
        return 0;
    *transmits = wi[2] * wo[2] < 0.0;
    to_side(side < 0, wo, o);
    return 1;
}

/* The share of the reflected lobe in sampling at w (its frame). */
static double reflect_share(const ll_measured *r, const ll_measured *t, const double w[3])
{
    double a = weight_at(r, w), b = weight_at(t, w);
    if (!(a > 0.0) && !(b > 0.0))
        return r ? 1.0 : 0.0;
    return a / (a + b);
}

void ll_measured_lobes_eval(const ll_measured *m, const double wi[3], const double wo[3],
                            double value[3])
{
    const ll_measured *r, *t;
    double w[3], o[3];
    int transmit;
    value[0] = value[1] = value[2] = 0.0;
    if (!pair_of(m, wi, wo, w, o, &r, &t, &transmit))
        return;
    if (transmit ? t != NULL : r != NULL)
        lobe_eval(transmit ? t : r, transmit, w, o, value);
}

double ll_measured_lobes_pdf(const ll_measured *m, const double wi[3], const double wo[3])
{
    const ll_measured *r, *t;
    double w[3], o[3], share;
    int transmit;
    if (!pair_of(m, wi, wo, w, o, &r, &t, &transmit))
        return 0.0;
    share = reflect_share(r, t, w);
    if (transmit)
        return t && share < 1.0 ? (1.0 - share) * lobe_pdf(t, 1, w, o) : 0.0;
    return r && share > 0.0 ? share * lobe_pdf(r, 0, w, o) : 0.0;
}

int ll_measured_lobes_sample(const ll_measured *m, const double wi[3], const double u[2],
                             double wo[3], double *pdf, double value[3])
{
    const ll_measured *r, *t;
    double w[3], v[2], share;
    int side = side_of(m, wi, w, &r, &t), transmit, ok;
    wo[0] = wo[1] = 0.0;
    wo[2] = 1.0;
    *pdf = 0.0;
    value[0] = value[1] = value[2] = 0.0;
    if (!side)
        return 0;
    share = reflect_share(r, t, w);
    transmit = !(u[0] < share);
    v[0] = transmit ? (u[0] - share) / (1.0 - share) : u[0] / share;
    v[0] = v[0] < 0.0 ? 0.0 : (v[0] > 1.0 ? 1.0 : v[0]);
    v[1] = u[1];
    if (transmit ? !t : !r)
        return 0;
    if (!transmit) {
        ok = ll_measured_sample(r, w, v, wo, pdf, value);
        if (ok)
            fresnel(r, w, wo, value);
    } else {
        ok = ll_measured_refract_sample(t, w, v, wo, pdf, value);
    }
    if (!ok) {
        wo[0] = wo[1] = 0.0;
        wo[2] = 1.0;
        *pdf = 0.0;
        return 0;
    }
    *pdf *= transmit ? 1.0 - share : share;
    if (side < 0)
        wo[2] = -wo[2];
    return *pdf > 0.0;
}
