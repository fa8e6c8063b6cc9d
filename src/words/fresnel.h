/*
 * Fresnel reflectance kernels, shared by the public functions (fresnel.c)
 * and the inner loops of the rough interfaces (microfacet_plan.c), which call
 * them for every azimuth sample and want them inlined. No argument checks
 * here: the callers have checked.
 */
#ifndef LL_FRESNEL_H
#define LL_FRESNEL_H

#include <math.h>

/* Unpolarised reflectance of a smooth dielectric boundary, relative index
 * eta != 1 (transmitted side / incident side) and inv_eta = 1 / eta, for
 * cos_i > 0; cos_i <= 0 is light from the other side, where the relative
 * index is 1/eta. *cos_t gets the refracted cosine with the sign opposite
 * to cos_i (0 under total internal reflection). The s and p amplitudes of
 * Born and Wolf section 1.5.2. (An inner loop computes inv_eta once per
 * pair: the doubles are those of ll_fresnel_dielectric_kernel.) */
static inline double ll_fresnel_dielectric_inv(double cos_i, double eta, double inv_eta,
                                               double *cos_t)
{
    double scale, cos_t2, ci, ct, rs, rp;
    /* Snell: sin_t = sin_i / eta_rel, with eta_rel = eta from this side. */
    scale = cos_i > 0.0 ? inv_eta : eta;
    cos_t2 = 1.0 - (1.0 - cos_i * cos_i) * (scale * scale);
    if (cos_t2 <= 0.0) {
        *cos_t = 0.0;
        return 1.0;
    }
    ci = fabs(cos_i);
    ct = sqrt(cos_t2);
    /* Written with eta rather than eta_rel: from the other side s and p
     * swap, which leaves the unpolarised average unchanged. */
    rs = (ci - eta * ct) / (ci + eta * ct);
    rp = (eta * ci - ct) / (eta * ci + ct);
    *cos_t = cos_i > 0.0 ? -ct : ct;
    return 0.5 * (rs * rs + rp * rp);
}

/* The same for any eta (eta = 1: no boundary, nothing reflected). */
static inline double ll_fresnel_dielectric_kernel(double cos_i, double eta, double *cos_t)
{
    if (eta == 1.0) {
        *cos_t = -cos_i;
        return 0.0;
    }
    return ll_fresnel_dielectric_inv(cos_i, eta, 1.0 / eta, cos_t);
}

/* Unpolarised reflectance for a complex relative index eta_re + i eta_im
 * (eta_im = 0 is a dielectric, including total internal reflection for
 * eta_re < 1), cos_i in [0, 1]; the closed form of K. D. Moeller, "Optics"
 * (1988), with a^2 + b^2 = |eta^2 - sin^2|. */
static inline double ll_fresnel_conductor_kernel(double cos_i, double eta_re, double eta_im)
{
    double c2 = cos_i * cos_i, s2 = 1.0 - c2, s4 = s2 * s2;
    double t1 = eta_re * eta_re - eta_im * eta_im - s2;
    double a2pb2 = sqrt(t1 * t1 + 4.0 * eta_im * eta_im * eta_re * eta_re);
    double a = sqrt(fmax(0.0, 0.5 * (a2pb2 + t1)));
    double term1 = a2pb2 + c2, term2 = 2.0 * a * cos_i;
    double rs2 = (term1 - term2) / (term1 + term2);
    double term3 = a2pb2 * c2 + s4, term4 = term2 * s2;
    double rp2 = rs2 * (term3 - term4) / (term3 + term4);
    return 0.5 * (rp2 + rs2);
}

#endif /* LL_FRESNEL_H */
