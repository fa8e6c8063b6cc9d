/*
 * conductor eta=NAME|n+ki|n [k=K] alpha=A [dist=beckmann|ggx]: a rough opaque metal
 * (ll_layer_set_microfacet with k > 0).
 *
 * A conductor's eta is the metal's own index, relative to vacuum, as
 * tables and measured spectra list it; the interface the light meets is the
 * metal against the dielectric above it, so the layer's relative index is
 * eta_metal / (product of the dielectric etas above). (The original
 * recipes, e.g. recipes/coated-gold.py, pass the metal's vacuum index
 * unchanged under a coat of 1.5, which overstates the metal's contrast;
 * Fresnel's equations depend on the ratio only.) A named metal (eta=Au)
 * has its per-channel indices from its spectra (material/ior.c).
 */
#include "material/word_table.h"
#include "search/probe.h"

#include "layerlab/ll_layer.h"

#include <string.h>

#define ETA LL_CONDUCTOR_ETA
#define K LL_CONDUCTOR_K
#define ALPHA LL_CONDUCTOR_ALPHA

/* Only characters of real numbers and commas (no `i` of a complex one). */
static int is_real_list(const ll_token *v)
{
    size_t i;
    for (i = 0; i < v->len; ++i)
        if (!strchr("0123456789+-.eE,", v->begin[i]))
            return 0;
    return 1;
}

/* A complex number n+ki or n-ki (the imaginary part ends in `i`). */
static int scan_complex(const ll_token *part, double *re, double *im)
{
    const char *s = part->begin;
    size_t len = part->len, i;
    if (len < 3 || s[len - 1] != 'i')
        return 0;
    /* The sign that starts the imaginary part: not the first character,
     * not right after an exponent's e. */
    for (i = len - 1; i-- > 1;) {
        if ((s[i] == '+' || s[i] == '-') && s[i - 1] != 'e' && s[i - 1] != 'E')
            break;
    }
    if (i == 0)
        return 0;
    return ll_scan_real(s, i, re) && ll_scan_real(s + i, len - 1 - i, im);
}

static void set_where(const ll_parser *p, ll_word *w, const ll_token *v)
{
    w->number[ETA].line = w->number[K].line = ll_parser_line(p);
    w->number[ETA].column = w->number[K].column = ll_parser_column(p, v->begin);
}

/* eta=NAME | n+ki[,n+ki,n+ki] | n[,n,n] (then k=...) */
static ll_status conductor_parse_eta(const ll_parser *p, ll_word *w, const ll_token *key,
                                     const ll_token *v)
{
    ll_token parts[3];
    int count, k;
    char name[sizeof w->metal];
    ll_status s;
    char c0 = v->begin[0];
    int named = (c0 >= 'A' && c0 <= 'Z') || (c0 >= 'a' && c0 <= 'z');

    if (w->number[ETA].count != 0)
        return ll_parse_error(p, key->begin, "eta is given twice");
    if (w->number[K].count && (named || !is_real_list(v)))
        return ll_parse_error(p, v->begin,
                              "eta: k= is given already; write eta=n with k=k, or "
                              "eta=n+ki or eta=NAME alone");
    if (named) {
        if (v->len + 1 > sizeof name)
            return ll_parse_error(p, v->begin, "eta: the metal name is too long");
        memcpy(name, v->begin, v->len);
        name[v->len] = '\0';
        s = ll_metal_ior_lookup(name, ll_parser_dir(p), &w->metal_ior);
        /* Out of memory is no mistake in the text: its status and message
         * stay as they are. */
        if (s == LL_ERROR_OUT_OF_MEMORY)
            return s;
        if (s != LL_OK)
            return ll_parse_error(p, v->begin, "eta=%s: %s", name, ll_last_error_message());
        memcpy(w->metal, name, sizeof name);
        w->named_metal = 1;
        w->number[ETA].count = w->number[K].count = 3;
        for (k = 0; k < 3; ++k) {
            w->number[ETA].v[k] = w->metal_ior.eta[k];
            w->number[K].v[k] = w->metal_ior.k[k];
        }
        set_where(p, w, v);
        return LL_OK;
    }
    if (is_real_list(v)) {
        s = ll_parse_number(p, key, v, &w->number[ETA]);
        if (s == LL_OK)
            s = ll_parse_check_range(p, key, v, &w->number[ETA], 0.0, 0, 1e300, 1,
                                     "the real part of a conductor's index must be > 0");
        return s;
    }
    count = ll_split_commas(v, parts);
    if (count != 1 && count != 3)
        return ll_parse_error(p, v->begin,
                              "eta: expected a metal name, one complex index n+ki or three "
                              "(R,G,B), got '%.*s'",
                              (int)v->len, v->begin);
    for (k = 0; k < count; ++k)
        if (!scan_complex(&parts[k], &w->number[ETA].v[k], &w->number[K].v[k]))
            return ll_parse_error(p, parts[k].begin,
                                  "eta: '%.*s' is not a complex index; expected n+ki such as "
                                  "0.2+3.9i",
                                  (int)parts[k].len, parts[k].begin);
    for (k = count; k < 3; ++k) {
        w->number[ETA].v[k] = w->number[ETA].v[0];
        w->number[K].v[k] = w->number[K].v[0];
    }
    w->number[ETA].count = w->number[K].count = count;
    set_where(p, w, v);
    s = ll_parse_check_range(p, key, v, &w->number[K], 0.0, 0, 1e300, 1,
                             "a conductor absorbs: the imaginary part k must be > 0 (an "
                             "interface with k = 0 is a dielectric)");
    if (s == LL_OK)
        s = ll_parse_check_range(p, key, v, &w->number[ETA], 0.0, 0, 1e300, 1,
                                 "the real part of a conductor's index must be > 0");
    return s;
}

static ll_status conductor_parse_k(const ll_parser *p, ll_word *w, const ll_token *key,
                                   const ll_token *v)
{
    ll_status s;
    if (w->named_metal)
        return ll_parse_error(p, key->begin, "k: eta=%s already gives the metal's k",
                              w->metal);
    if (w->number[K].count)
        return ll_parse_error(p, key->begin, "k is given already (by k= or by eta=n+ki)");
    s = ll_parse_number(p, key, v, &w->number[K]);
    if (s == LL_OK)
        s = ll_parse_check_range(p, key, v, &w->number[K], 0.0, 0, 1e300, 1,
                                 "a conductor absorbs: its extinction k must be > 0 (an "
                                 "interface with k = 0 is a dielectric)");
    return s;
}

static ll_status conductor_finish(const ll_parser *p, ll_word *w, const char *word_at)
{
    if (!w->named_metal && w->number[K].count == 0)
        return ll_parse_error(p, word_at,
                              "conductor needs an absorbing index: eta=NAME (e.g. Au), eta=n+ki "
                              "or eta=n with k=k");
    return LL_OK;
}

static int conductor_needs_colour(const ll_word *w) { return w->named_metal; }

static void conductor_params(const ll_word *w, size_t c, size_t n_channels, double above,
                             ll_word_params *out)
{
    double n, k;
    if (w->named_metal && n_channels == 1) {
        /* Monochrome: the luminance-weighted spectral averages. */
        n = w->metal_ior.eta_y;
        k = w->metal_ior.k_y;
    } else {
        n = ll_number_channel(&w->number[ETA], c, n_channels, 1.0);
        k = ll_number_channel(&w->number[K], c, n_channels, 0.0);
    }
    out->choice = w->choice; /* the distribution */
    out->v[ETA] = n / above;
    out->v[K] = k / above;
    out->v[ALPHA] = ll_number_channel(&w->number[ALPHA], c, n_channels, 0.0);
    out->v[LL_CONDUCTOR_COMPENSATE] = ll_compensate_value(&w->number[LL_CONDUCTOR_COMPENSATE]);
}

static ll_status conductor_resolution(const ll_word_params *p, double tolerance, double mu_min,
                                      ll_watch *watch, size_t *n, size_t *m, double *error)
{
    /* The layer conductor_build makes: with or without the compensation. */
    return ll_search_microfacet_from(p->v[ALPHA], p->v[ETA], p->v[K], p->choice,
                                     p->v[LL_CONDUCTOR_COMPENSATE] != 0.0, tolerance, mu_min,
                                     watch, n, m, error);
}

static void conductor_cost(const ll_word_params *p, size_t n, size_t m, ll_word_cost *out)
{
    ll_interface_cost(p->v[ALPHA], p->v[ETA], p->v[K], p->choice, n, m, out);
}

static ll_status conductor_build(const ll_word_build_ctx *ctx, const ll_word *w,
                                 const ll_word_params *p, ll_layer *layer)
{
    ll_microfacet mf = LL_MICROFACET_INIT;
    (void)w;
    mf.eta_re = p->v[ETA];
    mf.eta_im = p->v[K];
    mf.alpha = p->v[ALPHA];
    mf.distribution = p->choice;
    mf.compensate = p->v[LL_CONDUCTOR_COMPENSATE] != 0.0;
    return ll_layer_set_microfacet(layer, &mf, ctx->monitor(ctx->user, 1.0));
}

static void conductor_metadata(ll_text *b, const ll_word *w)
{
    if (w->named_metal) {
        ll_text_append(b, ", \"name\": ");
        ll_text_string(b, w->metal);
        ll_text_append(b, ", \"eta_luminance\": %.17g, \"k_luminance\": %.17g",
                       w->metal_ior.eta_y, w->metal_ior.k_y);
    }
    ll_text_number(b, "eta", &w->number[ETA]);
    ll_text_number(b, "k", &w->number[K]);
    ll_text_number(b, "alpha", &w->number[ALPHA]);
    ll_text_number(b, "compensate", &w->number[LL_CONDUCTOR_COMPENSATE]);
    ll_distribution_metadata(b, w);
}

const ll_word_desc ll_word_conductor = {
    "conductor", "conductor eta=Au alpha=0.1", "conductor interface", 1, 1,
    { { "eta", 1, ETA, 0, 0, 0, 0, NULL, conductor_parse_eta, NULL },
      { "k", 0, K, 0, 0, 0, 0, NULL, conductor_parse_k, NULL },
      LL_PARAM_ALPHA(ALPHA), LL_PARAM_COMPENSATE(LL_CONDUCTOR_COMPENSATE),
      LL_PARAM_DISTRIBUTION },
    conductor_finish, conductor_needs_colour, NULL, conductor_params, conductor_resolution,
    conductor_cost, conductor_build, conductor_metadata, NULL, 0, 1
};
