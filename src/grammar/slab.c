/*
 * A homogeneous slab from one symmetric eigendecomposition per order
 * (Stamnes & Swanson 1981; Stamnes et al. 1988): the closed-form solution of
 * the discrete-ordinate equations that doubling approximates by 2^k thin
 * layers (method.md, "Thickening a medium: the slab or doubling").
 *
 * The equations. With u the radiance going down (nodes +x), v the radiance
 * going up (nodes -x), X = diag(x) and the medium's weighted phase blocks
 * PT (down from down, = up from up) and PR (up from down, = down from up),
 * doubling's thin layer (R = tau0 X^-1 PR, T = I + tau0 X^-1 (PT - I)) is
 * the first step of
 *     du/dtau = X^-1 ((PT - I) u + PR v),   dv/dtau = -X^-1 ((PT - I) v + PR u).
 * For the sum s = u + v and the difference d = u - v this is s' = -b d,
 * d' = -a s with a = X^-1 (I - PT - PR) and b = X^-1 (I - PT + PR).
 *
 * Symmetric reduction. The blocks are reciprocal: PT = pT Wt, PR = pR Wt
 * with symmetric pT, pR and Wt = diag(w) (the weights folded into the
 * columns). With the symmetric E = (I - PT + PR) Wt^-1 (positive definite:
 * one minus the albedo times the odd part of the phase function), its
 * Cholesky factor E = L L^T, C = Wt X^-1 and the symmetric
 * C F C = Wt (I - PT - PR) X^-2, the product a b is similar to the
 * symmetric, positive semi-definite H = L^T (C F C) L. Its eigenpairs
 * H z = k^2 z give the modes U = Wt^-1 L^-T z of d (a b U = k^2 U) and
 * V = X^-1 L z = b U of s (a V = k^2 U). F is singular exactly for a
 * conservative medium's order 0 (k = 0, the diffusion mode), which the
 * forms below take without a special case.
 *
 * Reflection and transmission. The slab [0, tau] is symmetric about its
 * middle y = 0 (t = tau / 2 either side). Lighting both faces alike, the
 * solution is even: s = V cosh(k y), d = -k U sinh(k y); lighting them
 * with opposite signs it is odd: d = U cosh(k y), s = -V sinh(k y) / k.
 * Reading the outgoing over the incoming radiance at the top face, with
 * Psi = diag(k tanh(k t)) and Phi = diag(tanh(k t) / k):
 *     R + T = (V - U Psi)(V + U Psi)^-1,
 *     R - T = (V Phi - U)(U + V Phi)^-1.
 * Only tanh appears (the exponentials scaled by their value at the far
 * face, as DISORT scales them), so nothing overflows for any tau; and
 * tanh(k t) / k -> t, k tanh(k t) -> 0 as k -> 0, so the conservative mode
 * needs no special case.
 *
 * Cost: one Cholesky, two triangular products, one dsyevr, two triangular
 * products again and two LU solves: about the work of two or three adding
 * steps, where doubling takes one adding step per doubling (15 to 25).
 */
#include "grammar/grammar.h"
#include "grammar/slab.h"
#include "numerics/lu.h"

#include <cblas.h>
#include <lapacke.h>
#include <math.h>
#include <string.h>

/* dsyevr's work: 26 h is its minimum, (nb + 6) h its optimum with the
 * blocked tridiagonal reduction (nb = 32 in OpenBLAS' LAPACK). */
#define SLAB_LWORK_PER_NODE 64
#define SLAB_LIWORK_PER_NODE 10
/* Tile edge of symmetrize's walk (32 x 32 doubles: 8 KiB per tile). */
#define SLAB_TILE 32

/* Layout of the scratch, in doubles: 7 h x h matrices, 3 h vectors, the
 * dsyevr work, then the integers (pivots, isuppz, iwork) in the rest. */
static size_t int_doubles(size_t ints)
{
    return (ints * sizeof(lapack_int) + sizeof(double) - 1) / sizeof(double);
}

size_t ll_slab_scratch_doubles(size_t h)
{
    size_t hh, total, ints;
    if (!ll_size_mul(h, h, &hh) || !ll_size_mul(hh, 7, &total) ||
        !ll_size_mul(h, 3 + SLAB_LWORK_PER_NODE, &ints) || !ll_size_add(total, ints, &total) ||
        !ll_size_mul(h, 3 + SLAB_LIWORK_PER_NODE, &ints) ||
        !ll_size_add(total, int_doubles(ints), &total))
        return 0;
    return total;
}

/* Largest |a(r, c) - a(c, r)| relative to the largest |a|: 0 for an exactly
 * symmetric matrix; then a = (a + a^T) / 2. */
static double symmetrize(size_t h, double *a)
{
    double asym = 0.0, big = 0.0;
    size_t r, c, r0, c0;
    /* In tiles of SLAB_TILE x SLAB_TILE: the row-wise walk a[r * h + c] of
     * a whole column strides through h^2 doubles (3% of the dust on gold's
     * CPU before). Each pair r >= c is visited once either way, and max is
     * order-free: the same result. */
    for (c0 = 0; c0 < h; c0 += SLAB_TILE)
        for (r0 = c0; r0 < h; r0 += SLAB_TILE)
            for (c = c0; c < c0 + SLAB_TILE && c < h; ++c)
                for (r = r0 > c ? r0 : c; r < r0 + SLAB_TILE && r < h; ++r) {
                    double lo = a[c * h + r], up = a[r * h + c];
                    asym = fmax(asym, fabs(lo - up));
                    big = fmax(big, fmax(fabs(lo), fabs(up)));
                    a[c * h + r] = a[r * h + c] = 0.5 * (lo + up);
                }
    return big > 0.0 ? asym / big : 0.0;
}

/* B = B A^-1 for h x h column-major B and A (A overwritten by its LU
 * factors A = P L U): two right-sided triangular solves, then the column
 * interchanges of P undone in reverse order. Returns 0 if A is singular. */
static int solve_from_right(size_t h, double *A, lapack_int *piv, double *B)
{
    if (ll_lu_factor(h, A, piv) != 0)
        return 0;
    ll_right_solve_lu(h, A, piv, B);
    return 1;
}

/* out = (P - Q diag(f)) (P + Q diag(f))^-1, with den as scratch; sign -1
 * gives (Q diag(f) - P) (P + Q diag(f))^-1 instead. */
static int ratio(size_t h, const double *P, const double *Q, const double *f, double sign,
                 double *den, lapack_int *piv, double *out)
{
    size_t r, c;
    for (c = 0; c < h; ++c)
        for (r = 0; r < h; ++r) {
            double p = P[c * h + r], q = Q[c * h + r] * f[c];
            out[c * h + r] = sign * (p - q);
            den[c * h + r] = p + q;
        }
    return solve_from_right(h, den, piv, out);
}

int ll_slab_solve(size_t h, const double *PT, const double *PR, const double *x,
                  const double *w, double tau, double *scratch, double *R, double *T)
{
    size_t hh = h * h, r, c, j;
    double *L = scratch, *H = L + hh, *Z = H + hh, *U = Z + hh, *V = U + hh, *den = V + hh,
           *plus = den + hh, *k2 = plus + hh, *phi = k2 + h, *psi = phi + h, *work = psi + h;
    lapack_int *piv = (lapack_int *)(work + SLAB_LWORK_PER_NODE * h), *isuppz = piv + h,
               *iwork = isuppz + 2 * h, found = 0;
    double t = 0.5 * tau;
    /* The medium's blocks are reciprocal to rounding (media.c builds them
     * as one symmetric product); anything further from symmetric is not a
     * medium this method assumes. */
    const double reciprocity = 1e-9;

    /* E = (I - PT + PR) Wt^-1 and C F C = Wt (I - PT - PR) / (x x^T). */
    for (c = 0; c < h; ++c)
        for (r = 0; r < h; ++r) {
            double id = r == c ? 1.0 : 0.0;
            L[c * h + r] = (id - PT[c * h + r] + PR[c * h + r]) / w[c];
            H[c * h + r] = w[r] * (id - PT[c * h + r] - PR[c * h + r]) / (x[r] * x[c]);
        }
    if (symmetrize(h, L) > reciprocity || symmetrize(h, H) > reciprocity)
        return 0;
    if (LAPACKE_dpotrf_work(LAPACK_COL_MAJOR, 'L', (lapack_int)h, L, (lapack_int)h) != 0)
        return 0;
    for (c = 0; c < h; ++c) /* potrf leaves the upper triangle as it was */
        for (r = 0; r < c; ++r)
            L[c * h + r] = 0.0;

    /* H = L^T (C F C) L, symmetric (rounding aside), then its eigenpairs. */
    cblas_dtrmm(CblasColMajor, CblasRight, CblasLower, CblasNoTrans, CblasNonUnit, (blasint)h,
                (blasint)h, 1.0, L, (blasint)h, H, (blasint)h);
    cblas_dtrmm(CblasColMajor, CblasLeft, CblasLower, CblasTrans, CblasNonUnit, (blasint)h,
                (blasint)h, 1.0, L, (blasint)h, H, (blasint)h);
    symmetrize(h, H);
    if (LAPACKE_dsyevr_work(LAPACK_COL_MAJOR, 'V', 'A', 'L', (lapack_int)h, H, (lapack_int)h,
                            0.0, 0.0, 0, 0, 0.0, &found, k2, Z, (lapack_int)h, isuppz, work,
                            (lapack_int)(SLAB_LWORK_PER_NODE * h), iwork,
                            (lapack_int)(SLAB_LIWORK_PER_NODE * h)) != 0 ||
        (size_t)found != h)
        return 0;

    /* V = X^-1 L Z and U = Wt^-1 L^-T Z. */
    memcpy(V, Z, hh * sizeof(double));
    cblas_dtrmm(CblasColMajor, CblasLeft, CblasLower, CblasNoTrans, CblasNonUnit, (blasint)h,
                (blasint)h, 1.0, L, (blasint)h, V, (blasint)h);
    memcpy(U, Z, hh * sizeof(double));
    cblas_dtrsm(CblasColMajor, CblasLeft, CblasLower, CblasTrans, CblasNonUnit, (blasint)h,
                (blasint)h, 1.0, L, (blasint)h, U, (blasint)h);
    for (c = 0; c < h; ++c)
        for (r = 0; r < h; ++r) {
            V[c * h + r] /= x[r];
            U[c * h + r] /= w[r];
        }
    for (j = 0; j < h; ++j) {
        /* k^2 >= 0 up to rounding (H is semi-definite). */
        double k = sqrt(fmax(k2[j], 0.0)), kt = k * t, th = tanh(kt);
        phi[j] = kt < 1e-8 ? t : th / k;
        psi[j] = k * th;
    }

    /* R + T into plus, R - T into Z (free now), then R and T. */
    if (!ratio(h, V, U, psi, 1.0, den, piv, plus) || !ratio(h, U, V, phi, -1.0, den, piv, Z))
        return 0;
    for (j = 0; j < hh; ++j) {
        R[j] = 0.5 * (plus[j] + Z[j]);
        T[j] = 0.5 * (plus[j] - Z[j]);
    }
    return 1;
}

/*
 * The cost model, measured with bench/slab.c (one thread, OpenBLAS 0.3.21,
 * on 2 cores; HG g = 0.9, tau = 4, 17
 * doublings): one order by the slab costs as much as this many adding
 * steps of doubling,
 *     h      8    20    50   100   200   549
 *     steps  11   8.5   8.5  6.5   3.5   2.75
 * (dsyevr and the two LU solves against the gemm-bound adding step; small
 * h pays LAPACK's per-call overhead), fitted by max(2.5, 12 - 1.5 ln h).
 * Doubling needs one adding step per doubling (k = log2(tau / tau0), 15 or
 * more for tau >= 1 with tau0 <= 2^-15), so the slab is cheaper for every
 * slab but the thinnest.
 */
double ll_slab_order_steps(size_t h)
{
    double steps = 12.0 - 1.5 * log((double)(h ? h : 1));
    return steps > 2.5 ? steps : 2.5;
}

double ll_expand_order_steps(size_t h, size_t doublings)
{
    double slab = ll_slab_order_steps(h);
    return slab < (double)doublings ? slab : (double)doublings;
}
