/*
 * layerlab — writing .bsdf files ("SCATFUN" version 1, see ll_bsdf.h) from
 * layers. Split from ll_bsdf.h so that the reading half needs no layer
 * declarations: a renderer includes ll_bsdf.h alone and links the reader
 * library (liblayerlab_reader), a program that writes files includes this
 * header (or the umbrella layerlab.h) and links liblayerlab.
 */
#ifndef LAYERLAB_LL_BSDF_WRITE_H
#define LAYERLAB_LL_BSDF_WRITE_H

#include "ll_bsdf.h"
#include "ll_layer.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Options for writing. Set struct_size = sizeof(ll_bsdf_write_options) (the
 * INIT macro does); the library reads only the fields that struct_size
 * covers, so programs built against older headers keep working.
 * eta must lie in [1e-3, 1e3], alpha be finite and non-negative.
 * error_goal: a pair's series ends after the last order at which the sum of
 * |coefficient| over that order and all higher ones still exceeds
 * error_goal times the order-0 matrix entry (the original layerlab's rule;
 * that entry is twice the azimuthal mean a_0), the longest over channels
 * and bases; 0 keeps every non-zero order. */
typedef struct ll_bsdf_write_options {
    size_t struct_size;
    double eta;          /* header eta: eta(bottom)/eta(top); 1 for opaque stacks */
    double alpha[2];     /* header roughness of the top and bottom interface      */
    const char *metadata;/* text stored in the file; NULL = a JSON description     */
    double error_goal;   /* series truncation: relative tail sum, default 1e-3    */
} ll_bsdf_write_options;

#define LL_BSDF_WRITE_OPTIONS_INIT \
    { sizeof(ll_bsdf_write_options), 1.0, { 0.0, 0.0 }, NULL, 1e-3 }

/* Write layers[0 .. n_channels-1] (1 channel, or 3: R, G, B, stored as
 * Y, R, B) to path. All layers must share nodes and order count, and hold
 * surfaces or slabs (what the words and adding-doubling produce; a phase
 * function set on a layer but not yet expanded to a thickness is not a
 * BSDF). What is stored follows the original layerlab's BSDFStorage
 * (formats.md): the nodes with two mu = 0 nodes inserted, coefficients
 * f_k |mu_o| as float32, the CDF for sampling; the default metadata is a
 * JSON description (generator, nodes, orders, channels, eta, alpha, error
 * goal). opts may be NULL (defaults). Atomic: the file is written to a
 * hidden temporary file (.NAME.XXXXXX.tmp) in the same directory, flushed
 * (fsync) and renamed over path; on any failure path is untouched and no
 * temporary file remains (a stale temporary of an earlier, killed writer of
 * the same target is removed after 15 minutes). A new file's mode is 0666
 * less the umask, an existing target keeps its mode, and a symbolic link is
 * written through: the file it points to is replaced, the link stays.
 * Layers whose stored values take more than 64 MiB are first spilled, as
 * by ll_bsdf_writer_*, to an unlinked file beside path (which then needs
 * room for it too), smaller ones to memory. Returns LL_ERROR_IO (message names the path and
 * the system error), LL_ERROR_INVALID_ARGUMENT (a NULL, mismatched or
 * non-finite layer, bad options, more than 2^32 - 1 coefficients) or
 * LL_ERROR_OUT_OF_MEMORY.
 *
 * monitor (ll_common.h; nullable): stage "writing": series lengths,
 * offsets, CDF, then the bytes. The writer uses no other thread and polls
 * once per column or node row of every pass; LL_ERROR_CANCELLED (also at
 * the last report, which comes before the temporary file is renamed)
 * leaves no file and keeps an existing one. */
LL_API ll_status ll_bsdf_write(const char *path, const ll_layer *const *layers,
                               size_t n_channels, const ll_bsdf_write_options *opts,
                               const ll_monitor *monitor);

/* Textured file: n_parameters parameters, parameter p sampled at
 * param_counts[p] >= 1 positions (the param_positions array holds them
 * all, parameter 0's first; each parameter's strictly increasing).
 * n_bases = product of the counts; layers holds n_bases * n_channels
 * layers, basis-major (layers[basis * n_channels + ch]), with the basis
 * index running over parameter 0 fastest. Each basis gets its own CDF.
 * n_parameters = 0 writes an untextured file (as ll_bsdf_write). Same
 * statuses, atomicity and monitor as ll_bsdf_write. */
LL_API ll_status ll_bsdf_write_textured(const char *path, const ll_layer *const *layers,
                                        size_t n_channels, size_t n_parameters,
                                        const size_t *param_counts,
                                        const double *param_positions,
                                        const ll_bsdf_write_options *opts,
                                        const ll_monitor *monitor);

typedef struct ll_bsdf_writer ll_bsdf_writer;

/* A streaming writer of textured files: the bases are added one at a time,
 * in order 0 .. n_bases - 1, and the writer never holds more than one
 * basis's layers (it keeps none of the caller's layers after add_basis
 * returns): each basis's coefficients go to a spill file created beside
 * path (".NAME.spill.XXXXXX", unlinked right after it is created, so it has
 * no name while the writer works and its space returns when the process
 * ends, however it ends; it needs room on that file system too: the
 * layers' stored values as doubles, about 1.5 to 2 times the output's
 * size), and commit writes the file from it, so memory does not grow with
 * n_bases beyond a few bytes per basis, node and order
 * (n_channels (4 nn + 8 m + 24) + 8). The file is byte for byte what
 * ll_bsdf_write_textured writes for the same layers (series truncated by
 * the same rule, the longest over channels and bases), and as atomic: it
 * appears only when commit succeeds; abort, a failure or a cancel leaves no
 * file (not even the spill) and keeps an existing one.
 *
 * open: n_channels 1 or 3; the parameters as ll_bsdf_write_textured
 * (n_parameters = 0: one basis, an untextured file); opts (nullable) read
 * now (opts->metadata is copied). *out is the new writer, NULL on
 * failure; it is freed by ll_bsdf_writer_commit or ll_bsdf_writer_abort.
 * Statuses as ll_bsdf_write_textured. A writer is used by one thread at a
 * time; writers of different files may run at once. */
LL_API ll_status ll_bsdf_writer_open(const char *path, size_t n_channels, size_t n_parameters,
                                     const size_t *param_counts, const double *param_positions,
                                     const ll_bsdf_write_options *opts, ll_bsdf_writer **out);

/* The next basis: layers[0 .. n_channels-1], all with the nodes and order
 * count of the first basis. LL_ERROR_INVALID_ARGUMENT (mismatched,
 * non-finite or NULL layers, more bases than the parameters make),
 * LL_ERROR_IO (the spill file), LL_ERROR_OUT_OF_MEMORY. After a failure the
 * writer only accepts ll_bsdf_writer_abort. */
LL_API ll_status ll_bsdf_writer_add_basis(ll_bsdf_writer *writer,
                                          const ll_layer *const *layers);

/* Write the file (all bases must have been added) and free the writer,
 * whatever the outcome. monitor (nullable) as for ll_bsdf_write: stage
 * "writing", and a cancel leaves no file. Statuses as ll_bsdf_write
 * (LL_ERROR_INVALID_ARGUMENT also for a NULL writer, missing bases or a
 * writer that failed before). */
LL_API ll_status ll_bsdf_writer_commit(ll_bsdf_writer *writer, const ll_monitor *monitor);

/* Give up: no file is left (nor the spill); frees the writer. NULL is fine. */
LL_API void ll_bsdf_writer_abort(ll_bsdf_writer *writer);

#ifdef __cplusplus
}
#endif
#endif /* LAYERLAB_LL_BSDF_WRITE_H */
