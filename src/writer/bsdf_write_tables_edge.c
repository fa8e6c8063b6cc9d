/*
 * The edge of total internal reflection in a reflected set seen from the
 * denser side of a lone interface (bsdf_write_tables.h): where the .bsdf
 * cannot follow f.
 *
 * There f = F(wi.h) S, S the microfacets' own reflection (D G / (4 |cos
 * theta_i cos theta_o|), Walter et al. 2007, eq. 20), smooth across the
 * edge, while F rises to 1 with an infinite slope at the critical cosine
 * of wi.h. The .bsdf's spline in mu through its nodes cannot follow that
 * edge: within about one node interval of it the .bsdf's f is off its own
 * model by far more than elsewhere (rough glass, eta 1.5, alpha 0.3,
 * compensate=0, 230 nodes, against Mitsuba 3's roughdielectric: where
 * wi.h lies within 0.02 of the critical cosine the 95th and 99th
 * percentiles of |f_bsdf / f - 1| are 10% and 17%, elsewhere 0.06% and
 * 0.16%; 690 nodes: 2.3-3.9% and 7-8%). The writer stores f / F (the
 * reader multiplies F back), and there f_bsdf / F is not smooth: a table
 * interpolating it was off the model by 6.8% (99th percentile) at 32 x
 * 64^2 x 64^2 and 8.8% at 64 x 96^2 x 96^2, and a larger grid only
 * followed the .bsdf's error more closely. So a set's nodes within that
 * width of the edge take the continuation of f / F from the nodes beside
 * them instead (bsdf_write_tables_lobes.c), as a refracted set's nodes at
 * its edge do: 1.7% and 1.5% at those grids
 * (tests/test_tables_transmit_edge.c).
 *
 * A lone interface only: behind a coat (over a medium without a base) the
 * light the medium sends back does not follow F, f / F is not smooth
 * across the edge whatever the .bsdf, and the continuation moved that
 * coat's 95th percentile of f from 2.71% to 2.85%.
 */
#include "writer/bsdf_write_tables.h"

#include <math.h>

/* Whether the stack reflects light at normal incidence alike from both
 * sides, as a lone interface does (Fresnel's reflectance is the same
 * from either side; roughness moves it a little: examples/frosted-glass
 * 0.0402 from above, 0.0422 from below), within LONE_RATIO. A layer that
 * sends light back on one side only adds its own (the coat over a
 * medium without a base of docs/formats.md: 0.0513 from above, 0.1078
 * from below). */
#define LONE_RATIO 1.25

int ll_tables_lone_interface(const ll_bsdf *b)
{
    double r_top[3], r_bottom[3], t[3], a, c;
    if (ll_bsdf_albedo(b, 1.0, NULL, r_top, t) != LL_OK ||
        ll_bsdf_albedo(b, -1.0, NULL, r_bottom, t) != LL_OK)
        return 0;
    a = ll_tables_luminance(r_top);
    c = ll_tables_luminance(r_bottom);
    return a > 0.0 && c > 0.0 && c <= LONE_RATIO * a && a <= LONE_RATIO * c;
}

/* The width is the .bsdf's widest node interval in mu (0.0137 for 230
 * nodes, 0.0046 for 690): a spline cannot follow an edge narrower than
 * its intervals. Measured on rough glass at 64 x 80^2 x 80^2, the 99th
 * percentile of the table's f against Mitsuba's over that set's pairs
 * (the tests' pairs) was 3.03% without the continuation, 1.49% over a
 * width of 0.005, 0.96% over 0.01 and over the widest interval, 1.10%
 * over 0.02 (and its albedo at 85 degrees 0.85% off over 0.03: farther
 * from their source, the rings of the continuation flatten); at 690
 * nodes 0.96% over 0.0036, 0.95% over the widest interval and 0.97% over
 * 0.01. */
static double widest_interval(const ll_bsdf *b)
{
    double widest = 0.0;
    size_t k;
    for (k = 0; k + 1 < b->n_nodes; ++k)
        if (b->nodes[k + 1] - b->nodes[k] > widest)
            widest = b->nodes[k + 1] - b->nodes[k];
    return widest;
}

double ll_tables_edge_width(const ll_bsdf *b, int lone, int bottom)
{
    double eta = b->eta;
    if (!lone || !(fabs(eta - 1.0) > 1e-6) || (bottom ? !(eta > 1.0) : !(eta < 1.0)))
        return 0.0;
    return widest_interval(b);
}

int ll_tables_edge_near(const double wi[3], const double wo[3], double fresnel_eta, double width)
{
    double h[3] = { wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2] };
    double len = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]), c;
    double critical = sqrt(1.0 - fresnel_eta * fresnel_eta);
    if (!(len > 0.0) || !(fresnel_eta < 1.0))
        return 0;
    c = (wi[0] * h[0] + wi[1] * h[1] + wi[2] * h[2]) / len;
    return fabs(c - critical) < width;
}
