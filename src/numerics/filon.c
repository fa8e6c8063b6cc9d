/*
 * Filon quadrature of cosine moments (see filon.h).
 */
#include "numerics/filon.h"
#include "numerics/filon_powers.h"

#include <math.h>
#include <string.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define FILON_HAVE_AVX 1
#include <immintrin.h>
#else
#define FILON_HAVE_AVX 0
#endif

#if FILON_HAVE_AVX
/* The processor's features, as the compiler's runtime detected them
 * before main: read-only here. */
static int have_avx(void)
{
    return __builtin_cpu_supports("avx");
}
#endif

/* The three moments of one panel [x1 - h, x1 + h] in u = phi - x1, for
 * theta = l h:
 *   integral u^0 cos(l u) du = 2 h   sinc(theta)
 *   integral u^1 sin(l u) du = 2 h^2 m1(theta), m1 = (sin - theta cos) / theta^2
 *   integral u^2 cos(l u) du = 2 h^3 m2(theta),
 *                              m2 = (theta^2 sin + 2 theta cos - 2 sin) / theta^3
 * given sin(theta), cos(theta). The closed forms lose about
 * log10(1 / theta^2) digits to cancellation (m2 ~ 1/3 from terms ~ 2/theta^2),
 * so below SMALL_THETA (at most 4e-13 relative error above it) the Taylor
 * series are summed instead: four terms reach 1e-17 there. */
#define SMALL_THETA 0.05

static void panel_moments(double theta, double s, double c, double *sinc, double *m1,
                          double *m2)
{
    if (theta > SMALL_THETA) {
        double t2 = theta * theta;
        *sinc = s / theta;
        *m1 = (s - theta * c) / t2;
        *m2 = (t2 * s + 2.0 * theta * c - 2.0 * s) / (t2 * theta);
    } else {
        /* sum_k (-1)^k theta^2k / (2k)! times 1/(2k+1), 1/((2k+1)(2k+3)),
         * 1/(2k+3) */
        double t2 = theta * theta;
        *sinc = 1.0 - t2 / 6.0 * (1.0 - t2 / 20.0 * (1.0 - t2 / 42.0));
        *m1 = theta * (1.0 / 3.0 - t2 / 30.0 * (1.0 - t2 / 28.0 * (1.0 - t2 / 54.0)));
        *m2 = 1.0 / 3.0 - t2 / 10.0 * (1.0 - t2 * (5.0 / 84.0) * (1.0 - t2 * (7.0 / 270.0)));
    }
}

/* The rule's per-order constants and the rotating panel phase. */
typedef struct filon_rule {
    size_t n, panels;
    double *w_end_c;  /* [n] h m2: weight of an end sample, times cos(l x1)   */
    double *w_end_s;  /* [n] h m1: times sin(l x1), + at the start, - at the end */
    double *w_mid;    /* [n] 2 h (sinc - m2): mid sample, times cos(l x1)      */
    double *cos_x, *sin_x; /* [n] cos, sin(l x1) of the first panel centre   */
    double *rot_c, *rot_s; /* [n] cos, sin(2 l h): advance by one panel      */
} filon_rule;

/* The rule's per-order constants of four chains of every fourth order,
 * lane j the orders first + 4 q + j, in one pass: cos and sin of l x1
 * into cos_x, sin_x; those of theta = l h, with theta, give the weights
 * (w_end_c, w_end_s, w_mid) and, doubled, the rotation by 2 l h (rot_c,
 * rot_s); each chain advanced by rotations by 4 x1 and 4 h (rx_c, rx_s,
 * rh_c, rh_s). c*, s*, t*: the chains' values at the next four, by lane.
 * The weights are panel_moments' closed forms (one division per order:
 * the reciprocal of theta), except that the scalar loop, which takes the
 * fours holding an order with theta <= SMALL_THETA, sums the series
 * there. The SSE2 and AVX paths do the scalar loop's operations lane by
 * lane. */
typedef struct phase_chains {
    double cx[4], sx[4], ct[4], st[4], order[4];
    double rx_c, rx_s, rh_c, rh_s, h;
} phase_chains;

/* The orders l .. n - 1 (l a multiple of 4), lane by lane. */
static void orders_scalar(phase_chains *q, size_t l, size_t n, filon_rule *r)
{
    size_t j;
    for (; l < n; l += 4)
        for (j = 0; j < 4; ++j) {
            double next;
            if (l + j < n) {
                double theta = q->order[j] * q->h, s = q->st[j], c = q->ct[j], sinc, m1, m2;
                if (theta <= SMALL_THETA) {
                    panel_moments(theta, s, c, &sinc, &m1, &m2);
                } else {
                    double inv = 1.0 / theta;
                    sinc = s * inv;
                    m1 = (s - theta * c) * inv * inv;
                    m2 = ((theta * theta) * s + 2.0 * theta * c - 2.0 * s) * (inv * inv) * inv;
                }
                r->w_end_c[l + j] = q->h * m2;
                r->w_end_s[l + j] = q->h * m1;
                r->w_mid[l + j] = 2.0 * q->h * (sinc - m2);
                r->cos_x[l + j] = q->cx[j];
                r->sin_x[l + j] = q->sx[j];
                r->rot_c[l + j] = (c - s) * (c + s);
                r->rot_s[l + j] = 2.0 * s * c;
            }
            q->order[j] += 4.0;
            next = q->cx[j] * q->rx_c - q->sx[j] * q->rx_s;
            q->sx[j] = q->sx[j] * q->rx_c + q->cx[j] * q->rx_s;
            q->cx[j] = next;
            next = q->ct[j] * q->rh_c - q->st[j] * q->rh_s;
            q->st[j] = q->st[j] * q->rh_c + q->ct[j] * q->rh_s;
            q->ct[j] = next;
        }
}

#if defined(__SSE2__)
#define ROTATE2(c, s, rc, rs)                                                      \
    do {                                                                           \
        __m128d next_ = _mm_sub_pd(_mm_mul_pd(c, rc), _mm_mul_pd(s, rs));          \
        s = _mm_add_pd(_mm_mul_pd(s, rc), _mm_mul_pd(c, rs));                      \
        c = next_;                                                                 \
    } while (0)

/* Two orders' weights and rotation (lanes l, l + 1) from theta = o h and
 * its sine and cosine st, ct. */
static void weights2(__m128d o, __m128d st, __m128d ct, double h, filon_rule *r, size_t l)
{
    __m128d vh = _mm_set1_pd(h), two = _mm_set1_pd(2.0), theta = _mm_mul_pd(o, vh);
    __m128d inv = _mm_div_pd(_mm_set1_pd(1.0), theta), sinc = _mm_mul_pd(st, inv);
    __m128d m1 = _mm_mul_pd(_mm_mul_pd(_mm_sub_pd(st, _mm_mul_pd(theta, ct)), inv), inv);
    __m128d m2 =
        _mm_mul_pd(_mm_mul_pd(_mm_sub_pd(_mm_add_pd(_mm_mul_pd(_mm_mul_pd(theta, theta), st),
                                                    _mm_mul_pd(_mm_mul_pd(two, theta), ct)),
                                         _mm_mul_pd(two, st)),
                              _mm_mul_pd(inv, inv)),
                   inv);
    _mm_storeu_pd(r->w_end_c + l, _mm_mul_pd(vh, m2));
    _mm_storeu_pd(r->w_end_s + l, _mm_mul_pd(vh, m1));
    _mm_storeu_pd(r->w_mid + l, _mm_mul_pd(_mm_set1_pd(2.0 * h), _mm_sub_pd(sinc, m2)));
    _mm_storeu_pd(r->rot_c + l, _mm_mul_pd(_mm_sub_pd(ct, st), _mm_add_pd(ct, st)));
    _mm_storeu_pd(r->rot_s + l, _mm_mul_pd(_mm_mul_pd(two, st), ct));
}

/* The chains' whole fours from l on; returns the orders done (from l)
 * and leaves the chains where the scalar rest goes on. */
static size_t orders_sse2(phase_chains *q, size_t l, size_t n, filon_rule *r)
{
    __m128d cx0 = _mm_loadu_pd(q->cx), cx1 = _mm_loadu_pd(q->cx + 2);
    __m128d sx0 = _mm_loadu_pd(q->sx), sx1 = _mm_loadu_pd(q->sx + 2);
    __m128d ct0 = _mm_loadu_pd(q->ct), ct1 = _mm_loadu_pd(q->ct + 2);
    __m128d st0 = _mm_loadu_pd(q->st), st1 = _mm_loadu_pd(q->st + 2);
    __m128d o0 = _mm_loadu_pd(q->order), o1 = _mm_loadu_pd(q->order + 2);
    __m128d rxc = _mm_set1_pd(q->rx_c), rxs = _mm_set1_pd(q->rx_s);
    __m128d rhc = _mm_set1_pd(q->rh_c), rhs = _mm_set1_pd(q->rh_s);
    __m128d four = _mm_set1_pd(4.0);
    size_t start = l;
    for (; l + 4 <= n; l += 4) {
        weights2(o0, st0, ct0, q->h, r, l);
        weights2(o1, st1, ct1, q->h, r, l + 2);
        _mm_storeu_pd(r->cos_x + l, cx0);
        _mm_storeu_pd(r->cos_x + l + 2, cx1);
        _mm_storeu_pd(r->sin_x + l, sx0);
        _mm_storeu_pd(r->sin_x + l + 2, sx1);
        o0 = _mm_add_pd(o0, four);
        o1 = _mm_add_pd(o1, four);
        ROTATE2(cx0, sx0, rxc, rxs);
        ROTATE2(cx1, sx1, rxc, rxs);
        ROTATE2(ct0, st0, rhc, rhs);
        ROTATE2(ct1, st1, rhc, rhs);
    }
    _mm_storeu_pd(q->cx, cx0);
    _mm_storeu_pd(q->cx + 2, cx1);
    _mm_storeu_pd(q->sx, sx0);
    _mm_storeu_pd(q->sx + 2, sx1);
    _mm_storeu_pd(q->ct, ct0);
    _mm_storeu_pd(q->ct + 2, ct1);
    _mm_storeu_pd(q->st, st0);
    _mm_storeu_pd(q->st + 2, st1);
    _mm_storeu_pd(q->order, o0);
    _mm_storeu_pd(q->order + 2, o1);
    return l - start;
}

#undef ROTATE2
#endif

#if FILON_HAVE_AVX
#define ROTATE4(c, s, rc, rs)                                                      \
    do {                                                                           \
        __m256d next_ = _mm256_sub_pd(_mm256_mul_pd(c, rc), _mm256_mul_pd(s, rs)); \
        s = _mm256_add_pd(_mm256_mul_pd(s, rc), _mm256_mul_pd(c, rs));             \
        c = next_;                                                                 \
    } while (0)

/* orders_sse2 with the four chains in one AVX register. */
__attribute__((target("avx"))) static size_t orders_avx(phase_chains *q, size_t l, size_t n,
                                                        filon_rule *r)
{
    __m256d cx = _mm256_loadu_pd(q->cx), sx = _mm256_loadu_pd(q->sx);
    __m256d ct = _mm256_loadu_pd(q->ct), st = _mm256_loadu_pd(q->st);
    __m256d o = _mm256_loadu_pd(q->order);
    __m256d rxc = _mm256_set1_pd(q->rx_c), rxs = _mm256_set1_pd(q->rx_s);
    __m256d rhc = _mm256_set1_pd(q->rh_c), rhs = _mm256_set1_pd(q->rh_s);
    __m256d vh = _mm256_set1_pd(q->h), h2 = _mm256_set1_pd(2.0 * q->h);
    __m256d two = _mm256_set1_pd(2.0), one = _mm256_set1_pd(1.0), four = _mm256_set1_pd(4.0);
    size_t start = l;
    for (; l + 4 <= n; l += 4) {
        __m256d theta = _mm256_mul_pd(o, vh), inv = _mm256_div_pd(one, theta);
        __m256d sinc = _mm256_mul_pd(st, inv);
        __m256d m1 =
            _mm256_mul_pd(_mm256_mul_pd(_mm256_sub_pd(st, _mm256_mul_pd(theta, ct)), inv), inv);
        __m256d m2 = _mm256_mul_pd(
            _mm256_mul_pd(
                _mm256_sub_pd(_mm256_add_pd(_mm256_mul_pd(_mm256_mul_pd(theta, theta), st),
                                            _mm256_mul_pd(_mm256_mul_pd(two, theta), ct)),
                              _mm256_mul_pd(two, st)),
                _mm256_mul_pd(inv, inv)),
            inv);
        _mm256_storeu_pd(r->w_end_c + l, _mm256_mul_pd(vh, m2));
        _mm256_storeu_pd(r->w_end_s + l, _mm256_mul_pd(vh, m1));
        _mm256_storeu_pd(r->w_mid + l, _mm256_mul_pd(h2, _mm256_sub_pd(sinc, m2)));
        _mm256_storeu_pd(r->rot_c + l, _mm256_mul_pd(_mm256_sub_pd(ct, st), _mm256_add_pd(ct, st)));
        _mm256_storeu_pd(r->rot_s + l, _mm256_mul_pd(_mm256_mul_pd(two, st), ct));
        _mm256_storeu_pd(r->cos_x + l, cx);
        _mm256_storeu_pd(r->sin_x + l, sx);
        o = _mm256_add_pd(o, four);
        ROTATE4(cx, sx, rxc, rxs);
        ROTATE4(ct, st, rhc, rhs);
    }
    _mm256_storeu_pd(q->cx, cx);
    _mm256_storeu_pd(q->sx, sx);
    _mm256_storeu_pd(q->ct, ct);
    _mm256_storeu_pd(q->st, st);
    _mm256_storeu_pd(q->order, o);
    return l - start;
}

#undef ROTATE4
#endif

/* The orders first .. first + n - 1; scratch: 7 n doubles. The sines and
 * cosines of l x1 and l h come from rotations instead of 4 n calls to sin
 * and cos: those of the first order are computed directly, the next three
 * orders' by rotations by x1 and h, and from there the four chains of
 * every fourth order by rotations by 4 x1 and 4 h (one rounding per four
 * orders), side by side in vector registers, each four's weights and
 * rotation computed where its phases are (the fours holding the few
 * orders below SMALL_THETA by the scalar loop, which sums their Taylor
 * series). Lane by lane the operations are those of the scalar loop,
 * which does the same where SSE2 or AVX is not: the moments do not
 * depend on the processor. */
static void rule_init(filon_rule *r, size_t n_samples, double a, double b, size_t first,
                      size_t n, double *scratch)
{
    double h = (b - a) / (double)(n_samples - 1), x1 = a + h, l0 = (double)first;
    double c1 = cos(x1), s1 = sin(x1), ch = cos(h), sh = sin(h), c2, s2;
    phase_chains q;
    size_t l, j, small;
    r->n = n;
    r->panels = (n_samples - 1) / 2;
    r->w_end_c = scratch;
    r->w_end_s = scratch + n;
    r->w_mid = scratch + 2 * n;
    r->cos_x = scratch + 3 * n;
    r->sin_x = scratch + 4 * n;
    r->rot_c = scratch + 5 * n;
    r->rot_s = scratch + 6 * n;
    q.cx[0] = first ? cos(l0 * x1) : 1.0;
    q.sx[0] = first ? sin(l0 * x1) : 0.0;
    q.ct[0] = first ? cos(l0 * h) : 1.0;
    q.st[0] = first ? sin(l0 * h) : 0.0;
    q.order[0] = l0;
    for (j = 1; j < 4; ++j) {
        q.cx[j] = q.cx[j - 1] * c1 - q.sx[j - 1] * s1;
        q.sx[j] = q.sx[j - 1] * c1 + q.cx[j - 1] * s1;
        q.ct[j] = q.ct[j - 1] * ch - q.st[j - 1] * sh;
        q.st[j] = q.st[j - 1] * ch + q.ct[j - 1] * sh;
        q.order[j] = l0 + (double)j;
    }
    c2 = (c1 - s1) * (c1 + s1);
    s2 = 2.0 * s1 * c1;
    q.rx_c = (c2 - s2) * (c2 + s2);
    q.rx_s = 2.0 * s2 * c2;
    c2 = (ch - sh) * (ch + sh);
    s2 = 2.0 * sh * ch;
    q.rh_c = (c2 - s2) * (c2 + s2);
    q.rh_s = 2.0 * s2 * c2;
    q.h = h;
    /* the fours holding an order with theta <= SMALL_THETA (theta grows
     * with the order) */
    for (small = 0; small < n && (l0 + (double)small) * h <= SMALL_THETA; ++small)
        ;
    l = (small + 3) & ~(size_t)3;
    if (l > n)
        l = n;
    orders_scalar(&q, 0, l, r);
#if FILON_HAVE_AVX
    if (have_avx())
        l += orders_avx(&q, l, n, r);
#endif
#if defined(__SSE2__)
    l += orders_sse2(&q, l, n, r);
#endif
    orders_scalar(&q, l, n, r);
}

/* The panels' sum of one order is
 *   w_end_c S_ends + w_mid S_mid + w_end_s S_diff,
 * S_ends = sum_p cos(l x_p) (f_2p + f_2p+2), S_mid = sum_p cos(l x_p)
 * f_2p+1, S_diff = sum_p sin(l x_p) (f_2p - f_2p+2): three products and
 * sums per panel and order, the weights applied once at the end (where
 * each panel took five products), and the phase advanced by 2h (angle
 * addition; the error grows by about one rounding per panel). */
#define FILON_STEP(se, sm, sd, c, s, l)                                            \
    do {                                                                           \
        double c_ = (c), s_ = (s);                                                 \
        (se) += c_ * ends;                                                         \
        (sm) += c_ * f1;                                                           \
        (sd) += s_ * diff;                                                         \
        (c) = c_ * rc[l] - s_ * rs[l];                                             \
        (s) = s_ * rc[l] + c_ * rs[l];                                             \
    } while (0)

/* One order's sums into its moment. */
#define FILON_END(acc, se, sm, sd, l) ((acc) += wc[l] * (se) + wm[l] * (sm) + ws[l] * (sd))

#if defined(__SSE2__)
/* FILON_STEP for the two orders of each of the vectors c and s (lanes l, l
 * + 1 of the rotations rc, rs): the same operations in the same order per
 * lane, so the same roundings as one order at a time. */
#define FILON_STEP2(se, sm, sd, c, s, rc, rs)                                      \
    do {                                                                           \
        __m128d c_ = (c), s_ = (s);                                                \
        (se) = _mm_add_pd((se), _mm_mul_pd(c_, ends));                             \
        (sm) = _mm_add_pd((sm), _mm_mul_pd(c_, mid));                              \
        (sd) = _mm_add_pd((sd), _mm_mul_pd(s_, diff));                             \
        (c) = _mm_sub_pd(_mm_mul_pd(c_, rc), _mm_mul_pd(s_, rs));                  \
        (s) = _mm_add_pd(_mm_mul_pd(s_, rc), _mm_mul_pd(c_, rs));                  \
    } while (0)

/* FILON_END for the orders l, l + 1. */
static void filon_end2(double *acc, __m128d se, __m128d sm, __m128d sd, const double *wc,
                       const double *wm, const double *ws)
{
    _mm_storeu_pd(acc, _mm_add_pd(_mm_loadu_pd(acc),
                                  _mm_add_pd(_mm_add_pd(_mm_mul_pd(_mm_loadu_pd(wc), se),
                                                        _mm_mul_pd(_mm_loadu_pd(wm), sm)),
                                             _mm_mul_pd(_mm_loadu_pd(ws), sd))));
}

/* accumulate's orders in pairs, two pairs at a time while four remain
 * (the baseline of x86-64 has two doubles per register); returns the
 * orders done. */
static size_t accumulate_pairs(size_t panels, size_t n, const double *g, double *restrict acc,
                               const double *restrict cx, const double *restrict sx,
                               const double *restrict wc, const double *restrict ws,
                               const double *restrict wm, const double *restrict rc,
                               const double *restrict rs)
{
    size_t p, l;
    for (l = 0; l + 4 <= n; l += 4) {
        __m128d c0 = _mm_loadu_pd(cx + l), c1 = _mm_loadu_pd(cx + l + 2);
        __m128d s0 = _mm_loadu_pd(sx + l), s1 = _mm_loadu_pd(sx + l + 2);
        __m128d rc0 = _mm_loadu_pd(rc + l), rc1 = _mm_loadu_pd(rc + l + 2);
        __m128d rs0 = _mm_loadu_pd(rs + l), rs1 = _mm_loadu_pd(rs + l + 2);
        __m128d se0 = _mm_setzero_pd(), sm0 = _mm_setzero_pd(), sd0 = _mm_setzero_pd();
        __m128d se1 = _mm_setzero_pd(), sm1 = _mm_setzero_pd(), sd1 = _mm_setzero_pd();
        for (p = 0; p < panels; ++p) {
            double f0 = g[2 * p], f2 = g[2 * p + 2];
            __m128d ends = _mm_set1_pd(f0 + f2), diff = _mm_set1_pd(f0 - f2);
            __m128d mid = _mm_set1_pd(g[2 * p + 1]);
            FILON_STEP2(se0, sm0, sd0, c0, s0, rc0, rs0);
            FILON_STEP2(se1, sm1, sd1, c1, s1, rc1, rs1);
        }
        filon_end2(acc + l, se0, sm0, sd0, wc + l, wm + l, ws + l);
        filon_end2(acc + l + 2, se1, sm1, sd1, wc + l + 2, wm + l + 2, ws + l + 2);
    }
    for (; l + 2 <= n; l += 2) {
        __m128d c0 = _mm_loadu_pd(cx + l), s0 = _mm_loadu_pd(sx + l);
        __m128d rc0 = _mm_loadu_pd(rc + l), rs0 = _mm_loadu_pd(rs + l);
        __m128d se0 = _mm_setzero_pd(), sm0 = _mm_setzero_pd(), sd0 = _mm_setzero_pd();
        for (p = 0; p < panels; ++p) {
            double f0 = g[2 * p], f2 = g[2 * p + 2];
            __m128d ends = _mm_set1_pd(f0 + f2), diff = _mm_set1_pd(f0 - f2);
            __m128d mid = _mm_set1_pd(g[2 * p + 1]);
            FILON_STEP2(se0, sm0, sd0, c0, s0, rc0, rs0);
        }
        filon_end2(acc + l, se0, sm0, sd0, wc + l, wm + l, ws + l);
    }
    return l;
}

#undef FILON_STEP2
#endif

#if FILON_HAVE_AVX
/* FILON_STEP2 for four orders per AVX register, chosen at run time
 * (docs/style.md, item 12): additions and multiplications alone, no fused
 * ones, so each order's roundings are those of the other paths. */
#define FILON_STEP4(se, sm, sd, c, s, rc, rs)                                      \
    do {                                                                           \
        __m256d c_ = (c), s_ = (s);                                                \
        (se) = _mm256_add_pd((se), _mm256_mul_pd(c_, ends));                       \
        (sm) = _mm256_add_pd((sm), _mm256_mul_pd(c_, mid));                        \
        (sd) = _mm256_add_pd((sd), _mm256_mul_pd(s_, diff));                       \
        (c) = _mm256_sub_pd(_mm256_mul_pd(c_, rc), _mm256_mul_pd(s_, rs));         \
        (s) = _mm256_add_pd(_mm256_mul_pd(s_, rc), _mm256_mul_pd(c_, rs));         \
    } while (0)

/* filon_end2 for the orders l .. l + 3. */
__attribute__((target("avx"))) static void filon_end4(double *acc, __m256d se, __m256d sm,
                                                      __m256d sd, const double *wc,
                                                      const double *wm, const double *ws)
{
    _mm256_storeu_pd(
        acc, _mm256_add_pd(_mm256_loadu_pd(acc),
                           _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(_mm256_loadu_pd(wc), se),
                                                       _mm256_mul_pd(_mm256_loadu_pd(wm), sm)),
                                         _mm256_mul_pd(_mm256_loadu_pd(ws), sd))));
}

/* accumulate's orders four at a time, eight while eight remain; returns
 * the orders done. */
__attribute__((target("avx"))) static size_t
accumulate_quads(size_t panels, size_t n, const double *g, double *restrict acc,
                 const double *restrict cx, const double *restrict sx,
                 const double *restrict wc, const double *restrict ws,
                 const double *restrict wm, const double *restrict rc,
                 const double *restrict rs)
{
    size_t p, l;
    for (l = 0; l + 8 <= n; l += 8) {
        __m256d c0 = _mm256_loadu_pd(cx + l), c1 = _mm256_loadu_pd(cx + l + 4);
        __m256d s0 = _mm256_loadu_pd(sx + l), s1 = _mm256_loadu_pd(sx + l + 4);
        __m256d rc0 = _mm256_loadu_pd(rc + l), rc1 = _mm256_loadu_pd(rc + l + 4);
        __m256d rs0 = _mm256_loadu_pd(rs + l), rs1 = _mm256_loadu_pd(rs + l + 4);
        __m256d se0 = _mm256_setzero_pd(), sm0 = _mm256_setzero_pd(), sd0 = _mm256_setzero_pd();
        __m256d se1 = _mm256_setzero_pd(), sm1 = _mm256_setzero_pd(), sd1 = _mm256_setzero_pd();
        for (p = 0; p < panels; ++p) {
            double f0 = g[2 * p], f2 = g[2 * p + 2];
            __m256d ends = _mm256_set1_pd(f0 + f2), diff = _mm256_set1_pd(f0 - f2);
            __m256d mid = _mm256_set1_pd(g[2 * p + 1]);
            FILON_STEP4(se0, sm0, sd0, c0, s0, rc0, rs0);
            FILON_STEP4(se1, sm1, sd1, c1, s1, rc1, rs1);
        }
        filon_end4(acc + l, se0, sm0, sd0, wc + l, wm + l, ws + l);
        filon_end4(acc + l + 4, se1, sm1, sd1, wc + l + 4, wm + l + 4, ws + l + 4);
    }
    for (; l + 4 <= n; l += 4) {
        __m256d c0 = _mm256_loadu_pd(cx + l), s0 = _mm256_loadu_pd(sx + l);
        __m256d rc0 = _mm256_loadu_pd(rc + l), rs0 = _mm256_loadu_pd(rs + l);
        __m256d se0 = _mm256_setzero_pd(), sm0 = _mm256_setzero_pd(), sd0 = _mm256_setzero_pd();
        for (p = 0; p < panels; ++p) {
            double f0 = g[2 * p], f2 = g[2 * p + 2];
            __m256d ends = _mm256_set1_pd(f0 + f2), diff = _mm256_set1_pd(f0 - f2);
            __m256d mid = _mm256_set1_pd(g[2 * p + 1]);
            FILON_STEP4(se0, sm0, sd0, c0, s0, rc0, rs0);
        }
        filon_end4(acc + l, se0, sm0, sd0, wc + l, wm + l, ws + l);
    }
    return l;
}

#undef FILON_STEP4

#endif

/* The panels' sum. Four orders at a time keep their phases and sums in
 * registers over all panels (one load and store of each per four orders
 * instead of per panel); per order the operations are those of one panel
 * after the other, as order by order. */
static void accumulate(size_t panels, size_t n, const double *g, double *restrict acc,
                       const double *restrict cx, const double *restrict sx,
                       const double *restrict wc, const double *restrict ws,
                       const double *restrict wm, const double *restrict rc,
                       const double *restrict rs)
{
    size_t p, l = 0;
#if FILON_HAVE_AVX
    if (have_avx())
        l = accumulate_quads(panels, n, g, acc, cx, sx, wc, ws, wm, rc, rs);
#endif
#if defined(__SSE2__)
    l += accumulate_pairs(panels, n - l, g, acc + l, cx + l, sx + l, wc + l, ws + l, wm + l,
                          rc + l, rs + l);
#endif
    for (; l + 2 <= n; l += 2) {
        double c0 = cx[l], c1 = cx[l + 1], s0 = sx[l], s1 = sx[l + 1];
        double se0 = 0.0, sm0 = 0.0, sd0 = 0.0, se1 = 0.0, sm1 = 0.0, sd1 = 0.0;
        for (p = 0; p < panels; ++p) {
            double f0 = g[2 * p], f1 = g[2 * p + 1], f2 = g[2 * p + 2];
            double ends = f0 + f2, diff = f0 - f2;
            FILON_STEP(se0, sm0, sd0, c0, s0, l);
            FILON_STEP(se1, sm1, sd1, c1, s1, l + 1);
        }
        FILON_END(acc[l], se0, sm0, sd0, l);
        FILON_END(acc[l + 1], se1, sm1, sd1, l + 1);
    }
    for (; l < n; ++l) {
        double c = cx[l], s = sx[l], se = 0.0, sm = 0.0, sd = 0.0;
        for (p = 0; p < panels; ++p) {
            double f0 = g[2 * p], f1 = g[2 * p + 1], f2 = g[2 * p + 2];
            double ends = f0 + f2, diff = f0 - f2;
            FILON_STEP(se, sm, sd, c, s, l);
        }
        FILON_END(acc[l], se, sm, sd, l);
    }
}

#undef FILON_STEP
#undef FILON_END

/* The panel integral of the quadratic q through (f0, f1, f2) at
 * x1 - h, x1, x1 + h, with q = f1 + d1 u + d2 u^2, is
 *   cos(l x1) (f1 M0 + d2 M2) - sin(l x1) d1 M1,
 * which, collected by sample, gives the weights of filon_rule. */
void ll_filon_moments(const double *g, size_t n_samples, double a, double b,
                      size_t n_moments, double *moments, double *scratch)
{
    ll_filon_moments_from(g, n_samples, a, b, 0, n_moments, moments, scratch);
}

/* Low orders of a narrow interval: where l (b - a) / 2 <= NARROW_TAU,
 * cos(l phi) = cos(l x_c) cos(l u) - sin(l x_c) sin(l u), u = phi - x_c
 * about the centre x_c, and the Taylor series of cos(l u) and sin(l u) in
 * l u make the moment
 *   cos(l x_c) sum_(k even) (-1)^(k/2) l^k M_k / k!
 *     - sin(l x_c) sum_(k odd) (-1)^((k-1)/2) l^k M_k / k!,
 * M_k = integral q u^k du of the same piecewise quadratic q: the panels
 * are summed once per power instead of once per order (the pieces graded
 * towards a kink are this narrow for every order, and there each order
 * cost its panels). Each order takes the powers k < K whose bound
 * (l (b - a) / 2)^k / k! on their share (relative to the integral of |q|)
 * reaches NARROW_GOAL: term_needed[k - 1] = (NARROW_GOAL k!)^(1/k) is
 * where term k starts to count, so K <= 27 at NARROW_TAU. Which orders
 * take this form, and with how many powers, depends on the order and the
 * interval alone, not on how many orders are asked for: a series computed
 * to fewer orders is a prefix of one to more, bit for bit. Where the
 * piece's sample count has them, M_k come from fixed weights of the
 * samples (filon_powers.h); elsewhere the moment of the panel [x1 - h, x1
 * + h] with q = A + B u + C u^2 in u is A P_(k+1) + B P_(k+2) + C
 * P_(k+3), P_j = (beta^j - alpha^j) / j over its ends alpha, beta (the
 * expansion about the centre costs about two digits of cancellation at the
 * outer panels). The terms of the series reach tau^3 / 3! = 4.5 times the
 * integral of |q| at NARROW_TAU: the sum's rounding stays near 1e-15 of
 * it, as the rule's (a rounding per panel of the phase). */
#define NARROW_TAU 3.0
#define NARROW_POWERS LL_FILON_POWERS /* = 1 + the terms of term_needed at most
                                       * NARROW_TAU */

static const double term_needed[NARROW_POWERS - 1] = {
    1.0000000000000013e-15, 4.4721359549995863e-08, 1.8171205928321391e-05,
    0.00039359793425308617, 0.0026051710846973514,  0.0094672115710563581,
    0.024325484845607006,   0.050198422026142796,   0.089347988868909947,
    0.14321097559395296,    0.21250922748656381,    0.29741400390991907,
    0.39770405980972057,    0.51289582984850846,    0.64234247497797614,
    0.78530565461182733,    0.94100572489375511,    1.1086557743950802,
    1.287483945295584,      1.4767474542135719,     1.6757408354434047,
    1.8838002279380828,     2.1003050009539264,     2.3246776287698836,
    2.5563824486584048,     2.7949237399284534,
};

/* The powers an order with l (b - a) / 2 = tau takes, from at least k:
 * the first k with tau below term_needed[k - 1] (or NARROW_POWERS), by
 * bisection from k = 1 (term_needed increases), else step by step (the
 * next eight orders' from the last eight's). */
static size_t narrow_terms(double tau, size_t k)
{
    if (k == 1) {
        size_t hi = NARROW_POWERS;
        while (k < hi) {
            size_t mid = k + (hi - k) / 2;
            if (tau >= term_needed[mid - 1])
                k = mid + 1;
            else
                hi = mid;
        }
        return k;
    }
    while (k < NARROW_POWERS && tau >= term_needed[k - 1])
        ++k;
    return k;
}

/* The narrow terms go eight orders at a time, 8q .. 8q + 7, all with the
 * powers of the last (so an order takes the same powers whether the rest
 * of its eight is asked for or not; Horner's steps then share their
 * coefficients and loop), lane j the order 8q + j: its phase cos, sin(l
 * x_c) from eight chains of rotations by 8 x_c, and its term
 *   cos(l x_c) E(l^2) - sin(l x_c) l O(l^2),
 * E and O the even and odd sums by Horner's rule in l^2. Lanes outside
 * the orders asked for are computed and dropped. The AVX, SSE2 and
 * scalar loops do the same operations lane by lane. */
#define NARROW_LANES 8

typedef struct narrow_run {
    const double *even, *odd;
    double half, rc, rs;     /* (b - a) / 2; the rotation by 8 x_c           */
    double c[NARROW_LANES], s[NARROW_LANES]; /* the first eight's phases    */
    size_t start, first, end; /* the first eight's order; the orders asked for */
} narrow_run;

/* Add lane j's term of the eight at order start to its moment where that
 * order is asked for. */
static void narrow_keep(const narrow_run *r, size_t start, const double *term, double *moments)
{
    size_t j;
    for (j = 0; j < NARROW_LANES; ++j)
        if (start + j >= r->first && start + j < r->end)
            moments[start + j - r->first] += term[j];
}

#if !defined(__SSE2__)
static void narrow_scalar(const narrow_run *r, double *moments)
{
    double c[NARROW_LANES], s[NARROW_LANES], term[NARROW_LANES];
    size_t terms = 1, j, k, eight;
    memcpy(c, r->c, sizeof c);
    memcpy(s, r->s, sizeof s);
    for (eight = r->start; eight < r->end; eight += NARROW_LANES) {
        terms = narrow_terms((double)(eight + NARROW_LANES - 1) * r->half, terms);
        for (j = 0; j < NARROW_LANES; ++j) {
            double order = (double)(eight + j), lambda = order * order, e = 0.0, o = 0.0, next;
            for (k = (terms - 1) / 2 + 1; k-- > 0;)
                e = e * lambda + r->even[k];
            for (k = terms / 2; k-- > 0;)
                o = o * lambda + r->odd[k];
            term[j] = c[j] * e - s[j] * order * o;
            next = c[j] * r->rc - s[j] * r->rs;
            s[j] = s[j] * r->rc + c[j] * r->rs;
            c[j] = next;
        }
        narrow_keep(r, eight, term, moments);
    }
}
#endif

#if defined(__SSE2__)
static void narrow_sse2(const narrow_run *r, double *moments)
{
    __m128d c[4], s[4], o[4];
    __m128d rc = _mm_set1_pd(r->rc), rs = _mm_set1_pd(r->rs), step = _mm_set1_pd(8.0);
    size_t eight, terms = 1, k, i;
    for (i = 0; i < 4; ++i) {
        c[i] = _mm_loadu_pd(r->c + 2 * i);
        s[i] = _mm_loadu_pd(r->s + 2 * i);
        o[i] = _mm_set_pd((double)(r->start + 2 * i + 1), (double)(r->start + 2 * i));
    }
    for (eight = r->start; eight < r->end; eight += NARROW_LANES) {
        __m128d lambda[4], e[4], d[4], t[4];
        terms = narrow_terms((double)(eight + NARROW_LANES - 1) * r->half, terms);
        for (i = 0; i < 4; ++i) {
            lambda[i] = _mm_mul_pd(o[i], o[i]);
            e[i] = _mm_setzero_pd();
            d[i] = _mm_setzero_pd();
        }
        for (k = (terms - 1) / 2 + 1; k-- > 0;) {
            __m128d w = _mm_set1_pd(r->even[k]);
            for (i = 0; i < 4; ++i)
                e[i] = _mm_add_pd(_mm_mul_pd(e[i], lambda[i]), w);
        }
        for (k = terms / 2; k-- > 0;) {
            __m128d w = _mm_set1_pd(r->odd[k]);
            for (i = 0; i < 4; ++i)
                d[i] = _mm_add_pd(_mm_mul_pd(d[i], lambda[i]), w);
        }
        for (i = 0; i < 4; ++i) {
            __m128d next = _mm_sub_pd(_mm_mul_pd(c[i], rc), _mm_mul_pd(s[i], rs));
            t[i] = _mm_sub_pd(_mm_mul_pd(c[i], e[i]), _mm_mul_pd(_mm_mul_pd(s[i], o[i]), d[i]));
            s[i] = _mm_add_pd(_mm_mul_pd(s[i], rc), _mm_mul_pd(c[i], rs));
            c[i] = next;
            o[i] = _mm_add_pd(o[i], step);
        }
        if (eight >= r->first && eight + NARROW_LANES <= r->end) {
            double *m = moments + (eight - r->first);
            for (i = 0; i < 4; ++i)
                _mm_storeu_pd(m + 2 * i, _mm_add_pd(_mm_loadu_pd(m + 2 * i), t[i]));
        } else {
            double term[NARROW_LANES];
            for (i = 0; i < 4; ++i)
                _mm_storeu_pd(term + 2 * i, t[i]);
            narrow_keep(r, eight, term, moments);
        }
    }
}
#endif

#if FILON_HAVE_AVX
__attribute__((target("avx"))) static void narrow_avx(const narrow_run *r, double *moments)
{
    __m256d c0 = _mm256_loadu_pd(r->c), c1 = _mm256_loadu_pd(r->c + 4);
    __m256d s0 = _mm256_loadu_pd(r->s), s1 = _mm256_loadu_pd(r->s + 4);
    __m256d rc = _mm256_set1_pd(r->rc), rs = _mm256_set1_pd(r->rs);
    __m256d step = _mm256_set1_pd(8.0), start = _mm256_set1_pd((double)r->start);
    __m256d o0 = _mm256_add_pd(start, _mm256_set_pd(3.0, 2.0, 1.0, 0.0));
    __m256d o1 = _mm256_add_pd(start, _mm256_set_pd(7.0, 6.0, 5.0, 4.0));
    size_t eight, terms = 1, k;
    for (eight = r->start; eight < r->end; eight += NARROW_LANES) {
        __m256d l0 = _mm256_mul_pd(o0, o0), l1 = _mm256_mul_pd(o1, o1);
        __m256d e0 = _mm256_setzero_pd(), e1 = _mm256_setzero_pd();
        __m256d d0 = _mm256_setzero_pd(), d1 = _mm256_setzero_pd(), t0, t1, n0, n1;
        terms = narrow_terms((double)(eight + NARROW_LANES - 1) * r->half, terms);
        for (k = (terms - 1) / 2 + 1; k-- > 0;) {
            __m256d w = _mm256_broadcast_sd(r->even + k);
            e0 = _mm256_add_pd(_mm256_mul_pd(e0, l0), w);
            e1 = _mm256_add_pd(_mm256_mul_pd(e1, l1), w);
        }
        for (k = terms / 2; k-- > 0;) {
            __m256d w = _mm256_broadcast_sd(r->odd + k);
            d0 = _mm256_add_pd(_mm256_mul_pd(d0, l0), w);
            d1 = _mm256_add_pd(_mm256_mul_pd(d1, l1), w);
        }
        t0 = _mm256_sub_pd(_mm256_mul_pd(c0, e0), _mm256_mul_pd(_mm256_mul_pd(s0, o0), d0));
        t1 = _mm256_sub_pd(_mm256_mul_pd(c1, e1), _mm256_mul_pd(_mm256_mul_pd(s1, o1), d1));
        if (eight >= r->first && eight + NARROW_LANES <= r->end) {
            double *m = moments + (eight - r->first);
            _mm256_storeu_pd(m, _mm256_add_pd(_mm256_loadu_pd(m), t0));
            _mm256_storeu_pd(m + 4, _mm256_add_pd(_mm256_loadu_pd(m + 4), t1));
        } else {
            double term[NARROW_LANES];
            _mm256_storeu_pd(term, t0);
            _mm256_storeu_pd(term + 4, t1);
            narrow_keep(r, eight, term, moments);
        }
        n0 = _mm256_sub_pd(_mm256_mul_pd(c0, rc), _mm256_mul_pd(s0, rs));
        n1 = _mm256_sub_pd(_mm256_mul_pd(c1, rc), _mm256_mul_pd(s1, rs));
        s0 = _mm256_add_pd(_mm256_mul_pd(s0, rc), _mm256_mul_pd(c0, rs));
        s1 = _mm256_add_pd(_mm256_mul_pd(s1, rc), _mm256_mul_pd(c1, rs));
        c0 = n0;
        c1 = n1;
        o0 = _mm256_add_pd(o0, step);
        o1 = _mm256_add_pd(o1, step);
    }
}
#endif

/* The narrow terms of the orders first .. first + count - 1 of a piece
 * centred on x_c into moments. The phases start at the eight holding
 * first: the first lane's directly, the next seven by rotations by x_c. */
static void narrow_orders(const double *even, const double *odd, double half, double x_c,
                          size_t first, size_t count, double *moments)
{
    narrow_run r;
    double c1 = cos(x_c), s1 = sin(x_c), c2, s2;
    size_t j;
    r.even = even;
    r.odd = odd;
    r.half = half;
    r.first = first;
    r.end = first + count;
    r.start = first & ~(size_t)(NARROW_LANES - 1);
    r.c[0] = r.start ? cos((double)r.start * x_c) : 1.0;
    r.s[0] = r.start ? sin((double)r.start * x_c) : 0.0;
    for (j = 1; j < NARROW_LANES; ++j) {
        r.c[j] = r.c[j - 1] * c1 - r.s[j - 1] * s1;
        r.s[j] = r.s[j - 1] * c1 + r.c[j - 1] * s1;
    }
    /* the rotation by 8 x_c: x_c doubled three times */
    c2 = (c1 - s1) * (c1 + s1);
    s2 = 2.0 * s1 * c1;
    r.rc = (c2 - s2) * (c2 + s2);
    r.rs = 2.0 * s2 * c2;
    c2 = (r.rc - r.rs) * (r.rc + r.rs);
    s2 = 2.0 * r.rs * r.rc;
    r.rc = c2;
    r.rs = s2;
#if FILON_HAVE_AVX
    if (have_avx()) {
        narrow_avx(&r, moments);
        return;
    }
#endif
#if defined(__SSE2__)
    narrow_sse2(&r, moments);
#else
    narrow_scalar(&r, moments);
#endif
}

/* The powers' sums of the piece, powers of them (or all, where the
 * piece's sample count has a table of their weights: filon_powers.h, a
 * fixed sum of its samples per power instead of each panel's powers),
 * into kept's even and odd (Horner's coefficients in l^2). */
static void narrow_sums_of(const double *g, size_t n_samples, double a, double b, size_t powers,
                           ll_filon_kept *kept)
{
    double centre = 0.5 * (a + b), h = (b - a) / (double)(n_samples - 1);
    double inv[NARROW_POWERS + 3], m[NARROW_POWERS], fact = 1.0;
    double *even = kept->even, *odd = kept->odd;
    size_t k, p, j, panels = (n_samples - 1) / 2;
    if (ll_filon_power_sums(g, n_samples, 0.5 * (b - a), even, odd)) {
        kept->powers = NARROW_POWERS;
        return;
    }
    for (j = 1; j < powers + 3; ++j)
        inv[j] = 1.0 / (double)j;
    memset(m, 0, sizeof m);
    for (p = 0; p < panels; ++p) {
        double f0 = g[2 * p], f1 = g[2 * p + 1], f2 = g[2 * p + 2];
        double c = a + (double)(2 * p + 1) * h - centre, lo = c - h, hi = c + h;
        double d1 = (f2 - f0) / (2.0 * h), d2 = (f0 - 2.0 * f1 + f2) / (2.0 * h * h);
        double A = f1 - d1 * c + d2 * c * c, B = d1 - 2.0 * d2 * c, C = d2;
        double pw_lo = lo, pw_hi = hi, P[NARROW_POWERS + 3];
        for (j = 1; j < powers + 3; ++j) {
            P[j] = (pw_hi - pw_lo) * inv[j];
            pw_lo *= lo;
            pw_hi *= hi;
        }
        for (k = 0; k < powers; ++k)
            m[k] += A * P[k + 1] + B * P[k + 2] + C * P[k + 3];
    }
    /* (-1)^j M_2j / (2j)! and (-1)^j M_(2j+1) / (2j+1)!, Horner's in l^2. */
    for (k = 0; k < powers; ++k) {
        double signed_m = (k / 2) % 2 ? -m[k] : m[k];
        if (k > 0)
            fact *= inv[k];
        if (k % 2)
            odd[k / 2] = signed_m * fact;
        else
            even[k / 2] = signed_m * fact;
    }
    kept->powers = powers;
}

/* The orders first .. first + count - 1 that are narrow (at most n) into
 * moments; returns count. The powers' sums come
 * from kept where it holds enough of them (a block of orders after the
 * first), else are summed into it: each sum is the same whatever number
 * of powers is summed with it, so the moments do not depend on which
 * block summed them. kept NULL: summed here for this call alone. */
static size_t narrow_moments(const double *g, size_t n_samples, double a, double b, size_t first,
                             size_t n, double *moments, ll_filon_kept *kept)
{
    double half = 0.5 * (b - a), centre = 0.5 * (a + b), avail, sums_cost;
    size_t count, powers, panels = (n_samples - 1) / 2, last;
    int tabled = ll_filon_power_tabled(n_samples);
    ll_filon_kept own;
    avail = half > 0.0 ? floor(NARROW_TAU / half) - (double)first + 1.0 : (double)n;
    if (avail <= 0.0)
        return 0;
    /* Worth it where the narrow orders (all there are, however many are
     * asked for) save more of the panels' work (about 4 instructions per
     * panel and order, with the orders side by side in vector registers,
     * and 10 more per order for the rule's weights and phases) than the
     * powers' moments cost (about 10 per panel and power, or 2 per sample
     * and power from a table). */
    if (tabled) {
        sums_cost = 2.0 * (double)(n_samples * NARROW_POWERS);
    } else {
        powers = narrow_terms(fmin(NARROW_TAU, ((double)first + avail - 1.0) * half), 1);
        sums_cost = (double)(panels * powers) * 10.0;
    }
    if (!(avail * ((double)panels * 4.0 + 10.0) > sums_cost))
        return 0;
    count = avail >= (double)n ? n : (size_t)avail;
    /* the powers of the last of the last order's eight (narrow_orders); a
     * table gives them all at once */
    last = (first + count - 1) | (NARROW_LANES - 1);
    powers = tabled ? NARROW_POWERS : narrow_terms((double)last * half, 1);
    if (!kept) {
        kept = &own;
        narrow_sums_of(g, n_samples, a, b, powers, kept);
    } else if (kept->powers < powers) {
        /* all that the piece's narrow orders take, for the blocks after */
        last = ((first + (size_t)avail - 1) | (NARROW_LANES - 1));
        narrow_sums_of(g, n_samples, a, b, narrow_terms((double)last * half, 1), kept);
    }
    narrow_orders(kept->even, kept->odd, half, centre, first, count, moments);
    return count;
}

void ll_filon_moments_from(const double *g, size_t n_samples, double a, double b, size_t first,
                           size_t n_moments, double *moments, double *scratch)
{
    ll_filon_moments_kept(g, n_samples, a, b, first, n_moments, moments, scratch, NULL);
}

void ll_filon_moments_kept(const double *g, size_t n_samples, double a, double b, size_t first,
                           size_t n_moments, double *moments, double *scratch,
                           ll_filon_kept *kept)
{
    filon_rule r;
    size_t narrow =
        narrow_moments(g, n_samples, a, b, first, n_moments, moments, kept);
    if (narrow == n_moments)
        return;
    rule_init(&r, n_samples, a, b, first + narrow, n_moments - narrow, scratch);
    accumulate(r.panels, n_moments - narrow, g, moments + narrow, r.cos_x, r.sin_x, r.w_end_c,
               r.w_end_s, r.w_mid, r.rot_c, r.rot_s);
}
