/*
 * The azimuthal Fourier series of the rough (Beckmann or GGX microfacet) interface
 * for one pair of zenith cosines: the engine of ll_layer_set_microfacet,
 * exposed internally for tests.
 *
 * Convention (the original layerlab's microfacetFourierSeries, which the
 * layer calls with mu = -node because depth grows opposite to the normal):
 * wi = (-sin_i, 0, -mu_i) points back toward the light, wo = (sin_o cos phi,
 * sin_o sin phi, mu_o) is the direction the light leaves along, the pair
 * reflects when -mu_i mu_o > 0, and light with -mu_i > 0 arrives from the
 * side where the relative index is eta (from the other side it is 1/eta).
 */
#ifndef LL_MICROFACET_H
#define LL_MICROFACET_H

#include <stddef.h>
#include "support/support.h"
#include "support/watch.h"
#include "layer/order.h"
#include "layerlab/ll_layer.h"

/* The original's truncation goal (ERROR_GOAL): the widening's and GGX's
 * peak lengths aim at it, and GGX series are cut there (ll_microfacet_keep). */
#define LL_MICROFACET_RELERR 1e-3
/* The terms a Beckmann series keeps: down to this fraction of the first
 * (the rest of the terms, computed to TAIL_GOAL, are dropped). Not RELERR:
 * a cut there falls after a different order from one pair of cosines to
 * the next, so f jumps between neighbouring cosines by up to about 1e-3 of
 * the pair's mean, a percent of f at a lobe's tail, and no node count
 * resolves a jump: the resolution search chased them (gold, Beckmann alpha
 * 0.3, to 1542 nodes; 104 here). A file's own truncation (--error) is
 * applied where it is written. GGX keeps RELERR (ll_microfacet_keep). */
#define LL_MICROFACET_KEEP 1e-5

/* The sum of a[i] b[i] in the order of i: the compensations' weighted sums
 * of albedos (microfacet_compensation*.c). */
static inline double ll_microfacet_dot(const double *a, const double *b, size_t n)
{
    double sum = 0.0;
    size_t i;
    for (i = 0; i < n; ++i)
        sum += a[i] * b[i];
    return sum;
}

typedef struct ll_microfacet_model ll_microfacet_model;

/* The caller's ll_microfacet read up to its struct_size (defaults after),
 * the distribution checked. The other fields
 * are checked by their users. */
LL_INTERNAL ll_status ll_microfacet_read(const ll_microfacet *in, ll_microfacet *out,
                                         const char *fn);

/* The microfacet distributions (the values of the public
 * ll_microfacet_distribution). */
#define LL_DISTRIBUTION_BECKMANN LL_MICROFACET_BECKMANN
#define LL_DISTRIBUTION_GGX LL_MICROFACET_GGX

/* The model: complex relative index, Beckmann roughness, the number of
 * Fourier orders n_orders it is resolved with (a lobe too sharp for them is
 * widened, keeping its energy) and the most orders max_len any series will
 * be asked for. Arguments are not checked here. */
LL_INTERNAL ll_status ll_microfacet_create(double eta_re, double eta_im, double alpha,
                                           size_t n_orders, size_t max_len,
                                           ll_microfacet_model **out);
/* The same for a distribution (LL_DISTRIBUTION_*; alpha is its roughness;
 * ll_microfacet_create's is Beckmann). */
LL_INTERNAL ll_status ll_microfacet_create_distribution(double eta_re, double eta_im,
                                                        double alpha, int distribution,
                                                        size_t n_orders, size_t max_len,
                                                        ll_microfacet_model **out);
LL_INTERNAL void ll_microfacet_destroy(ll_microfacet_model *mf);

/* Resolve the lobes with n_orders (at most the n_orders of creation) from
 * now on: the series are then those of a model created with n_orders,
 * while the maps already prepared stay valid (they hold the orders of the
 * creation's). The resolution search (search/probe.h) so shares one model,
 * and its maps, between the order counts it tries. Not thread-safe. */
LL_INTERNAL void ll_microfacet_set_orders(ll_microfacet_model *mf, size_t n_orders);

/* From now on, a series of one term (max_len 1) on Beckmann's Filon path
 * takes Simpson's rule on the same samples instead of Filon's moments: the
 * same quadratic through the samples integrated exactly, so the same
 * order 0 to rounding (Filon's rule at order 0 is Simpson's), for a
 * fraction of the work. For the resolution search's albedos, which need
 * order 0 alone at every node pair; a layer's model never sets it, so
 * its bits stay those of Filon's moments. */
LL_INTERNAL void ll_microfacet_order0_simpson(ll_microfacet_model *mf);

/* Precompute the least-squares fits that the pairs (mu[a], mu[b]),
 * a, b < count, will use (in parallel). Required before ll_microfacet_series
 * for those pairs. */
LL_INTERNAL ll_status ll_microfacet_prepare(ll_microfacet_model *mf, const double *mu, size_t count);
/* The same, reporting to and polling a watch (nullable). */
LL_INTERNAL ll_status ll_microfacet_prepare_watched(ll_microfacet_model *mf, const double *mu,
                                                    size_t count, ll_watch *watch);

/* The same for the pairs (mu_o[k], mu_i[k]), k < count, alone. */
LL_INTERNAL ll_status ll_microfacet_prepare_pairs(ll_microfacet_model *mf, const double *mu_o,
                                                  const double *mu_i, size_t count);

/* Doubles of scratch that ll_microfacet_series needs for max_len terms. */
LL_INTERNAL size_t ll_microfacet_scratch_size(size_t max_len);

/* The cosine series of f(mu_o, mu_i, phi) (BSDF without cosine factor):
 * writes *len <= max_len terms to out (0 when the pair does not scatter).
 * ref0 (nullable) receives the order-0 term of the same series with the
 * Fresnel factor set to 1 (what a perfect mirror of the same roughness
 * reflects; the conductor's energy compensation needs it). scratch holds
 * ll_microfacet_scratch_size(max_len) doubles. Thread-safe for a prepared
 * mf; fails (LL_ERROR_INVALID_ARGUMENT) for a pair that was not prepared. */
LL_INTERNAL ll_status ll_microfacet_series(const ll_microfacet_model *mf, double mu_o, double mu_i,
                                           size_t max_len, double *out, size_t *len,
                                           double *ref0, double *scratch);
/* The same, and in *widened (non-zero) whether the lobe was widened
 * (ll_microfacet_widened) from the plan the series was made by: one plan
 * of the pair instead of two where the caller needs both. 0 where the
 * series is empty before planning (max_len 0). */
LL_INTERNAL ll_status ll_microfacet_series_widened(const ll_microfacet_model *mf, double mu_o,
                                                   double mu_i, size_t max_len, double *out,
                                                   size_t *len, double *ref0, double *scratch,
                                                   int *widened);

/* ll_microfacet_series for a model that may not be prepared for the
 * pair: where the pair needs a map that is not there, *missing is set
 * (else cleared), LL_OK returned and nothing computed; prepare the pair
 * (ll_microfacet_prepare_pairs) and ask again. One plan of the pair where
 * preparing every pair first would plan each twice. */
LL_INTERNAL ll_status ll_microfacet_series_if_prepared(const ll_microfacet_model *mf, double mu_o,
                                                       double mu_i, size_t max_len, double *out,
                                                       size_t *len, double *ref0,
                                                       double *scratch, int *missing);

/* Does ll_microfacet_series widen the lobe of this pair at the orders in
 * effect (ll_microfacet_set_orders)? Where it does not, the series of a
 * model with fewer orders is a prefix of the one with more (the terms
 * do not depend on how many are asked for), truncated by the same rule:
 * the resolution search reuses them between the order counts it tries. */
/* The fraction of its first term down to which a series of mf keeps its
 * terms: LL_MICROFACET_KEEP for Beckmann; RELERR for GGX, whose series are
 * computed only to a tenth of it (GGX_TAIL_GOAL), so a lower cut would still
 * move with the pair, and whose transmission converges only to first order
 * in the nodes at its jump, which the probes do not see in the albedo. */
LL_INTERNAL double ll_microfacet_keep(const ll_microfacet_model *mf);
LL_INTERNAL int ll_microfacet_widened(const ll_microfacet_model *mf, double mu_o, double mu_i);
/* The Smith shadowing-masking term G1 of a direction with |tan theta| =
 * tan_theta for Beckmann roughness alpha, by the rational approximation of
 * Walter et al. 2007 (eq. 27; below 0.35% error), as the original uses. */
LL_INTERNAL double ll_microfacet_smith_g1(double tan_theta, double alpha);

/* The energy compensation (ll_microfacet.compensate, words/microfacet_compensation.c):
 * order 0 of block q of a layer with h positive nodes gains
 * scale[q] u[q][i] v[q][j] at output node i, input node j, both indices
 * into the magnitudes of their half (the layer's j and j + h are -x_j and
 * x_j); scale[q] == 0: nothing. Blocks by the signs of (mu_o, mu_i) in
 * ll_layer_eval's convention: reflection from above R^t (-, +), from below
 * R^b (+, -), transmission down T^tb (+, +) and up T^bt (-, -). */
/* (LL_BLOCK_* of layer/order.h: 2 [mu_o > 0] + [mu_i > 0].) */
#define LL_BLOCK_OF(mu_o, mu_i) (2 * ((mu_o) > 0.0) + ((mu_i) > 0.0))
typedef struct ll_microfacet_compensation {
    const double *u[4], *v[4]; /* into the work array of the call          */
    double scale[4];
    /* The azimuthal spread of the reflection terms (a conductor's; NULL mu:
     * flat, order 0 only): at node cosines mu[i], mu[j] the term is spread
     * over the azimuth as (1 - peaked) + peaked vM(phi), vM the von Mises
     * density of mean 1 about the mirror side with concentration
     * spread sin_i sin_j / (mu_i + mu_j)^power (symmetric: reciprocal; of
     * mean 1: the energy of order 0). */
    const double *mu;
    double spread, power, peaked;
} ll_microfacet_compensation;

/* The Fourier series (f = c_0 + sum_k c_k cos(k phi), phi from the mirror
 * side: as ll_microfacet_series') of block q's term at output node i,
 * input node j, m terms at most, in out[m]; returns how many are written
 * (0: no term; the rest are negligible). The concentration is held to
 * what m orders resolve (m^2 / 40: the series truncated at m is within
 * e^-20 of the whole) and to 100, so a layer of m orders and the probes at
 * m orders carry the same term, the same for every m of 64 or more. */
LL_INTERNAL size_t ll_microfacet_compensation_series(const ll_microfacet_compensation *c, int q,
                                                     size_t i, size_t j, size_t m, double *out);

/* A dielectric's terms (words/microfacet_compensation_dielectric.c) from
 * the albedos (indexed by block: column sums of the unweighted order 0
 * with the weights w[i] = 2 pi w_i mu_i of the positive nodes) of the
 * single-scattering layer at the positive node cosines mu; mf is a model
 * of the interface (its distribution and roughness). work holds 4 h
 * doubles and must outlive *out. */
LL_INTERNAL void ll_microfacet_compensate_dielectric(const ll_microfacet_model *mf, size_t h,
                                                     const double *mu, const double *w,
                                                     double eta, const double *const albedo[4],
                                                     double *work,
                                                     ll_microfacet_compensation *out);
/* The first-order error of the node quadrature of a GGX transmission
 * albedo at its jump (docs/method.md, "Rough interfaces"): where the
 * refraction half vector turns horizontal, mu_j = e |mu_o| with e the
 * relative index ahead of the light (eta from above, 1 / eta from below), GGX's D stays
 * finite and f drops from a finite value to 0 along the whole azimuth, so
 * the nodes' sum of f W over the outgoing cosines counts the node cell
 * that the jump J cuts as wholly lit or wholly dark. With f = g+ above J
 * and g- below, the sum minus the integral is (g+ - g-) (sum of w_i over
 * mu_i > J - pi (1 - J^2)), up to terms of second order in the node
 * spacing (the rest of f is continuous there). It changes sign and size
 * from one node count to the next. This is that error for the albedo of
 * positive node j (mu ascending, weights w as for
 * ll_microfacet_compensate_dielectric), from above (below = 0) or below;
 * 0 for Beckmann, whose D vanishes at the horizontal normal (no jump).
 * scratch holds ll_microfacet_scratch_size(1) doubles. */
LL_INTERNAL double ll_microfacet_jump_error(const ll_microfacet_model *mf, size_t h,
                                            const double *mu, const double *w, double eta,
                                            size_t j, int below, double *scratch);
/* A conductor's from the albedos of reflection from above of the same
 * interface with F = 1 (ll_microfacet_series' ref0) and of the interface
 * itself, at the positive node cosines mu; mf is a model of the interface
 * (its index, distribution and roughness). work holds 2 h doubles and
 * must outlive *out. */
LL_INTERNAL void ll_microfacet_compensate_conductor(const ll_microfacet_model *mf, size_t h,
                                                    const double *mu, const double *w,
                                                    const double *mirror_albedo,
                                                    const double *albedo, double *work,
                                                    ll_microfacet_compensation *out);

#endif /* LL_MICROFACET_H */
