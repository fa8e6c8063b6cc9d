/*
 * The columns of an interface layer (ll_layer_set_microfacet in
 * microfacet.c): the job the layer's column builder runs, one incident
 * column of every order at a time, and the energy compensation of order 0
 * once the columns are done.
 */
#ifndef LL_WORDS_MICROFACET_COLUMNS_H
#define LL_WORDS_MICROFACET_COLUMNS_H

#include "words/microfacet.h"
#include "layer/layer.h"

typedef struct ll_microfacet_job {
    const ll_layer *layer;
    const ll_microfacet_model *mf;
    size_t column_doubles;       /* scratch of one column               */
    double **column_memory;      /* [slots]: each thread's, reused      */
    size_t slots;
    ll_order_builder **builders; /* [m]; order 0 goes through order0 */
    double *order0;              /* n x n column-major, unweighted     */
    double *ref0;                /* n x n or NULL (conductor compensation) */
    ll_watch *watch;             /* one unit per column, polled per row */
    const double *w;             /* [h] outgoing weights 2 pi w_j mu_j  */
    double *work;                /* [8 h] compensation scratch          */
    double eta_re, eta_im;
    int conserve_energy;
    int reciprocal;              /* columns compute one entry of each
                                  * reciprocal pair, the finish mirrors
                                  * the rest (ll_microfacet_column_rows) */
} ll_microfacet_job;

/* Doubles of scratch for one column of n nodes and m orders; 0 if that
 * overflows. */
LL_INTERNAL size_t ll_microfacet_column_doubles(size_t n, size_t m);
/* The rows whose series column col computes, first, first + 1, ...
 * (modulo n), count of them: every row, or with reciprocal only one entry
 * of each reciprocal pair (microfacet_columns.c says which). */
LL_INTERNAL void ll_microfacet_column_rows(size_t col, size_t n, int reciprocal, size_t *first,
                                           size_t *count);
/* One incident column (ctx: the job), every outgoing node, every order
 * but 0, which goes to job->order0 (and the reference's to job->ref0). */
LL_INTERNAL ll_status ll_microfacet_layer_column(size_t col, void *ctx);
/* After the columns: with job->reciprocal the entries not computed, from
 * their reciprocal ones, then energy compensation on the unweighted
 * order 0, the weights, and order 0 into its builder. */
LL_INTERNAL ll_status ll_microfacet_finish_order0(void *ctx);

/* ll_layer_set_microfacet; with every_pair non-zero each pair of nodes
 * gets its own series (no reciprocal copies): the reference the tests
 * hold the reciprocal build to. */
LL_INTERNAL ll_status ll_microfacet_set_layer(ll_layer *layer, const ll_microfacet *microfacet,
                                              const ll_monitor *monitor, int every_pair);

#endif /* LL_WORDS_MICROFACET_COLUMNS_H */
