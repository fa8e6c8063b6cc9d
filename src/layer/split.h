/*
 * Which Fourier orders the layer computations of the calling thread
 * produce. One process computes all of them; one rank of a distributed
 * build (src/distribution/) computes the orders k with k mod n_ranks ==
 * rank, and the words that build a layer by columns hand each order's
 * columns to its owner through the build's exchange. The split is the
 * build's context, not the layers': the build enters it on its calling
 * thread around its layer calls, and each layer call reads it once on
 * entry (its workers get it from the call's job), so a layer holds no
 * distributed-build state.
 */
#ifndef LL_LAYER_SPLIT_H
#define LL_LAYER_SPLIT_H

#include "support/support.h"

typedef struct ll_split {
    size_t rank, n_ranks;
    void *ctx;
    /* Every rank's status, exchanged: the outcome of the whole (every rank
     * calls it once after a failure of its own). */
    ll_status (*agree)(void *ctx, ll_status local);
    /* The all-to-all of bytes: send_bytes[d] bytes to rank d (concatenated
     * in rank order); *recv (ll_free it) receives recv_bytes[s] from each
     * rank s. Only after an agreement that found no failure. */
    ll_status (*exchange)(void *ctx, const unsigned char *send, const size_t *send_bytes,
                          unsigned char **recv, size_t *recv_bytes);
} ll_split;

/* The calling thread's split: NULL (all orders) unless a distributed
 * build entered one. */
LL_INTERNAL const ll_split *ll_split_current(void);
/* Enter split (nullable) on the calling thread; returns the previous one,
 * which ll_split_leave restores. */
LL_INTERNAL const ll_split *ll_split_enter(const ll_split *split);
LL_INTERNAL void ll_split_leave(const ll_split *previous);
/* Does the split (NULL: all) compute order k? Its owner is k mod n_ranks. */
LL_INTERNAL int ll_split_owns(const ll_split *split, size_t k);

#endif /* LL_LAYER_SPLIT_H */
