/*
 * The material language, inside: a parsed stack of words (material_parse.c),
 * what each word means per colour channel and the stack's header
 * (material_stack.c), the resolution and cost of a build
 * (material_resolution.c), the JSON description stored in files
 * (material_metadata.c) and the build itself (material_build.c).
 * The language is described in docs/material-language.md.
 */
#ifndef LL_MATERIAL_INTERNAL_H
#define LL_MATERIAL_INTERNAL_H

#include "support/support.h"
#include "material/ior.h"
#include "layerlab/ll_material.h"

typedef enum {
    LL_WORD_DIFFUSE,
    LL_WORD_DIELECTRIC,
    LL_WORD_CONDUCTOR,
    LL_WORD_MEDIUM,
    LL_WORD_MEASURED
} ll_word_kind;

typedef enum { LL_PHASE_ISOTROPIC, LL_PHASE_HG, LL_PHASE_VMF } ll_phase;

/* A number as written: one value or three (R, G, B). count 0 = absent. */
typedef struct ll_number {
    double v[3];
    int count;
    size_t line, column; /* where the value was written */
} ll_number;

typedef struct ll_word {
    ll_word_kind kind;
    size_t line, column;
    ll_number albedo, eta, k, alpha, tau, g, kappa;
    ll_number compensate;     /* dielectric, conductor: 0 = no energy compensation */
    ll_phase phase;
    int phase_given;
    int named_metal;          /* conductor eta=NAME                      */
    char metal[64];
    ll_metal_ior metal_ior;   /* its indices, relative to vacuum          */
    char *file;               /* measured: the resolved path              */
} ll_word;

struct ll_material {
    char *source;             /* name used in messages                   */
    ll_word *words;           /* top to bottom                           */
    size_t count;
    size_t nodes, orders, channels; /* settings; 0 = not set             */
    double error_goal;        /* 0 = not set                              */
    char *metadata;           /* JSON stored in written files             */
};

/* What one word is in one channel of a build with n_channels channels:
 * plain numbers, ready for the ll_layer_set_* calls. Two words with equal
 * parameters build identical layers (the sharing between channels). */
typedef struct ll_word_params {
    ll_word_kind kind;
    ll_phase phase;
    double albedo;
    double eta_re, eta_im;    /* relative to the medium right above        */
    double alpha;
    int uncompensated;        /* compensate=0: single scattering only      */
    double tau;
    double shape;             /* g (HG) or kappa (vMF), else 0             */
    double weights[3];        /* measured: weight of each MERL channel     */
} ll_word_params;

/* Luminance weights of linear sRGB (as the .bsdf Y channel). */
#define LL_LUMA_R 0.212671
#define LL_LUMA_G 0.715160
#define LL_LUMA_B 0.072169

/* ---- material_stack.c */
/* Does the description ask for colour (any three-valued number, a named
 * metal, a measured BRDF)? */
LL_INTERNAL int ll_material_is_rgb(const ll_material *m);
/* Is the bottom opaque (no light leaves through it)? */
LL_INTERNAL int ll_material_is_opaque(const ll_material *m);
/* The value of a number in channel c of an n_channels build: the channel's
 * own value, or for a monochrome build of three values their luminance. */
LL_INTERNAL double ll_number_channel(const ll_number *x, size_t c, size_t n_channels,
                                     double fallback);
LL_INTERNAL void ll_word_params_get(const ll_material *m, size_t word, size_t channel,
                                    size_t n_channels, ll_word_params *out);
LL_INTERNAL int ll_word_params_equal(const ll_word_params *a, const ll_word_params *b);
/* The physical checks on the whole stack (opaque layers only at the
 * bottom, ...). LL_ERROR_PARSE with file:line:column. */
LL_INTERNAL ll_status ll_material_check_stack(const ll_material *m);
/* The .bsdf header of an n_channels build: eta(bottom)/eta(top) (1 when
 * opaque) and the roughness of the top and bottom interfaces. */
LL_INTERNAL void ll_material_header(const ll_material *m, size_t n_channels, double *eta,
                                    double alpha[2]);
LL_INTERNAL const char *ll_word_kind_name(ll_word_kind kind);

/* ---- material_resolution.c */
/* The options with the caller's struct_size honoured and defaults filled. */
LL_INTERNAL ll_status ll_build_options_read(const ll_build_options *in, ll_build_options *out,
                                            const char *fn);
/* Resolution and channels for a build (options > settings > heuristics). */
LL_INTERNAL ll_status ll_material_plan(const ll_material *m, const ll_build_options *o,
                                       size_t *n_nodes, size_t *n_orders, size_t *n_channels);
/* Estimated seconds of one step of a build on `threads` threads: building
 * one word's layer, and one adding (a doubling counts as one). */
LL_INTERNAL double ll_cost_word(const ll_word_params *p, size_t n, size_t m, size_t threads);
LL_INTERNAL double ll_cost_add(size_t n, size_t m, size_t threads);
LL_INTERNAL double ll_cost_write(size_t n, size_t m, size_t n_channels);
/* Doublings that ll_layer_expand performs for tau on nodes whose smallest
 * |mu| is min_mu. */
LL_INTERNAL size_t ll_doubling_count(double tau, double min_mu);

/* ---- material_metadata.c */
LL_INTERNAL ll_status ll_material_make_metadata(ll_material *m, const char *text);

#endif /* LL_MATERIAL_INTERNAL_H */
