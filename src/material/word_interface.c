/*
 * What the two interface words (dielectric, conductor) share beyond their
 * cost model: the compensate key, which says whether the interface gets the
 * paper's energy compensation (ll_microfacet.compensate).
 * 1, the default, is the physical interface that keeps the energy lost to
 * shadowing in single scattering; 0 is single scattering only, which is what
 * renderers' microfacet BSDFs (Mitsuba's roughconductor / roughdielectric,
 * pbrt's) compute, and what a comparison with them needs.
 */
#include "material/word_table.h"

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
