/*
 * GGX's peak factor and shadowing (words/microfacet_ggx.h has the method).
 */
#include "words/microfacet_ggx.h"


#include <math.h>
#include <string.h>

void ll_ggx_basis_init(ll_ggx_basis *basis)
{
    /* Chebyshev points y_i = cos(theta_i), theta_i = pi (i + 1/2) / N, of
     * y = -cos phi (= v - 1, so that y = -1 is the peak). The interpolant's
     * coefficients a_j = (2 - [j = 0]) / N sum_i g_i cos(j theta_i), and
     * T_j(-cos phi) = (-1)^j cos(j phi): b_j = (-1)^j a_j. */
    size_t i, j;
    for (i = 0; i < LL_GGX_CHEB; ++i)
        basis->cos_phi[i] = -cos(LL_PI * ((double)i + 0.5) / LL_GGX_CHEB);
    for (j = 0; j < LL_GGX_CHEB; ++j)
        for (i = 0; i < LL_GGX_CHEB; ++i)
            basis->to_cosine[j][i] = (j == 0 ? 1.0 : 2.0) / LL_GGX_CHEB * (j % 2 ? -1.0 : 1.0) *
                                     cos(LL_PI * (double)j * ((double)i + 0.5) / LL_GGX_CHEB);
}

double ll_ggx_smith_g1(double tan_theta, double alpha)
{
    double a = alpha * tan_theta;
    return 2.0 / (1.0 + sqrt(1.0 + a * a));
}

/* c, s and r of E_beta = (c - d cos phi)^-2, c = 1 + beta, d = beta; s =
 * sqrt((c - d)(c + d)) without cancellation, r = d / (c + s) < 1. */
static void peak_constants(double beta, double *c, double *s, double *r)
{
    *c = 1.0 + beta;
    *s = sqrt(1.0 + 2.0 * beta);
    *r = beta / (*c + *s);
}

double ll_ggx_peak_mean(double beta)
{
    double c, s, r;
    peak_constants(beta, &c, &s, &r);
    return c / (s * s * s);
}

/* Term l of the cosine series relative to the first: 2 r^l (c + l s) / c. */
static double term_ratio(double beta, double l)
{
    double c, s, r;
    peak_constants(beta, &c, &s, &r);
    if (r == 0.0)
        return l == 0.0 ? 1.0 : 0.0;
    return 2.0 * exp(l * log(r)) * (c + l * s) / c;
}

/* Whether the term of order l has fallen below relerr times the first. */
static int term_below(double c, double s, double log_r, double l, double relerr)
{
    return 2.0 * exp(l * log_r) * (c + l * s) < relerr * c;
}

void ll_ggx_length_prepare(double beta, double relerr, size_t max_cap, ll_ggx_length *len)
{
    /* The first l with t(l) = log(2 (c + l s) / (relerr c)) + l log r < 0:
     * t is concave, so Newton's steps from the root's left (l log r alone
     * crosses first) land right of it and then close in from the right;
     * the integer found is checked against the terms themselves (a sharp
     * lobe's series has thousands of terms, which counting one by one
     * cost as much as the series). A cap at or below Newton's root is its
     * own answer; below it, the answer is the smaller of the cap and the
     * length walked to under max_cap, as the walk down from ceil(x) does
     * not depend on the cap and the walk up stops at the cap or the first
     * term below relerr, whichever comes first. */
    double c, s, r, log_r, l, x;
    int k;
    len->beta = beta;
    len->relerr = relerr;
    len->max_cap = max_cap;
    len->one = 0;
    len->x = HUGE_VAL;
    len->walked = max_cap;
    if (max_cap <= 1)
        return;
    peak_constants(beta, &c, &s, &r);
    log_r = r > 0.0 ? log(r) : 0.0;
    if (!(r > 0.0) || term_below(c, s, log_r, 1.0, relerr)) {
        len->one = 1;
        return;
    }
    x = fmax(1.0, log(0.5 * relerr) / log_r);
    for (k = 0; k < 8; ++k) {
        double t = log(2.0 * (c + x * s) / (relerr * c)) + x * log_r;
        double slope = s / (c + x * s) + log_r, step;
        if (!(slope < 0.0))
            break;
        step = t / slope;
        x -= step;
        if (fabs(step) < 0.01) /* the integer is settled below */
            break;
    }
    len->x = x;
    if (!(x < (double)max_cap))
        return;
    l = ceil(x);
    if (l < 1.0)
        l = 1.0;
    while (l > 1.0 && term_below(c, s, log_r, l - 1.0, relerr))
        l -= 1.0;
    while (l < (double)max_cap && !term_below(c, s, log_r, l, relerr))
        l += 1.0;
    len->walked = (size_t)l;
}

size_t ll_ggx_length_at(const ll_ggx_length *len, size_t cap)
{
    if (cap > len->max_cap) /* (not prepared that far) */
        return ll_ggx_peak_length(len->beta, len->relerr, cap);
    if (cap <= 1)
        return cap;
    if (len->one)
        return 1;
    if (!(len->x < (double)cap))
        return cap;
    return len->walked < cap ? len->walked : cap;
}

size_t ll_ggx_peak_length(double beta, double relerr, size_t cap)
{
    ll_ggx_length len;
    ll_ggx_length_prepare(beta, relerr, cap, &len);
    return ll_ggx_length_at(&len, cap);
}

double ll_ggx_max_beta(size_t n_orders, double relerr)
{
    /* term_ratio grows with beta: bisection in log beta. */
    double lo = log(1e-6), hi = log(1e16), n = (double)n_orders;
    int k;
    if (term_ratio(exp(hi), n) <= relerr)
        return exp(hi);
    if (term_ratio(exp(lo), n) > relerr)
        return exp(lo);
    for (k = 0; k < 200 && hi - lo > 1e-12; ++k) {
        double mid = 0.5 * (lo + hi);
        if (term_ratio(exp(mid), n) <= relerr)
            lo = mid;
        else
            hi = mid;
    }
    return exp(lo);
}

/* The series of E_beta p from p's two-sided coefficients b[j], j < n_b
 * (b_0 the mean, b_j half the amplitude of cos(j phi)); e: n_out + n_b
 * doubles. */
static void convolve(double beta, const double *b, size_t n_b, size_t n_out, double *out,
                     double *e)
{
    /* E_beta p with p = b_0 + sum_j 2 b_j cos(j phi): the two-sided
     * coefficient of order l is b_0 e_l + sum_(j >= 1) b_j (e_(l - j) +
     * e_(l + j)). From l = n_b - 1 on, every l - j >= 0 and e_k = r^k (c +
     * k s) / s^3 make that sum r^l ((c + l s) S_0 + S_1) / s^3 with
     *     S_0 = b_0 + sum_(j >= 1) b_j (r^-j + r^j),
     *     S_1 = s sum_(j >= 1) j b_j (r^j - r^-j),
     * one term per order instead of n_b (a sharp lobe has hundreds of
     * orders). For r below closed_r, r^-j would grow towards overflow;
     * such a peak is wide and its series short, summed term by term. */
    const double closed_r = 1e-2;
    double c, s, r, power = 1.0, inv_s3;
    size_t j, l, direct, n_e;
    peak_constants(beta, &c, &s, &r);
    inv_s3 = 1.0 / (s * s * s);
    direct = r < closed_r || n_out < n_b ? n_out : n_b;
    n_e = direct + n_b;
    for (l = 0; l < n_e; ++l) {
        e[l] = power * (c + (double)l * s) * inv_s3;
        power *= r;
    }
    if (direct <= LL_GGX_CHEB && n_b <= LL_GGX_CHEB) {
        /* The first orders side by side, each summed over j in order as
         * below: e_|l - j| from a mirrored copy, e_|k| at k + n_b - 1, so
         * that every l reads consecutive entries. */
        double mirror[3 * LL_GGX_CHEB], sum[LL_GGX_CHEB];
        for (l = 0; l + 1 < n_b; ++l)
            mirror[l] = e[n_b - 1 - l];
        for (l = 0; l < n_e; ++l)
            mirror[n_b - 1 + l] = e[l];
        for (l = 0; l < direct; ++l)
            sum[l] = b[0] * e[l];
        for (j = 1; j < n_b; ++j)
            for (l = 0; l < direct; ++l)
                sum[l] += b[j] * (mirror[n_b - 1 + l - j] + e[l + j]);
        for (l = 0; l < direct; ++l)
            out[l] = l == 0 ? sum[l] : 2.0 * sum[l];
    } else {
        for (l = 0; l < direct; ++l) {
            /* (j < l and j >= l apart: the same terms in the same order,
             * without a choice of index per term) */
            double total = b[0] * e[l];
            for (j = 1; j < n_b && j < l; ++j)
                total += b[j] * (e[l - j] + e[l + j]);
            for (; j < n_b; ++j)
                total += b[j] * (e[j - l] + e[l + j]);
            out[l] = l == 0 ? total : 2.0 * total;
        }
    }
    if (direct < n_out) {
        double s0 = b[0], s1 = 0.0, up = 1.0, down = 1.0, inv_r = 1.0 / r;
        for (j = 1; j < n_b; ++j) {
            up *= r;
            down *= inv_r;
            s0 += b[j] * (down + up);
            s1 += (double)j * b[j] * (up - down);
        }
        s1 *= s;
        power = 2.0 * inv_s3;
        for (l = 0; l < direct; ++l)
            power *= r;
        for (l = direct; l < n_out; ++l) {
            out[l] = power * ((c + (double)l * s) * s0 + s1);
            power *= r;
        }
    }
}

void ll_ggx_series(const ll_ggx_basis *basis, double beta, const double *g, size_t n_out,
                   double *out, double *scratch)
{
    double *b = scratch;
    size_t i, j;
    for (j = 0; j < LL_GGX_CHEB; ++j) {
        double sum = 0.0;
        for (i = 0; i < LL_GGX_CHEB; ++i)
            sum += basis->to_cosine[j][i] * g[i];
        b[j] = j == 0 ? sum : 0.5 * sum;
    }
    convolve(beta, b, LL_GGX_CHEB, n_out, out, scratch + LL_GGX_CHEB);
}

void ll_ggx_series_quadratic(double beta, const double *q, size_t n_out, double *out,
                             double *scratch)
{
    /* v = 1 - cos phi and v^2 = 3/2 - 2 cos phi + cos(2 phi) / 2. */
    double b[3];
    b[0] = q[0] + q[1] + 1.5 * q[2];
    b[1] = 0.5 * (-q[1] - 2.0 * q[2]);
    b[2] = 0.25 * q[2];
    convolve(beta, b, 3, n_out, out, scratch);
}
