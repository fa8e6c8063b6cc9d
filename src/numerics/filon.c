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
    double *cos_x, *sin_x; /* [n] cos, sin(l x1) of the first panel centre   */
    double *rot_c, *rot_s; /* [n] cos, sin(2 l h): advance by one panel      */
} filon_rule;

/* The orders first .. first + n - 1; scratch: 7 n doubles. The sines and
 * cosines of l x1 and l h come from rotations by x1 and h (one rounding
 * per order) instead of 4 n calls to sin and cos; those of the first order
 * are computed directly. */
static void rule_init(filon_rule *r, size_t n_samples, double a, double b, size_t first,
                      size_t n, double *scratch)
{
    double h = (b - a) / (double)(n_samples - 1), x1 = a + h, l0 = (double)first;
    double c1 = cos(x1), s1 = sin(x1), ch = cos(h), sh = sin(h);
    double cx = first ? cos(l0 * x1) : 1.0, sx = first ? sin(l0 * x1) : 0.0;
    double ct = first ? cos(l0 * h) : 1.0, st = first ? sin(l0 * h) : 0.0;
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
        panel_moments((double)(first + l) * h, st, ct, &sinc, &m1, &m2);
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

/* One order's step over a panel: accumulate, then advance the phase by 2h
 * (angle addition; the error grows by about one rounding per panel). */
#define FILON_STEP(sum, c, s, l)                                                   \
    do {                                                                           \
        double c_ = (c), s_ = (s);                                                 \
        (sum) += c_ * (wc[l] * ends + wm[l] * f1) + s_ * ws[l] * diff;             \
        (c) = c_ * rc[l] - s_ * rs[l];                                             \
        (s) = s_ * rc[l] + c_ * rs[l];                                             \
    } while (0)

/* The panels' sum. Four orders at a time keep their phases and sums in
 * registers over all panels (one load and store of each per four orders
 * instead of per panel); per order the operations are those of one panel
 * after the other, as order by order. */
static void accumulate(size_t panels, size_t n, const double *g, double *restrict acc,
                       const double *restrict cx, const double *restrict sx,
                       const double *restrict wc, const double *restrict ws,
                       const double *restrict wm, const double *restrict rc,
                       const double *restrict rs)
{
    size_t p, l;
    for (l = 0; l + 4 <= n; l += 4) {
        double c0 = cx[l], c1 = cx[l + 1], c2 = cx[l + 2], c3 = cx[l + 3];
        double s0 = sx[l], s1 = sx[l + 1], s2 = sx[l + 2], s3 = sx[l + 3];
        double a0 = acc[l], a1 = acc[l + 1], a2 = acc[l + 2], a3 = acc[l + 3];
        for (p = 0; p < panels; ++p) {
            double f0 = g[2 * p], f1 = g[2 * p + 1], f2 = g[2 * p + 2];
            double ends = f0 + f2, diff = f0 - f2;
            FILON_STEP(a0, c0, s0, l);
            FILON_STEP(a1, c1, s1, l + 1);
            FILON_STEP(a2, c2, s2, l + 2);
            FILON_STEP(a3, c3, s3, l + 3);
        }
        acc[l] = a0;
        acc[l + 1] = a1;
        acc[l + 2] = a2;
        acc[l + 3] = a3;
    }
    for (; l < n; ++l) {
        double c = cx[l], s = sx[l], sum = acc[l];
        for (p = 0; p < panels; ++p) {
            double f0 = g[2 * p], f1 = g[2 * p + 1], f2 = g[2 * p + 2];
            double ends = f0 + f2, diff = f0 - f2;
            FILON_STEP(sum, c, s, l);
        }
        acc[l] = sum;
    }
}

#undef FILON_STEP

/* The panel integral of the quadratic q through (f0, f1, f2) at
 * x1 - h, x1, x1 + h, with q = f1 + d1 u + d2 u^2, is
 *   cos(l x1) (f1 M0 + d2 M2) - sin(l x1) d1 M1,
 * which, collected by sample, gives the weights of filon_rule. */
void ll_filon_moments(const double *g, size_t n_samples, double a, double b,
                      size_t n_moments, double *moments, double *scratch)
{
    ll_filon_moments_from(g, n_samples, a, b, 0, n_moments, moments, scratch);
}

void ll_filon_moments_from(const double *g, size_t n_samples, double a, double b, size_t first,
                           size_t n_moments, double *moments, double *scratch)
{
    filon_rule r;
    rule_init(&r, n_samples, a, b, first, n_moments, scratch);
    accumulate(r.panels, n_moments, g, moments, r.cos_x, r.sin_x, r.w_end_c, r.w_end_s,
               r.w_mid, r.rot_c, r.rot_s);
}
