/*
 * A material at one wavelength (material_spectral.c): what a spectral
 * table file is built from, wavelength by wavelength (material_tables.c).
 */
#ifndef LL_MATERIAL_SPECTRAL_H
#define LL_MATERIAL_SPECTRAL_H

#include "material/material.h"
#include "material/rgb_spectrum.h"

typedef struct ll_spectral_plan {
    const ll_material *m;
    ll_word *words;                               /* [m->count] the view's */
    ll_rgb_spectrum (*fit)[LL_WORD_MAX_NUMBERS];  /* [m->count] per slot   */
    double worst_fit; /* the largest |rgb - rgb(fit)| of the albedo fits */
} ll_spectral_plan;

/* Check that every word of m has a spectrum (a named metal, albedos given
 * as R,G,B, every other number one value) and fit its RGB albedos.
 * LL_ERROR_INVALID_ARGUMENT naming the word and its line otherwise (fn
 * names the caller); LL_ERROR_OUT_OF_MEMORY. */
LL_INTERNAL ll_status ll_spectral_plan_init(const ll_material *m, ll_spectral_plan *p,
                                            const char *fn);
/* m at nm, as a one-channel material: *out shares everything with m but
 * its words (p's, rewritten here); valid until the next call, never
 * destroyed. */
LL_INTERNAL void ll_spectral_view(ll_spectral_plan *p, double nm, ll_material *out);
LL_INTERNAL void ll_spectral_plan_free(ll_spectral_plan *p);

#endif /* LL_MATERIAL_SPECTRAL_H */
