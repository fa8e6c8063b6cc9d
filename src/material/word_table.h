/*
 * The table of words of the material language: one descriptor per word
 * (diffuse, dielectric, conductor, medium, measured), which the parser, the
 * stack checks, the resolution, the cost model, the build and the metadata
 * iterate over. A word is one file, src/material/word_NAME.c, holding its
 * descriptor (its functions static inside), plus one entry in the table of
 * word_table.c; nothing else names a word.
 */
#ifndef LL_MATERIAL_WORD_TABLE_H
#define LL_MATERIAL_WORD_TABLE_H

#include "material/material.h"
#include "support/watch.h"

/* ------------------------------------------------ parsing, for the words */

/* A token: text [begin, begin + len) of the current line. */
typedef struct ll_token {
    const char *begin;
    size_t len;
} ll_token;

typedef struct ll_parser ll_parser; /* material_parse.c */
typedef struct ll_param_desc ll_param_desc; /* below */

LL_INTERNAL int ll_token_is(const ll_token *t, const char *s);
/* Split a value at commas (R,G,B): up to 3 parts. Returns the part count,
 * or 0 for more than 3 or an empty part. */
LL_INTERNAL int ll_split_commas(const ll_token *v, ll_token parts[3]);
/* source:line:column: what (LL_ERROR_PARSE). */
LL_INTERNAL ll_status ll_parse_error(const ll_parser *p, const char *at, const char *fmt, ...)
    LL_PRINTF(3, 4);
/* One value or three comma-separated ones (R,G,B). */
LL_INTERNAL ll_status ll_parse_number(const ll_parser *p, const ll_token *key,
                                      const ll_token *v, ll_number *out);
/* Every value of x within [lo, hi] (each bound closed when its flag is set),
 * else "key=value is out of range: why". */
LL_INTERNAL ll_status ll_parse_check_range(const ll_parser *p, const ll_token *key,
                                           const ll_token *v, const ll_number *x, double lo,
                                           int lo_closed, double hi, int hi_closed,
                                           const char *why);
/* One real number, the whole of [s, s + len): digits with an optional
 * sign, point and exponent (no hex, inf or nan). 1 if it is one. */
LL_INTERNAL int ll_scan_real(const char *s, size_t len, double *out);
LL_INTERNAL size_t ll_parser_line(const ll_parser *p);
LL_INTERNAL size_t ll_parser_column(const ll_parser *p, const char *at);
/* The material file's directory (names and relative paths), or NULL. */
LL_INTERNAL const char *ll_parser_dir(const ll_parser *p);

/* Sweeps (material_sweep.c): v = "[...]" for number parameter `param` of
 * word w (the material's last): its values into a new axis of m, the
 * first into the word's slot; and name=LABEL of a word. */
LL_INTERNAL ll_status ll_parse_sweep(const ll_parser *p, ll_material *m, ll_word *w,
                                     const ll_param_desc *param, const ll_token *key,
                                     const ll_token *v);
LL_INTERNAL ll_status ll_parse_label(const ll_parser *p, ll_word *w, const ll_token *key,
                                     const ll_token *v);

/* --------------------------------------------- metadata, for the words */

typedef struct ll_text {
    char *data;
    size_t len, cap;
    int failed;
} ll_text;

LL_INTERNAL void ll_text_append(ll_text *b, const char *fmt, ...) LL_PRINTF(2, 3);
LL_INTERNAL void ll_text_string(ll_text *b, const char *s); /* a JSON string */
/* , "key": v or , "key": [r, g, b]; nothing when x is absent. */
LL_INTERNAL void ll_text_number(ll_text *b, const char *key, const ll_number *x);

/* ------------------------------------------------------- the descriptors */

/* One parameter of a word. A number (parse == NULL) is stored in
 * ll_word.number[slot], may be one value or three (R, G, B) and must lie
 * in [lo, hi]; `check` (nullable) adds what a range cannot say. Other
 * parameters (a name, a path, a choice) parse themselves. */
struct ll_param_desc {
    const char *key;
    int required;
    int slot;                 /* index into ll_word.number, or -1       */
    double lo, hi;
    int lo_closed, hi_closed;
    const char *why;          /* the range's reason, in the message     */
    ll_status (*parse)(const ll_parser *p, ll_word *w, const ll_token *key,
                       const ll_token *v);
    ll_status (*check)(const ll_parser *p, const ll_word *w, const ll_token *key,
                       const ll_token *v, const ll_number *x);
};

/* The context a word's builder gets: the monitor to pass to its next
 * public layer call (credited with `share` of the word's modelled cost; it
 * carries the build's progress and cancellation; share 0 shows the call
 * under its own stage name, e.g. "phase function"), and the doubling of a
 * medium with the build's progress (ll_layer_expand). The builder uses
 * only public calls (ll_layer.h). */
typedef struct ll_word_build_ctx {
    const ll_monitor *(*monitor)(void *user, double share);
    ll_status (*expand)(void *user, ll_layer *layer, double tau);
    void *user;
} ll_word_build_ctx;

/* What one word's layer costs to build at n nodes and m orders, one
 * channel: its work by kind (its doublings not included), and, as
 * measured (docs/material-language.md, "Estimates"), the CPU seconds of
 * the part that runs in parallel over `items` (columns or orders) and of
 * the serial part (the progress weights), the doublings after it, the
 * orders that hold anything (what an adding step with it works on), its
 * stored values in units of n x n (dense_orders; what its layer keeps),
 * the scratch bytes of each thread while it is built and what it holds
 * once while it is built (a measured table). */
typedef struct ll_word_cost {
    ll_work work;
    double parallel_seconds;
    size_t items;
    double serial_seconds;
    size_t doublings;
    double orders_nonzero;
    double dense_orders;
    double thread_bytes;
    double build_bytes;       /* held once while it is built (a table)   */
} ll_word_cost;

#define LL_WORD_MAX_PARAMS 8

struct ll_word_desc {
    const char *name;
    const char *example;      /* a whole line, for messages              */
    const char *stage;        /* progress stage name                     */
    int opaque;               /* no light through: only at the bottom    */
    int interface;            /* its alpha is the header's roughness      */
    ll_param_desc params[LL_WORD_MAX_PARAMS]; /* up to the first key NULL */
    /* Checks once the whole line is read (nullable). */
    ll_status (*finish)(const ll_parser *p, ll_word *w, const char *word_at);
    /* Colour even without a three-valued number (nullable). */
    int (*needs_colour)(const ll_word *w);
    /* The relative index of refraction it puts below itself in channel c
     * (nullable: 1, index-matched). */
    double (*index_ratio)(const ll_word *w, size_t c, size_t n_channels);
    /* Plain numbers of channel c; `above` is the absolute index of the
     * medium right above the word. out is zeroed, out->desc set. */
    void (*channel)(const ll_word *w, size_t c, size_t n_channels, double above,
                   ll_word_params *out);
    /* Nodes and orders it needs to be within `tolerance` (relative) of the
     * converged layer at |mu| >= mu_min (the ll_resolution_search_* of
     * ll_layer.h); *error receives the largest relative error measured
     * against twice that resolution (0 for words exact at any resolution,
     * HUGE_VAL when it is beyond the search's reach and not verified); may
     * fail with a message naming the largest supported parameter. watch
     * (nullable): a search polls it (LL_ERROR_CANCELLED) and advances its
     * stage by up to LL_PROBE_SEARCH_UNITS (search/probe.h). A word with
     * resolution_starts reads *n_nodes, *n_orders on entry: where to start
     * its search (0, 0: its own first guess). */
    ll_status (*resolution)(const ll_word_params *p, double tolerance, double mu_min,
                            ll_watch *watch, size_t *n_nodes, size_t *n_orders, double *error);
    void (*cost)(const ll_word_params *p, size_t n, size_t m, ll_word_cost *out);
    /* Fill a created layer (any content) for one channel. */
    ll_status (*build)(const ll_word_build_ctx *ctx, const ll_word *w, const ll_word_params *p,
                       ll_layer *layer);
    /* Its fields of the JSON description: , "key": value ... */
    void (*metadata)(ll_text *b, const ll_word *w);
    /* Release what parse allocated in w (nullable). */
    void (*destroy)(ll_word *w);
    /* Bit k set: the resolution hook reads v[k] (words whose read values
     * are equal share one resolution search); 0: it may read them all. */
    unsigned resolution_reads;
    /* 1: the resolution hook starts where it is told (above): a channel's
     * search begins at the answer for the channel before it, which is
     * nearer than the word's own first guess (gold's three channels at
     * alpha 0.1 each chose 112 x 277, from a first guess of 76 x 227). */
    int resolution_starts;
};

/* The words, in the order messages list them. */
LL_INTERNAL extern const ll_word_desc *const ll_word_table[];
LL_INTERNAL extern const size_t ll_word_table_size;

/* The descriptors, one per word_NAME.c. */
LL_INTERNAL extern const ll_word_desc ll_word_diffuse;
LL_INTERNAL extern const ll_word_desc ll_word_dielectric;
LL_INTERNAL extern const ll_word_desc ll_word_conductor;
LL_INTERNAL extern const ll_word_desc ll_word_medium;
LL_INTERNAL extern const ll_word_desc ll_word_measured;

/* Where each word keeps its numbers (ll_word.number) and its per-channel
 * values (ll_word_params.v): the words' own files and the tests use these. */
enum { LL_DIFFUSE_ALBEDO = 0 };
enum { LL_DIELECTRIC_ETA = 0, LL_DIELECTRIC_ALPHA = 1, LL_DIELECTRIC_COMPENSATE = 2 };
                                              /* values: eta, alpha, compensate */
enum { LL_CONDUCTOR_ETA = 0, LL_CONDUCTOR_K = 1, LL_CONDUCTOR_ALPHA = 2,
       LL_CONDUCTOR_COMPENSATE = 3 };         /* likewise, relative to the medium above */
enum { LL_MEDIUM_ALBEDO = 0, LL_MEDIUM_TAU = 1, LL_MEDIUM_G = 2, LL_MEDIUM_KAPPA = 3,
       LL_MEDIUM_SHAPE = 2 /* value: g (HG) or kappa (vMF) */ };
typedef enum { LL_PHASE_ISOTROPIC, LL_PHASE_HG, LL_PHASE_VMF } ll_phase; /* medium's choice */
enum { LL_MEASURED_WEIGHT_R = 0 }; /* values: the weights of the MERL channels R, G, B */

/* --------------------------------------- shared by the words' cost models */

/* Doublings that ll_layer_expand performs for tau on nodes whose smallest
 * |mu| is min_mu. */
LL_INTERNAL size_t ll_doubling_count(double tau, double min_mu);

/* The cost of a rough interface (ll_layer_set_microfacet) of roughness
 * alpha, relative index eta_re + i eta_im and distribution
 * (LL_DISTRIBUTION_*; material_estimate.c). */
/* Per-order CPU seconds of an adding or doubling step per n x n entry:
 * orders where both layers hold something, and the others (a pass over
 * the storage). */
#define LL_COST_ADD_ORDER 4.5e-9
#define LL_COST_ADD_EMPTY 3e-10
LL_INTERNAL void ll_interface_cost(double alpha, double eta_re, double eta_im,
                                   int distribution, size_t n, size_t m, ll_word_cost *out);

/* The roughness parameter of interfaces: its lower limit is the one of
 * ll_layer_set_microfacet. */
#define LL_PARAM_ALPHA(slot_)                                                               \
    { "alpha", 1, (slot_), LL_MICROFACET_MIN_ALPHA, 1e300, 1, 1,                            \
      "the roughness alpha must be >= 0.001 (LL_MICROFACET_MIN_ALPHA: smoother "            \
      "interfaces need more Fourier orders than a layer can hold)",                       \
      NULL, NULL }

/* compensate=0|1 of the interfaces: whether the paper's energy
 * compensation term is added (ll_microfacet.compensate;
 * default 1). 0 gives the single-scattering interface that renderers'
 * microfacet BSDFs are, for comparisons with them. */
LL_INTERNAL ll_status ll_check_compensate(const ll_parser *p, const ll_word *w,
                                          const ll_token *key, const ll_token *v,
                                          const ll_number *x);
#define LL_PARAM_COMPENSATE_WHY                                                             \
    "compensate is 1 (energy compensation, the default) or 0 (single scattering only)"
#define LL_PARAM_COMPENSATE(slot_)                                                          \
    { "compensate", 0, (slot_), 0.0, 1.0, 1, 1, LL_PARAM_COMPENSATE_WHY, NULL,               \
      ll_check_compensate }
/* The value of a word's compensate in its parameters: 1 unless given. */
LL_INTERNAL double ll_compensate_value(const ll_number *x);

/* dist=beckmann|ggx of the interfaces: the microfacet distribution, the
 * word's choice (LL_DISTRIBUTION_* of words/microfacet.h; Beckmann unless
 * given), which the parameters carry as their choice. */
LL_INTERNAL ll_status ll_parse_distribution(const ll_parser *p, ll_word *w, const ll_token *key,
                                            const ll_token *v);
#define LL_PARAM_DISTRIBUTION { "dist", 0, -1, 0, 0, 0, 0, NULL, ll_parse_distribution, NULL }
/* , "dist": "ggx" when dist= is given (a file without it describes the
 * Beckmann interface it always did). */
LL_INTERNAL void ll_distribution_metadata(ll_text *b, const ll_word *w);

#endif /* LL_MATERIAL_WORD_TABLE_H */
