/*
 * The inner loops of .bsdf evaluation and sampling: dot products of stored
 * Fourier coefficients with a chunk of harmonics cos(k phi) or
 * sin(k phi) / k (double), weighted sums of stored series, and the series
 * and its integral in one pass for sampling phi.
 *
 * Every x86-64 processor runs the portable versions; processors with AVX2
 * and FMA run vector versions chosen at run time (style.md: no mandatory
 * ISA extension). Both read the stored floats, widen them (exactly) and
 * compute in double; they differ only in the order of the additions.
 */
#include "reader/bsdf_internal.h"

#if (defined(__x86_64__) || defined(__i386__)) && (defined(__GNUC__) || defined(__clang__))
#define LL_BSDF_HAVE_AVX2_PATH 1
#include <immintrin.h>
#else
#define LL_BSDF_HAVE_AVX2_PATH 0
#endif

#if defined(__GNUC__) || defined(__clang__)
#define LL_PREFETCH(p) __builtin_prefetch((p), 0, 3)
#else
#define LL_PREFETCH(p) ((void)(p))
#endif

/* ------------------------------------------------------------- portable */

/* Four partial sums: one accumulator would be a chain of dependent adds.
 * Stored coefficients are floats, summed series doubles. */
static double dot_portable(const float *a, const double *h, size_t m)
{
    double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
    size_t j = 0;
    for (; j + 4 <= m; j += 4) {
        s0 += (double)a[j] * h[j];
        s1 += (double)a[j + 1] * h[j + 1];
        s2 += (double)a[j + 2] * h[j + 2];
        s3 += (double)a[j + 3] * h[j + 3];
    }
    for (; j < m; ++j)
        s0 += (double)a[j] * h[j];
    return (s0 + s1) + (s2 + s3);
}

static double dot_dense_portable(const double *a, const double *h, size_t m)
{
    double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
    size_t j = 0;
    for (; j + 4 <= m; j += 4) {
        s0 += a[j] * h[j];
        s1 += a[j + 1] * h[j + 1];
        s2 += a[j + 2] * h[j + 2];
        s3 += a[j + 3] * h[j + 3];
    }
    for (; j < m; ++j)
        s0 += a[j] * h[j];
    return (s0 + s1) + (s2 + s3);
}

static void dot_chunk_portable(const ll_bsdf_series *s, size_t n_channels, size_t k0,
                               size_t count, const double *h, double out[3])
{
    size_t p, q, basis, c, nb = s->n_bases;
    for (p = 0; p < s->count; ++p) {
        size_t len = s->length[p], m;
        if (len <= k0)
            continue;
        m = len - k0 < count ? len - k0 : count;
        for (q = 0; q < s->n_active; ++q) {
            double w;
            basis = ll_bsdf_active_basis(s, q);
            w = s->weight[p] * (double)s->basis[basis];
            if (w == 0.0)
                continue;
            for (c = 0; c < n_channels; ++c)
                out[c] += w * dot_portable(s->coeff[p] + (c * nb + basis) * len + k0, h, m);
        }
    }
}

/* The state lives in locals during the loop so that the four chains stay in
 * registers (through h, every step would wait on a store and a load). */
static void harmonics_next_portable(ll_harmonics *h, size_t count, double *restrict out)
{
    double t = h->twice_cos4;
    double c0 = h->cur[0], c1 = h->cur[1], c2 = h->cur[2], c3 = h->cur[3];
    double p0 = h->prev[0], p1 = h->prev[1], p2 = h->prev[2], p3 = h->prev[3];
    size_t j;
    for (j = 0; j < count; j += 4) {
        double n0 = t * c0 - p0, n1 = t * c1 - p1, n2 = t * c2 - p2, n3 = t * c3 - p3;
        out[j] = c0;
        out[j + 1] = c1;
        out[j + 2] = c2;
        out[j + 3] = c3;
        p0 = c0;
        p1 = c1;
        p2 = c2;
        p3 = c3;
        c0 = n0;
        c1 = n1;
        c2 = n2;
        c3 = n3;
    }
    h->cur[0] = c0;
    h->cur[1] = c1;
    h->cur[2] = c2;
    h->cur[3] = c3;
    h->prev[0] = p0;
    h->prev[1] = p1;
    h->prev[2] = p2;
    h->prev[3] = p3;
}

static void add_scaled_portable(double *acc, const float *a, double w, size_t m)
{
    size_t j;
    for (j = 0; j < m; ++j)
        acc[j] += w * (double)a[j];
}

static void add_scaled4_portable(double *acc, const float *const a[4], const double w[4],
                                 size_t m, const char *pf, size_t pf_bytes)
{
    size_t j, pf_at = 0;
    for (j = 0; j < m; ++j) {
        if (j % 4 == 0 && pf_at < pf_bytes) {
            LL_PREFETCH(pf + pf_at);
            pf_at += 64;
        }
        acc[j] += (w[0] * (double)a[0][j] + w[1] * (double)a[1][j]) +
                  (w[2] * (double)a[2][j] + w[3] * (double)a[3][j]);
    }
}

static void integral_portable(const double *a, const double *recip, size_t n4,
                              const ll_harmonics *hc, const ll_harmonics *hs, double *F,
                              double *f)
{
    double c[4], cp[4], sn[4], sp[4], fa[4] = { 0, 0, 0, 0 }, Fa[4] = { 0, 0, 0, 0 };
    double t = hc->twice_cos4;
    size_t j;
    int r;
    for (r = 0; r < 4; ++r) {
        c[r] = hc->cur[r];
        cp[r] = hc->prev[r];
        sn[r] = hs->cur[r];
        sp[r] = hs->prev[r];
    }
    for (j = 0; j < n4; j += 4)
        for (r = 0; r < 4; ++r) {
            double nc = t * c[r] - cp[r], ns = t * sn[r] - sp[r];
            fa[r] += a[j + (size_t)r] * c[r];
            Fa[r] += a[j + (size_t)r] * recip[j + (size_t)r] * sn[r];
            cp[r] = c[r];
            c[r] = nc;
            sp[r] = sn[r];
            sn[r] = ns;
        }
    *f = (fa[0] + fa[1]) + (fa[2] + fa[3]);
    *F = (Fa[0] + Fa[1]) + (Fa[2] + Fa[3]);
}

/* ------------------------------------------------------------ AVX2, FMA */

#if LL_BSDF_HAVE_AVX2_PATH
#define LL_AVX2 __attribute__((target("avx2,fma")))

LL_AVX2 static double hsum(__m256d v)
{
    __m128d lo = _mm256_castpd256_pd128(v), hi = _mm256_extractf128_pd(v, 1);
    lo = _mm_add_pd(lo, hi);
    return _mm_cvtsd_f64(_mm_add_sd(lo, _mm_unpackhi_pd(lo, lo)));
}

/* Four stored floats widened to double (exact). */
LL_AVX2 static __m256d load4(const float *a) { return _mm256_cvtps_pd(_mm_loadu_ps(a)); }

/* Lane masks keeping the first r values of a group of 4 (r = 0: all). */
static const uint64_t ll_group_masks[4][4] = {
    { ~(uint64_t)0, ~(uint64_t)0, ~(uint64_t)0, ~(uint64_t)0 },
    { ~(uint64_t)0, 0, 0, 0 },
    { ~(uint64_t)0, ~(uint64_t)0, 0, 0 },
    { ~(uint64_t)0, ~(uint64_t)0, ~(uint64_t)0, 0 },
};

/* The last group of a series: 4 values loaded, those past its end
 * cleared. The load may read up to 3 values past the series, which stay
 * inside the coefficient array (padded by 4, bsdf_internal.h). */
LL_AVX2 static __m256d load_last(const float *a, const __m256d mask)
{
    return _mm256_and_pd(load4(a), mask);
}

/* Weighted dot products of one stored series (channels `stride` apart)
 * with h over m >= 1 values, added to the channel accumulators: one
 * accumulator per channel, the fewest instructions for a short series. */
LL_AVX2 __attribute__((always_inline)) static inline void
series_dot_short_avx2(const float *a, size_t stride, size_t n_channels, const double *h,
                      size_t m, double w, __m256d *acc0, __m256d *acc1, __m256d *acc2)
{
    size_t last = (m - 1) & ~(size_t)3, j = 0;
    __m256d mask = _mm256_castsi256_pd(
        _mm256_loadu_si256((const __m256i *)(const void *)ll_group_masks[m & 3]));
    __m256d wv = _mm256_set1_pd(w), s0 = _mm256_setzero_pd(), s1 = _mm256_setzero_pd();
    if (n_channels == 3) {
        const float *r = a + stride, *b = a + 2 * stride;
        __m256d s2 = _mm256_setzero_pd(), hv;
        for (; j < last; j += 4) {
            hv = _mm256_loadu_pd(h + j);
            s0 = _mm256_fmadd_pd(load4(a + j), hv, s0);
            s1 = _mm256_fmadd_pd(load4(r + j), hv, s1);
            s2 = _mm256_fmadd_pd(load4(b + j), hv, s2);
        }
        hv = _mm256_loadu_pd(h + last);
        s0 = _mm256_fmadd_pd(load_last(a + last, mask), hv, s0);
        s1 = _mm256_fmadd_pd(load_last(r + last, mask), hv, s1);
        s2 = _mm256_fmadd_pd(load_last(b + last, mask), hv, s2);
        *acc1 = _mm256_fmadd_pd(s1, wv, *acc1);
        *acc2 = _mm256_fmadd_pd(s2, wv, *acc2);
    } else {
        for (; j + 8 <= last; j += 8) {
            s0 = _mm256_fmadd_pd(load4(a + j), _mm256_loadu_pd(h + j), s0);
            s1 = _mm256_fmadd_pd(load4(a + j + 4), _mm256_loadu_pd(h + j + 4), s1);
        }
        if (j < last)
            s0 = _mm256_fmadd_pd(load4(a + j), _mm256_loadu_pd(h + j), s0);
        s1 = _mm256_fmadd_pd(load_last(a + last, mask), _mm256_loadu_pd(h + last), s1);
        s0 = _mm256_add_pd(s0, s1);
    }
    *acc0 = _mm256_fmadd_pd(s0, wv, *acc0);
}

/* The same for a long series (LL_BSDF_LONG_SERIES values and more), with
 * two accumulators per channel (four for one channel): a multiply-add
 * waits about four cycles for the one before it into the same register,
 * and the conversions of the stored floats allow one group of four every
 * cycle, so a single chain per channel left the loop waiting on latency.
 * On the way it asks for pf_bytes from pf (dot_chunk_avx2). Short series
 * keep the version above: from 32 orders on, the extra accumulators' set-up
 * and sums cost 13-14% more instructions per eval/pdf call on the golden
 * file, whose series are short; from 64 (and without the prefetches in
 * files that fit the caches) 2-6% (callgrind). */
#define LL_BSDF_LONG_SERIES 64
LL_AVX2 __attribute__((always_inline)) static inline void
series_dot_long_avx2(const float *a, size_t stride, size_t n_channels, const double *h,
                     size_t m, double w, const char *pf, size_t pf_bytes, __m256d *acc0,
                     __m256d *acc1, __m256d *acc2)
{
    size_t last = (m - 1) & ~(size_t)3, j = 0, pf_at = 0;
    __m256d mask = _mm256_castsi256_pd(
        _mm256_loadu_si256((const __m256i *)(const void *)ll_group_masks[m & 3]));
    __m256d wv = _mm256_set1_pd(w), s0 = _mm256_setzero_pd(), s1 = _mm256_setzero_pd();
    __m256d t0 = _mm256_setzero_pd(), t1 = _mm256_setzero_pd();
    if (n_channels == 3) {
        const float *r = a + stride, *b = a + 2 * stride;
        __m256d s2 = _mm256_setzero_pd(), t2 = _mm256_setzero_pd(), hv, hw;
        for (; j + 8 <= last; j += 8) {
            /* 96 bytes read per step, two lines of the next block asked for
             * (offsets, so that no pointer passes the block's end) */
            if (pf_at < pf_bytes) {
                LL_PREFETCH(pf + pf_at);
                if (pf_bytes - pf_at > 64)
                    LL_PREFETCH(pf + pf_at + 64);
                pf_at += 128;
            }
            hv = _mm256_loadu_pd(h + j);
            hw = _mm256_loadu_pd(h + j + 4);
            s0 = _mm256_fmadd_pd(load4(a + j), hv, s0);
            s1 = _mm256_fmadd_pd(load4(r + j), hv, s1);
            s2 = _mm256_fmadd_pd(load4(b + j), hv, s2);
            t0 = _mm256_fmadd_pd(load4(a + j + 4), hw, t0);
            t1 = _mm256_fmadd_pd(load4(r + j + 4), hw, t1);
            t2 = _mm256_fmadd_pd(load4(b + j + 4), hw, t2);
        }
        if (j < last) {
            hv = _mm256_loadu_pd(h + j);
            s0 = _mm256_fmadd_pd(load4(a + j), hv, s0);
            s1 = _mm256_fmadd_pd(load4(r + j), hv, s1);
            s2 = _mm256_fmadd_pd(load4(b + j), hv, s2);
        }
        hv = _mm256_loadu_pd(h + last);
        t0 = _mm256_fmadd_pd(load_last(a + last, mask), hv, t0);
        t1 = _mm256_fmadd_pd(load_last(r + last, mask), hv, t1);
        t2 = _mm256_fmadd_pd(load_last(b + last, mask), hv, t2);
        *acc1 = _mm256_fmadd_pd(_mm256_add_pd(s1, t1), wv, *acc1);
        *acc2 = _mm256_fmadd_pd(_mm256_add_pd(s2, t2), wv, *acc2);
        s0 = _mm256_add_pd(s0, t0);
    } else {
        for (; j + 16 <= last; j += 16) {
            if (pf_at < pf_bytes) {
                LL_PREFETCH(pf + pf_at);
                pf_at += 64;
            }
            s0 = _mm256_fmadd_pd(load4(a + j), _mm256_loadu_pd(h + j), s0);
            s1 = _mm256_fmadd_pd(load4(a + j + 4), _mm256_loadu_pd(h + j + 4), s1);
            t0 = _mm256_fmadd_pd(load4(a + j + 8), _mm256_loadu_pd(h + j + 8), t0);
            t1 = _mm256_fmadd_pd(load4(a + j + 12), _mm256_loadu_pd(h + j + 12), t1);
        }
        for (; j < last; j += 4)
            s0 = _mm256_fmadd_pd(load4(a + j), _mm256_loadu_pd(h + j), s0);
        s1 = _mm256_fmadd_pd(load_last(a + last, mask), _mm256_loadu_pd(h + last), s1);
        s0 = _mm256_add_pd(_mm256_add_pd(s0, s1), _mm256_add_pd(t0, t1));
    }
    *acc0 = _mm256_fmadd_pd(s0, wv, *acc0);
}

/* The dot products of each stored series with h over its overlap with the
 * chunk, weighted, summed per channel. The accumulators stay in registers
 * across the series (an accumulator in memory would chain every series to
 * the previous one through a store and a load); h has room for the chunk
 * rounded up to 4 values.
 *
 * The series of one stencil row (same incident node, four outgoing ones)
 * are adjacent in the file, so the hardware prefetcher follows a row as one
 * stream; the next row starts elsewhere and its first misses would each
 * wait a memory latency. So while series p is summed, the block of series
 * p + 4 (the next row's, in gather order) is asked for at the pace of the
 * reading: the fetches of the two rows overlap (measured on random 16 KiB
 * blocks of a 200 MB array: 4.3 -> 6.0 GB/s on this machine). Only in files
 * larger than the caches (s->prefetch_rows), untextured, long series. */
LL_AVX2 static void dot_chunk_avx2(const ll_bsdf_series *s, size_t n_channels, size_t k0,
                                   size_t count, const double *h, double out[3])
{
    __m256d acc0 = _mm256_setzero_pd(), acc1 = _mm256_setzero_pd(), acc2 = _mm256_setzero_pd();
    size_t p, q, basis, nb = s->n_bases;
    for (p = 0; p < s->count; ++p) {
        size_t len = s->length[p], m;
        if (len <= k0)
            continue;
        m = len - k0 < count ? len - k0 : count;
        if (nb == 1) {
            const char *pf = NULL;
            size_t pf_bytes = 0;
            if (m < LL_BSDF_LONG_SERIES) {
                series_dot_short_avx2(s->coeff[p] + k0, len, n_channels, h, m,
                                      s->weight[p] * (double)s->basis[0], &acc0, &acc1, &acc2);
                continue;
            }
            if (k0 == 0 && p + 4 < s->count && s->prefetch_rows) {
                pf = (const char *)(const void *)s->coeff[p + 4];
                pf_bytes = (size_t)s->length[p + 4] * n_channels * sizeof(float);
            }
            series_dot_long_avx2(s->coeff[p] + k0, len, n_channels, h, m,
                                 s->weight[p] * (double)s->basis[0], pf, pf_bytes, &acc0, &acc1,
                                 &acc2);
            continue;
        }
        for (q = 0; q < s->n_active; ++q) {
            double w;
            basis = ll_bsdf_active_basis(s, q);
            w = s->weight[p] * (double)s->basis[basis];
            if (w != 0.0)
                series_dot_short_avx2(s->coeff[p] + basis * len + k0, nb * len, n_channels, h,
                                      m, w, &acc0, &acc1, &acc2);
        }
    }
    out[0] += hsum(acc0);
    if (n_channels == 3) {
        out[1] += hsum(acc1);
        out[2] += hsum(acc2);
    }
}

/* Four doubles of a harmonics state, which ll_bsdf_harmonics_start has
 * just written one by one: read them one by one too (a vector load of
 * four separate recent stores cannot be forwarded and waits for them to
 * reach the cache). */
LL_AVX2 static __m256d load_state(const double v[4])
{
    return _mm256_setr_pd(v[0], v[1], v[2], v[3]);
}

/* cos or sin chunk: the four chains of ll_harmonics are the lanes of one
 * vector, advanced by one fused multiply-subtract. */
LL_AVX2 static void harmonics_next_avx2(ll_harmonics *hm, size_t count, double *out)
{
    __m256d t = _mm256_set1_pd(hm->twice_cos4);
    __m256d c = load_state(hm->cur), cp = load_state(hm->prev);
    size_t j;
    for (j = 0; j < count; j += 4) {
        __m256d next = _mm256_fmsub_pd(t, c, cp);
        _mm256_storeu_pd(out + j, c);
        cp = c;
        c = next;
    }
    _mm256_storeu_pd(hm->cur, c);
    _mm256_storeu_pd(hm->prev, cp);
}

LL_AVX2 static void add_scaled_avx2(double *acc, const float *a, double w, size_t m)
{
    __m256d wv = _mm256_set1_pd(w);
    size_t j = 0;
    for (; j + 4 <= m; j += 4)
        _mm256_storeu_pd(acc + j, _mm256_fmadd_pd(load4(a + j), wv, _mm256_loadu_pd(acc + j)));
    for (; j < m; ++j)
        acc[j] += w * (double)a[j];
}

/* m a multiple of 4 (a summed series is zero-padded to one). */
LL_AVX2 static double dot_dense_avx2(const double *a, const double *h, size_t m)
{
    __m256d s0 = _mm256_setzero_pd(), s1 = _mm256_setzero_pd();
    size_t j = 0;
    for (; j + 8 <= m; j += 8) {
        s0 = _mm256_fmadd_pd(_mm256_loadu_pd(a + j), _mm256_loadu_pd(h + j), s0);
        s1 = _mm256_fmadd_pd(_mm256_loadu_pd(a + j + 4), _mm256_loadu_pd(h + j + 4), s1);
    }
    if (j < m)
        s0 = _mm256_fmadd_pd(_mm256_loadu_pd(a + j), _mm256_loadu_pd(h + j), s0);
    return hsum(_mm256_add_pd(s0, s1));
}

/* Four series at once: the sum is loaded and stored once for four inputs
 * (a pass per series would move it 16 times per call). */
LL_AVX2 static void add_scaled4_avx2(double *acc, const float *const a[4], const double w[4],
                                     size_t m, const char *pf, size_t pf_bytes)
{
    __m256d w0 = _mm256_set1_pd(w[0]), w1 = _mm256_set1_pd(w[1]);
    __m256d w2 = _mm256_set1_pd(w[2]), w3 = _mm256_set1_pd(w[3]);
    const float *a0 = a[0], *a1 = a[1], *a2 = a[2], *a3 = a[3];
    size_t j = 0, pf_at = 0;
    for (; j + 4 <= m; j += 4) {
        __m256d s = _mm256_fmadd_pd(load4(a0 + j), w0, _mm256_loadu_pd(acc + j)), r;
        /* 64 bytes read per step: one line of the next block (pf) */
        if (pf_at < pf_bytes) {
            LL_PREFETCH(pf + pf_at);
            pf_at += 64;
        }
        r = _mm256_mul_pd(load4(a2 + j), w2);
        s = _mm256_fmadd_pd(load4(a1 + j), w1, s);
        r = _mm256_fmadd_pd(load4(a3 + j), w3, r);
        _mm256_storeu_pd(acc + j, _mm256_add_pd(s, r));
    }
    for (; j < m; ++j)
        acc[j] += (w[0] * (double)a0[j] + w[1] * (double)a1[j]) +
                  (w[2] * (double)a2[j] + w[3] * (double)a3[j]);
}

/* The four harmonic chains of ll_harmonics are the four lanes of a vector:
 * one fused multiply-subtract advances all of them. */
LL_AVX2 static void integral_avx2(const double *a, const double *recip, size_t n4,
                                  const ll_harmonics *hc, const ll_harmonics *hs, double *F,
                                  double *f)
{
    __m256d t = _mm256_set1_pd(hc->twice_cos4);
    __m256d c = load_state(hc->cur), cp = load_state(hc->prev);
    __m256d sn = load_state(hs->cur), sp = load_state(hs->prev);
    __m256d fa = _mm256_setzero_pd(), Fa = _mm256_setzero_pd();
    size_t j;
    for (j = 0; j < n4; j += 4) {
        __m256d av = _mm256_loadu_pd(a + j), nc, ns;
        fa = _mm256_fmadd_pd(av, c, fa);
        Fa = _mm256_fmadd_pd(_mm256_mul_pd(av, _mm256_loadu_pd(recip + j)), sn, Fa);
        nc = _mm256_fmsub_pd(t, c, cp);
        ns = _mm256_fmsub_pd(t, sn, sp);
        cp = c;
        c = nc;
        sp = sn;
        sn = ns;
    }
    *f = hsum(fa);
    *F = hsum(Fa);
}

/* The processor's features, as the compiler's runtime (libgcc or
 * compiler-rt) detected them before main: read-only here. */
static int have_avx2(void)
{
    return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
}
#else
static int have_avx2(void) { return 0; }
#endif

/* ----------------------------------------------------------- dispatch */

void ll_bsdf_prefetch_series(const ll_bsdf_series *s, size_t n_channels)
{
    size_t p, c, q, nb = s->n_bases;
    /* Short series: the out-of-order core overlaps their few misses by
     * itself, and the prefetches would only add instructions. Only the
     * bases that are visited (channel c, basis k at (c * nb + k) * len). */
    if (s->max_length < 64)
        return;
    for (p = 0; p < s->count; ++p)
        for (c = 0; c < n_channels; ++c)
            for (q = 0; q < s->n_active; ++q) {
                const float *a =
                    s->coeff[p] + (c * nb + ll_bsdf_active_basis(s, q)) * s->length[p];
                LL_PREFETCH(a);
                if (s->length[p] > 16)
                    LL_PREFETCH(a + 16);
            }
}

int ll_bsdf_kernels_vector(void) { return have_avx2(); }

void ll_bsdf_dot_chunk(int vector, const ll_bsdf_series *s, size_t n_channels, size_t k0,
                       size_t count, const double *h, double out[3])
{
#if LL_BSDF_HAVE_AVX2_PATH
    if (vector) {
        dot_chunk_avx2(s, n_channels, k0, count, h, out);
        return;
    }
#endif
    (void)vector;
    dot_chunk_portable(s, n_channels, k0, count, h, out);
}

double ll_bsdf_dot_dense(int vector, const double *a, const double *h, size_t m)
{
#if LL_BSDF_HAVE_AVX2_PATH
    if (vector && m % 4 == 0)
        return dot_dense_avx2(a, h, m);
#endif
    (void)vector;
    return dot_dense_portable(a, h, m);
}

void ll_bsdf_add_scaled(int vector, double *acc, const float *a, double w, size_t m)
{
#if LL_BSDF_HAVE_AVX2_PATH
    if (vector) {
        add_scaled_avx2(acc, a, w, m);
        return;
    }
#endif
    (void)vector;
    add_scaled_portable(acc, a, w, m);
}

void ll_bsdf_add_scaled4(int vector, double *acc, const float *const a[4], const double w[4],
                         size_t m, const void *prefetch, size_t prefetch_bytes)
{
    const char *pf = prefetch;
    size_t pf_bytes = pf ? prefetch_bytes : 0;
#if LL_BSDF_HAVE_AVX2_PATH
    if (vector) {
        add_scaled4_avx2(acc, a, w, m, pf, pf_bytes);
        return;
    }
#endif
    (void)vector;
    add_scaled4_portable(acc, a, w, m, pf, pf_bytes);
}

void ll_bsdf_integral_dense(int vector, const double *a, const double *recip, size_t n4,
                            const ll_harmonics *hc, const ll_harmonics *hs, double *F,
                            double *f)
{
#if LL_BSDF_HAVE_AVX2_PATH
    if (vector) {
        integral_avx2(a, recip, n4, hc, hs, F, f);
        return;
    }
#endif
    (void)vector;
    integral_portable(a, recip, n4, hc, hs, F, f);
}

void ll_bsdf_harmonics_next(int vector, ll_harmonics *h, size_t count, double *out)
{
#if LL_BSDF_HAVE_AVX2_PATH
    if (vector) {
        harmonics_next_avx2(h, count, out);
        return;
    }
#endif
    (void)vector;
    harmonics_next_portable(h, count, out);
}
