/*
 * g, the smooth factor of a pair's BSDF (microfacet_series.c): the Fresnel
 * factor, shadowing and the Jacobian, at given azimuths, and g with F = 1
 * (the reference of the energy compensation). With t = wi . wo and
 * unnormalised H:
 *   reflection:   |H|^2 = 2 (1 + t),  wi.H = 1 + t,
 *                 g = F D G / (4 |mu_i mu_o|) = scale F (1 + t)^2
 *   refraction:   |H|^2 = 1 + eta^2 + 2 eta t,  wi.H = 1 + eta t,
 *                 wo.H = t + eta, and the Jacobian's
 *                 (wi.H)(wo.H) / (wi.H + eta wo.H)^2 = (wi.H)(wo.H)/|H|^4,
 *                 g = scale (1 - F) |(1 + eta t)(t + eta)|
 *                 where both directions see the front of the facet
 * (scale: ll_microfacet_plan_pair's phi-independent factors). This is the
 * inner loop of every series (16 samples of a Chebyshev pair, about 150 of
 * a Filon one), and so most of a layer's and of the resolution search's
 * time.
 *
 * One loop per case (reflection from a dielectric, from a conductor,
 * refraction; with or without the Fresnel factor), the case being fixed
 * per pair: each keeps the operations of the general formula below, in
 * the same order, so that a sample is the same double whichever loop
 * computes it; the loops only leave out the tests that are the same for
 * every sample, the Fresnel factor where no output takes it, and the
 * calls of fmin/fmax (a library call each on x86-64, as maxsd is not
 * IEEE's fmax for NaN), replaced by comparisons that give the same
 * double for every argument that reaches them (no NaN, no -0: see
 * clamp_below).
 */
#include "words/microfacet_pair.h"

#include "words/fresnel.h"

#include <math.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__SSE2__) && defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define PROFILE_HAVE_AVX 1
#include <immintrin.h>
#else
#define PROFILE_HAVE_AVX 0
#endif

/* max(lo, x) as fmax gives it, unless x and lo are zeros of opposite
 * sign (fmax may return either then): 1 + t is never -0 (a sum with +1
 * is -0 only if both terms are), and lo is nonzero elsewhere. For a NaN
 * x, fmax gives lo, and so does this. */
static inline double clamp_below(double lo, double x)
{
    return x > lo ? x : lo;
}

/* min(hi, x), likewise (hi is nonzero). */
static inline double clamp_above(double hi, double x)
{
    return x < hi ? x : hi;
}

/* Fresnel's reflectance of a dielectric, eta != 1, with 1 / eta computed
 * once per pair (fresnel.h). */
static inline double dielectric_fresnel(double cos_i, double eta, double inv_eta)
{
    double unused;
    return ll_fresnel_dielectric_inv(cos_i, eta, inv_eta, &unused);
}

#if defined(__SSE2__)
/* The per-pair constants of the reflection loops: a dielectric's eta and
 * 1 / eta (eta != 1), or a conductor's a2 and b4 (conductor_fresnel). */
typedef struct reflect_constants {
    int conductor;
    double c0, c1;
} reflect_constants;

/* The loops two at a time (microfacet_profile_loops.h): reflect_sse2,
 * refract_sse2. */
#define PV __m128d
#define PW 2
#define PFN(name) name##_sse2
#define PATTR
#define P_SET1(x) _mm_set1_pd(x)
#define P_ZERO() _mm_setzero_pd()
#define P_ADD(a, b) _mm_add_pd(a, b)
#define P_SUB(a, b) _mm_sub_pd(a, b)
#define P_MUL(a, b) _mm_mul_pd(a, b)
#define P_DIV(a, b) _mm_div_pd(a, b)
#define P_SQRT(a) _mm_sqrt_pd(a)
#define P_AND(a, b) _mm_and_pd(a, b)
#define P_ANDNOT(a, b) _mm_andnot_pd(a, b)
#define P_OR(a, b) _mm_or_pd(a, b)
#define P_GT(a, b) _mm_cmpgt_pd(a, b)
#define P_LT(a, b) _mm_cmplt_pd(a, b)
#define P_LE(a, b) _mm_cmple_pd(a, b)
#define P_LOADU(p) _mm_loadu_pd(p)
#define P_STOREU(p, a) _mm_storeu_pd(p, a)
#include "words/microfacet_profile_loops.h"
#endif

#if PROFILE_HAVE_AVX
/* The processor's features, as the compiler's runtime detected them
 * before main: read-only here. */
static int have_avx(void)
{
    return __builtin_cpu_supports("avx");
}

/* The same loops four at a time (AVX without FMA: the same roundings):
 * reflect_avx, refract_avx, chosen at run time. */
#define PV __m256d
#define PW 4
#define PFN(name) name##_avx
#define PATTR __attribute__((target("avx")))
#define P_SET1(x) _mm256_set1_pd(x)
#define P_ZERO() _mm256_setzero_pd()
#define P_ADD(a, b) _mm256_add_pd(a, b)
#define P_SUB(a, b) _mm256_sub_pd(a, b)
#define P_MUL(a, b) _mm256_mul_pd(a, b)
#define P_DIV(a, b) _mm256_div_pd(a, b)
#define P_SQRT(a) _mm256_sqrt_pd(a)
#define P_AND(a, b) _mm256_and_pd(a, b)
#define P_ANDNOT(a, b) _mm256_andnot_pd(a, b)
#define P_OR(a, b) _mm256_or_pd(a, b)
#define P_GT(a, b) _mm256_cmp_pd(a, b, _CMP_GT_OQ)
#define P_LT(a, b) _mm256_cmp_pd(a, b, _CMP_LT_OQ)
#define P_LE(a, b) _mm256_cmp_pd(a, b, _CMP_LE_OQ)
#define P_LOADU(p) _mm256_loadu_pd(p)
#define P_STOREU(p, a) _mm256_storeu_pd(p, a)
#include "words/microfacet_profile_loops.h"
#endif

/* Reflection: g = scale F (1 + t)^2 (F = 1 in no_fresnel), t = wi . wo. */
static void reflect_profile(const ll_microfacet_model *mf, const pair_plan *p,
                            const double *cos_phi, size_t count, double *g, double *no_fresnel)
{
    double neg_sin = -p->sin_prod, mu_prod = p->mu_prod, s = p->sign_h, scale = p->scale;
    double eta = mf->eta_re, inv_eta = mf->conductor ? 0.0 : 1.0 / eta, eta_im = mf->eta_im;
    size_t k;
    if (!g) {
        for (k = 0; k < count; ++k) {
            double t = neg_sin * cos_phi[k] - mu_prod, one_t = clamp_below(0.0, 1.0 + t);
            no_fresnel[k] = scale * one_t * one_t;
        }
        return;
    }
    k = 0;
#if defined(__SSE2__)
    if (mf->conductor || eta != 1.0) {
        reflect_constants rc;
        rc.conductor = mf->conductor;
        /* (as the kernels form them: eta_re^2 - eta_im^2 - s2 and
         * 4 eta_im^2 eta_re^2 left to right) */
        rc.c0 = mf->conductor ? eta * eta - eta_im * eta_im : eta;
        rc.c1 = mf->conductor ? 4.0 * eta_im * eta_im * eta * eta : inv_eta;
#if PROFILE_HAVE_AVX
        if (have_avx())
            k = reflect_avx(p, &rc, cos_phi, count, g, no_fresnel);
#endif
        k += reflect_sse2(p, &rc, cos_phi + k, count - k, g + k,
                          no_fresnel ? no_fresnel + k : NULL);
    }
#endif
    for (; k < count; ++k) {
        double t = neg_sin * cos_phi[k] - mu_prod, one_t = clamp_below(0.0, 1.0 + t);
        double cos_h = s * sqrt(clamp_above(1.0, 0.5 * one_t)); /* wi . m */
        double value = scale * one_t * one_t, f;
        if (mf->conductor)
            f = ll_fresnel_conductor_kernel(fabs(cos_h), eta, eta_im);
        else
            f = eta == 1.0 ? 0.0 : dielectric_fresnel(cos_h, eta, inv_eta);
        g[k] = f * value;
        if (no_fresnel)
            no_fresnel[k] = value;
    }
}

/* Refraction: with unnormalised H, |H|^2 = 1 + eta^2 + 2 eta t, wi.H = 1 +
 * eta t, wo.H = t + eta, and g = scale (1 - F) |(wi.H)(wo.H)| where both
 * directions see the front of the facet, else 0. */
static void refract_profile(const ll_microfacet_model *mf, const pair_plan *p,
                            const double *cos_phi, size_t count, double *g, double *no_fresnel)
{
    double neg_sin = -p->sin_prod, mu_prod = p->mu_prod, s = p->sign_h, scale = p->scale;
    double eta = p->eta, one_eta2 = 1.0 + eta * eta, two_eta = 2.0 * eta;
    double neg_mu_i = -p->mu_i, mu_o = p->mu_o;
    double eta_re = mf->eta_re, inv_eta_re = 1.0 / eta_re;
    size_t k = 0;
#if PROFILE_HAVE_AVX
    if (g && eta_re != 1.0 && have_avx())
        k = refract_avx(p, eta_re, inv_eta_re, cos_phi, count, g, no_fresnel);
#endif
#if defined(__SSE2__)
    if (g && eta_re != 1.0)
        k += refract_sse2(p, eta_re, inv_eta_re, cos_phi + k, count - k, g + k,
                          no_fresnel ? no_fresnel + k : NULL);
#endif
    for (; k < count; ++k) {
        double t = neg_sin * cos_phi[k] - mu_prod;
        double wi_h = 1.0 + eta * t, wo_h = t + eta, value = 0.0, f;
        /* Both sides: v.m cos(theta_v) > 0 (wi.z = -mu_i, wo.z = mu_o). */
        if (s * wi_h * neg_mu_i > 0.0 && s * wo_h * mu_o > 0.0) {
            value = scale * fabs(wi_h * wo_h);
            if (g) {
                double len2 = clamp_below(1e-300, one_eta2 + two_eta * t);
                double cos_h = clamp_below(-1.0, clamp_above(1.0, s * wi_h / sqrt(len2)));
                f = eta_re == 1.0 ? 0.0 : dielectric_fresnel(cos_h, eta_re, inv_eta_re);
                g[k] = (1.0 - f) * value;
            }
        } else if (g) {
            g[k] = 0.0;
        }
        if (no_fresnel)
            no_fresnel[k] = value;
    }
}

void ll_microfacet_sample_profile(const ll_microfacet_model *mf, const pair_plan *p,
                                  const double *cos_phi, size_t count, double *g,
                                  double *no_fresnel)
{
    if (!g && !no_fresnel)
        return;
    if (p->reflect)
        reflect_profile(mf, p, cos_phi, count, g, no_fresnel);
    else
        refract_profile(mf, p, cos_phi, count, g, no_fresnel);
}
