/*
 * A distributed build's shared state (layerlab/ll_distribution.h;
 * share.c): the caller's collective, and whether a failure has been agreed
 * already (after which no rank makes another exchange). One per build,
 * used on the calling thread only. The layer computations see it only as
 * the split the build enters (ll_share_split, layer/split.h).
 */
#ifndef LL_DISTRIBUTION_SHARE_H
#define LL_DISTRIBUTION_SHARE_H

#include "layer/layer.h"
#include "layerlab/ll_distribution.h"

typedef struct ll_share {
    ll_distribution dist;  /* the caller's, read up to its struct_size     */
    size_t rank, n_ranks;
    int settled;           /* a failure was agreed: no further exchanges   */
    double peak_bytes;     /* this rank's estimated peak, for messages     */
    /* What the agreements and the counts of the exchanges use, allocated
     * by ll_share_begin, so that agreeing never fails to allocate. */
    void *scratch;
    size_t *agree_bytes, *exchange_bytes, *gather_bytes; /* [2 n_ranks] each */
    unsigned char *agree_send, *agree_recv;
    uint64_t *wire;        /* [2 n_ranks]                                  */
} ll_share;

/* Start a share from a checked distribution: the scratch of the
 * agreements. If even that cannot be allocated this rank cannot take part:
 * the distribution's abort is called (if any) and LL_ERROR_OUT_OF_MEMORY
 * returned, with no agreement. ll_share_end frees it (NULL-safe). */
LL_INTERNAL ll_status ll_share_begin(ll_share *share, const ll_distribution *dist);
LL_INTERNAL void ll_share_end(ll_share *share);
/* The split of the layer computations of this rank (round robin: order k
 * is rank k mod n_ranks's), its agreements and exchanges this share's. */
LL_INTERNAL ll_split ll_share_split(ll_share *share);
/* Every rank's status, exchanged: the outcome of the whole (a real failure
 * before a cancel, the lowest rank first), with on rank 0 the failing
 * rank's message and on the others a pointer to rank 0's. Marks the share
 * settled when it is a failure. A rank must call it (once) after a failure
 * of its own before it returns, since the others wait in it. */
LL_INTERNAL ll_status ll_share_agree(ll_share *share, ll_status local);
/* The all-to-all of bytes, counts included: send_bytes[d] bytes to rank d
 * (concatenated in rank order); *recv receives what every rank sent here
 * (ll_free it), recv_bytes[s] from rank s. Only after an agreement that
 * found no failure. */
LL_INTERNAL ll_status ll_share_exchange(ll_share *share, const unsigned char *send,
                                        const size_t *send_bytes, unsigned char **recv,
                                        size_t *recv_bytes);
/* Rank 0 receives every order of the n_channels layers from their owners
 * (built under this share's split) and holds them whole; the other ranks
 * send theirs. Only after an agreement that found no failure. */
LL_INTERNAL ll_status ll_share_gather_layers(ll_share *share, ll_layer *const *layers,
                                             size_t n_channels);

#endif /* LL_DISTRIBUTION_SHARE_H */
