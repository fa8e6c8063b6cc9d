/*
 * What the two interface words (dielectric, conductor) share beyond their
 * cost model: the dist key, the microfacet distribution (beckmann, the
 * default and the paper's, or ggx, Trowbridge-Reitz, what renderers and
 * material standards use), and the compensate key, which says whether the
 * interface gets the paper's energy compensation (ll_microfacet.compensate).
 * 1, the default, is the physical interface that keeps the energy lost to
 * shadowing in single scattering; 0 is single scattering only, which is what
 * renderers' microfacet BSDFs (Mitsuba's roughconductor / roughdielectric,
 * pbrt's) compute, and what a comparison with them needs.
 */
#include "material/word_table.h"
#include "words/microfacet.h"

ll_status ll_check_compensate(const ll_parser *p, const ll_word *w, const ll_token *key,
                              const ll_token *v, const ll_number *x)
{
    (void)w;
    (void)key;
    /* The range [0, 1] is checked already; a flag is one value, 0 or 1. */
    if (x->count != 1 || (x->v[0] != 0.0 && x->v[0] != 1.0))
        return ll_parse_error(p, v->begin, "%s", LL_PARAM_COMPENSATE_WHY);
    return LL_OK;
}

double ll_compensate_value(const ll_number *x)
{
    return x->count > 0 ? x->v[0] : 1.0;
}

ll_status ll_parse_distribution(const ll_parser *p, ll_word *w, const ll_token *key,
                                const ll_token *v)
{
    if (w->choice_given)
        return ll_parse_error(p, key->begin, "dist is given twice");
    if (ll_token_is(v, "beckmann"))
        w->choice = LL_DISTRIBUTION_BECKMANN;
    else if (ll_token_is(v, "ggx"))
        w->choice = LL_DISTRIBUTION_GGX;
    else
        return ll_parse_error(p, v->begin,
                              "dist: unknown microfacet distribution '%.*s'; expected beckmann "
                              "or ggx",
                              (int)v->len, v->begin);
    w->choice_given = 1;
    return LL_OK;
}

void ll_distribution_metadata(ll_text *b, const ll_word *w)
{
    if (w->choice_given)
        ll_text_append(b, ", \"dist\": \"%s\"",
                       w->choice == LL_DISTRIBUTION_GGX ? "ggx" : "beckmann");
}
