/*
 * Choosing a resolution by a stated tolerance: a fixed set of
 * probe directions, what a layer of n nodes and m Fourier orders gives
 * there, and the search for the smallest (n, m) that agrees with twice the
 * resolution within the tolerance where the BSDF is above 1% of its peak.
 * The fits of words/heuristics.c are the search's first guess only.
 */
#ifndef LL_SEARCH_PROBE_H
#define LL_SEARCH_PROBE_H

#include <stddef.h>
#include "support/support.h"
#include "words/microfacet.h"
#include "support/watch.h"
#include "words/media.h"
#include "words/merl.h"

/* The revision of what the search chooses: the probes, the criterion and
 * the words' numerics it measures (series truncation, energy
 * compensation). Remembered choices are keyed by it as well as by the
 * library's version (material/resolution_cache.c), so that a build of the
 * same version number with another search does not take a choice it would
 * no longer make: raise it with every change that can change a choice. */
#define LL_SEARCH_REVISION 4

/* Where the lobes are compared: pairs of layer cosines (ll_layer_eval's
 * mu_o, mu_i; |mu| >= mu_min), each evaluated at every azimuth of phi[].
 * A group is one incident direction and one block (reflection or
 * transmission): the "1% of its peak" is the peak of its group. */
typedef struct ll_probe_pair {
    double mu_o, mu_i;
    size_t group;
} ll_probe_pair;

/* Azimuths per pair, at most. */
#define LL_PROBE_MAX_PHI 17

typedef struct ll_probe_set {
    ll_probe_pair *pairs;
    size_t n_pairs, cap_pairs;
    double phi[LL_PROBE_MAX_PHI];
    size_t n_phi;
    size_t n_groups;
} ll_probe_set;

/* Values of a probe set: n_pairs x n_phi, pair-major. */
#define LL_PROBE_VALUES(set) ((set)->n_pairs * (set)->n_phi)

/* The fraction of a group's peak above which the tolerance applies. */
#define LL_PROBE_FLOOR 0.01

/* The probes of a rough interface of relative index eta_re + i eta_im
 * (conductor when eta_im > 0): incident cosines mu_min, 1.5 mu_min,
 * 2 mu_min (the grazing ones, where the azimuthal lobe is narrowest),
 * 0.35, 0.5, 0.6, 0.75, 0.85, 0.9, 0.95, 1 and three pseudo-random ones in
 * [mu_min, 1], from above and (dielectric) from below; outgoing: the mirror and the
 * refracted direction, 14 offsets of 0.01 .. 0.25 in mu around them and two
 * pseudo-random ones; azimuths 0 .. pi, dense near 0. Deterministic. */
LL_INTERNAL ll_status ll_probe_interface(double eta_re, double eta_im, double mu_min,
                                         ll_probe_set *out);
/* The probes of a medium's phase function: the same incident cosines,
 * outgoing cosines spread over both hemispheres (the forward peak at
 * mu_o = mu_i included). */
LL_INTERNAL ll_status ll_probe_medium(double mu_min, ll_probe_set *out);
/* The probes of an opaque surface seen from above (a measured BRDF): those
 * of a conductor, reflection from above only. */
LL_INTERNAL ll_status ll_probe_opaque(double mu_min, ll_probe_set *out);
LL_INTERNAL void ll_probe_free(ll_probe_set *set);

/* The worst relative difference |v - ref| / ref over the values whose ref
 * is above LL_PROBE_FLOOR of the peak of its group; a value NaN in either
 * array (ll_probe_mark_jump) is left out, and out of the peaks. */
LL_INTERNAL double ll_probe_error(const ll_probe_set *set, const double *v, const double *ref);

/* GGX's transmission jump (search/probe_jump.c): whether the spline
 * stencils of (mu_o, mu_i) on the positive half (h nodes) of the
 * Gauss-Lobatto nodes hold node pairs on both sides of the line
 * |mu_i| = e |mu_o|, e the relative index ahead of the light (eta from
 * above, mu_i > 0; 1 / eta from below), in the transmission blocks
 * (reflection: never). */
LL_INTERNAL int ll_probe_jump_straddles(const double *half, size_t h, double eta, double mu_o,
                                        double mu_i);
/* Set to NaN the values (LL_PROBE_VALUES(set)) of the probe pairs whose
 * stencils at n nodes straddle that line: what the search then leaves out
 * of its comparisons of a GGX dielectric (ll_probe_error). */
LL_INTERNAL ll_status ll_probe_mark_jump(const ll_probe_set *set, size_t n, double eta,
                                         double *values);
/* The same on the Gauss-Lobatto nodes of n the caller has (all n). */
LL_INTERNAL void ll_probe_mark_jump_nodes(const ll_probe_set *set, size_t n,
                                          const double *nodes, double eta, double *values);

/* The interface model that the evaluations of one search share (with
 * the maps of its series): every order, no widening (words/microfacet.h). */
LL_INTERNAL ll_status ll_probe_interface_model(double eta_re, double eta_im, double alpha,
                                               ll_microfacet_model **out);
/* The same for a distribution (LL_DISTRIBUTION_*, words/microfacet.h). */
LL_INTERNAL ll_status ll_probe_interface_model_distribution(double eta_re, double eta_im,
                                                            double alpha, int distribution,
                                                            ll_microfacet_model **out);

/* No widening: the orders a "true" series may have (more than any layer
 * holds: LL_MATERIAL_MAX_RESOLUTION is 100000). */
#define LL_PROBE_TRUE_ORDERS ((size_t)1 << 20)
/* The terms a true series may have (the model's max_len). */
#define LL_PROBE_TRUE_MAX_LEN ((size_t)100000)

/* The energy compensation of an interface layer at the probes: the terms
 * that ll_layer_set_microfacet (compensate = 1) on the Gauss-Lobatto
 * nodes of n adds to order 0, from the albedos of every node pair
 * (O(n^2) order-0 series; search/interface_probe_compensation.c). They do
 * not depend on the layer's orders (a widened lobe keeps the order 0 of
 * the true one), so they are computed once per n from the true series'
 * order 0, with a model of its own (ll_probe_compensation_model: maps of
 * one order; the lobe's maps of every order at every B of n^2 pairs took
 * 600 MB and most of a minute at alpha 0.02). watch (nullable) is polled
 * per column. */
LL_INTERNAL ll_status ll_probe_compensation_model(double eta_re, double eta_im, double alpha,
                                                  ll_microfacet_model **out);
LL_INTERNAL ll_status ll_probe_compensation_model_distribution(double eta_re, double eta_im,
                                                               double alpha, int distribution,
                                                               ll_microfacet_model **out);
typedef struct ll_probe_compensation {
    size_t h;
    double *memory;
    ll_microfacet_compensation terms;
} ll_probe_compensation;
LL_INTERNAL ll_status ll_probe_compensation_make(ll_microfacet_model *mf, double eta_re,
                                                 double eta_im, size_t n, ll_watch *watch,
                                                 ll_probe_compensation *out);
/* The same on the Gauss-Lobatto rule of n the caller has (nodes and
 * weights, all n): the search's evaluations at one n share it
 * (ll_probe_series_memo_rule). */
LL_INTERNAL ll_status ll_probe_compensation_make_rule(ll_microfacet_model *mf, double eta_re,
                                                      double eta_im, size_t n,
                                                      const double *nodes,
                                                      const double *weights, ll_watch *watch,
                                                      ll_probe_compensation *out);
/* The term's Fourier series (ll_microfacet_compensation_series: m terms
 * at most in out[m], returns how many) of block (LL_BLOCK_*) at output
 * node i, input node j (indices into the positive half); 0 for c ==
 * NULL. */
LL_INTERNAL size_t ll_probe_compensation_series(const ll_probe_compensation *c, int block,
                                                size_t i, size_t j, size_t m, double *out);
LL_INTERNAL void ll_probe_compensation_free(ll_probe_compensation *c);

/* What ll_layer_set_microfacet of the model's interface on the
 * Gauss-Lobatto nodes of n and m orders followed by ll_layer_eval gives at
 * the probes, from the series at the spline stencils of the probes alone
 * (no layer is built: 16 series per pair, each node pair that several
 * stencils hold computed once), plus the energy compensation's term there
 * when compensation (made for the same n) is not NULL. values holds
 * LL_PROBE_VALUES(set). watch (nullable) is polled per node pair and per
 * probe pair. */
LL_INTERNAL ll_status ll_probe_interface_eval(ll_microfacet_model *mf,
                                              const ll_probe_compensation *compensation,
                                              size_t n, size_t m, const ll_probe_set *set,
                                              ll_watch *watch, double *values);

/* What ll_layer_set_henyey_greenstein / _von_mises_fisher (kind, shape:
 * g or kappa; albedo 1) on the Gauss-Lobatto nodes of n and m orders
 * followed by ll_layer_eval gives at the probes, read from each order as
 * it is made and keeping none (search/medium_probe.c): O(n^2) memory per
 * thread instead of the layer's O(n^2 m); without with_forward, less the
 * delta-M forward term (a delta, not a lobe; the search compares the
 * lobe). monitor: nullable. */
LL_INTERNAL ll_status ll_probe_medium_eval(ll_medium_kind kind, double shape, int with_forward,
                                           size_t n, size_t m, const ll_probe_set *set,
                                           const ll_monitor *monitor, double *values);

/* The series of the stencils of one node count, kept for evaluations at
 * other order counts (ll_probe_interface_eval_memo): the search asks for
 * each n at several m, and where a lobe is not widened the series of fewer
 * orders is a prefix of the one with more (ll_microfacet_widened). Slots:
 * the distinct node pairs of the stencils (each computed once, however
 * many probes' stencils hold it), by (block, node o, node i). Zeroed:
 * empty. */
typedef struct ll_probe_series_memo {
    size_t n;               /* the node count; 0: empty                    */
    size_t m;               /* the orders the series were computed with    */
    size_t slots;
    double **series;        /* [slots] (NULL where len is 0)               */
    size_t *len;            /* [slots] terms after the truncation          */
    unsigned char *widened; /* [slots] the lobe was widened at m           */
    /* The Gauss-Lobatto rule of rule_n (nodes, then weights; O(n^2) to
     * make, and the search evaluates each n at several m, its
     * compensation and jump marks on the same nodes). */
    double *rule;
    size_t rule_n;
} ll_probe_series_memo;
LL_INTERNAL void ll_probe_series_memo_free(ll_probe_series_memo *memo);
/* The Gauss-Lobatto rule of n (*nodes, *weights: n each), made once and
 * kept by the memo (the one it held for another n replaced). */
LL_INTERNAL ll_status ll_probe_series_memo_rule(ll_probe_series_memo *memo, size_t n,
                                                const double **nodes, const double **weights);

/* ll_probe_interface_eval, reusing the series that memo (nullable) holds
 * for n when m is at most its orders, and refilling it otherwise: the
 * values are those of ll_probe_interface_eval bit for bit. */
LL_INTERNAL ll_status ll_probe_interface_eval_memo(ll_microfacet_model *mf,
                                                   const ll_probe_compensation *compensation,
                                                   ll_probe_series_memo *memo, size_t n,
                                                   size_t m, const ll_probe_set *set,
                                                   ll_watch *watch, double *values);

/* The Fourier orders the lobes themselves need
 * (search/interface_probe_orders.c): at every probe pair, the true series
 * (no widening) truncated after L terms is within tolerance / 2 of the
 * whole series at every azimuth where it is above LL_PROBE_FLOOR of its
 * group's peak; the largest such L over the pairs. */
LL_INTERNAL ll_status ll_probe_interface_orders(ll_microfacet_model *mf, double tolerance,
                                                const ll_probe_set *set, size_t *n_orders);

/* The Catmull-Rom stencil of ll_layer_eval for the cosine mu on the
 * positive half (h nodes) of the Gauss-Lobatto nodes: the signed node
 * cosines, weights and (nullable) indices into half of the non-zero ones;
 * their count (at most 4). */
LL_INTERNAL size_t ll_probe_stencil(const double *half, size_t h, double mu, double node[4],
                                    double w[4], size_t index[4]);
/* acc[k] += weight * sum_l c[l] cos(l phi[k]), k < n_phi. */
LL_INTERNAL void ll_probe_add_series(const double *c, size_t len, const double *phi,
                                     size_t n_phi, double weight, double *acc);

/* What the layer of a word gives at the probes at n nodes and m orders
 * (polling the watch in its long loops: a cancel returns
 * LL_ERROR_CANCELLED). */
typedef ll_status (*ll_probe_eval_fn)(void *ctx, size_t n, size_t m, ll_watch *watch,
                                      double *values);

/* Progress units of one search: each evaluation advances the watch's
 * stage by one, up to this many (a caller's stage per search has this
 * total). */
#define LL_PROBE_SEARCH_UNITS 24

/* The smallest resolution found, starting from (n, m), whose probe values
 * are within 0.6 of the tolerance of those at (2n, 2m) (a margin for the
 * directions between the probes): grow n and/or m (by 1.25 to
 * 2, from the error) while the comparison fails, as the comparisons at
 * (2n, m) and (n, 2m) say, then shrink n to the smallest of n 0.85^k
 * (k <= 3) that still holds (the candidates screened against the (2n, 2m)
 * already made first), then m by 0.85 (up to 3 times) while it still
 * holds. n stays even and
 * >= min_nodes; either beyond `limit` fails, naming the error reached.
 * *error receives the difference at the answer (nullable). watch
 * (nullable) is polled between and inside the evaluations: a cancel
 * returns LL_ERROR_CANCELLED (with nothing left allocated). */
LL_INTERNAL ll_status ll_probe_search(const ll_probe_set *set, ll_probe_eval_fn eval,
                                      void *ctx, ll_watch *watch, double tolerance,
                                      size_t min_nodes, size_t limit, const char *what,
                                      size_t *n_nodes, size_t *n_orders, double *error);

/* ll_resolution_search_microfacet and ll_resolution_search_henyey_greenstein
 * (resolution.c) on the parameters themselves, with a watch (nullable:
 * polled, and one stage's progress per search, LL_PROBE_SEARCH_UNITS) and,
 * for the interface, whether the layer gets the energy compensation
 * (ll_microfacet.compensate). */
LL_INTERNAL ll_status ll_search_microfacet(double alpha, double eta_re, double eta_im,
                                           int compensate, double tolerance, double mu_min,
                                           ll_watch *watch, size_t *n_nodes, size_t *n_orders,
                                           double *error);
/* The same for a distribution (LL_DISTRIBUTION_*): the probes evaluate its
 * model; the first guess is the (Beckmann) fit either way. */
LL_INTERNAL ll_status ll_search_microfacet_distribution(double alpha, double eta_re,
                                                        double eta_im, int distribution,
                                                        int compensate, double tolerance,
                                                        double mu_min, ll_watch *watch,
                                                        size_t *n_nodes, size_t *n_orders,
                                                        double *error);
/* The same, from a start: *n_nodes, *n_orders on entry (0, 0: the fit's
 * guess, as above). */
LL_INTERNAL ll_status ll_search_microfacet_from(double alpha, double eta_re, double eta_im,
                                                int distribution, int compensate,
                                                double tolerance, double mu_min,
                                                ll_watch *watch, size_t *n_nodes,
                                                size_t *n_orders, double *error);
LL_INTERNAL ll_status ll_search_henyey_greenstein(double g, double tolerance, double mu_min,
                                                  ll_watch *watch, size_t *n_nodes,
                                                  size_t *n_orders, double *error);

/* What ll_merl_set_layer on n nodes and m orders followed by ll_layer_eval
 * gives at the probes (merl_probe.c), from the series of the probes'
 * stencils alone. values holds LL_PROBE_VALUES(set). */
LL_INTERNAL ll_status ll_merl_probe_eval(const ll_merl *merl, const double weights[3],
                                         size_t n, size_t m, const ll_probe_set *set,
                                         ll_watch *watch, double *values);
/* The smallest (n, m) found, from the guess in *n_nodes, *n_orders, whose
 * projected lobe is within the tolerance of (2n, 2m) on the probes of
 * ll_probe_opaque (ll_probe_search); *error the difference there
 * (nullable). */
LL_INTERNAL ll_status ll_merl_resolution(const ll_merl *merl, const double weights[3],
                                         double tolerance, double mu_min, ll_watch *watch,
                                         size_t *n_nodes, size_t *n_orders, double *error);

#endif /* LL_SEARCH_PROBE_H */
