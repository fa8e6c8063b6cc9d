/*
 * The LU and right-sided solves of adding and the slab (src/numerics/lu.c:
 * recursive, gemm-bound) against what they replace: for random
 * and for structured matrices of sizes around the recursion's 64-column
 * panels, P L U must give back A, Z = B G^-1 must solve Z G = B, and a
 * singular matrix must be reported with dgetrf's info.
 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "numerics/lu.h"
#include "test_util.h"

/* |P L U - A| / |A| (max norms) for the factors lu and pivots of A. */
static double factor_error(size_t h, const double *A, const double *lu, const lapack_int *piv)
{
    double *L = calloc(h * h, sizeof(double)), *U = calloc(h * h, sizeof(double));
    double *PLU = calloc(h * h, sizeof(double)), err = 0.0, big = 0.0;
    size_t r, c, k;
    assert_non_null(L);
    assert_non_null(U);
    assert_non_null(PLU);
    for (c = 0; c < h; ++c)
        for (r = 0; r < h; ++r) {
            if (r > c)
                L[c * h + r] = lu[c * h + r];
            else
                U[c * h + r] = lu[c * h + r];
            if (r == c)
                L[c * h + r] = 1.0;
        }
    for (c = 0; c < h; ++c)
        for (k = 0; k < h; ++k)
            for (r = 0; r < h; ++r)
                PLU[c * h + r] += L[k * h + r] * U[c * h + k];
    /* Undo the interchanges (applied in order 0..h-1 to A's rows). */
    for (k = h; k-- > 0;) {
        size_t p = (size_t)piv[k] - 1;
        for (c = 0; c < h && p != k; ++c) {
            double t = PLU[c * h + k];
            PLU[c * h + k] = PLU[c * h + p];
            PLU[c * h + p] = t;
        }
    }
    for (k = 0; k < h * h; ++k) {
        err = fmax(err, fabs(PLU[k] - A[k]));
        big = fmax(big, fabs(A[k]));
    }
    free(L);
    free(U);
    free(PLU);
    return err / big;
}

static void fill(size_t h, double *A, uint64_t *rng, double diagonal)
{
    size_t k;
    for (k = 0; k < h * h; ++k)
        A[k] = ll_test_uniform(rng) - 0.5;
    for (k = 0; k < h; ++k)
        A[k * h + k] += diagonal;
}

static void factors_and_solves(void **state)
{
    static const size_t sizes[] = { 1, 2, 63, 64, 65, 100, 129, 200, 257 };
    uint64_t rng = 12345;
    size_t i, k, r, c;
    (void)state;
    for (i = 0; i < sizeof sizes / sizeof sizes[0]; ++i) {
        size_t h = sizes[i];
        /* diagonal 0: the pivots matter; 1: a dominant diagonal, as in I - R R. */
        double diagonal = i % 2 ? 0.0 : 1.0;
        double *A = malloc(h * h * sizeof(double)), *lu = malloc(h * h * sizeof(double));
        double *B = malloc(h * h * sizeof(double)), *Z = malloc(h * h * sizeof(double));
        lapack_int *piv = malloc(h * sizeof(lapack_int));
        double err = 0.0, big = 0.0;
        assert_true(A && lu && B && Z && piv);
        fill(h, A, &rng, diagonal);
        fill(h, B, &rng, 0.0);
        memcpy(lu, A, h * h * sizeof(double));
        assert_int_equal(ll_lu_factor(h, lu, piv), 0);
        for (k = 0; k < h; ++k)
            assert_true(piv[k] >= (lapack_int)k + 1 && piv[k] <= (lapack_int)h);
        if (factor_error(h, A, lu, piv) > 1e-13 * (double)h)
            fail_msg("h = %zu: |PLU - A| / |A| = %g", h, factor_error(h, A, lu, piv));
        /* Z G = B for Z = B G^-1. */
        memcpy(Z, B, h * h * sizeof(double));
        ll_right_solve_lu(h, lu, piv, Z);
        for (c = 0; c < h; ++c)
            for (r = 0; r < h; ++r) {
                double s = 0.0;
                for (k = 0; k < h; ++k)
                    s += Z[k * h + r] * A[c * h + k];
                err = fmax(err, fabs(s - B[c * h + r]));
                big = fmax(big, fabs(B[c * h + r]));
            }
        if (err > 1e-10 * big)
            fail_msg("h = %zu: |Z G - B| / |B| = %g", h, err / big);
        free(A);
        free(lu);
        free(B);
        free(Z);
        free(piv);
    }
}

/* A zero column (here the 100th of 150, in the recursion's second half)
 * gives dgetrf's info: its 1-based index. */
static void singular_is_reported(void **state)
{
    size_t h = 150, k, zero = 99;
    uint64_t rng = 99;
    double *A = malloc(h * h * sizeof(double)), *B = malloc(h * h * sizeof(double));
    lapack_int *piv = malloc(h * sizeof(lapack_int)), *piv2 = malloc(h * sizeof(lapack_int));
    (void)state;
    assert_true(A && B && piv && piv2);
    fill(h, A, &rng, 1.0);
    for (k = 0; k < h; ++k)
        A[zero * h + k] = 0.0;
    memcpy(B, A, h * h * sizeof(double));
    assert_int_equal(ll_lu_factor(h, A, piv),
                     LAPACKE_dgetrf_work(LAPACK_COL_MAJOR, (lapack_int)h, (lapack_int)h, B,
                                         (lapack_int)h, piv2));
    assert_int_equal(ll_lu_factor(h, B, piv), (lapack_int)zero + 1);
    free(A);
    free(B);
    free(piv);
    free(piv2);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(factors_and_solves),
        cmocka_unit_test(singular_is_reported),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
