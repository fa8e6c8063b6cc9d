/*
 * dielectric eta=E alpha=A [dist=beckmann|ggx]: a rough dielectric interface
 * (ll_layer_set_microfacet with k = 0). eta is relative to the medium right
 * above (`dielectric eta=1.5` is a coat in air), and every word below sees
 * the product of the dielectric indices above it.
 */
#include "material/word_table.h"
#include "search/probe.h"

#include "layerlab/ll_layer.h"

static ll_status dielectric_check_eta(const ll_parser *p, const ll_word *w,
                                      const ll_token *key, const ll_token *v,
                                      const ll_number *x)
{
    int k;
    (void)w;
    (void)key;
    for (k = 0; k < x->count; ++k)
        if (x->v[k] == 1.0)
            return ll_parse_error(p, v->begin,
                                  "eta=1 is no interface (nothing reflects or refracts); "
                                  "remove the line or use another eta");
    return LL_OK;
}

static double dielectric_index_ratio(const ll_word *w, size_t c, size_t n_channels)
{
    return ll_number_channel(&w->number[LL_DIELECTRIC_ETA], c, n_channels, 1.0);
}

static void dielectric_params(const ll_word *w, size_t c, size_t n_channels, double above,
                              ll_word_params *out)
{
    (void)above;
    out->choice = w->choice; /* the distribution */
    out->v[0] = ll_number_channel(&w->number[LL_DIELECTRIC_ETA], c, n_channels, 1.0);
    out->v[1] = ll_number_channel(&w->number[LL_DIELECTRIC_ALPHA], c, n_channels, 0.0);
    out->v[2] = ll_compensate_value(&w->number[LL_DIELECTRIC_COMPENSATE]);
}

static ll_status dielectric_resolution(const ll_word_params *p, double tolerance,
                                       double mu_min, ll_watch *watch, size_t *n, size_t *m,
                                       double *error)
{
    /* The layer dielectric_build makes: with or without the compensation. */
    return ll_search_microfacet_from(p->v[1], p->v[0], 0.0, p->choice, p->v[2] != 0.0,
                                     tolerance, mu_min, watch, n, m, error);
}

static void dielectric_cost(const ll_word_params *p, size_t n, size_t m, ll_word_cost *out)
{
    ll_interface_cost(p->v[1], p->v[0], 0.0, p->choice, n, m, out);
}

static ll_status dielectric_build(const ll_word_build_ctx *ctx, const ll_word *w,
                                  const ll_word_params *p, ll_layer *layer)
{
    ll_microfacet mf = LL_MICROFACET_INIT;
    (void)w;
    mf.eta_re = p->v[0];
    mf.eta_im = 0.0;
    mf.alpha = p->v[1];
    mf.distribution = p->choice;
    mf.compensate = p->v[2] != 0.0;
    return ll_layer_set_microfacet(layer, &mf, ctx->monitor(ctx->user, 1.0));
}

static void dielectric_metadata(ll_text *b, const ll_word *w)
{
    ll_text_number(b, "eta", &w->number[LL_DIELECTRIC_ETA]);
    ll_text_number(b, "alpha", &w->number[LL_DIELECTRIC_ALPHA]);
    ll_text_number(b, "compensate", &w->number[LL_DIELECTRIC_COMPENSATE]);
    ll_distribution_metadata(b, w);
}

const ll_word_desc ll_word_dielectric = {
    "dielectric", "dielectric eta=1.5 alpha=0.1", "dielectric interface", 0, 1,
    { { "eta", 1, LL_DIELECTRIC_ETA, 0.0, 1e300, 0, 1, "an index of refraction must be > 0",
        NULL, dielectric_check_eta },
      LL_PARAM_ALPHA(LL_DIELECTRIC_ALPHA), LL_PARAM_COMPENSATE(LL_DIELECTRIC_COMPENSATE),
      LL_PARAM_DISTRIBUTION },
    NULL, NULL, dielectric_index_ratio, dielectric_params, dielectric_resolution,
    dielectric_cost, dielectric_build, dielectric_metadata, NULL, 0, 1
};
