/*
 * Filon quadrature of cosine moments (see filon.h).
 */
#include "numerics/filon.h"

#include <math.h>
#include <string.h>

/* The three moments of one panel [x1 - h, x1 + h] in u = phi - x1, for
 * theta = l h:
 *   integral u^0 cos(l u) du = 2 h   sinc(theta)
 *   integral u^1 sin(l u) du = 2 h^2 m1(theta), m1 = (sin - theta cos) / theta^2
 *   integral u^2 cos(l u) du = 2 h^3 m2(theta),
 *                              m2 = (theta^2 sin + 2 theta cos - 2 sin) / theta^3
 * given sin(theta), cos(theta). The closed forms lose about
 * log10(1 / theta^2) digits to cancellation (m2 ~ 1/3 from terms ~ 2/theta^2),
 * so below SMALL_THETA (at most 4e-13 relative error above it) the Taylor
 * series are summed instead: four terms reach 1e-17 there. */
#define SMALL_THETA 0.05

static void panel_moments(double theta, double s, double c, double *sinc, double *m1,
                          double *m2)
{
    if (theta > SMALL_THETA) {
        double t2 = theta * theta;
        *sinc = s / theta;
        *m1 = (s - theta * c) / t2;
        *m2 = (t2 * s + 2.0 * theta * c - 2.0 * s) / (t2 * theta);
    } else {
        /* sum_k (-1)^k theta^2k / (2k)! times 1/(2k+1), 1/((2k+1)(2k+3)),
         * 1/(2k+3) */
        double t2 = theta * theta;
        *sinc = 1.0 - t2 / 6.0 * (1.0 - t2 / 20.0 * (1.0 - t2 / 42.0));
        *m1 = theta * (1.0 / 3.0 - t2 / 30.0 * (1.0 - t2 / 28.0 * (1.0 - t2 / 54.0)));
        *m2 = 1.0 / 3.0 - t2 / 10.0 * (1.0 - t2 * (5.0 / 84.0) * (1.0 - t2 * (7.0 / 270.0)));
    }
}

/* The rule's per-order constants and the rotating panel phase. */
typedef struct filon_rule {
    size_t n, panels;
    double *w_end_c;  /* [n] h m2: weight of an end sample, times cos(l x1)   */
    double *w_end_s;  /* [n] h m1: times sin(l x1), + at the start, - at the end */
    double *w_mid;    /* [n] 2 h (sinc - m2): mid sample, times cos(l x1)      */
    double *cos_x, *sin_x; /* [n] cos, sin(l x1) of the current panel centre */
    double *rot_c, *rot_s; /* [n] cos, sin(2 l h): advance by one panel      */
} filon_rule;

/* scratch: 7 n doubles. The sines and cosines of l x1 and l h come from
 * rotations by x1 and h (one rounding per order) instead of 4 n calls to
 * sin and cos. */
static void rule_init(filon_rule *r, size_t n_samples, double a, double b, size_t n,
                      double *scratch)
{
    double h = (b - a) / (double)(n_samples - 1), x1 = a + h;
    double c1 = cos(x1), s1 = sin(x1), ch = cos(h), sh = sin(h);
    double cx = 1.0, sx = 0.0, ct = 1.0, st = 0.0;
    size_t l;
    r->n = n;
    r->panels = (n_samples - 1) / 2;
    r->w_end_c = scratch;
    r->w_end_s = scratch + n;
    r->w_mid = scratch + 2 * n;
    r->cos_x = scratch + 3 * n;
    r->sin_x = scratch + 4 * n;
    r->rot_c = scratch + 5 * n;
    r->rot_s = scratch + 6 * n;
    for (l = 0; l < n; ++l) {
        double sinc, m1, m2, next;
        panel_moments((double)l * h, st, ct, &sinc, &m1, &m2);
        r->w_end_c[l] = h * m2;
        r->w_end_s[l] = h * m1;
        r->w_mid[l] = 2.0 * h * (sinc - m2);
        r->cos_x[l] = cx;
        r->sin_x[l] = sx;
        r->rot_c[l] = (ct - st) * (ct + st);
        r->rot_s[l] = 2.0 * st * ct;
        next = cx * c1 - sx * s1;
        sx = sx * c1 + cx * s1;
        cx = next;
        next = ct * ch - st * sh;
        st = st * ch + ct * sh;
        ct = next;
    }
}

/* The panels' sum. restrict: the arrays are distinct, so the loop over l
 * vectorises. */
static void accumulate(size_t panels, size_t n, const double *g, double *restrict acc,
                       double *restrict cx, double *restrict sx, const double *restrict wc,
                       const double *restrict ws, const double *restrict wm,
                       const double *restrict rc, const double *restrict rs)
{
    size_t p, l;
    for (p = 0; p < panels; ++p) {
        double f0 = g[2 * p], f1 = g[2 * p + 1], f2 = g[2 * p + 2];
        double ends = f0 + f2, diff = f0 - f2;
        /* Accumulate, then advance the phase by 2h (angle addition; the
         * error grows by about one rounding per panel). */
        for (l = 0; l < n; ++l) {
            double c = cx[l], s = sx[l];
            acc[l] += c * (wc[l] * ends + wm[l] * f1) + s * ws[l] * diff;
            cx[l] = c * rc[l] - s * rs[l];
            sx[l] = s * rc[l] + c * rs[l];
        }
    }
}

/* The panel integral of the quadratic q through (f0, f1, f2) at
 * x1 - h, x1, x1 + h, with q = f1 + d1 u + d2 u^2, is
 *   cos(l x1) (f1 M0 + d2 M2) - sin(l x1) d1 M1,
 * which, collected by sample, gives the weights of filon_rule. */
void ll_filon_moments(const double *g, size_t n_samples, double a, double b,
                      size_t n_moments, double *moments, double *scratch)
{
    filon_rule r;
    rule_init(&r, n_samples, a, b, n_moments, scratch);
    accumulate(r.panels, n_moments, g, moments, r.cos_x, r.sin_x, r.w_end_c, r.w_end_s,
               r.w_mid, r.rot_c, r.rot_s);
}
