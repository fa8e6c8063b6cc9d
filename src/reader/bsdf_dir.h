/*
 * The renderer convention's small pieces (reader/bsdf_dir.c), shared with
 * the batch pipeline of table files (reader/tables_batch.c) so that both
 * do the same arithmetic: a batch element is bit for bit its scalar call.
 */
#ifndef LL_READER_BSDF_DIR_H
#define LL_READER_BSDF_DIR_H

#include "reader/bsdf_internal.h"

#include <math.h>

/* A direction's length, or 0 if it is not a usable (finite, non-zero) one.
 * Unit vectors (what renderers pass) skip the square root: dividing by a
 * length within 1e-12 of 1 would change nothing that matters. */
static inline double ll_bsdf_dir_length(const double w[3])
{
    double len2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
    if (fabs(len2 - 1.0) <= 1e-12)
        return 1.0;
    if (!(len2 > 0.0) || !isfinite(len2))
        return 0.0;
    return sqrt(len2);
}

/* A table file (tables_internal.h) is evaluated on the directions
 * themselves, as the renderers' readers do: through (mu_i, mu_o, cos phi)
 * the azimuth's sine would come back as sqrt(1 - cos^2), which loses half
 * the digits next to the plane of incidence. wo and wi as units into v
 * and l (our wo, the viewer, is the format's wi); 0 if either direction
 * is not usable. */
static inline int ll_bsdf_unit_pair(const double wo[3], const double wi[3], double v[3],
                                    double l[3])
{
    double lo = ll_bsdf_dir_length(wo), li = ll_bsdf_dir_length(wi);
    int k;
    if (!(lo > 0.0) || !(li > 0.0))
        return 0;
    /* x / 1 is x: the division only for a direction that is not unit. */
    for (k = 0; k < 3; ++k) {
        v[k] = lo == 1.0 ? wo[k] : wo[k] / lo;
        l[k] = li == 1.0 ? wi[k] : wi[k] / li;
    }
    return 1;
}

/* pbrt-v3's FourierBSDF::f: in radiance mode, a transmitted value (mu_i and
 * mu_o of the same sign in the file's axes) is scaled by the square of the
 * relative index it crosses, 1 / eta going up through it (wi below the
 * surface) and eta going down (Veach's thesis, sec. 5.2). */
static inline double ll_bsdf_transport_scale(const ll_bsdf *b, double mu_i, double mu_o,
                                             ll_transport mode)
{
    double e;
    if (mode != LL_TRANSPORT_RADIANCE || !(mu_i * mu_o > 0.0))
        return 1.0;
    e = mu_o > 0.0 ? 1.0 / b->eta : b->eta;
    return e * e;
}

/* A table file's value times weight and the cosine factor of the light's
 * direction, as rgb (what is not a positive finite number: 0). C99's
 * isfinite in place, where support's ll_is_finite is a call: this runs on
 * every evaluation and sample. */
static inline void ll_bsdf_measured_rgb(const double value[3], double cos_light, double weight,
                                        double rgb[3])
{
    double scale = weight * ll_bsdf_cosine_scale(cos_light);
    int c;
    for (c = 0; c < 3; ++c) {
        rgb[c] = value[c] * scale;
        if (!(rgb[c] > 0.0) || !isfinite(rgb[c]))
            rgb[c] = 0.0;
    }
}

#endif
