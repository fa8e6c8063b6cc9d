/*
 * layerlab — .bsdf files ("SCATFUN" version 1, the Fourier BSDF format of
 * Jakob et al. 2014 that pbrt-v3's "fourier" material reads): opening them
 * safely, evaluating and sampling them. Writing them from layers is in
 * ll_bsdf_write.h; this header needs only ll_common.h, so a renderer that
 * only reads files includes it alone and links liblayerlab_reader.
 *
 * An opened file (ll_bsdf) is immutable and reference counted: it may be
 * evaluated and sampled from any number of threads at once, and shared by
 * every object that uses the same file (ll_bsdf_retain / ll_bsdf_release;
 * retain and release are thread-safe too). Evaluation and sampling allocate
 * nothing; their stack use is bounded independently of the file (below
 * 80 KiB in ll_bsdf_sample*, below 24 KiB in evaluation).
 *
 * Two conventions:
 *  - Layer convention (ll_bsdf_eval, ll_bsdf_pdf, ll_bsdf_sample), the
 *    file's own axes and those of ll_layer_eval: mu_i and mu_o are cosines
 *    of directions of travel, mu > 0 travelling down, so mu_i > 0 is light
 *    arriving from above and reflection goes to mu_o < 0; phi_d is the
 *    azimuth between the two directions of travel (phi_d = 0 with
 *    mu_o = -mu_i is the mirror direction). For the layer L a file was
 *    written from,
 *        ll_bsdf_eval(b, mu_i, mu_o, phi_d) == ll_layer_eval(L, mu_i, mu_o, phi_d)
 *    at the layer's nodes to float precision and the series truncation.
 *    Between nodes both interpolate with Catmull-Rom splines, the file over
 *    f |mu_o| with two extra nodes at mu = 0 where it is pinned to 0 (the
 *    original layerlab's format), so near grazing angles the two differ by
 *    the interpolation error. Cosines beyond the file's outermost nodes give
 *    0 (write layers on Gauss-Lobatto nodes, which include +-1).
 *  - Renderer convention (the *_dir calls): a local shading frame with
 *    z = the surface normal (the top side); wo points to the viewer and wi
 *    to the light, both away from the surface (pbrt-v3's BxDF::f(wo, wi));
 *    the vectors need not be normalised. f is returned without the cosine
 *    factor. These calls are pbrt-v3's FourierBSDF exactly: they evaluate
 *    the layer convention at
 *        mu_i = wo.z / |wo|             (pbrt-v3's muO = CosTheta(wo)),
 *        mu_o = -wi.z / |wi|            (pbrt-v3's muI = CosTheta(-wi)),
 *        cos phi_d = -(wo.x wi.x + wo.y wi.y) / (|wo.xy| |wi.xy|)
 *                                       (CosDPhi(-wi, wo); 1 if either
 *                                        direction is the normal),
 *    i.e. light travelling along -wo and leaving along wi, which equals
 *    the response to light from wi seen along wo by reciprocity, up to the
 *    eta^2 of transmission: in LL_TRANSPORT_RADIANCE mode a transmitted
 *    value (wo and wi on opposite sides) is multiplied by (1 / eta)^2 when
 *    wi is below the surface (wi.z < 0 < wo.z) and by eta^2 when wo is
 *    below, as pbrt-v3's FourierBSDF::f does for camera paths;
 *    LL_TRANSPORT_IMPORTANCE (light paths) omits the factor. eta is the
 *    file's eta(bottom) / eta(top). The layer-convention calls never scale.
 * Both conventions name the given direction first (mu_i, wo) and the
 * other second (mu_o, wi); the samplers pick the second.
 * Values: f is always the BSDF without the cosine factor, and the pdf a
 * density per solid angle of the second direction. The samplers return
 * both f and the pdf of the direction they pick (never their ratio); a
 * Monte Carlo estimator's weight is f |cos| / pdf, with |cos| = |mu_o| in
 * the layer convention and |wi.z| / |wi| in the renderer convention.
 * Failures: the calls return an ll_status; their outputs are then 0 (and a
 * sampled direction the normal), as ll_common.h says for every call.
 * rgb outputs are (R, G, B); one-channel files give three equal values;
 * three-channel files store Y, R, B and rebuild G = 1.39829 Y - 0.100913 B
 * - 0.297375 R (pbrt-v3). Negative values clamp to 0.
 * basis_coeffs: for a textured file, one weight per basis function
 * (ll_bsdf_info.n_bases floats, applied to every channel; required); for an
 * untextured file NULL (weight 1) or one weight that scales the result.
 */
#ifndef LAYERLAB_LL_BSDF_H
#define LAYERLAB_LL_BSDF_H

#include "ll_common.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct ll_bsdf ll_bsdf;

typedef enum { LL_TRANSPORT_RADIANCE = 0, LL_TRANSPORT_IMPORTANCE = 1 } ll_transport;

/* ------------------------------------------------------------- reading */

/* Limits on what ll_bsdf_open / ll_bsdf_open_memory accept from an
 * untrusted file, checked on the header before anything it sizes is
 * allocated or read (as OpenEXR's maximum image size and zstd's
 * windowLogMax). Set struct_size = sizeof(ll_open_options) (the INIT macro
 * does); the library reads only the fields struct_size covers. A field of
 * 0 takes its default; SIZE_MAX means no limit.
 *  max_bytes: largest file (default LL_OPEN_DEFAULT_MAX_BYTES, 512 MiB; an
 *    opened file costs about twice its size in memory);
 *  max_order: longest Fourier series (header nMaxOrder; default
 *    LL_OPEN_DEFAULT_MAX_ORDER, 16384: evaluation costs up to 16 series of
 *    this length per channel, so this bounds the time of one eval);
 *  max_nodes: zenith-cosine nodes (default LL_OPEN_DEFAULT_MAX_NODES, 8192;
 *    tables grow as its square).
 * A file beyond a limit gives LL_ERROR_UNSUPPORTED with a message naming
 * the field, its value and the limit. opts NULL applies the defaults;
 * LL_ERROR_INVALID_ARGUMENT for a struct_size smaller than the first
 * field's end. */
typedef struct ll_open_options {
    size_t struct_size;
    size_t max_bytes;
    size_t max_order;
    size_t max_nodes;
} ll_open_options;

#define LL_OPEN_DEFAULT_MAX_BYTES ((size_t)512 << 20)
#define LL_OPEN_DEFAULT_MAX_ORDER ((size_t)16384)
#define LL_OPEN_DEFAULT_MAX_NODES ((size_t)8192)
#define LL_OPEN_OPTIONS_INIT { sizeof(ll_open_options), 0, 0, 0 }

/* Open and fully validate a file: identifier and version (version 2 files
 * of the later "Layer Laboratory", which reuse the identifier with another
 * layout, are refused by name), flags, every count against the real file
 * size with overflow-checked arithmetic (before anything sized by the
 * header is allocated), nodes finite and ascending (one value at most
 * twice), parameters, CDF rows (finite, from 0, non-decreasing up to
 * rounding: a dip of at most 2^-20 of the row's total, as the original
 * layerlab's float32 running sums have, is accepted and stored flat), every
 * offset-table entry inside the coefficients with length <= nMaxOrder (and
 * nMaxOrder the longest), the blocks adding up to nCoeffs, every
 * coefficient finite and of magnitude <= 2^100, eta in [1e-3, 1e3], alpha
 * finite and >= 0; then the limits of opts (above).
 * Every problem yields LL_ERROR_FORMAT with a message naming the file
 * ("<path>" or <memory>) and the field; harmonic extrapolation (flags
 * bit 1) or a file beyond a limit LL_ERROR_UNSUPPORTED; I/O problems
 * (missing file; a FIFO, device or directory, refused without blocking and
 * named) LL_ERROR_IO; LL_ERROR_OUT_OF_MEMORY. *out is NULL on failure.
 * Memory: about the file's size (coefficients are kept as the file's
 * floats, which halves what evaluation reads; it computes in double) plus
 * 16 bytes per node pair and basis; the file's bytes are not held beside
 * them. A file that opens gives finite results for every direction (f is
 * the stored f |mu_o| over |mu_o|, with |mu_o| taken as at least 1e-6). */
LL_API ll_status ll_bsdf_open(const char *path, const ll_open_options *opts, ll_bsdf **out);

/* The same from memory (the bytes are copied; data may be freed after),
 * with the same checks and statuses; messages name the file <memory>. */
LL_API ll_status ll_bsdf_open_memory(const void *data, size_t size, const ll_open_options *opts,
                                     ll_bsdf **out);

/* Add a reference, which the caller drops with ll_bsdf_release; returns b
 * (NULL for NULL). Thread-safe (an atomic count). */
LL_API ll_bsdf *ll_bsdf_retain(ll_bsdf *b);
/* Drop a reference; the last one frees the file's memory, after every
 * other thread's last use of it. NULL is fine. Thread-safe. */
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
    uint32_t format;         /* LL_BSDF_FORMAT_FOURIER or LL_BSDF_FORMAT_TABLES */
    size_t n_wavelengths;    /* a spectral table file's wavelengths, else 0     */
} ll_bsdf_info;

#define LL_BSDF_INFO_INIT { sizeof(ll_bsdf_info), 0, 0, 0, 0, 0, 0, 0.0, { 0.0, 0.0 }, NULL, 0, \
                            0, 0, 0, 0 }

/* Which format ll_bsdf_open read (ll_bsdf_info.format), recognised by the
 * file's first bytes whatever its name:
 *  LL_BSDF_FORMAT_FOURIER: a .bsdf Fourier file (above);
 *  LL_BSDF_FORMAT_TABLES: a table file of the `measured` format of Mitsuba 3
 *    and pbrt-v4 (docs/formats.md; RGB or spectral, isotropic). A
 *    spectral file (fields "spectra" and "wavelengths"; info.n_wavelengths
 *    says how many) is read as linear sRGB: its values taken as a
 *    reflectance lit by CIE D65 and seen by the CIE 1931 2-degree observer
 *    (trapezoid rule on the file's wavelengths, normalised so that a
 *    constant spectrum 1 reads (1, 1, 1)), negative components clipped to
 *    0, converted once when the file is opened. It evaluates and
 *    samples through the same calls, as Mitsuba's `measured` does, with f
 *    returned without the cosine; it reflects only (mu_i > 0, mu_o < 0 in
 *    the layer convention, both directions above the surface in the
 *    renderer convention; elsewhere 0); the _dir calls evaluate it on the
 *    two directions themselves (wo is the format's fixed direction), not
 *    through (mu_i, mu_o, cos phi_d). A transmissive material's table file
 *    (layerlab's extension: field "layerlab_layout", a set of tables per
 *    lobe and side; RGB) reflects and transmits on both sides as a .bsdf
 *    does, transmitted values with the .bsdf's eta^2 in radiance mode, and
 *    its info's eta is the file's. Its info has n_channels 3, n_bases
 *    1, eta 1 (an extended file: its own), n_nodes, max_order, n_coeffs 0
 *    and flags 0, and metadata is
 *    the file's "layerlab_metadata" field (else its "description");
 *    ll_bsdf_nodes gives NULL and ll_bsdf_get_tables LL_ERROR_UNSUPPORTED. */
#define LL_BSDF_FORMAT_FOURIER 0u
#define LL_BSDF_FORMAT_TABLES 1u

/* The file's description (ll_bsdf_info above) into *info, of which only the
 * fields that info->struct_size covers are written (set it, or start from
 * LL_BSDF_INFO_INIT), so a program built against older headers keeps
 * working. info->metadata points into b and lives as long as b.
 * Thread-safe (b is immutable). LL_ERROR_INVALID_ARGUMENT for NULL b or
 * info, or a struct_size smaller than the struct_size field itself. */
LL_API ll_status ll_bsdf_get_info(const ll_bsdf *b, ll_bsdf_info *info);

/* Sample positions of textured parameter p (p < info.n_parameters):
 * *count values at *positions (owned by b, valid while b
 * lives). Thread-safe. LL_ERROR_INVALID_ARGUMENT for NULL arguments or p
 * out of range. */
LL_API ll_status ll_bsdf_get_parameter(const ll_bsdf *b, size_t p, size_t *count,
                                       const float **positions);

/* Name of textured parameter p (p < info.n_parameters): *name is a
 * NUL-terminated UTF-8 string owned by b, valid while b lives. Names come
 * from the metadata's top-level JSON key "parameters", an array of exactly
 * n_parameters distinct non-empty strings of at most 255 bytes in the
 * file's order (what layerlab's textured builds write, e.g.
 * ["coat.alpha", "base.alpha"]), read when the file is opened (the text is
 * scanned, bounded and allocation-free, before the names' one block is
 * allocated). A file without such an array -- other or no JSON, the default
 * writer's "parameters": <count>, a wrong count, a malformed or duplicate
 * string, more than 256 parameters -- opens as before and gets the names
 * "p0", "p1", ... Thread-safe (b is immutable).
 * LL_ERROR_INVALID_ARGUMENT for NULL arguments or p out of range. */
LL_API ll_status ll_bsdf_get_parameter_name(const ll_bsdf *b, size_t p, const char **name);

/* Weights of the file's bases for one point of parameter space: params holds one value per
 * textured parameter, in the file's order; coeffs receives info.n_bases floats, to be passed as
 * basis_coeffs to ll_bsdf_eval / _pdf / _sample and their _dir forms. Values outside a parameter's
 * sampled range are clamped to it. NULL params is valid only for an untextured file.
 * The weights are products of 1-D linear (hat) weights over each parameter's positions: >= 0,
 * at most two non-zero per parameter, summing to 1, so f stays >= 0 and sampling is exact;
 * evaluation and sampling visit only the non-zero ones (docs/formats.md, "Weights for a
 * point of parameter space", compares them with Catmull-Rom weights). Thread-safe.
 * LL_ERROR_INVALID_ARGUMENT for NULL b or coeffs, NULL params for a textured file, or a
 * non-finite parameter value. */
LL_API ll_status ll_bsdf_basis_coefficients(const ll_bsdf *b, const double *params, float *coeffs);

/* The file's nodes (n_nodes floats, ascending, owned by b and valid while
 * b lives); NULL for NULL b or a table file. */
LL_API const float *ll_bsdf_nodes(const ll_bsdf *b);

/* ------------------------------------------------- layer convention */

/* f(mu_i -> mu_o, phi_d) without cosine into f_rgb, as ll_layer_eval (see
 * the top of this file). Cosines are clamped into [-1, 1].
 * LL_ERROR_INVALID_ARGUMENT for NULL b or f_rgb, non-finite arguments, or
 * missing basis weights of a textured file. */
LL_API ll_status ll_bsdf_eval(const ll_bsdf *b, double mu_i, double mu_o, double phi_d,
                              const float *basis_coeffs, double f_rgb[3]);

/* Probability density (per solid angle, d mu_o d phi_d) that
 * ll_bsdf_sample picks (mu_o, phi_d) given mu_i, into *pdf: the luminance
 * f |mu_o| over the luminance albedo (0 where that is not positive).
 * Errors as ll_bsdf_eval (NULL pdf too). */
LL_API ll_status ll_bsdf_pdf(const ll_bsdf *b, double mu_i, double mu_o, double phi_d,
                             const float *basis_coeffs, double *pdf);

/* Sample an outgoing direction for light arriving along mu_i, from the
 * uniform numbers u[0], u[1] in [0, 1], both ends included (as pbrt-v3's
 * Sample_f: u[1] picks mu_o by inverting the luminance's spline CDF, u[0]
 * picks phi_d in [0, 2 pi) from the Fourier series, u[0] >= 1/2 the
 * mirrored half): writes mu_o, phi_d, the pdf (equal to ll_bsdf_pdf there)
 * and f (equal to ll_bsdf_eval there). A pdf and f of 0 mean no direction
 * (no light is scattered from mu_i); wherever light is scattered, every u
 * gives a direction of positive pdf. The inversions are Newton-bisection
 * with a bounded number of steps. LL_ERROR_INVALID_ARGUMENT for NULL
 * pointers, non-finite mu_i, u outside [0, 1]. */
LL_API ll_status ll_bsdf_sample(const ll_bsdf *b, double mu_i, const double u[2],
                                const float *basis_coeffs, double *mu_o, double *phi_d,
                                double *pdf, double f_rgb[3]);

/* The directional albedo for light arriving along mu_i (layer convention,
 * as ll_bsdf_eval): the integral of f |mu_o| over the reflected
 * hemisphere (mu_o of the other sign than mu_i; mu_i = 0 counts as from
 * above) into rgb_reflected and over the transmitted one into
 * rgb_transmitted (either may be NULL). At the file's own accuracy: the
 * order-0 series (the azimuthal mean) interpolated in mu_i with the file's
 * spline weights and integrated over mu_o with the spline the sampler
 * inverts, so that the luminance of the sum of both is the normalisation
 * of ll_bsdf_pdf and the mean of the sample weights f |mu_o| / pdf of
 * ll_bsdf_sample. Allocates nothing; O(n_nodes) work. Colour and basis
 * weights as ll_bsdf_eval. LL_ERROR_INVALID_ARGUMENT for NULL b,
 * non-finite mu_i or missing basis weights; LL_ERROR_UNSUPPORTED for a
 * table file (LL_BSDF_FORMAT_TABLES), which has no order-0 series. */
LL_API ll_status ll_bsdf_albedo(const ll_bsdf *b, double mu_i, const float *basis_coeffs,
                                double rgb_reflected[3], double rgb_transmitted[3]);

/* ---------------------------------------------- renderer convention */

/* f(wo, wi) without cosine into f_rgb (pbrt-v3's FourierBSDF::f; mapping
 * and the transport mode's eta^2 at the top of this file).
 * LL_ERROR_INVALID_ARGUMENT for NULL pointers, zero or non-finite
 * directions, an unknown mode or missing basis weights. */
LL_API ll_status ll_bsdf_eval_dir(const ll_bsdf *b, const double wo[3], const double wi[3],
                                  ll_transport mode, const float *basis_coeffs,
                                  double f_rgb[3]);

/* The density of sampling wi given wo (per solid angle of wi) into *pdf, as
 * pbrt-v3's Pdf(wo, wi). Errors as ll_bsdf_eval_dir but for the mode. */
LL_API ll_status ll_bsdf_pdf_dir(const ll_bsdf *b, const double wo[3], const double wi[3],
                                 const float *basis_coeffs, double *pdf);

/* Sample wi given wo as pbrt-v3's FourierBSDF::Sample_f does (same u gives
 * the same direction, to the solver's precision; u in [0, 1], both ends
 * included, as ll_bsdf_sample); writes wi (unit length, also when wo is
 * the normal: its azimuth is then taken from +x), its pdf (equal to
 * ll_bsdf_pdf_dir(wo, wi)) and f(wo, wi) (equal to ll_bsdf_eval_dir). pdf 0
 * and f 0 mean no direction (wi is then the normal). Errors as
 * ll_bsdf_eval_dir, and u outside [0, 1]. */
LL_API ll_status ll_bsdf_sample_dir(const ll_bsdf *b, const double wo[3], const double u[2],
                                    ll_transport mode, const float *basis_coeffs,
                                    double wi[3], double *pdf, double f_rgb[3]);

/* ------------------------------------------- renderer convention, batches */

/* The _dir calls over arrays, for wavefront renderers (one call per
 * wavefront). wo, wi, wi_out and rgb_out hold count packed 3-vectors
 * (element k at [3k, 3k + 3)), u count packed 2-vectors, pdf_out count
 * doubles. basis_coeffs: NULL (untextured file), or coeff_stride floats
 * per element (element k's weights at basis_coeffs + k * coeff_stride), or
 * coeff_stride 0 for one set of weights shared by all elements.
 *
 * Element k's outputs are bit-identical to the scalar call on element k
 * (ll_bsdf_eval_dir, ll_bsdf_pdf_dir, ll_bsdf_sample_dir), whatever the
 * thread count. An invalid element gets what the scalar call gives it
 * (zeros; wi_out the normal); the other elements are still computed, and
 * the batch then returns the status of the invalid element with the lowest
 * index, with that element's message in ll_last_error_message.
 * Before any element: LL_ERROR_INVALID_ARGUMENT for a NULL b, a NULL array
 * with count > 0, or sizes that overflow (nothing is written then).
 * count 0 is LL_OK. The calls allocate nothing on the heap.
 *
 * Threads: a batch of count >= 2048 is split into contiguous ranges of at
 * least 1024 elements over up to one POSIX thread per online processor
 * (the calling thread takes one range), or LAYERLAB_BATCH_THREADS (1..64)
 * threads if that environment variable is set. The calls are safe from any
 * number of threads at once, like the scalar calls. */
LL_API ll_status ll_bsdf_eval_dir_batch(const ll_bsdf *b, size_t count, const double *wo,
                                        const double *wi, ll_transport mode,
                                        const float *basis_coeffs, size_t coeff_stride,
                                        double *rgb_out);
LL_API ll_status ll_bsdf_pdf_dir_batch(const ll_bsdf *b, size_t count, const double *wo,
                                       const double *wi, const float *basis_coeffs,
                                       size_t coeff_stride, double *pdf_out);
LL_API ll_status ll_bsdf_sample_dir_batch(const ll_bsdf *b, size_t count, const double *wo,
                                          const double *u, ll_transport mode,
                                          const float *basis_coeffs, size_t coeff_stride,
                                          double *wi_out, double *pdf_out, double *rgb_out);

/* ------------------------------------------------------------ experimental
 * Declared only when the program defines LL_EXPERIMENTAL before including
 * this header. Not frozen: these declarations may change or go in a minor
 * release (their symbols are in the version node
 * LAYERLAB_READER_EXPERIMENTAL_1.0, and LAYERLAB_EXPERIMENTAL_1.0 in
 * liblayerlab), so a program that uses them is built against one release. */
#ifdef LL_EXPERIMENTAL

/* The validated tables of an opened file, as the evaluator reads them, for
 * renderers that evaluate the format themselves (e.g. traced into a GPU or
 * JIT kernel: python/layerlab/mitsuba_traced.py) without parsing the file a
 * second time. Const pointers into b: valid while b lives, never to be
 * written. Set struct_size = sizeof(ll_bsdf_tables) (the INIT macro does);
 * the library writes only the fields struct_size covers. n = n_nodes, nb =
 * n_bases; i the incident and o the outgoing node in the layer convention.
 *  nodes: [n] ascending (two at mu = 0);
 *  pairs: [2 (i n + o)] the first coefficient of pair (i, o)'s block in
 *    coeffs, [2 (i n + o) + 1] its series length (0: f is zero there);
 *  coeffs: [n_coeffs] floats; pair (i, o), channel c, basis k, order j at
 *    coeffs[offset + (c nb + k) length + j] (channels Y[, R, B]);
 *  cdf: [(i n + o) nb + k] the running integral over the outgoing nodes of
 *    a_0 of the luminance (the sampler's CDF rows, rounding dips already
 *    flattened as the reader stores them); a0: the same layout, a_0 itself;
 *  parameter_counts: [n_parameters] sample positions per textured
 *    parameter; parameter_positions: [n_parameter_values] those positions,
 *    parameter 0's first (NULL pointers and 0 counts for an untextured
 *    file). The scalars repeat ll_bsdf_info's so that one call suffices. */
typedef struct ll_bsdf_tables {
    size_t struct_size;
    size_t n_nodes;
    size_t n_channels;
    size_t n_bases;
    size_t max_order;
    size_t n_coeffs;
    size_t n_parameters;
    size_t n_parameter_values;
    double eta;
    const float *nodes;
    const uint32_t *pairs;
    const float *coeffs;
    const double *cdf;
    const double *a0;
    const uint32_t *parameter_counts;
    const float *parameter_positions;
} ll_bsdf_tables;

#define LL_BSDF_TABLES_INIT { sizeof(ll_bsdf_tables), 0, 0, 0, 0, 0, 0, 0, 0.0, NULL, NULL, \
                              NULL, NULL, NULL, NULL, NULL }

/* Fill *out with b's tables (above). LL_ERROR_INVALID_ARGUMENT for NULL
 * arguments or a struct_size smaller than the first field's end;
 * LL_ERROR_UNSUPPORTED for a table file (LL_BSDF_FORMAT_TABLES), which has
 * no Fourier tables. Thread-safe (b is immutable). */
LL_API ll_status ll_bsdf_get_tables(const ll_bsdf *b, ll_bsdf_tables *out);

#endif /* LL_EXPERIMENTAL */

#ifdef __cplusplus
}
#endif
#endif /* LAYERLAB_LL_BSDF_H */
