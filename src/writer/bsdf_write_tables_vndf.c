/*
 * The first two steps of every table the writer makes, whether the one
 * table of an opaque file (bsdf_write_tables.c) or a lobe of a
 * transmissive one (bsdf_write_tables_lobes.c): D and sigma as the float
 * tables and warps a reader builds from them, and the visible-normal
 * density of one incident elevation read back through those warps, so
 * that the file holds what a reader will interpolate.
 */
#include "writer/bsdf_write_tables.h"

#include <math.h>

double ll_tables_get_float(const void *ctx, size_t i)
{
    return (double)((const float *)ctx)[i];
}

ll_status ll_tables_ndf_warps(const double *d, const double *sigma, float *ndf_f,
                              float *sigma_f, ll_warp2d *ndf_w, ll_warp2d *sigma_w)
{
    enum { N = LL_TABLES_NDF_NODES };
    size_t j;
    ll_status s;
    for (j = 0; j < N; ++j) {
        ndf_f[j] = ndf_f[N + j] = (float)d[j];
        sigma_f[j] = sigma_f[N + j] = (float)sigma[j];
    }
    if ((s = ll_warp2d_init(ndf_w, N, 2, 0, NULL, NULL, ll_tables_get_float, ndf_f, 0)) !=
            LL_OK ||
        (s = ll_warp2d_init(sigma_w, N, 2, 0, NULL, NULL, ll_tables_get_float, sigma_f, 0)) !=
            LL_OK)
        return s;
    return LL_OK;
}

double ll_tables_sigma_at(const ll_warp2d *sigma_w, double theta)
{
    double u[2] = { sqrt(theta * (2.0 / LL_PI)), 0.5 };
    return ll_warp2d_eval(sigma_w, u, NULL);
}

void ll_tables_vndf_slice(const ll_warp2d *ndf_w, const ll_warp2d *sigma_w, double th, size_t nv,
                          float *out)
{
    size_t x, y;
    double wi[3] = { sin(th), 0.0, cos(th) };
    double inv_sigma = 1.0 / ll_tables_sigma_at(sigma_w, th);
    for (y = 0; y < nv; ++y) {
        double phi = (2.0 * (double)y / (double)(nv - 1) - 1.0) * LL_PI;
        for (x = 0; x < nv; ++x) {
            double u[2] = { (double)x / (double)(nv - 1), 0.5 };
            double tm = u[0] * u[0] * (LL_PI / 2);
            double m[3] = { sin(tm) * cos(phi), sin(tm) * sin(phi), cos(tm) };
            double dot = wi[0] * m[0] + wi[1] * m[1] + wi[2] * m[2];
            double v = dot > 0.0 ? dot * ll_warp2d_eval(ndf_w, u, NULL) * inv_sigma * 2.0 *
                                       LL_PI * LL_PI * u[0] * sin(tm)
                                 : 0.0;
            out[y * nv + x] = (float)v;
        }
    }
}
