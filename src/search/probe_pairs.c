/*
 * The distinct node pairs of the probes' stencils (search/probe_pairs.h).
 */
#include "search/probe_pairs.h"

#include <stdlib.h>
#include <string.h>

/* A stencil slot's node pair, for sorting: its block (the signs of the
 * probe pair's cosines, which its nodes take), node indices, slot. */
typedef struct slot_key {
    size_t block, io, ii, slot;
} slot_key;

static int slot_key_order(const void *x, const void *y)
{
    const slot_key *a = x, *b = y;
    if (a->block != b->block)
        return a->block < b->block ? -1 : 1;
    if (a->io != b->io)
        return a->io < b->io ? -1 : 1;
    if (a->ii != b->ii)
        return a->ii < b->ii ? -1 : 1;
    return a->slot < b->slot ? -1 : a->slot > b->slot;
}

static int same_node_pair(const slot_key *a, const slot_key *b)
{
    return a->block == b->block && a->io == b->io && a->ii == b->ii;
}

void ll_probe_node_pairs_free(ll_probe_node_pairs *np)
{
    size_t d;
    if (np->fresh)
        for (d = 0; d < np->count; ++d)
            ll_free(np->fresh[d]);
    ll_free(np->mu_o);
    ll_free(np->mu_i);
    ll_free(np->of_slot);
    ll_free(np->c);
    ll_free(np->len);
    ll_free(np->fresh);
    memset(np, 0, sizeof *np);
}

/* A sort, not a table of the n^2 / 4 node pairs of each block: the
 * stencils hold a few thousand. */
ll_status ll_probe_node_pairs_make(const ll_probe_set *set, const ll_probe_pair_stencil *stencils,
                                   ll_probe_node_pairs *np)
{
    slot_key *keys = NULL;
    size_t slots, p, a, b, k, count = 0;
    ll_status s = LL_OK;
    memset(np, 0, sizeof *np);
    if (!ll_size_mul(16, set->n_pairs, &slots))
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "resolution probes: out of memory");
    keys = ll_alloc_array(slots + 1, sizeof *keys);
    np->of_slot = ll_alloc_array(slots + 1, sizeof *np->of_slot);
    if (!keys || !np->of_slot) {
        s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "resolution probes: out of memory");
        goto done;
    }
    for (p = 0; p < set->n_pairs; ++p) {
        const ll_probe_pair_stencil *st = stencils + p;
        size_t block = 2 * (size_t)(set->pairs[p].mu_o < 0.0) + (size_t)(set->pairs[p].mu_i < 0.0);
        for (a = 0; a < st->co; ++a)
            for (b = 0; b < st->ci; ++b) {
                keys[count].block = block;
                keys[count].io = st->io[a];
                keys[count].ii = st->ii[b];
                keys[count].slot = 16 * p + 4 * a + b;
                ++count;
            }
    }
    /* (The slot breaks ties: one order whatever qsort does with equals.) */
    qsort(keys, count, sizeof *keys, slot_key_order);
    for (k = 0; k < count; ++k)
        if (k == 0 || !same_node_pair(&keys[k], &keys[k - 1]))
            ++np->count;
    np->mu_o = ll_alloc_array(np->count + 1, sizeof(double));
    np->mu_i = ll_alloc_array(np->count + 1, sizeof(double));
    np->c = ll_calloc_array(np->count + 1, sizeof *np->c);
    np->len = ll_calloc_array(np->count + 1, sizeof *np->len);
    np->fresh = ll_calloc_array(np->count + 1, sizeof *np->fresh);
    if (!np->mu_o || !np->mu_i || !np->c || !np->len || !np->fresh) {
        s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "resolution probes: out of memory");
        goto done;
    }
    np->count = 0;
    for (k = 0; k < count; ++k) {
        size_t slot = keys[k].slot, pp = slot / 16;
        const ll_probe_pair_stencil *st = stencils + pp;
        if (k > 0 && same_node_pair(&keys[k], &keys[k - 1])) {
            np->of_slot[slot] = np->count - 1;
            continue;
        }
        /* Depth grows opposite to the normal: the series takes -mu. */
        np->mu_o[np->count] = -st->no[(slot / 4) % 4];
        np->mu_i[np->count] = -st->ni[slot % 4];
        np->of_slot[slot] = np->count++;
    }
done:
    ll_free(keys);
    if (s != LL_OK)
        ll_probe_node_pairs_free(np);
    return s;
}
