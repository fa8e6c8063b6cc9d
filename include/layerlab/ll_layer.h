/*
 * layerlab — layers: the scattering matrices of one slab or interface, per
 * Fourier order of the azimuth, and the adding-doubling method that combines
 * them (Jakob, d'Eon, Jakob, Marschner: "A Comprehensive Framework for
 * Rendering Layered Materials", SIGGRAPH 2014, sections 4-6).
 *
 * Conventions (the original layerlab's):
 *  - mu is a zenith cosine of a *direction of travel*: mu > 0 travels down
 *    (light arriving from above the layer), mu < 0 travels up. A layer lit
 *    from above reflects into mu < 0 and transmits into mu > 0.
 *  - phi_d is the difference between the azimuths of the two directions of
 *    travel (the original layerlab's convention): at phi_d = 0 their
 *    horizontal components point the same way. So a mirror sends mu_i to
 *    mu_o = -mu_i at phi_d = 0, light passing straight through keeps
 *    phi_d = 0, and phi_d = pi is backscattering.
 *  - Arguments name the known direction first: (mu_i, mu_o, phi_d), light
 *    arriving along mu_i and leaving along mu_o, as ll_bsdf_eval.
 *  - f(mu_i, mu_o, phi) = sum_l f_l(mu_i, mu_o) cos(l phi); each order l is
 *    an n x n matrix with four h x h blocks (h = n / 2): rows = outgoing,
 *    columns = incident, R^t (lit from above, reflected up), R^b, T^tb
 *    (lit from above, transmitted down) and T^bt.
 *  - Long calls take a monitor (ll_common.h) as their last argument,
 *    nullable: stage names and what a cancel leaves are stated per call; a
 *    cancelled call returns LL_ERROR_CANCELLED and leaves its output layer
 *    exactly as it was.
 *
 * Ownership and threads: an ll_layer is created by ll_layer_create or
 * ll_layer_clone and freed by ll_layer_destroy. A layer may be read (eval,
 * matrix, albedo) from many threads at once; calls that modify a layer need
 * exclusive access to it. Internally, adding, doubling and interface
 * construction use ll_get_thread_count() threads; results are identical for
 * any thread count. Every setter and combination either succeeds or leaves
 * its output layer exactly as it was.
 */
#ifndef LAYERLAB_LL_LAYER_H
#define LAYERLAB_LL_LAYER_H

#include "ll_common.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ----------------------------------------------------------------- threads
 * The number of worker threads that layerlab calls made *from the calling
 * thread* may use (adding, doubling, building interfaces). 0 means all
 * processors (the default). Results never depend on this number: they are
 * bit-identical for any thread count. The setting is per calling thread, so
 * two renderer threads can use different counts without locking. The
 * worker threads a calling thread starts stay, asleep, until that thread
 * exits.
 * LL_ERROR_INVALID_ARGUMENT (the setting unchanged) above 4096 threads. */
LL_API ll_status ll_set_thread_count(size_t n_threads);
/* The effective count for the calling thread (>= 1): its setting, or the
 * number of processors when that is 0. */
LL_API size_t ll_get_thread_count(void);

typedef struct ll_layer ll_layer;

/* ------------------------------------------------------------ life cycle */

/* Create a layer on the given zenith-cosine discretisation: n_nodes nodes
 * in [-1, 1] (even count >= 2, no node at 0, finite, distinct, symmetric
 * about 0: the nodes of a quadrature rule), their integration weights
 * (positive, finite), and n_orders >= 1 Fourier orders. Nodes may be given
 * in ascending order (as the ll_quad_* rules write them). The new layer is
 * clear: no reflection, full transmission (R = 0, T = I for every order).
 * *out receives the layer, or NULL on failure; the caller frees it with
 * ll_layer_destroy. LL_ERROR_INVALID_ARGUMENT for NULL pointers or nodes,
 * weights or counts outside the rules above, LL_ERROR_OUT_OF_MEMORY. */
LL_API ll_status ll_layer_create(const double *nodes, const double *weights,
                                 size_t n_nodes, size_t n_orders, ll_layer **out);

/* A deep copy into *out (NULL on failure; freed by ll_layer_destroy):
 * internally, unchanged Fourier orders are shared copy-on-write, so a clone
 * is cheap, and either layer may then be changed without the other seeing
 * it. LL_ERROR_INVALID_ARGUMENT for NULL arguments, LL_ERROR_OUT_OF_MEMORY. */
LL_API ll_status ll_layer_clone(const ll_layer *layer, ll_layer **out);

/* Free a layer; NULL is fine. */
LL_API void ll_layer_destroy(ll_layer *layer);

/* Number of zenith-cosine nodes n, and of Fourier orders m. 0 for NULL. */
LL_API size_t ll_layer_node_count(const ll_layer *layer);
LL_API size_t ll_layer_order_count(const ll_layer *layer);

/* Copy the nodes and weights in ascending node order (as given to
 * ll_layer_create). Either buffer may be NULL; each holds node_count values.
 * LL_ERROR_INVALID_ARGUMENT for a NULL layer. */
LL_API ll_status ll_layer_get_nodes(const ll_layer *layer, double *nodes, double *weights);

/* Number of matrix entries actually stored (over all orders and blocks);
 * the rest are zero. A measure of memory use: about 8 bytes each. */
LL_API size_t ll_layer_stored_count(const ll_layer *layer);

/* ----------------------------------------------------------------- words
 * Each setter replaces the layer's contents, keeping its nodes and order
 * count. Statuses: LL_ERROR_INVALID_ARGUMENT for a NULL layer or a
 * parameter outside the range given, LL_ERROR_OUT_OF_MEMORY,
 * LL_ERROR_CANCELLED by the monitor; on any failure the layer is
 * unchanged. */

/* Lambertian reflector with the given albedo in [0, 1] on both sides:
 * f = albedo / pi on the reflection blocks, Fourier order 0 only, no
 * transmission. O(n^2). Stage "diffuse", one unit per column. */
LL_API ll_status ll_layer_set_diffuse(ll_layer *layer, double albedo, const ll_monitor *monitor);

/* The media: phase functions of an infinitesimally thin medium with
 * single-scattering albedo in [0, 1]; ll_layer_expand gives one a
 * thickness. Stage "phase function", one unit per Fourier order; every
 * worker polls within one node row of an order's construction and between
 * its BLAS products.
 *
 * Isotropic: p = albedo / (4 pi). */
LL_API ll_status ll_layer_set_isotropic(ll_layer *layer, double albedo,
                                        const ll_monitor *monitor);

/* Henyey-Greenstein phase function with asymmetry g in (-1, 1).
 * The phase matrices are built from the Legendre expansion of the phase
 * function (chi_k = g^k) truncated with the delta-M method (Wiscombe 1977)
 * at as many terms as the quadrature integrates exactly; the truncated
 * forward peak is kept as an exact forward (identity) term. This makes the
 * discrete scattering conserve energy exactly and matches discrete-ordinate
 * codes such as DISORT, where pointwise sampling of a peaked phase function
 * would lose energy. */
LL_API ll_status ll_layer_set_henyey_greenstein(ll_layer *layer, double albedo, double g,
                                                const ll_monitor *monitor);

/* von Mises-Fisher phase function p ~ exp(kappa cos theta), kappa >= 0
 * (kappa = 0 is isotropic); same construction as Henyey-Greenstein. */
LL_API ll_status ll_layer_set_von_mises_fisher(ll_layer *layer, double albedo, double kappa,
                                               const ll_monitor *monitor);

/* A rough interface between the medium above and one of relative index
 * eta = eta_re + i eta_im below. eta_im > 0: a conductor (opaque, reflects
 * on both sides as seen from above); eta_im == 0: a dielectric (reflects and
 * transmits; eta_re < 1 is allowed; eta_re == 1 is no interface at all and
 * makes the layer clear). Light from below sees the relative index 1/eta.
 *
 * distribution: the microfacet distribution, LL_MICROFACET_BECKMANN (the
 * paper's) or LL_MICROFACET_GGX (Trowbridge-Reitz, the distribution of
 * current renderers and material standards), both as in Walter et al. 2007.
 *
 * alpha is the roughness; alpha below LL_MICROFACET_MIN_ALPHA is rejected:
 * the Fourier series of a smoother interface would need more orders than
 * any layer can hold.
 *
 * compensate != 0 adds the paper's multiple-scattering compensation to
 * order 0 (recommended: on): the energy that single scattering loses to
 * shadowing returns as a low-rank term. For a dielectric it is split
 * between reflection and transmission (eta^2-reciprocal) by the share of
 * the lost light that leaves on either side, tabulated from a random walk
 * on the Smith microsurface; for a conductor it is coloured by the Fresnel
 * reflectance of the facets where each direction loses it and of the
 * bounces after, fitted to the same walk (docs/method.md, "Energy
 * compensation against a random walk"). A non-absorbing dielectric then
 * conserves energy (R + T = 1 per incident direction) wherever its lobes
 * are resolved, and so does a conductor with F = 1.
 *
 * n_orders_internal: the Fourier orders the lobes are resolved with, at
 * least the layer's (0 = the layer's). A lobe sharper than that many orders
 * can hold (grazing angles) is widened as in the original layerlab, but
 * keeping the true lobe's energy. */
typedef enum ll_microfacet_distribution {
    LL_MICROFACET_BECKMANN = 0,
    LL_MICROFACET_GGX = 1
} ll_microfacet_distribution;

#define LL_MICROFACET_MIN_ALPHA 1e-3

typedef struct ll_microfacet {
    size_t struct_size;       /* sizeof(ll_microfacet)                              */
    double eta_re, eta_im;    /* relative index below / above; eta_im > 0: conductor */
    double alpha;             /* roughness, >= LL_MICROFACET_MIN_ALPHA               */
    int distribution;         /* an ll_microfacet_distribution                       */
    int compensate;           /* non-zero: the multiple-scattering compensation      */
    size_t n_orders_internal; /* 0: the layer's                                      */
} ll_microfacet;

#define LL_MICROFACET_INIT \
    { sizeof(ll_microfacet), 1.5, 0.0, 0.1, LL_MICROFACET_BECKMANN, 1, 0 }

/* The interface of *microfacet on the layer's nodes. The BSDF is the
 * original layerlab's (microfacet.cpp), in the layer's conventions: the
 * distribution D with roughness alpha, Smith shadowing (Beckmann: Walter's
 * rational approximation of G1; GGX: its exact closed form), unpolarised Fresnel reflectance (ll_fresnel_* at the
 * microfacet), and Walter's refraction Jacobian including eta^2, so that
 * the transmission blocks obey f_bt(a, b) = f_tb(b, a) / eta^2 (radiance,
 * not importance).
 *
 * Resolution: in mu the lobes are sampled at the nodes. A lobe narrower
 * than the node spacing (alpha too small for n, or a refracted lobe of
 * width ~ alpha |eta - 1| / eta for eta near 1) is not resolved, and
 * directional albedos can then exceed 1 by any amount, most at the nodes
 * mu = +-1. ll_resolution_search_microfacet chooses a resolution that
 * resolves them.
 *
 * The azimuthal series are truncated after the last term above 1e-3 of
 * the first. Interfaces are built in parallel over incident directions.
 * Stage "interface": the fits of the series (a tenth), the columns (most
 * of it, one unit per incident node), the energy compensation; every
 * worker polls once per node pair of its column. Returns
 * LL_ERROR_INVALID_ARGUMENT (NULL layer or microfacet, a field out of
 * range) or LL_ERROR_OUT_OF_MEMORY; on failure
 * the layer is unchanged. */
LL_API ll_status ll_layer_set_microfacet(ll_layer *layer, const ll_microfacet *microfacet,
                                         const ll_monitor *monitor);

/* A measured isotropic BRDF in the MERL format ("Matusik et al. 2003",
 * .binary files), colour channel 0, 1 or 2 (R, G, B). The file's values are
 * multiplied by the MERL scale factors (1/1500, 1.15/1500, 1.66/1500) which
 * give reflectance in units of 1/sr. n_orders_internal as for
 * ll_microfacet. Stage "measured": reading the file, then one unit per
 * incident node; workers poll once per outgoing node. LL_ERROR_IO when the
 * file cannot be read, LL_ERROR_FORMAT when it is not a MERL table,
 * LL_ERROR_INVALID_ARGUMENT (NULL arguments, channel), LL_ERROR_OUT_OF_MEMORY,
 * LL_ERROR_CANCELLED; the layer is unchanged on failure. */
LL_API ll_status ll_layer_set_matusik(ll_layer *layer, const char *path, int channel,
                                      size_t n_orders_internal, const ll_monitor *monitor);

/* ------------------------------------------------------------- grammar */

/* Adding equations (Grant and Hunt 1969): out = top stacked on bottom.
 * top, bottom and out must have the same nodes and order count; out may be
 * top or bottom (or both). homogeneous != 0 promises that top and bottom are
 * the same symmetric slab (R^t = R^b, T^tb = T^bt), which halves the work.
 * Each Fourier order: one LU factorisation per gain matrix, then solves and
 * products (LAPACK getrf/getrs, BLAS gemm), orders in parallel. Stage
 * "adding", one unit per Fourier order; workers poll between the O(h^3)
 * BLAS/LAPACK calls of each order (h = n / 2). LL_ERROR_INVALID_ARGUMENT
 * for NULL or mismatched layers, LL_ERROR_NUMERICAL when a gain matrix
 * I - R R is singular (two non-absorbing perfect reflectors facing each
 * other), LL_ERROR_OUT_OF_MEMORY, LL_ERROR_CANCELLED; out is unchanged on
 * failure. */
LL_API ll_status ll_layer_add(const ll_layer *top, const ll_layer *bottom, ll_layer *out,
                              int homogeneous, const ll_monitor *monitor);

/* layer = top stacked on layer (ll_layer_add without a monitor; its
 * statuses). */
LL_API ll_status ll_layer_add_to_top(ll_layer *layer, const ll_layer *top);
/* layer = layer stacked on bottom (ll_layer_add without a monitor; its
 * statuses). */
LL_API ll_status ll_layer_add_to_bottom(ll_layer *layer, const ll_layer *bottom);

/* Thickness: the layer holds a phase function (set_isotropic, set_henyey_
 * greenstein, set_von_mises_fisher); turn it into a slab of optical
 * thickness tau >= 0 (tau = 0 gives a clear layer). By doubling: a thin
 * slab tau0 <= min(2 min|mu|, 2^-15) chosen so that tau0 2^k = tau exactly,
 * added to itself k times; or by the closed form that doubling converges
 * to (one symmetric eigendecomposition per Fourier order, the
 * discrete-ordinate method of DISORT), whichever costs less for the node
 * count and k: the same choice for any data and thread count (method.md,
 * "Thickening a medium: the slab or doubling"). Stage "doubling", one unit
 * per doubling step of each Fourier order; workers poll before every
 * doubling step and between its BLAS/LAPACK calls (the closed form: before
 * every order). A cancel leaves the phase function, not a partial slab.
 * LL_ERROR_INVALID_ARGUMENT for a NULL layer or a tau that is negative,
 * not finite or beyond 1e12, LL_ERROR_OUT_OF_MEMORY, LL_ERROR_NUMERICAL,
 * LL_ERROR_CANCELLED; the layer is unchanged on failure. */
LL_API ll_status ll_layer_expand(ll_layer *layer, double tau, const ll_monitor *monitor);

/* Turn the layer upside down (swap top and bottom). LL_ERROR_INVALID_ARGUMENT
 * for NULL, LL_ERROR_OUT_OF_MEMORY (the layer then unchanged). */
LL_API ll_status ll_layer_reverse(ll_layer *layer);

/* Make the layer clear (R = 0, T = I). LL_ERROR_INVALID_ARGUMENT for NULL,
 * LL_ERROR_OUT_OF_MEMORY (the layer then unchanged). */
LL_API ll_status ll_layer_clear(ll_layer *layer);

/* ------------------------------------------------------------- reading */

/* *f = the BSDF value f(mu_i, mu_o, phi_d) without cosine factor,
 * interpolated between nodes with Catmull-Rom splines in mu and summed over
 * Fourier orders; negative results clamp to 0. LL_ERROR_INVALID_ARGUMENT
 * for a NULL layer or f, or a NaN argument (then *f = 0). */
LL_API ll_status ll_layer_eval(const ll_layer *layer, double mu_i, double mu_o, double phi_d,
                               double *f);

/* Vectorised ll_layer_eval: out[k] = f(mu_i[k], mu_o[k], phi_d[k]) for
 * k < count. phi_d may be NULL (0 everywhere). LL_ERROR_INVALID_ARGUMENT
 * for a NULL layer or a NULL array other than phi_d. */
LL_API ll_status ll_layer_eval_many(const ll_layer *layer, size_t count, const double *mu_i,
                                    const double *mu_o, const double *phi_d, double *out);

/* The n x n BSDF matrix of Fourier order `order`, integration weights and
 * cosine factors removed (values of f_l), rows (outgoing) and columns
 * (incident) in ascending node order, stored row-major:
 * out[row * n + col]. out holds n * n doubles. LL_ERROR_INVALID_ARGUMENT
 * for NULL arguments or an order not below ll_layer_order_count. */
LL_API ll_status ll_layer_matrix(const ll_layer *layer, size_t order, double *out);

/* Directional-hemispherical totals for light travelling in direction mu_i
 * (mu_i > 0: arriving from above; mu_i < 0: from below), |mu_i| in (0, 1]:
 * the fraction reflected and the fraction transmitted, the unscattered
 * part of the transmission included. Either output may be NULL.
 * LL_ERROR_INVALID_ARGUMENT for a NULL layer or mu_i out of range. */
LL_API ll_status ll_layer_albedo(const ll_layer *layer, double mu_i, double *reflectance,
                                 double *transmittance);

/* ---------------------------------------------------------- resolution
 * The resolution (even node count n, Fourier orders m) a word needs. Two
 * kinds of call: the heuristics are instant fits; the resolution searches
 * measure the convergence and take up to seconds. */

/* Fit for a Henyey-Greenstein medium with asymmetry g in (-1, 1): the
 * original layerlab's parameterHeuristicHG, n = 8.6 / (1 - |g|) - 0.2,
 * m = 5.4 / (1 - |g|) - 1.3. Instant. LL_ERROR_INVALID_ARGUMENT for g
 * outside (-1, 1) or NULL outputs. */
LL_API ll_status ll_heuristic_henyey_greenstein(double g, size_t *n_nodes, size_t *n_orders);

/* Fit for a rough interface: the paper's fits (the original's
 * parameterHeuristicMicrofacet), n or m = max(A + B ln(alpha)^4 alpha,
 * C + D alpha^-1.2), alpha clamped to 1, extended to every eta:
 *  - conductors (eta_im > 0) use the generic conductor fit;
 *  - a dielectric is the same from both sides, so eta < 1 uses 1/eta;
 *  - between the fitted eta = 1.1, 1.3, 1.5, 1.7, n and m are interpolated
 *    linearly in eta (the original takes the larger neighbour);
 *  - above 1.7 the 1.7 fit holds: a denser medium widens the refracted
 *    lobe, and the reflected lobe, now the narrowest, does not change;
 *  - below 1.1 the refracted lobe narrows like (eta - 1) / eta, so the 1.1
 *    fit is evaluated at alpha times (eta - 1) / eta / (0.1 / 1.1), with
 *    eta taken as at least 1.05 (a narrower lobe exceeds any practical
 *    resolution and is widened by ll_layer_set_microfacet); eta = 1
 *    exactly is no interface: (2, 1).
 * The fits do not see the narrow azimuthal lobes of grazing pairs: a first
 * guess, which ll_resolution_search_microfacet verifies. Instant. alpha >=
 * LL_MICROFACET_MIN_ALPHA. LL_ERROR_INVALID_ARGUMENT also when the result
 * would exceed what a layer can hold. */
LL_API ll_status ll_heuristic_microfacet(double alpha, double eta_re, double eta_im,
                                         size_t *n_nodes, size_t *n_orders);

/* Resolution chosen by a stated tolerance (docs/method.md, "Resolution").
 * The searches return the smallest (n, m) found whose layer agrees with
 * the same layer at (2n, 2m) within `tolerance` (relative) wherever the
 * BSDF there is above 1% of the peak of its lobe (one incident direction
 * and one block: reflection or transmission), measured with
 * ll_layer_eval's interpolation on fixed probe directions with |mu| >=
 * mu_min: the grazing cosines mu_min, 1.5 mu_min, 2 mu_min, mirror and
 * refracted directions and offsets around them, azimuths 0 .. pi, and
 * pseudo-random ones. tolerance 0 means LL_DEFAULT_TOLERANCE, otherwise it
 * lies in [LL_MIN_TOLERANCE, 1); mu_min 0 means LL_DEFAULT_MU_MIN,
 * otherwise it lies in (0, 1]. The probes accept at 0.6 of the tolerance,
 * a margin for the directions between them. error (nullable) receives the
 * difference measured at the answer (<= 0.6 tolerance), or HUGE_VAL when
 * the answer is the fit, unverified (stated per search below).
 * Deterministic; the same answer for any thread count. Stage "resolution".
 * The series are evaluated at the probes' spline stencils only, yet a
 * search takes up to seconds of CPU. LL_ERROR_INVALID_ARGUMENT (and the
 * error reached) when the tolerance is not met within the search's limit. */
#define LL_DEFAULT_TOLERANCE 0.01
#define LL_DEFAULT_MU_MIN 0.1
#define LL_MIN_TOLERANCE 1e-3

/* Rough interface *microfacet (its n_orders_internal is not used). The
 * fit is the first guess of n only; m starts at what the probes' own
 * azimuthal series need (the most grazing pair that matters sets it), then
 * both are grown until the comparison with (2n, 2m) passes and shrunk
 * while it still does. The layer compared is ll_layer_set_microfacet's
 * with microfacet->compensate. Limit: 100000 nodes or orders. Where the fit
 * asks for more than 8000 nodes the fit is returned unverified. */
LL_API ll_status ll_resolution_search_microfacet(const ll_microfacet *microfacet,
                                                 double tolerance, double mu_min,
                                                 const ll_monitor *monitor, size_t *n_nodes,
                                                 size_t *n_orders, double *error);

/* Henyey-Greenstein medium, g in (-1, 1): the convergence of the phase
 * function's own layer (ll_layer_set_henyey_greenstein, the single-
 * scattering lobe; a slab's multiple scattering is smoother), the fit the
 * first guess of both n and m, compared without the delta-M forward term
 * (a delta, not a lobe: docs/method.md, "Resolution"). Limit: 4000 nodes
 * or orders. Beyond |g| = 0.95 the fit is returned unverified. */
LL_API ll_status ll_resolution_search_henyey_greenstein(double g, double tolerance,
                                                        double mu_min,
                                                        const ll_monitor *monitor,
                                                        size_t *n_nodes, size_t *n_orders,
                                                        double *error);

/* ------------------------------------------------------------- Fresnel
 * Thread-safe. LL_ERROR_INVALID_ARGUMENT for an argument out of range or
 * NaN, or a NULL output; the outputs are then 0. */

/* Unpolarised Fresnel reflectance of a smooth dielectric boundary with
 * relative index eta > 0 (transmitted side / incident side) for light
 * arriving with cos_theta_i in [-1, 1] (the sign chooses the side:
 * cos_theta_i < 0 means the light arrives from the other side, where the
 * relative index is 1/eta). cos_theta_t (nullable) receives the cosine of
 * the refracted direction with the sign of the side it leaves into (the
 * opposite of cos_theta_i), 0 under total internal reflection (reflectance
 * 1). */
LL_API ll_status ll_fresnel_dielectric(double cos_theta_i, double eta, double *reflectance,
                                       double *cos_theta_t);

/* Unpolarised Fresnel reflectance of a conductor of complex relative index
 * eta_re + i eta_im (both >= 0, not both 0; eta_im = 0 is a dielectric),
 * cos_theta_i in [0, 1]. */
LL_API ll_status ll_fresnel_conductor(double cos_theta_i, double eta_re, double eta_im,
                                      double *reflectance);

/* Hemispherical averages 2 * integral_0^1 F(mu) mu dmu: the fraction of
 * uniformly diffuse light that the boundary reflects (accurate to about
 * 1e-14, by tanh-sinh quadrature). For a dielectric, light arriving from
 * the side where the relative index is eta. */
LL_API ll_status ll_fresnel_dielectric_average(double eta, double *average);
LL_API ll_status ll_fresnel_conductor_average(double eta_re, double eta_im, double *average);

#ifdef __cplusplus
}
#endif
#endif /* LAYERLAB_LL_LAYER_H */
