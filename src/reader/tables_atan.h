/*
 * atan2 for the reader's look-ups of table files (tables_eval.c): an
 * eval or pdf takes the half vector's azimuth before it can read the
 * tables, and the C library's atan2 (over a hundred instructions with
 * branches) was the longest step of that wait. This one reduces the
 * angle to |z| <= tan(pi / 8) with one division (z = a / b, or (a - b) /
 * (a + b) and pi / 4 added, for a <= b the smaller and larger of |x|,
 * |y|), takes atan(z) as z P(z^2), P of degree 9 (its coefficients the
 * Chebyshev interpolant of atan(sqrt(s)) / sqrt(s) on [0, tan^2(pi / 8)]
 * at 10 nodes, summed in Estrin's order for a short chain), and puts the
 * quadrant back. Within 4e-16 of atan(z) on the whole interval (against
 * the long-double atan at 200,001 points), and within 9e-16 (two units
 * in the last place of pi) of the C library's atan2 over 2e7 directions
 * of the circle at several scales (the test checks 1e-15), where a
 * table look-up needs the angle to far less. Both arguments zero (or
 * NaN) go to the C library's, so that the signs of zeros give what they
 * give there.
 */
#ifndef LL_TABLES_ATAN_H
#define LL_TABLES_ATAN_H

#include "support/support.h"

#include <math.h>

#define LL_TAN_PI_8 0.41421356237309503 /* tan(pi / 8) = sqrt(2) - 1 */

static inline double ll_tables_atan2(double y, double x)
{
    static const double c[10] = { 0.9999999999999982,   -0.3333333333318851,
                                  0.1999999997486304,   -0.1428571249299815,
                                  0.11111044525224971,  -0.09089465023049004,
                                  0.076729483916895,    -0.06502834935275424,
                                  0.050155419679372135, -0.025202882134599803 };
    double ax = fabs(x), ay = fabs(y), a, b, z, s, s2, s4, p, r;
    int swap, reduce;
    if (!(ax > 0.0 || ay > 0.0))
        return atan2(y, x);
    swap = ay > ax;
    a = swap ? ax : ay;
    b = swap ? ay : ax;
    /* Above tan(pi / 8): atan(a / b) = pi / 4 + atan((a - b) / (a + b)). */
    reduce = a > b * LL_TAN_PI_8;
    z = (reduce ? a - b : a) / (reduce ? a + b : b);
    s = z * z;
    s2 = s * s;
    s4 = s2 * s2;
    p = (c[0] + c[1] * s) + s2 * (c[2] + c[3] * s) +
        s4 * ((c[4] + c[5] * s) + s2 * (c[6] + c[7] * s) + s4 * (c[8] + c[9] * s));
    r = z * p + (reduce ? LL_PI / 4 : 0.0);
    r = swap ? LL_PI / 2 - r : r;
    r = x < 0.0 ? LL_PI - r : r;
    return copysign(r, y);
}

#endif /* LL_TABLES_ATAN_H */
