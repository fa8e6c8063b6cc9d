/*
 * Pieces of the table writer (ll_tables.h). Writer side only.
 */
#ifndef LL_BSDF_WRITE_TABLES_H
#define LL_BSDF_WRITE_TABLES_H

#include "reader/bsdf_internal.h"

/* Nodes of the NDF and sigma tables along u_theta (uniform in u_theta;
 * also the quadrature of the derivation). */
#define LL_TABLES_NDF_NODES 256

/* Luminance of an RGB value (the Rec. 709 / sRGB weights Mitsuba uses). */
LL_INTERNAL double ll_tables_luminance(const double rgb[3]);

/* D(theta) and sigma(theta) at the LL_TABLES_NDF_NODES nodes
 * theta_j = u_j^2 pi / 2, u_j = j / (n - 1), for the opaque isotropic b:
 * the dominant eigenvector of the retro-reflection operator, normalised,
 * mixed with a Beckmann lobe of twice its roughness and a uniform floor
 * (bsdf_write_tables_ndf.c says why). *alpha receives the fitted Beckmann
 * roughness. LL_OK, or LL_ERROR_INVALID_ARGUMENT if b reflects nothing
 * back. */
LL_INTERNAL ll_status ll_tables_derive_ndf(const ll_bsdf *b, double *d, double *sigma,
                                           double *alpha);

#endif /* LL_BSDF_WRITE_TABLES_H */
