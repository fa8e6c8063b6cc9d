/*
 * Rough interfaces: the Beckmann or GGX microfacet BSDF of Walter et al. 2007
 * (dielectric or conductor) as a layer (Jakob et al. 2014, section 6.2 and
 * the appendix; the original layerlab's microfacetFourierSeries and
 * Layer::setMicrofacet, whose BSDF and conventions this reproduces):
 * ll_layer_set_microfacet, its arguments and the public struct. The
 * series of one pair of cosines: microfacet_series.c (the method),
 * microfacet_plan.c, microfacet_filon.c, microfacet_ggx_pair.c; the model
 * and its maps: microfacet_model.c; the layer's columns and energy
 * compensation: microfacet_columns.c.
 */
#include "words/microfacet_columns.h"
#include "support/watch.h"

#include "layerlab/ll_quad.h"

static ll_status check_arguments(const ll_layer *layer, double eta_re, double eta_im,
                                 double alpha)
{
    static const char fn[] = "ll_layer_set_microfacet";
    if (!layer)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: layer is NULL", fn);
    if (!(alpha >= LL_MICROFACET_MIN_ALPHA) || !ll_is_finite(alpha))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: alpha = %g; the smallest roughness supported is "
                       "LL_MICROFACET_MIN_ALPHA = %g (smoother interfaces need more Fourier "
                       "orders than a layer can hold)",
                       fn, alpha, LL_MICROFACET_MIN_ALPHA);
    if (!ll_is_finite(eta_re) || !ll_is_finite(eta_im) || !(eta_im >= 0.0) ||
        !(eta_im > 0.0 ? eta_re >= 0.0 : eta_re > 0.0))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: eta = %g + %g i is not a valid index (need eta_im >= 0, and "
                       "eta_re > 0 for a dielectric, >= 0 for a conductor)",
                       fn, eta_re, eta_im);
    return LL_OK;
}

ll_status ll_microfacet_read(const ll_microfacet *in, ll_microfacet *out, const char *fn)
{
    ll_microfacet defaults = LL_MICROFACET_INIT;
    ll_status s;
    *out = defaults;
    if (!in)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: microfacet is NULL", fn);
    s = ll_struct_read(out, sizeof *out, in, fn, "ll_microfacet");
    if (s != LL_OK)
        return s;
    if (out->distribution != LL_MICROFACET_BECKMANN && out->distribution != LL_MICROFACET_GGX)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "%s: distribution = %d is not an ll_microfacet_distribution", fn,
                       out->distribution);
    return LL_OK;
}

/* Is every node's mirror (k +- h) exactly its negative? Then a pair's
 * mirror is the same pair of cosines, and one series serves both
 * (microfacet_columns.c); ll_layer_create accepts nodes symmetric to
 * 1e-12 only, whose mirrors would be other cosines. */
static int nodes_mirrored(const ll_layer *layer)
{
    size_t h = layer->n / 2, k;
    for (k = 0; k < h; ++k)
        if (layer->nodes[k] != -layer->nodes[k + h])
            return 0;
    return 1;
}

ll_status ll_layer_set_microfacet(ll_layer *layer, const ll_microfacet *microfacet,
                                  const ll_monitor *monitor)
{
    return ll_microfacet_set_layer(layer, microfacet, monitor, 0);
}

ll_status ll_microfacet_set_layer(ll_layer *layer, const ll_microfacet *microfacet,
                                  const ll_monitor *monitor, int every_pair)
{
    static const char fn[] = "ll_layer_set_microfacet";
    size_t n, m, h, k, n_orders_internal;
    ll_microfacet_model *mf = NULL;
    double *mu = NULL, *order0 = NULL, *ref0 = NULL, *w = NULL, *work = NULL;
    double eta_re, eta_im, alpha;
    int conserve_energy, distribution;
    ll_microfacet_job job;
    ll_watch watch;
    ll_microfacet in;
    ll_status s = layer ? ll_microfacet_read(microfacet, &in, fn)
                        : ll_fail(LL_ERROR_INVALID_ARGUMENT, "%s: layer is NULL", fn);
    if (s != LL_OK)
        return s;
    eta_re = in.eta_re;
    eta_im = in.eta_im;
    alpha = in.alpha;
    conserve_energy = in.compensate;
    n_orders_internal = in.n_orders_internal;
    distribution = in.distribution;
    s = check_arguments(layer, eta_re, eta_im, alpha);
    if (s == LL_OK)
        s = ll_watch_begin(&watch, monitor, fn);
    if (s != LL_OK)
        return s;
    if (eta_im == 0.0 && eta_re == 1.0) {
        /* index-matched: no interface */
        ll_watch_stage(&watch, "interface", 0.0, 1.0, 0);
        s = ll_watch_finish(&watch, LL_OK, fn);
        return s == LL_OK ? ll_layer_clear(layer) : s;
    }
    n = layer->n;
    m = layer->m;
    h = n / 2;
    if (n_orders_internal < m)
        n_orders_internal = m;
    job.column_memory = NULL;
    job.slots = 0;

    s = ll_microfacet_create_distribution(eta_re, eta_im, alpha, distribution,
                                          n_orders_internal, m, &mf);
    if (s != LL_OK)
        return s;
    mu = ll_alloc_array(n, sizeof(double));
    w = ll_alloc_array(h, sizeof(double));
    work = ll_alloc_array(h, 8 * sizeof(double));
    order0 = ll_calloc_array(n, n * sizeof(double));
    if (eta_im > 0.0 && conserve_energy)
        ref0 = ll_calloc_array(n, n * sizeof(double));
    if (!mu || !w || !work || !order0 || (eta_im > 0.0 && conserve_energy && !ref0))
        goto oom;
    for (k = 0; k < n; ++k)
        mu[k] = -layer->nodes[k];
    s = ll_microfacet_prepare_watched(mf, mu, n, &watch);
    if (s != LL_OK)
        goto done;
    for (k = 0; k < h; ++k)
        w[k] = 2.0 * LL_PI * layer->weights[h + k] * layer->nodes[h + k];

    job.layer = layer;
    job.mf = mf;
    job.column_doubles = ll_microfacet_column_doubles(n, m);
    job.slots = ll_get_thread_count();
    job.column_memory = ll_calloc_array(job.slots, sizeof(double *));
    if (!job.column_doubles || !job.column_memory)
        goto oom;
    job.builders = NULL;
    job.order0 = order0;
    job.ref0 = ref0;
    job.watch = &watch;
    job.w = w;
    job.work = work;
    job.eta_re = eta_re;
    job.eta_im = eta_im;
    job.conserve_energy = conserve_energy;
    job.reciprocal = !every_pair && nodes_mirrored(layer);
    s = ll_watch_stage(&watch, "interface", 0.1, 0.85, n) ? ll_watch_check(&watch, fn) : LL_OK;
    if (s == LL_OK) {
        /* ll_microfacet_finish_order0 reads order 0 (and the mirror's) whole. */
        double *dense[2];
        dense[0] = order0;
        dense[1] = ref0;
        s = ll_layer_build_by_columns(layer, n, 0, ll_microfacet_layer_column,
                                      ll_microfacet_finish_order0, &job, &job.builders, dense,
                                      ref0 ? 2 : 1, &watch, fn);
    }
    goto done;
oom:
    s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_layer_set_microfacet: out of memory for %zu nodes",
                n);
done:
    for (k = 0; job.column_memory && k < job.slots; ++k)
        ll_free(job.column_memory[k]);
    ll_free(job.column_memory);
    ll_microfacet_destroy(mf);
    ll_free(mu);
    ll_free(w);
    ll_free(work);
    ll_free(order0);
    ll_free(ref0);
    return s;
}
