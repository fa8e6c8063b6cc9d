/*
 * The MPI behind llbuild-mpi's ll_distribution. MPI's own error handler
 * stays MPI_ERRORS_ARE_FATAL: a failed or dead rank ends the whole job
 * (mpirun kills the others), which is what keeps the survivors from
 * waiting for ever.
 */
#include "mpi_hook.h"

#include <limits.h>
#include <mpi.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Counts above INT_MAX (MPI's int counts) go as messages of at most this
 * many bytes. */
#define CHUNK_BYTES ((size_t)1 << 30)
#define MESSAGE_BYTES 1024

/* Displacements of counts in rank order; 0 when any does not fit an int. */
static int int_layout(const size_t *bytes, int n, int *count, int *displ)
{
    size_t at = 0;
    int r;
    for (r = 0; r < n; ++r) {
        if (bytes[r] > (size_t)INT_MAX || at > (size_t)INT_MAX)
            return 0;
        count[r] = (int)bytes[r];
        displ[r] = (int)at;
        at += bytes[r];
    }
    return 1;
}

/* The same exchange as chunked non-blocking messages (tag = chunk index,
 * so chunks of one pair cannot be confused). */
static int chunked(const unsigned char *send, const size_t *sb, unsigned char *recv,
                   const size_t *rb, int n)
{
    size_t requests = 0, at, k, r;
    MPI_Request *req;
    int ok;
    for (r = 0; r < (size_t)n; ++r)
        requests += (sb[r] + CHUNK_BYTES - 1) / CHUNK_BYTES + (rb[r] + CHUNK_BYTES - 1) / CHUNK_BYTES;
    req = malloc((requests ? requests : 1) * sizeof *req);
    if (!req)
        return 0;
    k = 0;
    for (r = 0, at = 0; r < (size_t)n; at += rb[r], ++r) {
        size_t off;
        for (off = 0; off < rb[r]; off += CHUNK_BYTES)
            MPI_Irecv(recv + at + off, (int)(rb[r] - off < CHUNK_BYTES ? rb[r] - off : CHUNK_BYTES),
                      MPI_BYTE, (int)r, (int)(off / CHUNK_BYTES), MPI_COMM_WORLD, &req[k++]);
    }
    for (r = 0, at = 0; r < (size_t)n; at += sb[r], ++r) {
        size_t off;
        for (off = 0; off < sb[r]; off += CHUNK_BYTES)
            MPI_Isend(send + at + off, (int)(sb[r] - off < CHUNK_BYTES ? sb[r] - off : CHUNK_BYTES),
                      MPI_BYTE, (int)r, (int)(off / CHUNK_BYTES), MPI_COMM_WORLD, &req[k++]);
    }
    ok = MPI_Waitall((int)k, req, MPI_STATUSES_IGNORE) == MPI_SUCCESS;
    free(req);
    return ok;
}

static ll_status alltoallv(void *user, const void *send, const size_t *send_bytes, void *recv,
                           const size_t *recv_bytes)
{
    mpi_job *job = user;
    int *layout = malloc(4 * (size_t)job->size * sizeof *layout), ok, r;
    if (!layout)
        return LL_ERROR_OUT_OF_MEMORY;
    /* What crosses between ranks, for the cost model (docs/mpi.md). */
    job->calls++;
    for (r = 0; r < job->size; ++r)
        if (r != job->rank)
            job->bytes_sent += (double)send_bytes[r];
    if (int_layout(send_bytes, job->size, layout, layout + job->size) &&
        int_layout(recv_bytes, job->size, layout + 2 * job->size, layout + 3 * job->size))
        /* (MPI-3 takes a const send buffer.) */
        ok = MPI_Alltoallv(send, layout, layout + job->size, MPI_BYTE, recv,
                           layout + 2 * job->size, layout + 3 * job->size, MPI_BYTE,
                           MPI_COMM_WORLD) == MPI_SUCCESS;
    else
        ok = chunked(send, send_bytes, recv, recv_bytes, job->size);
    free(layout);
    return ok ? LL_OK : LL_ERROR_IO;
}

/* This rank cannot take part in the agreements: end the job. */
static void abort_job(void *user, ll_status status)
{
    const mpi_job *job = user;
    fprintf(stderr, "llbuild-mpi: rank %d of %d: %s\n", job->rank, job->size,
            ll_last_error_message());
    MPI_Abort(MPI_COMM_WORLD, status == LL_ERROR_OUT_OF_MEMORY ? 3 : 1);
}

void mpi_distribution(mpi_job *job, ll_distribution *out)
{
    ll_distribution d = LL_DISTRIBUTION_INIT;
    d.rank = job->rank;
    d.n_ranks = job->size;
    d.user = job;
    d.alltoallv = alltoallv;
    d.abort = abort_job;
    *out = d;
}

ll_status mpi_agree(const mpi_job *job, ll_status local, const char *local_text, char *message,
                    size_t size)
{
    const char *mine_text = local_text ? local_text : ll_last_error_message();
    int *all = malloc((size_t)job->size * sizeof *all), r, decider = -1, mine = (int)local;
    ll_status outcome = LL_OK;
    if (!all) {
        /* Nothing to agree with: end the job rather than leave others waiting. */
        fprintf(stderr, "llbuild-mpi: out of memory on rank %d\n", job->rank);
        MPI_Abort(MPI_COMM_WORLD, 3);
    }
    MPI_Allgather(&mine, 1, MPI_INT, all, 1, MPI_INT, MPI_COMM_WORLD);
    for (r = 0; r < job->size && decider < 0; ++r)
        if (all[r] != LL_OK && all[r] != LL_ERROR_CANCELLED)
            decider = r;
    for (r = 0; r < job->size && decider < 0; ++r)
        if (all[r] != LL_OK)
            decider = r;
    free(all);
    if (decider < 0)
        return LL_OK;
    MPI_Bcast(&mine, 1, MPI_INT, decider, MPI_COMM_WORLD);
    outcome = (ll_status)mine;
    /* The failing rank's own words, to rank 0 which prints them. */
    if (decider != 0 && (job->rank == decider || job->rank == 0)) {
        char text[MESSAGE_BYTES];
        if (job->rank == decider) {
            snprintf(text, sizeof text, "%s", mine_text);
            MPI_Send(text, MESSAGE_BYTES, MPI_CHAR, 0, 0, MPI_COMM_WORLD);
        } else {
            MPI_Recv(text, MESSAGE_BYTES, MPI_CHAR, decider, 0, MPI_COMM_WORLD,
                     MPI_STATUS_IGNORE);
            text[MESSAGE_BYTES - 1] = '\0';
            if (message)
                snprintf(message, size, "rank %d of %d: %s", decider, job->size, text);
        }
    } else if (job->rank == 0 && message) {
        snprintf(message, size, "%s", mine_text);
    }
    return outcome;
}
