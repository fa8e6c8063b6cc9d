/*
 * The scaffolding of the words that fill a layer column by column
 * (microfacet interfaces, MERL BRDFs): one order builder per Fourier
 * order, the columns computed in parallel (each writes its column of every
 * order, so columns are independent and the result is the same for any
 * thread count), an optional serial step, and the layer set from the
 * builders at its single commit point.
 */
#include "layer/layer.h"

#include <stdlib.h>

ll_status ll_layer_build_by_columns(ll_layer *layer, size_t n_columns,
                                    ll_status (*column)(size_t col, void *ctx),
                                    ll_status (*finish)(void *ctx), void *ctx,
                                    ll_order_builder ***builders_slot, ll_watch *watch,
                                    const char *fn)
{
    size_t k, m = layer->m;
    ll_order_builder **builders = ll_calloc_array(m, sizeof *builders);
    ll_status s = LL_OK;
    if (!builders)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory for the %zu orders of a layer",
                       m);
    for (k = 0; k < m && s == LL_OK; ++k)
        s = ll_order_builder_create(layer->n, &builders[k]);
    *builders_slot = builders;
    if (s == LL_OK)
        s = ll_parallel_for_watched(n_columns, column, ctx, watch);
    if (s == LL_OK && finish)
        s = finish(ctx);
    /* The last report comes before the layer changes: a cancel there still
     * leaves it as it was. */
    s = ll_watch_finish(watch, s, fn);
    *builders_slot = NULL;
    if (s == LL_OK) {
        s = ll_layer_set_from_builders(layer, builders); /* takes the builders */
    } else {
        for (k = 0; k < m; ++k)
            ll_order_builder_destroy(builders[k]);
    }
    ll_free(builders);
    return s;
}
