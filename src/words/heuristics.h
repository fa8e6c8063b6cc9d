/*
 * The fits of the original layerlab (heuristics.c): an instant resolution
 * for a rough interface and a Henyey-Greenstein medium, the public
 * ll_heuristic_* and the first guess of the tolerance searches
 * (search/resolution.c).
 */
#ifndef LL_WORDS_HEURISTICS_H
#define LL_WORDS_HEURISTICS_H

#include <stddef.h>
#include "support/support.h"

/* What ll_heuristic_microfacet and ll_heuristic_henyey_greenstein return
 * (their argument checks and messages). */
LL_INTERNAL ll_status ll_fit_microfacet(double alpha, double eta_re, double eta_im,
                                        size_t *n_nodes, size_t *n_orders);
LL_INTERNAL ll_status ll_fit_henyey_greenstein(double g, size_t *n_nodes, size_t *n_orders);

#endif /* LL_WORDS_HEURISTICS_H */
