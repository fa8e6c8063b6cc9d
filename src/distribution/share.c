/*
 * The exchanges of a distributed build (layerlab/ll_distribution.h): the
 * agreement on the outcome, the all-to-all of bytes and the gathering of
 * the finished layers on rank 0, all over the caller's one collective,
 * alltoallv.
 *
 * The rule that keeps every rank in step: each exchange is preceded by an
 * agreement; a rank that fails makes no exchange, only that agreement, and
 * once a failure is agreed no rank makes any further call. So the calls
 * match one for one on every rank whatever fails where.
 */
#include "distribution/share.h"

#include <stdio.h>
#include <string.h>

/* A failing rank's message travels to rank 0 in a fixed-size slot, so
 * that every count of the agreement is known beforehand. */
#define MESSAGE_BYTES 1024
#define STATUS_BYTES sizeof(int32_t)

static ll_status split_agree(void *ctx, ll_status local)
{
    return ll_share_agree(ctx, local);
}

static ll_status split_exchange(void *ctx, const unsigned char *send, const size_t *send_bytes,
                                unsigned char **recv, size_t *recv_bytes)
{
    return ll_share_exchange(ctx, send, send_bytes, recv, recv_bytes);
}

ll_split ll_share_split(ll_share *share)
{
    ll_split split;
    split.rank = share->rank;
    split.n_ranks = share->n_ranks;
    split.ctx = share;
    split.agree = split_agree;
    split.exchange = split_exchange;
    return split;
}

static ll_status call_alltoallv(ll_share *share, const void *send, const size_t *send_bytes,
                                void *recv, const size_t *recv_bytes)
{
    ll_status s = share->dist.alltoallv(share->dist.user, send, send_bytes, recv, recv_bytes);
    if (s != LL_OK)
        return ll_fail(s, "the distribution's alltoallv failed on rank %zu of %zu (%s)",
                       share->rank, share->n_ranks, ll_status_string(s));
    return LL_OK;
}

ll_status ll_share_begin(ll_share *share, const ll_distribution *dist)
{
    size_t n = (size_t)dist->n_ranks, rank = (size_t)dist->rank, bytes = 0, part;
    size_t counts = 6 * n * sizeof(size_t), wire = 2 * n * sizeof(uint64_t);
    size_t agree_send = n * STATUS_BYTES + MESSAGE_BYTES;
    size_t agree_recv = n * (rank == 0 ? STATUS_BYTES + MESSAGE_BYTES : STATUS_BYTES);
    unsigned char *p;
    memset(share, 0, sizeof *share);
    share->dist = *dist;
    share->rank = rank;
    share->n_ranks = n;
    /* (n is an int: none of these sums can overflow a size_t.) */
    part = counts + wire;
    bytes = part + agree_send + agree_recv;
    share->scratch = p = ll_malloc(bytes);
    if (!p) {
        ll_status s = ll_fail(LL_ERROR_OUT_OF_MEMORY,
                              "rank %zu of %zu: out of memory for the %zu bytes that agreeing "
                              "with the other ranks needs; this rank cannot take part (end "
                              "the job)",
                              rank, n, bytes);
        if (dist->abort)
            dist->abort(dist->user, s);
        return s;
    }
    share->agree_bytes = (size_t *)(void *)p;
    share->exchange_bytes = share->agree_bytes + 2 * n;
    share->gather_bytes = share->exchange_bytes + 2 * n;
    share->wire = (uint64_t *)(void *)(p + counts);
    share->agree_send = p + part;
    share->agree_recv = p + part + agree_send;
    return LL_OK;
}

void ll_share_end(ll_share *share)
{
    if (share) {
        ll_free(share->scratch);
        share->scratch = NULL;
    }
}

ll_status ll_share_agree(ll_share *share, ll_status local)
{
    size_t n = share->n_ranks, r, decider;
    size_t to_root = STATUS_BYTES + MESSAGE_BYTES;
    size_t *send_bytes = share->agree_bytes, *recv_bytes = send_bytes + n;
    unsigned char *p = share->agree_send, *recv = share->agree_recv;
    char message[MESSAGE_BYTES];
    int32_t mine = (int32_t)local, status, deciding = LL_OK;
    ll_status s;

    memset(message, 0, sizeof message);
    if (local != LL_OK) {
        if (local == LL_ERROR_OUT_OF_MEMORY && share->peak_bytes > 0.0)
            snprintf(message, sizeof message, "%s (estimated peak of this rank: %.0f MiB)",
                     ll_last_error_message(), share->peak_bytes / 1048576.0);
        else
            snprintf(message, sizeof message, "%s", ll_last_error_message());
    }
    for (r = 0; r < n; ++r) {
        send_bytes[r] = r == 0 ? to_root : STATUS_BYTES;
        recv_bytes[r] = share->rank == 0 ? to_root : STATUS_BYTES;
        memcpy(p, &mine, STATUS_BYTES);
        p += STATUS_BYTES;
        if (r == 0) {
            memcpy(p, message, MESSAGE_BYTES);
            p += MESSAGE_BYTES;
        }
    }
    s = call_alltoallv(share, share->agree_send, send_bytes, recv, recv_bytes);
    if (s != LL_OK)
        goto done;
    /* The outcome: a real failure before a cancel (which another rank's
     * failure or a signal to every rank may have caused), a lower rank
     * before a higher one. */
    decider = n;
    for (r = 0; r < n; ++r) {
        memcpy(&status, recv + r * recv_bytes[0], STATUS_BYTES);
        if (status != LL_OK && (decider == n || (deciding == LL_ERROR_CANCELLED &&
                                                  status != LL_ERROR_CANCELLED))) {
            decider = r;
            deciding = status;
        }
    }
    if (decider == n) {
        s = LL_OK;
    } else if (share->rank == 0) {
        char *text = (char *)recv + decider * to_root + STATUS_BYTES;
        text[MESSAGE_BYTES - 1] = '\0';
        s = n == 1 ? ll_fail(deciding, "%s", text)
                   : ll_fail(deciding, "rank %zu of %zu: %s", decider, n, text);
    } else {
        s = ll_fail(deciding, "rank %zu of %zu failed (%s); rank 0 reports why", decider, n,
                    ll_status_string(deciding));
    }
done:
    if (s != LL_OK)
        share->settled = 1;
    return s;
}

ll_status ll_share_exchange(ll_share *share, const unsigned char *send,
                            const size_t *send_bytes, unsigned char **recv, size_t *recv_bytes)
{
    size_t n = share->n_ranks, r, total = 0, *ones = share->exchange_bytes;
    uint64_t *counts = share->wire;
    ll_status s;

    *recv = NULL;
    /* First the counts (one uint64 each way), then the bytes. */
    for (r = 0; r < n; ++r) {
        counts[r] = (uint64_t)send_bytes[r];
        ones[r] = sizeof(uint64_t);
    }
    s = call_alltoallv(share, counts, ones, counts + n, ones);
    for (r = 0; r < n && s == LL_OK; ++r) {
        recv_bytes[r] = (size_t)counts[n + r];
        if ((uint64_t)recv_bytes[r] != counts[n + r] ||
            !ll_size_add(total, recv_bytes[r], &total))
            s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "rank %zu would receive too many bytes",
                        share->rank);
    }
    if (s == LL_OK) {
        *recv = ll_malloc(total ? total : 1);
        if (!*recv)
            s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "out of memory receiving %.0f MiB of orders",
                        (double)total / 1048576.0);
    }
    /* Every rank has its receive buffer, or none goes on. */
    s = ll_share_agree(share, s);
    if (s == LL_OK)
        s = call_alltoallv(share, send, send_bytes, *recv, recv_bytes);
    if (s != LL_OK) {
        ll_free(*recv);
        *recv = NULL;
    }
    return s;
}

/* This rank's orders of the layers, one after the other (channel, then
 * order), to rank 0; rank 0 sends nothing. */
static ll_status pack_owned(const ll_share *share, ll_layer *const *layers, size_t n_channels,
                            unsigned char **out, size_t *bytes)
{
    size_t c, k, total = 0;
    unsigned char *p;
    *out = NULL;
    *bytes = 0;
    if (share->rank == 0)
        return LL_OK;
    for (c = 0; c < n_channels; ++c)
        for (k = share->rank; k < layers[c]->m; k += share->n_ranks)
            if (!ll_size_add(total, ll_order_packed_bytes(layers[c]->orders[k]), &total))
                return ll_fail(LL_ERROR_OUT_OF_MEMORY, "the layers are too large to send");
    p = *out = ll_malloc(total ? total : 1);
    if (!p)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY,
                       "rank %zu: out of memory packing %.0f MiB of orders for rank 0",
                       share->rank, (double)total / 1048576.0);
    for (c = 0; c < n_channels; ++c)
        for (k = share->rank; k < layers[c]->m; k += share->n_ranks)
            p = ll_order_pack(layers[c]->orders[k], p);
    *bytes = total;
    return LL_OK;
}

ll_status ll_share_gather_layers(ll_share *share, ll_layer *const *layers, size_t n_channels)
{
    size_t n = share->n_ranks, r, c, k, *send_bytes, *recv_bytes, packed = 0;
    unsigned char *send = NULL, *recv = NULL;
    const unsigned char *p, *end;
    ll_status s;

    send_bytes = share->gather_bytes;
    recv_bytes = send_bytes + n;
    memset(send_bytes, 0, n * sizeof *send_bytes);
    s = pack_owned(share, layers, n_channels, &send, &packed);
    send_bytes[0] = packed;
    /* A failure to pack must be agreed before the exchange. */
    s = ll_share_agree(share, s);
    if (s == LL_OK)
        s = ll_share_exchange(share, send, send_bytes, &recv, recv_bytes);
    ll_free(send);
    send = NULL;
    p = recv;
    for (r = 1; r < n && s == LL_OK && share->rank == 0; ++r) {
        end = p + recv_bytes[r];
        for (c = 0; c < n_channels && s == LL_OK; ++c)
            for (k = r; k < layers[c]->m && s == LL_OK; k += n) {
                ll_order *o;
                s = ll_order_unpack(layers[c]->n, &p, end, &o);
                if (s == LL_OK) {
                    ll_order_release(layers[c]->orders[k]);
                    layers[c]->orders[k] = o;
                }
            }
        if (s == LL_OK && p != end)
            s = ll_fail(LL_ERROR_FORMAT, "rank %zu sent more than its orders", r);
    }
    ll_free(recv);
    return s;
}
