/*
 * The normal distribution that parameterises a transmitted lobe's tables
 * (bsdf_write_tables.h). Retro-reflection (bsdf_write_tables_ndf.c) sees
 * nothing of a transmitted lobe; its own shape at normal incidence does:
 * with wi the normal, the visible normals' density is cos(theta_m) D(m)
 * (sigma(n) = 1), so the lobe's density over the half vector of its warp,
 * f |cos theta_o| times d omega_o / d omega_m, divided by cos(theta_m), is
 * D up to a constant. d omega_o / d omega_m is the refraction's (Walter
 * et al. 2007, tables_refract.h) for the refraction warp, 4 |wo'.m| for the
 * warp of the z-flipped direction wo' (a reflection's).
 *
 * Where normal incidence gives no direction (beyond the critical angle from
 * the denser side, beyond 45 degrees for the flipped warp) and where the
 * lobe has sunk to the numerical floor of the Fourier series (about 1e-4
 * of its peak: below it a series' ringing, not the lobe, sets the value,
 * and f / D would follow the ringing), D continues as a Beckmann lobe of
 * the peak's width, joined continuously. As for the reflected lobes, a
 * wider Beckmann lobe (wider still for the flipped warp) and a uniform
 * floor are mixed in so that the tails
 * get grid cells of their own and f / D stays bounded; D only shapes the
 * tables (the values carry f cos / D), not the BSDF.
 *
 * For the warp of the z-flipped direction across a net interface the
 * shape at normal incidence is the straight-through lobe narrowed by the
 * refraction: from above the refracted direction turns by about a third of
 * the microfacet's tilt (a half from below) and the flipped half vector by
 * half of that, so a rough glass of alpha 0.3 gives a peak of about 0.05
 * (0.07 from below). Such a set seen from the denser side of a lone
 * interface (a compensated rough dielectric: its transmitted lobe is too
 * much outside the refraction half vector's reach for the refraction
 * warp) holds beyond the critical angle little of that lobe and mostly the
 * light the compensation returns, spread evenly over the azimuths and
 * peaking at exit angles of 60 to 75 degrees, whose half vectors lie 40 to
 * 80 degrees from the normal, where the mixture above has only its floor.
 * There the floor is heavier (HEAVY_FLOOR_WEIGHT).
 *
 * Seen from the rarer side of a lone interface (the compensated rough
 * dielectric above, seen from the air) the flipped warp's lobe is the
 * refracted peak, which at normal incidence lies at the flipped half
 * vector's normal but moves off it as wi tilts: the refracted direction
 * turns by a third to two thirds of wi's turn, so the flipped half vector
 * of the peak lies half the difference from the normal (15 degrees at 70
 * degrees from above at eta 1.5), where a D of the shape at normal
 * incidence has few cells. There the measured part of D is the lobe's
 * own visible-normal density averaged over incident elevations
 * (sweep_ndf) rather than the one at normal incidence; the peak's width,
 * which sets the Beckmann lobes of the mixture, is still that at normal
 * incidence. Under a coat (not a lone interface) the medium's light does
 * not follow the refracted direction, and its D stays.
 *
 * A stack without a net interface (a pane: eta 1) has only the flipped
 * warp, and at grazing elevations its transmitted lobe spreads out of the
 * plane of incidence, so that a share of it lies at half vectors beyond
 * the wide lobe's reach; the tables then lose that share, and a finer
 * sample grid, not more elevations, was what brought it back. Its sets
 * take the heavier floor too.
 */
#include "writer/bsdf_write_tables.h"
#include "reader/tables_refract.h"
#include "reader/tables_warp.h"

#include <math.h>

/* Below this fraction of the peak a Fourier evaluation is its ringing. */
#define FOURIER_FLOOR 1e-4
#define WIDE_WEIGHT 0.2
#define WIDE_WIDTH 3.0 /* times the peak's roughness */
#define PEAK_WEIGHT 0.2
#define FLOOR_WEIGHT 0.02
/* The warp of the z-flipped direction (a pane) sees, at grazing
 * elevations, a transmitted lobe that spreads out of the plane of
 * incidence far wider than its shape at normal incidence: normals up to
 * 45 degrees and beyond. A wider and heavier lobe gives them grid cells
 * (chosen by measuring the frosted pane, docs/benchmarks.md, "D of the
 * transmitted sets": the 99th percentile of its transmitted f from 10%
 * to 2.2%). */
#define FLIPPED_WIDE_WEIGHT 0.45
#define FLIPPED_WIDE_WIDTH 5.0
/* The heavier floor of a flipped warp's D, for two kinds of set whose
 * light lies where the mixture above has little but its floor: seen from
 * the denser side of a lone interface (above), and across no net
 * interface (a pane), whose transmitted lobe at grazing elevations
 * spreads out of the plane of incidence beyond the wide lobe's reach, a
 * share that more elevations did not bring back and a finer sample grid
 * did. Other sets keep FLOOR_WEIGHT: a heavier floor for every flipped set
 * moved the compensated glass's and the coat's figures the wrong way. The
 * floors measured and their figures: docs/benchmarks.md, "D of the
 * transmitted sets". */
#define HEAVY_FLOOR_WEIGHT 0.05

/* The incident elevations (0 to SWEEP_LAST degrees, evenly) and the
 * azimuths of the normals over which sweep_ndf averages. */
#define SWEEP_ELEVATIONS 9
#define SWEEP_LAST 80.0
#define SWEEP_AZIMUTHS 64

/* The measured part of a flipped warp's D from the lobe at several
 * incident elevations: at each, the visible normals' density of a D is
 * D(m) (wi.m) / sigma(wi), and the lobe's density over the flipped half
 * vector m is f |cos theta_o| times d omega_o / d omega_m = 4 (wo'.m) =
 * 4 (wi.m) (wo' the mirror direction of wi about m, the z-flipped wo), so
 * the D whose visible normals follow the lobe is f |cos theta_o| up to a
 * constant. Averaged over the azimuths of m (D is isotropic), normalised
 * per elevation so that each counts alike, and averaged over the
 * elevations; n nodes theta, quadrature weights w. */
static void sweep_ndf(const ll_bsdf *b, int bottom, size_t n, const double *theta,
                      const double *w, double *d)
{
    double de[LL_TABLES_NDF_NODES];
    size_t e, j, k;
    for (j = 0; j < n; ++j)
        d[j] = 0.0;
    for (e = 0; e < SWEEP_ELEVATIONS; ++e) {
        double te = SWEEP_LAST * (LL_PI / 180) * (double)e / (double)(SWEEP_ELEVATIONS - 1);
        double wi[3] = { sin(te), 0.0, cos(te) }, norm = 0.0;
        for (j = 0; j < n; ++j) {
            double sum = 0.0;
            for (k = 0; k < SWEEP_AZIMUTHS; ++k) {
                double ph = 2.0 * LL_PI * ((double)k + 0.5) / SWEEP_AZIMUTHS, f[3], y, c;
                double m[3] = { sin(theta[j]) * cos(ph), sin(theta[j]) * sin(ph), cos(theta[j]) };
                double wo[3];
                c = wi[0] * m[0] + wi[1] * m[1] + wi[2] * m[2];
                wo[0] = 2.0 * c * m[0] - wi[0];
                wo[1] = 2.0 * c * m[1] - wi[1];
                wo[2] = -(2.0 * c * m[2] - wi[2]); /* z-flipped: the transmitted side */
                if (!(c > 0.0) || !(wo[2] < 0.0))
                    continue;
                ll_tables_lobe_f(b, bottom, wi, wo, f);
                y = ll_tables_luminance(f) * -wo[2];
                if (y > 0.0 && ll_is_finite(y))
                    sum += y;
            }
            de[j] = sum / SWEEP_AZIMUTHS;
            norm += 2.0 * LL_PI * w[j] * de[j] * cos(theta[j]);
        }
        if (norm > 0.0)
            for (j = 0; j < n; ++j)
                d[j] += de[j] / norm / SWEEP_ELEVATIONS;
    }
}

ll_status ll_tables_derive_transmit_ndf(const ll_bsdf *b, int bottom, double refract_eta,
                                        int heavy_floor, int sweep, double *d, double *sigma,
                                        double *alpha)
{
    enum { N = LL_TABLES_NDF_NODES };
    double theta[N], w[N], peak = 0.0, norm, join, peak_alpha = 1.0, wide, width, floor_w;
    const double wi[3] = { 0.0, 0.0, 1.0 };
    size_t j, last;
    int valid[N];
    ll_tables_ndf_quadrature(N, theta, w);
    for (j = 0; j < N; ++j) {
        double um[2] = { (double)j / (double)(N - 1), 0.5 }, m[3], wo[3], f[3], tm, dens = 0.0;
        valid[j] = 0;
        d[j] = 0.0;
        if (refract_eta > 0.0) {
            if (ll_tables_refract(wi, um, 0.0, refract_eta, &tm, m, wo) > 0.0 && wo[2] < 0.0) {
                double jac = ll_tables_refract_jacobian(wi, wo, m, refract_eta);
                ll_tables_lobe_f(b, bottom, wi, wo, f);
                if (jac > 0.0)
                    dens = ll_tables_luminance(f) * fabs(wo[2]) / jac;
                valid[j] = 1;
            }
        } else {
            double dot = ll_tables_mirror(wi, um, 0.0, &tm, m, wo);
            if (wo[2] > 0.0 && dot > 0.0) {
                double flipped[3] = { wo[0], wo[1], -wo[2] };
                ll_tables_lobe_f(b, bottom, wi, flipped, f);
                dens = ll_tables_luminance(f) * wo[2] * 4.0 * dot;
                valid[j] = 1;
            }
        }
        if (valid[j] && cos(theta[j]) > 1e-6 && dens > 0.0 && ll_is_finite(dens))
            d[j] = dens / cos(theta[j]);
        if (d[j] > peak)
            peak = d[j];
    }
    if (!(peak > 0.0))
        return ll_fail(LL_ERROR_INVALID_ARGUMENT,
                       "ll_tables_write_from_bsdf: the file transmits nothing at normal "
                       "incidence from the %s, so no normal distribution can be derived",
                       bottom ? "bottom" : "top");
    /* The measured part: from the normal up to where it leaves the
     * geometry or sinks to the floor. */
    for (last = 0; last + 1 < N && valid[last + 1] && d[last + 1] > FOURIER_FLOOR * peak; ++last)
        ;
    for (j = 1; j <= last; ++j) {
        double c = cos(theta[j]);
        if (d[j] * c * c * c * c <= d[0] * exp(-1.0)) {
            peak_alpha = tan(theta[j]);
            break;
        }
    }
    if (j > last)
        peak_alpha = last > 0 ? tan(theta[last]) : 0.05;
    if (!(peak_alpha >= 1e-3))
        peak_alpha = 1e-3;
    if (peak_alpha > 1.0)
        peak_alpha = 1.0;
    join = d[last] / ll_tables_beckmann(theta[last], peak_alpha);
    if (!ll_is_finite(join) || !(join > 0.0))
        join = 0.0;
    for (j = last + 1; j < N; ++j)
        d[j] = join * ll_tables_beckmann(theta[j], peak_alpha);
    if (sweep && refract_eta <= 0.0)
        sweep_ndf(b, bottom, N, theta, w, d);
    norm = 0.0;
    for (j = 0; j < N; ++j)
        norm += 2.0 * LL_PI * w[j] * d[j] * cos(theta[j]);
    wide = refract_eta > 0.0 ? WIDE_WEIGHT : FLIPPED_WIDE_WEIGHT;
    width = refract_eta > 0.0 ? WIDE_WIDTH : FLIPPED_WIDE_WIDTH;
    floor_w = refract_eta > 0.0 || !heavy_floor ? FLOOR_WEIGHT : HEAVY_FLOOR_WEIGHT;
    for (j = 0; j < N; ++j)
        d[j] = (1.0 - wide - PEAK_WEIGHT - floor_w) * d[j] / norm +
               wide * ll_tables_beckmann(theta[j], width * peak_alpha) +
               PEAK_WEIGHT * ll_tables_beckmann(theta[j], peak_alpha) + floor_w / LL_PI;
    *alpha = peak_alpha;
    ll_tables_projected_area(N, theta, w, d, sigma);
    return LL_OK;
}
