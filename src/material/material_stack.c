/*
 * What a parsed stack means: the physical checks on the whole stack, the
 * per-channel parameters of each word, and the header of its .bsdf file.
 *
 * Indices: a dielectric's eta is relative to the medium right above it (the
 * issue's convention: `dielectric eta=1.5` is a coat in air). A conductor's
 * eta is the metal's own index, relative to vacuum, as tables and the
 * spectra of data/ior list it; the interface the light meets is the metal
 * against the dielectric above it, so the word's relative index is
 * eta_metal / (product of the dielectric etas above). (The original
 * recipes, e.g. recipes/coated-gold.py, pass the metal's vacuum index
 * unchanged under a coat of 1.5, which overstates the metal's contrast;
 * Fresnel's equations depend on the ratio only.)
 */
#include "material/material.h"

#include <string.h>

const char *ll_word_kind_name(ll_word_kind kind)
{
    switch (kind) {
    case LL_WORD_DIFFUSE: return "diffuse";
    case LL_WORD_DIELECTRIC: return "dielectric";
    case LL_WORD_CONDUCTOR: return "conductor";
    case LL_WORD_MEDIUM: return "medium";
    default: return "measured";
    }
}

/* Opaque words let no light through: nothing can lie below them. */
static int word_is_opaque(ll_word_kind kind)
{
    return kind == LL_WORD_DIFFUSE || kind == LL_WORD_CONDUCTOR || kind == LL_WORD_MEASURED;
}

int ll_material_is_opaque(const ll_material *m)
{
    return m->count > 0 && word_is_opaque(m->words[m->count - 1].kind);
}

int ll_material_is_rgb(const ll_material *m)
{
    size_t i;
    for (i = 0; i < m->count; ++i) {
        const ll_word *w = &m->words[i];
        if (w->named_metal || w->kind == LL_WORD_MEASURED || w->albedo.count == 3 ||
            w->eta.count == 3 || w->k.count == 3 || w->alpha.count == 3 || w->tau.count == 3 ||
            w->g.count == 3 || w->kappa.count == 3)
            return 1;
    }
    return 0;
}

ll_status ll_material_check_stack(const ll_material *m)
{
    size_t i;
    for (i = 0; i + 1 < m->count; ++i) {
        const ll_word *w = &m->words[i], *below = &m->words[i + 1];
        if (word_is_opaque(w->kind))
            return ll_fail(LL_ERROR_PARSE,
                           "%s:%zu:%zu: %s is opaque (no light passes through it), so it must "
                           "be the bottom layer, but line %zu puts %s below it; expected "
                           "nothing below an opaque layer",
                           m->source, w->line, w->column, ll_word_kind_name(w->kind),
                           below->line, ll_word_kind_name(below->kind));
    }
    return LL_OK;
}

double ll_number_channel(const ll_number *x, size_t c, size_t n_channels, double fallback)
{
    if (x->count == 0)
        return fallback;
    if (x->count == 1)
        return x->v[0];
    if (n_channels == 3)
        return x->v[c];
    /* A monochrome build of a coloured number: its luminance. */
    return LL_LUMA_R * x->v[0] + LL_LUMA_G * x->v[1] + LL_LUMA_B * x->v[2];
}

/* Absolute index of the medium right above word `word` in a channel: the
 * product of the relative indices of the dielectrics above. */
static double index_above(const ll_material *m, size_t word, size_t c, size_t n_channels)
{
    double eta = 1.0;
    size_t i;
    for (i = 0; i < word; ++i)
        if (m->words[i].kind == LL_WORD_DIELECTRIC)
            eta *= ll_number_channel(&m->words[i].eta, c, n_channels, 1.0);
    return eta;
}

void ll_word_params_get(const ll_material *m, size_t word, size_t c, size_t n_channels,
                        ll_word_params *out)
{
    const ll_word *w = &m->words[word];
    memset(out, 0, sizeof *out);
    out->kind = w->kind;
    out->phase = LL_PHASE_ISOTROPIC;
    switch (w->kind) {
    case LL_WORD_DIFFUSE:
        out->albedo = ll_number_channel(&w->albedo, c, n_channels, 0.0);
        break;
    case LL_WORD_DIELECTRIC:
        out->eta_re = ll_number_channel(&w->eta, c, n_channels, 1.0);
        out->alpha = ll_number_channel(&w->alpha, c, n_channels, 0.0);
        out->uncompensated = w->compensate.count && w->compensate.v[0] == 0.0;
        break;
    case LL_WORD_CONDUCTOR: {
        double above = index_above(m, word, c, n_channels), n, k;
        if (w->named_metal && n_channels == 1) {
            /* Monochrome: the luminance-weighted spectral averages. */
            n = w->metal_ior.eta_y;
            k = w->metal_ior.k_y;
        } else {
            n = ll_number_channel(&w->eta, c, n_channels, 1.0);
            k = ll_number_channel(&w->k, c, n_channels, 0.0);
        }
        out->eta_re = n / above;
        out->eta_im = k / above;
        out->alpha = ll_number_channel(&w->alpha, c, n_channels, 0.0);
        out->uncompensated = w->compensate.count && w->compensate.v[0] == 0.0;
        break;
    }
    case LL_WORD_MEDIUM:
        out->albedo = ll_number_channel(&w->albedo, c, n_channels, 0.0);
        out->tau = ll_number_channel(&w->tau, c, n_channels, 0.0);
        out->phase = w->phase;
        if (w->phase == LL_PHASE_HG)
            out->shape = ll_number_channel(&w->g, c, n_channels, 0.0);
        else if (w->phase == LL_PHASE_VMF)
            out->shape = ll_number_channel(&w->kappa, c, n_channels, 0.0);
        break;
    case LL_WORD_MEASURED:
        if (n_channels == 3) {
            out->weights[c] = 1.0;
        } else {
            out->weights[0] = LL_LUMA_R;
            out->weights[1] = LL_LUMA_G;
            out->weights[2] = LL_LUMA_B;
        }
        break;
    }
}

int ll_word_params_equal(const ll_word_params *a, const ll_word_params *b)
{
    return a->kind == b->kind && a->phase == b->phase && a->albedo == b->albedo &&
           a->eta_re == b->eta_re && a->eta_im == b->eta_im && a->alpha == b->alpha &&
           a->uncompensated == b->uncompensated &&
           a->tau == b->tau && a->shape == b->shape && a->weights[0] == b->weights[0] &&
           a->weights[1] == b->weights[1] && a->weights[2] == b->weights[2];
}

void ll_material_header(const ll_material *m, size_t n_channels, double *eta, double alpha[2])
{
    /* The header holds one number each: the green channel of an RGB build
     * (nearest to luminance), the only channel of a monochrome one. */
    size_t c = n_channels == 3 ? 1 : 0, i;
    int have_top = 0;
    *eta = ll_material_is_opaque(m) ? 1.0 : index_above(m, m->count, c, n_channels);
    alpha[0] = alpha[1] = 0.0;
    for (i = 0; i < m->count; ++i) {
        const ll_word *w = &m->words[i];
        if (w->kind != LL_WORD_DIELECTRIC && w->kind != LL_WORD_CONDUCTOR)
            continue;
        alpha[1] = ll_number_channel(&w->alpha, c, n_channels, 0.0);
        if (!have_top) {
            alpha[0] = alpha[1];
            have_top = 1;
        }
    }
}
