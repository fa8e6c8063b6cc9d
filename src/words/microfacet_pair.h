/*
 * The insides of the microfacet model, shared by the files that make its
 * series (words/microfacet*.c; the method is described in
 * microfacet_series.c): the model and its maps, the plan of one pair of
 * cosines, and the steps each file provides to the others.
 */
#ifndef LL_WORDS_MICROFACET_PAIR_H
#define LL_WORDS_MICROFACET_PAIR_H

#include "words/microfacet.h"
#include "words/microfacet_ggx.h"

#define CHEB 16               /* Chebyshev points of g on the window           */
#define TAIL_GOAL 1e-6        /* matrices keep orders until exp(-B v)'s series
                               * falls below this fraction of its first term   */
#define FILON_SAMPLES 129     /* Filon samples of a main piece (odd)           */
/* ll_microfacet_scratch_size(max_len) as a constant expression (for a
 * series of one term on the stack): Chebyshev path 2 CHEB; Filon path
 * 2 FILON_SAMPLES + 7 max_len; GGX's total internal reflection a series
 * more. */
#define MICROFACET_SCRATCH(max_len) (2 * FILON_SAMPLES + 8 * (max_len) + 2 * CHEB)
#define ANGLE_EPS 1e-7        /* azimuths this close count as equal            */
#define NEGLIGIBLE 1e-10      /* skip pairs whose peak series starts below     */
#define FILON_EXTRA 100       /* a kinked f may need this many orders beyond
                               * its peak's (as the original allows)           */
#define GGX_TAIL_GOAL 1e-4    /* GGX's peak series falls geometrically: its
                               * terms below 1e-4 (a tenth of the original's
                               * truncation, LL_MICROFACET_RELERR) would double
                               * the orders of TAIL_GOAL's 1e-6 for nothing    */

/* The precomputed map of one grid point. */
typedef struct grid_entry {
    double b;            /* B_k                                            */
    double delta;        /* the window 0 <= v <= delta                     */
    size_t len;          /* orders it produces                             */
    double cos_phi[CHEB];/* cos phi at the Chebyshev points                */
    double u[CHEB];      /* u there                                        */
    double *matrix;      /* CHEB x len, point-major: matrix[i * len + l]   */
} grid_entry;

struct ll_microfacet_model {
    double eta_re, eta_im, alpha;
    int conductor;
    int ggx;             /* GGX, else Beckmann                             */
    ll_ggx_basis ggx_basis;
    double b_max;        /* lobes sharper than this are widened            */
    double map_b_max;    /* the maps hold every order up to this B (the
                          * b_max of creation; ll_microfacet_set_orders
                          * may lower b_max, never this)                   */
    size_t max_len;      /* orders wanted                                  */
    int simpson_order0;  /* order 0 alone by Simpson's rule on the Filon
                          * path (ll_microfacet_order0_simpson)            */
    size_t n_grid;
    grid_entry **grid;   /* [n_grid] NULL until prepared                   */
    double *window_rule; /* the maps' Gauss-Legendre rule (nodes, then
                          * weights), made with the first map: a search
                          * prepares maps in dozens of batches           */
};

/* Everything one pair needs, from its two cosines. */
typedef struct pair_plan {
    int reflect;
    double eta;        /* relative index in the half vector wi + eta wo     */
    double a_plus_b;   /* log of the peak of exp(A + B cos phi) (GGX: of
                        * (1 - A - B cos phi)^-2)                           */
    double peak;       /* Beckmann: exp(a_plus_b), as planned               */
    double b;          /* Beckmann: B; GGX: beta (words/microfacet_ggx.h)    */
    int widened;       /* B was reduced to what the orders hold             */
    size_t grid;       /* B_k <= B                                           */
    double phi_end;    /* the window in phi: [0, phi_end]                   */
    int filon;         /* g is not smooth enough: integrate f by Filon      */
    double split;      /* > 0: g has a kink here (inside the window)        */
    int grade_start;   /* a branch point of g lies just before phi = 0 ...  */
    int grade_end;     /* ... or just after phi_end                         */
    double near_start; /* where that branch point lies: u = v / Delta <= 0 ... */
    double near_end;   /* ... or >= 1 (classify_window)                      */
    /* g from t = wi . wo = -sin_prod cos phi - mu_prod: */
    double sin_prod, mu_prod;
    double sign_h;     /* sign of the half vector's z                       */
    double mu_i, mu_o;
    double scale;      /* G1(wi) G1(wo) / (pi alpha^2 h_z^4 |mu_i mu_o|)    */
    ll_ggx_length peak_len; /* GGX: ll_ggx_peak_length(b, GGX_TAIL_GOAL, cap)
                             * for the caps up to the pair's orders, prepared
                             * by ll_microfacet_series before its series    */
} pair_plan;

/* B_k, the grid point k of the maps (B_0 = 0), and the grid point at or
 * below b (microfacet_plan.c). */
LL_INTERNAL double ll_microfacet_grid_b(size_t k);
LL_INTERNAL size_t ll_microfacet_grid_index(double b);
/* The window in v = 1 - cos phi for exp(-b v), and the azimuth where v
 * reaches delta. */
LL_INTERNAL double ll_microfacet_window_delta(double b);
LL_INTERNAL double ll_microfacet_window_angle(double delta);
/* The window and the branch points of g on or near it; 0 if no azimuth
 * refracts into the pair. */
LL_INTERNAL int ll_microfacet_classify_window(const ll_microfacet_model *mf, pair_plan *p);
/* The phi-independent factor of g, times eta^2 for refraction. */
LL_INTERNAL double ll_microfacet_pair_scale(const ll_microfacet_model *mf, const pair_plan *p,
                                            double g1_i, double g1_o, double h_z);
/* Plan a pair, its lobe widened to at most B = b_limit; 0 if it does not
 * scatter at all (or negligibly). */
LL_INTERNAL int ll_microfacet_plan_pair(const ll_microfacet_model *mf, double mu_o, double mu_i,
                                        double b_limit, pair_plan *p);
/* g at the azimuths with the given cosines, and g with F = 1 (either
 * output may be NULL). */
LL_INTERNAL void ll_microfacet_sample_profile(const ll_microfacet_model *mf, const pair_plan *p,
                                              const double *cos_phi, size_t count, double *g,
                                              double *no_fresnel);

/* The rest of ll_microfacet_plan_pair for GGX (microfacet_ggx_pair.c). */
LL_INTERNAL int ll_microfacet_plan_ggx(const ll_microfacet_model *mf, pair_plan *p,
                                       double b_limit, double mu_i, double si, double so,
                                       double h_z);
/* The series of a smooth GGX pair (n_out terms, *n_out), and the order 0
 * of its reference (F = 1) if ref0 is not NULL. */
LL_INTERNAL ll_status ll_microfacet_ggx_pair_series(const ll_microfacet_model *mf,
                                                    const pair_plan *p, size_t max_len,
                                                    double *out, size_t *n_out, double *ref0,
                                                    double *scratch);

/* A GGX reflection pair with total internal reflection below its split
 * (microfacet_ggx_pair.c): n_out terms (*n_out) and the order 0 of the
 * reference (F = 1) if ref0 is not NULL. */
LL_INTERNAL ll_status ll_microfacet_ggx_tir_series(const ll_microfacet_model *mf,
                                                   const pair_plan *p, size_t max_len,
                                                   double *out, size_t *n_out, double *ref0,
                                                   double *scratch);

/* The cosine series of f minus its reference (F = 1) over [split, pi] of
 * a GGX reflection pair, by Filon's rule (microfacet_filon.c): at most
 * n_out terms, until they settle against the pair's mean; returns how
 * many. seen: f's largest value known. scratch holds 2 FILON_SAMPLES +
 * 7 n_out doubles. */
LL_INTERNAL size_t ll_microfacet_ggx_fresnel_part(const ll_microfacet_model *mf,
                                                  const pair_plan *p, double mean, double seen,
                                                  size_t n_out, double *out, double *scratch);

/* The cosine series of f, n_out terms, integrated by Filon's rule
 * (microfacet_filon.c); with F = 1 for the reference. scratch holds
 * ll_microfacet_scratch_size(n_out) doubles. */
LL_INTERNAL void ll_microfacet_filon_series(const ll_microfacet_model *mf, const pair_plan *p,
                                            int reference, size_t n_out, double *out,
                                            double *scratch);

#endif /* LL_WORDS_MICROFACET_PAIR_H */
