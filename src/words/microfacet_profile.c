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
/* (x > 0 ? x : 0, x < hi ? x : hi, mask ? a : b, |x|) two at a time */
#define POSITIVE2(x) _mm_and_pd(_mm_cmpgt_pd(x, _mm_setzero_pd()), x)
#define SELECT2(mask, a, b) _mm_or_pd(_mm_and_pd(mask, a), _mm_andnot_pd(mask, b))
#define BELOW2(x, hi) SELECT2(_mm_cmplt_pd(x, hi), x, hi)
#define ABS2(x) _mm_andnot_pd(_mm_set1_pd(-0.0), x)

/* dielectric_fresnel two at a time: the same operations on each (IEEE's
 * +, -, *, / and sqrt round the same in a vector register; ISO C's mode
 * contracts nothing into fused multiply-adds), with the branch as a
 * selection: a totally reflected sample (cos_t2 <= 0) takes F = 1 instead
 * of the amplitudes, which are computed from sqrt(max(cos_t2, 0)) and
 * dropped. */
static inline __m128d dielectric_fresnel2(__m128d cos_i, __m128d eta, __m128d inv_eta)
{
    __m128d one = _mm_set1_pd(1.0), zero = _mm_setzero_pd();
    __m128d sc = SELECT2(_mm_cmpgt_pd(cos_i, zero), inv_eta, eta);
    __m128d cos_t2 =
        _mm_sub_pd(one, _mm_mul_pd(_mm_sub_pd(one, _mm_mul_pd(cos_i, cos_i)), _mm_mul_pd(sc, sc)));
    __m128d ci = ABS2(cos_i), ct = _mm_sqrt_pd(POSITIVE2(cos_t2));
    __m128d e_ct = _mm_mul_pd(eta, ct), e_ci = _mm_mul_pd(eta, ci);
    __m128d rs = _mm_div_pd(_mm_sub_pd(ci, e_ct), _mm_add_pd(ci, e_ct));
    __m128d rp = _mm_div_pd(_mm_sub_pd(e_ci, ct), _mm_add_pd(e_ci, ct));
    __m128d f = _mm_mul_pd(_mm_set1_pd(0.5), _mm_add_pd(_mm_mul_pd(rs, rs), _mm_mul_pd(rp, rp)));
    return SELECT2(_mm_cmple_pd(cos_t2, zero), one, f);
}

/* ll_fresnel_conductor_kernel two at a time, the same operations; a2 and
 * b4 its per-pair eta_re^2 - eta_im^2 and 4 eta_im^2 eta_re^2 (fmax(0,
 * x) is 0 for the x < 0 that rounding may give, and x is never -0). */
static inline __m128d conductor_fresnel2(__m128d cos_i, __m128d a2, __m128d b4)
{
    __m128d one = _mm_set1_pd(1.0), half = _mm_set1_pd(0.5);
    __m128d c2 = _mm_mul_pd(cos_i, cos_i), s2 = _mm_sub_pd(one, c2), s4 = _mm_mul_pd(s2, s2);
    __m128d t1 = _mm_sub_pd(a2, s2);
    __m128d a2pb2 = _mm_sqrt_pd(_mm_add_pd(_mm_mul_pd(t1, t1), b4));
    __m128d a = _mm_sqrt_pd(POSITIVE2(_mm_mul_pd(half, _mm_add_pd(a2pb2, t1))));
    __m128d term1 = _mm_add_pd(a2pb2, c2);
    __m128d term2 = _mm_mul_pd(_mm_mul_pd(_mm_set1_pd(2.0), a), cos_i);
    __m128d rs2 = _mm_div_pd(_mm_sub_pd(term1, term2), _mm_add_pd(term1, term2));
    __m128d term3 = _mm_add_pd(_mm_mul_pd(a2pb2, c2), s4), term4 = _mm_mul_pd(term2, s2);
    __m128d rp2 =
        _mm_div_pd(_mm_mul_pd(rs2, _mm_sub_pd(term3, term4)), _mm_add_pd(term3, term4));
    return _mm_mul_pd(half, _mm_add_pd(rp2, rs2));
}

/* The per-pair constants of the reflection loops: a dielectric's eta and
 * 1 / eta (eta != 1), or a conductor's a2 and b4 (conductor_fresnel2). */
typedef struct reflect_constants {
    int conductor;
    double c0, c1;
} reflect_constants;

/* The samples of reflect_profile with the Fresnel factor two at a time;
 * returns the samples done (count rounded down to even). */
static size_t reflect_sse2(const pair_plan *p, const reflect_constants *rc,
                           const double *cos_phi, size_t count, double *g, double *no_fresnel)
{
    __m128d neg_sin = _mm_set1_pd(-p->sin_prod), mu_prod = _mm_set1_pd(p->mu_prod);
    __m128d s = _mm_set1_pd(p->sign_h), scale = _mm_set1_pd(p->scale);
    __m128d one = _mm_set1_pd(1.0), half = _mm_set1_pd(0.5);
    __m128d c0 = _mm_set1_pd(rc->c0), c1 = _mm_set1_pd(rc->c1);
    size_t k;
    for (k = 0; k + 2 <= count; k += 2) {
        __m128d t = _mm_sub_pd(_mm_mul_pd(neg_sin, _mm_loadu_pd(cos_phi + k)), mu_prod);
        __m128d one_t = POSITIVE2(_mm_add_pd(one, t));
        __m128d cos_h = _mm_mul_pd(s, _mm_sqrt_pd(BELOW2(_mm_mul_pd(half, one_t), one)));
        __m128d value = _mm_mul_pd(_mm_mul_pd(scale, one_t), one_t);
        __m128d f = rc->conductor ? conductor_fresnel2(ABS2(cos_h), c0, c1)
                                  : dielectric_fresnel2(cos_h, c0, c1);
        _mm_storeu_pd(g + k, _mm_mul_pd(f, value));
        if (no_fresnel)
            _mm_storeu_pd(no_fresnel + k, value);
    }
    return k;
}

/* The samples of refract_profile with the Fresnel factor (eta_re != 1),
 * two at a time: every sample computed, then those that do not see the
 * front of the facet from both sides set to 0. Returns the samples done. */
static size_t refract_sse2(const pair_plan *p, double eta_re, double inv_eta_re,
                           const double *cos_phi, size_t count, double *g, double *no_fresnel)
{
    __m128d neg_sin = _mm_set1_pd(-p->sin_prod), mu_prod = _mm_set1_pd(p->mu_prod);
    __m128d s = _mm_set1_pd(p->sign_h), scale = _mm_set1_pd(p->scale);
    __m128d eta = _mm_set1_pd(p->eta), one_eta2 = _mm_set1_pd(1.0 + p->eta * p->eta);
    __m128d two_eta = _mm_set1_pd(2.0 * p->eta), neg_mu_i = _mm_set1_pd(-p->mu_i);
    __m128d mu_o = _mm_set1_pd(p->mu_o), one = _mm_set1_pd(1.0), zero = _mm_setzero_pd();
    __m128d minus_one = _mm_set1_pd(-1.0), tiny = _mm_set1_pd(1e-300);
    __m128d e = _mm_set1_pd(eta_re), inv_e = _mm_set1_pd(inv_eta_re);
    size_t k;
    for (k = 0; k + 2 <= count; k += 2) {
        __m128d t = _mm_sub_pd(_mm_mul_pd(neg_sin, _mm_loadu_pd(cos_phi + k)), mu_prod);
        __m128d wi_h = _mm_add_pd(one, _mm_mul_pd(eta, t)), wo_h = _mm_add_pd(t, eta);
        __m128d s_wi = _mm_mul_pd(s, wi_h);
        __m128d front = _mm_and_pd(_mm_cmpgt_pd(_mm_mul_pd(s_wi, neg_mu_i), zero),
                                   _mm_cmpgt_pd(_mm_mul_pd(_mm_mul_pd(s, wo_h), mu_o), zero));
        __m128d value = _mm_and_pd(front, _mm_mul_pd(scale, ABS2(_mm_mul_pd(wi_h, wo_h))));
        __m128d len2 = _mm_add_pd(one_eta2, _mm_mul_pd(two_eta, t));
        __m128d cos_h, x;
        len2 = SELECT2(_mm_cmpgt_pd(len2, tiny), len2, tiny);
        x = BELOW2(_mm_div_pd(s_wi, _mm_sqrt_pd(len2)), one);
        cos_h = SELECT2(_mm_cmpgt_pd(x, minus_one), x, minus_one);
        /* (masked again: a sample that is dropped gives 0, never 0 times a NaN) */
        _mm_storeu_pd(g + k, _mm_and_pd(front, _mm_mul_pd(_mm_sub_pd(one, dielectric_fresnel2(
                                                                    cos_h, e, inv_e)),
                                                        value)));
        if (no_fresnel)
            _mm_storeu_pd(no_fresnel + k, value);
    }
    return k;
}
#endif

#if PROFILE_HAVE_AVX
/* The processor's features, as the compiler's runtime detected them
 * before main: read-only here. */
static int have_avx(void)
{
    return __builtin_cpu_supports("avx");
}

/* The SSE2 loops' operations four at a time (AVX without FMA: the same
 * roundings). */
#define POSITIVE4(x) _mm256_and_pd(_mm256_cmp_pd(x, _mm256_setzero_pd(), _CMP_GT_OQ), x)
#define SELECT4(mask, a, b) _mm256_or_pd(_mm256_and_pd(mask, a), _mm256_andnot_pd(mask, b))
#define BELOW4(x, hi) SELECT4(_mm256_cmp_pd(x, hi, _CMP_LT_OQ), x, hi)
#define ABS4(x) _mm256_andnot_pd(_mm256_set1_pd(-0.0), x)

__attribute__((target("avx"))) static inline __m256d
dielectric_fresnel4(__m256d cos_i, __m256d eta, __m256d inv_eta)
{
    __m256d one = _mm256_set1_pd(1.0), zero = _mm256_setzero_pd();
    __m256d sc = SELECT4(_mm256_cmp_pd(cos_i, zero, _CMP_GT_OQ), inv_eta, eta);
    __m256d cos_t2 = _mm256_sub_pd(
        one, _mm256_mul_pd(_mm256_sub_pd(one, _mm256_mul_pd(cos_i, cos_i)), _mm256_mul_pd(sc, sc)));
    __m256d ci = ABS4(cos_i), ct = _mm256_sqrt_pd(POSITIVE4(cos_t2));
    __m256d e_ct = _mm256_mul_pd(eta, ct), e_ci = _mm256_mul_pd(eta, ci);
    __m256d rs = _mm256_div_pd(_mm256_sub_pd(ci, e_ct), _mm256_add_pd(ci, e_ct));
    __m256d rp = _mm256_div_pd(_mm256_sub_pd(e_ci, ct), _mm256_add_pd(e_ci, ct));
    __m256d f = _mm256_mul_pd(_mm256_set1_pd(0.5),
                              _mm256_add_pd(_mm256_mul_pd(rs, rs), _mm256_mul_pd(rp, rp)));
    return SELECT4(_mm256_cmp_pd(cos_t2, zero, _CMP_LE_OQ), one, f);
}

__attribute__((target("avx"))) static inline __m256d
conductor_fresnel4(__m256d cos_i, __m256d a2, __m256d b4)
{
    __m256d one = _mm256_set1_pd(1.0), half = _mm256_set1_pd(0.5);
    __m256d c2 = _mm256_mul_pd(cos_i, cos_i), s2 = _mm256_sub_pd(one, c2);
    __m256d s4 = _mm256_mul_pd(s2, s2), t1 = _mm256_sub_pd(a2, s2);
    __m256d a2pb2 = _mm256_sqrt_pd(_mm256_add_pd(_mm256_mul_pd(t1, t1), b4));
    __m256d a = _mm256_sqrt_pd(POSITIVE4(_mm256_mul_pd(half, _mm256_add_pd(a2pb2, t1))));
    __m256d term1 = _mm256_add_pd(a2pb2, c2);
    __m256d term2 = _mm256_mul_pd(_mm256_mul_pd(_mm256_set1_pd(2.0), a), cos_i);
    __m256d rs2 = _mm256_div_pd(_mm256_sub_pd(term1, term2), _mm256_add_pd(term1, term2));
    __m256d term3 = _mm256_add_pd(_mm256_mul_pd(a2pb2, c2), s4);
    __m256d term4 = _mm256_mul_pd(term2, s2);
    __m256d rp2 = _mm256_div_pd(_mm256_mul_pd(rs2, _mm256_sub_pd(term3, term4)),
                                _mm256_add_pd(term3, term4));
    return _mm256_mul_pd(half, _mm256_add_pd(rp2, rs2));
}

__attribute__((target("avx"))) static size_t
reflect_avx(const pair_plan *p, const reflect_constants *rc, const double *cos_phi, size_t count,
            double *g, double *no_fresnel)
{
    __m256d neg_sin = _mm256_set1_pd(-p->sin_prod), mu_prod = _mm256_set1_pd(p->mu_prod);
    __m256d s = _mm256_set1_pd(p->sign_h), scale = _mm256_set1_pd(p->scale);
    __m256d one = _mm256_set1_pd(1.0), half = _mm256_set1_pd(0.5);
    __m256d c0 = _mm256_set1_pd(rc->c0), c1 = _mm256_set1_pd(rc->c1);
    size_t k;
    for (k = 0; k + 4 <= count; k += 4) {
        __m256d t =
            _mm256_sub_pd(_mm256_mul_pd(neg_sin, _mm256_loadu_pd(cos_phi + k)), mu_prod);
        __m256d one_t = POSITIVE4(_mm256_add_pd(one, t));
        __m256d cos_h =
            _mm256_mul_pd(s, _mm256_sqrt_pd(BELOW4(_mm256_mul_pd(half, one_t), one)));
        __m256d value = _mm256_mul_pd(_mm256_mul_pd(scale, one_t), one_t);
        __m256d f = rc->conductor ? conductor_fresnel4(ABS4(cos_h), c0, c1)
                                  : dielectric_fresnel4(cos_h, c0, c1);
        _mm256_storeu_pd(g + k, _mm256_mul_pd(f, value));
        if (no_fresnel)
            _mm256_storeu_pd(no_fresnel + k, value);
    }
    return k;
}

__attribute__((target("avx"))) static size_t
refract_avx(const pair_plan *p, double eta_re, double inv_eta_re, const double *cos_phi,
            size_t count, double *g, double *no_fresnel)
{
    __m256d neg_sin = _mm256_set1_pd(-p->sin_prod), mu_prod = _mm256_set1_pd(p->mu_prod);
    __m256d s = _mm256_set1_pd(p->sign_h), scale = _mm256_set1_pd(p->scale);
    __m256d eta = _mm256_set1_pd(p->eta), one_eta2 = _mm256_set1_pd(1.0 + p->eta * p->eta);
    __m256d two_eta = _mm256_set1_pd(2.0 * p->eta), neg_mu_i = _mm256_set1_pd(-p->mu_i);
    __m256d mu_o = _mm256_set1_pd(p->mu_o), one = _mm256_set1_pd(1.0);
    __m256d zero = _mm256_setzero_pd(), minus_one = _mm256_set1_pd(-1.0);
    __m256d tiny = _mm256_set1_pd(1e-300);
    __m256d e = _mm256_set1_pd(eta_re), inv_e = _mm256_set1_pd(inv_eta_re);
    size_t k;
    for (k = 0; k + 4 <= count; k += 4) {
        __m256d t =
            _mm256_sub_pd(_mm256_mul_pd(neg_sin, _mm256_loadu_pd(cos_phi + k)), mu_prod);
        __m256d wi_h = _mm256_add_pd(one, _mm256_mul_pd(eta, t)), wo_h = _mm256_add_pd(t, eta);
        __m256d s_wi = _mm256_mul_pd(s, wi_h);
        __m256d front = _mm256_and_pd(
            _mm256_cmp_pd(_mm256_mul_pd(s_wi, neg_mu_i), zero, _CMP_GT_OQ),
            _mm256_cmp_pd(_mm256_mul_pd(_mm256_mul_pd(s, wo_h), mu_o), zero, _CMP_GT_OQ));
        __m256d value =
            _mm256_and_pd(front, _mm256_mul_pd(scale, ABS4(_mm256_mul_pd(wi_h, wo_h))));
        __m256d len2 = _mm256_add_pd(one_eta2, _mm256_mul_pd(two_eta, t));
        __m256d cos_h, x, f;
        len2 = SELECT4(_mm256_cmp_pd(len2, tiny, _CMP_GT_OQ), len2, tiny);
        x = BELOW4(_mm256_div_pd(s_wi, _mm256_sqrt_pd(len2)), one);
        cos_h = SELECT4(_mm256_cmp_pd(x, minus_one, _CMP_GT_OQ), x, minus_one);
        f = dielectric_fresnel4(cos_h, e, inv_e);
        _mm256_storeu_pd(
            g + k, _mm256_and_pd(front, _mm256_mul_pd(_mm256_sub_pd(one, f), value)));
        if (no_fresnel)
            _mm256_storeu_pd(no_fresnel + k, value);
    }
    return k;
}
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
