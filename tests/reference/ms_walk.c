/*
 * The random walk on the Smith microsurface (Heitz, Hanika, d'Eon,
 * Dachsbacher 2016, "Multiple-Scattering Microfacet BSDFs with the Smith
 * Model"): the reference for the energy compensation of layerlab's rough
 * interfaces. It shares no code with layerlab: its own random numbers,
 * Fresnel equations (complex arithmetic), slope distributions, visible-
 * normal sampling and transport.
 *
 * The microsurface: Beckmann or GGX slopes of roughness alpha (Walter et
 * al. 2007's D, the same alpha as layerlab's), heights uncorrelated with
 * the slopes (uniform on [-1, 1]: the result does not depend on the height
 * distribution), the exact Smith Lambda. A ray is traced down from above
 * the surface: the height of its next intersection is sampled from the
 * Smith masking function (Heitz et al. 2016, sec. 4), the facet it hits
 * from the visible normals of its direction, and there it reflects (a
 * conductor, with the path's weight multiplied by the complex-index
 * Fresnel reflectance of each colour channel) or, on a dielectric,
 * reflects or refracts with the Fresnel probability; inside a dielectric
 * the walk runs on the mirrored microsurface (sec. 5.2). The scattering
 * order is the number of facets hit; order 1 is the single-scattering
 * BSDF with the height-correlated Smith G2 = 1 / (1 + Lambda_i + Lambda_o).
 *
 * Estimates:
 *  - directional albedo (conductor: per channel; dielectric: R and T from
 *    either side), split into order 1 and the total;
 *  - f(i, o) |cos o| by next-event estimation (sec. 6): at each hit the
 *    phase function towards o times the probability that o leaves from
 *    that height, split into order 1 and the orders >= 2.
 *
 * usage: ms_walk table FILE       the stored results (minutes)
 *        ms_walk check            the invariants (seconds)
 *        ms_walk rerun FILE       a few stored numbers again, within noise
 * Every estimate runs in chunks with seeds derived from (case, chunk): the
 * numbers do not depend on what else is computed.
 */
#include <complex.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MSW_PI 3.14159265358979323846
#define MSW_MAX_ORDER 10000
#define MSW_MAX_CHANNELS 13

/* ------------------------------------------------------------ numbers */

typedef struct { uint64_t s[4]; } msw_rng;

/* splitmix64 (Steele, Lea, Flood 2014) seeding xoshiro256** (Blackman and
 * Vigna 2018); (seed, chunk) are hashed, never added. */
static uint64_t msw_splitmix(uint64_t *x)
{
    uint64_t z = (*x += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

static void msw_seed(msw_rng *r, uint64_t seed, uint64_t chunk)
{
    uint64_t h = seed, a = msw_splitmix(&h);
    int k;
    h = a ^ chunk;
    a = msw_splitmix(&h);
    for (k = 0; k < 4; ++k)
        r->s[k] = msw_splitmix(&a);
}

static uint64_t msw_rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }

static double msw_uniform(msw_rng *r)
{
    uint64_t *s = r->s, result = msw_rotl(s[1] * 5, 7) * 9, t = s[1] << 17;
    s[2] ^= s[0];
    s[3] ^= s[1];
    s[1] ^= s[2];
    s[0] ^= s[3];
    s[2] ^= t;
    s[3] = msw_rotl(s[3], 45);
    return (double)(result >> 11) * 0x1.0p-53;
}

/* A hash of a case's name and numbers: its seed. */
static uint64_t msw_case_seed(const char *name, const double *v, int count)
{
    uint64_t h = 1469598103934665603ULL;
    int k;
    for (; *name; ++name)
        h = (h ^ (unsigned char)*name) * 1099511628211ULL;
    for (k = 0; k < count; ++k)
        h = (h ^ (uint64_t)llround(v[k] * 1e6)) * 1099511628211ULL;
    return h;
}

typedef struct { double x, y, z; } msw_vec;

static msw_vec msw_v(double x, double y, double z) { msw_vec v = { x, y, z }; return v; }
static double msw_dot(msw_vec a, msw_vec b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static msw_vec msw_scale(msw_vec a, double s) { return msw_v(a.x * s, a.y * s, a.z * s); }
static msw_vec msw_add(msw_vec a, msw_vec b) { return msw_v(a.x + b.x, a.y + b.y, a.z + b.z); }
static msw_vec msw_normalize(msw_vec a) { return msw_scale(a, 1.0 / sqrt(msw_dot(a, a))); }

/* The direction at polar angle theta (degrees) and azimuth phi. */
static msw_vec msw_dir(double theta_deg, double phi_deg)
{
    double t = theta_deg * MSW_PI / 180.0, p = phi_deg * MSW_PI / 180.0;
    return msw_v(sin(t) * cos(p), sin(t) * sin(p), cos(t));
}

/* ------------------------------------------------------------ Fresnel */

/* Unpolarised reflectance at cos_i (towards the light, on its side) into
 * the complex relative index eta of the other side. */
static double msw_fresnel(double cos_i, double complex eta)
{
    double sin2 = fmax(0.0, 1.0 - cos_i * cos_i), v;
    double complex cos_t, rs, rp;
    if (cimag(eta) == 0.0 && sin2 >= creal(eta) * creal(eta))
        return 1.0; /* total internal reflection */
    cos_t = csqrt(1.0 - sin2 / (eta * eta));
    rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    v = 0.5 * (creal(rs * conj(rs)) + creal(rp * conj(rp)));
    return v > 1.0 ? 1.0 : v;
}

/* ------------------------------------------------------ the microsurface */

enum { MSW_BECKMANN = 0, MSW_GGX = 1 };

typedef struct msw_surface {
    int dist;
    double alpha;
} msw_surface;

/* The slope distribution's D(m) of a unit normal m (m.z > 0). */
static double msw_ndf(const msw_surface *s, msw_vec m)
{
    double c2, t2, a2 = s->alpha * s->alpha;
    if (m.z <= 0.0)
        return 0.0;
    c2 = m.z * m.z;
    t2 = (1.0 - c2) / c2;
    if (s->dist == MSW_BECKMANN)
        return exp(-t2 / a2) / (MSW_PI * a2 * c2 * c2);
    return 1.0 / (MSW_PI * a2 * c2 * c2 * (1.0 + t2 / a2) * (1.0 + t2 / a2));
}

/* Smith's Lambda of a direction, for either sign of w.z (Lambda(-w) =
 * -1 - Lambda(w)): a = cot(theta) / alpha, signed. */
static double msw_lambda(const msw_surface *s, msw_vec w)
{
    double sin_t = sqrt(fmax(0.0, 1.0 - w.z * w.z)), a;
    if (sin_t == 0.0)
        return w.z > 0.0 ? 0.0 : -1.0;
    a = w.z / (sin_t * s->alpha);
    if (s->dist == MSW_BECKMANN)
        return 0.5 * (erf(a) - 1.0) + exp(-a * a) / (2.0 * a * sqrt(MSW_PI));
    return 0.5 * (-1.0 + (a > 0.0 ? 1.0 : -1.0) * sqrt(1.0 + 1.0 / (a * a)));
}

/* The projected area of the microsurface seen from w (either side):
 * w.z (1 + Lambda(w)), the normalisation of the visible normals. */
static double msw_projected_area(const msw_surface *s, msw_vec w)
{
    return w.z * (1.0 + msw_lambda(s, w));
}

/* Uniform heights on [-1, 1]: C1 and its inverse. */
static double msw_c1(double h) { return fmin(1.0, fmax(0.0, 0.5 * (h + 1.0))); }
static double msw_inv_c1(double u) { return fmax(-1.0, fmin(1.0, 2.0 * u - 1.0)); }

/* The probability that w leaves the surface from height h (0 downward). */
static double msw_g1(const msw_surface *s, msw_vec w, double h)
{
    if (w.z >= 1.0 - 1e-12)
        return 1.0;
    if (w.z <= 0.0)
        return 0.0;
    return pow(msw_c1(h), msw_lambda(s, w));
}

/* The height of the next intersection of the ray of direction w from
 * height h, or HUGE_VAL when it leaves (Heitz et al. 2016, sec. 4.2). */
static double msw_next_height(const msw_surface *s, msw_vec w, double h, double u)
{
    double lam;
    if (w.z >= 1.0 - 1e-12)
        return HUGE_VAL;
    if (w.z <= -1.0 + 1e-12)
        return msw_inv_c1(u * msw_c1(h));
    if (fabs(w.z) < 1e-12)
        return h;
    if (w.z > 0.0 && u > 1.0 - msw_g1(s, w, h))
        return HUGE_VAL;
    lam = msw_lambda(s, w);
    return msw_inv_c1(msw_c1(h) / pow(1.0 - u, 1.0 / lam));
}

/* A slope of the alpha = 1 surface seen from wi = (sin t, 0, cos t) (any
 * t in (0, pi)), with the density of its visible normals: x from its
 * marginal, whose unnormalised CDF is cos t (1 + erf x) / 2 + sin t
 * exp(-x^2) / (2 sqrt pi) for x < cot t (Newton steps inside a bisection
 * bracket), y independent and Gaussian. Beckmann. */
static void msw_beckmann_slope(double cos_t, double sin_t, double u1, double u2, double u3,
                               double *sx, double *sy)
{
    double cot = cos_t / sin_t, lo = fmin(cot, 0.0) - 7.0, hi = cot, x, target;
    int k;
#define MSW_CDF(v) (0.5 * cos_t * erfc(-(v)) + sin_t * exp(-(v) * (v)) / (2.0 * sqrt(MSW_PI)))
    target = u1 * MSW_CDF(cot);
    x = 0.5 * (lo + hi);
    for (k = 0; k < 100; ++k) {
        double c = MSW_CDF(x) - target, d = (cos_t - x * sin_t) * exp(-x * x) / sqrt(MSW_PI);
        double next;
        if (c > 0.0)
            hi = x;
        else
            lo = x;
        if (hi - lo < 1e-12)
            break;
        next = d > 0.0 ? x - c / d : 0.5 * (lo + hi);
        if (!(next > lo && next < hi))
            next = 0.5 * (lo + hi);
        if (fabs(next - x) < 1e-13)
            break;
        x = next;
    }
#undef MSW_CDF
    *sx = x;
    *sy = sqrt(-log(1.0 - u2)) * cos(2.0 * MSW_PI * u3);
}

/* A microfacet normal from the visible normals of wi (wi.z of either
 * sign): density max(0, wi.m) D(m) / projected area (Heitz et al. 2016,
 * sec. 5). GGX: Heitz 2018's construction on the stretched hemisphere,
 * which holds below the horizon too (the visible part is then the band
 * between the projected equator and the disk's rim); Beckmann: the
 * stretched slope of msw_beckmann_slope, rotated to wi's azimuth. */
static msw_vec msw_visible_normal(const msw_surface *s, msw_vec wi, msw_rng *r)
{
    double a = s->alpha, u1 = msw_uniform(r), u2 = msw_uniform(r);
    msw_vec v = msw_normalize(msw_v(a * wi.x, a * wi.y, wi.z)), m;
    if (s->dist == MSW_GGX) {
        double len2 = v.x * v.x + v.y * v.y, rad = sqrt(u1), phi = 2.0 * MSW_PI * u2;
        double t1 = rad * cos(phi), t2 = rad * sin(phi), h = 0.5 * (1.0 + v.z);
        msw_vec e1 = len2 > 0.0 ? msw_scale(msw_v(-v.y, v.x, 0.0), 1.0 / sqrt(len2))
                                : msw_v(1.0, 0.0, 0.0);
        msw_vec e2 = msw_v(v.y * e1.z - v.z * e1.y, v.z * e1.x - v.x * e1.z,
                           v.x * e1.y - v.y * e1.x);
        msw_vec n;
        t2 = (1.0 - h) * sqrt(fmax(0.0, 1.0 - t1 * t1)) + h * t2;
        n = msw_add(msw_add(msw_scale(e1, t1), msw_scale(e2, t2)),
                    msw_scale(v, sqrt(fmax(0.0, 1.0 - t1 * t1 - t2 * t2))));
        m = msw_normalize(msw_v(a * n.x, a * n.y, fmax(1e-300, n.z)));
    } else {
        double sin_t = sqrt(fmax(0.0, 1.0 - v.z * v.z)), sx, sy, c, sn, x, y;
        if (sin_t < 1e-9) {
            double rad = sqrt(-log(1.0 - u1));
            sx = rad * cos(2.0 * MSW_PI * u2);
            sy = rad * sin(2.0 * MSW_PI * u2);
            c = 1.0;
            sn = 0.0;
        } else {
            msw_beckmann_slope(v.z, sin_t, u1, u2, msw_uniform(r), &sx, &sy);
            c = v.x / sin_t;
            sn = v.y / sin_t;
        }
        x = (c * sx - sn * sy) * a;
        y = (sn * sx + c * sy) * a;
        m = msw_normalize(msw_v(-x, -y, 1.0));
    }
    if (!(m.z > 0.0) || !isfinite(m.x) || !isfinite(m.y))
        m = msw_normalize(msw_v(wi.x, wi.y, 1e-9)); /* (a facet on edge) */
    return m;
}

/* The conductor's phase function without Fresnel, from wi to wo (both
 * pointing away from the surface): D(h) / (4 A(wi)) (Heitz et al. 2016,
 * eq. 20 with F = 1). */
static double msw_phase_reflect(const msw_surface *s, msw_vec wi, msw_vec wo, msw_vec *h)
{
    msw_vec sum = msw_add(wi, wo);
    double len = sqrt(msw_dot(sum, sum)), area;
    if (!(len > 0.0))
        return 0.0;
    *h = msw_scale(sum, 1.0 / len);
    if (h->z <= 0.0)
        return 0.0;
    area = msw_projected_area(s, wi);
    return area > 0.0 ? msw_ndf(s, *h) / (4.0 * area) : 0.0;
}

/* ------------------------------------------------------------ estimates */

#define MSW_CHUNK 4096
/* Above the highest height: where every walk starts. */
#define MSW_TOP 2.0

typedef struct msw_channels {
    int count;                           /* channels: <= MSW_MAX_CHANNELS */
    double complex eta[MSW_MAX_CHANNELS]; /* complex index; 0: F = 1     */
} msw_channels;

static double msw_channel_fresnel(const msw_channels *ch, int k, double cos_i)
{
    return ch->eta[k] == 0.0 ? 1.0 : msw_fresnel(cos_i, ch->eta[k]);
}

/* The conductor's directional albedo from wi: order 1 and the total per
 * channel, the total's standard error; paths in chunks seeded from seed. */
static void msw_conductor_albedo(const msw_surface *s, const msw_channels *ch, msw_vec wi,
                                 long paths, uint64_t seed, double *e1, double *et, double *se)
{
    double sum1[MSW_MAX_CHANNELS] = { 0 }, sum[MSW_MAX_CHANNELS] = { 0 };
    double sum2[MSW_MAX_CHANNELS] = { 0 };
    long p;
    int k;
    msw_rng r;
    for (p = 0; p < paths; ++p) {
        double w[MSW_MAX_CHANNELS], h = MSW_TOP;
        msw_vec wr = msw_scale(wi, -1.0);
        int order = 0;
        if (p % MSW_CHUNK == 0)
            msw_seed(&r, seed, (uint64_t)(p / MSW_CHUNK));
        for (k = 0; k < ch->count; ++k)
            w[k] = 1.0;
        for (;;) {
            msw_vec m, back;
            double c;
            h = msw_next_height(s, wr, h, msw_uniform(&r));
            if (h == HUGE_VAL)
                break;
            if (++order > MSW_MAX_ORDER) {
                for (k = 0; k < ch->count; ++k)
                    w[k] = 0.0;
                break;
            }
            back = msw_scale(wr, -1.0);
            m = msw_visible_normal(s, back, &r);
            c = msw_dot(back, m);
            for (k = 0; k < ch->count; ++k)
                w[k] *= msw_channel_fresnel(ch, k, fmax(0.0, c));
            wr = msw_add(wr, msw_scale(m, 2.0 * c));
        }
        for (k = 0; k < ch->count; ++k) {
            sum[k] += w[k];
            sum2[k] += w[k] * w[k];
            if (order == 1)
                sum1[k] += w[k];
        }
    }
    for (k = 0; k < ch->count; ++k) {
        double mean = sum[k] / paths;
        e1[k] = sum1[k] / paths;
        et[k] = mean;
        se[k] = sqrt(fmax(0.0, sum2[k] / paths - mean * mean) / paths);
    }
}

/* The conductor's f(wi, wo) |wo.z| by next-event estimation: order 1
 * (f1) and the orders >= 2 (fm) per channel, with fm's standard error. */
static void msw_conductor_eval(const msw_surface *s, const msw_channels *ch, msw_vec wi,
                               msw_vec wo, long paths, uint64_t seed, double *f1, double *fm,
                               double *se1, double *sem)
{
    double s1[MSW_MAX_CHANNELS] = { 0 }, sm[MSW_MAX_CHANNELS] = { 0 };
    double q1[MSW_MAX_CHANNELS] = { 0 }, qm[MSW_MAX_CHANNELS] = { 0 };
    long p;
    int k;
    msw_rng r;
    for (p = 0; p < paths; ++p) {
        double w[MSW_MAX_CHANNELS], a1[MSW_MAX_CHANNELS] = { 0 }, am[MSW_MAX_CHANNELS] = { 0 };
        double h = MSW_TOP;
        msw_vec wr = msw_scale(wi, -1.0);
        int order = 0;
        if (p % MSW_CHUNK == 0)
            msw_seed(&r, seed, (uint64_t)(p / MSW_CHUNK));
        for (k = 0; k < ch->count; ++k)
            w[k] = 1.0;
        for (;;) {
            msw_vec m, back, half;
            double c, phase, leave;
            h = msw_next_height(s, wr, h, msw_uniform(&r));
            if (h == HUGE_VAL || ++order > MSW_MAX_ORDER)
                break;
            back = msw_scale(wr, -1.0);
            phase = msw_phase_reflect(s, back, wo, &half);
            leave = phase > 0.0 ? msw_g1(s, wo, h) : 0.0;
            if (leave > 0.0) {
                double cf = msw_dot(back, half);
                for (k = 0; k < ch->count; ++k) {
                    double v = w[k] * msw_channel_fresnel(ch, k, cf) * phase * leave;
                    if (order == 1)
                        a1[k] += v;
                    else
                        am[k] += v;
                }
            }
            m = msw_visible_normal(s, back, &r);
            c = msw_dot(back, m);
            for (k = 0; k < ch->count; ++k)
                w[k] *= msw_channel_fresnel(ch, k, fmax(0.0, c));
            wr = msw_add(wr, msw_scale(m, 2.0 * c));
        }
        for (k = 0; k < ch->count; ++k) {
            s1[k] += a1[k];
            q1[k] += a1[k] * a1[k];
            sm[k] += am[k];
            qm[k] += am[k] * am[k];
        }
    }
    for (k = 0; k < ch->count; ++k) {
        f1[k] = s1[k] / paths;
        fm[k] = sm[k] / paths;
        se1[k] = sqrt(fmax(0.0, q1[k] / paths - f1[k] * f1[k]) / paths);
        sem[k] = sqrt(fmax(0.0, qm[k] / paths - fm[k] * fm[k]) / paths);
    }
}

/* A dielectric of relative index eta (below over above) lit along wi from
 * above (wi.z > 0) or below: the fractions leaving on the side of the
 * light (R) and on the other (T), order 1 and total. Inside, the walk runs
 * on the mirrored microsurface with heights and directions negated. */
static void msw_dielectric(const msw_surface *s, double eta, msw_vec wi, long paths,
                           uint64_t seed, double out[6])
{
    long p, r1 = 0, rt = 0, t1 = 0, tt = 0;
    msw_rng r;
    int start_outside = wi.z > 0.0;
    for (p = 0; p < paths; ++p) {
        msw_vec wr = msw_scale(wi, -1.0);
        int outside = start_outside, order = 0;
        double h = outside ? MSW_TOP : -MSW_TOP;
        if (p % MSW_CHUNK == 0)
            msw_seed(&r, seed, (uint64_t)(p / MSW_CHUNK));
        for (;;) {
            msw_vec back, m;
            double e, c, f;
            double u = msw_uniform(&r);
            h = outside ? msw_next_height(s, wr, h, u)
                        : -msw_next_height(s, msw_scale(wr, -1.0), -h, u);
            if (fabs(h) == HUGE_VAL || ++order > MSW_MAX_ORDER)
                break;
            back = msw_scale(wr, -1.0);
            m = outside ? msw_visible_normal(s, back, &r)
                        : msw_scale(msw_visible_normal(s, msw_scale(back, -1.0), &r), -1.0);
            e = outside ? eta : 1.0 / eta;
            c = fmax(0.0, msw_dot(back, m));
            f = msw_fresnel(c, e);
            if (msw_uniform(&r) < f) {
                wr = msw_add(wr, msw_scale(m, 2.0 * c));
            } else {
                double cos_t = sqrt(fmax(0.0, 1.0 - (1.0 - c * c) / (e * e)));
                wr = msw_normalize(msw_add(msw_scale(back, -1.0 / e), msw_scale(m, c / e - cos_t)));
                outside = !outside;
            }
        }
        if (order > MSW_MAX_ORDER)
            continue;
        if (outside == start_outside) {
            rt++;
            r1 += order == 1;
        } else {
            tt++;
            t1 += order == 1;
        }
    }
    out[0] = (double)r1 / paths;
    out[1] = (double)rt / paths;
    out[2] = (double)t1 / paths;
    out[3] = (double)tt / paths;
    out[4] = sqrt(out[1] * (1.0 - out[1]) / paths);
    out[5] = sqrt(out[3] * (1.0 - out[3]) / paths);
}

/* ------------------------------------------------------------ the cases */

/* The channels of the stored tables: white (F = 1), then R, G, B of gold,
 * copper and aluminium with the per-channel complex indices that layerlab
 * makes of its named metals (data/ior's spectra reduced per channel, as
 * written in a built file's metadata). */
#define MSW_CHANNELS 10
static const char *const msw_channel_names[MSW_CHANNELS] = {
    "white", "Au.R", "Au.G", "Au.B", "Cu.R", "Cu.G", "Cu.B", "Al.R", "Al.G", "Al.B"
};
static const double msw_metal_n[9] = { 0.14314609816861512, 0.37311406987244777,
                                       1.4438126161131846,  0.19561986045500956,
                                       0.92562958214826851, 1.1021872800733044,
                                       1.6569217663319644,  0.880174210982267,
                                       0.52119897628501488 };
static const double msw_metal_k[9] = { 3.982616727574015,  2.3873901555307997,
                                       1.6024531886875775, 3.9108930334980392,
                                       2.4512894683232123, 2.1426425004061507,
                                       9.2242300865681415, 6.2696646162045937,
                                       4.8369802370193939 };

static msw_channels msw_table_channels(void)
{
    msw_channels ch;
    int k;
    ch.count = MSW_CHANNELS;
    ch.eta[0] = 0.0;
    for (k = 0; k < 9; ++k)
        ch.eta[k + 1] = msw_metal_n[k] + I * msw_metal_k[k];
    return ch;
}

static const char *const msw_dist_names[2] = { "beckmann", "ggx" };

/* The grids of the stored tables. */
static const double msw_alphas[10] = { 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0 };
static const double msw_thetas[6] = { 0, 15, 30, 45, 60, 75 };
static const double msw_f_alphas[2][4] = { { 0.3, 0.5, 0.8, 1.0 }, { 0.5, 1.0, 0, 0 } };
static const double msw_f_theta_i[3] = { 0, 30, 60 };
static const double msw_f_theta_o[6] = { 0, 15, 30, 45, 60, 75 };
static const double msw_f_phi[5] = { 0, 45, 90, 135, 180 };
#define MSW_ALBEDO_PATHS (1L << 19)
#define MSW_DIELECTRIC_PATHS (1L << 19)
#define MSW_F_PATHS (1L << 16)
#define MSW_ETA 1.5

/* One albedo line: A dist alpha theta_i, then per channel E1 Et se(Et). */
static void msw_albedo_case(FILE *out, int dist, double alpha, double theta, long paths,
                            uint64_t salt, double *e1, double *et, double *se)
{
    msw_surface s = { dist, alpha };
    msw_channels ch = msw_table_channels();
    double key[3] = { dist, alpha, theta };
    int k;
    msw_conductor_albedo(&s, &ch, msw_dir(theta, 0.0), paths,
                         msw_case_seed("albedo", key, 3) ^ salt, e1, et, se);
    if (!out)
        return;
    fprintf(out, "A %s %.2f %.0f", msw_dist_names[dist], alpha, theta);
    for (k = 0; k < ch.count; ++k)
        fprintf(out, " %.6f %.6f %.6f", e1[k], et[k], se[k]);
    fprintf(out, "\n");
}

/* One dielectric line: D dist alpha side theta, R1 R T1 T se(R) se(T). */
static void msw_dielectric_case(FILE *out, int dist, double alpha, int below, double theta,
                                long paths, uint64_t salt, double v[6])
{
    msw_surface s = { dist, alpha };
    double key[4] = { dist, alpha, below, theta };
    msw_vec wi = msw_dir(theta, 0.0);
    if (below)
        wi.z = -wi.z;
    msw_dielectric(&s, MSW_ETA, wi, paths, msw_case_seed("dielectric", key, 4) ^ salt, v);
    if (out)
        fprintf(out, "D %s %.2f %s %.0f %.6f %.6f %.6f %.6f %.6f %.6f\n", msw_dist_names[dist],
                alpha, below ? "below" : "above", theta, v[0], v[1], v[2], v[3], v[4], v[5]);
}

/* One f line: F dist alpha theta_i theta_o phi, then per channel the
 * multiple part f_m (BSDF, no cosine) and its standard error. phi is the
 * outgoing azimuth from the incident direction's (180: the mirror side). */
static void msw_f_case(FILE *out, int dist, double alpha, double ti, double to, double phi,
                       long paths, uint64_t salt, double *fm, double *sem)
{
    msw_surface s = { dist, alpha };
    msw_channels ch = msw_table_channels();
    double key[5] = { dist, alpha, ti, to, phi }, f1[MSW_MAX_CHANNELS], se1[MSW_MAX_CHANNELS];
    msw_vec wo = msw_dir(to, phi);
    int k;
    msw_conductor_eval(&s, &ch, msw_dir(ti, 0.0), wo, paths,
                       msw_case_seed("f", key, 5) ^ salt, f1, fm, se1, sem);
    for (k = 0; k < ch.count; ++k) {
        fm[k] /= wo.z;
        sem[k] /= wo.z;
    }
    if (!out)
        return;
    fprintf(out, "F %s %.2f %.0f %.0f %.0f", msw_dist_names[dist], alpha, ti, to, phi);
    for (k = 0; k < ch.count; ++k)
        fprintf(out, " %.6g %.3g", fm[k], sem[k]);
    fprintf(out, "\n");
}

#ifndef MS_WALK_NO_MAIN /* (the tests need no table) */
static int msw_table(const char *path)
{
    FILE *out = fopen(path, "w");
    double e1[MSW_MAX_CHANNELS], et[MSW_MAX_CHANNELS], se[MSW_MAX_CHANNELS], v[6];
    int d, a, t, b, i, o, p, k;
    if (!out) {
        perror(path);
        return 1;
    }
    fprintf(out, "# The random walk on the Smith microsurface (tests/reference/ms_walk.c;\n"
                 "# Heitz, Hanika, d'Eon, Dachsbacher 2016): `ms_walk table` writes this file.\n"
                 "# Channels:");
    for (k = 0; k < MSW_CHANNELS; ++k)
        fprintf(out, " %s", msw_channel_names[k]);
    fprintf(out, "\n# Metals' indices n+ik (R, G, B):");
    for (k = 0; k < 9; ++k)
        fprintf(out, " %.6f+%.6fi", msw_metal_n[k], msw_metal_k[k]);
    fprintf(out, "\n# A dist alpha theta_i [E1 E se(E)] per channel: conductor directional albedo,\n"
                 "#   order 1 and total (%ld paths)\n"
                 "# D dist alpha side theta_i R1 R T1 T se(R) se(T): dielectric eta %.1f, light\n"
                 "#   from above or below (%ld paths)\n"
                 "# F dist alpha theta_i theta_o phi [f_m se(f_m)] per channel: the multiple-\n"
                 "#   scattering part (orders >= 2) of the BSDF f (no cosine), phi from the\n"
                 "#   incident azimuth, 180 the mirror side (%ld paths)\n",
            MSW_ALBEDO_PATHS, MSW_ETA, MSW_DIELECTRIC_PATHS, MSW_F_PATHS);
    for (d = 0; d < 2; ++d)
        for (a = 0; a < 10; ++a)
            for (t = 0; t < 6; ++t)
                msw_albedo_case(out, d, msw_alphas[a], msw_thetas[t], MSW_ALBEDO_PATHS, 0, e1, et,
                                se);
    fflush(out);
    for (d = 0; d < 2; ++d)
        for (a = 0; a < 10; ++a)
            for (b = 0; b < 2; ++b)
                for (t = 0; t < 6; ++t)
                    msw_dielectric_case(out, d, msw_alphas[a], b, msw_thetas[t],
                                        MSW_DIELECTRIC_PATHS, 0, v);
    fflush(out);
    for (d = 0; d < 2; ++d)
        for (a = 0; a < 4 && msw_f_alphas[d][a] > 0.0; ++a)
            for (i = 0; i < 3; ++i)
                for (o = 0; o < 6; ++o)
                    for (p = 0; p < 5; ++p)
                        msw_f_case(out, d, msw_f_alphas[d][a], msw_f_theta_i[i],
                                   msw_f_theta_o[o], msw_f_phi[p], MSW_F_PATHS, 0, e1, se);
    return fclose(out) == 0 ? 0 : 1;
}
#endif

/* ------------------------------------------------------------ the checks */

/* The single-scattering BSDF times |wo.z| with the height-correlated Smith
 * term: F D G2 / (4 wi.z), G2 = 1 / (1 + Lambda(wi) + Lambda(wo)). */
static double msw_single(const msw_surface *s, double complex eta, msw_vec wi, msw_vec wo)
{
    msw_vec sum = msw_add(wi, wo), h;
    double f;
    if (wi.z <= 0.0 || wo.z <= 0.0)
        return 0.0;
    h = msw_normalize(sum);
    f = eta == 0.0 ? 1.0 : msw_fresnel(msw_dot(wi, h), eta);
    return f * msw_ndf(s, h) / (4.0 * wi.z * (1.0 + msw_lambda(s, wi) + msw_lambda(s, wo)));
}

/* Its directional albedo by the midpoint rule in (wo.z, phi). */
static double msw_single_albedo(const msw_surface *s, double complex eta, msw_vec wi)
{
    int a, b, na = 600, nb = 600;
    double sum = 0.0;
    for (a = 0; a < na; ++a)
        for (b = 0; b < nb; ++b) {
            double z = (a + 0.5) / na, phi = 2.0 * MSW_PI * (b + 0.5) / nb;
            double r = sqrt(1.0 - z * z);
            sum += msw_single(s, eta, wi, msw_v(r * cos(phi), r * sin(phi), z));
        }
    return sum * 2.0 * MSW_PI / ((double)na * nb);
}

static int msw_report(const char *what, double got, double want, double tol)
{
    int ok = fabs(got - want) <= tol;
    printf("%-4s %-58s %.6f against %.6f (tolerance %.2g)\n", ok ? "ok" : "FAIL", what, got,
           want, tol);
    return !ok;
}

/* The walk's own invariants; returns the number of failures. */
static int msw_check(void)
{
    msw_channels ch = msw_table_channels();
    double e1[MSW_MAX_CHANNELS], et[MSW_MAX_CHANNELS], se[MSW_MAX_CHANNELS];
    double f1[MSW_MAX_CHANNELS], fm[MSW_MAX_CHANNELS], se1[MSW_MAX_CHANNELS];
    double sem[MSW_MAX_CHANNELS], g1[MSW_MAX_CHANNELS], gm[MSW_MAX_CHANNELS];
    double ge1[MSW_MAX_CHANNELS], gem[MSW_MAX_CHANNELS], v[6];
    char what[128];
    int fails = 0, d, k;
    for (d = 0; d < 2; ++d) {
        msw_surface rough = { d, 1.0 }, mid = { d, 0.5 };
        const char *dn = msw_dist_names[d];
        double sum = 0.0, sum2 = 0.0, mean;
        long n = 20000, p;
        msw_rng r;
        /* F = 1 keeps every path, and a dielectric splits each path into R or T. */
        msw_conductor_albedo(&rough, &ch, msw_dir(80.0, 0.0), 20000, 11, e1, et, se);
        snprintf(what, sizeof what, "%s alpha 1, 80 deg: F = 1 albedo", dn);
        fails += msw_report(what, et[0], 1.0, 1e-12);
        msw_dielectric(&rough, MSW_ETA, msw_v(0.0, 0.0, -1.0), 20000, 12, v);
        snprintf(what, sizeof what, "%s alpha 1, eta 1.5 from below: R + T", dn);
        fails += msw_report(what, v[1] + v[3], 1.0, 1e-12);
        /* The next-event estimate integrates to the albedo: wo uniform
         * on the hemisphere, one walk each. */
        msw_seed(&r, 13, 0);
        for (p = 0; p < n; ++p) {
            double z = msw_uniform(&r), phi = 2.0 * MSW_PI * msw_uniform(&r), val;
            double rr = sqrt(1.0 - z * z);
            msw_conductor_eval(&rough, &ch, msw_dir(60.0, 0.0),
                               msw_v(rr * cos(phi), rr * sin(phi), z), 1, 1000 + (uint64_t)p,
                               f1, fm, se1, sem);
            val = 2.0 * MSW_PI * (f1[0] + fm[0]);
            sum += val;
            sum2 += val * val;
        }
        mean = sum / n;
        snprintf(what, sizeof what, "%s alpha 1, 60 deg: integral of f cos (F = 1)", dn);
        fails += msw_report(what, mean, 1.0, 4.0 * sqrt((sum2 / n - mean * mean) / n));
        /* The first bounce is the height-correlated single-scattering BSDF:
         * its albedo (visible-normal and height sampling) ... */
        for (k = 0; k < 2; ++k) {
            double theta = k ? 70.0 : 30.0;
            double want = msw_single_albedo(&mid, ch.eta[3], msw_dir(theta, 0.0));
            msw_conductor_albedo(&mid, &ch, msw_dir(theta, 0.0), 200000, 14 + k, e1, et, se);
            snprintf(what, sizeof what, "%s alpha 0.5, %.0f deg: order-1 albedo, Au.B", dn,
                     theta);
            fails += msw_report(what, e1[3], want, 4.0 * sqrt(want * (1.0 - want) / 200000) + 1e-4);
        }
        /* ... and its value (phase function and leaving probability). */
        msw_conductor_eval(&mid, &ch, msw_dir(40.0, 0.0), msw_dir(55.0, 160.0), 100000, 16, f1,
                           fm, se1, sem);
        snprintf(what, sizeof what, "%s alpha 0.5, 40 -> 55 deg, 160: order-1 f cos, Au.B", dn);
        fails += msw_report(what, f1[3],
                            msw_single(&mid, ch.eta[3], msw_dir(40.0, 0.0), msw_dir(55.0, 160.0)),
                            4.0 * se1[3]);
        /* Reciprocity of the multiple part: f_m(i, o) = f_m(o, i). */
        msw_conductor_eval(&rough, &ch, msw_dir(20.0, 0.0), msw_dir(65.0, 150.0), 200000, 17, f1,
                           fm, se1, sem);
        msw_conductor_eval(&rough, &ch, msw_dir(65.0, 150.0), msw_dir(20.0, 0.0), 200000, 18, g1,
                           gm, ge1, gem);
        for (k = 0; k < 4; k += 3) {
            double a = fm[k] / cos(65.0 * MSW_PI / 180.0), b = gm[k] / cos(20.0 * MSW_PI / 180.0);
            double sa = sem[k] / cos(65.0 * MSW_PI / 180.0), sb = gem[k] / cos(20.0 * MSW_PI / 180.0);
            snprintf(what, sizeof what, "%s alpha 1, 20 <-> 65 deg: f_m reciprocal, %s", dn,
                     msw_channel_names[k]);
            fails += msw_report(what, a, b, 4.0 * sqrt(sa * sa + sb * sb));
        }
    }
    return fails;
}

/* A few stored numbers again, with other random numbers: each within
 * 4.5 standard errors of both. Returns the failures (or -1: no file). */
static int msw_rerun(const char *path)
{
    FILE *in = fopen(path, "r");
    char line[4096], dn[32], side[16];
    long index_a = 0, index_d = 0, index_f = 0;
    int fails = 0, checked = 0, k;
    if (!in) {
        perror(path);
        return -1;
    }
    while (fgets(line, sizeof line, in)) {
        double alpha, t, to, phi, got[MSW_MAX_CHANNELS], gse[MSW_MAX_CHANNELS];
        double e1[MSW_MAX_CHANNELS], v[6], w[6];
        int d, pos, used;
        char *p;
        if (line[0] == 'A' && sscanf(line, "A %31s %lf %lf%n", dn, &alpha, &t, &pos) == 3) {
            if (index_a++ % 15 != 7)
                continue;
            d = strcmp(dn, "ggx") == 0;
            msw_albedo_case(NULL, d, alpha, t, MSW_ALBEDO_PATHS / 8, 0x5eed, e1, got, gse);
            p = line + pos;
            for (k = 0; k < MSW_CHANNELS; ++k) {
                double s1, st, ss;
                if (sscanf(p, "%lf %lf %lf%n", &s1, &st, &ss, &used) != 3)
                    return ++fails;
                p += used;
                if (fabs(got[k] - st) > 4.5 * sqrt(ss * ss + gse[k] * gse[k])) {
                    printf("FAIL %s", line);
                    printf("     channel %s: %.6f now\n", msw_channel_names[k], got[k]);
                    fails++;
                }
            }
            checked++;
        } else if (line[0] == 'D' &&
                   sscanf(line, "D %31s %lf %15s %lf %lf %lf %lf %lf %lf %lf", dn, &alpha, side,
                          &t, &w[0], &w[1], &w[2], &w[3], &w[4], &w[5]) == 10) {
            long paths = MSW_DIELECTRIC_PATHS / 8;
            if (index_d++ % 30 != 11)
                continue;
            d = strcmp(dn, "ggx") == 0;
            msw_dielectric_case(NULL, d, alpha, strcmp(side, "below") == 0, t, paths, 0x5eed, v);
            if (fabs(v[1] - w[1]) > 4.5 * sqrt(v[4] * v[4] + w[4] * w[4]) ||
                fabs(v[3] - w[3]) > 4.5 * sqrt(v[5] * v[5] + w[5] * w[5])) {
                printf("FAIL %s     now R %.6f T %.6f\n", line, v[1], v[3]);
                fails++;
            }
            checked++;
        } else if (line[0] == 'F' &&
                   sscanf(line, "F %31s %lf %lf %lf %lf%n", dn, &alpha, &t, &to, &phi, &pos) == 5) {
            if (index_f++ % 50 != 23)
                continue;
            d = strcmp(dn, "ggx") == 0;
            msw_f_case(NULL, d, alpha, t, to, phi, MSW_F_PATHS / 4, 0x5eed, got, gse);
            p = line + pos;
            for (k = 0; k < MSW_CHANNELS; ++k) {
                double sf, ss;
                if (sscanf(p, "%lf %lf%n", &sf, &ss, &used) != 2)
                    return ++fails;
                p += used;
                if (fabs(got[k] - sf) > 4.5 * sqrt(ss * ss + gse[k] * gse[k]) + 1e-9) {
                    printf("FAIL %s", line);
                    printf("     channel %s: %.6g now\n", msw_channel_names[k], got[k]);
                    fails++;
                }
            }
            checked++;
        }
    }
    fclose(in);
    printf("%s: %d stored cases rerun, %d differences beyond noise\n", path, checked, fails);
    return checked > 0 ? fails : ++fails;
}

#ifndef MS_WALK_NO_MAIN
int main(int argc, char **argv)
{
    if (argc == 3 && strcmp(argv[1], "table") == 0)
        return msw_table(argv[2]);
    if (argc == 2 && strcmp(argv[1], "check") == 0)
        return msw_check() != 0;
    if (argc == 3 && strcmp(argv[1], "rerun") == 0)
        return msw_rerun(argv[2]) != 0;
    fprintf(stderr, "usage: ms_walk table FILE | check | rerun FILE\n");
    return 2;
}
#endif
