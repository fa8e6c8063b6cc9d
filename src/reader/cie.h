/*
 * Colour tables and the conversion of reflectance spectra to linear sRGB
 * (cie1931.c): used by the reader (spectral table files are converted to
 * RGB when opened) and by the builder (named metals' spectra, the
 * upsampling of RGB albedos to spectra). One copy, in the lowest folder
 * both reach.
 */
#ifndef LL_CIE_H
#define LL_CIE_H

#include "support/support.h"

/* The CIE 1931 2-degree observer, 1 nm steps, 360..830 nm. */
#define LL_CIE1931_COUNT 471
#define LL_CIE1931_FIRST_NM 360.0
#define LL_CIE1931_LAST_NM 830.0
LL_INTERNAL extern const double ll_cie1931_cmf[LL_CIE1931_COUNT][3];

/* CIE standard illuminant D65, relative power (100 at 560 nm), 5 nm steps
 * over 360..830 nm. */
#define LL_D65_COUNT 95
LL_INTERNAL extern const double ll_d65_spd[LL_D65_COUNT];

/* The observer at nm, linear between the 1 nm entries; 0 outside its span. */
LL_INTERNAL void ll_cie1931_at(double nm, double xyz[3]);
/* D65 at nm, linear between the 5 nm entries; 0 outside 360..830 nm. */
LL_INTERNAL double ll_d65_at(double nm);

/* CIE XYZ to linear sRGB (IEC 61966-2-1 primaries, D65 white). */
LL_INTERNAL void ll_xyz_to_linear_srgb(const double xyz[3], double rgb[3]);

/* Weights w[l][c] that turn a reflectance sampled at lambda[0 .. n) (nm,
 * ascending) into linear sRGB, rgb_c = sum_l w[l][c] v_l: the reflectance
 * lit by D65 and seen by the CIE 1931 observer (trapezoid rule on the
 * nodes), XYZ to linear sRGB, each channel normalised so that a constant
 * spectrum 1 reads (1, 1, 1); a single wavelength reads as the grey of
 * its value (w = 1). Returns 0 (w unusable) when the nodes see no light of
 * some channel (they miss the observer's span, or too much of it). */
LL_INTERNAL int ll_spectral_rgb_weights(const double *lambda, size_t n, double (*w)[3]);

#endif /* LL_CIE_H */
