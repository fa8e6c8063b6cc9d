/*
 * The material language, inside: a parsed stack of words (material_parse.c),
 * what each word means per colour channel and the stack's header
 * (material_stack.c), the resolution and cost of a build
 * (material_resolution.c, material_estimate.c), the sharing between
 * channels that the build and its cost follow (material_sharing.c), the
 * JSON description stored in files (material_metadata.c) and the build
 * itself (material_build.c).
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
/* name=LABEL of a word: at most this many characters. */
#define LL_WORD_LABEL_MAX 32
/* Swept parameters of one material (the axes of its textured file). */
#define LL_MATERIAL_MAX_AXES 4

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
    char label[LL_WORD_LABEL_MAX + 1]; /* name=LABEL ("" if none): axis names */
    size_t label_line, label_column;
} ll_word;

/* A swept parameter (material_sweep.c): one axis of a textured file. The
 * word's number[slot] holds values[0], so everything that reads one
 * material (the stack checks, the channel count) sees the first basis. */
typedef struct ll_sweep {
    size_t word;              /* the word's index, 0 at the top           */
    int slot;                 /* its ll_word.number slot                  */
    size_t count;             /* values (>= 2)                            */
    ll_number *values;        /* [count] as written: one value or three   */
    double *positions;        /* [count] stored in the file: the value, or
                                 the luminance of a triple               */
    char name[LL_WORD_LABEL_MAX + 48]; /* "coat.alpha" or "1.alpha"      */
} ll_sweep;

struct ll_material {
    char *source;             /* name used in messages                   */
    ll_word *words;           /* top to bottom                           */
    size_t count, capacity;   /* words used, allocated                   */
    size_t nodes, orders, channels; /* settings; 0 = not set             */
    double error_goal;        /* 0 = not set                              */
    double tolerance, mu_min; /* the resolution's goal; 0 = not set       */
    char *metadata;           /* JSON stored in written files             */
    ll_sweep axes[LL_MATERIAL_MAX_AXES]; /* in order of appearance       */
    size_t n_axes;
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
    const char *file; /* the word's table (measured), or NULL: part of its identity */
} ll_word_params;

/* Luminance weights of linear sRGB (as the .bsdf Y channel). */
#define LL_LUMA_R 0.212671
#define LL_LUMA_G 0.715160
#define LL_LUMA_B 0.072169

/* ---- material_stack.c */
/* Does the description ask for colour (any three-valued number, a named
 * metal, a measured BRDF)? */
LL_INTERNAL int ll_material_is_rgb(const ll_material *m);
/* ll_material_is_opaque: public (ll_material.h, experimental). */
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
/* Resolution and channels for a build (options > settings > searches),
 * checked against the smallest meaningful resolution. With a monitor
 * (nullable; ll_common.h), as a build's stage: the searches of the
 * resolution (up to 5-18 s for a measured table) poll it, a cancel returns
 * LL_ERROR_CANCELLED with nothing allocated, and the progress goes through
 * the words (stage "resolution"). */
LL_INTERNAL ll_status ll_material_plan(const ll_material *m, const ll_build_options *o,
                                          const ll_monitor *monitor, size_t *n_nodes,
                                          size_t *n_orders, size_t *n_channels);
/* The words' answers so far, so that a word probed once (in one channel,
 * one basis) is not probed again: ll_material_plan_memo over the bases of
 * a swept material shares one memo. */
typedef struct ll_resolution_memo {
    ll_word_params *key;
    size_t (*answer)[2];
    double *error;
    size_t count, capacity;
    /* Nullable: polled by the searches, one stage ("resolution") per
     * word and channel (see ll_material_plan). */
    struct ll_watch *watch;
} ll_resolution_memo;
#define LL_RESOLUTION_MEMO_INIT { NULL, NULL, NULL, 0, 0, NULL }
/* error (nullable): the largest error a word's resolution was verified
 * to (HUGE_VAL: some word not verified), -1 when the resolution is given. */
LL_INTERNAL ll_status ll_material_plan_memo(const ll_material *m, const ll_build_options *o,
                                            ll_resolution_memo *memo, size_t *n_nodes,
                                            size_t *n_orders, size_t *n_channels,
                                            double *error);
LL_INTERNAL void ll_resolution_memo_free(ll_resolution_memo *memo);

/* ---- resolution_cache.c: the searches' choices kept between processes
 * in dir (ll_build_options.cache_dir; NULL or "" for none), keyed by the
 * word as its search sees it (and start: where its search started, the
 * nodes and orders; NULL or zeros for its own first guess), the tolerance,
 * mu_min and the library's version. get: 1 and the answer when a whole,
 * undamaged entry is there, else 0. put: writes the entry atomically (a
 * temporary file renamed over it), creating dir; a failure to write is
 * silent (a later build searches again). Neither touches the thread's
 * error message. */
LL_INTERNAL int ll_resolution_cache_get(const char *dir, const ll_word_params *p,
                                        const size_t *start, double tolerance, double mu_min,
                                        size_t *n, size_t *m, double *error);
LL_INTERNAL void ll_resolution_cache_put(const char *dir, const ll_word_params *p,
                                         const size_t *start, double tolerance, double mu_min,
                                         size_t n, size_t m, double error);
/* The smallest node count whose quadrature is meaningful
 * (docs/material-language.md, "Settings"), and the largest node or order
 * count a build accepts. */
#define LL_MATERIAL_MIN_NODES LL_BUILD_MIN_NODES
#define LL_MATERIAL_MAX_RESOLUTION LL_BUILD_MAX_RESOLUTION

/* ---- material_sharing.c: the one walk of a build's sharing between
 * channels, followed by the build, its progress weights and the cost
 * models. Levels go bottom-up, one per word; at each, channel c's stack is
 * owner[c]'s (c: its own) and, for an owner, its word layer is same[c]'s
 * (c: its own to make). After the last level, owner[] says whose finished
 * stack each channel's is. */
typedef struct ll_level_walk {
    const ll_word_params (*params)[3]; /* [word][channel] */
    size_t count, nch;
    size_t word;              /* this level's word, 0 at the top            */
    int bottom, top;          /* the first level, the last                  */
    size_t below[3];          /* owner[] of the level below (not at the bottom) */
    size_t owner[3];
    size_t same[3];
} ll_level_walk;
LL_INTERNAL void ll_level_walk_begin(ll_level_walk *walk, const ll_word_params (*params)[3],
                                     size_t count, size_t nch);
/* The next level up; 0 when the top was the last (owner[] is kept). */
LL_INTERNAL int ll_level_walk_next(ll_level_walk *walk);
/* The whole walk at once: levels[k] (count of them) is the walk at its
 * level k, bottom-up (levels[0] is the bottom word's). */
LL_INTERNAL void ll_material_levels(const ll_word_params (*params)[3], size_t count, size_t nch,
                                    ll_level_walk *levels);
/* Do two words build the same layer? (Equal parameters, the same table:
 * what the channels, a builder's cache and the resolution memo share.) */
LL_INTERNAL int ll_word_params_equal(const ll_word_params *a, const ll_word_params *b);

/* ---- material_estimate.c: the cost model, from counts alone */
/* Work by kind, the counts of ll_build_estimate: what a time model
 * multiplies by its machine's rates (llbuild --dry-run has one). */
typedef struct ll_work {
    double dielectric_pairs;  /* node pairs of dielectric interfaces, x alpha / 0.1 */
    double conductor_pairs;   /* node pairs of conductors                          */
    double pair_orders;       /* the interfaces' pairs x orders                    */
    double measured_lookups, measured_files;
    double phase_entries;     /* n^2 per order holding a phase function            */
    double diffuse_entries;   /* n^2 per diffuse word                              */
    double add_entries;       /* n^2 per order holding values, per adding or
                                 doubling step                                     */
    double add_empty_entries; /* n^2 per order empty in an operand, likewise       */
} ll_work;
/* acc += times * w, field by field. */
LL_INTERNAL void ll_work_add(ll_work *acc, const ll_work *w, double times);

typedef struct ll_cost_plan {
    size_t n, m, channels, threads;
    size_t layers_built, additions, doublings;
    double peak_bytes;
    ll_work work;             /* every step, after sharing                        */
    double held_peak_bytes;   /* a build that keeps every channel's stack to the
                                 end (ll_material_build_layers), peak_bytes
                                 being ll_material_build's streamed one     */
    double stored_values;     /* values the finished layers hold, all channels */
    double file_bytes;        /* the .bsdf file's estimated size              */
} ll_cost_plan;
/* The whole build's cost; params[word][channel] as ll_word_params_get. */
LL_INTERNAL void ll_material_cost(const ll_material *mat, const ll_word_params (*params)[3],
                                  size_t n, size_t m, size_t channels, size_t threads,
                                  ll_cost_plan *out);
/* One word's work (its doublings included), doublings and the bytes its
 * layer keeps. */
LL_INTERNAL void ll_cost_word_detail(const ll_word_params *p, size_t n, size_t m,
                                     ll_work *work, size_t *doublings, double *bytes);
/* The resident bytes of a process before any layer. */
LL_INTERNAL double ll_cost_process_bytes(void);
/* material_sweep_estimate.c: the cost of every basis of a swept material
 * built by a builder (its cache of word layers simulated), and a file's
 * size from the values its layers hold (stored_values per basis). */
LL_INTERNAL ll_status ll_material_cost_bases(const ll_material *m, size_t n, size_t orders,
                                             size_t nch, size_t threads, ll_cost_plan *out);
LL_INTERNAL double ll_file_bytes_estimate(size_t n, size_t nch, size_t n_bases,
                                          size_t n_parameter_values, double stored_values);
/* LL_ERROR_OUT_OF_MEMORY naming the estimate, the budget and how to raise
 * it when peak_bytes > budget. */
LL_INTERNAL ll_status ll_check_budget(const ll_material *mat, const ll_cost_plan *plan,
                                      size_t budget, const char *fn);
/* What the build of material_build.c takes from the cost model, in one
 * call: its peak bytes (streamed, or every stack held to the end; a
 * distributed build's ranks hold 1 / ranks each), checked against budget
 * as ll_check_budget, and its progress weights, the relative cost of each
 * word layer it makes (the walk's levels, bottom-up), of an adding step and
 * of the writing, in the units of the rates measured on the development
 * machine (only their ratios matter; a build's time is llbuild's model,
 * from the counts). */
typedef struct ll_build_weights {
    double (*word)[3];        /* [word][channel], the caller's array; set where
                                 the walk's owner makes its word layer      */
    double add, write;
    double total;             /* the words and addings, in the build's order */
} ll_build_weights;
LL_INTERNAL ll_status ll_material_cost_build(const ll_material *mat,
                                             const ll_word_params (*params)[3],
                                             const ll_level_walk *levels, size_t n, size_t m,
                                             size_t nch, size_t threads, int streamed,
                                             size_t ranks, size_t budget, const char *fn,
                                             double *peak_bytes, ll_build_weights *weights);
/* ---- material_sweep.c */
/* Once the text is read: labels unique, axis names. */
LL_INTERNAL ll_status ll_material_finish_axes(ll_material *m);
LL_INTERNAL void ll_material_free_axes(ll_material *m);
/* The axis indices of basis b (parameter 0 fastest). */
LL_INTERNAL void ll_basis_indices(const ll_material *m, size_t basis, size_t *index);
/* Basis `basis` as a plain material: *out shares everything with m except
 * its words, copied into words (m->count of them) with the swept numbers
 * of that basis; no axes. Never destroyed (nothing of its own). */
LL_INTERNAL void ll_material_basis_view(const ll_material *m, size_t basis, ll_word *words,
                                        ll_material *out);
/* ll_material_plan over every basis: the largest resolution any asks for
 * (all bases of a file share nodes and orders). watch (nullable): polled
 * by the searches. */
LL_INTERNAL ll_status ll_material_plan_bases(const ll_material *m, const ll_build_options *o,
                                             struct ll_watch *watch, size_t *n_nodes, size_t *n_orders,
                                             size_t *n_channels, double *error);

/* ---- material_sweep_cache.c: the builder's cache of word layers: LRU
 * over LL_WORD_CACHE_ENTRIES entries kept in a scratch file, of which the
 * LL_WORD_CACHE_IN_MEMORY most recently used also stay in memory
 * (material_sweep_estimate.c simulates it) */
#define LL_WORD_CACHE_ENTRIES 64
#define LL_WORD_CACHE_IN_MEMORY 4
typedef struct ll_word_cache ll_word_cache;
/* *out = a copy of the cached layer of word `word` with parameters p (read
 * back from the file if need be), or NULL when there is none. */
LL_INTERNAL ll_status ll_word_cache_get(ll_word_cache *c, size_t word, const ll_word_params *p,
                                        ll_layer **out);
/* Keep a copy of layer (sharing its orders), evicting the least recently
 * used entry when full; counts a layer built. */
LL_INTERNAL ll_status ll_word_cache_put(ll_word_cache *c, size_t word, const ll_word_params *p,
                                        const ll_layer *layer);
LL_INTERNAL void ll_word_cache_count_addition(ll_word_cache *c);
/* NULL when out of memory; destroy frees its layers and scratch file
 * (NULL is fine); the counts of layers built and additions (0 for NULL). */
LL_INTERNAL ll_word_cache *ll_word_cache_create(void);
LL_INTERNAL void ll_word_cache_destroy(ll_word_cache *c);
LL_INTERNAL size_t ll_word_cache_built(const ll_word_cache *c);
LL_INTERNAL size_t ll_word_cache_additions(const ll_word_cache *c);
/* ---- material_sweep_build.c */
/* ll_material_build for a swept material: builder and streaming writer. */
LL_INTERNAL ll_status ll_material_build_textured(const ll_material *m,
                                                 const ll_build_options *opts,
                                                 const ll_monitor *monitor,
                                                 const char *out_path);
/* ---- material_build.c: one stack, its word layers shared through cache
 * (nullable); refuses nothing swept-related (the caller passes a basis). */
LL_INTERNAL ll_status ll_material_build_layers_cached(const ll_material *material,
                                                      const ll_build_options *opts,
                                                      const ll_monitor *monitor,
                                                      ll_word_cache *cache, ll_layer *layers[3],
                                                      size_t *n_channels,
                                                      ll_bsdf_write_options *header);

/* ---- material_metadata.c */
LL_INTERNAL ll_status ll_material_make_metadata(ll_material *m, const char *text);

#endif /* LL_MATERIAL_INTERNAL_H */
