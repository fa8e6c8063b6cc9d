/*
 * The GGX (Trowbridge-Reitz) distribution's part of the rough interface
 * (words/microfacet_ggx_pair.c): its Smith shadowing term and the cosine series of
 * its peak factor, for one pair of zenith cosines.
 *
 * For GGX, D = 1 / (pi alpha^2 cos^4(theta_h) (1 + X)^2) with X =
 * tan^2(theta_h) / alpha^2 = X_0 + B v, v = 1 - cos phi (B, X_0 >= 0 from
 * the pair's half-vector geometry, as for Beckmann, where D holds exp(-X)
 * instead). So
 *     (1 + X)^-2 = (1 + X_0)^-2 E_beta(v),  E_beta(v) = (1 + beta v)^-2,
 *     beta = B / (1 + X_0),
 * a one-parameter peak of width ~ beta^-1/2 in phi whose tails fall only
 * like phi^-4. E_beta = (c - d cos phi)^-2 with c = 1 + beta, d = beta, and
 * its cosine series is known in closed form: with s = sqrt(c^2 - d^2) and
 * the Poisson-kernel ratio r = (c - s) / d = d / (c + s),
 *     E_beta = sum over all integers k of e_k e^(i k phi),
 *     e_k = r^|k| (c + |k| s) / s^3
 * (the derivative in c of 1 / (c - d cos phi) = sum r^|k| e^(i k phi) / s).
 *
 * The method. The rest of the BSDF, g (Fresnel, shadowing, Jacobian,
 * |H|^4 of D), is a smooth function of t = wi . wo, which is linear in
 * cos phi. It is replaced by its interpolant p, a polynomial of degree
 * LL_GGX_CHEB - 1 in cos phi through the Chebyshev points of cos phi on
 * the whole circle. Written in cosines, p = sum_j b_j cos(j phi), and the
 * series of E_beta p is the exact discrete convolution of the two:
 * nothing is truncated or fitted but g. The error of f is at most
 * |g - p| E_beta, so relative to the peak it is the interpolation error of
 * g (which converges geometrically while g's nearest branch point stays
 * away from the circle); the kinks and the near branch points take the
 * Filon path of words/microfacet_filon.c instead, as for Beckmann.
 */
#ifndef LL_MICROFACET_GGX_H
#define LL_MICROFACET_GGX_H

#include <stddef.h>
#include "support/support.h"

/* Chebyshev points of g on the whole circle. */
#define LL_GGX_CHEB 16

/* The sampling and the transform from samples to cosine coefficients. */
typedef struct ll_ggx_basis {
    double cos_phi[LL_GGX_CHEB];                 /* the samples' cos phi      */
    double to_cosine[LL_GGX_CHEB][LL_GGX_CHEB];  /* b_j = sum_i [j][i] g_i    */
} ll_ggx_basis;

LL_INTERNAL void ll_ggx_basis_init(ll_ggx_basis *basis);

/* The exact Smith G1 of GGX for a direction with |tan theta| = tan_theta:
 * 2 / (1 + sqrt(1 + alpha^2 tan^2 theta)). */
LL_INTERNAL double ll_ggx_smith_g1(double tan_theta, double alpha);

/* The mean of E_beta over phi (its order 0): c / s^3. */
LL_INTERNAL double ll_ggx_peak_mean(double beta);

/* The terms that E_beta's cosine series needs until they fall below
 * relerr times the first, at most cap (>= 1). */
LL_INTERNAL size_t ll_ggx_peak_length(double beta, double relerr, size_t cap);

/* ll_ggx_peak_length prepared once for every cap up to a largest one: a
 * pair asks its peak's length at several caps (its orders, its Filon
 * blocks, its closed-form part), and each answer would cost the same
 * logarithms and exponentials again. ll_ggx_length_at gives exactly what
 * ll_ggx_peak_length(beta, relerr, cap) does. */
typedef struct ll_ggx_length {
    double beta, relerr;
    size_t max_cap; /* the caps answered from the fields below          */
    int one;        /* the first term is already below relerr: length 1 */
    double x;       /* Newton's root (the caps at or below it answer    */
                    /* themselves)                                      */
    size_t walked;  /* the length for max_cap, where x < max_cap        */
} ll_ggx_length;

LL_INTERNAL void ll_ggx_length_prepare(double beta, double relerr, size_t max_cap,
                                       ll_ggx_length *len);
LL_INTERNAL size_t ll_ggx_length_at(const ll_ggx_length *len, size_t cap);

/* The largest beta whose series n_orders terms hold at relative error
 * relerr (the term of order n_orders below relerr times the first):
 * sharper lobes are widened. */
LL_INTERNAL double ll_ggx_max_beta(size_t n_orders, double relerr);

/* The cosine series (out[0] the mean, out[l] = 2/pi integral_0^pi ... cos
 * l phi) of E_beta p, l < n_out, where p interpolates the samples g at
 * basis->cos_phi; scratch holds n_out + 2 LL_GGX_CHEB doubles. */
LL_INTERNAL void ll_ggx_series(const ll_ggx_basis *basis, double beta, const double *g,
                               size_t n_out, double *out, double *scratch);

/* The cosine series of E_beta q, l < n_out, for the quadratic q = q[0] +
 * q[1] v + q[2] v^2 in v = 1 - cos phi (the part of a peak that the Filon
 * path takes in closed form, words/microfacet_filon.c); scratch holds
 * n_out + 3 doubles. */
LL_INTERNAL void ll_ggx_series_quadratic(double beta, const double *q, size_t n_out,
                                         double *out, double *scratch);

#endif /* LL_MICROFACET_GGX_H */
