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
 * model by far more than the tables' aims, elsewhere by far less. The
 * writer stores f / F (the reader multiplies F back), and there f_bsdf / F
 * is not smooth: a table interpolating it followed the .bsdf's error, the
 * more closely the larger its grid. So a set's nodes within that width of
 * the edge take the continuation of f / F from the nodes beside them
 * instead (bsdf_write_tables_lobes.c), as a refracted set's nodes at its
 * edge do, and the table follows the model there
 * (tests/test_tables_transmit_edge.c compares both with the closed form;
 * docs/benchmarks.md, "The edge of total internal reflection", has the
 * figures).
 *
 * A lone interface only: behind a coat (over a medium without a base) the
 * light the medium sends back does not follow F, f / F is not smooth
 * across the edge whatever the .bsdf, and the continuation made that
 * coat's figures worse.
 */
#include "writer/bsdf_write_tables.h"

#include <math.h>

/* Whether the stack reflects light at normal incidence alike from both
 * sides, as a lone interface does (Fresnel's reflectance is the same
 * from either side; roughness moves it a little), within LONE_RATIO. A
 * layer that sends light back on one side only adds its own (the coat
 * over a medium without a base of docs/formats.md reflects twice as much
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

/* The width is the .bsdf's widest node interval in mu: a spline cannot
 * follow an edge narrower than its intervals. Narrower widths left more
 * of the .bsdf's error in the table, wider ones continued f / F farther
 * from its source (docs/benchmarks.md, "The edge of total internal
 * reflection", has the widths measured). */
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
