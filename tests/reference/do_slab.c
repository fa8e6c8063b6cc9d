/*
 * Discrete-ordinate reference for a Henyey-Greenstein slab, alone (index
 * matched) or under a smooth Fresnel boundary, lit by a collimated beam from
 * any direction mu0: the directional albedo R(mu0) and transmittance T(mu0).
 * It shares no code with layerlab: its own Gauss-Legendre rule (Newton on
 * P_n), its own phase kernel, its own doubling and linear solver, and no
 * spline: the beam is a column of its own at mu0, never interpolated
 * between nodes. Only the azimuthal average (Fourier order 0) is needed for
 * albedos.
 *
 * The method (Grant and Hunt 1969; van de Hulst 1980, "Multiple Light
 * Scattering", ch. 5; Wiscombe 1976 for the beam terms):
 *  - nodes: double Gauss, N Gauss-Legendre nodes on each of [0, mu_c] and
 *    [mu_c, 1] per hemisphere (mu_c the critical cosine inside the boundary,
 *    so that total internal reflection starts at a node boundary; mu_c = 0.5
 *    without a boundary);
 *  - kernel: 2 pi <p>(mu, mu') = sum_k (2k+1)/2 g^k P_k(mu) P_k(mu') (the
 *    addition theorem), summed until g^k < 1e-18;
 *  - a thin slab dtau = tau / 2^k, dtau <= 2^-26, to first order,
 *    R = dtau M^-1 a P(-, +) W, T = 1 - dtau M^-1 + dtau M^-1 a P(+, +) W,
 *    the beam's columns (dtau / mu) a P(., mu0) and its direct part
 *    exp(-dtau / mu0); then k doublings, the beam carried along as an extra
 *    column (u = (1 - R R)^-1 (e rb + R tb), rb' = rb + T u,
 *    tb' = e tb + T (tb + R u), e' = e^2);
 *  - the boundary: specular, unpolarised Fresnel F(mu) inside (relative
 *    index 1 / eta, total reflection below mu_c); the refracted beam enters
 *    with the flux fraction 1 - F(mu0) and the internal light leaves with
 *    1 - F(mu), the rest returns: U = (1 - R F)^-1 rb.
 * The slab's other side is index matched: light leaving it is gone.
 *
 * usage: do_slab [-N nodes] [-e eta] albedo g tau mu0...   prints mu0 R T
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The thin slab doubling starts from (first order in dtau). */
#ifndef DO_SLAB_DTAU
#define DO_SLAB_DTAU 0x1.0p-26
#endif

/* Gauss-Legendre nodes and weights on [a, b] (n of them): Newton's method on
 * P_n from Chebyshev-like first guesses (A&S 25.4.29). */
static void do_gauss(size_t n, double a, double b, double *x, double *w)
{
    size_t i, k;
    for (i = 0; i < n; ++i) {
        double z = cos(3.14159265358979323846 * ((double)i + 0.75) / ((double)n + 0.5)), dp = 1.0;
        int it;
        for (it = 0; it < 100; ++it) {
            double p0 = 1.0, p1 = z, dz;
            for (k = 2; k <= n; ++k) {
                double p2 = ((2.0 * (double)k - 1.0) * z * p1 - ((double)k - 1.0) * p0) / (double)k;
                p0 = p1;
                p1 = p2;
            }
            if (n == 1) {
                p1 = z;
                p0 = 1.0;
            }
            dp = (double)n * (z * p1 - p0) / (z * z - 1.0);
            dz = p1 / dp;
            z -= dz;
            if (fabs(dz) < 1e-16)
                break;
        }
        x[i] = 0.5 * (a + b) + 0.5 * (b - a) * z;
        w[i] = (b - a) / ((1.0 - z * z) * dp * dp);
    }
}

/* 2 pi <p>(mu, mu') for HG(g) by the addition theorem. */
static double do_kernel(double g, double mu, double nu)
{
    double pm0 = 1.0, pm1 = mu, pn0 = 1.0, pn1 = nu, sum = 0.5, gk = g;
    int k;
    if (g == 0.0)
        return 0.5;
    sum += 1.5 * g * mu * nu;
    for (k = 2; fabs(gk) > 1e-18 && k < 100000; ++k) {
        double pm2 = ((2.0 * k - 1.0) * mu * pm1 - (k - 1.0) * pm0) / k;
        double pn2 = ((2.0 * k - 1.0) * nu * pn1 - (k - 1.0) * pn0) / k;
        gk *= g;
        sum += 0.5 * (2.0 * k + 1.0) * gk * pm2 * pn2;
        pm0 = pm1;
        pm1 = pm2;
        pn0 = pn1;
        pn1 = pn2;
    }
    return sum;
}

/* Unpolarised Fresnel reflectance, cos_i on the incident side, relative
 * index eta of the other side (real). */
static double do_fresnel(double cos_i, double eta)
{
    double s2 = (1.0 - cos_i * cos_i) / (eta * eta), ct, rs, rp;
    if (s2 >= 1.0)
        return 1.0;
    ct = sqrt(1.0 - s2);
    rs = (cos_i - eta * ct) / (cos_i + eta * ct);
    rp = (eta * cos_i - ct) / (eta * cos_i + ct);
    return 0.5 * (rs * rs + rp * rp);
}

/* Solve A X = B in place (A n x n, B n x m, row-major), Gaussian elimination
 * with partial pivoting; returns 0 if A is singular. */
static int do_solve(size_t n, size_t m, double *A, double *B)
{
    size_t i, j, k;
    for (k = 0; k < n; ++k) {
        size_t p = k;
        double big = fabs(A[k * n + k]);
        for (i = k + 1; i < n; ++i)
            if (fabs(A[i * n + k]) > big) {
                big = fabs(A[i * n + k]);
                p = i;
            }
        if (!(big > 0.0))
            return 0;
        if (p != k) {
            for (j = 0; j < n; ++j) {
                double t = A[k * n + j];
                A[k * n + j] = A[p * n + j];
                A[p * n + j] = t;
            }
            for (j = 0; j < m; ++j) {
                double t = B[k * m + j];
                B[k * m + j] = B[p * m + j];
                B[p * m + j] = t;
            }
        }
        for (i = k + 1; i < n; ++i) {
            double f = A[i * n + k] / A[k * n + k];
            if (f == 0.0)
                continue;
            for (j = k; j < n; ++j)
                A[i * n + j] -= f * A[k * n + j];
            for (j = 0; j < m; ++j)
                B[i * m + j] -= f * B[k * m + j];
        }
    }
    for (k = n; k-- > 0;) {
        for (j = 0; j < m; ++j) {
            double s = B[k * m + j];
            for (i = k + 1; i < n; ++i)
                s -= A[k * n + i] * B[i * m + j];
            B[k * m + j] = s / A[k * n + k];
        }
    }
    return 1;
}

/* C = A B (n x n times n x m). */
static void do_mul(size_t n, size_t m, const double *A, const double *B, double *C)
{
    size_t i, j, k;
    memset(C, 0, n * m * sizeof *C);
    for (i = 0; i < n; ++i)
        for (k = 0; k < n; ++k) {
            double a = A[i * n + k];
            if (a == 0.0)
                continue;
            for (j = 0; j < m; ++j)
                C[i * m + j] += a * B[k * m + j];
        }
}

/* R(mu0) and T(mu0) of the slab (albedo a, HG g, optical thickness tau) with
 * 2 N nodes per hemisphere, under a smooth boundary of relative index eta
 * (medium over outside; eta == 1: none). mu0 is the cosine outside. The
 * directional albedo counts the light that leaves through the lit side,
 * the boundary's specular reflection included; the transmittance counts the
 * light that leaves through the other side, the direct beam included.
 * Returns 0 on failure (memory, singular system). */
static int do_slab_albedo(double a, double g, double tau, double eta, size_t nodes_per_part,
                          double mu0_out, double *R_out, double *T_out)
{
    size_t h = 2 * nodes_per_part, n2 = h + 1, i, j, k, doublings = 0;
    double mu_c = eta > 1.0 ? sqrt(1.0 - 1.0 / (eta * eta)) : 0.5;
    double mu0, beam_in, dtau, e, R_total, T_total;
    double *x = malloc(h * sizeof *x), *w = malloc(h * sizeof *w);
    /* R and T of the slab: h x (h + 1), the last column the beam's. */
    double *R = calloc(h * n2, sizeof *R), *T = calloc(h * n2, sizeof *T);
    double *G = malloc(h * h * sizeof *G), *X = malloc(h * n2 * sizeof *X);
    double *Y = malloc(h * n2 * sizeof *Y), *Z = malloc(h * n2 * sizeof *Z);
    double *RR = malloc(h * h * sizeof *RR), *Rs = malloc(h * h * sizeof *Rs);
    int ok = 0;
    if (!x || !w || !R || !T || !G || !X || !Y || !Z || !RR || !Rs)
        goto done;
    if (eta != 1.0 && eta <= 1.0)
        goto done;
    do_gauss(nodes_per_part, 0.0, mu_c, x, w);
    do_gauss(nodes_per_part, mu_c, 1.0, x + nodes_per_part, w + nodes_per_part);
    /* The beam inside: refracted, with the flux that enters, per unit flux
     * outside (its intensity integral B carries flux mu0 B). */
    if (eta == 1.0) {
        mu0 = mu0_out;
        beam_in = 1.0 / mu0_out;
    } else {
        double s2 = (1.0 - mu0_out * mu0_out) / (eta * eta);
        mu0 = sqrt(1.0 - s2);
        beam_in = (1.0 - do_fresnel(mu0_out, eta)) / mu0;
    }
    dtau = tau;
    while (dtau > DO_SLAB_DTAU) {
        dtau *= 0.5;
        ++doublings;
    }
    for (i = 0; i < h; ++i) {
        double s = dtau / x[i];
        for (j = 0; j < h; ++j) {
            R[i * n2 + j] = s * a * do_kernel(g, -x[i], x[j]) * w[j];
            T[i * n2 + j] = s * a * do_kernel(g, x[i], x[j]) * w[j];
        }
        T[i * n2 + i] += 1.0 - s;
        R[i * n2 + h] = s * a * do_kernel(g, -x[i], mu0);
        T[i * n2 + h] = s * a * do_kernel(g, x[i], mu0);
    }
    e = exp(-dtau / mu0);
    for (k = 0; k < doublings; ++k) {
        /* G = 1 - R R (square parts), X = [R T | e rb + R tb]: the light
         * the lower half sends back up, before the gain G^-1. */
        for (i = 0; i < h; ++i)
            for (j = 0; j < h; ++j)
                Rs[i * h + j] = R[i * n2 + j];
        do_mul(h, h, Rs, Rs, RR);
        for (i = 0; i < h * h; ++i)
            G[i] = (i % (h + 1) == 0 ? 1.0 : 0.0) - RR[i];
        do_mul(h, n2, Rs, T, Y);
        for (i = 0; i < h; ++i) {
            for (j = 0; j < h; ++j)
                X[i * n2 + j] = Y[i * n2 + j];
            X[i * n2 + h] = e * R[i * n2 + h] + Y[i * n2 + h];
        }
        memcpy(Z, G, h * h * sizeof *Z);
        if (!do_solve(h, n2, Z, X))
            goto done; /* X = u: [G^-1 R T | G^-1 (e rb + R tb)] */
        /* rb' = rb + T u; R' = R + T u (square). */
        {
            double *Ts = RR; /* reuse: T's square part */
            for (i = 0; i < h; ++i)
                for (j = 0; j < h; ++j)
                    Ts[i * h + j] = T[i * n2 + j];
            do_mul(h, n2, Ts, X, Z); /* Z = T u */
            /* d = tb + R u (beam column) and T + R u (square): Y = R u. */
            do_mul(h, n2, Rs, X, Y);
            for (i = 0; i < h; ++i) {
                for (j = 0; j < h; ++j)
                    Y[i * n2 + j] += T[i * n2 + j];
                Y[i * n2 + h] += T[i * n2 + h];
            }
            /* T' = T d (square), tb' = e tb + T d (beam). */
            do_mul(h, n2, Ts, Y, X);
            for (i = 0; i < h; ++i) {
                for (j = 0; j < h; ++j) {
                    R[i * n2 + j] += Z[i * n2 + j];
                    T[i * n2 + j] = X[i * n2 + j];
                }
                R[i * n2 + h] += Z[i * n2 + h];
                T[i * n2 + h] = e * T[i * n2 + h] + X[i * n2 + h];
            }
        }
        e *= e;
    }
    /* The boundary (none: F = 0). U = (1 - R F)^-1 rb, the downward light
     * it returns D = F U, the transmitted diffuse light tb + T D. */
    for (i = 0; i < h; ++i)
        X[i] = R[i * n2 + h] * beam_in;
    if (eta != 1.0) {
        for (i = 0; i < h; ++i)
            for (j = 0; j < h; ++j)
                G[i * h + j] = (i == j ? 1.0 : 0.0) - R[i * n2 + j] * do_fresnel(x[j], 1.0 / eta);
        if (!do_solve(h, 1, G, X))
            goto done;
    }
    R_total = eta == 1.0 ? 0.0 : do_fresnel(mu0_out, eta);
    T_total = e * beam_in * mu0;
    for (i = 0; i < h; ++i) {
        double f = eta == 1.0 ? 0.0 : do_fresnel(x[i], 1.0 / eta), down = 0.0;
        R_total += w[i] * x[i] * (1.0 - f) * X[i];
        for (j = 0; j < h; ++j)
            down += T[i * n2 + j] * (eta == 1.0 ? 0.0 : do_fresnel(x[j], 1.0 / eta)) * X[j];
        T_total += w[i] * x[i] * (T[i * n2 + h] * beam_in + down);
    }
    *R_out = R_total;
    *T_out = T_total;
    ok = 1;
done:
    free(x);
    free(w);
    free(R);
    free(T);
    free(G);
    free(X);
    free(Y);
    free(Z);
    free(RR);
    free(Rs);
    return ok;
}

#ifndef DO_SLAB_NO_MAIN
int main(int argc, char **argv)
{
    size_t nodes = 64;
    double eta = 1.0;
    int a = 1;
    while (a + 1 < argc && argv[a][0] == '-' && (argv[a][1] == 'N' || argv[a][1] == 'e')) {
        if (argv[a][1] == 'N')
            nodes = (size_t)atoi(argv[a + 1]);
        else
            eta = atof(argv[a + 1]);
        a += 2;
    }
    if (argc - a < 4) {
        fprintf(stderr, "usage: do_slab [-N nodes] [-e eta] albedo g tau mu0...\n");
        return 2;
    }
    {
        double albedo = atof(argv[a]), g = atof(argv[a + 1]), tau = atof(argv[a + 2]);
        for (a += 3; a < argc; ++a) {
            double mu = atof(argv[a]), R, T;
            if (!do_slab_albedo(albedo, g, tau, eta, nodes, mu, &R, &T))
                return 1;
            printf("%.6f %.9f %.9f\n", mu, R, T);
        }
    }
    return 0;
}
#endif
