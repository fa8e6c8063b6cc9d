/*
 * layerlab — one material built by several processes (ranks), for builds
 * that outgrow one machine (docs/mpi.md). The library stays free of any
 * message-passing library: the caller (tools/llbuild-mpi, over MPI)
 * supplies one collective operation, and the library decides what moves.
 *
 * How the work is split (Jakob et al. 2014: every step but the expansion
 * of an interface works on each Fourier order alone):
 *  - rank r owns the Fourier orders l with l mod n_ranks == r (round robin,
 *    which spreads the long early orders evenly);
 *  - a rough interface or a measured BRDF produces all orders of one
 *    incident column at a time, so each rank computes the columns
 *    c with c mod n_ranks == r, and one all-to-all hands every rank its
 *    orders of every column;
 *  - phase functions, doubling and adding run on each rank's own orders
 *    only: a layer holds nothing and costs nothing in the orders it does
 *    not own, so each rank holds about 1 / n_ranks of the layers;
 *  - rank 0 receives the orders of the finished stack and holds it whole.
 * Every number is computed by the same code as in ll_material_build, so the
 * layers, and a file written from them, are the same bytes for every
 * n_ranks.
 *
 * Failure: every rank agrees on the outcome. A rank that fails (bad
 * options, out of memory, a cancel through its monitor)
 * stops its own work and says so at the next exchange; then every rank
 * returns the same status. On rank 0 the message is the failing rank's own,
 * prefixed "rank R of N: "; on the others it says which rank failed.
 *
 * Experimental: everything here is declared only when LL_EXPERIMENTAL is
 * defined before the include, and may change in a minor release (the
 * symbols are in the version node LAYERLAB_EXPERIMENTAL_1.0).
 */
#include "ll_common.h"
#include "ll_layer.h"
#include "ll_material.h"

/* (The guard is inside the condition, so that a file included once
 * without LL_EXPERIMENTAL and then again with it gets the declarations.) */
#ifdef LL_EXPERIMENTAL
#ifndef LAYERLAB_LL_DISTRIBUTION_H
#define LAYERLAB_LL_DISTRIBUTION_H

#ifdef __cplusplus
extern "C" {
#endif

/* The caller's collective, size-tagged (struct_size = sizeof). alltoallv
 * is called by every rank in the same order
 * (the library's sequence of calls is the same on every rank, whatever
 * fails): rank r sends send_bytes[d] bytes to each rank d, taken one
 * after the other from send in rank order, and receives recv_bytes[s] bytes
 * from each rank s into recv, likewise in rank order (MPI_Alltoallv on
 * bytes; counts may exceed INT_MAX). Both arrays hold n_ranks counts; the
 * library always knows what it will receive. A non-LL_OK return is taken
 * as that rank's failure (an MPI implementation normally aborts the whole
 * job instead).
 *
 * abort (nullable) is called when this rank cannot take part at all: the
 * few bytes per rank that the agreements need are allocated once, on
 * entry, and if even that fails the others would wait for this rank for
 * ever. It should end the job (MPI_Abort); if it returns, or is NULL, the
 * call returns LL_ERROR_OUT_OF_MEMORY without telling the other ranks,
 * and ending the job is the caller's duty. */
typedef struct ll_distribution {
    size_t struct_size;   /* sizeof(ll_distribution)                       */
    int rank;             /* this process, 0 <= rank < n_ranks              */
    int n_ranks;          /* 1 or more                                      */
    void *user;           /* passed to alltoallv                            */
    ll_status (*alltoallv)(void *user, const void *send, const size_t *send_bytes,
                           void *recv, const size_t *recv_bytes);
    void (*abort)(void *user, ll_status status);
} ll_distribution;

#define LL_DISTRIBUTION_INIT { sizeof(ll_distribution), 0, 1, NULL, NULL, NULL }

/* ll_material_build_layers across the ranks of dist; every rank calls it
 * with the same material and options. On rank 0, layers receives the
 * n_channels finished layers (caller frees each) and header (nullable) the
 * file's eta and alpha; on the other ranks layers stay NULL, and
 * *n_channels is set on every rank. The memory budget applies per rank, to
 * the estimate divided by n_ranks. The monitor is called
 * on every rank (a tool shows rank 0's); a cancel on any rank stops all.
 * A file written from rank 0's layers with ll_material_write is byte for
 * byte the one ll_material_build writes. Statuses as
 * ll_material_build_layers, the same on every rank; a failing collective
 * is that rank's failure. */
LL_API ll_status ll_material_build_layers_distributed(const ll_material *material,
                                                      const ll_build_options *opts,
                                                      const ll_monitor *monitor,
                                                      const ll_distribution *dist,
                                                      ll_layer *layers[3], size_t *n_channels,
                                                      ll_bsdf_write_options *header);

/* Build and write: ll_material_build across the ranks. Rank 0 writes
 * out_path atomically (the other ranks ignore out_path, which may be NULL
 * there); every rank returns the outcome of the whole, the write included.
 * A failure anywhere leaves no file and no temporary. Statuses as
 * ll_material_build, the same on every rank. */
LL_API ll_status ll_material_build_distributed(const ll_material *material,
                                               const ll_build_options *opts,
                                               const ll_monitor *monitor,
                                               const ll_distribution *dist,
                                               const char *out_path);

/* A layer as bytes, to move built layers between processes (llbuild-mpi
 * sends each basis of a textured material to rank 0 this way): the stored
 * form copied exactly, so the unpacked layer is the same layer bit for bit
 * and a file written from it the same bytes. The bytes are for the same
 * build of the library on the same architecture (native byte order).
 * ll_layer_pack_size: the bytes that ll_layer_pack writes (0 for NULL).
 * ll_layer_pack: LL_ERROR_INVALID_ARGUMENT for NULL or a buffer smaller
 * than that. ll_layer_unpack checks the bytes before allocating what they
 * claim (LL_ERROR_FORMAT when they are not a whole packed layer, with what
 * is wrong in the message) and *out receives a new layer (NULL on failure;
 * free it with ll_layer_destroy). */
LL_API size_t ll_layer_pack_size(const ll_layer *layer);
LL_API ll_status ll_layer_pack(const ll_layer *layer, void *buffer, size_t size);
LL_API ll_status ll_layer_unpack(const void *buffer, size_t size, ll_layer **out);

#ifdef __cplusplus
}
#endif
#endif /* LAYERLAB_LL_DISTRIBUTION_H */
#endif /* LL_EXPERIMENTAL */
