/*
 * Internal extras of the media words (media.c) for the grammar: the phase
 * matrices of a medium handed, order by order, to a caller that finishes
 * each one (gives it its thickness) before it is stored, so that a thick
 * medium never holds its phase matrices and its slab at once.
 */
#ifndef LL_WORDS_MEDIA_H
#define LL_WORDS_MEDIA_H

#include "layer/layer.h"

typedef enum { LL_MEDIUM_ISOTROPIC, LL_MEDIUM_HG, LL_MEDIUM_VMF } ll_medium_kind;

/* order(user, l, P, forward, out), on a worker thread: P is order l's dense
 * n x n weighted phase matrix (column-major, the caller's to overwrite), or
 * NULL for an order beyond the kept moments, which is forward * I; it
 * stores the finished order into *out (NULL if all zero). */
typedef struct ll_medium_finish {
    ll_status (*order)(void *user, size_t l, double *P, double forward, ll_order **out);
    void *user;
} ll_medium_finish;

/* ll_layer_set_isotropic / _henyey_greenstein / _von_mises_fisher
 * (shape: unused, g, kappa) with every order passed through finish (NULL:
 * stored as the phase matrix, as those do). */
LL_INTERNAL ll_status ll_layer_set_medium_finished(ll_layer *layer, ll_medium_kind kind,
                                                   double albedo, double shape,
                                                   const ll_medium_finish *finish,
                                                   const ll_monitor *monitor);

#endif /* LL_WORDS_MEDIA_H */
