/*
 * Named metals: measured complex refractive indices n + i k (the files
 * NAME.eta.spd and NAME.k.spd of data/ior) reduced to one complex index
 * per colour channel, as the original layerlab recipes do
 * (recipes/utils/cie.py): average n and k over the visible spectrum with
 * the CIE 1931 colour-matching functions as weights, then convert the
 * averages from XYZ to linear sRGB.
 *
 * Where the spectra live is a search list (ll_ior_search_dirs); see
 * docs/material-language.md, "Named metals".
 */
#ifndef LL_IOR_H
#define LL_IOR_H

#include "support/support.h"
#include "reader/cie.h"

/* The CIE 1931 observer and the XYZ to linear sRGB matrix: reader/cie.h. */

/* ---- tabulated spectra */
typedef struct ll_spectrum {
    size_t count;   /* samples, >= 2                         */
    double *lambda; /* [count] wavelengths in nm, ascending  */
    double *value;  /* [count]                               */
} ll_spectrum;

/* Read a `wavelength value` file (`#` starts a comment line). Errors:
 * LL_ERROR_IO (cannot open), LL_ERROR_FORMAT (naming path and line). */
LL_INTERNAL ll_status ll_spectrum_read(const char *path, ll_spectrum *out);
LL_INTERNAL void ll_spectrum_free(ll_spectrum *s);

/* The colour-matching-function-weighted averages of the spectrum,
 * X = int x(l) s(l) dl / int y(l) dl (likewise Y, Z), so that a constant
 * spectrum 1 gives Y = 1. The spectrum is interpolated with Catmull-Rom
 * splines and held at its end values outside its range. */
LL_INTERNAL void ll_spectrum_to_xyz(const ll_spectrum *s, double xyz[3]);


/* ---- metals */
typedef struct ll_metal_ior {
    double eta[3], k[3]; /* per channel R, G, B                            */
    double eta_y, k_y;   /* the Y (luminance-weighted) averages: monochrome */
    /* The spectra themselves at 1 nm steps over the observer's span
     * (LL_CIE1931_FIRST_NM + j), interpolated as ll_spectrum_to_xyz reads
     * them: what a spectral build takes per wavelength. */
    double eta_nm[LL_CIE1931_COUNT], k_nm[LL_CIE1931_COUNT];
} ll_metal_ior;

/* n and k of the metal at nm (linear between the 1 nm samples, held at the
 * ends of the span). */
LL_INTERNAL void ll_metal_ior_at(const ll_metal_ior *m, double nm, double *eta, double *k);

/* The complex index of a metal from NAME.eta.spd and NAME.k.spd in dir. */
LL_INTERNAL ll_status ll_metal_ior_from_dir(const char *dir, const char *name,
                                            ll_metal_ior *out);

/* The directories searched for spectra, in order, as one string with the
 * entries separated by '\n' (malloc'ed; the caller frees): those of
 * $LAYERLAB_IOR_DIR, material_dir/ior, then LIBDIR/../share/layerlab/ior
 * where LIBDIR is the folder of the loaded liblayerlab (dladdr). material_dir
 * (nullable) is the directory of the material file being read. */
LL_INTERNAL ll_status ll_ior_search_dirs(const char *material_dir, char **out);

/* Look name up along the search list. On failure (LL_ERROR_PARSE-free:
 * returns LL_ERROR_INVALID_ARGUMENT for an unknown name, with a message
 * listing the directories tried and the names found there; LL_ERROR_FORMAT
 * or LL_ERROR_IO for a broken file). */
LL_INTERNAL ll_status ll_metal_ior_lookup(const char *name, const char *material_dir,
                                          ll_metal_ior *out);

#endif /* LL_IOR_H */
