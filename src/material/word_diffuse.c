/*
 * diffuse albedo=R: an opaque Lambertian base (ll_layer_set_diffuse).
 */
#include "material/word_table.h"

#include "layerlab/ll_layer.h"

/* Filling the single order 0: one entry per (mu_o, mu_i) pair. */
#define COST_DIFFUSE 1e-8 /* seconds per entry */

static void diffuse_params(const ll_word *w, size_t c, size_t n_channels, double above,
                           ll_word_params *out)
{
    (void)above;
    out->v[0] = ll_number_channel(&w->number[LL_DIFFUSE_ALBEDO], c, n_channels, 0.0);
}

/* No heuristic of its own: a Lambertian layer is exact at any resolution
 * (constant in mu, order 0 only), so the tolerance does not change it: the
 * smallest meaningful quadrature (LL_MATERIAL_MIN_NODES, what the HG fit
 * gives at g = 0) and one order. */
static ll_status diffuse_resolution(const ll_word_params *p, double tolerance, double mu_min,
                                    ll_watch *watch, size_t *n, size_t *m, double *error)
{
    (void)p;
    (void)watch;
    (void)tolerance;
    (void)mu_min;
    *error = 0.0; /* exact at any resolution */
    *n = LL_MATERIAL_MIN_NODES;
    *m = 1;
    return LL_OK;
}

static void diffuse_cost(const ll_word_params *p, size_t n, size_t m, ll_word_cost *out)
{
    (void)p;
    (void)m;
    out->serial_seconds = (double)n * (double)n * COST_DIFFUSE;
    out->work.diffuse_entries = (double)n * (double)n;
    out->orders_nonzero = 1.0;
    out->dense_orders = 0.25; /* order 0's R^t block only */
}

static ll_status diffuse_build(const ll_word_build_ctx *ctx, const ll_word *w,
                               const ll_word_params *p, ll_layer *layer)
{
    (void)w;
    return ll_layer_set_diffuse(layer, p->v[0], ctx->monitor(ctx->user, 1.0));
}

static void diffuse_metadata(ll_text *b, const ll_word *w)
{
    ll_text_number(b, "albedo", &w->number[LL_DIFFUSE_ALBEDO]);
}

const ll_word_desc ll_word_diffuse = {
    "diffuse", "diffuse albedo=0.5", "diffuse", 1, 0,
    { { "albedo", 1, LL_DIFFUSE_ALBEDO, 0.0, 1.0, 1, 1,
        "an albedo is a fraction of light, in [0, 1]", NULL, NULL } },
    NULL, NULL, NULL, diffuse_params, diffuse_resolution, diffuse_cost, diffuse_build,
    diffuse_metadata, NULL, 0, 0
};
