/*
 * The microfacet normal distribution of an isotropic BSDF from its
 * retro-reflection (Dupuy et al. 2015, "Extracting Microfacet-based BRDF
 * Parameters from Arbitrary Materials with Power Iterations"; the operator
 * as docs/formats.md states it): with masking and shadowing of the
 * retro-reflected ray fully correlated, f(k, k) = F D(k) / (4 cos(theta_k)
 * sigma(k)), so D(k) = c cos(theta_k) f(k, k) sigma[D](k), sigma[D](k) =
 * integral of max(0, k.m) D(m) dm, linear in D: D is the dominant
 * eigenvector of K(k, m) = cos(theta_k) f(k, k) max(0, k.m), found by power
 * iteration, and c is fixed by the normalisation integral of D cos = 1.
 *
 * For an isotropic D the azimuthal integral of max(0, k.m) over a ring of
 * normals is closed-form, so K is an n x n matrix over elevation nodes.
 *
 * The floor. The tables' values are f cos over D (the jacobian rule), and
 * the sample grid spends its last cell on everything beyond the VNDF's
 * last-but-one quantile. The derived D follows the retro-reflection down
 * to the numerical floor of a Fourier series (about 1e-4 of the peak), so
 * its support reaches the horizon while its tail is almost nothing: the
 * outer node of the grid then lands at the horizon with value 0 and the
 * lobe's tail is interpolated towards zero (on rough gold, alpha 0.2, at
 * 32 x 128^2 x 64^2, the plain derived D loses 0.3% of albedo at cos
 * theta_i = 0.7 and 1.2% at 0.3; with the mixture below 0.02% and 0.02%).
 * Zeroing D below a threshold
 * instead makes f / D explode where f has its floor. A Beckmann lobe and a
 * uniform floor 1/pi (weight 0.02, itself normalised: the integral of
 * cos / pi is 1) give the tails grid cells of their own and keep f / D
 * bounded. D only parameterises the tables (the values carry f cos / D and
 * the renderer multiplies D back), so the mixture changes where the grid's
 * resolution goes, not the BSDF.
 *
 * The Beckmann lobe's width and weight. Retro-reflection sees a layered
 * material's lobes only at normal-like angles: under a clear coat the
 * metal's lobe, refracted, spreads far wider at grazing angles than
 * retro-reflection at the same half vector shows, and with too little D
 * there its cells are few and wide (examples/coated-gold.layers at 32 x
 * 64^2 x 64^2, with a lobe of twice the fitted roughness at weight 0.2:
 * 99th percentile of the relative error 20%, at both elevations beyond 65
 * degrees and half vectors of 17..35 degrees). Three times the fitted
 * roughness at weight 0.4 gives that region cells (99th percentile 2.2%,
 * albedo within 0.28%; rough gold, alpha 0.2, stays at 2.0% and 0.19%);
 * 2.5 or 3.5 times, or weights 0.3 or 0.5, did worse on one figure or the
 * other, and six times lost the sharp lobe's cells (17%). Shaping the VNDF
 * table by the slice's own reflection instead (the readers use it only as
 * a warp) does not work: the renderers multiply the stored values by the
 * global D, which then varies across a cell of that warp, and the albedo
 * at grazing angles came out 1-4% high.
 *
 * The peak. When a broad lobe dominates the retro-reflection (a coat over
 * a bright diffuse base: examples/plastic.layers fits alpha 0.40 from
 * D(0), while its coat's peak is 0.20 wide), both lobes above are broad
 * and the coat's lobe, which carries the dark channels at grazing angles,
 * gets few cells: albedo 10% off at 85 degrees at 32 x 64^2 x 64^2. A
 * Beckmann lobe of the peak's own width (peak_roughness) at weight 0.2
 * brings that to 1.8% (99th percentile 20% -> 8.5%; weights 0.35 and 0.5,
 * or 0.75 and 1.5 times the width, did worse); on rough gold and coated
 * gold the peak's width is the fitted roughness, and the lobe changes
 * little at a given grid (coated gold at 32 x 64^2 x 64^2: albedo 0.28%
 * -> 0.54%, f unchanged), while the sizes the tolerance chooses fall
 * (coated gold 8.85 -> 6.15 MB).
 *
 * A peak on a pedestal (ll_tables_derive_ndf_pedestal, for the reflected
 * sets of a transmissive stack that reflects alike from both sides). A
 * frosted pane's retro-reflection is its first surface's microfacets,
 * seen through F at normal incidence, on a broad pedestal of the light
 * that crossed that surface and came back from the second, so the fitted
 * roughness comes out well above the width of the central peak (a lone
 * rough interface's two agree). At grazing incidence F rises to 1 and
 * the reflection is that sharp first-surface lobe, which a wide lobe
 * scaled from the fitted roughness leaves too few columns of the sample
 * grid. Where the fitted roughness exceeds PEDESTAL_RATIO times the
 * peak's width, the wide lobe is scaled from the peak's width instead and
 * the peak lobe weighs more; the derived D keeps its share, without which
 * f / D explodes where the pedestal's light falls beyond a narrow D.
 * Opaque stacks keep the mixture above: a coat over a bright base has
 * the same shape, but there the broad lobe is the base's own reflection
 * at every angle. The options measured and their figures:
 * docs/benchmarks.md, "Reflected sets' D".
 *
 * A coat's peak (ll_tables_derive_ndf_coat, for the reflected set seen
 * from the rarer side of a transmissive stack that is not a lone
 * interface). Seen from there, a coat over a medium without a base reflects
 * its microfacets' lobe on the medium's broad light, and for a viewer
 * towards grazing the coat's lobe, the mirror direction, lies at the pole
 * of the normals, where the visible normals are few (their density in the
 * square goes as u_theta^3 by the area element, and wi.m is smallest
 * there): with the plain mixture the first column of the sample grid
 * spanned several degrees of normals from the pole, and f interpolated
 * across it came out well above the .bsdf's in the mirror plane. More
 * weight on the peak's own lobe, taken from the wider one, gives the pole
 * columns of its own, while the derived D keeps its share of the medium's
 * light (the weights measured and their figures: docs/benchmarks.md,
 * "Reflected sets' D"). The fitted roughness and the peak's width are close
 * here, so the pedestal rule above does not apply.
 */
#include "writer/bsdf_write_tables.h"

#include <math.h>
#include <string.h>

#define POWER_ITERATIONS 200
#define BECKMANN_WEIGHT 0.4
#define BECKMANN_WIDTH 3.0 /* times the fitted roughness */
#define PEAK_WEIGHT 0.2
#define FLOOR_WEIGHT 0.02
#define PEDESTAL_RATIO 1.25
#define PEDESTAL_PEAK_WEIGHT 0.4
#define COAT_PEAK_WEIGHT 0.7
#define COAT_BECKMANN_WEIGHT 0.1

enum { PLAIN, PEDESTAL, COAT };

double ll_tables_luminance(const double rgb[3])
{
    return 0.212671 * rgb[0] + 0.715160 * rgb[1] + 0.072169 * rgb[2];
}

/* The integral over azimuth phi in [0, 2 pi) of max(0, a + b cos(phi)),
 * b >= 0: 2 (a phi0 + b sin(phi0)) with phi0 = acos(-a / b) where the
 * integrand changes sign, else 2 pi a or 0. */
static double ring(double a, double b)
{
    double phi0;
    if (b <= fabs(a))
        return a > 0.0 ? 2.0 * LL_PI * a : 0.0;
    phi0 = acos(-a / b);
    return 2.0 * (a * phi0 + b * sin(phi0));
}

/* Quadrature over the hemisphere of normals: the integral of g(theta) over
 * theta in [0, pi/2] is that of g(theta(u)) pi u du (theta = u^2 pi / 2),
 * by trapezoids in u; the weight of node j includes sin(theta_j). */
void ll_tables_ndf_quadrature(size_t n, double *theta, double *w)
{
    size_t j;
    for (j = 0; j < n; ++j) {
        double u = (double)j / (double)(n - 1), h = 1.0 / (double)(n - 1);
        theta[j] = u * u * (LL_PI / 2);
        w[j] = (j == 0 || j == n - 1 ? 0.5 * h : h) * LL_PI * u * sin(theta[j]);
    }
}

/* sigma at each node from D at the nodes. */
void ll_tables_projected_area(size_t n, const double *theta, const double *w, const double *d,
                              double *sigma)
{
    size_t k, j;
    for (k = 0; k < n; ++k) {
        double s = 0.0;
        for (j = 0; j < n; ++j)
            s += w[j] * d[j] *
                 ring(cos(theta[k]) * cos(theta[j]), sin(theta[k]) * sin(theta[j]));
        sigma[k] = s;
    }
}

double ll_tables_beckmann(double theta, double alpha)
{
    double c = cos(theta), t2;
    if (c < 1e-6)
        return 0.0;
    t2 = (1.0 - c * c) / (c * c);
    return exp(-t2 / (alpha * alpha)) / (LL_PI * alpha * alpha * c * c * c * c);
}

/* The roughness of D's central peak from its width: a Beckmann D falls to
 * D(0) / e (times 1 / cos^4) at tan(theta) = alpha, whatever broad
 * pedestal lies under the peak, where D(0) = 1 / (pi alpha^2) would count
 * the pedestal's mass too. fallback if D never falls that far. */
static double peak_roughness(const double *d, const double *theta, double fallback)
{
    size_t j;
    for (j = 1; j < LL_TABLES_NDF_NODES; ++j) {
        double c = cos(theta[j]);
        if (d[j] * c * c * c * c <= d[0] * exp(-1.0))
            return tan(theta[j]);
    }
    return fallback;
}

/* D of side, with the pedestal rule of ll_tables_derive_ndf_pedestal
 * (rule PEDESTAL) or the weights of ll_tables_derive_ndf_coat (COAT). */
static ll_status derive(const ll_bsdf *b, int side, int rule, double *d, double *sigma,
                        double *alpha)
{
    enum { N = LL_TABLES_NDF_NODES };
    double theta[N], w[N], g[N], next[N], norm, peak, peak_alpha, wide, peak_weight;
    double wide_weight = BECKMANN_WEIGHT;
    size_t j, it;
    ll_tables_ndf_quadrature(N, theta, w);
    /* g = cos(theta) f(k, k) in luminance, k at azimuth 0. */
    peak = 0.0;
    for (j = 0; j < N; ++j) {
        double k[3] = { sin(theta[j]), 0.0, side * cos(theta[j]) }, rgb[3];
        if (ll_bsdf_eval_dir(b, k, k, LL_TRANSPORT_RADIANCE, NULL, rgb) != LL_OK)
            rgb[0] = rgb[1] = rgb[2] = 0.0;
        g[j] = cos(theta[j]) * ll_tables_luminance(rgb);
        if (!(g[j] > 0.0) || !ll_is_finite(g[j]))
            g[j] = 0.0;
        if (g[j] > peak)
            peak = g[j];
        d[j] = 1.0;
    }
    if (!(peak > 0.0))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_tables_write_from_bsdf: the file reflects nothing back towards "
                       "the light, so no normal distribution can be derived");
    for (it = 0; it < POWER_ITERATIONS; ++it) {
        double top = 0.0;
        ll_tables_projected_area(N, theta, w, d, sigma);
        for (j = 0; j < N; ++j) {
            next[j] = g[j] * sigma[j];
            if (next[j] > top)
                top = next[j];
        }
        for (j = 0; j < N; ++j)
            d[j] = next[j] / top;
    }
    /* The integral of D cos over the hemisphere = 1. */
    norm = 0.0;
    for (j = 0; j < N; ++j)
        norm += 2.0 * LL_PI * w[j] * d[j] * cos(theta[j]);
    for (j = 0; j < N; ++j)
        d[j] /= norm;
    /* Beckmann's D(0) = 1 / (pi alpha^2). */
    *alpha = 1.0 / sqrt(LL_PI * d[0]);
    if (!ll_is_finite(*alpha) || *alpha > 1.0)
        *alpha = 1.0;
    peak_alpha = peak_roughness(d, theta, *alpha);
    wide = *alpha;
    peak_weight = PEAK_WEIGHT;
    if (rule == PEDESTAL && *alpha > PEDESTAL_RATIO * peak_alpha) {
        wide = peak_alpha;
        peak_weight = PEDESTAL_PEAK_WEIGHT;
    }
    if (rule == COAT) {
        peak_weight = COAT_PEAK_WEIGHT;
        wide_weight = COAT_BECKMANN_WEIGHT;
    }
    for (j = 0; j < N; ++j)
        d[j] = (1.0 - wide_weight - peak_weight - FLOOR_WEIGHT) * d[j] +
               wide_weight * ll_tables_beckmann(theta[j], BECKMANN_WIDTH * wide) +
               peak_weight * ll_tables_beckmann(theta[j], peak_alpha) + FLOOR_WEIGHT / LL_PI;
    ll_tables_projected_area(N, theta, w, d, sigma);
    return LL_OK;
}

ll_status ll_tables_derive_ndf(const ll_bsdf *b, double *d, double *sigma, double *alpha)
{
    return derive(b, 1, PLAIN, d, sigma, alpha);
}

ll_status ll_tables_derive_ndf_side(const ll_bsdf *b, int side, double *d, double *sigma,
                                    double *alpha)
{
    return derive(b, side, PLAIN, d, sigma, alpha);
}

ll_status ll_tables_derive_ndf_pedestal(const ll_bsdf *b, int side, double *d, double *sigma,
                                        double *alpha)
{
    return derive(b, side, PEDESTAL, d, sigma, alpha);
}

ll_status ll_tables_derive_ndf_coat(const ll_bsdf *b, int side, double *d, double *sigma,
                                    double *alpha)
{
    return derive(b, side, COAT, d, sigma, alpha);
}
