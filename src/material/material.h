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

/* A word's descriptor (material/word_table.h): its parameters, builder,
 * resolution heuristic, cost model and metadata. */
typedef struct ll_word_desc ll_word_desc;

/* A number as written: one value or three (R, G, B). count 0 = absent. */
typedef struct ll_number {
    double v[3];
    int count;
    size_t line, column; /* where the value was written */
} ll_number;

#define LL_WORD_MAX_NUMBERS 6

/* One word as parsed. The meaning of number[] and of the other fields is
 * the word's own (its word_NAME.c). */
typedef struct ll_word {
    const ll_word_desc *desc;
    size_t line, column;
    ll_number number[LL_WORD_MAX_NUMBERS];
    int choice;               /* an enumerated parameter (medium: phase)  */
    int choice_given;
    int named_metal;          /* conductor eta=NAME                      */
    char metal[64];
    ll_metal_ior metal_ior;   /* its indices, relative to vacuum          */
    char *file;               /* measured: the resolved path              */
    double file_bytes;        /* measured: its size (for the estimate)    */
} ll_word;

struct ll_material {
    char *source;             /* name used in messages                   */
    ll_word *words;           /* top to bottom                           */
    size_t count, capacity;   /* words used, allocated                   */
    size_t nodes, orders, channels; /* settings; 0 = not set             */
    double error_goal;        /* 0 = not set                              */
    double tolerance, mu_min; /* the resolution's goal; 0 = not set       */
    char *metadata;           /* JSON stored in written files             */
};

#define LL_WORD_MAX_VALUES 6

/* What one word is in one channel of a build with n_channels channels:
 * plain numbers, ready for the ll_layer_set_* calls (their meaning is the
 * word's own). Two words with equal parameters build identical layers (the
 * sharing between channels). */
typedef struct ll_word_params {
    const ll_word_desc *desc;
    int choice;
    double v[LL_WORD_MAX_VALUES];
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
/* Every word's parameters in every channel, params[word][channel], in one
 * pass down the stack (ll_word_params_get walks the words above). */
LL_INTERNAL void ll_material_params(const ll_material *m, size_t n_channels,
                                    ll_word_params (*params)[3]);
/* One word's, given the absolute index above it in that channel; and the
 * relative index it puts below itself (callers walking down the stack keep
 * the product). */
LL_INTERNAL void ll_word_params_above(const ll_material *m, size_t word, size_t channel,
                                      size_t n_channels, double above, ll_word_params *out);
LL_INTERNAL double ll_word_index_ratio(const ll_material *m, size_t word, size_t channel,
                                       size_t n_channels);
LL_INTERNAL int ll_word_params_equal(const ll_word_params *a, const ll_word_params *b);
/* The physical checks on the whole stack (opaque layers only at the
 * bottom, ...). LL_ERROR_PARSE with file:line:column. */
LL_INTERNAL ll_status ll_material_check_stack(const ll_material *m);
/* The .bsdf header of an n_channels build: eta(bottom)/eta(top) (1 when
 * opaque) and the roughness of the top and bottom interfaces. */
LL_INTERNAL void ll_material_header(const ll_material *m, size_t n_channels, double *eta,
                                    double alpha[2]);
LL_INTERNAL const char *ll_word_name(const ll_word *w);

/* ---- material_resolution.c */
/* The options with the caller's struct_size honoured and defaults filled
 * (max_memory_bytes: half of the physical memory when 0). */
LL_INTERNAL ll_status ll_build_options_read(const ll_build_options *in, ll_build_options *out,
                                            const char *fn);
/* Resolution and channels for a build (options > settings > heuristics),
 * checked against the smallest meaningful resolution. */
LL_INTERNAL ll_status ll_material_plan(const ll_material *m, const ll_build_options *o,
                                       size_t *n_nodes, size_t *n_orders, size_t *n_channels);
/* The smallest node count whose quadrature is meaningful
 * (docs/material-language.md, "Settings"), and the largest node or order
 * count a build accepts. */
#define LL_MATERIAL_MIN_NODES 10
#define LL_MATERIAL_MAX_RESOLUTION 100000

/* ---- material_estimate.c: the cost model, from counts alone */
typedef struct ll_cost_plan {
    size_t n, m, channels, threads;
    size_t layers_built, additions, doublings;
    double peak_bytes, seconds, cpu_seconds;
} ll_cost_plan;
/* The whole build's cost; params[word][channel] as ll_word_params_get. */
LL_INTERNAL void ll_material_cost(const ll_material *mat, const ll_word_params (*params)[3],
                                  size_t n, size_t m, size_t channels, size_t threads,
                                  ll_cost_plan *out);
/* Wall seconds of one word's layer, of one adding step and of writing. */
LL_INTERNAL double ll_cost_word(const ll_word_params *p, size_t n, size_t m, size_t threads);
LL_INTERNAL double ll_cost_add(size_t n, size_t m, size_t threads);
LL_INTERNAL double ll_cost_write(size_t n, size_t m, size_t n_channels);
/* LL_ERROR_OUT_OF_MEMORY naming the estimate, the budget and how to raise
 * it when peak_bytes > budget. */
LL_INTERNAL ll_status ll_check_budget(const ll_material *mat, const ll_cost_plan *plan,
                                      size_t budget, const char *fn);
/* Channels c whose stack is another's, and words equal to another
 * channel's (the sharing of material_build.c). */
LL_INTERNAL size_t ll_same_word_as(const ll_word_params (*params)[3], size_t w, size_t c);
LL_INTERNAL void ll_stack_owners(const ll_word_params (*params)[3], size_t w, size_t nch,
                                 const size_t *below, size_t *owner);

/* ---- material_metadata.c */
LL_INTERNAL ll_status ll_material_make_metadata(ll_material *m, const char *text);

#endif /* LL_MATERIAL_INTERNAL_H */
