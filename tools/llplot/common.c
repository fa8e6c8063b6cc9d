/*
 * llplot — error reporting, images and threads shared by the modes.
 */
#include "llplot.h"

#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

int llplot_fail(int code, const char *fmt, ...)
{
    va_list ap;
    fputs("llplot: ", stderr);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
    return code;
}

int llplot_fail_ll(ll_status status, const char *what)
{
    const char *detail = ll_last_error_message();
    int code = status == LL_ERROR_IO ? LLPLOT_EXIT_IO : LLPLOT_EXIT_INPUT;
    if (!detail[0])
        detail = ll_status_string(status);
    /* The library's messages usually name the file already
     * ("coated.layers:3:14: ..."): then once is enough. */
    if (strstr(detail, what))
        return llplot_fail(code, "%s", detail);
    return llplot_fail(code, "%s: %s", what, detail);
}

double llplot_luminance(const double rgb[3])
{
    return 0.212671 * rgb[0] + 0.715160 * rgb[1] + 0.072169 * rgb[2];
}

/* ---------------------------------------------------------------- images */

int llplot_image_alloc(llplot_image *img, size_t width, size_t height, size_t channels)
{
    size_t i;
    img->data = NULL;
    img->width = width;
    img->height = height;
    img->channels = channels;
    for (i = 0; i < 4; ++i)
        img->names[i] = NULL;
    /* Checked: width * height * channels * sizeof(float) must fit a size_t. */
    if (width == 0 || height == 0 || channels == 0 || channels > 4 ||
        height > (size_t)-1 / width || channels > (size_t)-1 / (width * height) ||
        width * height * channels > (size_t)-1 / sizeof(float))
        return llplot_fail(LLPLOT_EXIT_INPUT, "an image of %zu x %zu pixels, %zu channels, is too large",
                           width, height, channels);
    img->data = calloc(width * height * channels, sizeof(float));
    if (!img->data)
        return llplot_fail(LLPLOT_EXIT_IO, "out of memory for a %zu x %zu image", width, height);
    return LLPLOT_EXIT_OK;
}

void llplot_image_free(llplot_image *img)
{
    free(img->data);
    img->data = NULL;
}

/* --------------------------------------------------------------- threads */

typedef struct row_queue {
    pthread_mutex_t lock;
    size_t next, n_rows;
    llplot_row_fn body;
    void *ctx;
} row_queue;

static void *row_worker(void *arg)
{
    row_queue *q = arg;
    for (;;) {
        size_t row;
        pthread_mutex_lock(&q->lock);
        row = q->next < q->n_rows ? q->next++ : q->n_rows;
        pthread_mutex_unlock(&q->lock);
        if (row >= q->n_rows)
            return NULL;
        q->body(row, q->ctx);
    }
}

void llplot_parallel_rows(size_t n_rows, size_t threads, llplot_row_fn body, void *ctx)
{
    enum { MAX_THREADS = 64 };
    pthread_t tid[MAX_THREADS];
    row_queue q;
    size_t k, started = 0;
    if (threads == 0) {
        long online = sysconf(_SC_NPROCESSORS_ONLN);
        threads = online > 0 ? (size_t)online : 1;
    }
    if (threads > MAX_THREADS)
        threads = MAX_THREADS;
    if (threads > n_rows)
        threads = n_rows;
    q.next = 0;
    q.n_rows = n_rows;
    q.body = body;
    q.ctx = ctx;
    pthread_mutex_init(&q.lock, NULL);
    /* The calling thread works too; if a thread cannot be started, the
     * others simply take its rows. */
    for (k = 1; k < threads; ++k)
        if (pthread_create(&tid[started], NULL, row_worker, &q) == 0)
            ++started;
    row_worker(&q);
    for (k = 0; k < started; ++k)
        pthread_join(tid[k], NULL);
    pthread_mutex_destroy(&q.lock);
}
