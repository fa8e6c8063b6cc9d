/*
 * llbuild-mpi's side of ll_distribution (layerlab/ll_distribution.h): the
 * library's one collective over MPI, and the tool's own agreements (before
 * and after the library call: reading the material, writing the file).
 */
#ifndef LLBUILD_MPI_HOOK_H
#define LLBUILD_MPI_HOOK_H

#define LL_EXPERIMENTAL /* ll_distribution */
#include <layerlab.h>

typedef struct mpi_job {
    int rank, size;
    double bytes_sent;   /* by this rank to the others, over all exchanges */
    unsigned long calls; /* collective calls made                          */
} mpi_job;

/* An ll_distribution over MPI_COMM_WORLD (job must outlive it). */
void mpi_distribution(mpi_job *job, ll_distribution *out);

/* Every rank's status: the outcome (the lowest failing rank's, a real
 * failure before a cancel). On rank 0, message (nullable, size bytes)
 * receives the failing rank's text, prefixed "rank R of N: " when R != 0:
 * its local_text, or when that is NULL its ll_last_error_message().
 * Collective. */
ll_status mpi_agree(const mpi_job *job, ll_status local, const char *local_text, char *message,
                    size_t size);

#endif
