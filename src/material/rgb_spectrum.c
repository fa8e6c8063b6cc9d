/*
 * The fit of rgb_spectrum.h. The colour of a coefficient vector is the sum
 * over the 1 nm nodes of the observer's span of rho times the weights of
 * ll_spectral_rgb_weights (D65, CIE 1931, linear sRGB, white-normalised), so
 * a constant spectrum v is the grey (v, v, v) exactly. The residual is
 * measured in CIELAB (white: the sRGB white), as Jakob & Hanika do, so that
 * dark colours are fitted to their visible precision too; its Jacobian by
 * central differences (three unknowns, three residuals: a square system).
 */
#include "material/rgb_spectrum.h"
#include "reader/cie.h"

#include <math.h>

#define CENTRE_NM 595.0
#define HALF_SPAN_NM 235.0
/* Continuation steps from the grey to the target, and Gauss-Newton
 * iterations per step (the last step runs to convergence). */
#define FIT_STEPS 8
#define FIT_ITERATIONS 40

typedef struct fit_ctx {
    double w[LL_CIE1931_COUNT][3];
} fit_ctx;

static double sigmoid(double x) { return 0.5 + x / (2.0 * sqrt(1.0 + x * x)); }

double ll_rgb_spectrum_at(const ll_rgb_spectrum *s, double nm)
{
    double t = (nm - CENTRE_NM) / HALF_SPAN_NM;
    if (s->constant)
        return s->level;
    return sigmoid((s->c[0] * t + s->c[1]) * t + s->c[2]);
}

static void weights(fit_ctx *f)
{
    double lambda[LL_CIE1931_COUNT];
    size_t j;
    for (j = 0; j < LL_CIE1931_COUNT; ++j)
        lambda[j] = LL_CIE1931_FIRST_NM + (double)j;
    ll_spectral_rgb_weights(lambda, LL_CIE1931_COUNT, f->w);
}

static void colour(const fit_ctx *f, const ll_rgb_spectrum *s, double rgb[3])
{
    size_t j;
    int c;
    rgb[0] = rgb[1] = rgb[2] = 0.0;
    for (j = 0; j < LL_CIE1931_COUNT; ++j) {
        double v = ll_rgb_spectrum_at(s, LL_CIE1931_FIRST_NM + (double)j);
        for (c = 0; c < 3; ++c)
            rgb[c] += f->w[j][c] * v;
    }
}

void ll_rgb_spectrum_colour(const ll_rgb_spectrum *s, double rgb[3])
{
    fit_ctx f;
    weights(&f);
    colour(&f, s, rgb);
}

/* Linear sRGB to CIELAB with the sRGB white (rgb (1, 1, 1)). */
static void lab(const double rgb[3], double out[3])
{
    static const double m[3][3] = { /* the inverse of the sRGB matrix */
        { 0.412453, 0.357580, 0.180423 },
        { 0.212671, 0.715160, 0.072169 },
        { 0.019334, 0.119193, 0.950227 },
    };
    double xyz[3], white[3], f[3];
    int r;
    for (r = 0; r < 3; ++r) {
        double q;
        xyz[r] = m[r][0] * rgb[0] + m[r][1] * rgb[1] + m[r][2] * rgb[2];
        white[r] = m[r][0] + m[r][1] + m[r][2];
        q = xyz[r] / white[r];
        f[r] = q > 216.0 / 24389.0 ? cbrt(q) : (24389.0 / 27.0 * q + 16.0) / 116.0;
    }
    out[0] = 116.0 * f[1] - 16.0;
    out[1] = 500.0 * (f[0] - f[1]);
    out[2] = 200.0 * (f[1] - f[2]);
}

static void residual(const fit_ctx *f, const ll_rgb_spectrum *s, const double target_lab[3],
                     double r[3])
{
    double rgb[3], l[3];
    int k;
    colour(f, s, rgb);
    lab(rgb, l);
    for (k = 0; k < 3; ++k)
        r[k] = l[k] - target_lab[k];
}

static double norm2(const double r[3]) { return r[0] * r[0] + r[1] * r[1] + r[2] * r[2]; }

/* Solve the 3 x 3 system a x = b (Cramer's rule); 0 if singular. */
static int solve3(double a[3][3], const double b[3], double x[3])
{
    double det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
                 a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
                 a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
    int c, r;
    if (!(fabs(det) > 1e-300))
        return 0;
    for (c = 0; c < 3; ++c) {
        double m[3][3];
        for (r = 0; r < 3; ++r) {
            m[r][0] = c == 0 ? b[r] : a[r][0];
            m[r][1] = c == 1 ? b[r] : a[r][1];
            m[r][2] = c == 2 ? b[r] : a[r][2];
        }
        x[c] = (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])) /
               det;
    }
    return 1;
}

/* Gauss-Newton steps towards target_lab from s, each step halved until
 * the residual falls (a step that cannot lower it ends the iteration). */
static void gauss_newton(const fit_ctx *f, ll_rgb_spectrum *s, const double target_lab[3],
                         int iterations)
{
    double r[3];
    int it;
    residual(f, s, target_lab, r);
    for (it = 0; it < iterations && norm2(r) > 1e-20; ++it) {
        double jac[3][3], step[3], neg[3], before = norm2(r), scale = 1.0;
        int k, q, improved = 0;
        for (k = 0; k < 3; ++k) {
            ll_rgb_spectrum p = *s, m = *s;
            double rp[3], rm[3], h = 1e-5 * (1.0 + fabs(s->c[k]));
            p.c[k] += h;
            m.c[k] -= h;
            residual(f, &p, target_lab, rp);
            residual(f, &m, target_lab, rm);
            for (q = 0; q < 3; ++q)
                jac[q][k] = (rp[q] - rm[q]) / (2.0 * h);
        }
        for (q = 0; q < 3; ++q)
            neg[q] = -r[q];
        if (!solve3(jac, neg, step))
            break;
        for (k = 0; k < 30 && !improved; ++k, scale *= 0.5) {
            ll_rgb_spectrum t = *s;
            double rt[3];
            for (q = 0; q < 3; ++q)
                t.c[q] += scale * step[q];
            residual(f, &t, target_lab, rt);
            if (norm2(rt) < before) {
                *s = t;
                r[0] = rt[0];
                r[1] = rt[1];
                r[2] = rt[2];
                improved = 1;
            }
        }
        if (!improved)
            break;
    }
}

ll_status ll_rgb_spectrum_fit(const double rgb[3], ll_rgb_spectrum *out, double *error)
{
    fit_ctx f;
    ll_rgb_spectrum s = { { 0.0, 0.0, 0.0 }, 0, 0.0 };
    double grey, got[3], worst = 0.0;
    int k, step;
    for (k = 0; k < 3; ++k)
        if (!(rgb[k] >= 0.0 && rgb[k] <= 1.0))
            return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                           "an albedo of (%g, %g, %g) has a component outside [0, 1]", rgb[0],
                           rgb[1], rgb[2]);
    if (rgb[0] == rgb[1] && rgb[1] == rgb[2]) {
        s.constant = 1;
        s.level = rgb[0];
        *out = s;
        if (error)
            *error = 0.0;
        return LL_OK;
    }
    weights(&f);
    /* Start: the grey of the target's luminance, a constant spectrum
     * (S^-1(v) = (2v - 1) / (2 sqrt(v (1 - v)))), kept inside (0, 1). */
    grey = 0.212671 * rgb[0] + 0.715160 * rgb[1] + 0.072169 * rgb[2];
    grey = grey < 1e-3 ? 1e-3 : grey > 1.0 - 1e-3 ? 1.0 - 1e-3 : grey;
    s.c[2] = (2.0 * grey - 1.0) / (2.0 * sqrt(grey * (1.0 - grey)));
    for (step = 1; step <= FIT_STEPS; ++step) {
        double a = (double)step / FIT_STEPS, target[3], target_lab[3];
        for (k = 0; k < 3; ++k)
            target[k] = grey + a * (rgb[k] - grey);
        lab(target, target_lab);
        gauss_newton(&f, &s, target_lab, step == FIT_STEPS ? 4 * FIT_ITERATIONS
                                                            : FIT_ITERATIONS);
    }
    colour(&f, &s, got);
    for (k = 0; k < 3; ++k)
        if (fabs(got[k] - rgb[k]) > worst)
            worst = fabs(got[k] - rgb[k]);
    *out = s;
    if (error)
        *error = worst;
    return LL_OK;
}
