/*
 * A material at one wavelength (material_spectral.h). Each number becomes
 * its value at that wavelength: a named metal's n and k from its measured
 * spectra (ior.h), an albedo written as R,G,B from the smooth reflectance
 * spectrum fitted to it (rgb_spectrum.h), every other number as written
 * (one value: a dielectric's eta, a roughness, a depth are the same at
 * every wavelength). Numbers written as R,G,B that are no reflectance (an
 * index, a roughness) have no spectrum that the RGB would determine, and a
 * measured MERL table holds RGB only: those are refused rather than
 * guessed.
 */
#include "material/material_spectral.h"
#include "material/word_table.h"

#include <string.h>

/* Is slot k of word w an albedo (a reflectance in [0, 1])? */
static int is_albedo(const ll_word *w, int k)
{
    return (w->desc == &ll_word_diffuse && k == LL_DIFFUSE_ALBEDO) ||
           (w->desc == &ll_word_medium && k == LL_MEDIUM_ALBEDO);
}

static const char *slot_key(const ll_word *w, int k)
{
    size_t i;
    for (i = 0; i < LL_WORD_MAX_PARAMS && w->desc->params[i].key; ++i)
        if (w->desc->params[i].slot == k)
            return w->desc->params[i].key;
    return "a number";
}

ll_status ll_spectral_plan_init(const ll_material *m, ll_spectral_plan *p, const char *fn)
{
    size_t i;
    int k;
    ll_status s;
    memset(p, 0, sizeof *p);
    p->m = m;
    p->words = ll_alloc_array(m->count, sizeof *p->words);
    p->fit = ll_calloc_array(m->count, sizeof *p->fit);
    if (!p->words || !p->fit) {
        ll_spectral_plan_free(p);
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "%s: out of memory", fn);
    }
    for (i = 0; i < m->count; ++i) {
        const ll_word *w = &m->words[i];
        if (w->desc == &ll_word_measured) {
            ll_spectral_plan_free(p);
            return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                           "%s: %s:%zu: a measured table holds RGB values only: it has no "
                           "spectrum to build a spectral file from (write an RGB file)",
                           fn, m->source, w->line);
        }
        for (k = 0; k < LL_WORD_MAX_NUMBERS; ++k) {
            const ll_number *x = &w->number[k];
            double err;
            if (x->count != 3)
                continue;
            if (w->named_metal && (k == LL_CONDUCTOR_ETA || k == LL_CONDUCTOR_K))
                continue;
            if (!is_albedo(w, k)) {
                ll_spectral_plan_free(p);
                return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                               "%s: %s:%zu: %s's %s is given as R,G,B: a spectral file is built "
                               "at each wavelength, and three values of %s say nothing about "
                               "the spectrum between them (give one value%s, or write an RGB "
                               "file)",
                               fn, m->source, x->line ? x->line : w->line, ll_word_name(w),
                               slot_key(w, k), slot_key(w, k),
                               w->desc == &ll_word_conductor ? ", or a named metal eta=NAME "
                                                               "whose spectra are known"
                                                             : "");
            }
            s = ll_rgb_spectrum_fit(x->v, &p->fit[i][k], &err);
            if (s != LL_OK) {
                ll_spectral_plan_free(p);
                return ll_fail(s, "%s: %s:%zu: %s", fn, m->source, x->line,
                               ll_last_error_message());
            }
            if (err > p->worst_fit)
                p->worst_fit = err;
        }
    }
    return LL_OK;
}

void ll_spectral_view(ll_spectral_plan *p, double nm, ll_material *out)
{
    const ll_material *m = p->m;
    size_t i;
    int k;
    for (i = 0; i < m->count; ++i) {
        ll_word *w = &p->words[i];
        *w = m->words[i];
        if (w->named_metal) {
            double eta, kappa;
            ll_metal_ior_at(&w->metal_ior, nm, &eta, &kappa);
            /* A plain index from here on (the channel code reads the
             * numbers of a word that is no named metal). */
            w->named_metal = 0;
            w->number[LL_CONDUCTOR_ETA].v[0] = eta;
            w->number[LL_CONDUCTOR_ETA].count = 1;
            w->number[LL_CONDUCTOR_K].v[0] = kappa;
            w->number[LL_CONDUCTOR_K].count = 1;
        }
        for (k = 0; k < LL_WORD_MAX_NUMBERS; ++k)
            if (w->number[k].count == 3 && is_albedo(w, k)) {
                w->number[k].v[0] = ll_rgb_spectrum_at(&p->fit[i][k], nm);
                w->number[k].count = 1;
            }
    }
    *out = *m;
    out->words = p->words;
    out->channels = 1;
    out->n_axes = 0;
}

void ll_spectral_plan_free(ll_spectral_plan *p)
{
    ll_free(p->words);
    ll_free(p->fit);
    p->words = NULL;
    p->fit = NULL;
}
