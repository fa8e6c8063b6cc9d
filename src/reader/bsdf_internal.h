/*
 * An opened .bsdf file (ll_bsdf) and the pieces its evaluation and
 * sampling share. Reader side only: nothing here knows about layers, so a
 * renderer that reads files links none of the adding-doubling code.
 *
 * Axes: the file's table index is (o, i) -> o + i * n, o the outgoing and i
 * the incident zenith-cosine node in the layer convention (ll_layer.h: mu > 0
 * travels down). pbrt-v3 calls the same two axes muI = CosTheta(-wi) (our o)
 * and muO = CosTheta(wo) (our i): see ll_bsdf.h.
 */
#ifndef LL_BSDF_INTERNAL_H
#define LL_BSDF_INTERNAL_H

#include "support/support.h"
#include "layerlab/ll_bsdf.h"

/* One (offset, length) entry of the offset table. */
typedef struct ll_bsdf_pair {
    uint32_t offset;  /* first coefficient of the pair's block in coeffs   */
    uint32_t length;  /* series length (0 = the BSDF is zero there)        */
} ll_bsdf_pair;

/* One spline interval [x0, x0 + 1 / inv_width] of the nodes, with the
 * difference-quotient factors of its end derivatives (0 at the ends of the
 * node range, where the differences are one-sided). */
typedef struct ll_bsdf_interval {
    double x0, inv_width, f0, f1;
} ll_bsdf_interval;

struct ll_measured;

struct ll_bsdf {
    int refcount;               /* atomic; the object is immutable otherwise   */
    struct ll_measured *measured; /* a table file of the `measured` format
                                   (tables_internal.h), or NULL for a .bsdf;
                                   a table handle has no Fourier parts (no
                                   nodes, series or CDF): n_nodes is 0      */
    struct ll_measured **measured_bases; /* a textured table file: [n_bases]
                                   sets, measured_bases[0] also in measured;
                                   NULL otherwise                             */
    size_t n_nodes;
    size_t max_order;
    size_t n_channels;          /* 1 or 3 (stored as Y, R, B)                  */
    size_t n_bases;
    size_t n_parameters;
    size_t n_parameter_values;
    size_t n_coeffs;
    size_t file_size;
    uint32_t flags;
    double eta;
    double alpha[2];
    float *nodes_f;             /* [n_nodes] as stored                         */
    double *nodes;              /* [n_nodes] the same, for the spline code     */
    uint32_t *param_counts;     /* [n_parameters]                              */
    size_t *param_first;        /* [n_parameters] index of the first position  */
    float *param_positions;     /* [n_parameter_values]                        */
    double *cdf;                /* [(i * n + o) * n_bases + b]; the running
                                   maximum of the stored row (its dips
                                   flattened, bsdf_cdf.c)                      */
    unsigned char *cdf_flat;    /* [i * (n - 1) + o]: 1 if flattening changed
                                   an end of segment o (nodes o, o + 1) of row
                                   i in some basis; NULL if no row has a dip  */
    double *a0;                 /* same layout: order-0 luminance coefficient  */
    ll_bsdf_pair *pairs;        /* [i * n + o]                                 */
    float *coeffs;              /* [n_coeffs + 4] as stored (float: the calls
                                   wait on memory, so half the bytes of double
                                   is what counts; every sum is in double, so
                                   the results are those of double storage),
                                   then 4 zeros, so that vector loads of a
                                   series' last group (up to 3 values past its
                                   end) stay inside the array                 */
    double *recip;              /* [max_order + 4] 1 / k, with 0 at k = 0 and
                                   from max_order on (vector loops read whole
                                   groups of 4)                                */
    ll_bsdf_interval *intervals;/* [n_nodes - 1] spline constants (bsdf_spline.c) */
    size_t n_buckets;           /* uniform buckets over [nodes[0], nodes[n-1]] */
    double bucket_scale;        /* n_buckets / (nodes[n-1] - nodes[0])         */
    uint32_t *bucket_first;     /* [n_buckets] interval at the bucket's start  */
    char *metadata;             /* NUL-terminated copy                         */
    size_t metadata_size;
    const char **param_names;   /* [n_parameters] (NULL if none), one block
                                   with the names' bytes after the pointers
                                   (bsdf_names.c)                              */
};

/* The Fourier series at one (mu_i, mu_o): the spline-weighted sum of up to
 * 16 stored series (Jakob et al. 2014, sec. 7: tensor-product Catmull-Rom
 * in the two cosines), kept as references rather than summed so that
 * evaluating it needs no buffer sized by the file. Channel c, basis b of
 * entry p starts at coeff[p] + (c * n_bases + b) * length[p]. */
#define LL_BSDF_SERIES_MAX 16
/* A textured file's weights have few non-zero entries (linear weights: at
 * most 2 per parameter, ll_bsdf_basis_coefficients), so the series lists
 * the non-zero bases and the sums visit only those: a 64-basis file then
 * costs what its few weighted bases cost. More non-zero weights than this
 * visit every basis (zeros skipped one by one). */
#define LL_BSDF_ACTIVE_MAX 16
typedef struct ll_bsdf_series {
    size_t count;
    const float *coeff[LL_BSDF_SERIES_MAX];
    uint32_t length[LL_BSDF_SERIES_MAX];
    double weight[LL_BSDF_SERIES_MAX];
    uint32_t max_length;
    size_t n_bases;
    const float *basis;         /* n_bases weights (never NULL)                */
    size_t n_active;            /* bases to visit: active[0 .. n_active) ...   */
    int all_bases;              /* ... or, if set, every one of 0 .. n_bases   */
    uint32_t active[LL_BSDF_ACTIVE_MAX];
    const double *dense;        /* if set: the series already summed, channel
                                   c at dense + c * dense_stride, c <
                                   dense_channels (ll_bsdf_series_densify*;
                                   read only when dense is set);
                                   the stored references stay valid            */
    size_t dense_channels, dense_stride;
    int prefetch_rows;          /* ask for the next stencil row while one is
                                   read (a file larger than the caches:
                                   LL_BSDF_PREFETCH_ROWS_FROM)                 */
} ll_bsdf_series;

/* Files of at least this many stored coefficients (32 MiB as float, more
 * than the caches of the machines we measure on hold) get the next-row
 * prefetches of ll_bsdf_series.prefetch_rows; in a smaller file the rows
 * are mostly in cache and the prefetches would only add instructions (on
 * coated gold, 7 MB: 9-11% more per eval/pdf call, callgrind). */
#define LL_BSDF_PREFETCH_ROWS_FROM ((size_t)8 << 20)

/* Basis q of the series' visiting order, q < s->n_active. */
static inline size_t ll_bsdf_active_basis(const ll_bsdf_series *s, size_t q)
{
    return s->all_bases ? q : s->active[q];
}

/* Fill b->param_names from b->metadata (validated first, then one
 * allocation; default names "p0", ... when the metadata has none):
 * bsdf_names.c. 0 when out of memory. */
LL_INTERNAL int ll_bsdf_read_parameter_names(ll_bsdf *b);

/* Free every part of a (possibly half-built) bsdf; NULL is fine. */
LL_INTERNAL void ll_bsdf_free(ll_bsdf *b);

/* Basis weight used when an untextured file is evaluated without any. */
LL_INTERNAL extern const float ll_bsdf_unit_basis[1];

/* Spline weights of mu against the file's nodes (bsdf_spline.c): those of
 * ll_spline_weights (pbrt-v3's CatmullRomWeights) from constants prepared
 * at open. 0 if mu is outside the nodes' range or NaN. */
LL_INTERNAL int ll_bsdf_weights(const ll_bsdf *b, double mu, ptrdiff_t *offset, double w[4]);
/* Fill b->intervals, b->bucket_* from b->nodes (validated). */
LL_INTERNAL void ll_bsdf_spline_prepare(ll_bsdf *b);

/* Gather the series of (mu_i, mu_o) into s; 0 if either cosine is out of
 * range (then the BSDF is zero there). basis: n_bases weights. */
LL_INTERNAL int ll_bsdf_gather(const ll_bsdf *b, double mu_i, double mu_o, const float *basis,
                               ll_bsdf_series *s);
/* The same with the incident weights already known. */
LL_INTERNAL int ll_bsdf_gather_weighted(const ll_bsdf *b, ptrdiff_t off_i, const double w_i[4],
                                        double mu_o, const float *basis, ll_bsdf_series *s);

/* sum_k a_k cos(k phi) of channels 0 .. n_channels-1 (<= 3) at cos(phi). */
LL_INTERNAL void ll_bsdf_series_eval(const ll_bsdf_series *s, size_t n_channels,
                                     double cos_phi, double out[3]);

/* cos(k phi) (or sin(k phi)) for consecutive k by the Chebyshev recurrence
 * x_{k+4} = 2 cos(4 phi) x_k - x_{k-4}, run as four interleaved chains:
 * the plain three-term recurrence is one long chain of dependent
 * multiply-adds, which leaves the processor waiting; four independent ones
 * overlap (and fill one AVX register). Like the plain one, the recurrence's
 * error grows only linearly with the number of steps. */
typedef struct ll_harmonics {
    double twice_cos4;   /* 2 cos(4 phi)                                 */
    double prev[4];      /* x_{k+r-4}, r = 0..3                          */
    double cur[4];       /* x_{k+r}: the next four values to hand out    */
} ll_harmonics;

/* Start at k = 0 with x_k = cos(k phi) (sine = 0) or sin(k phi) (sine = 1). */
LL_INTERNAL void ll_bsdf_harmonics_start(ll_harmonics *h, double cos_phi, double sin_phi,
                                         int sine);
/* out[0 .. count) = the next count values, count a multiple of 4
 * (bsdf_kernels.c; vector as below). */
LL_INTERNAL void ll_bsdf_harmonics_next(int vector, ll_harmonics *h, size_t count, double *out);

/* a_0 of the luminance series: its mean over phi. */
LL_INTERNAL double ll_bsdf_series_mean(const ll_bsdf_series *s);

/* The luminance series summed into dense[0 .. s->max_length), zero-padded
 * to a multiple of 4, and d set up to evaluate it (each Newton step then
 * reads one series, not 16). */
LL_INTERNAL void ll_bsdf_series_densify(const ll_bsdf_series *s, double *dense,
                                        ll_bsdf_series *d);
/* The same for channels 0 .. n_channels-1, each zero-padded to
 * stride = max_length rounded up to 4: dense has n_channels * stride
 * values, channel c at dense + c * stride. ll_bsdf_series_eval then reads
 * the sum for up to n_channels channels. */
LL_INTERNAL void ll_bsdf_series_densify_channels(const ll_bsdf_series *s, size_t n_channels,
                                                 double *dense, ll_bsdf_series *d);

/* Sample phi in [0, 2 pi) from the luminance series (channel 0) with u in
 * [0, 1], as pbrt-v3's SampleFourier: u < 1/2 picks [0, pi], else the
 * mirror half. 0 if the series has no positive mean (no phi written), else
 * 1. recip holds 1 / k for k < s->max_length. */
LL_INTERNAL int ll_bsdf_series_sample(const ll_bsdf_series *s, const double *recip, double u,
                                      double *phi);

/* Inner loops (bsdf_kernels.c). vector: use the AVX2/FMA versions, which
 * only ll_bsdf_kernels_vector() (this processor has them) allows; the
 * portable ones always work. Results differ only by rounding.
 * dot_chunk: out[c] += sum_p w_p sum_j a_{p,c}[k0 + j] h[j] over
 *   j < count, k0 + j < length_p, c < n_channels (s->dense unused);
 * add_scaled: acc[j] += w a[j], j < m;
 * integral_dense: *f = sum a[k] cos(k phi), *F = sum a[k] recip[k] sin(k phi)
 *   over k < n4 (a multiple of 4; a and recip have n4 values), the
 *   harmonics hc (cosines) and hs (sines) started at k = 0. */
LL_INTERNAL int ll_bsdf_kernels_vector(void);
/* Ask for the first cache lines of each series' channels, so that the 16
 * memory latencies of a call overlap instead of coming one per series
 * (series of 64 orders and more; shorter ones need no help). */
LL_INTERNAL void ll_bsdf_prefetch_series(const ll_bsdf_series *s, size_t n_channels);
LL_INTERNAL void ll_bsdf_dot_chunk(int vector, const ll_bsdf_series *s, size_t n_channels,
                                   size_t k0, size_t count, const double *h, double out[3]);
LL_INTERNAL void ll_bsdf_add_scaled(int vector, double *acc, const float *a, double w,
                                    size_t m);
/* sum_j a[j] h[j], j < m (a summed series against harmonics). */
LL_INTERNAL double ll_bsdf_dot_dense(int vector, const double *a, const double *h, size_t m);
/* acc[j] += sum_q w[q] a[q][j], j < m (four series in one pass); asks
 * for the prefetch_bytes from prefetch (NULL: none) on the way, a cache
 * line per 64 bytes read (the next block, bsdf_fourier.c). */
LL_INTERNAL void ll_bsdf_add_scaled4(int vector, double *acc, const float *const a[4],
                                     const double w[4], size_t m, const void *prefetch,
                                     size_t prefetch_bytes);
LL_INTERNAL void ll_bsdf_integral_dense(int vector, const double *a, const double *recip,
                                        size_t n4, const ll_harmonics *hc,
                                        const ll_harmonics *hs, double *F, double *f);

/* The CDF rows (bsdf_cdf.c). settle: check every dip of the stored rows
 * in b->cdf against the row's own spline integral of b->a0, flatten them
 * (running maximum) and fill b->cdf_flat; LL_ERROR_FORMAT naming the row,
 * entry and bound for a dip no float32 sum of the row produces.
 * flattened: whether segment idx of the row interpolated over (off_i, w_i)
 * has a flattened end in a row of non-zero weight; there the sampling
 * density in mu_o is flat_density (the segment's mass over its width and
 * the row's total, 0 if the mass is not positive), everywhere else a_0's
 * spline over the total. flat_segment: the segment strictly containing
 * mu_o, if it is such a segment. */
LL_INTERNAL ll_status ll_bsdf_cdf_settle(ll_bsdf *b, const char *file);
LL_INTERNAL int ll_bsdf_cdf_flattened(const ll_bsdf *b, ptrdiff_t off_i, const double w_i[4],
                                      size_t idx);
LL_INTERNAL int ll_bsdf_cdf_flat_segment(const ll_bsdf *b, ptrdiff_t off_i,
                                         const double w_i[4], double mu_o, size_t *idx);
LL_INTERNAL double ll_bsdf_cdf_flat_density(const ll_bsdf *b, ptrdiff_t off_i,
                                            const double w_i[4], const float *basis,
                                            size_t idx);

/* Catmull-Rom spline interpolation, over the incident weights (off_i, w_i),
 * of the per-row tables cdf or a0 at outgoing node o, with basis weights. */
LL_INTERNAL double ll_bsdf_row_value(const ll_bsdf *b, const double *table, ptrdiff_t off_i,
                                     const double w_i[4], size_t o, const float *basis);

/* The three stored sums (Y[, R, B]) times scale -> clamped (R, G, B), with
 * pbrt-v3's reconstruction of green. */
LL_INTERNAL void ll_bsdf_to_rgb(const ll_bsdf *b, const double sums[3], double scale,
                                double rgb[3]);

/* The cores of the public calls, in the layer convention with cos(phi_d)
 * given (arguments already checked, basis never NULL):
 * eval_cos: f(mu_i -> mu_o) * extra_scale as clamped RGB;
 * pdf_cos: density per solid angle of sampling mu_o, phi_d given mu_i;
 * sample_core: mu_o and phi_d from u (u[1] picks mu_o, u[0] phi_d, as
 * pbrt-v3's Sample_f), their density, and the raw stored sums (Y[, R, B])
 * at the sample (f * |mu_o| before colour reconstruction). Returns 0 when
 * nothing can be sampled (then *pdf = 0). */
LL_INTERNAL void ll_bsdf_eval_cos(const ll_bsdf *b, double mu_i, double mu_o, double cos_phi,
                                  const float *basis, double extra_scale, double rgb[3]);
LL_INTERNAL double ll_bsdf_pdf_cos(const ll_bsdf *b, double mu_i, double mu_o, double cos_phi,
                                   const float *basis);
LL_INTERNAL int ll_bsdf_sample_core(const ll_bsdf *b, double mu_i, const double u[2],
                                    const float *basis, double *mu_o, double *phi_d,
                                    double *pdf, double sums[3]);

/* 1 / |mu_o|, which turns the stored f |mu_o| into f, with |mu_o| taken as
 * at least LL_BSDF_MU_FLOOR; 0 at mu_o = 0 (pbrt-v3's convention). For a
 * file with the format's pair of mu = 0 nodes the stored series vanishes
 * linearly there and f has a finite limit anyway; for one without them (or
 * with values at those nodes) f |mu_o| does not vanish and f would grow as
 * 1 / |mu_o| to infinity (5e-324 gave +inf). The floor bounds f by 1e6
 * times the stored series, so every result is finite for every file that
 * opens; it changes nothing beyond 1e-6 of the horizon (5.7e-5 degrees). */
#define LL_BSDF_MU_FLOOR 1e-6
LL_INTERNAL double ll_bsdf_cosine_scale(double mu_o);

/* Check the public arguments shared by the evaluation calls. */
LL_INTERNAL ll_status ll_bsdf_check_basis(const ll_bsdf *b, const float *basis_coeffs,
                                          const char *fn, const float **basis);

#endif /* LL_BSDF_INTERNAL_H */
