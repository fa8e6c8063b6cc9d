/*
 * A homogeneous slab of finite optical thickness from one symmetric
 * eigendecomposition per Fourier order (the discrete-ordinate method of
 * Stamnes & Swanson 1981, J. Atmos. Sci. 38, and Stamnes et al. 1988, Appl.
 * Opt. 27, "DISORT"), the second way besides doubling to give a medium its
 * thickness. The matrices are those of the discrete-ordinate system whose
 * first-order thin layer is doubling's (adding.c), so the two agree up to
 * doubling's own truncation error; the forward peak is already truncated by
 * media.c (delta-M, Wiscombe 1977; Nakajima & Tanaka 1988 for the idea of
 * a truncated forward peak kept as an identity term).
 */
#ifndef LL_GRAMMAR_SLAB_H
#define LL_GRAMMAR_SLAB_H

#include "layer/layer.h"

/* Doubles of scratch that ll_slab_solve needs for h = n / 2 nodes per
 * hemisphere (0 if the size overflows); a whole number of doubles holds the
 * LAPACK integer work too. */
LL_INTERNAL size_t ll_slab_scratch_doubles(size_t h);

/*
 * The slab of optical thickness tau of one order: PT and PR are the dense
 * h x h blocks T^tb and R^t of the medium's phase matrix (weights folded
 * into the columns as media.c does: column i times weights[h + i]), x the
 * h positive node cosines, w their weights. On success (returns 1) R and T
 * (h x h, column-major) are the reflection and transmission of the slab,
 * the same on both sides. Returns 0 when the order is not one the method
 * solves (the phase blocks not reciprocal, or I - PT + PR not positive
 * definite: a medium that amplifies odd moments); the caller then doubles.
 * PT and PR are left unchanged. scratch holds ll_slab_scratch_doubles(h).
 */
LL_INTERNAL int ll_slab_solve(size_t h, const double *PT, const double *PR, const double *x,
                              const double *w, double tau, double *scratch, double *R,
                              double *T);

/* The cost of one order by the slab, in adding steps of doubling (one
 * step per doubling; measured, slab.c), and of expanding one order by the
 * cheaper of the two: what ll_layer_expand picks (the slab exactly when
 * ll_slab_order_steps(h) < doublings) and what the build estimate counts. */
LL_INTERNAL double ll_slab_order_steps(size_t h);
LL_INTERNAL double ll_expand_order_steps(size_t h, size_t doublings);

#endif /* LL_GRAMMAR_SLAB_H */
