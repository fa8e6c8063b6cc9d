/*
 * The grammar of layers: adding (Grant and Hunt 1969) and doubling, the only
 * code that combines layers. Public entry points are in layerlab/ll_layer.h;
 * these are the internal extras that the material builder uses.
 */
#ifndef LL_GRAMMAR_GRAMMAR_H
#define LL_GRAMMAR_GRAMMAR_H

#include "layer/layer.h"

/* ---- doubling with progress and cancellation (for long builds) */
typedef struct ll_expand_monitor {
    const volatile int *cancel;                       /* nullable; nonzero stops */
    void (*progress)(double fraction, void *user);    /* nullable; calling thread */
    void *user;
} ll_expand_monitor;

/* ll_layer_expand with a monitor (kept for the material builder; a thin
 * adapter over ll_layer_expand_ex's watch): progress reports the fraction of
 * the doubling steps done, on the calling thread; a raised cancel flag is
 * seen by every thread between BLAS calls and stops with LL_ERROR_CANCELLED,
 * leaving the layer unchanged. */
LL_INTERNAL ll_status ll_layer_expand_monitored(ll_layer *layer, double tau,
                                                const ll_expand_monitor *monitor);

/* The doubling schedule of ll_layer_expand for nodes whose smallest |mu| is
 * min_mu: the initial thickness tau0 and the count k with tau0 2^k = tau. */
LL_INTERNAL void ll_expand_schedule(double tau, double min_mu, double *tau0, size_t *doublings);

/* How ll_layer_expand gives a medium its thickness: by doubling (the
 * reference), by the closed form of one eigendecomposition per order
 * (slab.c; an order it does not take is doubled), or by whichever the cost
 * model of slab.c says is cheaper for the node count and the doublings (the
 * default of ll_layer_expand: it depends on neither data nor threads). */
typedef enum { LL_EXPAND_CHEAPEST, LL_EXPAND_DOUBLING, LL_EXPAND_SLAB } ll_expand_method;
LL_INTERNAL ll_status ll_layer_expand_by(ll_layer *layer, double tau, ll_expand_method method);

#endif /* LL_GRAMMAR_GRAMMAR_H */
