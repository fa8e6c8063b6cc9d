/*
 * layerlab — the material language: a text description of a layer stack
 * (top to bottom, one word per line) compiled into layers or a .bsdf file.
 * The language is described in docs/material-language.md and by
 * `llbuild --help`:
 *
 *     # rough gold under a rough clear coat holding a thin blue-scattering layer
 *     dielectric  eta=1.5 alpha=0.1
 *     medium      albedo=0.25,0.0,0.95 g=0.5 tau=0.5
 *     conductor   eta=Au alpha=0.1
 *
 * Named metals (eta=Au) are read from NAME.eta.spd / NAME.k.spd spectra
 * found, in this order, in the folders of $LAYERLAB_IOR_DIR, the material
 * file's ior/ folder, and ../share/layerlab/ior from the folder of the
 * loaded liblayerlab (PREFIX/share/layerlab/ior once installed; in a build
 * tree build/share/layerlab/ior, the copy of the project's data/ior that
 * make puts there).
 *
 * An ll_material is immutable once parsed: it may be built from several
 * threads at once.
 */
#ifndef LAYERLAB_LL_MATERIAL_H
#define LAYERLAB_LL_MATERIAL_H

#include "ll_common.h"
#include "ll_layer.h"
#include "ll_bsdf_write.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct ll_material ll_material;

/* Parse a material description. source_name (nullable) names the text in
 * messages ("coated.layers:3:14: ..."). Errors: LL_ERROR_PARSE with file,
 * line, column and what was expected in ll_last_error_message() (also for
 * an unknown metal name or a missing or malformed measured file); *out is
 * NULL on failure. Relative `file=` paths resolve against the working
 * directory. */
LL_API ll_status ll_material_parse(const char *text, const char *source_name,
                                   ll_material **out);
/* The same for a file; relative `file=` paths inside resolve against the
 * file's directory. LL_ERROR_IO if it cannot be read. *out (NULL on
 * failure) is freed with ll_material_destroy. */
LL_API ll_status ll_material_parse_file(const char *path, ll_material **out);
/* Free a parsed material and everything it owns (axis names and
 * positions); NULL is fine. No build of it may still be running. */
LL_API void ll_material_destroy(ll_material *material);

/* The resolutions a build accepts: a node count is even and at least
 * LL_BUILD_MIN_NODES (with fewer, the quadrature's error in an albedo is
 * above 1%); node and order counts are at most LL_BUILD_MAX_RESOLUTION. */
#define LL_BUILD_MIN_NODES 10
#define LL_BUILD_MAX_RESOLUTION 100000

/* Options of a build. Every field's zero is its default. */
typedef struct ll_build_options {
    size_t struct_size;       /* sizeof(ll_build_options)                          */
    size_t n_nodes;           /* 0: the material's setting, else chosen (below)     */
    size_t n_orders;          /* 0: likewise                                        */
    size_t n_channels;        /* 0: from the material; 1 or 3 forces                */
    size_t threads;           /* 0: all processors                                  */
    /* The resolution's goal: the resolution chosen is within `tolerance`
     * (relative) of the converged layers where the BSDF is above 1% of its
     * peak, at every |mu| >= mu_min (ll_resolution_search_*, ll_layer.h).
     * 0: the material's `set tolerance= mu_min=`, else LL_DEFAULT_TOLERANCE
     * and LL_DEFAULT_MU_MIN. Ignored where the resolution is given
     * (n_nodes and n_orders, or the material's set nodes= orders=). */
    double tolerance;
    double mu_min;
    double error_goal;        /* series truncation; 0: the material's, else 1e-3  */
    /* Memory budget: a build whose estimated peak is above it is refused
     * before anything is allocated, with LL_ERROR_OUT_OF_MEMORY. 0: half of
     * the physical memory. */
    size_t max_memory_bytes;
    /* Each channel's finished layer: ll_material_build hands every
     * channel's stack to the file as soon as it is complete and frees it,
     * so that no two channels' stacks are alive at once; channel_done
     * (nullable) sees the layer just before that, on the calling thread
     * (channel 0 = R or mono, 1 = G, 2 = B, in the order the build finishes
     * them), e.g. to report its albedo. The layer is valid only during the
     * call. Not called by the other builds, which return the layers. */
    void (*channel_done)(void *user, size_t channel, const ll_layer *layer);
    void *channel_done_user;
    /* Where the resolution searches' choices are remembered between
     * processes (a directory, created when first written): a word searched
     * once at a tolerance and mu_min is not searched again by this library
     * version. NULL (the default): nothing is read or written there, so a
     * library call never writes to the user's files unasked;
     * ll_material_cache_dir gives the user's cache directory, which
     * llbuild and the Python package pass. Entries are one small file per
     * word, replaced atomically: builds may share the directory at once,
     * and a damaged entry is ignored and rewritten. */
    const char *cache_dir;
} ll_build_options;

#define LL_BUILD_OPTIONS_INIT \
    { sizeof(ll_build_options), 0, 0, 0, 0, 0.0, 0.0, 0.0, 0, NULL, NULL, NULL }

/* The user's cache directory for ll_build_options.cache_dir:
 * $LAYERLAB_CACHE_DIR if set, else $XDG_CACHE_HOME/layerlab (an absolute
 * XDG_CACHE_HOME), else $HOME/.cache/layerlab; written into buffer (size
 * bytes, NUL-terminated). Creates nothing. Errors:
 * LL_ERROR_INVALID_ARGUMENT for a NULL or too small buffer or when none of
 * the three variables is set. Thread-safe as getenv is. */
LL_API ll_status ll_material_cache_dir(char *buffer, size_t size);

/* The resolution's goal of a build with these options: the tolerance and
 * mu_min in effect (opts, else the material's set, else the defaults) and
 * whether the resolution is chosen by them (*chosen = 0 when both nodes
 * and orders are given by opts or the material). Instant. Any output may
 * be NULL. LL_ERROR_INVALID_ARGUMENT for a NULL material or bad options. */
LL_API ll_status ll_material_goal(const ll_material *material, const ll_build_options *opts,
                                  double *tolerance, double *mu_min, int *chosen);

/* The resolution and channel count a build with these options would use.
 * Choosing it by the tolerance runs the resolution search of every
 * distinct interface and medium (ll_resolution_search_*: up to seconds
 * each) that opts->cache_dir does not remember. monitor (nullable): stage
 * "resolution K/COUNT" during the K-th of the COUNT searches left; a
 * cancel returns LL_ERROR_CANCELLED. */
LL_API ll_status ll_material_resolution(const ll_material *material,
                                        const ll_build_options *opts,
                                        const ll_monitor *monitor, size_t *n_nodes,
                                        size_t *n_orders, size_t *n_channels);

/* Build and write a .bsdf file (atomically; a failed or cancelled build
 * leaves no file and does not touch an existing one). opts may be NULL.
 * Each channel's stack goes to the file as soon as it is complete and is
 * freed (opts->channel_done sees it first): its stored values wait in an
 * unlinked spill file beside out_path, which needs room for them there, and
 * the file is written from the spill at the end, byte for byte what
 * ll_material_build_layers then ll_material_write give. A swept material
 * (below) is written as a textured file.
 *
 * monitor (nullable): the fraction of the whole build (weighted by the
 * work of each step) and the stage ("resolution", "quadrature",
 * "dielectric interface", "medium", "adding", "writing", ...), on the
 * calling thread only. A non-zero return stops the build within one step
 * of the inner loops of whatever stage runs (every layer call polls) with
 * LL_ERROR_CANCELLED. A program that stops on a signal lets its handler
 * raise a flag that the monitor's callback returns: the callback is called
 * at least every 20 ms while the build runs.
 *
 * Errors: LL_ERROR_INVALID_ARGUMENT (options), LL_ERROR_CANCELLED,
 * LL_ERROR_NUMERICAL, LL_ERROR_OUT_OF_MEMORY (also when the estimated peak
 * is above opts->max_memory_bytes: refused before anything is allocated,
 * with the estimate and the budget in the message), LL_ERROR_IO
 * (writing). The worker-thread count of the calling thread
 * (ll_set_thread_count) is opts->threads during the build and restored
 * after it. */
LL_API ll_status ll_material_build(const ll_material *material, const ll_build_options *opts,
                                   const ll_monitor *monitor, const char *out_path);

/* Build in memory: layers receives n_channels layers (caller frees each with
 * ll_layer_destroy); header (nullable) receives the eta and alpha that a
 * file of this stack carries. The memory budget and the monitor as for
 * ll_material_build; a cancel returns no layers. A swept material is
 * refused (LL_ERROR_INVALID_ARGUMENT). */
LL_API ll_status ll_material_build_layers(const ll_material *material,
                                          const ll_build_options *opts,
                                          const ll_monitor *monitor, ll_layer *layers[3],
                                          size_t *n_channels, ll_bsdf_write_options *header);

/* Write layers that ll_material_build_layers returned (n_channels of them,
 * 1 or 3) to out_path as a .bsdf file with this material's header (eta,
 * alpha), its JSON description as metadata and the truncation error of
 * opts or the material. opts may be NULL; only error_goal is read.
 * Atomic, like ll_material_build; monitor (nullable) as for ll_bsdf_write:
 * a cancel, also at the last report before the file replaces out_path,
 * leaves no file and keeps an existing one. Statuses as ll_bsdf_write. */
LL_API ll_status ll_material_write(const ll_material *material, const ll_build_options *opts,
                                   ll_layer *const *layers, size_t n_channels,
                                   const char *out_path, const ll_monitor *monitor);

/* Number of words (layers) in the stack; 0 for NULL. */
LL_API size_t ll_material_word_count(const ll_material *material);

/* Does light leave the stack through its bottom? 1 unless the bottom word
 * is opaque (conductor, diffuse, an opaque measured table); a stack of
 * interfaces and media transmits whatever its indices (a pane of glass in
 * air has eta 1 and still transmits). 0 for NULL. */
LL_API int ll_material_transmits(const ll_material *material);

/* ------------------------------------------------------------ sweeps
 *
 * A number parameter written as a sweep, `alpha=[0.02 0.05 0.1]` or
 * `alpha=[0.05..0.4:8]` (docs/material-language.md, "Sweeps"), is one axis
 * of a textured .bsdf file: the file holds one basis per point of the
 * tensor product of the axes, axis 0 (the first sweep in the text, top
 * word first, left to right) fastest. ll_material_build writes such a
 * file; ll_material_build_layers and ll_material_write, which hold one
 * stack, refuse a swept material (LL_ERROR_INVALID_ARGUMENT). */

/* Number of swept parameters (axes): 0 for an untextured material. */
LL_API size_t ll_material_axis_count(const ll_material *material);

/* One axis. name: "LABEL.key" for a word given name=LABEL, else
 * "INDEX.key" with INDEX the word's 0-based position from the top of the
 * stack ("1.alpha"). positions: the n_values sample positions the file
 * stores (strictly increasing): each value, or for R,G,B triples their
 * luminance 0.212671 R + 0.715160 G + 0.072169 B. The strings and arrays
 * belong to the material and live as long as it. */
typedef struct ll_material_axis {
    size_t struct_size;       /* sizeof(ll_material_axis)                        */
    const char *name;
    size_t n_values;
    const double *positions;  /* [n_values]                                      */
} ll_material_axis;

#define LL_MATERIAL_AXIS_INIT { sizeof(ll_material_axis), NULL, 0, NULL }

/* Axis `axis` (< ll_material_axis_count) into *out (its struct_size set by
 * the caller; only the fields it covers are written).
 * LL_ERROR_INVALID_ARGUMENT for a NULL argument or an axis out of range. */
LL_API ll_status ll_material_get_axis(const ll_material *material, size_t axis,
                                      ll_material_axis *out);

/* Number of bases: the product of the axes' value counts; 1 for an
 * untextured material (0 for NULL). */
LL_API size_t ll_material_basis_count(const ll_material *material);

#ifdef __cplusplus
}
#endif
#endif /* LAYERLAB_LL_MATERIAL_H */

/* ------------------------------------------------------ experimental
 * Declared only when LL_EXPERIMENTAL is defined before the include: these
 * may change in a minor release (their symbols are in the version node
 * LAYERLAB_EXPERIMENTAL_1.0, not in the stable one). The block has its own
 * guard, so that a file included once without LL_EXPERIMENTAL and then
 * again with it gets these declarations. */
#if defined(LL_EXPERIMENTAL) && !defined(LAYERLAB_LL_MATERIAL_EXPERIMENTAL_H)
#define LAYERLAB_LL_MATERIAL_EXPERIMENTAL_H

#ifdef __cplusplus
extern "C" {
#endif

/* What a build with these options would take, from counts alone
 * (resolution, words, channels: no quadrature, no allocation that grows
 * with the resolution), so it is instant once the resolution is given;
 * choosing it by the tolerance runs the resolution searches first
 * (ll_material_resolution; monitor, nullable, as there). Memory: an upper bound of the build's peak
 * (the layers alive at once and the adding's workspace), the bound the
 * budget is checked against. Time: not estimated here; the counts of work
 * below are what a time model multiplies by its machine's rates (llbuild
 * --dry-run has one). For a swept material the counts cover every basis
 * (a word layer shared between bases counted once) and peak_bytes is the
 * builder's (a few bases at once, never all). */
typedef struct ll_build_estimate {
    size_t struct_size;       /* set by the caller: sizeof(ll_build_estimate)       */
    size_t n_nodes;           /* resolution and channels the build would use         */
    size_t n_orders;
    size_t n_channels;
    size_t n_bases;           /* ll_material_basis_count: 1 for an untextured build  */
    size_t threads;           /* worker threads the build would use                  */
    /* The largest relative error, where the BSDF is above 1% of its peak at
     * |mu| >= mu_min, that the chosen resolution was measured to against
     * twice itself, over every word (0 for words exact at any resolution);
     * HUGE_VAL when some word's resolution is the unverified fit
     * (ll_resolution_search_*); -1 when the resolution is given, not chosen. */
    double resolution_error;
    double peak_bytes;        /* upper bound of ll_material_build's peak memory      */
    double file_bytes;        /* the .bsdf file's size                               */
    size_t max_memory_bytes;  /* the budget in effect (opts or half the RAM)         */
    int over_budget;          /* non-zero: peak_bytes > max_memory_bytes, so a build
                                 with these options is refused                       */
    /* Work, after sharing between channels (and bases): */
    size_t layers_built;      /* word layers built                                   */
    size_t additions;         /* adding steps (doubling steps not included)          */
    size_t doublings;         /* doubling steps of all media                         */
    double dielectric_pairs;  /* node pairs (mu_i, mu_o) whose azimuthal series the
                                 dielectric interfaces compute, times their
                                 roughness in units of 0.1 (a rougher lobe takes
                                 more samples)                                      */
    double conductor_pairs;   /* the same for conductors (not weighted)              */
    double pair_orders;       /* those pairs times the orders they fill              */
    double measured_lookups;  /* table lookups of the measured words                 */
    double measured_files;    /* measured files read                                 */
    double phase_entries;     /* phase-matrix entries of the media (n^2 per order)   */
    double diffuse_entries;   /* matrix entries of the diffuse words                 */
    double add_entries;       /* n^2 per order holding values, over every adding and
                                 doubling step                                       */
    double add_empty_entries; /* n^2 per order that is zero in one of the operands   */
    double stored_values;     /* values the finished layers hold (the writing's work) */
} ll_build_estimate;

#define LL_BUILD_ESTIMATE_INIT                                                              \
    { sizeof(ll_build_estimate), 0, 0, 0, 0, 0, 0.0, 0.0, 0.0, 0, 0, 0, 0, 0,              \
      0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0 }

/* Fill *estimate (ll_build_estimate above; only the fields its struct_size
 * covers are written) for a build of material with opts (nullable:
 * defaults). Over the budget is not an error here: over_budget says so,
 * and ll_material_build would refuse. Statuses: LL_ERROR_INVALID_ARGUMENT
 * for a NULL material or estimate, a struct_size smaller than the
 * struct_size field itself or bad options; when the tolerance chooses the
 * resolution, those of ll_material_resolution (LL_ERROR_CANCELLED by the
 * monitor, LL_ERROR_INVALID_ARGUMENT when a search misses its tolerance,
 * LL_ERROR_OUT_OF_MEMORY). Threads: as ll_material_resolution (the
 * searches run on opts->threads workers); material may be shared. */
LL_API ll_status ll_material_estimate(const ll_material *material,
                                      const ll_build_options *opts,
                                      ll_build_estimate *estimate, const ll_monitor *monitor);

/* Non-zero when the stack's bottom word is opaque (conductor, diffuse,
 * measured), so no light leaves through it and a file of it holds
 * reflection only; 0 for a transmissive stack or NULL. Known from the
 * parsed text alone, before any build: a tool that writes a format holding
 * reflection only (ll_tables.h) refuses a transmissive stack with it. */
LL_API int ll_material_is_opaque(const ll_material *material);

typedef struct ll_material_builder ll_material_builder;

/* A builder makes the bases of a (swept or plain) material one at a time,
 * all at one resolution: the largest any basis's heuristics ask for, unless
 * the options or `set` give it. Word layers are shared between bases: a
 * word whose resolved parameters (its own values and the indices above it)
 * are those of a word already built is not built again but taken from a
 * cache of word layers (bounded: LRU over 64 entries kept in an unlinked
 * scratch file from tmpfile(), the 4 most recently used also in memory;
 * docs/material-language.md "Sweeps"), so an 8 x 8 coat x base grid built
 * in basis order builds 8 + 8 interfaces and 64 additions. Memory: those
 * few word layers, the quadrature and one basis's stack, whatever the
 * basis count. The budget of opts->max_memory_bytes applies to that peak
 * (ll_material_estimate). A builder is not thread-safe (one thread at a
 * time); several builders of one material may run in parallel.
 * monitor (nullable): the progress of each build_basis call as a whole
 * (stages "basis 3/64: adding", ...); a non-zero return cancels the call
 * in progress with LL_ERROR_CANCELLED, and the builder may be used again.
 * create fails
 * (LL_ERROR_INVALID_ARGUMENT) when bases would need different file
 * headers' eta (the format stores one relative index: sweep indices only
 * in opaque stacks) or the options are bad; LL_ERROR_OUT_OF_MEMORY over
 * the budget, as ll_material_build. *out is the new builder (NULL on
 * failure), freed by ll_material_builder_destroy. */
LL_API ll_status ll_material_builder_create(const ll_material *material,
                                            const ll_build_options *opts,
                                            const ll_monitor *monitor,
                                            ll_material_builder **out);

/* Build basis `basis` (< ll_material_basis_count; any order, though basis
 * order shares the most): layers receives *n_channels layers (the caller
 * destroys each with ll_layer_destroy), header (nullable) the file's
 * header: the eta and alpha of basis 0 (one per file), the material's
 * metadata, the error goal. Every basis has the same nodes and order count,
 * ready for ll_bsdf_writer_add_basis. Same statuses as
 * ll_material_build_layers. */
LL_API ll_status ll_material_builder_build_basis(ll_material_builder *builder, size_t basis,
                                                 ll_layer *layers[3], size_t *n_channels,
                                                 ll_bsdf_write_options *header);

/* Word layers the builder has built so far (a cache hit builds none), and
 * adding steps performed: what sharing saves, observable. NULL: 0. */
LL_API size_t ll_material_builder_layers_built(const ll_material_builder *builder);
LL_API size_t ll_material_builder_additions(const ll_material_builder *builder);

/* Frees the builder and its cache; NULL is fine. */
LL_API void ll_material_builder_destroy(ll_material_builder *builder);

#ifdef __cplusplus
}
#endif
#endif /* LL_EXPERIMENTAL */
