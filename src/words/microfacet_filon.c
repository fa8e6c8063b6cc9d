/*
 * The Filon path of a pair's series. Where g has a kink inside the window
 * (the critical azimuth of total internal reflection, or the azimuth where
 * refraction ends), or a branch point just outside it (grazing pairs), no
 * polynomial fits it (3-10% of the pairs). The product f itself is then
 * integrated by Filon's rule for every order, split at the kink and with
 * panels shrinking geometrically towards it (Fresnel's square-root
 * behaviour there): Filon is exact for the oscillation of cos(l phi)
 * whatever l. GGX's pieces double in width away from its peak, and a
 * peak much narrower than g's own scale is taken out in closed form first
 * (ggx_split_series).
 */
#include "words/microfacet_pair.h"

#include "numerics/filon.h"

#include <math.h>
#include <string.h>

#define FILON_LEVELS 4        /* geometric pieces towards a singular point     */
#define FILON_LEVEL_SAMPLES 5 /* samples of each of them (odd)                 */
#define GGX_PIECE_SAMPLES 17  /* Filon samples of each of GGX's pieces, which
                               * double in width away from the peak and shrink
                               * by 4 towards a singular point ...             */
#define GGX_KINK_LEVELS 8     /* ... this many times towards the square root of
                               * total internal reflection, on the circle or
                               * just off it,                                  */
#define GGX_END_LEVELS 2      /* ... and this many towards the end of
                               * refraction (where g falls to 0 like a power
                               * >= 1) and towards a branch point just off the
                               * circle but TIR's: measured against direct
                               * integration, 2 is as accurate there as 8 (TIR
                               * needs its 8: with 5, its worst pair at alpha 1
                               * errs by 3.3e-4 of the peak instead of 2.3e-4,
                               * and with 2 just off the circle by 5.1e-4
                               * instead of 1.6e-4)                            */
#define GGX_KINK_GOAL 1e-4    /* the Fresnel part's grading stops where the
                               * piece next to the kink, d wide, after one
                               * whose largest f is f_d, has d f_d below this
                               * times the pair's peak (add_towards)           */
#define GGX_NEGLIGIBLE 1e-6   /* Filon pieces of GGX below this fraction of the
                               * pair's peak add nothing (ggx_piece)           */
#define GGX_FIRST_EXTRA 16    /* GGX's first block of orders: its peak's and
                               * this many more ...                            */
#define GGX_SETTLED 2.5e-4    /* ... doubled until the last quarter
                               * of the block stays below this fraction of the
                               * mean: a quarter of what the layer keeps
                               * (LL_MICROFACET_RELERR)                        */

/* cos(a + k h) for k < count, h = (b - a) / (count - 1), by rotation
 * (the error grows by about one rounding per step); with p not NULL, each
 * cosine's Beckmann peak factor exp(A + B (cos - 1)) into peak, in the
 * same loop: the rotation is a chain of dependent roundings, which the
 * exponentials' independent work overlaps. */
static void azimuth_cosines(double a, double b, size_t count, double *out, const pair_plan *p,
                            double *peak)
{
    double h = (b - a) / (double)(count - 1), ch = cos(h), sh = sin(h);
    double c = cos(a), s = sin(a);
    size_t k;
    for (k = 0; k < count; ++k) {
        double next_c = c * ch - s * sh;
        out[k] = c;
        if (p)
            peak[k] = exp(p->a_plus_b + p->b * (c - 1.0));
        s = s * ch + c * sh;
        c = next_c;
    }
}

/* The larger of a and b, as fmax(a, b) where a is not NaN (b NaN gives
 * a): the running maxima below start from 0 or a sample, and fmax is a
 * library call that the compiler may not inline (it must order signed
 * zeros and NaNs as C99 says), once per sample. */
static double larger(double a, double b)
{
    return b > a ? b : a;
}

/* Scratch of the Filon path: samples, their cosines, Filon's own. */
enum { FILON_SCR_F = 0, FILON_SCR_COS = FILON_SAMPLES, FILON_SCR_FILON = 2 * FILON_SAMPLES };

/* Add the Filon moments of f = exp(A + B cos phi) g over [a, b] to out
 * (with F = 1 in g for the reference). */
static void add_piece(const ll_microfacet_model *mf, const pair_plan *p, int reference, double a,
                      double b, size_t samples, size_t n_out, double *out, double *scratch)
{
    double *f = scratch + FILON_SCR_F, *cos_phi = scratch + FILON_SCR_COS;
    double *filon = scratch + FILON_SCR_FILON;
    size_t k;
    double peak[FILON_SAMPLES];
    if (!(b > a))
        return;
    azimuth_cosines(a, b, samples, cos_phi, p, peak);
    ll_microfacet_sample_profile(mf, p, cos_phi, samples, reference ? NULL : f,
                                 reference ? f : NULL);
    for (k = 0; k < samples; ++k)
        f[k] *= peak[k];
    if (n_out == 1 && mf->simpson_order0) {
        /* (samples is odd: panels of two intervals, as Filon's) */
        double odd = 0.0, even = 0.0, h = (b - a) / (double)(samples - 1);
        for (k = 1; k < samples; k += 2)
            odd += f[k];
        for (k = 2; k + 1 < samples; k += 2)
            even += f[k];
        out[0] += h / 3.0 * (f[0] + 4.0 * odd + 2.0 * even + f[samples - 1]);
        return;
    }
    ll_filon_moments(f, samples, a, b, n_out, out, filon);
}

/* add_piece for GGX, with its peak factor; *seen is the largest f of the
 * pair's pieces so far. A piece whose samples all stay below
 * GGX_NEGLIGIBLE of it adds no moments: its share of f at any azimuth, of
 * the series' partial sums too, is below that fraction of the peak (the
 * tails of a sharp lobe and the kinks far out in them cost most of the
 * samples otherwise). part: GGX_WHOLE (f), GGX_REFERENCE (f with F = 1) or
 * GGX_FRESNEL (f minus its reference).
 *
 * A piece far out in the tail needs fewer samples, as its error counts
 * against the pair's peak, not its own size: every fourth sample is taken
 * first, and the rest only where those reach GGX_COARSE of *seen (every
 * second) or GGX_MEDIUM (all). The quadratic through 5 samples of a
 * piece over which f falls like phi^-4 (the tails' doubling pieces) errs
 * by about 12% of the piece's largest f, through 9 by 1.5% and through 17
 * by 0.2%: so at most about 1.2e-5 and 1.5e-5 of the peak where fewer are
 * taken (the square root at a kink, graded, errs less). Every order block
 * of the pair makes the same choices, as they depend on the samples and
 * *seen alone. */
enum { GGX_WHOLE, GGX_REFERENCE, GGX_FRESNEL };

#define GGX_COARSE 1e-4
#define GGX_MEDIUM 1e-3
#if GGX_PIECE_SAMPLES != 17
#error "ggx_piece takes every fourth, every second, then all of 17 samples"
#endif
/* f (or its part) at the cosines cos_phi[k stride], count of them, into
 * f[k stride]; returns the largest |f| of them. peak: exp(p->a_plus_b),
 * which the pair's pieces share. */
static double ggx_samples(const ll_microfacet_model *mf, const pair_plan *p, int part,
                          const double *q, double peak, const double *cos_phi, size_t first,
                          size_t stride, size_t count, double *f)
{
    double c_sub[GGX_PIECE_SAMPLES], f_sub[GGX_PIECE_SAMPLES], ref_sub[GGX_PIECE_SAMPLES];
    double largest = 0.0;
    size_t k;
    for (k = 0; k < count; ++k)
        c_sub[k] = cos_phi[first + k * stride];
    ll_microfacet_sample_profile(mf, p, c_sub, count, part == GGX_REFERENCE ? NULL : f_sub,
                                 part == GGX_WHOLE ? NULL : part == GGX_REFERENCE ? f_sub
                                                                                  : ref_sub);
    for (k = 0; k < count; ++k) {
        double v = 1.0 - c_sub[k], c = 1.0 + p->b * v, value = f_sub[k];
        if (part == GGX_FRESNEL)
            value -= ref_sub[k];
        if (q)
            value -= q[0] + v * (q[1] + v * q[2]);
        value *= peak / (c * c);
        f[first + k * stride] = value;
        largest = larger(largest, fabs(value));
    }
    return largest;
}

/* One pass over a pair's pieces: the largest f seen so far, and the
 * samples each piece took (its stride, 0 if skipped, their largest |f|,
 * then the samples), which the passes of the next blocks of orders replay
 * instead of taking them again (cache NULL: more pieces than it holds,
 * sampled again). */
#define GGX_CACHE 1152
#define GGX_KEPT 48 /* pieces whose Taylor sums are kept (the rest: summed per block) */
typedef struct ggx_pass {
    double seen;
    const double *q; /* g's quadratic taken out with the peak (ggx_split_series) */
    double peak;     /* exp(a_plus_b), once for all the pass' samples              */
    double *cache;
    size_t used;
    int replay;
    size_t piece;    /* the pieces so far in this pass */
    size_t kept_ready; /* kept[0 .. kept_ready - 1] are initialised        */
    double kink_goal; /* > 0: the grading towards TIR's kink stops early
                       * (add_towards) against this                     */
    ll_filon_kept kept[GGX_KEPT];
} ggx_pass;

/* The kept Taylor sums of the pass's next piece (NULL: beyond GGX_KEPT). */
static ll_filon_kept *next_kept(ggx_pass *pass)
{
    size_t piece = pass->piece++;
    if (piece >= GGX_KEPT)
        return NULL;
    if (piece >= pass->kept_ready) { /* (a pair uses a few of them) */
        pass->kept[piece].powers = 0;
        pass->kept_ready = piece + 1;
    }
    return &pass->kept[piece];
}

/* Record a piece's stride (0: skipped), the largest |f| of its samples
 * and the samples. */
static void ggx_record(ggx_pass *pass, size_t stride, double largest, const double *f)
{
    size_t count = stride ? (GGX_PIECE_SAMPLES - 1) / stride + 1 : 0;
    if (pass->cache && pass->used + 2 + count <= GGX_CACHE) {
        pass->cache[pass->used] = (double)stride;
        pass->cache[pass->used + 1] = largest;
        memcpy(pass->cache + pass->used + 2, f, count * sizeof *f);
    } else {
        pass->cache = NULL;
    }
    pass->used += 2 + count;
}

/* Replaying, the next piece's samples where they are kept (NULL: the
 * piece is skipped), their count and largest |f|. */
static const double *ggx_replay(ggx_pass *pass, size_t *count, double *largest)
{
    size_t stride = (size_t)pass->cache[pass->used];
    const double *f = pass->cache + pass->used + 2;
    *count = stride ? (GGX_PIECE_SAMPLES - 1) / stride + 1 : 0;
    *largest = pass->cache[pass->used + 1];
    pass->used += 2 + *count;
    return stride ? f : NULL;
}

/* One piece of ggx_filon's; returns the largest |f| of its samples (0 if
 * it is skipped), the same replayed as sampled. */
static double ggx_piece(const ll_microfacet_model *mf, const pair_plan *p, int part, double a,
                      double b, size_t first, size_t n_out, double *out, double *scratch,
                      ggx_pass *pass)
{
    double *f = scratch + FILON_SCR_F, *cos_phi = scratch + FILON_SCR_COS;
    double *filon = scratch + FILON_SCR_FILON, largest, *seen = &pass->seen;
    size_t stride = 4, k;
    ll_filon_kept *kept;
    if (!(b > a))
        return 0.0;
    kept = next_kept(pass);
    if (pass->replay) {
        size_t count;
        const double *kept_f = ggx_replay(pass, &count, &largest);
        if (!kept_f)
            return 0.0;
        ll_filon_moments_kept(kept_f, count, a, b, first, n_out, out, filon, kept);
        return largest;
    }
    azimuth_cosines(a, b, GGX_PIECE_SAMPLES, cos_phi, NULL, NULL);
    largest = ggx_samples(mf, p, part, pass->q, pass->peak, cos_phi, 0, 4, 5, f);
    *seen = larger(*seen, largest);
    if (largest >= GGX_COARSE * *seen) {
        stride = 2;
        largest = larger(largest,
                         ggx_samples(mf, p, part, pass->q, pass->peak, cos_phi, 2, 4, 4, f));
        *seen = larger(*seen, largest);
        if (largest >= GGX_MEDIUM * *seen) {
            stride = 1;
            largest = larger(largest,
                             ggx_samples(mf, p, part, pass->q, pass->peak, cos_phi, 1, 2, 8, f));
            *seen = larger(*seen, largest);
        }
    }
    if (largest < GGX_NEGLIGIBLE * *seen || !(largest > 0.0)) {
        ggx_record(pass, 0, 0.0, f);
        return 0.0;
    }
    if (stride > 1) /* the samples taken, side by side */
        for (k = 1; k * stride < GGX_PIECE_SAMPLES; ++k)
            f[k] = f[k * stride];
    ggx_record(pass, stride, largest, f);
    ll_filon_moments_kept(f, (GGX_PIECE_SAMPLES - 1) / stride + 1, a, b, first, n_out, out, filon,
                          kept);
    return largest;
}

/* [a, b] on uniform panels, except that next to an end at (or near) a
 * branch point the first panel pair is replaced by pieces shrinking by 4
 * towards it: Fresnel's square root there would cost O(h^1/2) on uniform
 * panels; graded, only the last tiny piece errs. */
static void add_graded(const ll_microfacet_model *mf, const pair_plan *p, int reference, double a,
                       double b, size_t samples, int grade_a, int grade_b, size_t n_out,
                       double *out, double *scratch)
{
    double edge = 2.0 * (b - a) / (double)(samples - 1), lo_frac = 0.25, hi_frac = 1.0;
    double main_a = grade_a ? a + edge : a, main_b = grade_b ? b - edge : b;
    int level;
    add_piece(mf, p, reference, main_a, main_b, samples, n_out, out, scratch);
    for (level = 0; level < FILON_LEVELS; ++level) {
        double lo = level == FILON_LEVELS - 1 ? 0.0 : lo_frac;
        if (grade_a)
            add_piece(mf, p, reference, a + lo * edge, a + hi_frac * edge,
                      FILON_LEVEL_SAMPLES, n_out, out, scratch);
        if (grade_b)
            add_piece(mf, p, reference, b - hi_frac * edge, b - lo * edge,
                      FILON_LEVEL_SAMPLES, n_out, out, scratch);
        hi_frac = lo_frac;
        lo_frac *= 0.25;
    }
}

/* The pieces towards an end of [a, b] (d = b - a) whose branch point
 * lies rho off the circle (in phi; 0: on it, a kink): at most max_levels,
 * and no more than make the last piece, d 4^-(levels - 1) wide, at most
 * rho. A piece no wider than its distance from the branch point sees an
 * analytic f, which its 8 quadratic panels resolve as well as the graded
 * pieces resolve a kink on the circle (the error of a panel goes like
 * (h / distance)^3, and each piece is as wide as its distance from the
 * end); pieces finer than that only cost samples and orders (the grazing
 * reflections next to total internal reflection, whose branch point lies
 * just off phi = 0, took 8 levels inside the peak's own piece). */
static int levels_towards(int max_levels, double d, double rho)
{
    int levels = 1;
    if (!(rho > 0.0))
        return max_levels;
    while (levels < max_levels && d > rho) {
        d *= 0.25;
        ++levels;
    }
    return levels;
}

/* How far off the circle, in phi, the branch point near phi = 0 (at u <=
 * 0 of the whole circle's v = 2u) or near phi = pi (u >= 1) lies: 1 - cos
 * phi = 2u at phi = i y, cosh y = 1 - 2u, and at phi = pi + i y, cosh y =
 * 2u - 1. */
static double branch_distance(double outside)
{
    double x = 2.0 * outside;
    return outside > 0.0 ? log1p(x + sqrt(x * (2.0 + x))) : 0.0;
}

/* [a, b] for GGX, graded towards a singular end over its whole length:
 * pieces at distances [d / 4, d] from it, d = b - a, b - a / 4, ..., each
 * with the same samples, so that every piece resolves the square root of
 * Fresnel at the kink to the same relative accuracy (on uniform panels,
 * as add_graded's, the panels next to the graded ones err by O(h^1/2)
 * there, and a kink under a wide GGX lobe is summed over ~100 orders).
 * levels_a, levels_b: the pieces towards each end at most (0: not
 * graded), as levels_towards allows for a branch point rho_a, rho_b off
 * the circle. Where the pass has a kink_goal (the Fresnel part of total
 * internal reflection), the grading stops early: the piece that reaches
 * the kink, d wide, errs by about d times the square root's size there,
 * which the piece before it (at [d, 4 d], its largest |f| f_d) bounds,
 * so once d f_d is below the goal, finer pieces change nothing that
 * matters (a kink far out in a narrow lobe's tail took all 8 levels). The
 * choice depends on the samples alone, so a replayed pass makes it
 * again the same. */
static void add_towards(const ll_microfacet_model *mf, const pair_plan *p, int part, double a,
                        double b, int levels_a, double rho_a, int levels_b, double rho_b,
                        size_t first, size_t n_out, double *out, double *scratch,
                        ggx_pass *pass)
{
    double d = b - a, last = HUGE_VAL;
    int level, levels;
    if (!(b > a))
        return;
    if (levels_a && levels_b) {
        double mid = 0.5 * (a + b);
        add_towards(mf, p, part, a, mid, levels_a, rho_a, 0, 0.0, first, n_out, out, scratch,
                    pass);
        add_towards(mf, p, part, mid, b, 0, 0.0, levels_b, rho_b, first, n_out, out, scratch,
                    pass);
        return;
    }
    levels = levels_a ? levels_towards(levels_a, d, rho_a)
             : levels_b ? levels_towards(levels_b, d, rho_b)
                        : 0;
    if (!levels) {
        ggx_piece(mf, p, part, a, b, first, n_out, out, scratch, pass);
        return;
    }
    for (level = 0; level < levels; ++level) {
        double near = level == levels - 1 || d * last < pass->kink_goal ? 0.0 : 0.25 * d;
        if (levels_a)
            last = ggx_piece(mf, p, part, a + near, a + d, first, n_out, out, scratch, pass);
        else
            last = ggx_piece(mf, p, part, b - d, b - near, first, n_out, out, scratch, pass);
        if (near == 0.0)
            break;
        d = near;
    }
}

/* GGX's f over [start, pi] (or [start, split] for refraction; start is 0
 * or the split): pieces doubling in width from the peak's half width
 * beta^-1/2 on (the tails fall like phi^-4, so each piece spans the same
 * relative change of f), cut at the kink and graded towards it and towards
 * near branch points; the orders first .. first + n_out - 1 into out[0 ..
 * n_out - 1]. seen: the largest f known before the first piece. */
static void ggx_filon(const ll_microfacet_model *mf, const pair_plan *p, int part, double start,
                      double seen, size_t first, size_t n_out, double *out, double *scratch,
                      ggx_pass *pass)
{
    /* (refraction ends at its split, but the rest of a split peak, -E_beta
     * q beyond it, does not) */
    double end = !p->reflect && p->split > 0.0 && !pass->q ? p->split : LL_PI;
    double a = start, width = p->b > 0.0 ? fmin(LL_PI, 1.0 / sqrt(p->b)) : LL_PI;
    /* (a dielectric's reflection: its branch points may be TIR's) */
    int kink_levels = p->reflect ? GGX_KINK_LEVELS : GGX_END_LEVELS;
    int branch_levels = p->reflect && !mf->conductor ? GGX_KINK_LEVELS : GGX_END_LEVELS;
    pass->seen = seen;
    pass->used = 0;
    pass->piece = 0;
    while (a < end) {
        double b = a == 0.0 ? width : 2.0 * a;
        int grade_a, grade_b;
        if (b > end - ANGLE_EPS)
            b = end;
        if (p->split > a && p->split < b)
            b = p->split;
        /* Reflection's kink is total internal reflection, which holds
         * below the split (t < 1 - 2 eta^2, and t grows with phi): F = 1
         * there, and Fresnel's square root is on the far side alone. */
        grade_a = a == 0.0 ? (p->grade_start ? branch_levels : 0)
                  : a == p->split ? kink_levels
                                  : 0;
        grade_b = b == p->split && !p->reflect ? kink_levels
                  : b == LL_PI && p->grade_end ? branch_levels
                                               : 0;
        add_towards(mf, p, part, a, b, grade_a, a == 0.0 ? branch_distance(-p->near_start) : 0.0,
                    grade_b, b == LL_PI ? branch_distance(p->near_end - 1.0) : 0.0, first,
                    n_out, out, scratch, pass);
        a = b;
    }
}

/* Whether the block of orders [0, n) of Filon moments has settled: its
 * last quarter (at least 8 orders) below GGX_SETTLED of the mean, given
 * as the moment of order 0 (the series' terms are 2 / pi times the
 * moments, its mean 1 / pi times the moment of order 0). */
static int ggx_settled(const double *out, size_t n, double moment0)
{
    size_t width = n / 4 > 8 ? n / 4 : 8, l;
    double largest = 0.0;
    if (width > n)
        width = n;
    for (l = n - width; l < n; ++l)
        largest = larger(largest, fabs(out[l]));
    return 2.0 * largest < GGX_SETTLED * fabs(moment0);
}

/* The asymptotic tail of total internal reflection's kink. Beyond the
 * critical azimuth phi_c the refracted cosine is sqrt(cos phi_c - cos phi)
 * times a constant, so the Fresnel part is a power series in s^1/2, s =
 * phi - phi_c: d_1 s^1/2 + d_2 s + d_3 s^3/2 + ... (f is 0 before phi_c,
 * smooth after it and even about pi). Its moments at high orders are then
 * the end point's alone (integral_0^inf s^nu e^(i l s) ds = Gamma(nu + 1)
 * e^(i pi (nu + 1) / 2) / l^(nu + 1)):
 *     A_l = sum_p d_p Gamma(p / 2 + 1) cos(l phi_c + pi (p / 2 + 1) / 2)
 *           / l^(p / 2 + 1),  p = 1 .. GGX_TAIL_TERMS,
 * which errs like l^-7/2 from the powers left out (and, at low orders, by
 * the rest of f's shape). The l^-3/2 of the first term is what kept most
 * such pairs at the orders' limit, each block of Filon moments costing all
 * the pieces again. So once a block after the first agrees with A_l order
 * by order to within 16 GGX_SETTLED of the moment of order 0 over the
 * block's last order n, the orders after it are A_l's (until they settle
 * too): the error of A_l summed over those orders, about n / 2.5 times the
 * block's as it falls like l^-7/2, stays within about 4 GGX_SETTLED of the
 * mean in the series, where settling leaves out every term below
 * GGX_SETTLED, however many. (Measured, n = 200, eta 1.5: 16 takes 9% of
 * the instructions off the build at alpha 0.05 and 11% at 0.1, 32 no more,
 * and checking the first block's second half as well errs by 1.5e-4 of
 * the peak against direct integration.) d_p come from the polynomial in
 * s^1/2 through f / s^1/2 at GGX_TAIL_POINTS points s^1/2 = sigma, 2 sigma,
 * ..., sigma = GGX_TAIL_FIT times the square root of the span over which
 * the series holds (to pi, and to where cos phi reaches the peak factor's
 * pole 1 + 1 / beta), fitted only when a second block is needed; the
 * block check makes a poor fit cost orders, not accuracy. tail: d_1 ..
 * d_5, phi_c. */
#define GGX_TAIL_FIT 0.05
#define GGX_TAIL_POINTS 6 /* samples of the fit: the polynomial's degree + 1 */
#define GGX_TAIL_TERMS 5  /* powers s^(p/2) in the tail, p = 1 .. 5          */
#define GGX_TAIL_MATCH 16.0 /* the block check's bound, in GGX_SETTLED of the
                             * moment of order 0 over the block's end        */

static int kink_tail_fit(const ll_microfacet_model *mf, const pair_plan *p, double *tail)
{
    double phi_c = p->split, x_c = cos(phi_c), span = LL_PI - phi_c, sigma;
    double x[GGX_TAIL_POINTS], f[GGX_TAIL_POINTS], c[GGX_TAIL_POINTS];
    size_t j, k;
    if (p->b > 0.0 && sin(phi_c) > 0.0)
        span = fmin(span, (1.0 + 1.0 / p->b - x_c) / sin(phi_c));
    if (!(span > 0.0))
        return 0;
    sigma = GGX_TAIL_FIT * sqrt(span);
    for (j = 0; j < GGX_TAIL_POINTS; ++j) {
        double root = (double)(j + 1) * sigma;
        x[j] = cos(phi_c + root * root);
    }
    ggx_samples(mf, p, GGX_FRESNEL, NULL, exp(p->a_plus_b), x, 0, 1, GGX_TAIL_POINTS, f);
    /* f / s^1/2 at the nodes t_j = j + 1 (in units of sigma): Newton's
     * divided differences, then the monomial coefficients in t */
    for (j = 0; j < GGX_TAIL_POINTS; ++j)
        c[j] = f[j] / ((double)(j + 1) * sigma);
    for (k = 1; k < GGX_TAIL_POINTS; ++k)
        for (j = GGX_TAIL_POINTS - 1; j >= k; --j)
            c[j] = (c[j] - c[j - 1]) / (double)k;
    for (k = GGX_TAIL_POINTS - 1; k-- > 0;)
        for (j = k; j + 1 < GGX_TAIL_POINTS; ++j)
            c[j] -= (double)(k + 1) * c[j + 1];
    for (k = 0; k < GGX_TAIL_TERMS; ++k) {
        tail[k] = c[k] / pow(sigma, (double)k);
        if (!isfinite(tail[k]))
            return 0;
    }
    tail[GGX_TAIL_TERMS] = phi_c;
    return 1;
}

/* A_l of the tail for l = from .. to - 1 (from >= 1), into a, or, with
 * check not NULL, only as long as |check[l] - A_l| stays within limit;
 * returns whether it did. The phase l phi_c goes by rotation (one
 * rounding per order). */
static int kink_tail(const double *tail, size_t from, size_t to, double *a, const double *check,
                     double limit)
{
    /* Gamma(p / 2 + 1) */
    static const double gamma[GGX_TAIL_TERMS] = { 0.88622692545275801, 1.0,
                                                  1.3293403881791370, 2.0,
                                                  3.3233509704478426 };
    double wc[GGX_TAIL_TERMS], ws[GGX_TAIL_TERMS], phi_c = tail[GGX_TAIL_TERMS];
    double c = cos((double)from * phi_c), s = sin((double)from * phi_c);
    double rc = cos(phi_c), rs = sin(phi_c);
    size_t k, l;
    for (k = 0; k < GGX_TAIL_TERMS; ++k) {
        double phase = 0.25 * LL_PI * (double)(k + 3);
        wc[k] = tail[k] * gamma[k] * cos(phase);
        ws[k] = tail[k] * gamma[k] * sin(phase);
    }
    for (l = from; l < to; ++l) {
        double order = (double)l, step = 1.0 / sqrt(order), power = 1.0 / order, sum = 0.0;
        double next = c * rc - s * rs;
        for (k = 0; k < GGX_TAIL_TERMS; ++k) {
            power *= step;
            sum += (wc[k] * c - ws[k] * s) * power;
        }
        if (check && !(fabs(check[l] - sum) <= limit))
            return 0;
        if (a)
            a[l - from] = sum;
        s = s * rc + c * rs;
        c = next;
    }
    return 1;
}

/* Whether the moments of the orders [from, to) agree with the tail's. */
static int tail_matches(const double *tail, const double *out, size_t from, size_t to,
                        double moment0)
{
    return kink_tail(tail, from > 0 ? from : 1, to, NULL, out,
                     GGX_TAIL_MATCH * GGX_SETTLED * fabs(moment0) / (double)to);
}

/* The orders from n on from the tail, doubling until settled against
 * moment0 (at most n_out); returns the orders. */
static size_t tail_extend(const double *tail, double *out, size_t n, size_t n_out,
                          double moment0)
{
    while (n < n_out) {
        size_t step = n > 8 ? n : 8, next = n_out - n > step ? n + step : n_out;
        kink_tail(tail, n, next, out + n, NULL, 0.0);
        n = next;
        if (ggx_settled(out, n, moment0))
            break;
    }
    return n;
}

/* GGX's Filon moments from start on, n_out orders at most, by blocks: a
 * kink far out in the tail, or the end of refraction, adds terms that
 * fall like a power of the order, and how far they matter depends on the
 * size of the kink, which only the moments tell. Each block costs its
 * orders times the samples, so the first holds the orders of the sharpest
 * thing the integrand holds (first: the peak's, or fewer where the peak
 * is taken out, q not NULL) and a few more, and the next ones (the orders
 * after it, the same pieces and samples, replayed) double it until its
 * last quarter has settled against the pair's moment of order
 * 0: moment0, plus the moments' own order 0 if own0 (doubling, not
 * adding half, as every block's pass over the pieces costs the pieces'
 * setup again, which the fewer passes save more of than the orders
 * beyond the settled ones cost). tail (not NULL: total internal
 * reflection's Fresnel part, room for kink_tail_fit's fit): the orders
 * after a block that agrees with the kink's asymptotic tail are the
 * tail's. Returns the orders computed. */
static size_t ggx_orders(const ll_microfacet_model *mf, const pair_plan *p, int part,
                         const double *q, double *tail, double start, double seen,
                         size_t first, double moment0, int own0, size_t n_out, double *out,
                         double *scratch)
{
    double cache[GGX_CACHE];
    ggx_pass pass;
    size_t blocks = 1, n = ll_ggx_length_at(&p->peak_len, n_out) + GGX_FIRST_EXTRA;
    int fitted = 0; /* the tail: 0 not yet fitted, 1 fitted, -1 no fit */
    if (first && first < n)
        n = first;
    if (n > n_out)
        n = n_out;
    pass.cache = cache;
    pass.replay = 0;
    pass.q = q;
    pass.peak = exp(p->a_plus_b);
    pass.kink_goal = part == GGX_FRESNEL ? GGX_KINK_GOAL * seen : 0.0;
    pass.kept_ready = 0;
    ggx_filon(mf, p, part, start, seen, 0, n, out, scratch, &pass);
    pass.replay = pass.cache != NULL;
    while (n < n_out && !ggx_settled(out, n, moment0 + (own0 ? out[0] : 0.0))) {
        size_t step = n > 8 ? n : 8, next = n_out - n > step ? n + step : n_out;
        if (tail && blocks >= 2) {
            if (!fitted)
                fitted = kink_tail_fit(mf, p, tail) ? 1 : -1;
            if (fitted > 0 && tail_matches(tail, out, n / 2, n, moment0))
                return tail_extend(tail, out, n, n_out, moment0);
        }
        ggx_filon(mf, p, part, start, seen, n, next - n, out + n, scratch, &pass);
        n = next;
        ++blocks;
    }
    return n;
}

/* The moments into a cosine series: (2 - [l = 0]) / pi. */
static void moments_to_series(double *out, size_t n)
{
    size_t l;
    if (n == 0)
        return;
    out[0] *= LL_INV_PI;
    for (l = 1; l < n; ++l)
        out[l] *= 2.0 * LL_INV_PI;
}

size_t ll_microfacet_ggx_fresnel_part(const ll_microfacet_model *mf, const pair_plan *p,
                                      double mean, double seen, size_t n_out, double *out,
                                      double *scratch)
{
    /* The part starts at the split, v_s = 1 - cos(split) from the peak,
     * where E_beta varies like a peak of sharpness beta / (1 + beta v_s)
     * (its logarithmic derivative in v): the first block holds that
     * peak's orders, not the pair's. */
    double half = sin(0.5 * p->split), local = p->b / (1.0 + p->b * 2.0 * half * half);
    double tail[GGX_TAIL_TERMS + 1];
    size_t n, first = ll_ggx_peak_length(local, GGX_TAIL_GOAL, n_out) + GGX_FIRST_EXTRA;
    memset(out, 0, n_out * sizeof(double));
    n = ggx_orders(mf, p, GGX_FRESNEL, NULL, tail, p->split, seen, first, LL_PI * mean, 0, n_out,
                   out, scratch);
    moments_to_series(out, n);
    return n;
}

/* The peak split. Where g is analytic over a distance delta in v = 1 -
 * cos phi around the peak at phi = 0 and the peak is much narrower (beta
 * delta >= GGX_SPLIT_REACH), f = peak E_beta g is split into peak E_beta q,
 * q the quadratic in v through g at v = 0, V/2 and V, V = GGX_SPLIT_SPAN /
 * beta, whose series the closed form gives (ll_ggx_series_quadratic), and
 * the rest peak E_beta (g - q), which takes the Filon path. That rest has
 * no sharp peak: g - q is at most about (V / delta)^3 of g over the peak's
 * v <~ 1 / beta, and beyond it E_beta (g - q), with E_beta ~ (beta v)^-2
 * against g - q ~ (v / delta)^3, stays below about (beta delta)^-2 of the
 * peak and varies on g's own scale delta. So the rest needs the orders of
 * g's kinks and branch points, not the hundreds of the peak's: its first
 * block holds GGX_FIRST_EXTRA plus 4 / sqrt(delta) (g's scale in phi is
 * about sqrt(2 delta)), and the blocks grow from there as for any kink,
 * settled against the whole pair's mean. delta: the kink (the end of
 * refraction), a branch point just before phi = 0, or GGX_SPLIT_UNRECORDED
 * (beyond which classify_window records none). The peak's orders are the
 * closed form's, one term each. */
#define GGX_SPLIT_REACH 16.0
#define GGX_SPLIT_SPAN 4.0
#define GGX_SPLIT_UNRECORDED 0.2 /* in v: 2 NEAR_SINGULAR of microfacet_plan.c's
                                  * u = v / 2 on GGX's whole circle            */

/* The quadratic of the peak split, of g into q_g and times the peak
 * factor into q, and the distance delta; 0 if the pair is not split. */
static int ggx_peak_quadratic(const ll_microfacet_model *mf, const pair_plan *p, int reference,
                              double *q_g, double *q, double *delta)
{
    double d = GGX_SPLIT_UNRECORDED, span, h, cos_phi[3], g[3], d1, d12, d2, peak;
    if (p->split > 0.0) {
        double half = sin(0.5 * p->split);
        d = fmin(d, 2.0 * half * half);
    }
    if (p->grade_start)
        d = fmin(d, -2.0 * p->near_start);
    if (!(p->b * d >= GGX_SPLIT_REACH))
        return 0;
    span = GGX_SPLIT_SPAN / p->b;
    h = 0.5 * span;
    cos_phi[0] = 1.0;
    cos_phi[1] = 1.0 - h;
    cos_phi[2] = 1.0 - span;
    ll_microfacet_sample_profile(mf, p, cos_phi, 3, reference ? NULL : g, reference ? g : NULL);
    peak = exp(p->a_plus_b);
    d1 = (g[1] - g[0]) / h;
    d12 = (g[2] - g[1]) / h;
    d2 = (d12 - d1) / span;
    q_g[0] = g[0];
    q_g[1] = d1 - d2 * h;
    q_g[2] = d2;
    q[0] = q_g[0] * peak;
    q[1] = q_g[1] * peak;
    q[2] = q_g[2] * peak;
    *delta = d;
    return 1;
}

/* GGX's whole series by the Filon path (ll_microfacet_filon_series), its
 * peak split off where it can be. */
static void ggx_split_series(const ll_microfacet_model *mf, const pair_plan *p, int reference,
                             size_t n_out, double *out, double *scratch)
{
    double q[3], q_rest[3], delta, mean; /* q_rest: q without the peak factor */
    size_t first, n_closed, l;
    int part = reference ? GGX_REFERENCE : GGX_WHOLE;
    if (!ggx_peak_quadratic(mf, p, reference, q_rest, q, &delta)) {
        ggx_orders(mf, p, part, NULL, NULL, 0.0, 0.0, 0, 0.0, 1, n_out, out, scratch);
        moments_to_series(out, n_out);
        return;
    }
    ll_ggx_series_quadratic(p->b, q, 1, &mean, scratch);
    first = GGX_FIRST_EXTRA + (size_t)ceil(4.0 / sqrt(delta));
    ggx_orders(mf, p, part, q_rest, NULL, 0.0, q[0], first, LL_PI * mean, 1, n_out, out, scratch);
    moments_to_series(out, n_out);
    n_closed = ll_ggx_length_at(&p->peak_len, n_out) + 3;
    if (n_closed > n_out)
        n_closed = n_out;
    ll_ggx_series_quadratic(p->b, q, n_closed, scratch, scratch + n_closed);
    for (l = 0; l < n_closed; ++l)
        out[l] += scratch[l];
}

/* The cosine series c_l = (2 - [l = 0]) / pi integral_0^pi f cos(l phi)
 * dphi, l < n_out, over the window (f is below 1e-12 of its peak beyond),
 * split at a kink. */
void ll_microfacet_filon_series(const ll_microfacet_model *mf, const pair_plan *p, int reference,
                                size_t n_out, double *out, double *scratch)
{
    memset(out, 0, n_out * sizeof(double));
    if (mf->ggx) {
        ggx_split_series(mf, p, reference, n_out, out, scratch);
        return;
    } else if (p->split > 0.0) {
        add_graded(mf, p, reference, 0.0, p->split, FILON_SAMPLES, p->grade_start, 1, n_out,
                   out, scratch);
        if (p->reflect) /* refracted light ends at the split */
            add_graded(mf, p, reference, p->split, p->phi_end, FILON_SAMPLES, 1, p->grade_end,
                       n_out, out, scratch);
    } else {
        add_graded(mf, p, reference, 0.0, p->phi_end, FILON_SAMPLES, p->grade_start,
                   p->grade_end, n_out, out, scratch);
    }
    moments_to_series(out, n_out);
}
