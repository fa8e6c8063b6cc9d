/*
 * A medium given its thickness in the same pass as its phase matrices: each
 * order's phase matrix (media.c) goes straight into the closed-form slab
 * (slab.c) on the worker thread that made it, and only the slab is stored.
 * ll_layer_set_henyey_greenstein (etc.) followed by ll_layer_expand holds
 * the phase matrices of every order and the slab of every order at once,
 * twice the memory (gigabytes each for the largest media a material asks
 * for); the results are the same bits as that two-step path with the slab
 * (tests/test_slab.c).
 */
#include "grammar/grammar.h"
#include "grammar/slab.h"

#include <math.h>
#include <string.h>

typedef struct slab_medium {
    const ll_layer *layer; /* nodes and weights */
    double tau;
    size_t slots;
    double **scratch;      /* per thread: slab.c's scratch, then PT, PR, R, T */
    int unsolved;          /* an order the closed form does not take */
} slab_medium;

static int block_is_zero(const double *x, size_t count)
{
    size_t i;
    for (i = 0; i < count; ++i)
        if (x[i] != 0.0)
            return 0;
    return 1;
}

/* Only the unscattered light: T = exp(-tau (1 - d) / x) on the diagonal
 * (d: the phase matrix's forward diagonal), as ll_layer_expand's slab. */
static ll_status straight_order(const slab_medium *m, double *d, ll_order **out)
{
    const ll_layer *l = m->layer;
    size_t h = l->n / 2, c;
    for (c = 0; c < h; ++c)
        d[c] = exp(-m->tau * (1.0 - d[c]) / l->nodes[h + c]);
    return ll_order_from_diagonals(l->n, d, d, LL_DROP_THRESHOLD, out);
}

static ll_status finish_order(void *user, size_t order, double *P, double forward,
                              ll_order **out)
{
    slab_medium *m = user;
    const ll_layer *l = m->layer;
    size_t n = l->n, h = n / 2, hh = h * h, slot = ll_parallel_slot(), r, c, doubles;
    double *scratch, *PT, *PR, *R, *T;
    const double *blocks[4];

    if (slot >= m->slots)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "medium: thread %zu of %zu", slot, m->slots);
    if (!m->scratch[slot]) {
        doubles = ll_slab_scratch_doubles(h);
        if (!doubles || !ll_size_add(doubles, 4 * hh, &doubles))
            doubles = 0;
        m->scratch[slot] = doubles ? ll_alloc_array(doubles, sizeof(double)) : NULL;
        if (!m->scratch[slot])
            return ll_fail(LL_ERROR_OUT_OF_MEMORY,
                           "medium: out of memory for the slab of %zu nodes", n);
    }
    scratch = m->scratch[slot];
    PT = scratch + ll_slab_scratch_doubles(h);
    PR = PT + hh;
    R = PR + hh;
    T = R + hh;
    if (!P) { /* beyond the kept moments: forward * I */
        for (c = 0; c < h; ++c)
            PT[c] = forward;
        return straight_order(m, PT, out);
    }
    /* The blocks T^tb (rows and columns >= h) and R^t (rows < h, columns
     * >= h) of the column-major n x n matrix. */
    for (c = 0; c < h; ++c)
        for (r = 0; r < h; ++r) {
            PT[c * h + r] = P[(h + c) * n + h + r];
            PR[c * h + r] = P[(h + c) * n + r];
        }
    if (block_is_zero(PR, hh) && ll_block_is_diagonal(PT, h)) {
        for (c = 0; c < h; ++c)
            PT[c] = PT[c * h + c];
        return straight_order(m, PT, out);
    }
    if (!ll_slab_solve(h, PT, PR, l->nodes + h, l->weights + h, m->tau, scratch, R, T)) {
        m->unsolved = 1;
        return ll_fail(LL_ERROR_NUMERICAL, "medium: order %zu is not one the slab solves",
                       order);
    }
    blocks[LL_BLOCK_TBT] = T;
    blocks[LL_BLOCK_RT] = R;
    blocks[LL_BLOCK_RB] = R;
    blocks[LL_BLOCK_TTB] = T;
    return ll_order_from_blocks(blocks, h, LL_DROP_THRESHOLD, out);
}

int ll_medium_slab_applies(const ll_layer *layer, double tau)
{
    double min_mu = 1.0, tau0;
    size_t i, k;
    if (!layer || !(tau > 0.0) || !(tau <= 1e12))
        return 0;
    for (i = 0; i < layer->n; ++i)
        if (fabs(layer->nodes[i]) < min_mu)
            min_mu = fabs(layer->nodes[i]);
    ll_expand_schedule(tau, min_mu, &tau0, &k);
    return ll_slab_order_steps(layer->n / 2) < (double)k;
}

ll_status ll_layer_set_medium_slab(ll_layer *layer, ll_medium_kind kind, double albedo,
                                   double shape, double tau, const ll_monitor *monitor,
                                   int *done)
{
    slab_medium m;
    ll_medium_finish finish;
    ll_status s;
    size_t i;

    *done = 0;
    if (!ll_medium_slab_applies(layer, tau))
        return LL_OK;
    m.layer = layer;
    m.tau = tau;
    m.unsolved = 0;
    m.slots = ll_get_thread_count();
    m.scratch = ll_calloc_array(m.slots, sizeof(double *));
    if (!m.scratch)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "medium: out of memory");
    finish.order = finish_order;
    finish.user = &m;
    s = ll_layer_set_medium_finished(layer, kind, albedo, shape, &finish, monitor);
    for (i = 0; i < m.slots; ++i)
        ll_free(m.scratch[i]);
    ll_free(m.scratch);
    if (s != LL_OK && m.unsolved)
        return LL_OK; /* the layer is unchanged: the caller takes the two steps */
    *done = s == LL_OK;
    return s;
}
