/*
 * Measured isotropic BRDFs in the format of the MERL BRDF database
 * (Matusik, Pfister, Brand, McMillan: "A Data-Driven Reflectance Model",
 * SIGGRAPH 2003), turned into the top reflection of a layer.
 *
 * File: three int32 (little-endian) resolutions of theta_half, theta_diff
 * and phi_diff (90, 90, 180 in the database), then the R, G and B tables of
 * float64 (little-endian), each res_theta_h * res_theta_d * res_phi_d values,
 * phi_diff fastest. A stored value times the channel's scale (below) is the
 * BRDF in 1/sr.
 */
#ifndef LL_MERL_H
#define LL_MERL_H

#include "layer/layer.h"
#include "support/watch.h"

/* MERL's own reader (BRDFRead.cpp: RED_SCALE, GREEN_SCALE, BLUE_SCALE) turns
 * the stored numbers into reflectance in 1/sr with these factors. The
 * original layerlab multiplied by a further 2 (marked "too dark?" there); that factor
 * has no physical basis (its DCT already yields the cosine-series
 * coefficients of f itself), so it is not applied here. */
#define LL_MERL_SCALE_R (1.0 / 1500.0)
#define LL_MERL_SCALE_G (1.15 / 1500.0)
#define LL_MERL_SCALE_B (1.66 / 1500.0)

typedef struct ll_merl {
    size_t res_theta_h, res_theta_d, res_phi_d;
    double *values; /* [3][res_theta_h][res_theta_d][res_phi_d], scaled to 1/sr */
} ll_merl;

/* Validate a file's header against its size without reading the tables.
 * LL_ERROR_IO (cannot open) or LL_ERROR_FORMAT (naming the path and field). */
LL_INTERNAL ll_status ll_merl_check(const char *path);

/* Read a whole file (validated as ll_merl_check does). */
LL_INTERNAL ll_status ll_merl_load(const char *path, ll_merl **out);
LL_INTERNAL void ll_merl_free(ll_merl *merl);

/* The BRDF (1/sr) for the unit directions wi (to the light) and wo (to the
 * viewer) in a frame whose z axis is the normal, as sum_c weights[c] *
 * channel c. Directions below the surface and missing measurements
 * (negative values in the file) give 0. */
LL_INTERNAL double ll_merl_eval(const ll_merl *merl, const double wi[3], const double wo[3],
                                const double weights[3]);

/* Replace the layer by the measured BRDF: reflection from above only (no
 * transmission, nothing seen from below), Fourier orders from a discrete
 * cosine transform (DCT-I) of 4 * max(n_orders_internal, the layer's orders)
 * azimuth samples on [0, pi]. With a public monitor (stage "measured";
 * nullable), or with a begun watch (support/watch.h; nullable): the one code
 * path of both and of ll_layer_set_matusik. A cancel leaves the layer
 * unchanged. */
LL_INTERNAL ll_status ll_merl_set_layer(ll_layer *layer, const ll_merl *merl,
                                           const double weights[3], size_t n_orders_internal,
                                           const ll_monitor *monitor);
LL_INTERNAL ll_status ll_merl_set_layer_watched(ll_layer *layer, const ll_merl *merl,
                                                const double weights[3],
                                                size_t n_orders_internal, ll_watch *watch);

/* The cosine series of one node pair (mu_i > 0 the incident cosine, mu_o
 * > 0 the outgoing one's magnitude) as the layer holds it: m coefficients
 * into a (the negligible tail zeroed) from N azimuth samples into f, with
 * the table of ll_merl_cos_table. */
LL_INTERNAL void ll_merl_pair_series(const ll_merl *merl, const double weights[3], double mu_i,
                                     double mu_o, size_t m, size_t N, const double *cos_table,
                                     double *f, double *a);
/* The samples N of a layer of `orders` internal orders (4 per order, at
 * least 4) and cos(pi t / (N - 1)) for t < 2 (N - 1), allocated. */
LL_INTERNAL ll_status ll_merl_cos_table(size_t orders, size_t *samples, double **table);

#endif /* LL_MERL_H */
