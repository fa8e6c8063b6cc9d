/*
 * The renderer convention (ll_bsdf.h): directions in the local shading
 * frame, both pointing away from the surface, wo to the viewer and wi to
 * the light, as pbrt-v3's BxDF interface. These calls map the directions to
 * the file's axes exactly as pbrt-v3's FourierBSDF does,
 *     file incident  mu_i = CosTheta(wo)     (pbrt's muO),
 *     file outgoing  mu_o = CosTheta(-wi)    (pbrt's muI),
 *     cos(phi_d)     = CosDPhi(-wi, wo),
 * evaluate there, and scale f by 1 / |mu_o| (the stored series is
 * f * |mu_o|) and, for radiance transport through the interface, eta^2.
 */
#include "reader/bsdf_dir.h"
#include "reader/bsdf_internal.h"
#include "reader/tables_internal.h"

#include <math.h>

static double clamp_unit(double x) { return x > 1.0 ? 1.0 : (x < -1.0 ? -1.0 : x); }

/* Map (wo, wi) to the file's (mu_i, mu_o, cos phi_d). The vectors need not
 * be normalised. 0 if either is zero or not finite. */
static int to_file_axes(const double wo[3], const double wi[3], double *mu_i, double *mu_o,
                        double *cos_phi)
{
    double lo = ll_bsdf_dir_length(wo), li = ll_bsdf_dir_length(wi);
    double xy_o = wo[0] * wo[0] + wo[1] * wo[1], xy_i = wi[0] * wi[0] + wi[1] * wi[1];
    if (!(lo > 0.0) || !(li > 0.0))
        return 0;
    *mu_i = clamp_unit(wo[2] / lo);
    *mu_o = clamp_unit(-wi[2] / li);
    /* pbrt-v3's CosDPhi(-wi, wo): 1 when either has no azimuth. */
    if (xy_o == 0.0 || xy_i == 0.0)
        *cos_phi = 1.0;
    else
        *cos_phi = clamp_unit(-(wi[0] * wo[0] + wi[1] * wo[1]) / sqrt(xy_o * xy_i));
    return 1;
}

static ll_status check_mode(ll_transport mode, const char *fn)
{
    if (mode != LL_TRANSPORT_RADIANCE && mode != LL_TRANSPORT_IMPORTANCE)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: transport mode %d is neither "
                       "LL_TRANSPORT_RADIANCE nor LL_TRANSPORT_IMPORTANCE", fn, (int)mode);
    return LL_OK;
}

ll_status ll_bsdf_eval_dir(const ll_bsdf *b, const double wo[3], const double wi[3],
                           ll_transport mode, const float *basis_coeffs, double rgb[3])
{
    const float *basis;
    double mu_i, mu_o, cos_phi;
    ll_status s;
    if (!b || !wo || !wi || !rgb)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_bsdf_eval_dir: a required pointer is NULL");
    rgb[0] = rgb[1] = rgb[2] = 0.0;
    if ((s = check_mode(mode, "ll_bsdf_eval_dir")) != LL_OK ||
        (s = ll_bsdf_check_basis(b, basis_coeffs, "ll_bsdf_eval_dir", &basis)) != LL_OK)
        return s;
    if (b->measured) {
        /* ll_bsdf_unit_pair refuses what to_file_axes refuses. */
        double v[3], l[3], value[3];
        if (!ll_bsdf_unit_pair(wo, wi, v, l))
            return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                           "ll_bsdf_eval_dir: wo and wi must be finite and non-zero");
        /* The bases blended with their weights; a transmitted value is
         * stored as the .bsdf stores it: radiance takes the same eta^2. */
        ll_measured_blend_eval(b, v, l, basis, value);
        ll_bsdf_measured_rgb(value, l[2], ll_bsdf_transport_scale(b, v[2], -l[2], mode), rgb);
        return LL_OK;
    }
    if (!to_file_axes(wo, wi, &mu_i, &mu_o, &cos_phi))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_bsdf_eval_dir: wo and wi must be finite and non-zero");
    ll_bsdf_eval_cos(b, mu_i, mu_o, cos_phi, basis, ll_bsdf_transport_scale(b, mu_i, mu_o, mode),
                     rgb);
    return LL_OK;
}

ll_status ll_bsdf_pdf_dir(const ll_bsdf *b, const double wo[3], const double wi[3],
                          const float *basis_coeffs, double *pdf)
{
    const float *basis;
    double mu_i, mu_o, cos_phi;
    ll_status s;
    if (!b || !wo || !wi || !pdf)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_bsdf_pdf_dir: a required pointer is NULL");
    *pdf = 0.0;
    if ((s = ll_bsdf_check_basis(b, basis_coeffs, "ll_bsdf_pdf_dir", &basis)) != LL_OK)
        return s;
    if (b->measured) {
        double v[3], l[3];
        if (!ll_bsdf_unit_pair(wo, wi, v, l))
            return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                           "ll_bsdf_pdf_dir: wo and wi must be finite and non-zero");
        *pdf = ll_measured_blend_pdf(b, v, l, basis);
        return LL_OK;
    }
    if (!to_file_axes(wo, wi, &mu_i, &mu_o, &cos_phi))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_bsdf_pdf_dir: wo and wi must be finite and non-zero");
    *pdf = ll_bsdf_pdf_cos(b, mu_i, mu_o, cos_phi, basis);
    return LL_OK;
}

ll_status ll_bsdf_sample_dir(const ll_bsdf *b, const double wo[3], const double u[2],
                             ll_transport mode, const float *basis_coeffs, double wi[3],
                             double *pdf, double rgb[3])
{
    const float *basis;
    double lo, mu_i, mu_o, phi, sums[3], sin_o, cx, cy, sin_i, len;
    ll_status s;
    if (!b || !wo || !u || !wi || !pdf || !rgb)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_bsdf_sample_dir: a required pointer is NULL");
    *pdf = 0.0;
    rgb[0] = rgb[1] = rgb[2] = 0.0;
    wi[0] = wi[1] = 0.0;
    wi[2] = 1.0;
    if ((s = check_mode(mode, "ll_bsdf_sample_dir")) != LL_OK ||
        (s = ll_bsdf_check_basis(b, basis_coeffs, "ll_bsdf_sample_dir", &basis)) != LL_OK)
        return s;
    lo = ll_bsdf_dir_length(wo);
    if (!(lo > 0.0) || !(u[0] >= 0.0 && u[0] <= 1.0) || !(u[1] >= 0.0 && u[1] <= 1.0))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_bsdf_sample_dir: wo must be finite and non-zero and u = (%g, %g) "
                       "in [0, 1]",
                       u[0], u[1]);
    if (b->measured) {
        double v[3], value[3];
        int k;
        for (k = 0; k < 3; ++k)
            v[k] = lo == 1.0 ? wo[k] : wo[k] / lo; /* as ll_bsdf_unit_pair */
        if (ll_measured_blend_sample(b, v, u, basis, wi, pdf, value))
            ll_bsdf_measured_rgb(value, wi[2], ll_bsdf_transport_scale(b, v[2], -wi[2], mode), rgb);
        return LL_OK;
    }
    mu_i = clamp_unit(wo[2] / lo);
    if (!ll_bsdf_sample_core(b, mu_i, u, basis, &mu_o, &phi, pdf, sums))
        return LL_OK;

    /* wi = -(R(phi) applied to wo's azimuth, sin theta; mu_o), pbrt-v3's
     * construction, with wo's azimuth taken along x when wo is the normal
     * (pbrt-v3 would divide by sin theta_o = 0 there), so that wi is a unit
     * vector whatever wo is; the final normalisation only removes rounding. */
    sin_o = sqrt(wo[0] * wo[0] + wo[1] * wo[1]);
    if (sin_o > 0.0) {
        cx = wo[0] / sin_o;
        cy = wo[1] / sin_o;
    } else {
        cx = 1.0;
        cy = 0.0;
    }
    sin_i = 1.0 - mu_o * mu_o;
    sin_i = sin_i > 0.0 ? sqrt(sin_i) : 0.0;
    wi[0] = -sin_i * (cos(phi) * cx - sin(phi) * cy);
    wi[1] = -sin_i * (sin(phi) * cx + cos(phi) * cy);
    wi[2] = -mu_o;
    len = sqrt(wi[0] * wi[0] + wi[1] * wi[1] + wi[2] * wi[2]);
    wi[0] /= len;
    wi[1] /= len;
    wi[2] /= len;
    ll_bsdf_to_rgb(b, sums,
                   ll_bsdf_transport_scale(b, mu_i, mu_o, mode) * ll_bsdf_cosine_scale(mu_o),
                   rgb);
    return LL_OK;
}
