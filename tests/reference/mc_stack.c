/*
 * Monte Carlo reference for a layered stack: a rough (or smooth) dielectric
 * coat over a Henyey-Greenstein slab over a rough conductor (or over
 * nothing), the directional albedo R(mu_i) = the fraction of a collimated
 * beam from direction mu_i that leaves through the top, with its standard
 * error. It shares no code with layerlab: its own random numbers, Fresnel
 * equations (complex arithmetic), microfacet sampling and transport, so it
 * checks the discretisation (nodes, splines, Fourier orders, doubling) of
 * the layer code, not the model.
 *
 * The model is the one layerlab's words define, as described in
 * docs/method.md, "Words: what fills one layer":
 *  - interfaces: Beckmann D, separable Smith shadowing G1(wi) G1(wo) with
 *    Walter's rational approximation of G1 (Walter et al. 2007, eq. 27);
 *    or (-D ggx) the GGX D with its exact G1 = 2 / (1 + sqrt(1 + alpha^2
 *    tan^2)) (Walter et al. eqs. 33, 34), separable as the library's, or
 *    (-G correlated) with the height-correlated G2 = 1 / (1 + Lambda(wi) +
 *    Lambda(wo)) (Heitz 2014, eq. 99) that pbrt-v4's microfacet BSDFs use;
 *    unpolarised Fresnel reflectance at the microfacet, Walter's BTDF
 *    (eq. 21); no multiple-scattering compensation (conserve_energy = 0,
 *    the original's recipes). Sampled as Walter et al. 2007 section 5.3:
 *    m ~ D(m) |m.n|, reflect with probability F(i.m), else refract; the
 *    path weight is |i.m| G / (|i.n| |m.n|) (eq. 41), 0 when the sampled
 *    direction lies on the wrong side of the macro-surface. A conductor
 *    always reflects and its weight gets F. alpha = 0: a smooth boundary.
 *  - the medium: optical thickness tau, single-scattering albedo a, HG
 *    phase function (g), free paths exp(-tau / |mu|); absorption by
 *    weight (w *= a per scattering event) with Russian roulette below 1e-3.
 *  - below the medium: the conductor, a Lambertian base (-b diffuse,albedo:
 *    cosine-distributed, weight albedo), or nothing (the light leaves).
 *
 * usage: mc_stack [-D beckmann|ggx] [-G separable|correlated] [-c eta,alpha]
 *                 [-m albedo,g,tau] [-b eta,k,alpha | -b diffuse,albedo | -b none]
 *                 [-o mu_o,phi_o,half_angle] [-n paths] [-s seed] mu_i...
 * (-o: f at the outgoing direction of cosine mu_o and azimuth phi_o in
 * degrees from the direction towards the light, so 0 is retro-reflection
 * and 180 the mirror direction: the light leaving within half_angle
 * degrees of it, over the cone's solid angle and mu_o; printed in place of
 * R and its standard error.)
 * (-c 1,0: no coat, -m 0,0,0: no medium.) Prints per mu_i:
 *     mu_i R se(R) T se(T)
 * Paths run in chunks of 2^16, each with its own seed derived from
 * (seed, mu index, chunk): the result does not depend on the thread count.
 */
#include <complex.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979323846
#define CHUNK 65536
#define ROULETTE 1e-3
#define MAX_EVENTS 100000

typedef struct { uint64_t s[4]; } rng;

/* splitmix64 (Steele, Lea, Flood 2014) to seed xoshiro256** (Blackman and
 * Vigna 2018). */
static uint64_t splitmix(uint64_t *x)
{
    uint64_t z = (*x += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

static void rng_seed(rng *r, uint64_t seed)
{
    int k;
    for (k = 0; k < 4; ++k)
        r->s[k] = splitmix(&seed);
}

/* The generator of one chunk: (seed, stream, chunk) hashed through three
 * splitmix steps before seeding. Seeds that differ by multiples of the
 * splitmix increment would give generators whose states are shifted copies
 * of each other (correlated chunks, standard errors that understate the
 * scatter), so the three numbers are never simply added. */
static void rng_seed_chunk(rng *r, uint64_t seed, uint64_t stream, uint64_t chunk)
{
    uint64_t h = seed, a = splitmix(&h);
    h = a ^ stream;
    a = splitmix(&h);
    h = a ^ chunk;
    rng_seed(r, splitmix(&h));
}

static uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }

/* Uniform in [0, 1). */
static double uniform(rng *r)
{
    uint64_t *s = r->s, result = rotl(s[1] * 5, 7) * 9, t = s[1] << 17;
    s[2] ^= s[0];
    s[3] ^= s[1];
    s[1] ^= s[2];
    s[0] ^= s[3];
    s[2] ^= t;
    s[3] = rotl(s[3], 45);
    return (double)(result >> 11) * 0x1.0p-53;
}

typedef struct { double x, y, z; } vec;

static vec v3(double x, double y, double z) { vec v = { x, y, z }; return v; }
static double dot(vec a, vec b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static vec scale(vec a, double s) { return v3(a.x * s, a.y * s, a.z * s); }
static vec add(vec a, vec b) { return v3(a.x + b.x, a.y + b.y, a.z + b.z); }

/* An orthonormal pair perpendicular to the unit vector n. */
static void frame(vec n, vec *t, vec *b)
{
    vec a = fabs(n.x) < 0.9 ? v3(1, 0, 0) : v3(0, 1, 0);
    double d = dot(a, n), len;
    *t = add(a, scale(n, -d));
    len = sqrt(dot(*t, *t));
    *t = scale(*t, 1.0 / len);
    *b = v3(n.y * t->z - n.z * t->y, n.z * t->x - n.x * t->z, n.x * t->y - n.y * t->x);
}

/* Unpolarised Fresnel reflectance for cos_i = cos of the angle between the
 * direction towards the light and the facet normal, on its side, and the
 * complex relative index eta of the other side: the two amplitude
 * coefficients from Snell's law in complex form. */
static double fresnel(double cos_i, double complex eta)
{
    double sin2 = fmax(0.0, 1.0 - cos_i * cos_i);
    double complex cos_t = csqrt(1.0 - sin2 / (eta * eta));
    double complex rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    double complex rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    double v;
    if (cimag(eta) == 0.0 && sin2 >= creal(eta) * creal(eta))
        return 1.0; /* total internal reflection */
    v = 0.5 * (creal(rs * conj(rs)) + creal(rp * conj(rp)));
    return v > 1.0 ? 1.0 : v;
}

/* The microfacet model of every rough interface of a run (-D, -G). */
static int use_ggx, use_correlated;

/* GGX's Smith Lambda (Heitz 2014, eq. 86 with alpha^2 tan^2). */
static double ggx_lambda(double cos_v, double alpha)
{
    double c = fabs(cos_v), t2 = fmax(0.0, 1.0 - c * c) / (c * c);
    return 0.5 * (sqrt(1.0 + alpha * alpha * t2) - 1.0);
}

/* Walter et al. 2007 eq. 27: Smith G1 of Beckmann, rational approximation;
 * GGX's exact G1 = 1 / (1 + Lambda) (eq. 34). */
static double smith_g1(double cos_v, double alpha)
{
    double c = fabs(cos_v), t = sqrt(fmax(0.0, 1.0 - c * c)) / c, a;
    if (use_ggx)
        return 1.0 / (1.0 + ggx_lambda(cos_v, alpha));
    if (t == 0.0)
        return 1.0;
    a = 1.0 / (alpha * t);
    if (a >= 1.6)
        return 1.0;
    return (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a);
}

/* A Beckmann (or GGX) microfacet normal around +z (or n = +z when alpha =
 * 0): pdf D(m) |m.z| (Walter et al. 2007 eqs. 28 and 35). */
static vec sample_facet(rng *r, double alpha)
{
    double u1 = uniform(r), u2 = uniform(r), tan2, c, s, phi;
    if (alpha == 0.0)
        return v3(0, 0, 1);
    tan2 = use_ggx ? alpha * alpha * u1 / (1.0 - u1) : -alpha * alpha * log(1.0 - u1);
    c = 1.0 / sqrt(1.0 + tan2);
    s = sqrt(fmax(0.0, 1.0 - c * c));
    phi = 2.0 * PI * u2;
    return v3(s * cos(phi), s * sin(phi), c);
}

typedef struct interface {
    double eta_re, eta_im; /* relative index below / above                   */
    double alpha;          /* 0: smooth                                        */
} interface;

/* Scatter a direction of travel d off an interface whose macro normal is
 * +z, seen from the side up = (d.z < 0) (light arriving from above). A
 * conductor reflects; a dielectric reflects or refracts. Updates d and the
 * weight; returns 0 when the path dies (sampled into the wrong side). */
static int scatter_interface(const interface *s, rng *r, vec *d, double *w)
{
    int from_above = d->z < 0.0;
    double complex eta = from_above ? s->eta_re + I * s->eta_im : 1.0 / s->eta_re;
    vec wi = scale(*d, -1.0), m = sample_facet(r, s->alpha), wo;
    double cos_im, f, weight;
    int conductor = s->eta_im != 0.0;
    if (!from_above)
        m = scale(m, -1.0); /* normals face the side the light comes from */
    cos_im = dot(wi, m);
    if (cos_im <= 0.0)
        return 0;
    f = fresnel(cos_im, eta);
    weight = s->alpha == 0.0 ? 1.0 : cos_im / (fabs(wi.z) * fabs(m.z));
    if (conductor || uniform(r) < f) {
        wo = add(scale(m, 2.0 * cos_im), scale(wi, -1.0));
        if (conductor)
            weight *= f;
        if ((wo.z > 0.0) != from_above)
            return 0;
    } else {
        /* Refraction: wo = -wi / eta + (cos_i / eta - cos_t) m. */
        double e = creal(eta), sin2_t = (1.0 - cos_im * cos_im) / (e * e);
        double cos_t = sqrt(fmax(0.0, 1.0 - sin2_t));
        wo = add(scale(wi, -1.0 / e), scale(m, cos_im / e - cos_t));
        if ((wo.z < 0.0) != from_above)
            return 0;
    }
    if (s->alpha != 0.0)
        weight *= use_correlated ? 1.0 / (1.0 + ggx_lambda(wi.z, s->alpha) +
                                          ggx_lambda(wo.z, s->alpha))
                                 : smith_g1(wi.z, s->alpha) * smith_g1(wo.z, s->alpha);
    *d = wo;
    *w *= weight;
    return 1;
}

/* A new direction at cos theta from HG(g) around d. */
static vec scatter_hg(rng *r, vec d, double g)
{
    double u = uniform(r), c, s, phi;
    vec t, b;
    if (fabs(g) < 1e-6) {
        c = 1.0 - 2.0 * u;
    } else {
        double q = (1.0 - g * g) / (1.0 - g + 2.0 * g * u);
        c = (1.0 + g * g - q * q) / (2.0 * g);
    }
    c = fmax(-1.0, fmin(1.0, c));
    s = sqrt(fmax(0.0, 1.0 - c * c));
    phi = 2.0 * PI * uniform(r);
    frame(d, &t, &b);
    return add(scale(d, c), add(scale(t, s * cos(phi)), scale(b, s * sin(phi))));
}

typedef struct stack {
    interface coat;     /* eta_re == 1: none                                */
    double albedo, g, tau; /* tau == 0: no medium                           */
    int has_base;       /* 0: none, 1: the interface base, 2: Lambertian    */
    interface base;
    double base_albedo; /* of the Lambertian base                           */
} stack;

/* A Lambertian reflection into the upper hemisphere (cosine-distributed,
 * so the weight is the albedo). */
static vec scatter_lambert(rng *r)
{
    double u = uniform(r), phi = 2.0 * PI * uniform(r), s = sqrt(u);
    return v3(s * cos(phi), s * sin(phi), sqrt(fmax(0.0, 1.0 - u)));
}

typedef struct tally { double r, r2, t, t2; } tally;

/* -o: only light leaving the top within a cone around one direction is
 * counted, so that R / (solid angle x cos) estimates f there (a point
 * value, to the cone's curvature: O(half angle^2)). */
static int use_cone;
static vec cone_axis;
static double cone_cos;

/* One path: returns the weight leaving through the top (or bottom). */
static void trace(const stack *st, rng *r, double mu_i, tally *out)
{
    vec d = v3(-sqrt(fmax(0.0, 1.0 - mu_i * mu_i)), 0.0, -mu_i);
    double w = 1.0, z = 0.0; /* optical depth below the coat: 0 .. tau */
    int events = 0, has_coat = st->coat.eta_re != 1.0;
    /* The coat, from above. */
    if (has_coat) {
        if (!scatter_interface(&st->coat, r, &d, &w))
            return;
        if (d.z > 0.0)
            goto leave_top;
    }
    for (; events < MAX_EVENTS; ++events) {
        /* In the medium (possibly of thickness 0), travelling along d. */
        if (st->tau > 0.0) {
            double s = -log(1.0 - uniform(r)), zn = z - s * d.z; /* depth grows downward */
            if (zn > 0.0 && zn < st->tau) {
                z = zn;
                w *= st->albedo;
                if (w < ROULETTE) {
                    if (uniform(r) >= 0.5)
                        return;
                    w *= 2.0;
                }
                d = scatter_hg(r, d, st->g);
                continue;
            }
            z = zn <= 0.0 ? 0.0 : st->tau;
        } else {
            z = d.z < 0.0 ? st->tau : 0.0;
        }
        if (d.z > 0.0) {
            /* At the coat from below. */
            if (!has_coat)
                goto leave_top;
            if (!scatter_interface(&st->coat, r, &d, &w))
                return;
            if (d.z > 0.0)
                goto leave_top;
        } else {
            if (!st->has_base) {
                out->t += w;
                out->t2 += w * w;
                return;
            }
            if (st->has_base == 2) {
                d = scatter_lambert(r);
                w *= st->base_albedo;
            } else if (!scatter_interface(&st->base, r, &d, &w)) {
                return;
            }
        }
    }
    return;
leave_top:
    if (use_cone && dot(d, cone_axis) < cone_cos)
        return;
    out->r += w;
    out->r2 += w * w;
}

/* R(mu) and T(mu) with their standard errors from paths (rounded up to
 * whole chunks) traced from seed; stream numbers one run among several. */
static void mc_albedo(const stack *st, double mu, double paths, uint64_t seed, uint64_t stream,
                      double *R, double *se_R, double *T, double *se_T)
{
    long long chunks = (long long)ceil(paths / CHUNK), c;
    tally *part = calloc((size_t)chunks, sizeof *part);
    tally sum = { 0, 0, 0, 0 };
    double n = (double)chunks * CHUNK;
    *R = *se_R = *T = *se_T = NAN;
    if (!part)
        return;
#pragma omp parallel for schedule(dynamic)
    for (c = 0; c < chunks; ++c) {
        rng r;
        long long p;
        rng_seed_chunk(&r, seed, stream, (uint64_t)c);
        for (p = 0; p < CHUNK; ++p)
            trace(st, &r, mu, &part[c]);
    }
    for (c = 0; c < chunks; ++c) {
        sum.r += part[c].r;
        sum.r2 += part[c].r2;
        sum.t += part[c].t;
        sum.t2 += part[c].t2;
    }
    free(part);
    *R = sum.r / n;
    *T = sum.t / n;
    *se_R = sqrt(fmax(0.0, sum.r2 / n - *R * *R) / n);
    *se_T = sqrt(fmax(0.0, sum.t2 / n - *T * *T) / n);
}

#ifndef MC_STACK_NO_MAIN
static int parse_list(const char *s, double *v, int count)
{
    int k;
    char *end;
    for (k = 0; k < count; ++k) {
        v[k] = strtod(s, &end);
        if (end == s)
            return 0;
        s = end;
        if (k + 1 < count) {
            if (*s != ',')
                return 0;
            ++s;
        }
    }
    return *s == '\0';
}

static void usage(void)
{
    fprintf(stderr, "usage: mc_stack [-D beckmann|ggx] [-G separable|correlated] "
                    "[-c eta,alpha] [-m albedo,g,tau]\n"
                    "                [-b eta,k,alpha | -b diffuse,albedo | -b none] "
                    "[-o mu_o,phi_o,half_angle] [-n paths] [-s seed] mu_i...\n");
    exit(2);
}

int main(int argc, char **argv)
{
    /* Defaults: the original's coated-gold-with-scatmedium recipe, R channel. */
    stack st = { { 1.5, 0.0, 0.1 }, 0.25, 0.5, 0.5, 1,
                 { 0.14317534881908534, 3.9826674681176435, 0.1 }, 0.0 };
    double paths = 1e6;
    unsigned long long seed = 1;
    int a, first_mu;
    for (a = 1; a < argc && argv[a][0] == '-' && argv[a][1] != '\0' && argv[a][1] != '.' &&
                (argv[a][1] < '0' || argv[a][1] > '9');
         a += 2) {
        double v[3];
        if (a + 1 >= argc)
            usage();
        switch (argv[a][1]) {
        case 'c':
            if (!parse_list(argv[a + 1], v, 2))
                usage();
            st.coat.eta_re = v[0];
            st.coat.eta_im = 0.0;
            st.coat.alpha = v[1];
            break;
        case 'm':
            if (!parse_list(argv[a + 1], v, 3))
                usage();
            st.albedo = v[0];
            st.g = v[1];
            st.tau = v[2];
            break;
        case 'D':
            if (strcmp(argv[a + 1], "ggx") && strcmp(argv[a + 1], "beckmann"))
                usage();
            use_ggx = !strcmp(argv[a + 1], "ggx");
            break;
        case 'G':
            if (strcmp(argv[a + 1], "correlated") && strcmp(argv[a + 1], "separable"))
                usage();
            use_correlated = !strcmp(argv[a + 1], "correlated");
            break;
        case 'b':
            if (strcmp(argv[a + 1], "none") == 0) {
                st.has_base = 0;
                break;
            }
            if (strncmp(argv[a + 1], "diffuse,", 8) == 0) {
                if (!parse_list(argv[a + 1] + 8, v, 1) || v[0] < 0.0 || v[0] > 1.0)
                    usage();
                st.has_base = 2;
                st.base_albedo = v[0];
                break;
            }
            if (!parse_list(argv[a + 1], v, 3) || v[1] <= 0.0)
                usage();
            st.has_base = 1;
            st.base.eta_re = v[0];
            st.base.eta_im = v[1];
            st.base.alpha = v[2];
            break;
        case 'o': {
            double s_o, half;
            if (!parse_list(argv[a + 1], v, 3) || !(v[0] > 0.0 && v[0] <= 1.0) ||
                !(v[2] > 0.0 && v[2] < 30.0))
                usage();
            s_o = sqrt(fmax(0.0, 1.0 - v[0] * v[0]));
            /* The light travels along (-sin, 0, -mu): it comes from +x. */
            cone_axis = v3(s_o * cos(v[1] * PI / 180.0), s_o * sin(v[1] * PI / 180.0), v[0]);
            half = v[2] * PI / 180.0;
            cone_cos = cos(half);
            use_cone = 1;
            break;
        }
        case 'n':
            paths = strtod(argv[a + 1], NULL);
            break;
        case 's':
            seed = strtoull(argv[a + 1], NULL, 10);
            break;
        default:
            usage();
        }
    }
    if (a >= argc || !(paths >= 1.0) || (use_correlated && !use_ggx))
        usage(); /* the correlated G here is GGX's (Beckmann's G1 is rational) */
    first_mu = a;
    for (a = first_mu; a < argc; ++a) {
        double mu = strtod(argv[a], NULL), R, se_R, T, se_T;
        if (!(mu > 0.0 && mu <= 1.0))
            usage();
        mc_albedo(&st, mu, paths, (uint64_t)seed, (uint64_t)(a - first_mu), &R, &se_R, &T, &se_T);
        if (R != R)
            return 1;
        if (use_cone) {
            /* The cone's solid angle times the cosine at its axis. */
            double solid = 2.0 * PI * (1.0 - cone_cos) * cone_axis.z;
            R /= solid;
            se_R /= solid;
        }
        printf("%.6f %.7f %.7f %.7f %.7f\n", mu, R, se_R, T, se_T);
        fflush(stdout);
    }
    return 0;
}
#endif
