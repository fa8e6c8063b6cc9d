/*
 * The diffuse word: an ideal Lambertian reflector of the given albedo, on
 * both sides, with no transmission. Only Fourier order 0 is non-zero.
 */
#include "layer/layer.h"
#include "support/watch.h"

#include <stdlib.h>

ll_status ll_layer_set_diffuse(ll_layer *layer, double albedo, const ll_monitor *monitor)
{
    static const char fn[] = "ll_layer_set_diffuse";
    size_t n, h, c;
    ll_order_builder *b;
    ll_order *o = NULL, **orders;
    double *column;
    ll_watch watch;
    ll_status s;

    if (!layer)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_layer_set_diffuse: layer is NULL");
    if (!(albedo >= 0.0 && albedo <= 1.0))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_layer_set_diffuse: albedo %g is outside [0, 1]", albedo);
    s = ll_watch_begin(&watch, monitor, fn);
    if (s != LL_OK)
        return s;
    n = layer->n;
    h = n / 2;
    column = ll_calloc_array(n, sizeof(double));
    orders = ll_calloc_array(layer->m, sizeof *orders);
    if (!column || !orders) {
        ll_free(column);
        ll_free(orders);
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_layer_set_diffuse: out of memory");
    }
    s = ll_order_builder_create(n, &b);
    /* O(n^2): seconds at n = 30000, so polled per column. */
    if (s == LL_OK && ll_watch_stage(&watch, "diffuse", 0.0, 1.0, n))
        s = ll_watch_check(&watch, fn);
    for (c = 0; s == LL_OK && c < n; ++c) {
        /* f = albedo / pi on the reflection blocks only (rows of the other
         * half), weighted by w |mu| pi * 2 (order 0). */
        double v = albedo * LL_INV_PI * ll_layer_surface_factor(layer, c, 0);
        size_t r;
        for (r = 0; r < n; ++r)
            column[r] = ((r < h) != (c < h)) ? v : 0.0;
        s = ll_order_builder_set_column(b, c, column, 0.0);
        ll_watch_advance(&watch, 1);
        if (s == LL_OK)
            s = ll_watch_check(&watch, fn);
    }
    /* The last report comes before the layer changes. */
    s = ll_watch_finish(&watch, s, fn);
    if (s == LL_OK)
        s = ll_order_builder_finish(b, &o);
    else
        ll_order_builder_destroy(b);
    ll_free(column);
    if (s != LL_OK) {
        ll_free(orders);
        return s;
    }
    orders[0] = o;
    ll_layer_replace_orders(layer, orders);
    ll_free(orders);
    return LL_OK;
}
