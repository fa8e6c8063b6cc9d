/*
 * The piecewise-bilinear 2D warp of the `measured` format
 * (docs/formats.md, "The 2D warp"): a density given by its values
 * at the nodes of a W x H grid over the unit square, interpolated
 * bilinearly, with conditional slices selected by up to three parameters
 * and interpolated linearly between them. The one implementation that both
 * the reader (evaluation and sampling of table files) and the writer (which
 * pushes its sample grid through it, so that the stored values are exact at
 * the nodes) use.
 *
 * Axes: x is the last (contiguous) axis of the stored array, y the one
 * before it; node (x_k, y_l) = (k / (W - 1), l / (H - 1)). Slices are
 * stored parameter 0 outermost. Sampling takes y from the marginal
 * (binary search over the trapezoid integrals of the rows, then the root of
 * the quadratic that the linear density gives inside the interval), then x
 * the same way from the conditional row interpolated at that y; invert is
 * the exact inverse of sample, and both return the density there.
 */
#ifndef LL_TABLES_WARP_H
#define LL_TABLES_WARP_H

#include "support/support.h"

#include <math.h>
#include <stdint.h>

#define LL_WARP_MAX_PARAMS 3

typedef struct ll_warp2d {
    size_t w, h;                              /* nodes along x and y (>= 2)       */
    size_t n_params;
    size_t param_size[LL_WARP_MAX_PARAMS];    /* values per parameter (>= 1)      */
    double *param_values[LL_WARP_MAX_PARAMS]; /* ascending, owned                 */
    size_t n_slices;                          /* product of param_size            */
    /* Stored as float, as the renderers store them: a look-up reads a few
     * scattered rows of tables of megabytes, so their size is what costs;
     * every sum over them is in double. */
    float *data;                              /* [n_slices][h][w], but see inner
                                                 and step                         */
    /* A warp that only interpolates stores its last parameter innermost,
     * [outer slices][h][w][inner]: the channels of an RGB table (or the
     * neighbouring wavelengths of a spectral one) that a look-up reads
     * together then share cache lines instead of lying a table apart.
     * inner is that parameter's count, or 1 (sampling warps, no
     * parameters). */
    size_t inner;
    /* A sampling warp keeps each node's running integral next to its
     * value: a look-up reads both at the same nodes, which then share
     * their cache lines (an evaluation reads half the lines it would from
     * two tables). step is the floats from one node to the next in data:
     * 2 for a sampling warp, inner otherwise. */
    size_t step;
    float *cond;                              /* data + 1, read with step 2: the
                                                 running trapezoid integrals
                                                 along x (NULL if the warp only
                                                 interpolates)                    */
    float *marg;                              /* [n_slices][h] the same along y of
                                                 the row totals                   */
    int normalized;                           /* each slice divided by its total  */
    double area;                              /* a sampling warp's density per unit
                                                 area of the square from a value:
                                                 (w - 1) (h - 1), taken once; else
                                                 1                                */
    float *row_total;                         /* [n_slices][h] the last entry of
                                                 each row of cond: the totals a
                                                 look-up reads every time, in a
                                                 table small enough to stay in
                                                 cache (NULL with cond)           */
    int rows_equal;                           /* every row of every slice holds
                                                 the same values: y does not
                                                 matter (an isotropic file's ndf
                                                 and sigma)                       */
    /* Where a sampling warp's searches end: guide tables (Chen and Asau
     * 1974; Devroye, Non-Uniform Random Variate Generation, 1986), as the
     * Mitsuba plugin's warp has them (python/layerlab/mitsuba_warp.py).
     * marg_guide[k][j], j = 0 .. marg_buckets: the marginal search's answer in slice k alone for the target j / marg_buckets;
     * cond_guide[k][y][j], j = 0 .. cond_buckets: the conditional search's
     * answer in row y of slice k alone for the target (j / cond_buckets)
     * times the row's total. A search for u in bucket j of a blend of
     * rows and slices (non-negative weights) ends between the least of
     * their answers at j and the greatest at j + 1, up to rounding: the
     * search checks that the blend's values at both ends bracket its
     * target, then counts only the nodes between, which finds what the
     * whole search finds (a few nodes instead of two rounds of about
     * sqrt(w)). Where the check fails (rounding at a tie) the whole search
     * runs. Entries are bytes where every node index fits one (w and h
     * up to 257), which keeps a row's guide within a cache line or two
     * and both warps' guides within a core's second-level cache for the
     * usual grids; else 16 bits (guide_wide). NULL (every search whole)
     * if a running integral decreases anywhere, where only the whole
     * search defines the answer, or if the nodes do not fit 16 bits.
     * marg_stride, guide_stride: the first round's strides of the whole
     * searches along y and x (about sqrt of the node count: both rounds
     * read about as many values). */
    size_t guide_stride, marg_stride;
    size_t marg_buckets, cond_buckets;        /* powers of two                    */
    int guide_wide;                           /* entries uint16_t, else bytes     */
    void *marg_guide;                         /* [n_slices][marg_buckets + 1]     */
    void *cond_guide;                         /* [n_slices][h][cond_buckets + 1]  */
    /* 1 / (w - 1) and 1 / (h - 1): a sampled point's coordinates are its
     * node index and fraction times these (a multiplication where a
     * division would lengthen the chain of a sample that feeds one warp's
     * point to the next). */
    double inv_cells[2];
} ll_warp2d;

/* Entry k of a guide of wp (ll_warp2d.marg_guide, cond_guide). */
static inline size_t ll_warp_guide_entry(const ll_warp2d *wp, const void *guide, size_t k)
{
    return wp->guide_wide ? ((const uint16_t *)guide)[k] : ((const unsigned char *)guide)[k];
}

/* The slices around one parameter point and their weights (only those of
 * non-zero weight), computed once and shared by the look-ups of warps with
 * the same parameter lists. */
typedef struct ll_warp_slices {
    size_t count;
    size_t index[1 << LL_WARP_MAX_PARAMS];
    double weight[1 << LL_WARP_MAX_PARAMS];
} ll_warp_slices;

/* Build from data[n_slices * h * w] (any float layout the caller decodes
 * through get(ctx, index)), params[p][param_size[p]] ascending.
 * sampling: build the CDFs (then every slice must have a positive integral
 * and is normalised). Returns LL_OK, LL_ERROR_OUT_OF_MEMORY, or
 * LL_ERROR_FORMAT (message "slice k has no positive integral") which the
 * caller prefixes with the field. */
typedef double (*ll_warp_get)(const void *ctx, size_t index);
LL_INTERNAL ll_status ll_warp2d_init(ll_warp2d *wp, size_t w, size_t h, size_t n_params,
                                     const size_t *param_size, const double *const *params,
                                     ll_warp_get get, const void *ctx, int sampling);
LL_INTERNAL void ll_warp2d_free(ll_warp2d *wp);

/* The bilinear value at pos (clamped into the square) for the parameters
 * param[n_params]; a sampling warp returns the density per unit area of
 * the square. */
LL_INTERNAL double ll_warp2d_eval(const ll_warp2d *wp, const double pos[2], const double *param);

/* Map u in [0, 1]^2 to a point; *pdf its density (sampling warps only). */
LL_INTERNAL void ll_warp2d_sample(const ll_warp2d *wp, const double u[2], const double *param,
                                  double pos[2], double *pdf);

/* The inverse of sample: the u that maps to pos, and the density at pos. */
LL_INTERNAL void ll_warp2d_invert(const ll_warp2d *wp, const double pos[2], const double *param,
                                  double u[2], double *pdf);

/* The same with the slices given: ll_warp2d_slices finds them for the
 * parameters param[n_params]; ll_warp_slices_append extends them by one
 * more parameter that hits node k of its n values exactly (a channel). */
LL_INTERNAL void ll_warp2d_slices(const ll_warp2d *wp, const double *param, ll_warp_slices *s);
LL_INTERNAL void ll_warp_slices_append(const ll_warp_slices *s, size_t k, size_t n,
                                       ll_warp_slices *out);
LL_INTERNAL double ll_warp2d_eval_at(const ll_warp2d *wp, const ll_warp_slices *s,
                                     const double pos[2]);
/* n values at pos of a warp whose last parameter has exactly n values,
 * each hit at its node (the channels of an RGB table): out[k] is the value
 * for slices s extended by k. One cell look-up for all n (n <= 3). */
LL_INTERNAL void ll_warp2d_eval_nodes(const ll_warp2d *wp, const ll_warp_slices *s, size_t n,
                                      const double pos[2], double *out);
/* The value at pos of a warp without parameters (n_params 0); one whose
 * rows are equal (rows_equal) interpolates along x only. The value of
 * ll_warp2d_eval to rounding. */
LL_INTERNAL double ll_warp2d_eval_single(const ll_warp2d *wp, const double pos[2]);
/* Ask the memory for the nodes that ll_warp2d_eval_nodes will read at
 * pos for the slices s (without the inner parameter), so that their fetch
 * overlaps other work; a hint that changes no result. On a sampling warp
 * the same cell's nodes carry their running integrals: what
 * ll_warp2d_eval_at and ll_warp2d_invert_at read there (beside the
 * marginal and row totals, small tables that stay in cache). */
LL_INTERNAL void ll_warp2d_prefetch_nodes(const ll_warp2d *wp, const ll_warp_slices *s,
                                          const double pos[2]);
/* The one slice of a warp without parameters. */
LL_INTERNAL void ll_warp_slices_single(ll_warp_slices *s);
LL_INTERNAL void ll_warp2d_sample_at(const ll_warp2d *wp, const ll_warp_slices *s,
                                     const double u[2], double pos[2], double *pdf);
/* sample_at in steps split at its loads from memory, for callers that
 * overlap those of several samples (the batch calls' pipeline):
 * ll_warp2d_draw_begin keeps u_in off the edges and, for one or two
 * slices, finds the row interval from the marginal and the stretch of
 * the column search from the guides (small tables, in cache);
 * ll_warp2d_prefetch_draw asks for that stretch of the rows (a hint that
 * changes no result); ll_warp2d_draw_end reads it and gives what
 * sample_at gives. */
typedef struct ll_warp_draw {
    double u[2];              /* off the edges                          */
    size_t r;                 /* the row interval                       */
    size_t base, top;         /* the column search's stretch: its answer
                                 lies in base .. top, which the nodes
                                 base .. top + 1 settle                 */
    int guided;               /* the stretch is the guide's (else the
                                 whole search's first round)            */
    double ty, target;        /* the row's fraction, the column target  */
} ll_warp_draw;
LL_INTERNAL void ll_warp2d_draw_begin(const ll_warp2d *wp, const ll_warp_slices *s,
                                      const double u_in[2], ll_warp_draw *dr);
LL_INTERNAL void ll_warp2d_prefetch_draw(const ll_warp2d *wp, const ll_warp_slices *s,
                                         const ll_warp_draw *dr);
LL_INTERNAL void ll_warp2d_draw_end(const ll_warp2d *wp, const ll_warp_slices *s,
                                    const ll_warp_draw *dr, double pos[2], double *pdf);
LL_INTERNAL void ll_warp2d_invert_at(const ll_warp2d *wp, const ll_warp_slices *s,
                                     const double pos[2], double u[2], double *pdf);

/* The interval of an ascending list v[0 .. n) that holds x, and the weight
 * of its upper end, clamped to the list's ends; a single value needs no
 * weight. The halving runs over a length that does not depend on x: every
 * call looks up a new elevation, whose comparisons a branch would
 * mispredict half the time. */
static inline void ll_warp_locate(const double *v, size_t n, double x, size_t *i, double *t)
{
    size_t lo = 0, len;
    if (n < 2) {
        *i = 0;
        *t = 0.0;
        return;
    }
    for (len = n - 1; len > 1;) {
        size_t half = len / 2, mid = lo + half;
        lo = v[mid] <= x ? mid : lo;
        len -= half;
    }
    *i = lo;
    *t = (x - v[lo]) / (v[lo + 1] - v[lo]);
    if (!(*t > 0.0))
        *t = 0.0;
    if (*t > 1.0)
        *t = 1.0;
}

/* The square coordinates of a direction, shared by the reflected
 * (tables_eval.c) and refracted (tables_refract.c) lobes: the elevation
 * of unit d from its chord to the pole (exact near the pole, where acos
 * loses digits), and u_theta = sqrt(theta 2 / pi), u_phi = (phi + pi) /
 * 2 pi. */
static inline double ll_tables_elevation(const double d[3])
{
    double x = d[0], y = d[1], z = d[2] - 1.0, r = 0.5 * sqrt(x * x + y * y + z * z);
    return 2.0 * asin(r > 1.0 ? 1.0 : r);
}

static inline double ll_tables_theta_to_u(double theta) { return sqrt(theta * (2.0 / LL_PI)); }

static inline double ll_tables_phi_to_u(double phi) { return (phi + LL_PI) * (0.5 / LL_PI); }

/* wi reflected about the unit normal m into wo; returns wi.m. */
static inline double ll_tables_reflect_about(const double wi[3], const double m[3], double wo[3])
{
    double d = wi[0] * m[0] + wi[1] * m[1] + wi[2] * m[2];
    wo[0] = 2.0 * d * m[0] - wi[0];
    wo[1] = 2.0 * d * m[1] - wi[1];
    wo[2] = 2.0 * d * m[2] - wi[2];
    return d;
}

/* The microfacet normal m of a point um of the visible-normal square
 * (theta_m = u_theta^2 pi / 2, phi_m = (2 u_phi - 1) pi + phi_i) and wi
 * reflected about it into wo; returns wi.m. The writer's sample grid
 * (at phi_i = 0) stores values at the very directions the readers' warps
 * produce; the reader's sampler uses the same mapping in the form below,
 * which takes phi_i as a unit vector. */
static inline double ll_tables_mirror(const double wi[3], const double um[2], double phi_i,
                                      double *theta_m, double m[3], double wo[3])
{
    double tm = um[0] * um[0] * (LL_PI / 2), pm = (2.0 * um[1] - 1.0) * LL_PI + phi_i;
    m[0] = sin(tm) * cos(pm);
    m[1] = sin(tm) * sin(pm);
    m[2] = cos(tm);
    *theta_m = tm;
    return ll_tables_reflect_about(wi, m, wo);
}

/* The same mapping for a wi of any azimuth phi_i, given as its unit
 * vector (cos phi_i, sin phi_i): the normal is made at phi_i = 0 and
 * turned, which spares the reader's sampler an atan2 of wi; the
 * directions are those of ll_tables_mirror to rounding. *sin_theta_m:
 * sin(theta_m), which the sampler's pdf needs too. */
static inline double ll_tables_mirror_dir(const double wi[3], const double um[2],
                                          double cos_phi_i, double sin_phi_i, double *theta_m,
                                          double *sin_theta_m, double m[3], double wo[3])
{
    double tm = um[0] * um[0] * (LL_PI / 2), pm = (2.0 * um[1] - 1.0) * LL_PI;
    double st = sin(tm), x = st * cos(pm), y = st * sin(pm);
    m[0] = x * cos_phi_i - y * sin_phi_i;
    m[1] = y * cos_phi_i + x * sin_phi_i;
    m[2] = cos(tm);
    *theta_m = tm;
    *sin_theta_m = st;
    return ll_tables_reflect_about(wi, m, wo);
}

#endif /* LL_TABLES_WARP_H */
