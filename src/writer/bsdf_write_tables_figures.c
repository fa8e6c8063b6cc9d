/*
 * ll_tables_measure (bsdf_write_tables.h): the figures a table's tolerance
 * is stated in (ll_tables.h), measured on the opened table against the
 * file it was written from, through the public calls a renderer uses.
 *
 * Albedo: R and T (the integrals of f |cos| over the viewer's hemisphere
 * and the other), per channel, at viewer elevations 0..85 degrees (a
 * transmissive source: above and below), both files by the same quadrature
 * of eval (ll_tables_albedo, whose own error is about 1e-4 of a lobe); the
 * source's once per search (ll_tables_reference). A lobe is held to the
 * relative aim where it carries at least 1% of the viewer's R + T (per
 * channel): rough glass's transmission from below beyond 65 degrees
 * (1.5e-4 of the light at 70 degrees) is 10% off at the largest grid, which
 * moves 0.002% of the light. Not each file's own sampler weights: with
 * 256^2 strata, a lobe that gets a few percent of them comes out 2-3% off,
 * for the .bsdf and the table alike, more than the aim it would check.
 *
 * f: PAIRS direction pairs from a fixed
 * seed, both elevations <= 80 degrees, the viewer uniform in cos theta and
 * the light half uniform in cos theta, half within 0.4 radians of the
 * mirror direction (where f changes fastest and renders look); relative
 * errors where f cos is above 1% of its largest value over the pairs,
 * per channel, pooled.
 *
 * A transmissive source (its tables a set per lobe and side): the pairs a
 * quarter per lobe and side, the light near the lobe's peak (the mirror,
 * the refracted, or the straight-through direction) for half of them, and
 * 1% of the largest f cos taken per lobe and side. The reflected pairs of
 * a lone interface's denser side within ll_tables_edge_width of the edge
 * of total internal reflection are not counted: there the source's f is
 * off its own model by more than the aims, the tables hold the model
 * instead (bsdf_write_tables_edge.c), and no grid follows the source's
 * error, so counting them would only grow the grid to the size cap.
 * tests/test_tables_transmit_tolerance.c still counts every pair.
 */
#include "writer/bsdf_write_tables.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define FLOOR 0.01 /* of R + T: the smallest lobe held to the albedo aim */
#define PAIRS 20000
#define ANGLES LL_TABLES_ANGLES
#define LIMIT_DEG 80.0

const double ll_tables_angles_deg[LL_TABLES_ANGLES] = { 0, 10, 20, 30, 40, 50, 60, 70, 80, 85 };

static double uniform(uint64_t *s)
{
    *s = *s * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*s >> 11) * (1.0 / 9007199254740992.0);
}

static void direction(double theta, double phi, double w[3])
{
    w[0] = sin(theta) * cos(phi);
    w[1] = sin(theta) * sin(phi);
    w[2] = cos(theta);
}

/* The viewer at elevation theta (below the surface if bottom). */
static void viewer(double theta, int bottom, double wo[3])
{
    direction(theta, 0.0, wo);
    if (bottom)
        wo[2] = -wo[2];
}

/* out[0..2] the reflected albedo per channel, out[3..5] the transmitted
 * (a viewer below if bottom); an opaque source's out[3..5] stay 0. The
 * quadrature is finest about the mirror direction and the refracted one
 * (src's eta; beyond the critical angle the grazing one, where the
 * transmitted lobe then lies). */
static ll_status albedo(const ll_bsdf *b, const ll_bsdf *src, double theta, int bottom,
                        double out[6])
{
    double wo[3], peak[2], st = sin(theta) * (bottom ? src->eta : 1.0 / src->eta);
    int c;
    for (c = 0; c < 6; ++c)
        out[c] = 0.0;
    viewer(theta, bottom, wo);
    peak[0] = theta;
    peak[1] = st < 1.0 ? asin(st) : LL_PI / 2.0;
    return ll_tables_albedo(b, wo, peak, ll_tables_transmits(src), out, out + 3);
}

ll_status ll_tables_albedos(const ll_bsdf *b, const ll_bsdf *src, ll_tables_source *out)
{
    int k, bottom, sides = ll_tables_transmits(src) ? 2 : 1;
    ll_status s;
    memset(out, 0, sizeof *out);
    for (bottom = 0; bottom < sides; ++bottom)
        for (k = 0; k < ANGLES; ++k)
            if ((s = albedo(b, src, ll_tables_angles_deg[k] * LL_PI / 180.0, bottom,
                            out->albedo[bottom][k])) != LL_OK)
                return s;
    return LL_OK;
}

ll_status ll_tables_reference(const ll_bsdf *src, ll_tables_source *ref)
{
    return ll_tables_albedos(src, src, ref);
}

static int compare(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* The light direction of pair k for the viewer wo (elevation tv): an
 * opaque source's (transmissive 0) as always; a transmissive source's
 * lobe (k / 4) % 2, its side k % 4 / 2 (wo already there). */
static void light_of(size_t k, const double wo[3], double tv, int transmissive, double eta,
                     uint64_t *rng, double wi[3])
{
    const double lim = LIMIT_DEG * LL_PI / 180.0;
    int transmit = transmissive && (k / 4) % 2, bottom = wo[2] < 0.0;
    double e = bottom ? 1.0 / eta : eta, st = sin(tv) / e, peak_t = 0.0;
    int peak = k % 2 == 1 && (!transmit || st < 1.0);
    if (transmit && st < 1.0)
        peak_t = asin(st);
    do {
        if (!peak) {
            double tl = acos(1.0 - uniform(rng) * (1.0 - cos(lim)));
            direction(tl, 2.0 * LL_PI * uniform(rng), wi);
        } else {
            /* Near the mirror or transmitted peak: the same azimuth
             * (phi pi), elevation tv or its refraction. */
            double c = transmit ? peak_t : tv;
            double dt = 0.4 * (2.0 * uniform(rng) - 1.0);
            double dp = 0.4 * (2.0 * uniform(rng) - 1.0) / (sin(c) + 0.2);
            direction(fabs(c + dt), LL_PI + dp, wi);
        }
    } while (acos(wi[2]) > lim);
    if (bottom != transmit)
        wi[2] = -wi[2];
}

/* Whether the reflected pair (wo, wi), both on one side, lies within
 * width of the edge of total internal reflection seen from that side. */
static int near_edge(const double wo[3], const double wi[3], double eta, double width)
{
    double a[3] = { wo[0], wo[1], fabs(wo[2]) }, b[3] = { wi[0], wi[1], fabs(wi[2]) };
    return ll_tables_edge_near(a, b, wo[2] < 0.0 ? 1.0 / eta : eta, width);
}

static ll_status f_errors(const ll_bsdf *src, const ll_bsdf *table, ll_tables_figures *out)
{
    const double lim = LIMIT_DEG * LL_PI / 180.0;
    double *ref = ll_alloc_array(PAIRS, 4 * sizeof(double));
    double *got = ll_alloc_array(PAIRS, 3 * sizeof(double));
    double *err = ll_alloc_array(PAIRS, 3 * sizeof(double)), top[4][3], edge[2] = { 0.0, 0.0 };
    unsigned char *apart = ll_alloc_array(PAIRS, 1);
    int transmissive = ll_tables_transmits(src);
    uint64_t rng = 0x7ab1e5;
    size_t k, n = 0;
    int c, g;
    ll_status s = LL_OK;
    if (!ref || !got || !err || !apart) {
        s = ll_fail(LL_ERROR_OUT_OF_MEMORY, "ll_tables_write_from_bsdf: out of memory (figures)");
        goto done;
    }
    memset(top, 0, sizeof top);
    if (transmissive) {
        int lone = ll_tables_lone_interface(src);
        edge[0] = ll_tables_edge_width(src, lone, 0);
        edge[1] = ll_tables_edge_width(src, lone, 1);
    }
    for (k = 0; k < PAIRS && s == LL_OK; ++k) {
        double wo[3], wi[3], tv = acos(1.0 - uniform(&rng) * (1.0 - cos(lim)));
        direction(tv, 0.0, wo);
        if (transmissive && k % 4 >= 2)
            wo[2] = -wo[2];
        light_of(k, wo, tv, transmissive, src->eta, &rng, wi);
        if ((s = ll_bsdf_eval_dir(src, wo, wi, LL_TRANSPORT_RADIANCE, NULL, ref + 4 * k)) !=
                LL_OK ||
            (s = ll_bsdf_eval_dir(table, wo, wi, LL_TRANSPORT_RADIANCE, NULL, got + 3 * k)) !=
                LL_OK)
            break;
        ref[4 * k + 3] = fabs(wi[2]);
        g = transmissive ? (int)(k % 4 / 2 * 2 + (k / 4) % 2) : 0;
        apart[k] = g % 2 == 0 && edge[g / 2] > 0.0 && near_edge(wo, wi, src->eta, edge[g / 2]);
        for (c = 0; c < 3; ++c)
            if (ref[4 * k + c] * ref[4 * k + 3] > top[g][c])
                top[g][c] = ref[4 * k + c] * ref[4 * k + 3];
    }
    if (s != LL_OK)
        goto done;
    for (k = 0; k < PAIRS; ++k) {
        g = transmissive ? (int)(k % 4 / 2 * 2 + (k / 4) % 2) : 0;
        for (c = 0; c < 3 && !apart[k]; ++c)
            if (ref[4 * k + c] * ref[4 * k + 3] > 0.01 * top[g][c])
                err[n++] = fabs(got[3 * k + c] / ref[4 * k + c] - 1.0);
    }
    if (n == 0) {
        s = ll_fail(LL_ERROR_INVALID_ARGUMENT,
                    "ll_tables_write_from_bsdf: the file reflects nothing to compare");
        goto done;
    }
    qsort(err, n, sizeof *err, compare);
    out->p50 = err[n / 2];
    out->p95 = err[(size_t)(0.95 * (double)n)];
    out->p99 = err[(size_t)(0.99 * (double)n)];
done:
    ll_free(ref);
    ll_free(got);
    ll_free(err);
    ll_free(apart);
    return s;
}

ll_status ll_tables_measure(const ll_bsdf *src, const ll_tables_source *ref,
                            const ll_bsdf *table, ll_tables_figures *out)
{
    int k, c, bottom, sides = ll_tables_transmits(src) ? 2 : 1;
    ll_tables_source got;
    ll_status s;
    out->albedo = 0.0;
    if ((s = ll_tables_albedos(table, src, &got)) != LL_OK)
        return s;
    for (bottom = 0; bottom < sides; ++bottom)
        for (k = 0; k < ANGLES; ++k) {
            const double *as = ref->albedo[bottom][k], *at = got.albedo[bottom][k];
            for (c = 0; c < 6; ++c) {
                double all = as[c % 3] + as[c % 3 + 3];
                double r = as[c] > 0.0 && as[c] >= FLOOR * all ? fabs(at[c] / as[c] - 1.0) : 0.0;
                if (!(r <= out->albedo))
                    out->albedo = r;
            }
        }
    return f_errors(src, table, out);
}
