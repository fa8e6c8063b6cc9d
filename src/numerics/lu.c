/*
 * The LU factorisation and the right-sided triangular solves of the adding
 * equations and the closed-form slab, recursive so that they run at nearly
 * the rate of gemm (declared in lu.h).
 */
#include "numerics/lu.h"

#include <cblas.h>
#include <lapacke.h>

/*
 * The right-sided triangular solves, recursively: halving the triangle
 * turns all but the diagonal blocks of up to RIGHT_SOLVE_BLOCK columns into
 * one large gemm per level. OpenBLAS's dtrsm runs these solves at 0.3-0.4
 * of its dgemm rate at h = 250-550 (one thread; bench/adding.c's
 * lu_solve_ratio), and they are 2 h^3 of an adding half's 32/3 h^3 flops:
 * the recursion runs them at about 0.6-0.8. (Rounding differs from dtrsm's
 * at the level of the last bits: 6e-16 relative in the solution.)
 */
#define RIGHT_SOLVE_BLOCK 64

/* X U = B for the m x n upper triangle U (non-unit), X in place of B. */
static void right_solve_upper(size_t m, size_t n, const double *U, size_t ldu, double *B,
                              size_t ldb)
{
    size_t n1 = n / 2, n2 = n - n / 2;
    if (n <= RIGHT_SOLVE_BLOCK) {
        cblas_dtrsm(CblasColMajor, CblasRight, CblasUpper, CblasNoTrans, CblasNonUnit,
                    (blasint)m, (blasint)n, 1.0, U, (blasint)ldu, B, (blasint)ldb);
        return;
    }
    /* [X1 X2] [U11 U12; 0 U22] = [B1 B2]: X1 first, then X2 U22 = B2 - X1 U12. */
    right_solve_upper(m, n1, U, ldu, B, ldb);
    cblas_dgemm(CblasColMajor, CblasNoTrans, CblasNoTrans, (blasint)m, (blasint)n2,
                (blasint)n1, -1.0, B, (blasint)ldb, U + n1 * ldu, (blasint)ldu, 1.0,
                B + n1 * ldb, (blasint)ldb);
    right_solve_upper(m, n2, U + n1 * ldu + n1, ldu, B + n1 * ldb, ldb);
}

/* X L = B for the unit lower triangle L, X in place of B. */
static void right_solve_unit_lower(size_t m, size_t n, const double *L, size_t ldl, double *B,
                                   size_t ldb)
{
    size_t n1 = n / 2, n2 = n - n / 2;
    if (n <= RIGHT_SOLVE_BLOCK) {
        cblas_dtrsm(CblasColMajor, CblasRight, CblasLower, CblasNoTrans, CblasUnit, (blasint)m,
                    (blasint)n, 1.0, L, (blasint)ldl, B, (blasint)ldb);
        return;
    }
    /* [X1 X2] [L11 0; L21 L22] = [B1 B2]: X2 first, then X1 L11 = B1 - X2 L21. */
    right_solve_unit_lower(m, n2, L + n1 * ldl + n1, ldl, B + n1 * ldb, ldb);
    cblas_dgemm(CblasColMajor, CblasNoTrans, CblasNoTrans, (blasint)m, (blasint)n1,
                (blasint)n2, -1.0, B + n1 * ldb, (blasint)ldb, L + n1, (blasint)ldl, 1.0, B,
                (blasint)ldb);
    right_solve_unit_lower(m, n1, L, ldl, B, ldb);
}

/* L X = B for the unit lower triangle L (m x m), X in place of B (m x n). */
static void left_solve_unit_lower(size_t m, size_t n, const double *L, size_t ldl, double *B,
                                  size_t ldb)
{
    size_t m1 = m / 2, m2 = m - m / 2;
    if (m <= RIGHT_SOLVE_BLOCK) {
        cblas_dtrsm(CblasColMajor, CblasLeft, CblasLower, CblasNoTrans, CblasUnit, (blasint)m,
                    (blasint)n, 1.0, L, (blasint)ldl, B, (blasint)ldb);
        return;
    }
    /* [L11 0; L21 L22] [X1; X2] = [B1; B2]: X1, then L22 X2 = B2 - L21 X1. */
    left_solve_unit_lower(m1, n, L, ldl, B, ldb);
    cblas_dgemm(CblasColMajor, CblasNoTrans, CblasNoTrans, (blasint)m2, (blasint)n,
                (blasint)m1, -1.0, L + m1, (blasint)ldl, B, (blasint)ldb, 1.0, B + m1,
                (blasint)ldb);
    left_solve_unit_lower(m2, n, L + m1 * ldl + m1, ldl, B + m1, ldb);
}

/*
 * LU with partial pivoting of the m x n (m >= n) column-major A, as
 * dgetrf leaves it (A = P L U, 1-based pivots), recursively on halves of
 * the columns (Toledo 1997): the left half factored, its interchanges
 * applied to the right half, U12 = L11^-1 A12, A22 -= L21 U12 (one gemm),
 * the right half factored, its interchanges applied back to the left.
 * OpenBLAS's dgetrf runs at 0.3-0.45 of dgemm's rate on the gain matrices
 * (h = 100-550, one thread); this is gemm but for 64-column panels, which
 * dgetrf factors. The pivots are chosen by the same rule (largest
 * magnitude in the column), the rounding differs in the last bits.
 * Returns dgetrf's info (0, or the first zero pivot, 1-based).
 */
static lapack_int lu_recursive(size_t m, size_t n, double *A, size_t lda, lapack_int *piv)
{
    size_t n1 = n / 2, n2 = n - n / 2, i;
    lapack_int info, info2;
    if (n <= RIGHT_SOLVE_BLOCK)
        return LAPACKE_dgetrf_work(LAPACK_COL_MAJOR, (lapack_int)m, (lapack_int)n, A,
                                   (lapack_int)lda, piv);
    info = lu_recursive(m, n1, A, lda, piv);
    LAPACKE_dlaswp_work(LAPACK_COL_MAJOR, (lapack_int)n2, A + n1 * lda, (lapack_int)lda, 1,
                        (lapack_int)n1, piv, 1);
    left_solve_unit_lower(n1, n2, A, lda, A + n1 * lda, lda);
    cblas_dgemm(CblasColMajor, CblasNoTrans, CblasNoTrans, (blasint)(m - n1), (blasint)n2,
                (blasint)n1, -1.0, A + n1, (blasint)lda, A + n1 * lda, (blasint)lda, 1.0,
                A + n1 * lda + n1, (blasint)lda);
    info2 = lu_recursive(m - n1, n2, A + n1 * lda + n1, lda, piv + n1);
    if (info == 0 && info2 > 0)
        info = info2 + (lapack_int)n1;
    for (i = n1; i < n; ++i)
        piv[i] += (lapack_int)n1;
    LAPACKE_dlaswp_work(LAPACK_COL_MAJOR, (lapack_int)n1, A, (lapack_int)lda,
                        (lapack_int)n1 + 1, (lapack_int)n, piv, 1);
    return info;
}

lapack_int ll_lu_factor(size_t h, double *A, lapack_int *piv)
{
    return lu_recursive(h, h, A, h, piv);
}

/* Z = B G^-1 from the LU factors of G (G = P L U, as getrf leaves them):
 * Z P L U = B is solved by two right-sided triangular solves and the column
 * interchanges of P undone in reverse order. In place on B (h x h). */
void ll_right_solve_lu(size_t h, const double *lu, const lapack_int *piv, double *B)
{
    size_t i, r;
    right_solve_upper(h, h, lu, h, B, h);
    right_solve_unit_lower(h, h, lu, h, B, h);
    for (i = h; i-- > 0;) {
        size_t j = (size_t)piv[i] - 1; /* LAPACK pivots are 1-based */
        if (j != i)
            for (r = 0; r < h; ++r) {
                double t = B[i * h + r];
                B[i * h + r] = B[j * h + r];
                B[j * h + r] = t;
            }
    }
}
