/*
 * Fresnel reflectance of smooth boundaries (dielectric and conductor) and
 * its hemispherical averages, the public face of the kernels in fresnel.h.
 */
#include "words/fresnel.h"
#include "support/support.h"

#include "layerlab/ll_layer.h"

#include <math.h>

/* The functions return a double, so an invalid argument gives NaN (which
 * cannot be mistaken for a reflectance) and a message for
 * ll_last_error_message(). */
static double invalid(const char *fn, const char *what, double value)
{
    ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: %s (got %g)", fn, what, value);
    return NAN;
}

double ll_fresnel_dielectric(double cos_theta_i, double eta, double *cos_theta_t)
{
    double unused;
    if (!(cos_theta_i >= -1.0 && cos_theta_i <= 1.0))
        return invalid("ll_fresnel_dielectric", "cos_theta_i must be in [-1, 1]", cos_theta_i);
    if (!(eta > 0.0) || !ll_is_finite(eta))
        return invalid("ll_fresnel_dielectric", "eta must be positive and finite", eta);
    return ll_fresnel_dielectric_kernel(cos_theta_i, eta, cos_theta_t ? cos_theta_t : &unused);
}

static int conductor_args_ok(const char *fn, double eta_re, double eta_im)
{
    if (!(eta_re >= 0.0) || !ll_is_finite(eta_re))
        return invalid(fn, "eta_re must be finite and >= 0", eta_re), 0;
    if (!(eta_im >= 0.0) || !ll_is_finite(eta_im))
        return invalid(fn, "eta_im must be finite and >= 0", eta_im), 0;
    if (eta_re == 0.0 && eta_im == 0.0)
        return invalid(fn, "eta must not be 0", 0.0), 0;
    return 1;
}

double ll_fresnel_conductor(double cos_theta_i, double eta_re, double eta_im)
{
    if (!(cos_theta_i >= 0.0 && cos_theta_i <= 1.0))
        return invalid("ll_fresnel_conductor", "cos_theta_i must be in [0, 1]", cos_theta_i);
    if (!conductor_args_ok("ll_fresnel_conductor", eta_re, eta_im))
        return NAN;
    return ll_fresnel_conductor_kernel(cos_theta_i, eta_re, eta_im);
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

double ll_fresnel_dielectric_average(double eta)
{
    if (!(eta > 0.0) || !ll_is_finite(eta))
        return invalid("ll_fresnel_dielectric_average", "eta must be positive and finite", eta);
    if (eta == 1.0)
        return 0.0;
    if (eta < 1.0)
        return (1.0 - eta) * (1.0 + eta) + dielectric_flux_inside(eta);
    /* Outside: detailed balance across the boundary, 1 - Fbar(eta) =
     * eta^2 (1 - Fbar(1/eta)), gives Fbar(eta) = eta^2 * flux_inside(1/eta)
     * exactly, without the steep integrand of eta -> 1+ at grazing angles. */
    return eta * eta * dielectric_flux_inside(1.0 / eta);
}

double ll_fresnel_conductor_average(double eta_re, double eta_im)
{
    double param[2];
    if (!conductor_args_ok("ll_fresnel_conductor_average", eta_re, eta_im))
        return NAN;
    if (eta_im == 0.0)
        return ll_fresnel_dielectric_average(eta_re);
    param[0] = eta_re;
    param[1] = eta_im;
    return tanh_sinh_flux(conductor_at, param, 0.0, 1.0);
}
