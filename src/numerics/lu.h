/*
 * LU with partial pivoting and the right-sided solve with its factors, as
 * LAPACK's dgetrf and the solve Z G = B leave them, run recursively so that
 * all but small panels are one gemm (lu.c). Adding and the closed-form slab
 * (grammar/) use them for their gain matrices.
 */
#ifndef LL_NUMERICS_LU_H
#define LL_NUMERICS_LU_H

#include <stddef.h>
#include <lapacke.h>
#include "support/support.h"

/* LU with partial pivoting of the h x h column-major A in place, as
 * LAPACK's dgetrf leaves it (A = P L U, 1-based pivots; recursive,
 * gemm-bound); returns dgetrf's info. */
LL_INTERNAL lapack_int ll_lu_factor(size_t h, double *A, lapack_int *piv);

/* B = B G^-1 from the LU factors of G (G = P L U, as getrf leaves them), in
 * place on the h x h column-major B. */
LL_INTERNAL void ll_right_solve_lu(size_t h, const double *lu, const lapack_int *piv, double *B);

#endif /* LL_NUMERICS_LU_H */
