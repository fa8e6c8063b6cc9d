/*
 * The spline stencils of the probes at one node count, and the distinct
 * node pairs they hold (search/probe_pairs.c): what an interface's
 * evaluation at the probes computes series for (search/interface_probe.c).
 */
#ifndef LL_SEARCH_PROBE_PAIRS_H
#define LL_SEARCH_PROBE_PAIRS_H

#include "search/probe.h"

/* One probe pair's 4 x 4 stencil (signed node cosines and weights;
 * ll_probe_stencil). */
typedef struct ll_probe_pair_stencil {
    double no[4], wo[4], ni[4], wi[4];
    size_t io[4], ii[4]; /* node indices into the positive half */
    size_t co, ci;
} ll_probe_pair_stencil;

/* The node pairs of an evaluation's stencils, each once: probes 0.01
 * apart in mu share stencil nodes wherever the nodes are not much farther
 * apart, so the 16 slots of every probe pair name fewer distinct series,
 * the more so the fewer the nodes (docs/benchmarks.md). Ordered by
 * (block, node o, node i), the same for any thread count. */
typedef struct ll_probe_node_pairs {
    size_t count;
    double *mu_o, *mu_i;  /* [count] node cosines as the series takes them */
    size_t *of_slot;      /* [16 n_pairs] the pair of stencil slot 16 p + 4 a + b */
    const double **c;     /* [count] the series the evaluation reads */
    size_t *len;          /* [count] their terms */
    double **fresh;       /* [count] series computed and not kept by a memo */
} ll_probe_node_pairs;

/* The distinct node pairs of the stencils of set's pairs (np->count of
 * them) and which one each slot reads; c, len and fresh zeroed. */
LL_INTERNAL ll_status ll_probe_node_pairs_make(const ll_probe_set *set,
                                               const ll_probe_pair_stencil *stencils,
                                               ll_probe_node_pairs *np);
/* Free np and the fresh series it holds. */
LL_INTERNAL void ll_probe_node_pairs_free(ll_probe_node_pairs *np);

#endif
