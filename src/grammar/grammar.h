/*
 * The grammar of layers: adding (Grant and Hunt 1969), doubling and the
 * closed-form slab (slab.h), the only code that combines layers. Public entry points are in layerlab/ll_layer.h;
 * these are the internal extras that the material builder uses.
 */
#ifndef LL_GRAMMAR_GRAMMAR_H
#define LL_GRAMMAR_GRAMMAR_H

#include "layer/layer.h"
#include "words/media.h"


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

/* A medium with its thickness in one pass (slab_medium.c): the phase
 * matrix of each order goes straight into the closed-form slab and only
 * the slab is stored, the same bits as ll_layer_set_* then ll_layer_expand
 * by the slab, with half the memory. Only where ll_layer_expand would take
 * the slab (ll_medium_slab_applies: tau > 0 and the cost model); otherwise,
 * or if an order is not one the slab solves, *done = 0 and the layer is
 * unchanged (the caller takes the two steps). */
LL_INTERNAL int ll_medium_slab_applies(const ll_layer *layer, double tau);
LL_INTERNAL ll_status ll_layer_set_medium_slab(ll_layer *layer, ll_medium_kind kind,
                                               double albedo, double shape, double tau,
                                               const ll_monitor *monitor, int *done);

/* Is the h x h column-major block zero off its diagonal? (Adding and the
 * slab take a shortcut for the unscattered light of a forward-only order.) */
LL_INTERNAL int ll_block_is_diagonal(const double *x, size_t h);

#endif /* LL_GRAMMAR_GRAMMAR_H */
