/*
 * The bases of a textured material across MPI ranks. Every rank has its
 * own ll_material_builder, so a word shared by bases (the coat of a coat x
 * base grid) is built once per rank that needs it (the builder's cache).
 * Rank 0 keeps the queue: it hands out basis indices on demand (two ahead
 * per worker, so a worker never waits while rank 0 is busy), builds bases
 * itself in between, and feeds the streaming writer in basis order,
 * holding the bases that arrive early until their turn. The layers travel
 * packed (ll_layer_pack: the stored form, bit for bit), so the file is the
 * one ll_material_build writes.
 *
 * Rank 0 never blocks on the others: it polls (MPI_Iprobe) between and
 * inside its own bases (from the builder's monitor) and, when idle, every
 * millisecond, watching the cancel flag all the while. So when a worker
 * dies and mpirun sends SIGTERM, rank 0 aborts the writer at once (its
 * spill is an unlinked file; no output or temporary is left) rather than
 * wait for the others.
 *
 * Messages (tags): WORK (rank 0 -> worker: int64 basis, or -1 = stop);
 * RESULT (worker -> rank 0: int64 basis, status, byte count), then the
 * bytes (DATA, in pieces of at most 1 GiB): the packed layers of each
 * channel after their uint64 sizes, or the failure's message.
 */
#include "textured.h"

#include <mpi.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

enum { TAG_WORK = 1, TAG_RESULT = 2, TAG_DATA = 3 };
#define PIECE ((size_t)1 << 30)
#define AHEAD 2
#define TEXT_BYTES 1024

typedef struct basis_bytes {
    unsigned char *data; /* NULL: not arrived */
    size_t size;
} basis_bytes;

/* Rank 0's state. */
typedef struct queue {
    mpi_job *job;
    const ll_material *m;
    const volatile sig_atomic_t *cancel;
    const char *path;
    size_t bases, next, written;   /* next to hand out, next to write   */
    int *outstanding;              /* [size] bases a worker holds       */
    int *stopped;                  /* [size] a worker was told to stop  */
    basis_bytes *early;            /* [bases] arrived before their turn */
    ll_bsdf_writer *writer;
    size_t n_channels;
    ll_status status;              /* the first failure, or LL_OK       */
    char text[2 * TEXT_BYTES];     /* its message                       */
    const ll_monitor *shown;       /* the bases written (nullable)      */
} queue;

/* Show the bases written so far. */
static void show_written(const queue *q)
{
    if (q->shown && q->shown->progress)
        (void)q->shown->progress(q->shown->user, 0.97 * (double)q->written / (double)q->bases,
                                 "bases");
}

/* A worker's builder stops at the signal flag. */
typedef struct cancel_watch {
    const volatile sig_atomic_t *cancel;
} cancel_watch;

static int cancel_from_flag(void *user, double fraction, const char *stage)
{
    const cancel_watch *c = user;
    (void)fraction;
    (void)stage;
    return *c->cancel != 0;
}

static void send_bytes(const unsigned char *p, size_t size, int to)
{
    size_t off;
    for (off = 0; off < size; off += PIECE)
        MPI_Send(p + off, (int)(size - off < PIECE ? size - off : PIECE), MPI_BYTE, to, TAG_DATA,
                 MPI_COMM_WORLD);
}

static void recv_bytes(unsigned char *p, size_t size, int from)
{
    size_t off;
    for (off = 0; off < size; off += PIECE)
        MPI_Recv(p + off, (int)(size - off < PIECE ? size - off : PIECE), MPI_BYTE, from,
                 TAG_DATA, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
}

/* The layers of one basis as bytes: per channel its size, then it. */
static ll_status pack_basis(ll_layer *const *layers, size_t n_channels, unsigned char **out,
                            size_t *size)
{
    size_t c, total = 0;
    unsigned char *p;
    ll_status s = LL_OK;
    for (c = 0; c < n_channels; ++c)
        total += sizeof(uint64_t) + ll_layer_pack_size(layers[c]);
    p = *out = malloc(total ? total : 1);
    if (!p)
        return LL_ERROR_OUT_OF_MEMORY;
    for (c = 0; c < n_channels && s == LL_OK; ++c) {
        uint64_t bytes = (uint64_t)ll_layer_pack_size(layers[c]);
        memcpy(p, &bytes, sizeof bytes);
        p += sizeof bytes;
        s = ll_layer_pack(layers[c], p, (size_t)bytes);
        p += bytes;
    }
    *size = total;
    return s;
}

static ll_status unpack_basis(const unsigned char *p, size_t size, size_t n_channels,
                              ll_layer *layers[3])
{
    const unsigned char *end = p + size;
    size_t c;
    ll_status s = LL_OK;
    for (c = 0; c < n_channels && s == LL_OK; ++c) {
        uint64_t bytes;
        if ((size_t)(end - p) < sizeof bytes)
            return LL_ERROR_FORMAT;
        memcpy(&bytes, p, sizeof bytes);
        p += sizeof bytes;
        if (bytes > (uint64_t)(end - p))
            return LL_ERROR_FORMAT;
        s = ll_layer_unpack(p, (size_t)bytes, &layers[c]);
        p += bytes;
    }
    return s;
}

static void destroy_layers(ll_layer *layers[3])
{
    size_t c;
    for (c = 0; c < 3; ++c) {
        ll_layer_destroy(layers[c]);
        layers[c] = NULL;
    }
}

/* A failure (the first one is kept): no more bases are handed out. */
static void fail(queue *q, ll_status s, const char *text)
{
    if (q->status == LL_OK) {
        q->status = s;
        snprintf(q->text, sizeof q->text, "%s", text);
    }
    q->next = q->bases;
}

/* Give worker w its next basis, or tell it to stop once it holds none. */
static void hand_out(queue *q, int w)
{
    int64_t basis = -1;
    if (q->next < q->bases && q->status == LL_OK) {
        basis = (int64_t)q->next++;
        q->outstanding[w]++;
    } else if (q->outstanding[w] > 0 || q->stopped[w]) {
        return;
    }
    if (basis < 0)
        q->stopped[w] = 1;
    MPI_Send(&basis, 1, MPI_INT64_T, w, TAG_WORK, MPI_COMM_WORLD);
}

/* Write the bases whose turn has come. */
static void write_ready(queue *q)
{
    while (q->status == LL_OK && q->written < q->bases && q->early[q->written].data) {
        basis_bytes *b = &q->early[q->written];
        ll_layer *layers[3] = { NULL, NULL, NULL };
        ll_status s = unpack_basis(b->data, b->size, q->n_channels, layers);
        if (s == LL_OK)
            s = ll_bsdf_writer_add_basis(q->writer, (const ll_layer *const *)layers);
        destroy_layers(layers);
        free(b->data);
        b->data = NULL;
        if (s != LL_OK) {
            fail(q, s, ll_last_error_message());
            return;
        }
        q->written++;
        show_written(q);
    }
}

/* One finished basis (or a failure) from worker w. */
static void take_result(queue *q, int w)
{
    int64_t head[3];
    unsigned char *data;
    size_t size;
    MPI_Recv(head, 3, MPI_INT64_T, w, TAG_RESULT, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    size = (size_t)head[2];
    data = malloc(size ? size : 1);
    if (!data) {
        /* Drain the bytes in pieces we can hold? Not worth it: end the job. */
        fprintf(stderr, "llbuild-mpi: rank 0 is out of memory for a basis of %zu bytes\n",
                size);
        MPI_Abort(MPI_COMM_WORLD, 3);
    }
    recv_bytes(data, size, w);
    q->outstanding[w]--;
    if (head[1] != LL_OK) {
        char text[TEXT_BYTES + 64];
        data[size ? size - 1 : 0] = '\0';
        snprintf(text, sizeof text, "rank %d of %d: %s", w, q->job->size, (char *)data);
        free(data);
        fail(q, (ll_status)head[1], text);
    } else if (q->status != LL_OK || head[0] < 0 || (size_t)head[0] >= q->bases ||
               q->early[head[0]].data) {
        free(data); /* after a failure, or not a basis we handed out */
    } else {
        q->early[head[0]].data = data;
        q->early[head[0]].size = size;
    }
    hand_out(q, w);
    write_ready(q);
}

/* Serve every message that has arrived; never blocks. */
static void serve(queue *q)
{
    int flag = 1;
    MPI_Status st;
    while (flag) {
        MPI_Iprobe(MPI_ANY_SOURCE, TAG_RESULT, MPI_COMM_WORLD, &flag, &st);
        if (flag)
            take_result(q, st.MPI_SOURCE);
    }
    if (*q->cancel && q->status == LL_OK)
        fail(q, LL_ERROR_CANCELLED, "the build was cancelled");
}

/* Rank 0 serves the workers from inside its own bases too. */
static int serve_from_monitor(void *user, double fraction, const char *stage)
{
    queue *q = user;
    (void)fraction;
    (void)stage;
    serve(q);
    return q->status != LL_OK;
}

static int workers_done(const queue *q)
{
    int w;
    for (w = 1; w < q->job->size; ++w)
        if (!q->stopped[w])
            return 0;
    return 1;
}

static void sleep_ms(void)
{
    struct timespec t = { 0, 1000000 };
    nanosleep(&t, NULL);
}

/* Rank 0's own basis: basis 0 first (its header opens the writer). */
static void build_own(queue *q, ll_material_builder *b, size_t basis)
{
    ll_layer *layers[3] = { NULL, NULL, NULL };
    ll_bsdf_write_options header = LL_BSDF_WRITE_OPTIONS_INIT;
    size_t n_channels = 0;
    unsigned char *data = NULL;
    size_t size = 0;
    ll_status s = ll_material_builder_build_basis(b, basis, layers, &n_channels, &header);
    if (s == LL_OK && !q->writer) {
        size_t counts[16], values = 0, a, k, axes = ll_material_axis_count(q->m);
        double *positions;
        for (a = 0; a < axes && a < 16; ++a) {
            ll_material_axis axis = LL_MATERIAL_AXIS_INIT;
            ll_material_get_axis(q->m, a, &axis);
            counts[a] = axis.n_values;
            values += axis.n_values;
        }
        positions = malloc((values ? values : 1) * sizeof *positions);
        if (!positions)
            s = LL_ERROR_OUT_OF_MEMORY;
        for (a = 0, k = 0; a < axes && s == LL_OK; ++a) {
            ll_material_axis axis = LL_MATERIAL_AXIS_INIT;
            ll_material_get_axis(q->m, a, &axis);
            memcpy(positions + k, axis.positions, axis.n_values * sizeof *positions);
            k += axis.n_values;
        }
        if (s == LL_OK)
            s = ll_bsdf_writer_open(q->path, n_channels, axes, counts, positions, &header,
                                    &q->writer);
        free(positions);
        q->n_channels = n_channels;
    }
    /* Its turn already: straight to the writer; else held, packed. */
    if (s == LL_OK && basis == q->written) {
        s = ll_bsdf_writer_add_basis(q->writer, (const ll_layer *const *)layers);
        if (s == LL_OK) {
            q->written++;
            show_written(q);
        }
    } else if (s == LL_OK) {
        s = pack_basis(layers, n_channels, &data, &size);
        if (s == LL_OK) {
            q->early[basis].data = data;
            q->early[basis].size = size;
        } else {
            free(data);
        }
    }
    destroy_layers(layers);
    if (s != LL_OK)
        fail(q, s, ll_last_error_message());
    write_ready(q);
}

/* Rank 0: the queue, its own share of the bases, the writer. */
static ll_status run_queue(queue *q, ll_material_builder *b)
{
    int w;
    ll_monitor writing = LL_MONITOR_INIT;
    ll_status s;
    q->next = 1; /* basis 0 is rank 0's: its header opens the writer */
    for (w = 1; w < q->job->size; ++w) {
        int k;
        for (k = 0; k < AHEAD; ++k)
            hand_out(q, w);
    }
    build_own(q, b, 0);
    for (;;) {
        serve(q);
        if (q->status != LL_OK && q->writer) {
            /* At once, not after the workers: mpirun may follow its
             * SIGTERM with a SIGKILL, and the spill must be gone by then. */
            ll_bsdf_writer_abort(q->writer);
            q->writer = NULL;
        }
        if (q->status == LL_OK && q->next < q->bases) {
            build_own(q, b, q->next++);
            continue;
        }
        for (w = 1; w < q->job->size; ++w)
            hand_out(q, w); /* (a stop, to those that hold nothing) */
        if (workers_done(q) && (q->status != LL_OK || q->written == q->bases))
            break;
        sleep_ms();
    }
    if (q->status != LL_OK)
        return q->status;
    writing.progress = serve_from_monitor;
    writing.user = q;
    s = ll_bsdf_writer_commit(q->writer, &writing);
    q->writer = NULL;
    if (s != LL_OK)
        fail(q, s, ll_last_error_message());
    return s;
}

/* A worker: bases as rank 0 hands them out, until it says stop. After a
 * failure it builds no more, only answers. */
static ll_status run_worker(mpi_job *job, ll_material_builder *b, char *text, size_t size)
{
    ll_status failed = LL_OK;
    for (;;) {
        int64_t basis, head[3];
        ll_layer *layers[3] = { NULL, NULL, NULL };
        unsigned char *data = NULL;
        size_t n_channels = 0, bytes = 0;
        ll_status s = failed;
        MPI_Recv(&basis, 1, MPI_INT64_T, 0, TAG_WORK, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        if (basis < 0)
            break;
        if (s == LL_OK)
            s = ll_material_builder_build_basis(b, (size_t)basis, layers, &n_channels, NULL);
        if (s == LL_OK)
            s = pack_basis(layers, n_channels, &data, &bytes);
        destroy_layers(layers);
        if (s != LL_OK) {
            free(data);
            if (failed == LL_OK) {
                failed = s;
                snprintf(text, size, "%s", ll_last_error_message());
            }
            bytes = strlen(text) + 1;
            data = (unsigned char *)text;
        }
        head[0] = basis;
        head[1] = s;
        head[2] = (int64_t)bytes;
        MPI_Send(head, 3, MPI_INT64_T, 0, TAG_RESULT, MPI_COMM_WORLD);
        send_bytes(data, bytes, 0);
        job->bytes_sent += (double)bytes; /* (the summary's count) */
        job->calls++;
        if (data != (unsigned char *)text)
            free(data);
    }
    return failed;
}

ll_status textured_build(mpi_job *job, const ll_material *m, const ll_build_options *o,
                         const char *out_path, const volatile sig_atomic_t *cancel,
                         const ll_monitor *shown, char *message, size_t size)
{
    ll_material_builder *b = NULL;
    char text[TEXT_BYTES];
    queue q;
    size_t k;
    ll_status s;

    ll_monitor serving = LL_MONITOR_INIT;
    cancel_watch flag;

    memset(&q, 0, sizeof q);
    text[0] = '\0';
    if (job->rank == 0) {
        q.job = job;
        q.m = m;
        q.cancel = cancel;
        q.path = out_path;
        q.bases = ll_material_basis_count(m);
        q.shown = shown;
        q.outstanding = calloc((size_t)job->size, sizeof *q.outstanding);
        q.stopped = calloc((size_t)job->size, sizeof *q.stopped);
        q.early = calloc(q.bases, sizeof *q.early);
        if (!q.outstanding || !q.stopped || !q.early) {
            fprintf(stderr, "llbuild-mpi: rank 0 is out of memory for the queue of %zu bases\n",
                    q.bases);
            MPI_Abort(MPI_COMM_WORLD, 3);
        }
        /* Rank 0 answers the workers from inside its own bases. */
        serving.progress = serve_from_monitor;
        serving.user = &q;
    } else {
        flag.cancel = cancel;
        serving.progress = cancel_from_flag;
        serving.user = &flag;
    }
    /* Every rank's builder (the options, the budget), agreed. */
    s = mpi_agree(job, ll_material_builder_create(m, o, &serving, &b),
                  NULL, message, size);
    if (s != LL_OK || job->rank != 0) {
        if (s == LL_OK)
            s = mpi_agree(job, run_worker(job, b, text, sizeof text), text[0] ? text : NULL,
                          message, size);
        ll_material_builder_destroy(b);
        free(q.early);
        free(q.outstanding);
        free(q.stopped);
        return s;
    }
    s = run_queue(&q, b);
    if (q.writer)
        ll_bsdf_writer_abort(q.writer);
    for (k = 0; k < q.bases; ++k)
        free(q.early[k].data);
    free(q.early);
    free(q.outstanding);
    free(q.stopped);
    ll_material_builder_destroy(b);
    return mpi_agree(job, s, s == LL_OK ? NULL : q.text, message, size);
}
