/*
 * Pieces of the table writer (ll_tables.h). Writer side only.
 */
#ifndef LL_BSDF_WRITE_TABLES_H
#define LL_BSDF_WRITE_TABLES_H

#include "layerlab/ll_tables.h"
#include "reader/bsdf_internal.h"

/* Nodes of the NDF and sigma tables along u_theta (uniform in u_theta;
 * also the quadrature of the derivation). */
#define LL_TABLES_NDF_NODES 256

/* Luminance of an RGB value (the Rec. 709 / sRGB weights Mitsuba uses). */
LL_INTERNAL double ll_tables_luminance(const double rgb[3]);

/* D(theta) and sigma(theta) at the LL_TABLES_NDF_NODES nodes
 * theta_j = u_j^2 pi / 2, u_j = j / (n - 1), for the opaque isotropic b:
 * the dominant eigenvector of the retro-reflection operator, normalised,
 * mixed with Beckmann lobes of three times its roughness and of its peak's
 * width, and a uniform floor
 * (bsdf_write_tables_ndf.c says why). *alpha receives the fitted Beckmann
 * roughness. LL_OK, or LL_ERROR_INVALID_ARGUMENT if b reflects nothing
 * back. */
LL_INTERNAL ll_status ll_tables_derive_ndf(const ll_bsdf *b, double *d, double *sigma,
                                           double *alpha);

/* ll_tables_write_from_bsdf at the grid opts gives (a size of 0 takes
 * 32, 128 or 64; the tolerance is not read): one table, no measurement.
 * figures (nullable): JSON members ending in ", " that the metadata field
 * holds after the grid. */
LL_INTERNAL ll_status ll_tables_write_grid(const ll_bsdf *b, const char *path,
                                           const ll_tables_options *opts, const char *figures,
                                           const ll_monitor *monitor);

/* How far table is from src (the figures of the tolerance, ll_tables.h),
 * per channel, all channels pooled: the worst albedo ratio's distance from
 * 1 over viewer elevations 0..85 degrees, and the median, 95th and 99th
 * percentiles of the relative error of f where f cos is above 1% of its
 * largest value (both elevations <= 80 degrees, half of the pairs near
 * the mirror direction). LL_OK, LL_ERROR_OUT_OF_MEMORY, or the status of
 * a failed evaluation. */
typedef struct ll_tables_figures {
    double albedo, p50, p95, p99;
} ll_tables_figures;
LL_INTERNAL ll_status ll_tables_measure(const ll_bsdf *src, const ll_bsdf *table,
                                        ll_tables_figures *out);

#endif /* LL_BSDF_WRITE_TABLES_H */
