/*
 * llbuild's energy check of the file it wrote (energy.h).
 */
#include "energy.h"

#include <layerlab.h>

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static const double check_degrees[4] = { 0.0, 30.0, 60.0, 80.0 };

/* The point of parameter space of grid index k (the first parameter
 * varying slowest), its positions into params; 0 if the file's parameters
 * cannot be read. */
static int grid_point(const ll_bsdf *b, size_t n_parameters, size_t k, double *params)
{
    size_t p = n_parameters;
    while (p-- > 0) {
        size_t count = 0;
        const float *positions = NULL;
        if (ll_bsdf_get_parameter(b, p, &count, &positions) != LL_OK || count == 0)
            return 0;
        params[p] = positions[k % count];
        k /= count;
    }
    return 1;
}

/* The number of grid points (the product of the parameters' counts), 0 on
 * overflow or an unreadable parameter. */
static size_t grid_size(const ll_bsdf *b, size_t n_parameters)
{
    size_t p, n = 1;
    for (p = 0; p < n_parameters; ++p) {
        size_t count = 0;
        const float *positions = NULL;
        if (ll_bsdf_get_parameter(b, p, &count, &positions) != LL_OK || count == 0 ||
            n > SIZE_MAX / count)
            return 0;
        n *= count;
    }
    return n;
}

typedef struct worst_point {
    double sum;       /* the largest R + T of any channel          */
    double degrees;   /* its incident elevation                    */
    int from_below;
    size_t point;     /* its grid point                            */
    size_t n_over;    /* grid points with some R + T over 1 + slack */
} worst_point;

/* R + T of the file at one point (coeffs NULL: untextured) into *w. */
static void check_point(const ll_bsdf *b, const float *coeffs, size_t point, worst_point *w)
{
    size_t a, c;
    int side, over = 0;
    for (side = 0; side < 2; ++side) {
        int transmits = 0;
        for (a = 0; a < 4; ++a) {
            double r[3] = { 0, 0, 0 }, t[3] = { 0, 0, 0 };
            double mu = cos(check_degrees[a] * 3.14159265358979323846 / 180.0);
            if (ll_bsdf_albedo(b, side ? -mu : mu, coeffs, r, t) != LL_OK)
                continue;
            for (c = 0; c < 3; ++c) {
                double sum = r[c] + t[c];
                transmits |= t[c] > 0.0;
                over |= sum > 1.0 + LLBUILD_ENERGY_SLACK;
                if (sum > w->sum) {
                    w->sum = sum;
                    w->degrees = check_degrees[a];
                    w->from_below = side;
                    w->point = point;
                }
            }
        }
        /* An opaque file has no side below. */
        if (!transmits)
            break;
    }
    w->n_over += over;
}

/* "coat.alpha = 0.02, gold.alpha = 0.2" into text. */
static void describe_point(const ll_bsdf *b, size_t n_parameters, size_t point,
                           double *params, char *text, size_t size)
{
    size_t p, used = 0;
    text[0] = '\0';
    if (!grid_point(b, n_parameters, point, params))
        return;
    for (p = 0; p < n_parameters && used < size; ++p) {
        const char *name = "?";
        int n;
        ll_bsdf_get_parameter_name(b, p, &name);
        n = snprintf(text + used, size - used, "%s%s = %g", p ? ", " : "", name, params[p]);
        if (n < 0)
            break;
        used += (size_t)n;
    }
}

int llbuild_warn_energy(FILE *out, const char *path, int resolution_given)
{
    ll_bsdf *b = NULL;
    ll_bsdf_info info = LL_BSDF_INFO_INIT;
    worst_point w;
    size_t n_points = 1, k;
    float *coeffs = NULL;
    double *params = NULL;
    char where[512] = "";
    int warned = 0;
    memset(&w, 0, sizeof w);
    if (ll_bsdf_open(path, NULL, &b) != LL_OK || ll_bsdf_get_info(b, &info) != LL_OK)
        goto done;
    if (info.n_parameters > 0) {
        n_points = grid_size(b, info.n_parameters);
        coeffs = calloc(info.n_bases, sizeof *coeffs);
        params = calloc(info.n_parameters, sizeof *params);
        if (n_points == 0 || !coeffs || !params)
            goto done;
    }
    for (k = 0; k < n_points; ++k) {
        if (coeffs && (!grid_point(b, info.n_parameters, k, params) ||
                       ll_bsdf_basis_coefficients(b, params, coeffs) != LL_OK))
            goto done;
        check_point(b, coeffs, k, &w);
    }
    if (w.n_over == 0)
        goto done;
    if (coeffs) {
        char point[400];
        describe_point(b, info.n_parameters, w.point, params, point, sizeof point);
        snprintf(where, sizeof where, " at %s (%zu of its %zu bases exceed 1)", point, w.n_over,
                 n_points);
    }
    fprintf(out,
            "llbuild: warning: %s reflects and transmits more light than it receives: "
            "R + T = %.3g at %g degrees from %s%s. Its resolution does not resolve the "
            "material's sharpest lobe; %s\n",
            path, w.sum, w.degrees, w.from_below ? "below" : "above", where,
            resolution_given ? "without a given resolution (set nodes= orders=, --nodes, "
                               "--orders) the tolerance chooses one that does (--dry-run "
                               "shows it)"
                             : "a smaller --tolerance chooses more");
    warned = 1;
done:
    free(params);
    free(coeffs);
    ll_bsdf_release(b);
    return warned;
}
