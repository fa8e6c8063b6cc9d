/*
 * medium albedo=R tau=T [g=G | phase=isotropic | phase=vmf kappa=K]: a
 * scattering slab of optical thickness tau, index-matched to the medium
 * above (ll_layer_set_henyey_greenstein / _isotropic / _von_mises_fisher,
 * then ll_layer_expand doubles it to tau).
 */
#include "material/word_table.h"
#include "grammar/grammar.h"
#include "search/probe.h"

#include "layerlab/ll_layer.h"

#include <math.h>

#define ALBEDO LL_MEDIUM_ALBEDO
#define TAU LL_MEDIUM_TAU
#define G LL_MEDIUM_G
#define KAPPA LL_MEDIUM_KAPPA

/* The resolution heuristics' cap (docs/material-language.md, "Settings"):
 * the HG fit asks for 8.6 / (1 - |g|) nodes, 860 nodes and 539 orders at
 * |g| = 0.99 and without bound beyond. Above the cap a medium needs its
 * resolution given with `set` (or the options). */
#define G_MAX 0.99
/* The vMF concentration whose mean cosine coth(kappa) - 1/kappa is G_MAX. */
#define KAPPA_MAX 100.0

/* Seconds per phase-function entry (one thread; measured: the HG phase
 * matrices of 196 nodes x 267 orders took 0.031 s each): each order's n x n
 * matrix of the phase function's Fourier coefficients. */
#define COST_PHASE 7e-9

static ll_status medium_parse_phase(const ll_parser *p, ll_word *w, const ll_token *key,
                                    const ll_token *v)
{
    if (w->choice_given)
        return ll_parse_error(p, key->begin, "phase is given twice");
    if (ll_token_is(v, "isotropic"))
        w->choice = LL_PHASE_ISOTROPIC;
    else if (ll_token_is(v, "hg") || ll_token_is(v, "henyey-greenstein"))
        w->choice = LL_PHASE_HG;
    else if (ll_token_is(v, "vmf") || ll_token_is(v, "von-mises-fisher"))
        w->choice = LL_PHASE_VMF;
    else
        return ll_parse_error(p, v->begin,
                              "phase: unknown phase function '%.*s'; expected isotropic, hg "
                              "or vmf",
                              (int)v->len, v->begin);
    w->choice_given = 1;
    return LL_OK;
}

static ll_status medium_finish(const ll_parser *p, ll_word *w, const char *word_at)
{
    if (w->number[G].count && w->choice_given && w->choice != LL_PHASE_HG)
        return ll_parse_error(p, word_at, "g= belongs to phase=hg, not to the phase given");
    if (w->number[KAPPA].count && w->choice != LL_PHASE_VMF)
        return ll_parse_error(p, word_at, "kappa= needs phase=vmf");
    if (w->choice == LL_PHASE_VMF && w->number[KAPPA].count == 0)
        return ll_parse_error(p, word_at, "phase=vmf needs kappa=... (concentration >= 0)");
    if (w->choice == LL_PHASE_HG && w->number[G].count == 0)
        return ll_parse_error(p, word_at, "phase=hg needs g=... (asymmetry in (-1, 1))");
    if (w->number[G].count && !w->choice_given)
        w->choice = LL_PHASE_HG;
    return LL_OK;
}

static void medium_params(const ll_word *w, size_t c, size_t n_channels, double above,
                          ll_word_params *out)
{
    (void)above;
    out->choice = w->choice;
    out->v[ALBEDO] = ll_number_channel(&w->number[ALBEDO], c, n_channels, 0.0);
    out->v[TAU] = ll_number_channel(&w->number[TAU], c, n_channels, 0.0);
    if (w->choice == LL_PHASE_HG)
        out->v[LL_MEDIUM_SHAPE] = ll_number_channel(&w->number[G], c, n_channels, 0.0);
    else if (w->choice == LL_PHASE_VMF)
        out->v[LL_MEDIUM_SHAPE] = ll_number_channel(&w->number[KAPPA], c, n_channels, 0.0);
}

/* The von Mises-Fisher lobe's mean cosine coth(kappa) - 1/kappa: the HG
 * asymmetry of the same width, for the resolution heuristic. */
static double vmf_mean_cosine(double kappa)
{
    if (kappa < 1e-4)
        return kappa / 3.0;
    return 1.0 / tanh(kappa) - 1.0 / kappa;
}

static ll_status medium_resolution(const ll_word_params *p, double tolerance, double mu_min,
                                   ll_watch *watch, size_t *n, size_t *m, double *error)
{
    double shape = p->v[LL_MEDIUM_SHAPE];
    if (p->choice == LL_PHASE_ISOTROPIC) {
        /* Constant phase function: one order and the smallest meaningful
         * quadrature (the HG fit at g = 0). Not searched: the phase layer
         * of HG at g = 0 varies by 0.3% between 80 and 160 nodes (its
         * exact energy normalisation per node), which would ask for 80
         * nodes for a function the layers hold exactly. */
        (void)tolerance;
        (void)mu_min;
        (void)watch;
        *error = 0.0; /* exact at any resolution */
        *n = LL_MATERIAL_MIN_NODES;
        *m = 1;
        return LL_OK;
    }
    if (p->choice == LL_PHASE_HG && !(fabs(shape) <= G_MAX))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "g=%g is beyond what the resolution heuristic supports: the largest "
                       "is |g| = %g (860 nodes, 539 orders), and g=%g would ask for %.3g "
                       "nodes; give the resolution yourself (set nodes=N orders=M, or "
                       "llbuild --nodes --orders)",
                       shape, G_MAX, shape, 8.6 / (1.0 - fabs(shape)));
    if (p->choice == LL_PHASE_VMF && !(shape <= KAPPA_MAX))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "kappa=%g is beyond what the resolution heuristic supports: the "
                       "largest is kappa = %g (mean cosine %g, 860 nodes, 539 orders); give "
                       "the resolution yourself (set nodes=N orders=M, or llbuild --nodes "
                       "--orders)",
                       shape, KAPPA_MAX, G_MAX);
    return ll_search_henyey_greenstein(p->choice == LL_PHASE_HG ? shape : vmf_mean_cosine(shape),
                                       tolerance, mu_min, watch, n, m, error);
}

/* Measured (docs/material-language.md, "Estimates"): an HG medium's
 * orders hold values down to |g|^l ~ 1e-12 and beyond (the doubling fills
 * them), about 2.7 * 27.6 / -ln|g| orders but no more than about 1.7 n
 * (the time of its doublings stops growing past g = 0.7 at n = 100, and
 * at n = 56 it fills 96 orders at g = 0.6); its stored values are about
 * 8 + 5 / (1 - |g|) dense orders (n = 100, m = 400, tau = 1: 14.7, 18.6,
 * 23.9, 28, 60 at g = 0.3, 0.5, 0.7, 0.8, 0.9). A vMF lobe counts as the
 * HG lobe of its mean cosine; an isotropic medium holds order 0. */
static void medium_cost(const ll_word_params *p, size_t n, size_t m, ll_word_cost *out)
{
    double g = 0.0, nonzero = 1.0, dense = 1.0;
    if (p->choice != LL_PHASE_ISOTROPIC) {
        double shape = p->v[LL_MEDIUM_SHAPE];
        g = p->choice == LL_PHASE_HG ? fmin(fabs(shape), G_MAX)
                                     : vmf_mean_cosine(fmin(shape, KAPPA_MAX));
        if (g > 1e-6) {
            nonzero = 2.7 * 27.6 / -log(g);
            dense = 8.0 + 5.0 / (1.0 - g);
        }
    }
    if (nonzero > 1.7 * (double)n)
        nonzero = 1.7 * (double)n;
    if (nonzero > (double)m)
        nonzero = (double)m;
    if (dense > nonzero)
        dense = nonzero;
    out->parallel_seconds = (double)n * (double)n * nonzero * COST_PHASE;
    out->work.phase_entries = (double)n * (double)n * nonzero;
    out->items = (size_t)nonzero;
    out->doublings = p->v[TAU] > 0.0 ? ll_doubling_count(p->v[TAU], 1.0) : 0;
    out->orders_nonzero = nonzero;
    out->dense_orders = dense;
    /* Per thread, where the slab gives the thickness in one pass: an order's
     * phase matrix with its Legendre values (n^2 + 2 n K, at most 3 n^2)
     * and the slab's 11 h x h matrices (grammar/slab_medium.c). */
    if (p->v[TAU] > 0.0)
        out->thread_bytes = 8.0 * (double)n * (double)n * (3.0 + 11.0 / 4.0);
}

static ll_status medium_build(const ll_word_build_ctx *ctx, const ll_word *w,
                              const ll_word_params *p, ll_layer *layer)
{
    const ll_monitor *phase;
    ll_status s;
    (void)w;
    /* Where the slab gives the thickness, in one pass with the phase
     * matrices (half the memory of two; grammar.h), carrying the whole
     * cost; else the phase matrices show as their own stage and the
     * doublings carry the medium's cost. */
    if (ll_medium_slab_applies(layer, p->v[TAU])) {
        int done;
        ll_medium_kind kind = p->choice == LL_PHASE_HG    ? LL_MEDIUM_HG
                              : p->choice == LL_PHASE_VMF ? LL_MEDIUM_VMF
                                                          : LL_MEDIUM_ISOTROPIC;
        s = ll_layer_set_medium_slab(layer, kind, p->v[ALBEDO], p->v[LL_MEDIUM_SHAPE],
                                     p->v[TAU], ctx->monitor(ctx->user, 1.0), &done);
        if (s != LL_OK || done)
            return s;
    }
    phase = ctx->monitor(ctx->user, 0.0);
    if (p->choice == LL_PHASE_HG)
        s = ll_layer_set_henyey_greenstein(layer, p->v[ALBEDO], p->v[LL_MEDIUM_SHAPE], phase);
    else if (p->choice == LL_PHASE_VMF)
        s = ll_layer_set_von_mises_fisher(layer, p->v[ALBEDO], p->v[LL_MEDIUM_SHAPE], phase);
    else
        s = ll_layer_set_isotropic(layer, p->v[ALBEDO], phase);
    if (s == LL_OK)
        s = ctx->expand(ctx->user, layer, p->v[TAU]);
    return s;
}

static void medium_metadata(ll_text *b, const ll_word *w)
{
    static const char *const phase_names[] = { "isotropic", "hg", "vmf" };
    ll_text_number(b, "albedo", &w->number[ALBEDO]);
    ll_text_number(b, "tau", &w->number[TAU]);
    ll_text_append(b, ", \"phase\": \"%s\"", phase_names[w->choice]);
    ll_text_number(b, "g", &w->number[G]);
    ll_text_number(b, "kappa", &w->number[KAPPA]);
}

const ll_word_desc ll_word_medium = {
    "medium", "medium albedo=0.9 tau=1 g=0.5", "medium", 0, 0,
    { { "albedo", 1, ALBEDO, 0.0, 1.0, 1, 1, "an albedo is a fraction of light, in [0, 1]",
        NULL, NULL },
      { "tau", 1, TAU, 0.0, 1e12, 1, 1, "the optical thickness tau must be in [0, 1e12]", NULL,
        NULL },
      { "g", 0, G, -1.0, 1.0, 0, 0, "the Henyey-Greenstein asymmetry g must be in (-1, 1)",
        NULL, NULL },
      { "phase", 0, -1, 0, 0, 0, 0, NULL, medium_parse_phase, NULL },
      { "kappa", 0, KAPPA, 0.0, 1e4, 1, 1,
        "the von Mises-Fisher concentration kappa must be in [0, 10000]", NULL, NULL } },
    medium_finish, NULL, NULL, medium_params, medium_resolution, medium_cost, medium_build,
    medium_metadata, NULL, 1u << LL_MEDIUM_SHAPE, 0
};
