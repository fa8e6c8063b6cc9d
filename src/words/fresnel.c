/*
 * Fresnel reflectance of smooth boundaries (dielectric and conductor) and
 * its hemispherical averages, the public face of the kernels in fresnel.h.
 */
#include "words/fresnel.h"
#include "support/support.h"

#include "layerlab/ll_layer.h"

#include <math.h>

/* An invalid argument: LL_ERROR_INVALID_ARGUMENT with a message, and the
 * outputs 0 (set by the callers first). */
static ll_status invalid(const char *fn, const char *what, double value)
{
    return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: %s (got %g)", fn, what, value);
}

ll_status ll_fresnel_dielectric(double cos_theta_i, double eta, double *reflectance,
                                double *cos_theta_t)
{
    static const char fn[] = "ll_fresnel_dielectric";
    double unused;
    if (cos_theta_t)
        *cos_theta_t = 0.0;
    if (!reflectance)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: reflectance is NULL", fn);
    *reflectance = 0.0;
    if (!(cos_theta_i >= -1.0 && cos_theta_i <= 1.0))
        return invalid(fn, "cos_theta_i must be in [-1, 1]", cos_theta_i);
    if (!(eta > 0.0) || !ll_is_finite(eta))
        return invalid(fn, "eta must be positive and finite", eta);
    *reflectance =
        ll_fresnel_dielectric_kernel(cos_theta_i, eta, cos_theta_t ? cos_theta_t : &unused);
    return LL_OK;
}

static ll_status conductor_args(const char *fn, double eta_re, double eta_im)
{
    if (!(eta_re >= 0.0) || !ll_is_finite(eta_re))
        return invalid(fn, "eta_re must be finite and >= 0", eta_re);
    if (!(eta_im >= 0.0) || !ll_is_finite(eta_im))
        return invalid(fn, "eta_im must be finite and >= 0", eta_im);
    if (eta_re == 0.0 && eta_im == 0.0)
        return invalid(fn, "eta must not be 0", 0.0);
    return LL_OK;
}

ll_status ll_fresnel_conductor(double cos_theta_i, double eta_re, double eta_im,
                               double *reflectance)
{
    static const char fn[] = "ll_fresnel_conductor";
    ll_status s;
    if (!reflectance)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: reflectance is NULL", fn);
    *reflectance = 0.0;
    if (!(cos_theta_i >= 0.0 && cos_theta_i <= 1.0))
        return invalid(fn, "cos_theta_i must be in [0, 1]", cos_theta_i);
    s = conductor_args(fn, eta_re, eta_im);
    if (s == LL_OK)
        *reflectance = ll_fresnel_conductor_kernel(cos_theta_i, eta_re, eta_im);
    return s;
}

/* ------------------------------------------------------------ averages
 * 2 * integral_a^b F(mu) mu dmu by tanh-sinh quadrature (Takahasi and Mori
 * 1974): its nodes crowd doubly exponentially towards the ends, so the
 * square-root behaviour of F at the critical angle of total internal
 * reflection (an end point below) and the near-singular F of eta -> 1 at
 * grazing incidence cost no accuracy. Step 1/32 on t in [-4, 4]: the
 * truncation and discretisation errors are below 1e-14 for these
 * integrands. (The original uses a 10-point rule for conductors and
 * polynomial fits for dielectrics, good to 0.1-10%.) */
#define TS_STEP (1.0 / 32.0)
#define TS_HALF_COUNT 128

typedef double (*reflectance_fn)(double mu, const double *param);

static double tanh_sinh_flux(reflectance_fn f, const double *param, double a, double b)
{
    double sum = 0.0, half = 0.5 * (b - a);
    int k;
    for (k = -TS_HALF_COUNT; k <= TS_HALF_COUNT; ++k) {
        double t = k * TS_STEP;
        double u = 0.5 * LL_PI * sinh(t);
        double ch = cosh(u);
        /* x = a + half (1 + tanh u); the weight is d x / d t. */
        double w = half * 0.5 * LL_PI * cosh(t) / (ch * ch);
        double mu = a + half * (1.0 + tanh(u));
        if (w < 1e-300)
            continue;
        sum += w * f(mu, param) * mu;
    }
    return 2.0 * TS_STEP * sum;
}

static double dielectric_at(double mu, const double *param)
{
    double unused;
    return ll_fresnel_dielectric_kernel(mu, param[0], &unused);
}

static double conductor_at(double mu, const double *param)
{
    return ll_fresnel_conductor_kernel(mu, param[0], param[1]);
}

/* Light inside the denser medium (eta < 1) is totally reflected below the
 * critical cosine mu_c = sqrt(1 - eta^2); this is the flux reflected above
 * it, 2 * integral_{mu_c}^1 F mu dmu. */
static double dielectric_flux_inside(double eta)
{
    double mu_c = sqrt((1.0 - eta) * (1.0 + eta));
    return tanh_sinh_flux(dielectric_at, &eta, mu_c, 1.0);
}

/* Both averages, arguments checked. */
static double dielectric_average(double eta)
{
    if (eta == 1.0)
        return 0.0;
    if (eta < 1.0)
        return (1.0 - eta) * (1.0 + eta) + dielectric_flux_inside(eta);
    /* Outside: detailed balance across the boundary, 1 - Fbar(eta) =
     * eta^2 (1 - Fbar(1/eta)), gives Fbar(eta) = eta^2 * flux_inside(1/eta)
     * exactly, without the steep integrand of eta -> 1+ at grazing angles. */
    return eta * eta * dielectric_flux_inside(1.0 / eta);
}

ll_status ll_fresnel_dielectric_average(double eta, double *average)
{
    static const char fn[] = "ll_fresnel_dielectric_average";
    if (!average)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: average is NULL", fn);
    *average = 0.0;
    if (!(eta > 0.0) || !ll_is_finite(eta))
        return invalid(fn, "eta must be positive and finite", eta);
    *average = dielectric_average(eta);
    return LL_OK;
}

ll_status ll_fresnel_conductor_average(double eta_re, double eta_im, double *average)
{
    static const char fn[] = "ll_fresnel_conductor_average";
    double param[2];
    ll_status s;
    if (!average)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: average is NULL", fn);
    *average = 0.0;
    s = conductor_args(fn, eta_re, eta_im);
    if (s != LL_OK)
        return s;
    if (eta_im == 0.0) {
        *average = dielectric_average(eta_re);
        return LL_OK;
    }
    param[0] = eta_re;
    param[1] = eta_im;
    *average = tanh_sinh_flux(conductor_at, param, 0.0, 1.0);
    return LL_OK;
}
