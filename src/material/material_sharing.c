/*
 * The sharing of a build between its colour channels, as one walk up the
 * stack that the build (material_build.c), its progress weights and the
 * cost models (material_estimate.c, material_sweep_estimate.c) all follow,
 * so that what the models count is what the build does.
 *
 * A word whose parameters are equal in two channels (a clear coat) is one
 * layer, made for the lowest such channel; two channels whose stacks agree
 * from the bottom up to a word are one stack, the lowest channel's, until a
 * word differs (material.h, ll_level_walk).
 */
#include "material/material.h"

#include <string.h>

/* Parameters are a word layer's identity: the tables of two measured words
 * are compared by their path. */
int ll_word_params_equal(const ll_word_params *a, const ll_word_params *b)
{
    size_t k;
    if (a->desc != b->desc || a->choice != b->choice)
        return 0;
    /* Two tables of the same size are different words. */
    if ((a->file || b->file) && (!a->file || !b->file || strcmp(a->file, b->file) != 0))
        return 0;
    for (k = 0; k < LL_WORD_MAX_VALUES; ++k)
        if (a->v[k] != b->v[k])
            return 0;
    return 1;
}

/* The lowest channel whose word w is equal to channel c's (c if none). */
static size_t same_word_as(const ll_word_params (*params)[3], size_t w, size_t c)
{
    size_t d;
    for (d = 0; d < c; ++d)
        if (ll_word_params_equal(&params[w][d], &params[w][c]))
            return d;
    return c;
}

/* The lowest channel whose stack after word w is channel c's: equal words
 * on one stack below (below NULL: at the bottom, where there is none). */
static void stack_owners(const ll_word_params (*params)[3], size_t w, size_t nch,
                         const size_t *below, size_t *owner)
{
    size_t c, d;
    for (c = 0; c < nch; ++c) {
        owner[c] = c;
        for (d = 0; d < c; ++d)
            if ((!below || below[d] == below[c]) &&
                ll_word_params_equal(&params[w][d], &params[w][c])) {
                owner[c] = d;
                break;
            }
    }
}

void ll_level_walk_begin(ll_level_walk *walk, const ll_word_params (*params)[3], size_t count,
                         size_t nch)
{
    memset(walk, 0, sizeof *walk);
    walk->params = params;
    walk->count = count;
    walk->nch = nch;
    walk->word = count;
}

int ll_level_walk_next(ll_level_walk *walk)
{
    size_t c;
    if (walk->word == 0)
        return 0;
    if (walk->word < walk->count)
        memcpy(walk->below, walk->owner, sizeof walk->below);
    --walk->word;
    walk->bottom = walk->word + 1 == walk->count;
    walk->top = walk->word == 0;
    stack_owners(walk->params, walk->word, walk->nch, walk->bottom ? NULL : walk->below,
                 walk->owner);
    for (c = 0; c < walk->nch; ++c)
        walk->same[c] = same_word_as(walk->params, walk->word, c);
    return 1;
}

void ll_material_levels(const ll_word_params (*params)[3], size_t count, size_t nch,
                        ll_level_walk *levels)
{
    ll_level_walk walk;
    size_t k = 0;
    ll_level_walk_begin(&walk, params, count, nch);
    while (ll_level_walk_next(&walk))
        levels[k++] = walk;
}
