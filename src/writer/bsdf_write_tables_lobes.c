/*
 * The table file of a transmissive material (bsdf_write_tables.h): an
 * extended file (docs: "layerlab_layout") with a set of tables per lobe,
 * reflect_top., reflect_bottom., transmit_top. and transmit_bottom. (the
 * side of the fixed direction), and no table of the plain names, so that
 * a renderer that knows only the `measured` format refuses the file
 * instead of rendering its reflection as an opaque material.
 *
 * Each set follows the opaque writer's steps (bsdf_write_tables.c) in its
 * own frame, where the fixed direction lies above (a bottom set sees the
 * material with z negated): D and sigma (retro-reflection for a reflected
 * lobe, ll_tables_derive_ndf_side; the lobe at normal incidence for a
 * transmitted one, bsdf_write_tables_tndf.c), the VNDF slices, the sample
 * grid pushed through the reader's own warp, then reflected about the
 * normal, refracted through it (net interface: tables_refract.h), or
 * reflected and z-flipped (eta 1: tables_lobes.c says why), and f |cos|
 * 4 sigma / D stored there. The values are the .bsdf's own (importance
 * transport); the reader applies radiance's eta^2 as for the .bsdf.
 * A transmitted set's "warp_eta" names its warp: the refraction's
 * relative index where the stack has a net interface and the refraction
 * half vector reaches the lobe, else 0 for the z-flipped direction's (the
 * reader takes either per set). A reflected set seen from the denser side
 * stores its values over the Fresnel reflectance of its half vector and
 * names that index in "fresnel_eta" (the reader multiplies it back);
 * behind a coat, over that reflectance with a floor, "fresnel_floor"
 * (FRESNEL_FLOOR says why).
 * A set's "albedo" field holds its luminance albedo per incident
 * elevation (the .bsdf's order-0 integral), by which the reader's sampler
 * picks between the reflected and the transmitted lobe.
 * Every set's VNDF, luminance and values are stored as float16, as a
 * textured file's bases are (bsdf_write_tables.c): four sets are large,
 * and a renderer's look-ups walk through them. The VNDF is rounded before
 * the warp that places the sample nodes is built from it, the values and
 * luminance once a slice is complete, so that the tolerance search
 * measures the tables as stored.
 */
#include "layerlab/ll_tables.h"
#include "writer/bsdf_write_tables.h"
#include "writer/bsdf_write_tensor.h"
#include "reader/tables_warp.h"
#include "reader/tables_refract.h"
#include "support/watch.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define FN "ll_tables_write_from_bsdf"
#define LUMINANCE_FLOOR 1e-3
#define LOBES 4
#define FIELDS_PER_LOBE 10

static const char *const prefixes[LOBES] = { "reflect_top.", "reflect_bottom.", "transmit_top.",
                                             "transmit_bottom." };
static const char *const field_names[FIELDS_PER_LOBE] = { "ndf",       "sigma", "vndf",
                                                          "luminance", "rgb",   "albedo",
                                                          "warp_eta",  "fresnel_eta",
                                                          "transmittance_eta", "fresnel_floor" };

typedef struct lobe {
    int bottom, transmit;
    double refract_eta;                     /* > 0: the refraction warp      */
    double fresnel_eta;                     /* > 0: values over F (reflected) */
    double edge_width;                      /* > 0: f / F continued there     */
    double fresnel_floor;                   /* k: over (F + q) / (1 + q)      */
    double transmittance_eta;               /* > 0: values over (1 - F) J     */
    float *ndf, *sigma, *vndf, *lum, *rgb, *albedo, warp_eta[1], fresnel_f[1];
    float transmittance_f[1], floor_f[1];
    ll_warp2d ndf_w, sigma_w, vndf_w;
    double alpha;
    char names[FIELDS_PER_LOBE][40];
} lobe;

typedef struct writer {
    const ll_bsdf *b;
    size_t n_ti, nv, ns;
    float *theta_i, phi_i[1], eta[1];
    double *theta_d;
    unsigned char *valid, *next;            /* [ns * ns]: extend_slice's (valid
                                               1, to continue 0, neither 2),
                                               next also fit_slice's below    */
    int lone;                               /* ll_tables_lone_interface(b)   */
    lobe l[LOBES];
} writer;

void ll_tables_lobe_f(const ll_bsdf *b, int bottom, const double wi[3], const double wo[3],
                      double f[3])
{
    double a[3] = { wi[0], wi[1], bottom ? -wi[2] : wi[2] };
    double c[3] = { wo[0], wo[1], bottom ? -wo[2] : wo[2] };
    int k;
    if (ll_bsdf_eval_dir(b, a, c, LL_TRANSPORT_IMPORTANCE, NULL, f) != LL_OK)
        f[0] = f[1] = f[2] = 0.0;
    for (k = 0; k < 3; ++k)
        if (!(f[k] > 0.0) || !ll_is_finite(f[k]))
            f[k] = 0.0;
}

/* Whether b's stack has a net interface (eta not 1): its transmitted
 * light refracts, and one side is the denser. */
static int net_interface(const ll_bsdf *b)
{
    return fabs(b->eta - 1.0) > 1e-6;
}

static ll_status allocate(writer *w)
{
    size_t nd = LL_TABLES_NDF_NODES, v, s;
    int k;
    if (!ll_size_mul(w->nv, w->nv, &v) || !ll_size_mul(v, w->n_ti, &v) ||
        !ll_size_mul(w->ns, w->ns, &s) || !ll_size_mul(s, w->n_ti, &s))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT, FN ": the tables' size overflows");
    w->theta_i = ll_alloc_array(w->n_ti, sizeof(float));
    w->theta_d = ll_alloc_array(w->n_ti, sizeof(double));
    w->valid = ll_alloc_array(w->ns, w->ns);
    w->next = ll_alloc_array(w->ns, w->ns);
    if (!w->theta_i || !w->theta_d || !w->valid || !w->next)
        return ll_fail(LL_ERROR_OUT_OF_MEMORY, FN ": out of memory (tables)");
    for (k = 0; k < LOBES; ++k) {
        lobe *l = &w->l[k];
        l->ndf = ll_alloc_array(2 * nd, sizeof(float));
        l->sigma = ll_alloc_array(2 * nd, sizeof(float));
        l->vndf = ll_alloc_array(v, sizeof(float));
        l->lum = ll_alloc_array(s, sizeof(float));
        l->rgb = ll_alloc_array(s, 3 * sizeof(float));
        l->albedo = ll_alloc_array(w->n_ti, sizeof(float));
        if (!l->ndf || !l->sigma || !l->vndf || !l->lum || !l->rgb || !l->albedo)
            return ll_fail(LL_ERROR_OUT_OF_MEMORY, FN ": out of memory (tables)");
    }
    return LL_OK;
}

static void release(writer *w)
{
    int k;
    ll_free(w->theta_i);
    ll_free(w->theta_d);
    ll_free(w->valid);
    ll_free(w->next);
    for (k = 0; k < LOBES; ++k) {
        lobe *l = &w->l[k];
        ll_free(l->ndf);
        ll_free(l->sigma);
        ll_free(l->vndf);
        ll_free(l->lum);
        ll_free(l->rgb);
        ll_free(l->albedo);
        ll_warp2d_free(&l->ndf_w);
        ll_warp2d_free(&l->sigma_w);
        ll_warp2d_free(&l->vndf_w);
    }
}

/* A reflected set's D from retro-reflection: its own side's, except for
 * a set seen from the denser side (fresnel_eta set) of a stack that is not
 * a lone interface, which takes the other side's, and of a lone interface
 * whose D comes out more than WIDER times as wide as the other side's,
 * which takes the other side's too. Retro-reflection sees the microfacets
 * through F at normal incidence, 4% for eta 1.5 from either side. From
 * the rarer side little else comes back, but from the denser side the
 * light the microfacets scatter among themselves is trapped by total
 * internal reflection and returns as reflection (a compensated interface
 * returns all of it), so it outweighs the microfacets' own
 * retro-reflection and D comes out as wide as that light
 * (examples/frosted-glass: alpha 0.58 against 0.32 from above), while
 * beyond the critical angle the reflection is the microfacets' own sharp
 * lobe (F = 1). With the wide D the sample grid gave that lobe's normals,
 * about the pole at grazing incidence, a few columns, and the cells
 * across it lost 2.4% of the albedo at 85 degrees at 64 x 96^2 x 96^2
 * (0.005% with the D from above). Without the compensation both sides
 * give the same width (rough glass: 0.3001 from above, 0.3005 from
 * below) and the set keeps its own D: the D from above moved the
 * search's 99th percentile of f from 2.21% to 2.34%, over its aim of
 * 2.25%, by nothing but a slightly other grid. Behind a coat the
 * retro-reflection from below is mostly a medium's light, which grows
 * towards grazing angles, so the D derived from it is wide and rises off
 * the pole; at grazing viewers from below the sample grid then gave the
 * coat's own sharp reflection beyond the critical angle a column or two
 * and f came out far too low there. The D from above is the coat's lobe
 * and the medium's broad light keeps enough cells under it; mixtures of
 * the two did worse (docs/benchmarks.md, "Reflected sets' D", has the
 * figures). */
#define WIDER 1.1

/* D from one side's retro-reflection. For a stack that reflects alike
 * from both sides (w->lone) it is ll_tables_derive_ndf_pedestal's: a
 * frosted pane (eta 1.5 over 1 / 1.5, symmetric, so lone) retro-reflects
 * its first surface's microfacets on a broad pedestal of the light its
 * second surface sends back, while at grazing incidence its reflection is
 * that first surface's sharp lobe, which the mixture's lobes then follow.
 * A lone interface's fit and peak agree (rough glass 0.30 and 0.30) and
 * keep the plain mixture; so does the D from the rarer side that the
 * denser side takes below (frosted glass 0.32 and 0.30). A coat over a
 * medium is not lone, and its pedestal is the medium's own lobe at every
 * angle, which the derived D gives its cells; seen from the rarer side
 * the coat's lobe lies at the pole of the normals for a grazing viewer,
 * and that set (own: the set's own side) takes ll_tables_derive_ndf_coat's
 * heavier peak. The denser side's set, which takes the D from the rarer
 * side (reflected_ndf), keeps the plain mixture: the heavier peak there
 * did better at a large grid but worse at small ones (docs/benchmarks.md,
 * "Reflected sets' D"). */
static ll_status side_ndf(const writer *w, int side, int own, double *d, double *sigma,
                          double *alpha)
{
    double eta = w->b->eta;
    int rarer = net_interface(w->b) && side == (eta > 1.0 ? 1 : -1);
    if (w->lone)
        return ll_tables_derive_ndf_pedestal(w->b, side, d, sigma, alpha);
    return rarer && own ? ll_tables_derive_ndf_coat(w->b, side, d, sigma, alpha)
                        : ll_tables_derive_ndf_side(w->b, side, d, sigma, alpha);
}

static ll_status reflected_ndf(const writer *w, lobe *l, double *d, double *sigma)
{
    double d2[LL_TABLES_NDF_NODES], sigma2[LL_TABLES_NDF_NODES], alpha2;
    int side = l->bottom ? -1 : 1;
    ll_status s = side_ndf(w, side, 1, d, sigma, &l->alpha);
    if (s != LL_OK || !(l->fresnel_eta > 0.0))
        return s;
    if ((s = side_ndf(w, -side, 0, d2, sigma2, &alpha2)) != LL_OK)
        return s;
    if (!w->lone || l->alpha > WIDER * alpha2) {
        memcpy(d, d2, sizeof d2);
        memcpy(sigma, sigma2, sizeof sigma2);
        l->alpha = alpha2;
    }
    return LL_OK;
}

/* D and sigma of lobe l as float tables of two equal rows and their warps. */
static ll_status ndf_tables(const writer *w, lobe *l)
{
    double d[LL_TABLES_NDF_NODES], sigma[LL_TABLES_NDF_NODES], eta = w->b->eta;
    int net = net_interface(w->b);
    int heavy_floor = !net || (w->lone && l->bottom == (eta > 1.0));
    int sweep = net && w->lone && l->bottom != (eta > 1.0);
    ll_status s = l->transmit ? ll_tables_derive_transmit_ndf(w->b, l->bottom, l->refract_eta,
                                                              heavy_floor, sweep, d, sigma,
                                                              &l->alpha)
                              : reflected_ndf(w, l, d, sigma);
    if (s != LL_OK)
        return s;
    return ll_tables_ndf_warps(d, sigma, l->ndf, l->sigma, &l->ndf_w, &l->sigma_w);
}

/* The visible-normal density of slice t over the normal's square. */
static void vndf_slice(const writer *w, lobe *l, size_t t)
{
    size_t nv = w->nv;
    ll_tables_vndf_slice(&l->ndf_w, &l->sigma_w, w->theta_d[t], nv, l->vndf + t * nv * nv);
}

/* The direction the reader's sampler gives for the normal's point um:
 * 1 and wo, or 0 if none. *sampling receives the factor by which the
 * sampler's density over wo differs from p_l p_v / area (the density of
 * the two squares per steradian of normals) times the stored value's
 * D / (4 sigma wi.m) (the value's own share): 1 for a reflection (d omega_m
 * / d omega_o = 1 / (4 wi.m)), 4 wi.m d omega_m / d omega_o for a
 * refraction. The luminance table is divided by it, so that the sampler
 * follows f |cos| for refraction as it does for reflection. */
static int direction(const lobe *l, const double wi[3], const double um[2], double wo[3],
                     double *sampling)
{
    double tm, m[3], d;
    *sampling = 1.0;
    if (l->transmit && l->refract_eta > 0.0) {
        d = ll_tables_refract(wi, um, 0.0, l->refract_eta, &tm, m, wo);
        if (!(d > 0.0) || !(wo[2] < 0.0))
            return 0;
        *sampling = 4.0 * d * ll_tables_refract_jacobian(wi, wo, m, l->refract_eta);
        return *sampling > 0.0 && ll_is_finite(*sampling);
    }
    d = ll_tables_mirror(wi, um, 0.0, &tm, m, wo);
    if (!(d > 0.0) || !(wo[2] > 0.0))
        return 0;
    if (l->transmit)
        wo[2] = -wo[2];
    return 1;
}

/* A set stored over its refraction's transmittance has no value where
 * the node's normal refracts nothing (beyond the edge of total internal
 * reflection, or a refracted direction above the surface), nor where
 * that factor is below TRANSMITTANCE_FLOOR: at the edge the factor falls
 * to 0 like |wo.m|^2 and f with it, but the .bsdf's series does not follow
 * f so far down, and the quotient of the two came out thousands of times
 * the lobe's values (rough glass at 32 x 48^2 x 48^2, seen from below at
 * 42.5 degrees: a node with a factor of 1.2e-6 and f 1.2e-4 stored 6124,
 * its continuation beyond the edge up to 12,249, where every other value
 * of the file is at most 5: renders 1.7% bright, with fireflies). Nodes
 * with a factor of 6e-4 and more hold values of the lobe's order. There the
 * smooth quotient is continued ring after ring outwards until every node
 * has one: a node next to valid ones takes the mean of their linear
 * extrapolations (2 v1 - v2 along each line of two valid nodes, at least
 * 0) or, where no line has two, of their values. A cell across the edge
 * then interpolates the continued quotient instead of falling to 0 inside
 * it, and so does the interpolation between two slices, whose edges lie
 * at different nodes. */
#define LINE_RINGS 1
#define TRANSMITTANCE_FLOOR 1e-4
static int valid_at(const writer *w, size_t x, size_t y, int dx, int dy, int k, size_t *j)
{
    ptrdiff_t px = (ptrdiff_t)x + k * dx, py = (ptrdiff_t)y + k * dy, ns = (ptrdiff_t)w->ns;
    if (px < 0 || py < 0 || px >= ns || py >= ns)
        return 0;
    *j = (size_t)(py * ns + px);
    return w->valid[*j] == 1;
}

static void extend_slice(const writer *w, float *rgb)
{
    size_t ns = w->ns, plane = ns * ns, x, y, c;
    int dx, dy, grew = 1, ring = 0;
    for (; grew; ++ring) {
        grew = 0;
        memcpy(w->next, w->valid, plane);
        for (y = 0; y < ns; ++y)
            for (x = 0; x < ns; ++x) {
                double line[3] = { 0.0, 0.0, 0.0 }, near[3] = { 0.0, 0.0, 0.0 };
                size_t i = y * ns + x, n_line = 0, n_near = 0, j1, j2;
                if (w->valid[i])
                    continue;
                for (dy = -1; dy <= 1; ++dy)
                    for (dx = -1; dx <= 1; ++dx) {
                        if ((!dx && !dy) || !valid_at(w, x, y, dx, dy, 1, &j1))
                            continue;
                        for (c = 0; c < 3; ++c)
                            near[c] += (double)rgb[c * plane + j1];
                        ++n_near;
                        if (ring >= LINE_RINGS || !valid_at(w, x, y, dx, dy, 2, &j2))
                            continue;
                        for (c = 0; c < 3; ++c) {
                            double v = 2.0 * (double)rgb[c * plane + j1] -
                                       (double)rgb[c * plane + j2];
                            line[c] += v > 0.0 ? v : 0.0;
                        }
                        ++n_line;
                    }
                if (!n_near)
                    continue;
                for (c = 0; c < 3; ++c)
                    rgb[c * plane + i] = (float)(n_line ? line[c] / (double)n_line
                                                        : near[c] / (double)n_near);
                w->next[i] = 1;
                grew = 1;
            }
        memcpy(w->valid, w->next, plane);
    }
}

/* A reflected set's nodes beyond the horizon (bsdf_write_tables_horizon.c),
 * fitted per channel to the side's reflected albedo at the slice's
 * elevation as the opaque writer's are: without them the cells that cross
 * the horizon pull a grazing viewer's lobe down (rough glass seen from
 * above at 85 degrees, 32 x 64^2: 0.79% low). A transmitted set of the
 * z-flipped direction's warp is fitted alike to the side's transmitted
 * albedo: its square maps onto directions as a reflected set's does, with
 * z negated, so its nodes beyond the horizon (wo above the surface) and
 * the area element are the reflection's, and light that leaves a medium
 * into the denser side without an interface there (a coat over a medium
 * without a base) is bright up to the grazing exit, where the cells that
 * cross the horizon held its transmission low (docs/benchmarks.md, "Table
 * files: the writer's choices, measured"). A refracted set's horizon lies
 * elsewhere in its square and is not fitted. The luminance is fitted as
 * a plane of its own to the side's luminance albedo, by the opaque
 * writer's code (ll_tables_horizon_fit_rgb says why). The RGB of a set
 * stored over F is weighed with F there; its luminance, f cos itself, is
 * not: formed from the fitted values times F, as it was, its albedo as
 * stored was up to 3.6% short of the source's luminance albedo (a coat
 * over a coloured medium seen from below, tests/test_tables_horizon.c),
 * as the luminance interpolated between nodes is not the interpolated
 * values times F. */
static ll_status fit_slice(const writer *w, lobe *l, size_t t, double th)
{
    size_t plane = w->ns * w->ns;
    double target[3];
    ll_tables_horizon h;
    ll_status s;
    if ((s = ll_tables_horizon_target(w->b, th, l->bottom, l->transmit, target)) != LL_OK)
        return s;
    if (!(target[0] > 0.0 || target[1] > 0.0 || target[2] > 0.0))
        return LL_OK;
    h.ndf_w = &l->ndf_w;
    h.vndf_w = &l->vndf_w;
    h.sigma = ll_tables_sigma_at(&l->sigma_w, th);
    h.param[0] = 0.0;
    h.param[1] = th;
    h.fresnel_eta = l->fresnel_eta;
    h.fresnel_floor = l->fresnel_floor;
    h.over_f = 0u; /* set by the fit of RGB and luminance */
    return ll_tables_horizon_fit_rgb(&h, w->ns, w->next, target, l->rgb + t * 3 * plane,
                                     l->lum + t * plane);
}

/* Whether transmitted set l is fitted at the horizon (fit_slice): one of
 * the z-flipped direction's warp across a net interface that is not a
 * lone one (a coat over a medium without a base). A lone interface's or a
 * pane's transmitted light leaves through an interface, whose
 * transmittance falls to 0 at the grazing exit, so their horizon cells
 * hold little; fitted, the compensated glass's albedo figure and the
 * pane's sampled T came out further from their .bsdf's. */
static int fits_transmitted(const writer *w, const lobe *l)
{
    return l->transmit && l->refract_eta == 0.0 && net_interface(w->b) && !w->lone;
}

/* The values and luminance of slice t at the sample grid's nodes. */
static ll_status value_slice(const writer *w, lobe *l, size_t t)
{
    size_t ns = w->ns, x, y, c, plane = ns * ns;
    double th = w->theta_d[t], wi[3] = { sin(th), 0.0, cos(th) };
    double param[2] = { 0.0, th }, top = 0.0, floor_v;
    size_t n_edge = 0;
    double four_sigma = 4.0 * ll_tables_sigma_at(&l->sigma_w, th);
    float *lum = l->lum + t * plane, *rgb = l->rgb + t * 3 * plane;
    for (y = 0; y < ns; ++y) {
        for (x = 0; x < ns; ++x) {
            double sq[2] = { (double)x / (double)(ns - 1), (double)y / (double)(ns - 1) };
            double um[2], pdf, wo[3], f[3] = { 0.0, 0.0, 0.0 }, scale = 0.0, y_lum;
            double sampling = 1.0, over = 1.0;
            int reached;
            w->valid[y * ns + x] = 0;
            ll_warp2d_sample(&l->vndf_w, sq, param, um, &pdf);
            reached = wi[2] > 0.0 && direction(l, wi, um, wo, &sampling);
            w->next[y * ns + x] = !reached;
            if (l->edge_width > 0.0)
                w->valid[y * ns + x] = reached ? 1 : 2;
            if (reached) {
                ll_tables_lobe_f(w->b, l->bottom, wi, wo, f);
                scale = fabs(wo[2]) * four_sigma / ll_warp2d_eval(&l->ndf_w, um, NULL);
                if (!ll_is_finite(scale))
                    scale = 0.0;
                if (l->fresnel_eta > 0.0)
                    over = 1.0 / ll_tables_fresnel_floor_pair(wi, wo, l->fresnel_eta,
                                                              l->fresnel_floor, &l->ndf_w);
                if (l->edge_width > 0.0 &&
                    ll_tables_edge_near(wi, wo, l->fresnel_eta, l->edge_width)) {
                    w->valid[y * ns + x] = 0;
                    ++n_edge;
                }
                if (l->transmittance_eta > 0.0) {
                    double tr = ll_tables_transmittance_pair(wi, wo, l->transmittance_eta);
                    over = tr > 0.0 ? 1.0 / tr : 0.0;
                    w->valid[y * ns + x] = tr >= TRANSMITTANCE_FLOOR && ll_is_finite(over);
                    /* (A node left invalid holds 0 until extend_slice
                     * continues the quotient there.) */
                    if (!w->valid[y * ns + x])
                        over = 0.0;
                }
            }
            for (c = 0; c < 3; ++c) {
                double v = f[c] * scale;
                f[c] = v > 0.0 ? v : 0.0;
                rgb[c * plane + y * ns + x] = (float)(f[c] * over);
            }
            y_lum = ll_tables_luminance(f) / sampling;
            lum[y * ns + x] = (float)y_lum;
            if (y_lum > top)
                top = y_lum;
        }
    }
    if (l->transmittance_eta > 0.0)
        extend_slice(w, rgb);
    /* f / F continued across the edge of total internal reflection
     * (bsdf_write_tables_edge.c); fit_slice's mask is again the nodes
     * beyond the horizon. */
    if (n_edge) {
        extend_slice(w, rgb);
        for (x = 0; x < plane; ++x)
            w->next[x] = w->valid[x] == 2;
    }
    if (!l->transmit || fits_transmitted(w, l)) {
        ll_status s = fit_slice(w, l, t, th);
        if (s != LL_OK)
            return s;
        for (x = 0, top = 0.0; x < plane; ++x)
            if ((double)lum[x] > top)
                top = (double)lum[x];
    }
    floor_v = top > 0.0 ? LUMINANCE_FLOOR * top : 1.0;
    if (floor_v < LL_TABLES_HALF_TINY)
        floor_v = LL_TABLES_HALF_TINY;
    for (x = 0; x < plane; ++x)
        if (!((double)lum[x] >= floor_v))
            lum[x] = (float)floor_v;
    {
        ll_status s = ll_tables_round_half(rgb, 3 * plane, l->names[4]);
        return s != LL_OK ? s : ll_tables_round_half(lum, plane, l->names[3]);
    }
}

/* A set stored over F holds f / F, smooth across the edge of total
 * internal reflection only where f is proportional to F. Seen from the
 * denser side f = S F + C: S the microfacets' own single reflection, C
 * light that does not follow F, and C / F keeps a kink of F's shape at
 * the edge, relatively large where C outweighs S F. Stored over
 * (F + q) / (1 + q) instead (1 beyond the edge for every q, F for q = 0),
 * the kink's share of a value goes as |q - C / S| / ((F + q) (F + C / S)):
 * q = 0 suits a lobe that is S, a larger q one that is mostly C. Behind a
 * coat C is a medium's back-scattered light, broad, while S follows the
 * microfacets' D, so the worst errors lay in the lobe's flanks just beyond
 * the edge, where C outweighs S most: q = k D(0) / D(m), D the set's own
 * (the D from above, reflected_ndf, which is the coat's lobe), m the half
 * vector (tables_refract.h). k = 1 did best over the coats measured, with
 * constant floors and other powers of D's ratio (docs/benchmarks.md,
 * "The Fresnel floor", has the sweep): a smaller k
 * did better on some coats and far worse on a rough one over a thick
 * medium. A lone interface
 * gains nothing: there C is at most the compensation's share, a few
 * percent of S at the edge, and a floor made the figures worse. So the
 * floor is FRESNEL_FLOOR where the stack is not a lone interface, else 0
 * (and the file has no "fresnel_floor"). */
#define FRESNEL_FLOOR 1.0

/* The luminance albedo of each lobe at each incident elevation, from the
 * .bsdf's order-0 integral (the file's incident cosine is the fixed
 * direction's z, negative from the bottom). */
static void albedos(writer *w)
{
    size_t t;
    int bottom;
    for (bottom = 0; bottom < 2; ++bottom)
        for (t = 0; t < w->n_ti; ++t) {
            double mu = cos(w->theta_d[t]), r[3] = { 0.0, 0.0, 0.0 }, tr[3] = { 0.0, 0.0, 0.0 };
            double a, b;
            if (mu < 1e-4)
                mu = 1e-4;
            if (ll_bsdf_albedo(w->b, bottom ? -mu : mu, NULL, r, tr) != LL_OK)
                r[0] = r[1] = r[2] = tr[0] = tr[1] = tr[2] = 0.0;
            a = ll_tables_luminance(r);
            b = ll_tables_luminance(tr);
            w->l[bottom ? 1 : 0].albedo[t] = (float)(a > 0.0 ? a : 0.0);
            w->l[bottom ? 3 : 2].albedo[t] = (float)(b > 0.0 ? b : 0.0);
        }
}

/* The opaque writer's incident elevations (bsdf_write_tables.c),
 * theta = 90 sin(90 v) degrees for v uniform, where the stack has no net
 * interface. Across one, light from the denser side leaves at
 * asin(eta sin theta), whose slope grows without bound at the critical
 * angle: near it one step of theta sweeps the transmitted lobe towards
 * the horizon; beyond it the edge of total internal reflection moves
 * through the lobe's normals as fast as theta. The tables, interpolated
 * between elevations at the same normal, smear both. There the nodes are
 * the inverse of a mixture of the opaque grid's distribution (share 0.75),
 * one uniform in that exit angle (0.15), which packs them towards the
 * critical angle from below, and one uniform over the 30 degrees beyond it
 * (0.1). The shares were chosen by measuring rough glass (eta 1.5, alpha
 * 0.3; docs/benchmarks.md, "Incident elevations of transmissive
 * files"): larger ones left the reflection from below,
 * whose sampling needs the opaque grid's elevations, further off. */
#define EXIT_SHARE 0.15
#define BEYOND_SHARE 0.1
#define BEYOND_SPAN 30.0 /* degrees */

static double elevation_cdf(double th, double dense)
{
    double base = asin(th / (LL_PI / 2)) / (LL_PI / 2), s = dense * sin(th), ex, be;
    double tc = dense > 1.0 ? asin(1.0 / dense) : LL_PI / 2, span = BEYOND_SPAN * LL_PI / 180;
    if (dense <= 1.0)
        return base;
    ex = s >= 1.0 ? 1.0 : asin(s) / (LL_PI / 2);
    if (tc + span > LL_PI / 2)
        span = LL_PI / 2 - tc;
    be = th <= tc ? 0.0 : (th >= tc + span ? 1.0 : (th - tc) / span);
    return (1.0 - EXIT_SHARE - BEYOND_SHARE) * base + EXIT_SHARE * ex + BEYOND_SHARE * be;
}

static void elevations(writer *w)
{
    double eta = w->b->eta, dense = eta > 1.0 ? eta : 1.0 / eta;
    size_t t;
    int it;
    if (!net_interface(w->b))
        dense = 1.0;
    for (t = 0; t < w->n_ti; ++t) {
        double v = (double)t / (double)(w->n_ti - 1), lo = 0.0, hi = LL_PI / 2;
        for (it = 0; it < 60; ++it) {
            double mid = 0.5 * (lo + hi);
            if (elevation_cdf(mid, dense) < v)
                lo = mid;
            else
                hi = mid;
        }
        w->theta_i[t] = (float)(t == 0 ? 0.0 : (t + 1 == w->n_ti ? LL_PI / 2 : 0.5 * (lo + hi)));
        /* Strictly ascending as floats, however many nodes crowd the
         * critical angle. */
        if (t > 0 && !(w->theta_i[t] > w->theta_i[t - 1]))
            w->theta_i[t] = nextafterf(w->theta_i[t - 1], 2.0f);
        w->theta_d[t] = (double)w->theta_i[t];
    }
}

/* Whether the refraction half vector of relative index eta reaches the
 * transmitted lobe of a side: the share of f |cos| (over the transmitted
 * hemisphere, at incident elevations 0..80 degrees) at pairs that have a
 * refraction half vector is at least REACHED. A rough interface's lobe
 * lies there entirely (its microfacets refract through that very half
 * vector: rough glass, at most 0.03% unreached); light scattered by a
 * medium under a coat leaves in directions it cannot give (the coat over
 * a medium without a base of docs/formats.md, "Transmission": 4% to 96%
 * unreached), which
 * the warp of the z-flipped direction, defined for every pair, covers. */
#define REACHED 0.995
#define REACH_ELEVATIONS 5
#define REACH_NODES 48

static int refraction_reaches(const ll_bsdf *b, int bottom, double eta)
{
    static const double deg[REACH_ELEVATIONS] = { 0.0, 20.0, 40.0, 60.0, 80.0 };
    size_t e, i, j;
    for (e = 0; e < REACH_ELEVATIONS; ++e) {
        double th = deg[e] * (LL_PI / 180), wi[3] = { sin(th), 0.0, cos(th) };
        double all = 0.0, reached = 0.0;
        for (i = 0; i < REACH_NODES; ++i) {
            double to = ((double)i + 0.5) / REACH_NODES * (LL_PI / 2);
            for (j = 0; j < REACH_NODES; ++j) {
                double po = ((double)j + 0.5) / REACH_NODES * LL_PI, m[3], f[3], y;
                double wo[3] = { sin(to) * cos(po), sin(to) * sin(po), -cos(to) };
                ll_tables_lobe_f(b, bottom, wi, wo, f);
                y = ll_tables_luminance(f) * cos(to) * sin(to);
                all += y;
                if (ll_tables_refract_half(wi, wo, eta, m))
                    reached += y;
            }
        }
        if (all > 0.0 && reached < REACHED * all)
            return 0;
    }
    return 1;
}

static char *metadata_text(const writer *w, const char *figures, size_t *size)
{
    size_t cap = 640, at;
    char *buf;
    const char *src = w->b->metadata ? w->b->metadata : "";
    if (!figures)
        figures = "";
    if (!ll_size_add(cap, w->b->metadata_size, &cap) || !ll_size_mul(cap, 6, &cap) ||
        !ll_size_add(cap, strlen(figures), &cap))
        return NULL;
    if (!(buf = ll_malloc(cap)))
        return NULL;
    at = (size_t)snprintf(buf, cap,
                          "{\"writer\": \"layerlab %s\", \"layout\": \"transmissive\", "
                          "\"theta_i\": %zu, \"vndf\": [%zu, %zu], \"sample\": [%zu, %zu], "
                          "\"ndf_alpha\": [%.6g, %.6g, %.6g, %.6g], \"eta\": %.9g, "
                          "\"wavelengths\": 0, %s\"bsdf_metadata\": ",
                          ll_version_string(), w->n_ti, w->nv, w->nv, w->ns, w->ns,
                          w->l[0].alpha, w->l[1].alpha, w->l[2].alpha, w->l[3].alpha, w->b->eta,
                          figures);
    at = ll_tables_json_string(buf, at, cap, src);
    buf[at++] = '}';
    buf[at] = '\0';
    *size = at;
    return buf;
}

static ll_status build_lobe(writer *w, lobe *l, ll_watch *watch)
{
    const double phi[1] = { 0.0 }, *params[2];
    size_t sizes[2], t;
    ll_status s;
    if ((s = ndf_tables(w, l)) != LL_OK)
        return s;
    for (t = 0; t < w->n_ti; ++t)
        vndf_slice(w, l, t);
    /* (allocate() checked the product.) */
    if ((s = ll_tables_round_half(l->vndf, w->n_ti * w->nv * w->nv, l->names[2])) != LL_OK)
        return s;
    params[0] = phi;
    params[1] = w->theta_d;
    sizes[0] = 1;
    sizes[1] = w->n_ti;
    if ((s = ll_warp2d_init(&l->vndf_w, w->nv, w->nv, 2, sizes, params, ll_tables_get_float,
                            l->vndf, 1)) != LL_OK)
        return s;
    for (t = 0; t < w->n_ti; ++t) {
        if ((s = value_slice(w, l, t)) != LL_OK)
            return s;
        ll_watch_advance(watch, 1);
        if ((s = ll_watch_check(watch, FN)) != LL_OK)
            return s;
    }
    return LL_OK;
}

ll_status ll_tables_write_lobes(const ll_bsdf *b, const char *path, const ll_tables_options *o,
                                const char *figures, const ll_monitor *monitor)
{
    static const unsigned char jacobian[1] = { 1 };
    static const char layout[] = "reflect_top reflect_bottom transmit_top transmit_bottom";
    writer w;
    ll_watch watch;
    char *meta = NULL;
    size_t meta_size = 0, nd = LL_TABLES_NDF_NODES, nf = 0;
    ll_tensor_out_field f[7 + LOBES * FIELDS_PER_LOBE];
    const char *desc;
    int k;
    ll_status s;
    if (o->format != LL_TABLES_RGB)
        return ll_fail(LL_ERROR_UNSUPPORTED,
                       FN ": spectral tables of a transmissive file are not written by this "
                       "version (LL_TABLES_RGB writes them)");
    if ((s = ll_watch_begin(&watch, monitor, FN)) != LL_OK)
        return s;
    memset(&w, 0, sizeof w);
    w.b = b;
    w.n_ti = o->n_theta_i;
    w.nv = o->vndf_size;
    w.ns = o->sample_size;
    w.eta[0] = (float)b->eta;
    if ((s = allocate(&w)) != LL_OK)
        goto done;
    elevations(&w);
    w.lone = ll_tables_lone_interface(b);
    for (k = 0; k < LOBES; ++k) {
        lobe *l = &w.l[k];
        int j;
        for (j = 0; j < FIELDS_PER_LOBE; ++j)
            snprintf(l->names[j], sizeof l->names[j], "%s%s", prefixes[k], field_names[j]);
        l->bottom = k == 1 || k == 3;
        l->transmit = k >= 2;
        if (l->transmit && net_interface(b) &&
            refraction_reaches(b, l->bottom, l->bottom ? 1.0 / b->eta : b->eta))
            l->refract_eta = l->bottom ? 1.0 / b->eta : b->eta;
        l->warp_eta[0] = (float)l->refract_eta;
        /* Reflection seen from the denser side has the edge of total
         * internal reflection, where F, and with it f, rises to 1 with an
         * infinite slope: stored over F(wi.h) the values are smooth
         * across it, and the reader multiplies F back exactly. */
        if (!l->transmit && net_interface(b) && (l->bottom ? b->eta > 1.0 : b->eta < 1.0))
            l->fresnel_eta = l->bottom ? 1.0 / b->eta : b->eta;
        l->fresnel_f[0] = (float)l->fresnel_eta;
        l->edge_width = l->transmit ? 0.0 : ll_tables_edge_width(b, w.lone, l->bottom);
        if (l->fresnel_eta > 0.0 && !w.lone)
            l->fresnel_floor = FRESNEL_FLOOR;
        l->floor_f[0] = (float)l->fresnel_floor;
        l->fresnel_floor = (double)l->floor_f[0]; /* as a reader takes it */
        /* A refracted set: f |cos| / D vanishes at the edge of total
         * internal reflection (seen from the denser side) like |wo.m|^2,
         * as the Fresnel transmittance and the change of variables to
         * the refracted direction each do, and a thin strip of normals
         * there spreads over a wide range of directions: stored over
         * both, the values are smooth to the edge and the reader
         * multiplies them back exactly (tables_refract.h). */
        l->transmittance_eta = l->refract_eta;
        l->transmittance_f[0] = (float)l->transmittance_eta;
    }
    albedos(&w);
    ll_watch_stage(&watch, "tables", 0.0, 0.9, LOBES * w.n_ti);
    for (k = 0; k < LOBES; ++k)
        if ((s = build_lobe(&w, &w.l[k], &watch)) != LL_OK)
            goto done;
    if (!(meta = metadata_text(&w, figures, &meta_size))) {
        s = ll_fail(LL_ERROR_OUT_OF_MEMORY, FN ": out of memory (metadata)");
        goto done;
    }
    ll_watch_stage(&watch, "writing", 0.9, 0.1, 1);
    desc = o->description ? o->description
                          : "layerlab: warped tables of a transmissive layered material (RGB; "
                            "an extension of the measured format: see layerlab_layout)";
    {
        ll_tensor_out_field shared[7] = {
            { "description", LL_TENSOR_U8, 1, { strlen(desc) }, desc, NULL, NULL },
            { "jacobian", LL_TENSOR_U8, 1, { 1 }, jacobian, NULL, NULL },
            { "theta_i", LL_TENSOR_F32, 1, { w.n_ti }, w.theta_i, NULL, NULL },
            { "phi_i", LL_TENSOR_F32, 1, { 1 }, w.phi_i, NULL, NULL },
            { "eta", LL_TENSOR_F32, 1, { 1 }, w.eta, NULL, NULL },
            { "layerlab_layout", LL_TENSOR_U8, 1, { sizeof layout - 1 }, layout, NULL, NULL },
            { "layerlab_metadata", LL_TENSOR_U8, 1, { meta_size }, meta, NULL, NULL },
        };
        for (nf = 0; nf < 7; ++nf)
            f[nf] = shared[nf];
    }
    for (k = 0; k < LOBES; ++k) {
        lobe *l = &w.l[k];
        int j;
        {
            ll_tensor_out_field set[FIELDS_PER_LOBE] = {
                { l->names[0], LL_TENSOR_F32, 2, { 2, nd }, l->ndf, NULL, NULL },
                { l->names[1], LL_TENSOR_F32, 2, { 2, nd }, l->sigma, NULL, NULL },
                { l->names[2], LL_TENSOR_F16, 4, { 1, w.n_ti, w.nv, w.nv }, l->vndf, NULL,
                  NULL },
                { l->names[3], LL_TENSOR_F16, 4, { 1, w.n_ti, w.ns, w.ns }, l->lum, NULL,
                  NULL },
                { l->names[4], LL_TENSOR_F16, 5, { 1, w.n_ti, 3, w.ns, w.ns }, l->rgb, NULL,
                  NULL },
                { l->names[5], LL_TENSOR_F32, 1, { w.n_ti }, l->albedo, NULL, NULL },
                { l->names[6], LL_TENSOR_F32, 1, { 1 }, l->warp_eta, NULL, NULL },
                { l->names[7], LL_TENSOR_F32, 1, { 1 }, l->fresnel_f, NULL, NULL },
                { l->names[8], LL_TENSOR_F32, 1, { 1 }, l->transmittance_f, NULL, NULL },
                { l->names[9], LL_TENSOR_F32, 1, { 1 }, l->floor_f, NULL, NULL },
            };
            /* warp_eta: transmitted sets only; fresnel_eta: reflected sets
             * stored over F only; transmittance_eta: refracted sets stored
             * over (1 - F) J only. */
            for (j = 0; j < FIELDS_PER_LOBE - 4; ++j)
                f[nf++] = set[j];
            if (l->transmit)
                f[nf++] = set[6];
            if (l->fresnel_eta > 0.0)
                f[nf++] = set[7];
            if (l->transmittance_eta > 0.0)
                f[nf++] = set[8];
            if (l->fresnel_eta > 0.0 && l->fresnel_floor > 0.0)
                f[nf++] = set[9];
        }
    }
    if ((s = ll_watch_finish(&watch, LL_OK, FN)) != LL_OK)
        goto done;
    s = ll_tensor_write(path, FN, f, nf);
done:
    ll_free(meta);
    release(&w);
    return s;
}
