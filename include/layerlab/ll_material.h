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
 * file's directory. LL_ERROR_IO if it cannot be read. */
LL_API ll_status ll_material_parse_file(const char *path, ll_material **out);
LL_API void ll_material_destroy(ll_material *material);

/* Progress: fraction in [0, 1] of the whole build, a short stage name
 * ("dielectric interface", "medium", "adding", "writing"). Called on the
 * thread that called the build. */
typedef void (*ll_progress_fn)(double fraction, const char *stage, void *user);

typedef struct ll_build_options {
    size_t struct_size;        /* sizeof(ll_build_options)                         */
    size_t n_nodes;            /* 0: the material's setting, else the heuristic     */
    size_t n_orders;           /* 0: likewise                                       */
    size_t n_channels;         /* 0: from the material; 1 or 3 forces               */
    size_t threads;            /* 0: all processors                                 */
    double error_goal;         /* 0: the material's setting, else 1e-3              */
    ll_progress_fn progress;   /* nullable                                          */
    void *progress_user;
    const volatile int *cancel;/* nullable; nonzero stops with LL_ERROR_CANCELLED
                                  (deprecated: prefer an ll_monitor, *_ex below)  */
    /* Memory budget (appended in 1.x; callers whose struct_size ends before
     * it get the default). A build whose estimated peak (ll_material_estimate)
     * is above it is refused before anything is allocated, with
     * LL_ERROR_OUT_OF_MEMORY. 0: half of the physical memory. */
    size_t max_memory_bytes;
    /* The resolution's goal (appended in 1.x, issue 14; callers whose
     * struct_size ends before them get the defaults): the resolution that
     * the heuristics choose is within `tolerance` (relative) of the
     * converged layers where the BSDF is above 1% of its peak, at every
     * |mu| >= mu_min (ll_heuristic_microfacet_ex, ll_layer.h).
     * 0: the material's `set tolerance= mu_min=`, else LL_DEFAULT_TOLERANCE
     * (0.01) and LL_DEFAULT_MU_MIN (0.1). Ignored where the resolution is
     * given (n_nodes and n_orders, or the material's set nodes= orders=). */
    double tolerance;
    double mu_min;
} ll_build_options;

#define LL_BUILD_OPTIONS_INIT                                                               \
    { sizeof(ll_build_options), 0, 0, 0, 0, 0.0, NULL, NULL, NULL, 0, 0.0, 0.0 }

/* The resolution's goal of a build with these options: the tolerance and
 * mu_min in effect (opts, else the material's set, else the defaults) and
 * whether the heuristics choose the resolution by them (*chosen = 0 when
 * both nodes and orders are given by opts or the material). Instant. Any
 * output may be NULL. */
LL_API ll_status ll_material_goal(const ll_material *material, const ll_build_options *opts,
                                  double *tolerance, double *mu_min, int *chosen);

/* The resolution and channel count a build with these options would use.
 * Choosing it by the tolerance probes every interface and medium (about a
 * second for the examples; ll_heuristic_microfacet_ex). */
LL_API ll_status ll_material_resolution(const ll_material *material,
                                        const ll_build_options *opts, size_t *n_nodes,
                                        size_t *n_orders, size_t *n_channels);

/* Build and write a .bsdf file (atomically; a failed or cancelled build
 * leaves no file and does not touch an existing one). opts may be NULL.
 * Errors: LL_ERROR_INVALID_ARGUMENT (options), LL_ERROR_CANCELLED,
 * LL_ERROR_NUMERICAL, LL_ERROR_OUT_OF_MEMORY (also when the estimated peak
 * is above opts->max_memory_bytes: refused before anything is allocated,
 * with the estimate and the budget in the message), LL_ERROR_IO
 * (writing). The
 * worker-thread count of the calling thread (ll_set_thread_count) is
 * opts->threads during the build and restored after it. */
LL_API ll_status ll_material_build(const ll_material *material, const ll_build_options *opts,
                                   const char *out_path);

/* Build in memory: layers receives n_channels layers (caller frees each with
 * ll_layer_destroy); header (nullable) receives the eta and alpha that a
 * file of this stack carries. The memory budget applies as to
 * ll_material_build. */
LL_API ll_status ll_material_build_layers(const ll_material *material,
                                          const ll_build_options *opts,
                                          ll_layer *layers[3], size_t *n_channels,
                                          ll_bsdf_write_options *header);

/* The two builds with a monitor (ll_common.h; NULL = the plain call): the
 * fraction of the whole build (cost-weighted, as opts->progress, which is
 * still called too) and the stage ("quadrature", "dielectric interface",
 * "medium", "adding", "writing", ...), on the calling thread only. A
 * non-zero return stops the build within one step of the inner loops of
 * whatever stage runs (every layer call polls) with LL_ERROR_CANCELLED: no
 * file is written and an existing one is kept; no layers are returned.
 * opts->cancel, a flag that may be raised from a signal handler, works the
 * same way and is kept as a deprecated alias of a monitor that returns
 * non-zero: the calling thread reads it at least every 20 ms while a layer
 * call runs (also while it waits for workers), and the workers stop at
 * their next poll. */
LL_API ll_status ll_material_build_ex(const ll_material *material, const ll_build_options *opts,
                                      const ll_monitor *monitor, const char *out_path);
LL_API ll_status ll_material_build_layers_ex(const ll_material *material,
                                             const ll_build_options *opts,
                                             const ll_monitor *monitor, ll_layer *layers[3],
                                             size_t *n_channels,
                                             ll_bsdf_write_options *header);

/* Write layers that ll_material_build_layers returned (n_channels of them,
 * 1 or 3) to out_path as a .bsdf file with this material's header (eta,
 * alpha), its JSON description as metadata and the truncation error of
 * opts or the material. Atomic, like ll_material_build: opts->cancel is
 * checked once the file is complete and before it replaces out_path, so a
 * cancelled or failed write leaves no file and keeps an existing one.
 * opts may be NULL; only error_goal and cancel are read. */
LL_API ll_status ll_material_write(const ll_material *material, const ll_build_options *opts,
                                   ll_layer *const *layers, size_t n_channels,
                                   const char *out_path);

/* Number of words (layers) in the stack. */
LL_API size_t ll_material_word_count(const ll_material *material);

/* What a build with these options would take, estimated from counts
 * alone (resolution, words, channels: no quadrature, no allocation that
 * grows with the resolution), so it is instant for any input once the
 * resolution is given (llbuild --dry-run); choosing it by the tolerance
 * probes each distinct word first (ll_material_resolution: about a second
 * each). Memory: the layers alive at once and the adding's
 * workspace, as stored compactly; time: per-stage operation counts times
 * rates measured on a 2-core x86-64 machine with OpenBLAS
 * (docs/material-language.md, "Estimates", gives the model and its error
 * on the examples). The estimate may have the struct_size of an older
 * version of this struct (ending at `seconds`); the fields past it are
 * then not written. */
typedef struct ll_build_estimate {
    size_t struct_size;   /* set by the caller: sizeof(ll_build_estimate)       */
    size_t n_nodes;       /* resolution and channels the build would use         */
    size_t n_orders;
    size_t n_channels;
    size_t layers_built;  /* word layers built, after sharing between channels   */
    size_t additions;     /* adding steps (doubling steps not included)          */
    size_t doublings;     /* doubling steps of all media                         */
    double peak_bytes;    /* estimated peak memory of the build, bytes           */
    double seconds;       /* estimated wall time with opts->threads threads      */
    /* Appended in 1.x (filled only when struct_size covers them): */
    double cpu_seconds;   /* estimated CPU time, summed over the threads          */
    size_t max_memory_bytes; /* the budget in effect (opts or half the RAM)      */
    int over_budget;      /* nonzero: peak_bytes > max_memory_bytes, so a build
                             with these options is refused                       */
} ll_build_estimate;

#define LL_BUILD_ESTIMATE_INIT { sizeof(ll_build_estimate), 0, 0, 0, 0, 0, 0, 0.0, 0.0, 0.0, 0, 0 }

/* estimate->struct_size may be the sizeof of an older, smaller
 * ll_build_estimate: only the fields it covers are written (the least
 * accepted is sizeof(size_t), the struct_size field itself, as for every
 * size-tagged struct). */

LL_API ll_status ll_material_estimate(const ll_material *material,
                                      const ll_build_options *opts,
                                      ll_build_estimate *estimate);

#ifdef __cplusplus
}
#endif
#endif /* LAYERLAB_LL_MATERIAL_H */
