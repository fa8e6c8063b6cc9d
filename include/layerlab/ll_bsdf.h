/*
 * layerlab — .bsdf files ("SCATFUN" version 1, the Fourier BSDF format of
 * Jakob et al. 2014 that pbrt-v3's "fourier" material reads): writing them
 * from layers, opening them safely, evaluating and sampling them.
 *
 * An opened file (ll_bsdf) is immutable and reference counted: it may be
 * evaluated and sampled from any number of threads at once, and shared by
 * every object that uses the same file (ll_bsdf_retain / ll_bsdf_release;
 * retain and release are thread-safe too).
 *
 * Two conventions:
 *  - Layer convention (as ll_layer_eval): mu_i > 0 is light arriving from
 *    above, travelling down; reflection goes to mu_o < 0. phi_d as in
 *    ll_layer_eval.
 *  - Renderer convention (the *_dir calls): a local shading frame with
 *    z = the surface normal (the top side); wo points to the viewer and wi
 *    to the light, both away from the surface (as pbrt-v3's BxDF::f(wo, wi)).
 *    f is returned without the cosine factor. In LL_TRANSPORT_RADIANCE mode
 *    the value across a dielectric boundary is scaled by eta^2 as radiance
 *    requires; LL_TRANSPORT_IMPORTANCE omits that factor (as pbrt-v3 does
 *    for light paths).
 * rgb outputs are (R, G, B); one-channel files give three equal values.
 * Negative values clamp to 0. basis_coeffs: one weight per basis function of
 * a textured file (NULL for an untextured one).
 */
#ifndef LAYERLAB_LL_BSDF_H
#define LAYERLAB_LL_BSDF_H

#include "ll_common.h"
#include "ll_layer.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct ll_bsdf ll_bsdf;

typedef enum { LL_TRANSPORT_RADIANCE = 0, LL_TRANSPORT_IMPORTANCE = 1 } ll_transport;

/* ------------------------------------------------------------- writing */

/* Options for writing. Set struct_size = sizeof(ll_bsdf_write_options) (the
 * INIT macro does); the library reads only the fields that struct_size
 * covers, so programs built against older headers keep working. */
typedef struct ll_bsdf_write_options {
    size_t struct_size;
    double eta;          /* header eta: eta(bottom)/eta(top); 1 for opaque stacks */
    double alpha[2];     /* header roughness of the top and bottom interface      */
    const char *metadata;/* text stored in the file; NULL = a JSON description     */
    double error_goal;   /* series truncation: relative tail sum, default 1e-3    */
} ll_bsdf_write_options;

#define LL_BSDF_WRITE_OPTIONS_INIT \
    { sizeof(ll_bsdf_write_options), 1.0, { 0.0, 0.0 }, NULL, 1e-3 }

/* Write layers[0 .. n_channels-1] (1 channel, or 3: R, G, B, stored as
 * Y, R, B) to path. All layers must share nodes and order count. opts may be
 * NULL (defaults). Atomic: the file is written to a temporary file in the
 * same directory, flushed and renamed over path; on any failure path is
 * untouched and no temporary file remains. Returns LL_ERROR_IO (message
 * names the path and the system error) or LL_ERROR_INVALID_ARGUMENT. */
LL_API ll_status ll_bsdf_write(const char *path, const ll_layer *const *layers,
                               size_t n_channels, const ll_bsdf_write_options *opts);

/* Textured file: n_parameters parameters, parameter p sampled at
 * param_counts[p] positions (the param_positions array holds them all,
 * parameter 0's first). n_bases = product of the counts; layers holds
 * n_bases * n_channels layers, basis-major (layers[basis * n_channels + ch]),
 * with the basis index running over parameter 0 fastest. */
LL_API ll_status ll_bsdf_write_textured(const char *path, const ll_layer *const *layers,
                                        size_t n_channels, size_t n_parameters,
                                        const size_t *param_counts,
                                        const double *param_positions,
                                        const ll_bsdf_write_options *opts);

/* ------------------------------------------------------------- reading */

/* Open and fully validate a file. Every structural problem yields
 * LL_ERROR_FORMAT with a message naming the file and the field; I/O
 * problems LL_ERROR_IO. *out is NULL on failure. */
LL_API ll_status ll_bsdf_open(const char *path, ll_bsdf **out);

/* The same from memory (the bytes are copied; data may be freed after). */
LL_API ll_status ll_bsdf_open_memory(const void *data, size_t size, ll_bsdf **out);

/* Add a reference; returns b. */
LL_API ll_bsdf *ll_bsdf_retain(ll_bsdf *b);
/* Drop a reference; the last one frees. NULL is fine. */
LL_API void ll_bsdf_release(ll_bsdf *b);

typedef struct ll_bsdf_info {
    size_t struct_size;      /* set by the caller: sizeof(ll_bsdf_info)         */
    size_t n_nodes;          /* zenith-cosine nodes (two of them at mu = 0)     */
    size_t max_order;        /* longest Fourier series                          */
    size_t n_channels;       /* 1 or 3                                          */
    size_t n_bases;          /* 1 unless textured                               */
    size_t n_parameters;     /* textured parameters                             */
    size_t n_coeffs;         /* float32 coefficients stored                     */
    double eta;              /* relative index, bottom over top                 */
    double alpha[2];         /* roughness of the top and bottom interface       */
    const char *metadata;    /* NUL-terminated copy, valid while b lives        */
    size_t metadata_size;    /* bytes, without the terminator                   */
    size_t file_size;        /* bytes                                           */
    uint32_t flags;          /* header flags                                    */
} ll_bsdf_info;

#define LL_BSDF_INFO_INIT { sizeof(ll_bsdf_info), 0, 0, 0, 0, 0, 0, 0.0, { 0.0, 0.0 }, NULL, 0, 0, 0 }

LL_API ll_status ll_bsdf_get_info(const ll_bsdf *b, ll_bsdf_info *info);

/* Sample positions of textured parameter p: *count values at *positions
 * (owned by b). */
LL_API ll_status ll_bsdf_get_parameter(const ll_bsdf *b, size_t p, size_t *count,
                                       const float **positions);

/* The file's nodes (n_nodes floats, ascending, owned by b). */
LL_API const float *ll_bsdf_nodes(const ll_bsdf *b);

/* ------------------------------------------------- layer convention */

LL_API ll_status ll_bsdf_eval(const ll_bsdf *b, double mu_i, double mu_o, double phi_d,
                              const float *basis_coeffs, double rgb[3]);

/* Probability density (per solid angle) that ll_bsdf_sample picks (mu_o,
 * phi_d) given mu_i. */
LL_API double ll_bsdf_pdf(const ll_bsdf *b, double mu_i, double mu_o, double phi_d,
                          const float *basis_coeffs);

/* Sample an outgoing direction for light arriving along mu_i, from the
 * uniform numbers u[0], u[1] in [0, 1): writes mu_o, phi_d, the pdf and the
 * weight f * |mu_o| / pdf. A zero weight and pdf mean no direction. */
LL_API ll_status ll_bsdf_sample(const ll_bsdf *b, double mu_i, const double u[2],
                                const float *basis_coeffs, double *mu_o, double *phi_d,
                                double *pdf, double weight_rgb[3]);

/* ---------------------------------------------- renderer convention */

LL_API ll_status ll_bsdf_eval_dir(const ll_bsdf *b, const double wo[3], const double wi[3],
                                  ll_transport mode, const float *basis_coeffs,
                                  double rgb[3]);

/* pdf of sampling wi given wo (per solid angle), as pbrt-v3's Pdf(wo, wi). */
LL_API double ll_bsdf_pdf_dir(const ll_bsdf *b, const double wo[3], const double wi[3],
                              const float *basis_coeffs);

/* Sample wi given wo as pbrt-v3's FourierBSDF::Sample_f does (same u gives
 * the same direction); writes wi (unit length), its pdf and f(wo, wi). */
LL_API ll_status ll_bsdf_sample_dir(const ll_bsdf *b, const double wo[3], const double u[2],
                                    ll_transport mode, const float *basis_coeffs,
                                    double wi[3], double *pdf, double rgb[3]);

#ifdef __cplusplus
}
#endif
#endif /* LAYERLAB_LL_BSDF_H */
