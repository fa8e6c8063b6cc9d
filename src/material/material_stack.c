/*
 * What a parsed stack means: the physical checks on the whole stack, the
 * per-channel parameters of each word (its descriptor's params), and the
 * header of its .bsdf file.
 *
 * Indices: a word's index of refraction is relative to the medium right
 * above it; the absolute index above a word is the product of the relative
 * indices (the descriptors' index_ratio) of the words above it.
 */
#include "material/word_table.h"

#include <string.h>

const char *ll_word_name(const ll_word *w) { return w->desc->name; }

int ll_material_is_opaque(const ll_material *m)
{
    return m && m->count > 0 && m->words[m->count - 1].desc->opaque;
}

int ll_material_is_rgb(const ll_material *m)
{
    size_t i, k;
    for (i = 0; i < m->count; ++i) {
        const ll_word *w = &m->words[i];
        if (w->desc->needs_colour && w->desc->needs_colour(w))
            return 1;
        for (k = 0; k < LL_WORD_MAX_NUMBERS; ++k)
            if (w->number[k].count == 3)
                return 1;
    }
    return 0;
}

ll_status ll_material_check_stack(const ll_material *m)
{
    size_t i;
    for (i = 0; i + 1 < m->count; ++i) {
        const ll_word *w = &m->words[i], *below = &m->words[i + 1];
        if (w->desc->opaque)
            return ll_fail(LL_ERROR_PARSE,
                           "%s:%zu:%zu: %s is opaque (no light passes through it), so it must "
                           "be the bottom layer, but line %zu puts %s below it; expected "
                           "nothing below an opaque layer",
                           m->source, w->line, w->column, ll_word_name(w), below->line,
                           ll_word_name(below));
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

double ll_word_index_ratio(const ll_material *m, size_t word, size_t c, size_t n_channels)
{
    const ll_word *w = &m->words[word];
    return w->desc->index_ratio ? w->desc->index_ratio(w, c, n_channels) : 1.0;
}

/* Absolute index of the medium right above word `word` in a channel. */
static double index_above(const ll_material *m, size_t word, size_t c, size_t n_channels)
{
    double eta = 1.0;
    size_t i;
    for (i = 0; i < word; ++i)
        eta *= ll_word_index_ratio(m, i, c, n_channels);
    return eta;
}

void ll_word_params_above(const ll_material *m, size_t word, size_t c, size_t n_channels,
                          double above, ll_word_params *out)
{
    const ll_word *w = &m->words[word];
    memset(out, 0, sizeof *out);
    out->desc = w->desc;
    w->desc->channel(w, c, n_channels, above, out);
}

void ll_word_params_get(const ll_material *m, size_t word, size_t c, size_t n_channels,
                        ll_word_params *out)
{
    ll_word_params_above(m, word, c, n_channels, index_above(m, word, c, n_channels), out);
}

void ll_material_params(const ll_material *m, size_t n_channels, ll_word_params (*params)[3])
{
    double above[3] = { 1.0, 1.0, 1.0 };
    size_t w, c;
    for (w = 0; w < m->count; ++w)
        for (c = 0; c < n_channels; ++c) {
            ll_word_params_above(m, w, c, n_channels, above[c], &params[w][c]);
            above[c] *= ll_word_index_ratio(m, w, c, n_channels);
        }
}

/* The roughness of an interface word in channel c: its "alpha" number. */
static double word_alpha(const ll_word *w, size_t c, size_t n_channels)
{
    size_t i;
    for (i = 0; i < LL_WORD_MAX_PARAMS && w->desc->params[i].key; ++i)
        if (!strcmp(w->desc->params[i].key, "alpha") && w->desc->params[i].slot >= 0)
            return ll_number_channel(&w->number[w->desc->params[i].slot], c, n_channels, 0.0);
    return 0.0;
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
        if (!w->desc->interface)
            continue;
        alpha[1] = word_alpha(w, c, n_channels);
        if (!have_top) {
            alpha[0] = alpha[1];
            have_top = 1;
        }
    }
}
