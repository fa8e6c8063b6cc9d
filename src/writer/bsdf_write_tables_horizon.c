/*
 * The sample grid's nodes beyond the horizon (ll_tables_horizon_fit,
 * bsdf_write_tables.h). A node whose reflected direction lies below the
 * horizon is never returned by a reader (the format is one-sided: f and
 * the sampled direction are 0 there), but the cells it shares with nodes
 * above the horizon interpolate towards it. Stored as 0, those cells
 * pull the lobe down wherever f cos is still large close to the horizon,
 * which it is for a grazing viewer: on the rough corner of the coated-gold
 * grid (coat and gold alpha 0.4) at 32 x 64^2 x 64^2 the albedo at 85
 * degrees came out 1.5% low, at 128^2 samples 0.03%.
 *
 * So, per channel, each node below the horizon that touches one above it
 * stores lambda times the mean of its neighbours above it, with lambda
 * chosen so that the slice's albedo in that channel (the integral of the
 * stored values over the part of the sample square whose directions are
 * above the horizon, weighted by the square's area element in f cos
 * d omega) equals the source's (ll_bsdf_albedo, per channel) at the
 * slice's elevation. lambda = 1 continues the lobe flat across the
 * horizon; it is kept in [0, LAMBDA_MAX]. Where the slice is too bright
 * in a channel even with lambda = 0 (its interior, not its edge), that
 * channel's values are scaled down to the source's albedo instead. A
 * slice too dark where the edge carries almost nothing is left so: rough
 * glass's reflection beyond 85 degrees (4% short at 86.7 degrees on a 64^2
 * sample grid, 1.3% on 96^2, with the edge carrying 0.1% of the albedo
 * per unit of lambda) is the sample grid's cells inside the lobe, and a
 * scale of the whole slice up to it moved f everywhere else (a coat over
 * a scattering medium: median error of f 0.17% to 0.21%).
 *
 * Each channel follows its own source: a coloured lobe whose blue part
 * leaves the luminance's towards grazing (a coat over gold) keeps every
 * channel's albedo there, which one factor for all channels from the
 * luminance did not (tests/test_tables_horizon.c holds both cases). The
 * luminance table (what sampling follows) is fitted alike as one plane to
 * the source's luminance albedo (ll_tables_horizon_fit_rgb says why): sampling
 * follows the stored values, but for the horizon's cells of a coloured
 * lobe not node for node. A spectral file is fitted the same
 * way per wavelength (its plane is that wavelength's file), so it follows
 * its source per wavelength as the RGB file does per channel; the
 * luminance of the RGB file and a spectral file's plane of the same
 * source agree node for node only for a grey source. The reflected sets
 * of a transmissive file are fitted alike (ll_tables_horizon_fit_rgb
 * serves both writers), to their side's reflected albedo: the RGB of a
 * set stored over F weighed with it, its luminance, f cos itself, not
 * (bsdf_write_tables_lobes.c).
 * A table source (no order-0 series to take the albedo from) is left as
 * it is.
 */
#include "writer/bsdf_write_tables.h"
#include "reader/tables_refract.h"

#include <math.h>

#define LAMBDA_MAX 4.0
/* The edge is fitted only where it carries at least this share of the
 * albedo per unit of lambda (viewers beyond about 70 degrees on the
 * coated-gold grid): below, the cells that cross the horizon hold almost
 * nothing and a fit of them would only follow the measurement's noise
 * (at normal incidence it moved the measured albedo by 0.3% through
 * them). */
#define EDGE_SHARE 1e-3
/* Points per side of a cell crossing the horizon, where the integral
 * follows the horizon through the cell. */
#define SUB 8

/* Where the square's point sq goes at incident direction wi: 0 if its
 * reflected direction is below the horizon, else the area element of the
 * square in f cos d omega per unit of stored value, D(m) (wi.m) 2 pi^2
 * u_theta sin(theta_m) / (sigma pdf), D, sigma and the density pdf of the
 * visible normals as a reader interpolates them (ideally the same for all
 * points, the jacobian's purpose; it is not quite, by the bilinear VNDF
 * table). *fresnel receives F of the pair (1 without fresnel_eta), or
 * with the set's floor k (F + q) / (1 + q), q = k D(0) / D(m) by the set's
 * D (tables_refract.h), the further factor of a plane stored over it. */
static double weight(const ll_tables_horizon *h, const double wi[3], const double sq[2],
                     double *fresnel)
{
    double um[2], pdf, tm, m[3], wo[3], d;
    *fresnel = 1.0;
    ll_warp2d_sample(h->vndf_w, sq, h->param, um, &pdf);
    d = ll_tables_mirror(wi, um, 0.0, &tm, m, wo);
    if (!(wo[2] > 0.0) || !(pdf > 0.0))
        return 0.0;
    /* A plane stored over F (with its floor): the reader multiplies it
     * back. */
    if (h->fresnel_eta > 0.0)
        *fresnel = ll_tables_fresnel_floor_pair(wi, wo, h->fresnel_eta, h->fresnel_floor,
                                                h->ndf_w);
    return ll_warp2d_eval(h->ndf_w, um, NULL) * d * 2.0 * LL_PI * LL_PI * um[0] * sin(tm) /
           (h->sigma * pdf);
}

/* The bilinear value of plane (ns x ns) in cell (x, y) at (fx, fy). */
static double bilinear(const float *plane, size_t ns, size_t x, size_t y, double fx, double fy)
{
    const float *p = plane + y * ns + x;
    return (1.0 - fy) * ((1.0 - fx) * p[0] + fx * p[1]) + fy * ((1.0 - fx) * p[ns] + fx * p[ns + 1]);
}

/* Per plane c, the slice's albedo of the values as stored (a0[c]) and,
 * if edge is given (n_ch planes after one another), of the edge's values
 * (a1[c]). A plane is weighed with F where over_f names it: a reflected
 * set's RGB is stored over F, its luminance (what sampling follows, f
 * cos itself) is not: weighed with F, its F would count twice. */
static void sums(const ll_tables_horizon *h, size_t ns, const unsigned char *below, size_t n_ch,
                 const float *const *planes, const float *edge, double *a0, double *a1)
{
    size_t plane = ns * ns, x, y, c;
    double theta = h->param[1], wi[3] = { sin(theta), 0.0, cos(theta) };
    double cell = 1.0 / ((double)(ns - 1) * (double)(ns - 1));
    for (y = 0; y + 1 < ns; ++y)
        for (x = 0; x + 1 < ns; ++x) {
            size_t at = y * ns + x;
            int crossing = below[at] || below[at + 1] || below[at + ns] || below[at + ns + 1];
            int i, j, sub = crossing ? SUB : 1;
            for (j = 0; j < sub; ++j)
                for (i = 0; i < sub; ++i) {
                    double fx = (i + 0.5) / sub, fy = (j + 0.5) / sub, fresnel;
                    double sq[2] = { ((double)x + fx) / (double)(ns - 1),
                                     ((double)y + fy) / (double)(ns - 1) };
                    double base = weight(h, wi, sq, &fresnel);
                    if (base == 0.0)
                        continue;
                    for (c = 0; c < n_ch; ++c) {
                        double wt = cell / (sub * sub) *
                                    ((h->over_f >> c) & 1u ? base * fresnel : base);
                        a0[c] += wt * bilinear(planes[c], ns, x, y, fx, fy);
                        if (edge)
                            a1[c] += wt * bilinear(edge + c * plane, ns, x, y, fx, fy);
                    }
                }
        }
}

ll_status ll_tables_horizon_fit(const ll_tables_horizon *h, size_t ns,
                                const unsigned char *below, size_t n_ch, const double *targets,
                                float *const *planes)
{
    size_t plane = ns * ns, x, y, q, c, n_edge = 0;
    double a0[LL_TABLES_HORIZON_CHANNELS], a1[LL_TABLES_HORIZON_CHANNELS];
    double lambda[LL_TABLES_HORIZON_CHANNELS], gain[LL_TABLES_HORIZON_CHANNELS];
    float *edge;
    if (n_ch == 0 || n_ch > LL_TABLES_HORIZON_CHANNELS)
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, "ll_tables_horizon_fit: %zu channels (1..%d)",
                       n_ch, LL_TABLES_HORIZON_CHANNELS);
    for (q = 0; q < plane; ++q)
        n_edge += below[q];
    if (n_edge == 0)
        return LL_OK;
    for (c = 0; c < n_ch; ++c) {
        a0[c] = a1[c] = lambda[c] = 0.0;
        gain[c] = 1.0;
    }
    /* edge: per channel, the mean of the neighbours above the horizon at
     * each node below it that has one, 0 elsewhere. */
    if (!ll_size_mul(plane, n_ch, &q) || !(edge = ll_calloc_array(q, sizeof *edge)))
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_tables_write_from_bsdf: out of memory");
    for (y = 0; y < ns; ++y)
        for (x = 0; x < ns; ++x) {
            int n = 0, dy, dx;
            if (!below[y * ns + x])
                continue;
            for (dy = -1; dy <= 1; ++dy)
                for (dx = -1; dx <= 1; ++dx) {
                    size_t yy = y + (size_t)dy, xx = x + (size_t)dx; /* wraps below 0 */
                    if (yy >= ns || xx >= ns || below[yy * ns + xx])
                        continue;
                    ++n;
                    for (c = 0; c < n_ch; ++c)
                        edge[c * plane + y * ns + x] += planes[c][yy * ns + xx];
                }
            for (c = 0; n > 0 && c < n_ch; ++c)
                edge[c * plane + y * ns + x] /= (float)n;
        }
    /* Per channel, the slice's albedo as stored (a0) and per unit of
     * lambda (a1). */
    sums(h, ns, below, n_ch, (const float *const *)planes, edge, a0, a1);
    for (c = 0; c < n_ch; ++c) {
        double target = targets[c];
        if (!(target > 0.0))
            continue;
        if (a1[c] > EDGE_SHARE * target) {
            double l = (target - a0[c]) / a1[c];
            lambda[c] = l > 0.0 ? (l < LAMBDA_MAX ? l : LAMBDA_MAX) : 0.0;
        }
        if (a0[c] > target)
            gain[c] = target / a0[c];
    }
    for (c = 0; c < n_ch; ++c)
        for (q = 0; q < plane; ++q) {
            float *v = &planes[c][q];
            if (below[q])
                *v = (float)(lambda[c] * (double)edge[c * plane + q]);
            else
                *v = (float)(gain[c] * (double)*v);
        }
    ll_free(edge);
    return LL_OK;
}

ll_status ll_tables_horizon_fit_rgb(const ll_tables_horizon *h, size_t ns,
                                    const unsigned char *below, const double target[3],
                                    float *rgb, float *lum)
{
    /* The luminance as a plane of its own, to the source's luminance
     * albedo: the luminance of the per-channel fitted values would make
     * the cells that cross the horizon steeper where the channels'
     * factors part (a coat over gold: blue's near LAMBDA_MAX), and a
     * float32 reader's pdf there left the C reader's by 1.4e-4 (the
     * Mitsuba plugin, a viewer at 87 degrees) against 5e-5 with this fit.
     * Sampling needs f cos only roughly, and pdf stays exactly the
     * density of what is sampled. A reflected set stores its RGB over F
     * (bsdf_write_tables_lobes.c) but its luminance as f cos itself, so
     * only the RGB planes are weighed with F. */
    ll_tables_horizon fit = *h;
    double targets[4];
    float *planes[4];
    size_t plane = ns * ns;
    targets[0] = target[0];
    targets[1] = target[1];
    targets[2] = target[2];
    targets[3] = ll_tables_luminance(target);
    planes[0] = rgb;
    planes[1] = rgb + plane;
    planes[2] = rgb + 2 * plane;
    planes[3] = lum;
    fit.over_f = 7u; /* R, G and B */
    return ll_tables_horizon_fit(&fit, ns, below, 4, targets, planes);
}

double ll_tables_horizon_albedo(const ll_tables_horizon *h, size_t ns, const unsigned char *below,
                                const float *plane, int over_f)
{
    ll_tables_horizon one = *h;
    double a0 = 0.0;
    one.over_f = over_f ? 1u : 0u;
    sums(&one, ns, below, 1, &plane, NULL, &a0, NULL);
    return a0;
}

ll_status ll_tables_horizon_target(const ll_bsdf *b, double theta, int bottom, int transmitted,
                                   double out[3])
{
    double mu = cos(theta), reflected[3];
    out[0] = out[1] = out[2] = 0.0;
    if (b->measured)
        return LL_OK;
    /* mu_i = 0 counts as from above: the grazing slice from below just
     * under it. */
    if (bottom)
        mu = -(mu > 1e-4 ? mu : 1e-4);
    return transmitted ? ll_bsdf_albedo(b, mu, NULL, reflected, out)
                       : ll_bsdf_albedo(b, mu, NULL, out, NULL);
}
