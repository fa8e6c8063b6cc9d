/*
 * RGB albedos as smooth reflectance spectra, for spectral builds
 * (rgb_spectrum.c): the sigmoid of a quadratic of Jakob & Hanika 2019, "A
 * Low-Dimensional Function Space for Efficient Spectral Upsampling"
 * (Computer Graphics Forum 38(2)), fitted per colour.
 */
#ifndef LL_RGB_SPECTRUM_H
#define LL_RGB_SPECTRUM_H

#include "support/support.h"

/* rho(lambda) = S(c[0] t^2 + c[1] t + c[2]), t = (lambda - 595 nm) / 235 nm
 * (-1 at 360 nm, 1 at 830 nm), S(x) = 1/2 + x / (2 sqrt(1 + x^2)): smooth
 * and inside (0, 1) by construction. A grey albedo is the constant
 * `level` exactly (0 and 1 included), flagged by `constant`. */
typedef struct ll_rgb_spectrum {
    double c[3];
    int constant;
    double level;
} ll_rgb_spectrum;

/* The spectrum whose colour, as a reflectance lit by D65 and seen by the
 * CIE 1931 observer in linear sRGB (reader/cie.h, on the 1 nm tables), is
 * rgb (each in [0, 1]): Gauss-Newton on the CIELAB difference, from the
 * grey of the same luminance towards rgb in steps (a continuation, as the
 * paper's table is filled). *error (nullable) receives the largest
 * difference |rgb_c - rgb(fit)_c| that remains. LL_ERROR_INVALID_ARGUMENT
 * when a component is outside [0, 1] or not finite. */
LL_INTERNAL ll_status ll_rgb_spectrum_fit(const double rgb[3], ll_rgb_spectrum *out,
                                          double *error);
/* rho at nm. */
LL_INTERNAL double ll_rgb_spectrum_at(const ll_rgb_spectrum *s, double nm);
/* Its colour (as the fit measures it). */
LL_INTERNAL void ll_rgb_spectrum_colour(const ll_rgb_spectrum *s, double rgb[3]);

#endif /* LL_RGB_SPECTRUM_H */
