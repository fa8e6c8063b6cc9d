/*
 * Pieces of the table writer (ll_tables.h). Writer side only.
 */
#ifndef LL_BSDF_WRITE_TABLES_H
#define LL_BSDF_WRITE_TABLES_H

#include "layerlab/ll_tables.h"
#include "reader/bsdf_internal.h"
#ifndef LL_EXPERIMENTAL
#define LL_EXPERIMENTAL /* the library's build defines it for every file */
#endif
#include "layerlab/ll_tables.h"
#include "reader/tables_warp.h"
#include "support/watch.h"

#include <stdio.h>

/* Nodes of the NDF and sigma tables along u_theta (uniform in u_theta;
 * also the quadrature of the derivation). */
#define LL_TABLES_NDF_NODES 256

/* Steps 1 and 2 of a table (bsdf_write_tables_vndf.c), shared by the
 * opaque writer and the lobes of a transmissive one. ll_tables_ndf_warps:
 * D and sigma at the LL_TABLES_NDF_NODES nodes as float tables of two
 * equal rows (ndf_f and sigma_f, 2 LL_TABLES_NDF_NODES each) and the warps
 * that interpolate them exactly as a reader will. ll_tables_sigma_at:
 * sigma of the elevation theta through its warp. ll_tables_vndf_slice:
 * the visible-normal density of incident elevation theta over the
 * normal's nv x nv square, into out. ll_tables_get_float: the warps'
 * reader of a float table. */
LL_INTERNAL double ll_tables_get_float(const void *ctx, size_t i);
LL_INTERNAL ll_status ll_tables_ndf_warps(const double *d, const double *sigma, float *ndf_f,
                                          float *sigma_f, ll_warp2d *ndf_w, ll_warp2d *sigma_w);
LL_INTERNAL double ll_tables_sigma_at(const ll_warp2d *sigma_w, double theta);
LL_INTERNAL void ll_tables_vndf_slice(const ll_warp2d *ndf_w, const ll_warp2d *sigma_w,
                                      double theta, size_t nv, float *out);

/* The caller's monitor whole seen through one part of the work
 * (bsdf_write_tables_share.c): the part reports 0..1 for itself, whole
 * sees [lo, lo + width]. ll_tables_share_of sets sh's share and returns
 * the part's monitor, valid while sh lives. */
typedef struct ll_tables_share {
    ll_monitor whole;
    double lo, width;
} ll_tables_share;
LL_INTERNAL ll_monitor ll_tables_share_of(ll_tables_share *sh, double lo, double width);

/* Luminance of an RGB value (the Rec. 709 / sRGB weights Mitsuba uses). */
LL_INTERNAL double ll_tables_luminance(const double rgb[3]);

/* The edge of total internal reflection in a reflected set seen from the
 * denser side (bsdf_write_tables_edge.c). ll_tables_lone_interface:
 * whether b reflects alike from both sides at normal incidence, as a lone
 * interface does. ll_tables_edge_width: for the reflected set of side
 * bottom of b (lone: ll_tables_lone_interface(b)), the width in wi.h about
 * the critical cosine within which the .bsdf does not follow f, so that
 * the set's values there are continued from beside it and the figures
 * count those pairs apart; 0 for any other set. ll_tables_edge_near:
 * whether the pair (wi, wo), both above in the set's frame, lies within
 * that width of the edge of a smooth interface of relative index
 * fresnel_eta (< 1). */
LL_INTERNAL int ll_tables_lone_interface(const ll_bsdf *b);
LL_INTERNAL double ll_tables_edge_width(const ll_bsdf *b, int lone, int bottom);
LL_INTERNAL int ll_tables_edge_near(const double wi[3], const double wo[3], double fresnel_eta,
                                    double width);

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

/* The same for the reflection of the bottom side (side -1: the
 * retro-reflected direction below the surface), or the top (side 1). */
LL_INTERNAL ll_status ll_tables_derive_ndf_side(const ll_bsdf *b, int side, double *d,
                                                double *sigma, double *alpha);
/* The same for a reflected set of a transmissive stack that reflects
 * alike from both sides: where the fitted roughness is well above the
 * width of D's central peak (a sharp reflection on a broad pedestal of
 * light that came back through the stack), the mixture's lobes follow
 * the peak (bsdf_write_tables_ndf.c says how and why). *alpha receives
 * the fitted roughness all the same. */
LL_INTERNAL ll_status ll_tables_derive_ndf_pedestal(const ll_bsdf *b, int side, double *d,
                                                    double *sigma, double *alpha);
/* The same for the reflected set seen from the rarer side of a
 * transmissive stack that is not a lone interface (a coat over a medium
 * without a base): the mixture's peak lobe weighs more, so that the
 * coat's lobe at the pole of the normals keeps columns of the sample grid
 * at grazing viewers (bsdf_write_tables_ndf.c says why). */
LL_INTERNAL ll_status ll_tables_derive_ndf_coat(const ll_bsdf *b, int side, double *d,
                                                double *sigma, double *alpha);
/* The pieces of the derivation that the transmitted lobes' D shares
 * (bsdf_write_tables_tndf.c): the quadrature nodes theta_j = u_j^2 pi / 2
 * and their weights (sin theta included), sigma from D at the nodes, and
 * Beckmann's D. */
LL_INTERNAL void ll_tables_ndf_quadrature(size_t n, double *theta, double *w);
LL_INTERNAL void ll_tables_projected_area(size_t n, const double *theta, const double *w,
                                          const double *d, double *sigma);
LL_INTERNAL double ll_tables_beckmann(double theta, double alpha);

/* f (without cosine, importance transport: the .bsdf's own values) of b
 * at a pair in a lobe's frame, where the fixed direction wi lies above:
 * bottom negates both z before evaluating (bsdf_write_tables_lobes.c). 0
 * where the evaluation fails. */
LL_INTERNAL void ll_tables_lobe_f(const ll_bsdf *b, int bottom, const double wi[3],
                                  const double wo[3], double f[3]);
/* D and sigma at the LL_TABLES_NDF_NODES nodes for a transmitted lobe
 * (bsdf_write_tables_tndf.c): from its density over the half vector at
 * normal incidence; refract_eta > 0 the refraction warp's relative index,
 * 0 the warp of the z-flipped direction; heavy_floor: the set is seen from
 * the denser side of a lone interface or crosses no net interface (eta 1),
 * where the flipped warp takes a heavier floor; sweep: the set is seen
 * from the rarer side of a lone interface, where the flipped warp's D
 * follows the lobe over the incident elevations (bsdf_write_tables_tndf.c
 * says why). LL_ERROR_INVALID_ARGUMENT if the lobe transmits nothing at
 * normal incidence. */
LL_INTERNAL ll_status ll_tables_derive_transmit_ndf(const ll_bsdf *b, int bottom,
                                                    double refract_eta, int heavy_floor,
                                                    int sweep, double *d, double *sigma,
                                                    double *alpha);
/* s as JSON text (quotes and escapes) at buf[at], cap bytes at most
 * written; returns the end it would have without the cap. */
LL_INTERNAL size_t ll_tables_json_string(char *buf, size_t at, size_t cap, const char *s);
/* Whether b transmits light (eta != 1, or transmitted series beyond a
 * millionth of the reflected). */
LL_INTERNAL int ll_tables_transmits(const ll_bsdf *b);
/* The tables of every lobe of a transmissive b, both sides
 * (bsdf_write_tables_lobes.c), at the grid opts gives; as
 * ll_tables_write_grid with half set: the VNDF, luminance and values of
 * every set are stored as float16. */
LL_INTERNAL ll_status ll_tables_write_lobes(const ll_bsdf *b, const char *path,
                                            const ll_tables_options *opts, const char *figures,
                                            const ll_monitor *monitor);

/* The values of a spectral table file (bsdf_write_tables_spectra.c): per
 * wavelength, f cos of the source's file at the sample nodes, whose
 * directions and jacobian factors geom holds (per slice t and node q of
 * the N x N square, 4 doubles: wo, then 4 sigma(wi) / D(m) times nothing
 * else, 0 where wo is below the horizon). The values go to a scratch file,
 * wavelength after wavelength; fill copies them out in the file's order
 * [theta_i][wavelength][N][N]. */
typedef struct ll_tables_spectra {
    size_t n_ti, plane, n_l;       /* slices, N * N, wavelengths         */
    const double *wavelengths;     /* [n_l], nm                          */
    const float *theta_i;          /* [n_ti]                             */
    const double *geom;            /* [n_ti * plane * 4]                 */
    FILE *scratch;                 /* tmpfile(), [n_l][n_ti][plane] floats */
    const ll_warp2d *ndf_w, *vndf_w, *sigma_w; /* the warp, for the horizon fit */
} ll_tables_spectra;

/* Every wavelength's values (source(user, l, lambda) opened, evaluated,
 * released, one at a time) into the scratch file, and into lum (n_ti *
 * plane, zeroed here) their luminance: the Y of the spectrum lit by D65,
 * seen by the CIE 1931 observer (uniform weights when the wavelengths see
 * none). watch advances by one per wavelength. fn names the caller. */
LL_INTERNAL ll_status ll_tables_spectra_run(ll_tables_spectra *sp, ll_tables_spectrum_fn source,
                                            void *user, float *lum, ll_watch *watch,
                                            const char *fn);
/* ll_tensor_out_field.fill of the "spectra" field: block b = t * n_l + l. */
LL_INTERNAL ll_status ll_tables_spectra_fill(void *ctx, size_t block, float *out);
LL_INTERNAL void ll_tables_spectra_close(ll_tables_spectra *sp);

/* ll_tables_write_from_bsdf at the grid opts gives (a size of 0 takes
 * 32, 128 or 64; the tolerance is not read): one table, no measurement.
 * figures (nullable): JSON members ending in ", " that the metadata field
 * holds after the grid. half: the opaque b's tables for a textured file,
 * whose VNDF, luminance and values are stored as float16: each rounded to
 * float16 where it is made (the VNDF before the warp built from it), in a
 * float32 file that converts to float16 exactly. */
LL_INTERNAL ll_status ll_tables_write_grid(const ll_bsdf *b, const char *path,
                                           const ll_tables_options *opts, const char *figures,
                                           int half, const ll_monitor *monitor);

/* The smallest positive float16 (a subnormal): a float16 table's
 * luminance floor stays above it, so that rounding keeps it positive. */
#define LL_TABLES_HALF_TINY 0x1p-24
/* The n values v rounded to float16 in place; LL_ERROR_INVALID_ARGUMENT,
 * naming the table, if one lies beyond float16's range. */
LL_INTERNAL ll_status ll_tables_round_half(float *v, size_t n, const char *table);

/* ll_tables_write_from_bsdf of the untextured, opaque b (one basis of a
 * textured file) with its grids rounded to float16 as
 * ll_tables_write_grid's half says, the tolerance measured on the
 * rounded tables (bsdf_write_tables_search.c). */
LL_INTERNAL ll_status ll_tables_write_half(const ll_bsdf *b, const char *path,
                                           const ll_tables_options *opts,
                                           const ll_monitor *monitor);

/* The reflected (r) and transmitted (t, 0 unless transmissive) albedo per
 * channel of b for the viewer wo, radiance transport: the integrals of f
 * |cos| over wo's hemisphere and the other, by quadrature of
 * ll_bsdf_eval_dir (bsdf_write_tables_albedo.c says how and how closely);
 * peak[0] and peak[1] the elevations from the normal (0..pi/2) of the
 * reflected and the transmitted lobe's peak, where the quadrature is
 * finest. Deterministic, and the same for any thread count. LL_OK,
 * LL_ERROR_OUT_OF_MEMORY, or the status of a failed evaluation. */
LL_INTERNAL ll_status ll_tables_albedo(const ll_bsdf *b, const double wo[3], const double peak[2],
                                       int transmissive, double r[3], double t[3]);

/* How far table is from src (the figures of the tolerance, ll_tables.h),
 * per channel, all channels pooled: the worst albedo ratio's distance from
 * 1 over viewer elevations 0..85 degrees (R and T apart, on both sides for
 * a transmissive src; a lobe under 1% of R + T not counted), and the
 * median, 95th and 99th percentiles of the relative error of f where f cos
 * is above 1% of its largest value (both elevations <= 80 degrees, half of
 * the pairs near the mirror direction). ref: src's albedos
 * (ll_tables_reference), measured once for every table of a search. LL_OK,
 * LL_ERROR_OUT_OF_MEMORY, or the status of a failed evaluation. */
/* The viewer elevations of the albedo figure: 0, 10, .., 80, 85 degrees. */
#define LL_TABLES_ANGLES 10
typedef struct ll_tables_figures {
    double albedo, p50, p95, p99;
} ll_tables_figures;
typedef struct ll_tables_source {
    double albedo[2][LL_TABLES_ANGLES][6]; /* [bottom][viewer elevation][R, T rgb] */
} ll_tables_source;
LL_INTERNAL ll_status ll_tables_reference(const ll_bsdf *src, ll_tables_source *ref);
/* The same albedos of b (src, or a table of it) by the same quadrature,
 * finest where src's lobes peak: ll_tables_reference is b = src. The
 * viewer elevations, in degrees: ll_tables_angles_deg. */
LL_INTERNAL ll_status ll_tables_albedos(const ll_bsdf *b, const ll_bsdf *src,
                                        ll_tables_source *out);
LL_INTERNAL extern const double ll_tables_angles_deg[LL_TABLES_ANGLES];
LL_INTERNAL ll_status ll_tables_measure(const ll_bsdf *src, const ll_tables_source *ref,
                                        const ll_bsdf *table, ll_tables_figures *out);

/* The nodes of one slice's sample grid (ns x ns, n_ch planes of values,
 * 1..LL_TABLES_HORIZON_CHANNELS, each its own array) whose directions are below the horizon
 * (below[q] != 0) and that touch a node above it: set per channel so that
 * the slice's albedo of that channel is its targets[c]; where a channel is
 * too bright without them, that channel scaled down to it; a channel whose
 * target is 0 keeps its values (bsdf_write_tables_horizon.c). The planes
 * share the slice's weights, computed once: RGB and the luminance fitted
 * in one call. The slice as a reader sees it: */
#define LL_TABLES_HORIZON_CHANNELS 4
typedef struct ll_tables_horizon {
    const ll_warp2d *ndf_w, *vndf_w; /* D and the visible normals' warp      */
    double sigma;                    /* sigma of the slice's elevation       */
    double param[2];                 /* the VNDF warp's parameters: 0, theta */
    double fresnel_eta;              /* > 0: the index of F for the planes
                                        over_f names (a set's "fresnel_eta"),
                                        0: no plane stored over F           */
    double fresnel_floor;            /* with fresnel_eta > 0: those planes
                                        are over (F + q) / (1 + q), q this
                                        k times D(0) / D(m) by ndf_w (a
                                        set's "fresnel_floor", 0: F)       */
    unsigned over_f;                 /* bit c set: plane c is stored over F
                                        (a reflected set's RGB, not its
                                        luminance), read if fresnel_eta > 0 */
} ll_tables_horizon;
LL_INTERNAL ll_status ll_tables_horizon_fit(const ll_tables_horizon *h, size_t ns,
                                            const unsigned char *below, size_t n_ch,
                                            const double *targets, float *const *planes);
/* The fit above of a slice of an RGB table, the one both the opaque and
 * the transmissive writer make: R, G and B (rgb, three planes) to
 * target per channel, and the luminance (lum, what sampling follows) as a
 * plane of its own to the luminance of target (bsdf_write_tables_horizon.c
 * says why); with h->fresnel_eta > 0 the RGB planes are stored over F and
 * the luminance is not (h->over_f is not read). */
LL_INTERNAL ll_status ll_tables_horizon_fit_rgb(const ll_tables_horizon *h, size_t ns,
                                                const unsigned char *below,
                                                const double target[3], float *rgb,
                                                float *lum);
/* The slice's albedo of one stored plane (ns x ns) as the fit integrates
 * it: stored value times the square's area element in f cos d omega,
 * times F (or (F + q) / (1 + q), q = k D(0) / D(m), k h->fresnel_floor,
 * D h->ndf_w) if over_f and
 * h->fresnel_eta > 0; below as for the fit (which
 * cells cross the horizon). What a test holds a written slice to. */
LL_INTERNAL double ll_tables_horizon_albedo(const ll_tables_horizon *h, size_t ns,
                                            const unsigned char *below, const float *plane,
                                            int over_f);
/* The reflected (or, if transmitted, the transmitted) albedo per channel
 * of the untextured b at incident elevation theta, seen from below if
 * bottom (ll_bsdf_albedo), into out; 0 if b is a table file, which has
 * none (its slices are then not fitted). */
LL_INTERNAL ll_status ll_tables_horizon_target(const ll_bsdf *b, double theta, int bottom,
                                               int transmitted, double out[3]);

/* Basis k of the textured b as an untextured handle of its own (its
 * coefficients and per-row tables copied; release it with
 * ll_bsdf_release): bsdf_write_tables_basis.c. */
LL_INTERNAL ll_status ll_tables_basis_view(const ll_bsdf *b, size_t k, ll_bsdf **out);

/* ll_tables_write_from_bsdf of a textured b (opts read and complete): a
 * table set per basis (bsdf_write_tables_textured.c). */
LL_INTERNAL ll_status ll_tables_write_textured(const ll_bsdf *b, const char *path,
                                               const ll_tables_options *opts,
                                               const ll_monitor *monitor);

#endif /* LL_BSDF_WRITE_TABLES_H */
